//! `splat_photons` on the reference's stored photons, tile counts and camera G-buffer:
//! a pixel's sum changes only where a splat's containment test (a sum of three squared
//! ratios against 1) or its reach (a `ceil`) lands within a few ulps of the threshold,
//! ~1e-5 of the splat-pixel pairs: at least
//! [`DEPOSIT_TEXEL_AGREEMENT`](crate::harness::tolerance::DEPOSIT_TEXEL_AGREEMENT) of the
//! texels must hold the same number of splats, and those within [`SPLAT_REL`] of the flux
//! plus one quantum per splat (each contribution `E x area` carries ~40 ulp: the
//! kernel's normalisations, square roots and divisions, the pixel area's footprint;
//! rounding to quanta moves each by at most one unit).
//!
//! Its counters are checked exactly on each backend by themselves
//! ([`check_splat_counters`]): underflow and saturation at flux quanta where every
//! contribution does one or the other, the clipped splats at a threshold no photon's reach
//! comes near.
//!
//! One link of PhotonGi's chain, [`super::shading_normal_correction::check_photon_gi`].

use super::trace_indirect::*;
use crate::harness::fixture::{run_and_free, Fixture};
use caustica_core::backend::{read_buf, read_photon_map, Backend};
use caustica_core::device::layout::{counter, DepositTexel, GBufferTexel, GiPhoton, SplatParams};
use caustica_core::kernels::SplatPhotons;
use caustica_core::math::fixed_point::join_u64;
use caustica_core::recording::Recording;

/// Relative tolerance of a splatted texel's flux (module doc, point 4): 40 ulp ~ 2.4e-6,
/// 1e-5 with margin.
pub const SPLAT_REL: f64 = 1e-5;

pub(crate) fn splat_params(fx: &Fixture, power_scale: f32, quantum: f32) -> SplatParams {
    let d = (fx.ds.bounds.max - fx.ds.bounds.min).length();
    let cam = fx.camera;
    SplatParams {
        camera: cam,
        tile_size: TILE,
        power_scale,
        flux_quantum: quantum,
        max_splat_px: 12,
        max_ray_length: 0.5 * d,
        min_length_scale: 0.1,
        density_radius_min: 1e-4 * d,
        density_radius_max: 0.05 * d,
        photons_per_pixel: 2.0,
        normal_compression: 0.1,
        max_stretch: 4.0,
        tile_constant: caustica_core::math::photon_splat::tile_area_constant(
            cam.tan_half_fov_x,
            cam.tan_half_fov_y,
            (TILE, TILE),
            (cam.width, cam.height),
        ),
        min_splat_px: 1.5,
        light_direction: 1,
        scene_magnitude: fx.ds.bounds.min.abs().max(fx.ds.bounds.max.abs()).max_element(),
        _pad: [0],
    }
}

pub(crate) fn run_splat(
    fx: &Fixture,
    b: &mut dyn Backend,
    gbuffer: &[GBufferTexel],
    photons: &[GiPhoton],
    tiles: &[u32],
    params: SplatParams,
) -> Result<Splats, String> {
    let n = fx.camera.width * fx.camera.height;
    let mut rec = Recording::new();
    let g = rec.upload_gbuffer(gbuffer);
    let one = [GiPhoton::default()];
    let ph = rec.upload(
        if photons.is_empty() {
            &one[..]
        } else {
            photons
        },
        "photons",
    );
    let count = rec.upload(&[photons.len() as u32], "count");
    let t = rec.upload(tiles, "tile counts");
    let counters = rec.create(counter::WORDS as u32, "counters");
    let map = rec.create_photon_map(n);
    let directions = rec.create_photon_map(n);
    rec.clear(counters);
    rec.clear_photon_map(&map);
    rec.clear_photon_map(&directions);
    rec.kernel(SplatPhotons {
        params,
        gbuffer: g,
        photons: ph,
        photon_count: count,
        tile_counts: t,
        counters,
        photon_map: map,
        direction_map: directions,
    });
    run_and_free(b, "splat_photons", &rec, |b| {
        Ok((
            read_photon_map(b, &map)?,
            read_buf(b, counters)?,
            read_photon_map(b, &directions)?,
        ))
    })
}

/// What `splat_photons` writes: the photon map, the counters, the light-direction map.
pub(crate) type Splats = (Vec<DepositTexel>, Vec<u32>, Vec<DepositTexel>);

/// Point 4 of the module doc: of the splatted texels `ma` / `mb` and their light-direction
/// sums `da` / `db` (reference, candidate), how many hold the same number of splats and
/// how many of their channels differ in flux.
pub(crate) fn splat_agreement(
    (ma, da): (&[DepositTexel], &[DepositTexel]),
    (mb, db): (&[DepositTexel], &[DepositTexel]),
) -> (u64, u64) {
    let mut same = 0u64;
    let mut flux_bad = 0u64;
    // the light-direction sums as the flux's: each contribution w (d + 1) / 2 and w
    // is a few more roundings of the same `E x area` (a luminance, a sum and a
    // product: ~5 ulp more, inside SPLAT_REL), plus one quantum per splat
    for ((a, b), (x_d, y_d)) in ma.iter().zip(mb).zip(da.iter().zip(db)) {
        if a.photons != b.photons {
            continue;
        }
        same += 1;
        let splats = join_u64(a.photons) as f64;
        let words = |t: &DepositTexel| {
            [t.flux[0], t.flux[1], t.flux[2], t.hit_distance].map(|w| join_u64(w) as f64)
        };
        let pairs = (0..3)
            .map(|ch| (join_u64(a.flux[ch]) as f64, join_u64(b.flux[ch]) as f64))
            .chain(words(x_d).into_iter().zip(words(y_d)));
        for (x, y) in pairs {
            if (x - y).abs() > SPLAT_REL * x.max(y) + splats {
                flux_bad += 1;
            }
        }
    }
    (same, flux_bad)
}

/// Relative distance from a clip boundary `T - 1` (pixels) within which no photon's reach
/// ratio (pixels, [`reach_ratio`]) may lie for [`check_splat_counters`] to count the
/// clipped splats exactly: the ratio is a few roundings of the kernel's half-axes (its
/// normalisations, square roots and products, ~40 ulp as the module doc gives for `E x
/// area`), then `z - radius`, which amplifies that by at most `1 + (T - 1) x pixel`
/// (`pixel` the footprint per unit depth, ~1e-3), and a division: ~2.4e-6 relative; 1e-4
/// is 40x that.
pub const CLIP_MARGIN: f32 = 1e-4;

/// Pixels a photon's projection must keep from the image's edges for
/// [`check_splat_counters`]: whether it is on screen is then the same on every backend
/// (its projection carries a few ulp of the image width, ~1e-3 px at 1920).
pub const EDGE_MARGIN_PX: f32 = 1e-2;

/// The ratio whose `ceil` plus one is `caustica_cpu`'s `splat_reach_px` (`radius /
/// (near x pixel)`, pixels; infinite where the kernel's sphere reaches the camera plane,
/// which the kernel's `u32::MAX` reach stands for), computed as the CPU kernel computes
/// it; `None` where the photon is skipped (no power, behind the camera or off screen).
#[allow(clippy::neg_cmp_op_on_partial_ord)] // the kernel's NaN handling, as it is written
fn reach_ratio(p: &SplatParams, ph: &GiPhoton, tiles: &[u32]) -> Option<f32> {
    use caustica_core::device::layout::project_to_pixel;
    use caustica_core::math::packing::{unpack_rgb9e5, unpack_unit_vector};
    use caustica_core::math::photon_splat::*;
    let power = unpack_rgb9e5(ph.power) * p.power_scale;
    if !(power.max_element() > 0.0) {
        return None;
    }
    let pos = glam::Vec3::from(ph.position);
    let (_, _, z) = project_to_pixel(&p.camera, pos)?;
    let k = caustica_cpu::kernels::splat_photons::splat_constants(p);
    let s = (ray_length_scale(ph.ray_length, &k)
        * density_scale(z, p.tile_constant, tiles[ph.tile as usize], &k))
    .max(min_splat_scale(
        z,
        p.camera.tan_half_fov_y,
        p.camera.height,
        p.min_splat_px,
    ));
    let n = unpack_unit_vector(ph.normal);
    let radius = splat_kernel(n, -unpack_unit_vector(ph.direction), s, &k)
        .axes
        .max_element();
    let near = z - radius;
    if !(near > 0.0) {
        return Some(f32::INFINITY);
    }
    let pixel = 2.0 * p.camera.tan_half_fov_y / p.camera.height as f32;
    Some(radius / (near * pixel))
}

/// The splat's `UNDERFLOW`, `SATURATED` and `DEPOSITED` counters on one backend `b`
/// (`who`), exactly, over `photons` made grey (each photon's largest channel in all
/// three, so that every contribution is positive in every channel) and kept
/// [`EDGE_MARGIN_PX`] inside the image or out of it. A contribution is the photon's
/// packed power (rgb9e5: 6e-8 to 65408) times `power_scale` times a pixel's area over the
/// kernel's (1e-7 to 1e3), so
///
/// - at a flux quantum (power units) of `2^40 power_scale` every channel of every
///   contribution is 5e-27 to 6e-5 units, rounds to zero and is no subnormal a GPU could
///   flush: `UNDERFLOW` = 3 `DEPOSITED`;
/// - at `2^-100 power_scale` every channel is over 7e15 units and saturates (a quantum that
///   flushes to zero gives infinities, which saturate too): `SATURATED` = 3 `DEPOSITED`
///   more than at the huge quantum, `UNDERFLOW` = 0, and both runs deposit the same
///   splats;
/// - the clipped splats are counted on the host at a threshold `max_splat_px = T` where
///   no photon's reach ratio lies within [`CLIP_MARGIN`] of the clip's boundary
///   (`ceil(x) + 1 > T` iff `x > T - 1`): `SATURATED` at the huge quantum equals them. Where no
///   threshold from 2 to 64 keeps the margin, the run takes `params.max_splat_px` and the
///   clipped splats are not compared.
///
/// Returns a note.
#[allow(clippy::too_many_arguments)]
pub(crate) fn check_splat_counters(
    v: &mut crate::harness::verdict::Verdict,
    fx: &Fixture,
    who: &str,
    b: &mut dyn Backend,
    gbuffer: &[GBufferTexel],
    photons: &[GiPhoton],
    tiles: &[u32],
    params: SplatParams,
) -> Result<String, String> {
    use caustica_core::device::layout::project_to_screen;
    use caustica_core::math::packing::{pack_rgb9e5, unpack_rgb9e5};
    let cam = &params.camera;
    let clear_of_edges = |p: &GiPhoton| {
        let m = EDGE_MARGIN_PX;
        project_to_screen(cam, glam::Vec3::from(p.position)).is_some_and(|(x, y, _)| {
            let away = |c: f32, end: f32| (c - 0.0).abs() > m && (c - end).abs() > m;
            away(x, cam.width as f32) && away(y, cam.height as f32)
        })
    };
    let grey: Vec<GiPhoton> = photons
        .iter()
        .filter(|p| clear_of_edges(p))
        .map(|p| GiPhoton {
            power: pack_rgb9e5(glam::Vec3::splat(unpack_rgb9e5(p.power).max_element())),
            ..*p
        })
        .collect();
    let ratios: Vec<f32> = grey
        .iter()
        .filter_map(|p| reach_ratio(&params, p, tiles))
        .collect();
    // the threshold that splits the splats most evenly, keeping the margin
    let pick = (2u32..=64)
        .filter(|&t| {
            let edge = (t - 1) as f32;
            ratios
                .iter()
                .all(|&x| (x - edge).abs() > CLIP_MARGIN * edge)
        })
        .map(|t| {
            let clipped = ratios.iter().filter(|&&x| x > (t - 1) as f32).count();
            (clipped.min(ratios.len() - clipped), t, clipped as u64)
        })
        .max();
    let (t, clipped) = pick.map_or((params.max_splat_px, None), |(_, t, c)| (t, Some(c)));
    let run = |b: &mut dyn Backend, quantum: f32| {
        let p = SplatParams {
            max_splat_px: t,
            flux_quantum: quantum,
            ..params
        };
        run_splat(fx, b, gbuffer, &grey, tiles, p).map(|s| s.1)
    };
    let under = run(b, params.power_scale * 2f32.powi(40))?;
    let over = run(b, params.power_scale * 2f32.powi(-100))?;
    let word = |k: &[u32], w: usize| k[w] as u64;
    let deposits = word(&under, counter::DEPOSITED);
    let clips = word(&under, counter::SATURATED);
    let mut checks = vec![
        (
            "underflow at a huge quantum",
            word(&under, counter::UNDERFLOW),
            3 * deposits,
        ),
        (
            "underflow at a tiny quantum",
            word(&over, counter::UNDERFLOW),
            0,
        ),
        (
            "saturated at a tiny quantum",
            word(&over, counter::SATURATED),
            3 * deposits + clips,
        ),
        (
            "deposits at a tiny quantum",
            word(&over, counter::DEPOSITED),
            deposits,
        ),
    ];
    if let Some(c) = clipped {
        checks.push(("saturated (clipped) at a huge quantum", clips, c));
    }
    for (what, got, want) in checks {
        v.check(got == want, || {
            format!(
                "the {who}'s splat counters: {what}: {got}, expected {want} ({deposits} \
                 deposits, {clips} splats clipped at {t} px)"
            )
        });
    }
    Ok(match clipped {
        Some(c) => format!(
            "{who}: {deposits} deposits, {c} of {} splats clipped at {t} px",
            ratios.len()
        ),
        None => format!(
            "{who}: {deposits} deposits; no clip threshold kept the margin, {clips} splats \
             clipped at {t} px not compared"
        ),
    })
}

//! PhotonGi's kernels on the same inputs, for every light of the fixture's scene (point:
//! six faces, spot: one or six, directional: one orthographic face): faces of
//! `RSM_SIDE^2` texels rendered on the reference (an orthographic face also on the
//! candidate, compared as `primary_gbuffer`'s check compares the camera's), then
//!
//! 1. `rsm_importance` (level 0 and every pyramid level) on the reference's face
//!    G-buffers: texel kinds and positions are copies (bitwise), normals are packed
//!    (within a snorm16 quantum: the octahedral map divides); the flux is
//!    `I x falloff x dw` (a square root and two divisions, 2.5 ulp each on GPUs, and ~10
//!    roundings: < 20 ulp ~ 1.2e-6), the level-0 importance its luminance, and a pyramid
//!    sum adds at most `4^k` such terms in a fixed order with one rounding per level
//!    (`k <= 5` here): all within [`RSM_REL`] = 1e-5 relative.
//! 2. `sample_rsm` on the reference's texels and pyramid: the warp takes a texel by
//!    comparing the sample with ratios of sums (one 2.5-ulp division each), so a sample
//!    within a few ulps of a split point may take the neighbouring texel: at most
//!    [`DEPOSIT_PHOTON_CHANGES`] of the samples (~1e-6 expected per split, ~20 splits)
//!    may differ; the others have bitwise origins and bounce counts, flux within
//!    [`RSM_REL`] (the probability is a product of ~20 ratios: ~50 ulp) and directions
//!    within [`DIRECTION_TOL`] (`sin`, `cos`, `sqrt` of the cosine warp, then 16-bit
//!    octahedral packing: one quantum is ~5e-5 rad).
//! 3. `trace_indirect` on the reference's RSM photons: the stored photons as counts and
//!    flux sums within the path-divergence allowance ([`divergence_allowance`] of the
//!    stored photons, each diverged path changing at most `bounces` of them), as
//!    multisets (each photon matched by one of the other backend's within
//!    `trace_photons`' position tolerance, with the same tile and power within one rgb9e5
//!    step, but for [`PHOTON_MATCH`]'s share), every path end accounted for, and tile
//!    counts that add up to the stored photons.
//! 4. `splat_photons` on the reference's stored photons, tile counts and camera G-buffer:
//!    a pixel's sum changes only where a splat's containment test (a sum of three squared
//!    ratios against 1) or its reach (a `ceil`) lands within a few ulps of the threshold,
//!    ~1e-5 of the splat-pixel pairs: at least [`DEPOSIT_TEXEL_AGREEMENT`] of the texels
//!    must hold the same number of splats, and those within [`SPLAT_REL`] of the flux
//!    plus one quantum per splat (each contribution `E x area` carries ~40 ulp: the
//!    kernel's normalisations, square roots and divisions, the pixel area's footprint;
//!    rounding to quanta moves each by at most one unit).

use crate::harness::fixture::{run_and_free, Fixture, ReferenceInputs};
use crate::harness::tolerance::{
    divergence_allowance, DEPOSIT_PHOTON_CHANGES, DEPOSIT_TEXEL_AGREEMENT, PHOTON_FLUX_REL,
    PHOTON_MATCH, PHOTON_POSITION_REL,
};
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, read_gbuffer, read_photon_map, Backend};
use caustica_core::device::layout::{
    counter, gbuffer_flags, CorrectionParams, DepositTexel, GBufferTexel, GiPhoton, GpuCamera,
    RsmParams, RsmPhoton, RsmTexel, SplatParams,
};
use caustica_core::kernels::{
    PrimaryGbuffer, RsmImportance, SampleRsm, ShadingNormalCorrection, SplatPhotons, TraceIndirect,
};
use caustica_core::math::fixed_point::join_u64;
use caustica_core::math::gi_photon::{gi_store, screen_tiles};
use caustica_core::math::irradiance_filter::shading_normal_departs;
use caustica_core::math::packing::unpack_unit_vector;
use caustica_core::math::rsm::{level_count, pyramid_len};
use caustica_core::recording::Recording;
use caustica_core::techniques::photon_gi::rsm_faces;

/// Texels per side of the checked RSM faces.
pub const RSM_SIDE: u32 = 32;
/// Samples per light.
pub const SAMPLES: u32 = 4096;
/// Relative tolerance of RSM fluxes, importances, pyramid sums and sampled fluxes (module
/// doc, point 1 and 2).
pub const RSM_REL: f32 = 1e-5;
/// Angle (rad) within which sampled directions must agree (module doc, point 2).
pub const DIRECTION_TOL: f32 = 1e-3;
/// Relative tolerance of a splatted texel's flux (module doc, point 4): 40 ulp ~ 2.4e-6,
/// 1e-5 with margin.
pub const SPLAT_REL: f64 = 1e-5;
/// Diffuse bounces of the checked paths.
const BOUNCES: u32 = 3;
const TILE: u32 = 8;

fn rsm_params(
    light: u32,
    face: u32,
    cam: GpuCamera,
    level: u32,
    faces: u32,
    seed: u32,
) -> RsmParams {
    RsmParams {
        face_camera: cam,
        light,
        face,
        side: RSM_SIDE,
        level,
        face_count: faces,
        first_sample: 0,
        sample_count: SAMPLES,
        seed,
        ..Default::default()
    }
}

fn face_gbuffers(
    fx: &Fixture,
    r: &mut dyn Backend,
    faces: &[GpuCamera],
) -> Result<Vec<Vec<GBufferTexel>>, String> {
    faces
        .iter()
        .map(|cam| {
            let mut rec = Recording::new();
            let g = rec.create_gbuffer(RSM_SIDE * RSM_SIDE);
            rec.kernel(PrimaryGbuffer {
                scene: fx.args,
                camera: *cam,
                gbuffer: g,
            });
            run_and_free(r, "primary_gbuffer (RSM face)", &rec, |b| {
                read_gbuffer(b, &g)
            })
        })
        .collect()
}

fn run_rsm(
    fx: &Fixture,
    b: &mut dyn Backend,
    light: u32,
    faces: &[GpuCamera],
    gbufs: &[Vec<GBufferTexel>],
) -> Result<(Vec<RsmTexel>, Vec<f32>), String> {
    let n = faces.len() as u32;
    let mut rec = Recording::new();
    let texels = rec.create(n * RSM_SIDE * RSM_SIDE, "RSM texels");
    let pyramid = rec.create(n * pyramid_len(RSM_SIDE), "RSM pyramid");
    for (f, (cam, g)) in faces.iter().zip(gbufs).enumerate() {
        let gbuffer = rec.upload_gbuffer(g);
        rec.kernel(RsmImportance {
            params: rsm_params(light, f as u32, *cam, 0, n, 0),
            lights: fx.args.lights,
            gbuffer,
            texels,
            pyramid,
        });
    }
    let g1 = rec.upload_gbuffer(&gbufs[0][..1]);
    for level in 1..level_count(RSM_SIDE) {
        rec.kernel(RsmImportance {
            params: rsm_params(light, n - 1, faces[0], level, n, 0),
            lights: fx.args.lights,
            gbuffer: g1,
            texels,
            pyramid,
        });
    }
    run_and_free(b, "rsm_importance", &rec, |b| {
        Ok((read_buf(b, texels)?, read_buf(b, pyramid)?))
    })
}

fn run_sample(
    fx: &Fixture,
    b: &mut dyn Backend,
    light: u32,
    face0: GpuCamera,
    faces: u32,
    texels: &[RsmTexel],
    pyramid: &[f32],
) -> Result<Vec<RsmPhoton>, String> {
    let mut rec = Recording::new();
    let t = rec.upload(texels, "RSM texels");
    let p = rec.upload(pyramid, "RSM pyramid");
    let photons = rec.create(SAMPLES, "RSM photons");
    rec.kernel(SampleRsm {
        params: rsm_params(light, 0, face0, 0, faces, 0x5eed ^ light),
        lights: fx.args.lights,
        texels: t,
        pyramid: p,
        photons,
    });
    run_and_free(b, "sample_rsm", &rec, |b| read_buf(b, photons))
}

/// (stored photons, tile counts, counters) of `trace_indirect`.
type Traced = (Vec<GiPhoton>, Vec<u32>, Vec<u32>);

fn run_trace(
    fx: &Fixture,
    b: &mut dyn Backend,
    rsm: &[RsmPhoton],
    gbuffer: &[GBufferTexel],
    power_scale: f32,
    quantum: f32,
) -> Result<Traced, String> {
    let cam = fx.camera;
    let mut rec = Recording::new();
    let g = rec.upload_gbuffer(gbuffer);
    let r = rec.upload(rsm, "RSM photons");
    let photons = rec.create::<[u32; 8]>(rsm.len() as u32 * BOUNCES, "indirect photons");
    let count = rec.create(1, "count");
    let tiles = rec.create(screen_tiles(cam.width, cam.height, TILE), "tile counts");
    let counters = rec.create(counter::WORDS as u32, "counters");
    rec.clear(count);
    rec.clear(tiles);
    rec.clear(counters);
    rec.kernel(TraceIndirect {
        scene: fx.args,
        params: caustica_core::device::layout::IndirectTraceParams {
            camera: cam,
            first: 0,
            count: rsm.len() as u32,
            seed: 77,
            max_bounces: BOUNCES,
            max_segments: 12,
            tile_size: TILE,
            store: gi_store::PACKED,
            fresnel_model: 0,
            power_scale,
            flux_quantum: quantum,
            _pad: [0; 2],
        },
        rsm_photons: r,
        photons,
        photon_count: count,
        tile_counts: tiles,
        counters,
        gbuffer: g,
    });
    run_and_free(b, "trace_indirect", &rec, |b| {
        let n = read_buf(b, count)?[0] as usize;
        let words = read_buf(b, photons)?;
        let ph = words[..n.min(words.len())]
            .iter()
            .map(|w| bytemuck::cast::<[u32; 8], GiPhoton>(*w))
            .collect();
        Ok((ph, read_buf(b, tiles)?, read_buf(b, counters)?))
    })
}

fn splat_params(fx: &Fixture, power_scale: f32, quantum: f32) -> SplatParams {
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
        _pad: [0; 2],
    }
}

fn run_splat(
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
type Splats = (Vec<DepositTexel>, Vec<u32>, Vec<DepositTexel>);

/// Runs `shading_normal_correction` on `b` over the reference's G-buffer and direction
/// map, on a fixed input image.
fn run_correction(
    fx: &Fixture,
    b: &mut dyn Backend,
    gbuffer: &[GBufferTexel],
    directions: &[DepositTexel],
    input: &[[f32; 4]],
) -> Result<Vec<[f32; 4]>, String> {
    let mut rec = Recording::new();
    let g = rec.upload_gbuffer(gbuffer);
    let d = rec.upload_photon_map(directions);
    let i = rec.upload(input, "input");
    let out = rec.create(input.len() as u32, "corrected");
    rec.kernel(ShadingNormalCorrection {
        params: CorrectionParams {
            width: fx.camera.width,
            height: fx.camera.height,
            max_stretch: 4.0,
            epsilon: caustica_core::techniques::photon_gi::SHADING_EPSILON,
        },
        gbuffer: g,
        direction_map: d,
        input: i,
        out,
    });
    run_and_free(b, "shading_normal_correction", &rec, |b| read_buf(b, out))
}

/// Photons of `a` without a photon of `b` at the same place (within
/// `PHOTON_POSITION_REL` of the scene diagonal: `trace_photons`' argument) with the same
/// tile, normal and direction within a packing quantum or two, and power within one rgb9e5
/// step (2^-9 of the largest channel: the same float flux may round to neighbouring
/// mantissas when it differs by an ulp).
fn unmatched(a: &[GiPhoton], b: &[GiPhoton], diagonal: f32) -> u64 {
    use caustica_core::math::packing::unpack_rgb9e5;
    let tol = PHOTON_POSITION_REL * diagonal;
    let close = |x: &GiPhoton, y: &GiPhoton| {
        let d = glam::Vec3::from(x.position) - glam::Vec3::from(y.position);
        let (px, py) = (unpack_rgb9e5(x.power), unpack_rgb9e5(y.power));
        let step = px.max_element().max(py.max_element()) * (2.0 / 512.0);
        d.length() <= tol
            && x.tile == y.tile
            && (px - py).abs().max_element() <= step
            && unpack_unit_vector(x.normal).dot(unpack_unit_vector(y.normal)) >= 1.0 - 1e-4
    };
    a.iter().filter(|x| !b.iter().any(|y| close(x, y))).count() as u64
}

/// Two packed unit vectors whose snorm16 components differ by at most one.
fn within_one_quantum(a: u32, b: u32) -> bool {
    let d = |s: u32| ((a >> s) as u16 as i16 as i32 - (b >> s) as u16 as i16 as i32).abs();
    d(0) <= 1 && d(16) <= 1
}

fn rel_close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) || a == b
}

/// PhotonGi's four kernels on the same inputs (see the module doc).
pub fn check_photon_gi(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("photon_gi kernels");
    let mut checked = 0;
    for (li, light) in fx.ds.lights.iter().enumerate() {
        checked += 1;
        let l = li as u32;
        let faces = rsm_faces(light, RSM_SIDE, &fx.ds.bounds);
        let nf = faces.len() as u32;
        let gbufs = face_gbuffers(fx, r, &faces)?;
        // 0. an orthographic face's G-buffer itself (the new primary-ray path; a
        // perspective face is the camera's path, which `primary_gbuffer`'s check covers
        // with generated cameras: cube faces inside an axis-aligned box aim texel rays at
        // shared edges, where hardware and software traversal legitimately part, 16 of
        // 1024 texels of a `cornell` face on lavapipe's Vulkan)
        if faces[0].tan_half_fov_x < 0.0 {
            let gc = face_gbuffers(fx, c, &faces)?;
            v.absorb(crate::kernels::compare_gbuffers(&fx.ds, &faces[0], &gbufs[0], &gc[0]).0);
        }
        // 1. rsm_importance
        let (ta, pa) = run_rsm(fx, r, l, &faces, &gbufs)?;
        let (tb, pb) = run_rsm(fx, c, l, &faces, &gbufs)?;
        // a spot's smoothstep falloff has an absolute error of a few ulps of 1: near the
        // outer cone the flux is tiny and its relative error large, so fluxes agree within
        // RSM_REL of the larger or of the face's largest texel flux (sums likewise)
        let peak = ta.iter().flat_map(|t| t.flux).fold(0.0f32, f32::max);
        // Inside a spot's transition the falloff is smoothstep(t), t = (cos - cos_outer) /
        // (cos_inner - cos_outer): the cosine, a dot product of two normalised vectors, may
        // differ by ~4 ulp of 1 (2^-22) where a GPU fuses its products (seen on the H200: a
        // spot whose transition spans a few degrees, flux 3.4e-5 relative apart), which
        // t divides by the transition's width and smoothstep's slope (<= 1.5) carries into
        // the falloff: an absolute error up to 1.5 * 2^-22 / width of the unit falloff,
        // i.e. of the flux at falloff 1 (at most the face's peak for a face in the cone;
        // 1e-6 rounds 3.6e-7 up for the peak not being at falloff 1).
        let spot = if light.kind == caustica_core::device::layout::light_kind::SPOT {
            peak * 1e-6 / (light.cos_inner - light.cos_outer).max(f32::MIN_POSITIVE)
        } else {
            0.0
        };
        let floor = (peak * RSM_REL).max(spot);
        let close = |a: f32, b: f32| rel_close(a, b, RSM_REL) || (a - b).abs() <= floor;
        let differs = |a: &RsmTexel, b: &RsmTexel| {
            a.kind != b.kind
                || a.position.map(f32::to_bits) != b.position.map(f32::to_bits)
                // packing divides by the normal's L1 norm: GPUs' approximate
                // division may move it by one snorm16 quantum (~3e-5 rad)
                || !within_one_quantum(a.normal, b.normal)
                || !(0..3).all(|k| close(a.flux[k], b.flux[k]))
        };
        let texel_bad = ta.iter().zip(&tb).filter(|(a, b)| differs(a, b)).count();
        v.check(texel_bad == 0, || {
            // the first one, field by field (what a GPU-only failure needs to be read)
            let first = ta
                .iter()
                .zip(&tb)
                .enumerate()
                .find(|(_, (a, b))| differs(a, b))
                .map(|(i, (a, b))| {
                    format!(
                        "; first at texel {i}: kind {} vs {}, position {:?} vs {:?}, normal \
                         {:#010x} vs {:#010x}, flux {:?} vs {:?}",
                        a.kind, b.kind, a.position, b.position, a.normal, b.normal, a.flux, b.flux
                    )
                })
                .unwrap_or_default();
            format!("light {l}: {texel_bad} RSM texels differ{first}")
        });
        let pyr_bad = pa
            .iter()
            .zip(&pb)
            // a sum holds at most RSM_SIDE^2 texels, each within `floor`
            .filter(|(a, b)| {
                !rel_close(**a, **b, RSM_REL)
                    && (**a - **b).abs() > floor * (RSM_SIDE * RSM_SIDE) as f32
            })
            .count();
        v.check(pyr_bad == 0, || {
            format!("light {l}: {pyr_bad} pyramid sums differ beyond {RSM_REL}")
        });
        // 2. sample_rsm
        let sa = run_sample(fx, r, l, faces[0], nf, &ta, &pa)?;
        let sb = run_sample(fx, c, l, faces[0], nf, &ta, &pa)?;
        let mut other_texel = 0u64;
        let mut bad = 0u64;
        for (a, b) in sa.iter().zip(&sb) {
            // the same texel gives origins a few ulps apart (the normal's unpacking and the
            // offset divide and normalise); another texel is a texel's width away
            let (oa, ob) = (glam::Vec3::from(a.origin), glam::Vec3::from(b.origin));
            if (oa - ob).length() > 1e-5 * (oa.abs().max_element() + 1.0) || a.bounces != b.bounces
            {
                other_texel += 1;
                continue;
            }
            let angle = unpack_unit_vector(a.direction)
                .dot(unpack_unit_vector(b.direction))
                .clamp(-1.0, 1.0)
                .acos();
            let flux_ok = (0..3).all(|k| rel_close(a.flux[k], b.flux[k], RSM_REL));
            let angle_ok = angle <= DIRECTION_TOL; // false for NaN
            bad += (!flux_ok || !angle_ok) as u64;
        }
        let allow = (DEPOSIT_PHOTON_CHANGES * SAMPLES as f64).ceil() as u64 + 2;
        v.check(other_texel <= allow, || {
            format!("light {l}: {other_texel} of {SAMPLES} samples took another texel (allowance {allow})")
        });
        v.check(bad == 0, || {
            format!("light {l}: {bad} samples differ in flux or direction")
        });
        // 3. trace_indirect on the reference's photons
        let mean = sa
            .iter()
            .map(|p| p.flux.iter().cloned().fold(0.0f32, f32::max))
            .sum::<f32>()
            / SAMPLES as f32;
        let power_scale = mean.max(f32::MIN_POSITIVE);
        let quantum = power_scale / 1_048_576.0;
        let (pha, tia, ca) = run_trace(fx, r, &sa, &inputs.gbuffer, power_scale, quantum)?;
        let (phb, tib, cb) = run_trace(fx, c, &sa, &inputs.gbuffer, power_scale, quantum)?;
        // diverged paths: a share of the paths, each moving one path end and at most
        // BOUNCES stored photons
        let stored = ca[counter::STORED].max(cb[counter::STORED]) as u64;
        let paths_allow = divergence_allowance(SAMPLES as u64);
        let allow = divergence_allowance(stored) * BOUNCES as u64;
        let diff = |k: usize| (ca[k] as i64 - cb[k] as i64).unsigned_abs();
        v.check(diff(counter::STORED) <= allow, || {
            format!(
                "light {l}: stored {} vs {} (allowance {allow})",
                ca[counter::STORED],
                cb[counter::STORED]
            )
        });
        for k in [
            counter::ESCAPED,
            counter::NEGLIGIBLE,
            counter::BOUNCE_LIMIT,
            counter::OFF_SCREEN,
            counter::DEPTH_MISMATCH,
        ] {
            v.check(diff(k) <= paths_allow.max(allow), || {
                format!("light {l}: counter {k}: {} vs {}", ca[k], cb[k])
            });
        }
        v.check(
            pha.len() as u32 == ca[counter::STORED] && phb.len() as u32 == cb[counter::STORED],
            || "stored photons and STORED disagree".into(),
        );
        v.check(
            tia.iter().sum::<u32>() as usize == pha.len()
                && tib.iter().sum::<u32>() as usize == phb.len(),
            || format!("light {l}: tile counts do not add up to the stored photons"),
        );
        let ends =
            |c: &[u32]| c[counter::ESCAPED] + c[counter::NEGLIGIBLE] + c[counter::BOUNCE_LIMIT];
        v.check(ends(&ca) == SAMPLES && ends(&cb) == SAMPLES, || {
            format!(
                "light {l}: path ends {} / {} of {SAMPLES}",
                ends(&ca),
                ends(&cb)
            )
        });
        for ch in 0..3 {
            let fa = join_u64([
                ca[counter::STORED_FLUX + 2 * ch],
                ca[counter::STORED_FLUX + 2 * ch + 1],
            ]) as f64;
            let fb = join_u64([
                cb[counter::STORED_FLUX + 2 * ch],
                cb[counter::STORED_FLUX + 2 * ch + 1],
            ]) as f64;
            // each diverged path moves at most BOUNCES photons of up to the largest
            // photon's flux; the rest agree within PHOTON_FLUX_REL
            let biggest = pha
                .iter()
                .chain(&phb)
                .map(|p| caustica_core::math::packing::unpack_rgb9e5(p.power).max_element())
                .fold(0.0f32, f32::max) as f64
                * power_scale as f64
                / quantum as f64;
            let tol = PHOTON_FLUX_REL * fa.max(fb) + allow as f64 * biggest + 3.0;
            v.check((fa - fb).abs() <= tol, || {
                format!("light {l}: stored flux channel {ch}: {fa} vs {fb} units")
            });
        }
        let diagonal = (fx.ds.bounds.max - fx.ds.bounds.min).length();
        let unmatched_ab = unmatched(&pha, &phb, diagonal);
        let unmatched_ba = unmatched(&phb, &pha, diagonal);
        let allow_match = ((1.0 - PHOTON_MATCH) * stored as f64).ceil() as u64 + 2;
        v.check(
            unmatched_ab <= allow_match && unmatched_ba <= allow_match,
            || {
                format!(
                    "light {l}: {unmatched_ab} / {unmatched_ba} stored photons without a match \
                 (allowance {allow_match})"
                )
            },
        );
        // 4. splat_photons on the reference's photons
        let sp = splat_params(fx, power_scale, quantum);
        let (ma, _, da) = run_splat(fx, r, &inputs.gbuffer, &pha, &tia, sp)?;
        let (mb, _, db) = run_splat(fx, c, &inputs.gbuffer, &pha, &tia, sp)?;
        let mut same = 0u64;
        let mut flux_bad = 0u64;
        // the light-direction sums as the flux's: each contribution w (d + 1) / 2 and w
        // is a few more roundings of the same `E x area` (a luminance, a sum and a
        // product: ~5 ulp more, inside SPLAT_REL), plus one quantum per splat
        for ((a, b), (x_d, y_d)) in ma.iter().zip(&mb).zip(da.iter().zip(&db)) {
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
        // 5. shading_normal_correction on the reference's direction map
        let input: Vec<[f32; 4]> = (0..ma.len())
            .map(|i| [1.0 + (i % 5) as f32, 1.0, 0.5, 0.25])
            .collect();
        let ca = run_correction(fx, r, &inputs.gbuffer, &da, &input)?;
        let cb = run_correction(fx, c, &inputs.gbuffer, &da, &input)?;
        let mut corrected = 0u64;
        let mut correction_bad = Vec::new();
        for (k, ((x, y), t)) in ca.iter().zip(&cb).zip(&da).enumerate() {
            let w = join_u64(t.hit_distance) as f32;
            let v =
                glam::Vec3::from_array([0, 1, 2].map(|ch| 2.0 * join_u64(t.flux[ch]) as f32 - w));
            let g = &inputs.gbuffer[k];
            let ng = unpack_unit_vector(g.geometric_normal);
            // where Eq. 20 does not apply (no receiver, no splat, or a shading normal that
            // does not depart from the geometric one: exact decisions on the same
            // G-buffer) the input passes through bitwise
            let applies = g.flags & gbuffer_flags::RECEIVER != 0
                && w > 0.0
                && shading_normal_departs(glam::Vec3::from(g.normal), ng);
            if !applies {
                let ok = y.map(f32::to_bits) == input[k].map(f32::to_bits);
                if !ok && correction_bad.len() < 3 {
                    correction_bad.push(format!("pixel {k}: {y:?}, input {:?} kept", input[k]));
                }
                continue;
            }
            let (f, den) = (
                x[0] / input[k][0],
                v.normalize_or_zero().dot(ng).max(0.0) + 1e-4,
            );
            corrected += (f != 1.0) as u64;
            // the mean direction 2 d - w carries ~4 ulp of w (cancellation: times w / |v|),
            // each dot product 3 ulp, the division 2.5 ulp: 16 ulp x w / |v| of the
            // factor's numerator and denominator, relative to the denominator
            let bound =
                16.0 * f32::EPSILON * (w / v.length().max(f32::MIN_POSITIVE)).max(1.0) * (1.0 + f)
                    / den
                    + 1e-6;
            let ok = (0..4)
                .all(|ch| (x[ch] - y[ch]).abs() <= bound * x[ch].abs().max(input[k][ch]))
                && y.iter().all(|c| c.is_finite());
            if !ok && correction_bad.len() < 3 {
                correction_bad.push(format!("pixel {k}: {y:?} vs cpu {x:?} (bound {bound:.2e})"));
            }
        }
        v.check(correction_bad.is_empty(), || {
            format!(
                "light {l}: shading_normal_correction differs: {}",
                correction_bad.join("; ")
            )
        });
        let n = ma.len() as f64;
        v.check(same as f64 >= DEPOSIT_TEXEL_AGREEMENT * n, || {
            format!("light {l}: {same} of {n} texels hold the same splats")
        });
        v.check(flux_bad == 0, || {
            format!("light {l}: {flux_bad} texel channels differ in flux")
        });
        let splatted = ma.iter().filter(|t| join_u64(t.photons) > 0).count();
        v.note(format!(
            "light {l}: {nf} faces, {} / {} photons stored, {splatted} texels splatted, \
             {corrected} corrected by Eq. 20",
            pha.len(),
            phb.len()
        ));
    }
    v.check(checked > 0, || "the scene has no light".into());
    Ok(v)
}

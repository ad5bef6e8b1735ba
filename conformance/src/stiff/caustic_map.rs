//! The caustic-map group: CausticMap's own extremes, on every backend. Each case
//! runs a CausticMap frame and checks ([`checked`]): every output finite (camera images and
//! the atlas); photon accounting (path ends add up to the emitted photons plus the
//! branches the deterministic split added, atlas outcomes to the stored ones); stored flux at most the emitted flux plus the fixed-point rounding; no
//! saturation; and on a backend other than cpu, against the CPU's frame: emitted counts
//! and flux equal, stored counts within the path-divergence allowance, and the atlas's
//! relative L2 error within `sqrt(2 k / n) + 1e-4` (`k` the allowance, `n` the deposited
//! photons: a diverged photon moves its flux from one texel to another, the argument of
//! `techniques::sspm::compare_frames`).

use super::runner::outcome;
use super::scenes::{glass, obj, sphere_scene};
use super::Outcome;
use crate::harness::candidates::{reference, REFERENCE_BACKEND};
use crate::harness::measure::relative_l2;
use crate::harness::tolerance::divergence_allowance;
use crate::harness::verdict::Verdict;
use caustica_core::backend::{Backend, BackendError};
use caustica_core::frame::image::Image;
use caustica_core::frame::output::Output;
use caustica_core::scene::{Light, Material, Scene, Shape};
use caustica_core::techniques::adaptive_caustics::AdaptiveStats;
use caustica_core::techniques::caustic_map::{CausticMap, CausticMapSettings};
use caustica_core::{AtlasSettings, FrameSettings, PlaneSettings};
use caustica_core::{Error, FrameStats};
use glam::{Vec2, Vec3};

/// What a CausticMap frame gives the checks.
pub struct MapFrame {
    pub stats: FrameStats,
    pub atlas: Image,
    pub caustics: Image,
    pub composite: Image,
}

fn settings(atlas: u32) -> CausticMapSettings {
    CausticMapSettings {
        frame: FrameSettings {
            photons_w: 128,
            photons_h: 128,
            ..CausticMapSettings::default().frame
        },
        atlas: AtlasSettings {
            atlas_size: atlas,
            ..CausticMapSettings::default().atlas
        },
        ..CausticMapSettings::default()
    }
}

/// Builds the technique a case checks: CausticMap, or AdaptiveCaustics (the same atlas
/// receiver with Wyman 2009's traversal).
pub type MakeMap<'a> =
    &'a dyn Fn(&mut dyn Backend, &Scene) -> Result<Box<dyn caustica_core::Technique>, Error>;

/// Renders one CausticMap frame on `b`.
pub fn render(
    b: &mut dyn Backend,
    scene: &Scene,
    s: &CausticMapSettings,
) -> Result<MapFrame, Error> {
    render_with(b, scene, &|b, scene| {
        Ok(Box::new(CausticMap::new(b, scene, s.clone())?))
    })
}

/// Renders one frame of the technique `make` builds on `b`.
pub fn render_with(b: &mut dyn Backend, scene: &Scene, make: MakeMap) -> Result<MapFrame, Error> {
    let mut t = make(b, scene)?;
    let stats = t.frame(b, &mut |_| {})?;
    let f = MapFrame {
        stats,
        atlas: t.read_output(b, Output::CausticAtlas)?,
        caustics: t.read_output(b, Output::FilteredCaustics)?,
        composite: t.read_output(b, Output::Composite)?,
    };
    t.free(b)?;
    Ok(f)
}

/// The universal checks and the comparison with the CPU (see the module doc).
fn checked(
    b: &mut dyn Backend,
    scene: &Scene,
    s: &CausticMapSettings,
    v: &mut Verdict,
) -> Result<MapFrame, String> {
    checked_with(
        b,
        scene,
        &|b, scene| Ok(Box::new(CausticMap::new(b, scene, s.clone())?)),
        v,
    )
}

/// [`checked`] for the technique `make` builds. With Wyman 2009's traversal the path ends
/// add up to the photons traced (every level) and the stored photons of that count, and
/// the photons traced on two backends may differ by the refinements of diverged photons
/// (within the allowance, as the stored ones).
pub(super) fn checked_with(
    b: &mut dyn Backend,
    scene: &Scene,
    make: MakeMap,
    v: &mut Verdict,
) -> Result<MapFrame, String> {
    let f = render_with(b, scene, make).map_err(|e| e.to_string())?;
    for (name, img) in [
        ("atlas", &f.atlas),
        ("caustics", &f.caustics),
        ("composite", &f.composite),
    ] {
        v.check(img.all_finite(), || format!("{name} has NaN/Inf"));
    }
    let st = &f.stats;
    let d = &st.discarded;
    // an adaptive traversal's probe photons that met a caster end at their one segment
    let traced_stored = AdaptiveStats::of(st)
        .as_ref()
        .map_or(st.photons_stored, |a| {
            a.photons_traced_stored + a.probes_met_caster
        });
    let ends = traced_stored + d.no_specular + d.escaped + d.negligible_power + d.bounce_limit;
    v.check(ends == st.photons_emitted + st.photon_splits, || {
        format!(
            "path ends {ends}, emitted {} + split branches {}",
            st.photons_emitted, st.photon_splits
        )
    });
    v.check(
        st.photons_deposited + d.off_screen == st.photons_stored,
        || {
            format!(
                "atlas outcomes {} + {}, stored {}",
                st.photons_deposited, d.off_screen, st.photons_stored
            )
        },
    );
    let rounding = 0.5 * st.flux_quantum * st.photons_stored as f64;
    let dispersive = scene.materials.values().any(Material::is_dispersive);
    let (stored, emitted): (f64, f64) = if dispersive {
        (st.stored_flux.iter().sum(), st.emitted_flux.iter().sum())
    } else {
        (st.stored_flux[0], st.emitted_flux[0])
    };
    // a spectral photon's channel sum changes with its wavelength (kept per channel in
    // expectation only): bounded by the largest gain a wavelength gives
    let gain = if dispersive {
        crate::harness::tolerance::spectral_sum_gain()
    } else {
        1.0
    };
    v.check(
        stored <= gain * emitted * (1.0 + 1e-6) + 3.0 * rounding,
        || format!("stored flux {stored:e} over emitted {emitted:e}"),
    );
    v.check(st.fixed_point_saturated == 0, || {
        "fixed-point saturation".into()
    });
    if b.name() != REFERENCE_BACKEND {
        let mut cpu = reference();
        let r = render_with(&mut cpu, scene, make).map_err(|e| format!("cpu: {e}"))?;
        let rs = &r.stats;
        let k = divergence_allowance(rs.photons_emitted);
        let traced = if AdaptiveStats::of(st).is_some() {
            k
        } else {
            0
        };
        v.check(
            rs.photons_emitted.abs_diff(st.photons_emitted) <= traced,
            || {
                format!(
                    "emitted counts differ: {} vs cpu {}",
                    st.photons_emitted, rs.photons_emitted
                )
            },
        );
        v.check(rs.emitted_flux == st.emitted_flux, || {
            "emitted flux differs".into()
        });
        let k = divergence_allowance(rs.photons_stored);
        v.check(rs.photons_stored.abs_diff(st.photons_stored) <= k, || {
            format!(
                "stored {} vs cpu {} (allowance {k})",
                st.photons_stored, rs.photons_stored
            )
        });
        let n = rs.photons_deposited.max(1) as f64;
        let bound = (2.0 * k as f64 / n).sqrt() + 1e-4;
        let e = relative_l2(&r.atlas.pixels, &f.atlas.pixels, None);
        v.check(e <= bound || rs.photons_deposited == 0, || {
            format!("atlas relative L2 {e:.2e} vs cpu over {bound:.2e}")
        });
        v.note(format!("atlas rel L2 vs cpu {e:.1e}"));
    }
    Ok(f)
}

pub(super) fn atlas_1x1(b: &mut dyn Backend) -> Result<Outcome, String> {
    let mut v = Verdict::new("1x1 atlas");
    let f = checked(b, &sphere_scene(), &settings(1), &mut v)?;
    // the floor's one texel holds every deposited photon's flux over the floor's area
    v.check(f.stats.photons_deposited > 0, || "nothing deposited".into());
    outcome(format!("texel irradiance {:.3e}", f.atlas.pixels[0][0]), v)
}

pub(super) fn atlas_16384(b: &mut dyn Backend) -> Result<Outcome, String> {
    let mut v = Verdict::new("16384^2 atlas");
    match CausticMap::new(b, &sphere_scene(), settings(16384)) {
        Err(Error::Backend(BackendError::OutOfMemory { bytes, what })) => {
            v.check(what.contains("max_atlas_bytes"), || {
                format!("the error does not say why: {what}")
            });
            outcome(format!("OutOfMemory {bytes} bytes"), v)
        }
        Err(e) => Err(format!(
            "16384^2 atlas: expected a typed OutOfMemory, got {e}"
        )),
        Ok(t) => {
            let _ = t.free(b);
            Err("16384^2 atlas under the default max_atlas_bytes was accepted".into())
        }
    }
}

pub(super) fn grazing_receiver(b: &mut dyn Backend) -> Result<Outcome, String> {
    // the sun 2 degrees above the floor through the ball: the caustic is a long streak
    // on the floor; a texel's photons arrive at cos 0.035
    let mut scene = sphere_scene();
    let a = 2f32.to_radians();
    scene.lights = vec![Light::Directional {
        direction: Vec3::new(a.cos(), -a.sin(), 0.0),
        irradiance: Vec3::ONE,
        projection_volume: None,
    }];
    let mut v = Verdict::new("grazing receiver");
    let f = checked(b, &scene, &settings(256), &mut v)?;
    outcome(format!("deposited {}", f.stats.photons_deposited), v)
}

pub(super) fn tiny_receiver(b: &mut dyn Backend) -> Result<Outcome, String> {
    // a receiver of 1e-6 units^2 beside the floor: its one texel has near-zero area
    // (irradiance = flux / 1e-6), finite
    let mut scene = sphere_scene();
    let m = scene.objects[0].material.clone();
    scene.objects.push(obj(
        "speck",
        &m,
        Shape::Quad {
            center: Vec3::new(0.0, 0.001, 0.0),
            u: Vec3::new(0.0005, 0.0, 0.0),
            v: Vec3::new(0.0, 0.0, 0.0005),
        },
    ));
    let mut v = Verdict::new("tiny receiver");
    let f = checked(b, &scene, &settings(256), &mut v)?;
    outcome(format!("deposited {}", f.stats.photons_deposited), v)
}

pub(super) fn uv_seams(b: &mut dyn Backend) -> Result<Outcome, String> {
    // A white box as the only receiver under the ball: its six faces are a 3x2 grid of UV
    // islands filling its tile, with seams between faces of different sizes (so texels of
    // different world areas meet there). Every texel centre is covered and every stored
    // photon lands on the box, so the raw map keeps the flux too.
    let mut scene = sphere_scene();
    scene.objects[0].shape = Shape::Cuboid {
        min: Vec3::new(-2.0, -0.5, -2.0),
        max: Vec3::new(2.0, 0.0, 2.0),
    };
    flux_kept(b, &scene, "uv seams", false)
}

/// The gather stays within the tile and keeps the flux: sum E x texel area over the atlas
/// equals the stored flux, for the 3x3 box gather, the density gather and the raw map.
/// The only differences are f32 roundings: the u64 sum to f32 (2^-24), the division by
/// the area and the product with it again (2 x 2^-24), summed in f64: relative 1e-5 is
/// over 40 times that. The density gather within 1e-4: each of its two passes adds the
/// rounding of a <= 33-term sum and a division per source (~35 ulp, 2e-6; the argument of
/// `filter_flux.rs`).
///
/// With `islands` (UV islands that leave texels uncovered: a photon within half a texel
/// of an island's border can land in a texel whose centre lies outside every triangle),
/// the raw map has no area to show that photon in: it shows the flux of the covered
/// texels, and the flux left in uncovered texels is reported and bounded by 1% (the
/// islands' half-texel border bands over their area: 3e-4 here). The box gather keeps it
/// (it spreads it over the covered texels of its window), and so does the density
/// gather: `gather_footprint` adds an uncovered texel's flux to its heir, a covered
/// neighbour of the same tile (`math::density_gather::atlas_edge_texels`), so both keep
/// the stored flux (1e-5 and 1e-4 as above).
fn flux_kept(
    b: &mut dyn Backend,
    scene: &Scene,
    what: &str,
    islands: bool,
) -> Result<Outcome, String> {
    let ds = caustica_core::device::device_scene::DeviceScene::build(scene, Default::default())
        .map_err(|e| e.to_string())?;
    let receiver = caustica_core::frame::receivers::atlas::layout::atlas_receivers(scene);
    let layout =
        caustica_core::frame::receivers::atlas::layout::atlas_layout(&ds, &receiver, (256, 256))
            .map_err(|e| e.to_string())?;
    let flux = |img: &Image| -> f64 {
        img.pixels
            .iter()
            .zip(&layout.texels)
            .map(|(p, t)| p[0] as f64 * f32::from_bits(t[0]) as f64)
            .sum()
    };
    let mut v = Verdict::new(what);
    let with = |gather, gather_width| CausticMapSettings {
        atlas: AtlasSettings {
            gather,
            gather_width,
            ..settings(256).atlas
        },
        ..settings(256)
    };
    use caustica_core::techniques::caustic_map::MapGather;
    let f = checked(b, scene, &with(MapGather::Box, 3), &mut v)?;
    let density = checked(b, scene, &with(MapGather::Density, 3), &mut v)?;
    let raw = checked(b, scene, &with(MapGather::Box, 1), &mut v)?;
    let stored = f.stats.stored_flux[0];
    v.check(stored > 0.0, || "nothing stored".into());
    let (g, d, r) = (flux(&f.atlas), flux(&density.atlas), flux(&raw.atlas));
    for (what, x, of, tol) in [
        ("gathered", g, stored, 1e-5),
        ("density", d, stored, 1e-4),
        ("raw", r, stored, if islands { 1e-2 } else { 1e-5 }),
    ] {
        v.check(((x - of) / of).abs() < tol, || {
            format!("{what} map flux {x:.7e} vs {of:.7e}")
        });
    }
    let mut key = format!(
        "gathered / stored {:.7}, density / stored {:.7}",
        g / stored,
        d / stored
    );
    if islands {
        key += &format!(
            ", in uncovered texels {:.1e} of stored",
            (stored - r) / stored
        );
    }
    outcome(key, v)
}

pub(super) fn generated_uv_charts(b: &mut dyn Backend) -> Result<Outcome, String> {
    // The floor as a mesh without UVs: a box of 8 shared corners (12 triangles), as an
    // OBJ or glTF file without texture coordinates has it. CausticMap refuses it by name
    // until `generate_missing_uvs` gives it charts (six, one per face, packed with
    // gutters), after which its caustic keeps the stored flux as any UV islands' does
    // ([`flux_kept`]).
    let mut scene = sphere_scene();
    let corners: Vec<Vec3> = (0..8)
        .map(|k| {
            Vec3::new(
                if k & 1 == 0 { -2.0 } else { 2.0 },
                if k & 2 == 0 { -0.5 } else { 0.0 },
                if k & 4 == 0 { -2.0 } else { 2.0 },
            )
        })
        .collect();
    // outward-facing quads (counter-clockwise seen from outside), two triangles each
    let quads = [
        [0, 4, 6, 2], // -x
        [1, 3, 7, 5], // +x
        [0, 1, 5, 4], // -y
        [2, 6, 7, 3], // +y
        [0, 2, 3, 1], // -z
        [4, 5, 7, 6], // +z
    ];
    let indices: Vec<[u32; 3]> = quads
        .iter()
        .flat_map(|q: &[u32; 4]| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
        .collect();
    scene.objects[0].shape = Shape::Mesh {
        positions: corners.into(),
        normals: Vec::new().into(),
        uvs: Vec::new().into(),
        indices: indices.into(),
    };
    let mut v = Verdict::new("generated uv charts");
    match CausticMap::new(b, &scene, settings(256)) {
        Err(Error::InvalidScene(why)) => {
            v.check(
                why.contains(&scene.objects[0].name) && why.contains("uv_charts"),
                || format!("unclear: {why}"),
            );
        }
        Err(e) => return Err(format!("expected InvalidScene, got {e}")),
        Ok(t) => {
            let _ = t.free(b);
            return Err("a receiver without UVs was accepted".into());
        }
    }
    let notes = caustica_core::scene::uv_charts::generate_missing_uvs(&mut scene);
    v.check(notes.len() == 1 && notes[0].contains("6 UV charts"), || {
        format!("{notes:?}")
    });
    let kept = flux_kept(b, &scene, "generated uv charts", true)?;
    v.absorb(kept.verdict);
    outcome(kept.key, v)
}

pub(super) fn overlapping_uvs(b: &mut dyn Backend) -> Result<Outcome, String> {
    // a receiver mesh whose two triangles share their UVs: a typed InvalidScene naming it
    let mut scene = sphere_scene();
    let m = scene.objects[0].material.clone();
    scene.objects[0] = obj(
        "folded floor",
        &m,
        Shape::Mesh {
            positions: vec![
                Vec3::new(-2.0, 0.0, 2.0),
                Vec3::new(2.0, 0.0, 2.0),
                Vec3::new(2.0, 0.0, -2.0),
                Vec3::new(-2.0, 0.0, -2.0),
            ]
            .into(),
            normals: Vec::new().into(),
            uvs: vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(1.0, 0.0),
            ]
            .into(),
            indices: vec![[0, 1, 2], [0, 2, 3]].into(),
        },
    );
    let mut v = Verdict::new("overlapping uvs");
    match CausticMap::new(b, &scene, settings(64)) {
        Err(Error::InvalidScene(why)) => {
            v.check(
                why.contains("folded floor") && why.contains("overlap"),
                || format!("unclear: {why}"),
            );
            outcome("InvalidScene".into(), v)
        }
        Err(e) => Err(format!("expected InvalidScene, got {e}")),
        Ok(t) => {
            let _ = t.free(b);
            Err("overlapping UVs were accepted".into())
        }
    }
}

pub(super) fn ball_glass(b: &mut dyn Backend) -> Result<Outcome, String> {
    // IOR near 1 and very high on the caster: finite, accounted, agrees with cpu
    let mut v = Verdict::new("ior extremes");
    for ior in [1.0001f32, 4.0] {
        let mut scene = sphere_scene();
        for m in scene.materials.values_mut() {
            if matches!(m, Material::Dielectric { .. }) {
                *m = glass(ior);
            }
        }
        checked(b, &scene, &settings(128), &mut v)?;
    }
    outcome("ior 1.0001 and 4".into(), v)
}

pub(super) fn dispersion_split(b: &mut dyn Backend) -> Result<Outcome, String> {
    // the dispersive prism with Vanderstichelen 2021's deterministic splits (three one-channel branches at
    // the first dispersive surface, both Fresnel branches at every glass surface) and with
    // the stochastic choice: finite, accounted (path ends = emitted + splits), both agree
    // with cpu, and the two store the same flux per channel in expectation (within 3% at
    // 256^2 photons a light: the stochastic run's channel choice has a standard error of
    // about sqrt(2 / n) over its n ~ 27k stored photons, 0.9%, so 3% is 3.5 of them)
    let mut scene = caustica_core::scene::builtin::builtin("prism").expect("built-in");
    (scene.camera.width, scene.camera.height) = super::SIZE;
    let mut v = Verdict::new("dispersion split");
    use caustica_core::techniques::caustic_map::FresnelSplit;
    let with = |fresnel_split| CausticMapSettings {
        frame: FrameSettings {
            photons_w: 256,
            photons_h: 256,
            ..settings(128).frame
        },
        planes: PlaneSettings {
            fresnel_split,
            ..settings(128).planes
        },
        ..settings(128)
    };
    let split = checked(b, &scene, &with(FresnelSplit::Deterministic), &mut v)?;
    let stochastic = checked(b, &scene, &with(FresnelSplit::Stochastic), &mut v)?;
    v.check(split.stats.photon_splits > 0, || {
        "no branch was split".into()
    });
    for c in 0..3 {
        let (a, s) = (split.stats.stored_flux[c], stochastic.stats.stored_flux[c]);
        v.check((a / s - 1.0).abs() < 0.03, || {
            format!("channel {c}: split stores {a:.5e} W, stochastic {s:.5e} W")
        });
    }
    outcome(
        format!(
            "splits {}, stored {} vs {}",
            split.stats.photon_splits, split.stats.photons_stored, stochastic.stats.photons_stored
        ),
        v,
    )
}

pub(super) fn schlick(b: &mut dyn Backend) -> Result<Outcome, String> {
    // Vanderstichelen 2021's Schlick reflectance on `sphere`, with the deterministic split and the
    // stochastic choice: finite, accounted, both agree with cpu. With the split the photons
    // of the two models follow the same rays, and only the branch weights differ, so the
    // ratio of their stored flux is the closed forms' (`sphere_closed_form.rs`: Schlick
    // 1.77532 W, exact 1.74909 W on the plane, ratio 1.0150); the grid of 128^2 texels
    // samples the two smooth integrands alike, so the ratio must agree within 0.3% (a
    // fifth of the models' difference).
    use caustica_core::techniques::caustic_map::{FresnelModel, FresnelSplit};
    let mut v = Verdict::new("schlick");
    let scene = sphere_scene();
    let run = |b: &mut dyn Backend, fresnel, split, v: &mut Verdict| {
        checked(
            b,
            &scene,
            &CausticMapSettings {
                planes: PlaneSettings {
                    fresnel,
                    fresnel_split: split,
                    ..settings(128).planes
                },
                ..settings(128)
            },
            v,
        )
    };
    let schlick = run(
        b,
        FresnelModel::Schlick,
        FresnelSplit::Deterministic,
        &mut v,
    )?;
    let exact = run(b, FresnelModel::Exact, FresnelSplit::Deterministic, &mut v)?;
    run(b, FresnelModel::Schlick, FresnelSplit::Stochastic, &mut v)?;
    let ratio = schlick.stats.stored_flux[0] / exact.stats.stored_flux[0];
    v.check((ratio - 1.0150).abs() < 0.003, || {
        format!("stored flux Schlick / exact {ratio:.5}, closed form 1.0150")
    });
    outcome(format!("stored flux Schlick / exact {ratio:.5}"), v)
}

//! The [`Sspm`] technique, whole frames: photon statistics (emitted equal, stored and
//! deposited within the path-divergence allowance, stored flux) and image relative L2 error
//! of the caustics, per-pixel agreement of the direct light, all over the pixels whose
//! G-buffers agree ([`compare_frames`] argues each bound).

use crate::harness::measure::relative_l2;
use crate::harness::tolerance::{
    divergence_allowance, PATH_DIVERGENCE, PHOTON_FLUX_REL, SPECTRAL_FLUX_REL,
};
use crate::harness::verdict::Verdict;
use crate::kernels::direct_light::compare_direct;
use crate::kernels::primary_gbuffer::compare_gbuffers;
use caustica_core::backend::{read_gbuffer, Backend};
use caustica_core::device::layout::{GBufferTexel, GpuCamera};
use caustica_core::frame::image::Image;
use caustica_core::math::fixed_point::MAX_PHOTON_QUANTA;
use caustica_core::scene::Scene;
use caustica_core::{FrameStats, Output, Sspm, SspmSettings};

/// Everything a frame produces that the comparison reads.
pub struct Frame {
    pub stats: FrameStats,
    pub gbuffer: Vec<GBufferTexel>,
    pub composite: Image,
    pub raw: Image,
    pub filtered: Image,
    pub direct: Image,
}

/// Renders one [`Sspm`] frame of `scene` (its own camera and resolution) on `b`.
pub fn render_frame(
    b: &mut dyn Backend,
    scene: &Scene,
    settings: &SspmSettings,
) -> Result<Frame, String> {
    let name = b.name();
    let err = |e: caustica_core::Error| format!("sspm on backend {name}: {e}");
    let mut s = Sspm::new(b, scene, settings.clone()).map_err(err)?;
    let stats = s.frame(b, &mut |_| {}).map_err(err)?;
    let frame = Frame {
        stats,
        gbuffer: read_gbuffer(b, &s.gbuffer()).map_err(|e| format!("reading the G-buffer: {e}"))?,
        composite: s.read_output(b, Output::Composite).map_err(err)?,
        raw: s.read_output(b, Output::RawCaustics).map_err(err)?,
        filtered: s.read_output(b, Output::FilteredCaustics).map_err(err)?,
        direct: s.read_output(b, Output::Direct).map_err(err)?,
    };
    s.free(b).map_err(err)?;
    Ok(frame)
}

/// Compares two frames of the same scene and settings (reference first).
///
/// - G-buffer: as [`compare_gbuffers`]; `q` = fraction of pixels that do not agree.
/// - Photons: emitted count, emitted flux, flux quantum and batch count equal (host-side
///   arithmetic, identical); each backend's path ends add up to the emitted count; stored
///   counts within [`divergence_allowance`]; deposited counts within
///   `ceil((PATH_DIVERGENCE + q) n) + 2` (a G-buffer difference changes the deposit of the
///   photons landing there; this assumes photons are no denser on those pixels than on
///   average); stored flux within the diverged photons' flux (<= 2^24 quanta each) plus
///   [`PHOTON_FLUX_REL`].
/// - Raw and filtered caustics, over the pixels whose G-buffers agree: relative L2 error
///   `<= sqrt(2 k / n) + 1e-4` with `n` deposited photons and `k` their allowance. A
///   diverged photon removes its radiance from one pixel and adds it to another; with `k`
///   such photons among `n` of comparable radiance spread over distinct pixels, the error
///   norm is `sqrt(2 k)` photon-radiances against a norm of at least `sqrt(n)` (photons
///   that share a pixel only raise the reference's norm); the gather is a normalised
///   average, which spreads both norms alike. 1e-4 covers per-pixel rounding
///   ([`RESOLVE_REL`], [`GATHER_REL`]).
/// - Direct light, over the pixels whose G-buffers agree: per pixel as [`DIRECT_REL`] on
///   [`DIRECT_AGREEMENT`] of them.
///
/// [`RESOLVE_REL`]: crate::harness::tolerance::RESOLVE_REL
/// [`GATHER_REL`]: crate::harness::tolerance::GATHER_REL
/// [`DIRECT_REL`]: crate::harness::tolerance::DIRECT_REL
/// [`DIRECT_AGREEMENT`]: crate::harness::tolerance::DIRECT_AGREEMENT
pub fn compare_frames(scene: &Scene, a: &Frame, b: &Frame) -> Verdict {
    let mut v = Verdict::new("sspm frame");
    let cam = GpuCamera::from_camera(&scene.camera);
    // the geometric normals' edge ties are resolved against the scene's triangles
    let ds = caustica_core::device::device_scene::DeviceScene::build(scene, Default::default());
    let (gv, agree) = match &ds {
        Ok(ds) => compare_gbuffers(ds, &cam, &a.gbuffer, &b.gbuffer),
        Err(e) => {
            v.check(false, || format!("the scene does not build: {e}"));
            return v;
        }
    };
    let disagree = agree.iter().filter(|x| !**x).count() as u64;
    let q = disagree as f64 / agree.len().max(1) as f64;
    v.absorb(gv);
    let (sa, sb) = (&a.stats, &b.stats);
    v.check(sa.photons_emitted == sb.photons_emitted, || {
        format!(
            "emitted {} photons, cpu {}",
            sb.photons_emitted, sa.photons_emitted
        )
    });
    v.check(sa.emitted_flux == sb.emitted_flux, || {
        format!(
            "emitted flux {:?}, cpu {:?}",
            sb.emitted_flux, sa.emitted_flux
        )
    });
    v.check(
        sa.flux_quantum == sb.flux_quantum && sa.batches == sb.batches,
        || {
            format!(
                "flux quantum {} / {} batches, cpu {} / {}",
                sb.flux_quantum, sb.batches, sa.flux_quantum, sa.batches
            )
        },
    );
    for (who, s) in [("cpu", sa), ("candidate", sb)] {
        let d = &s.discarded;
        let ends =
            s.photons_stored + d.no_specular + d.escaped + d.negligible_power + d.bounce_limit;
        v.check(ends == s.photons_emitted, || {
            format!(
                "{who}: path ends add up to {ends}, {} emitted",
                s.photons_emitted
            )
        });
        let dep = s.photons_deposited + d.off_screen + d.depth_mismatch;
        v.check(dep == s.photons_stored, || {
            format!(
                "{who}: deposit outcomes add up to {dep}, {} stored",
                s.photons_stored
            )
        });
    }
    let diff = |x: u64, y: u64| (x as i64 - y as i64).unsigned_abs();
    let n_stored = sa.photons_stored.max(sb.photons_stored);
    let allow_stored = divergence_allowance(n_stored);
    v.check(
        diff(sa.photons_stored, sb.photons_stored) <= allow_stored,
        || {
            format!(
                "stored {} photons, cpu {} (allowed difference {allow_stored})",
                sb.photons_stored, sa.photons_stored
            )
        },
    );
    let n_dep = sa.photons_deposited.max(sb.photons_deposited);
    let allow_dep = ((PATH_DIVERGENCE + q) * n_dep as f64).ceil() as u64 + 2;
    v.check(
        diff(sa.photons_deposited, sb.photons_deposited) <= allow_dep,
        || {
            format!(
                "deposited {} photons, cpu {} (allowed difference {allow_dep})",
                sb.photons_deposited, sa.photons_deposited
            )
        },
    );
    let max_photon_flux = sa.flux_quantum * MAX_PHOTON_QUANTA as f64;
    // photons of a spectral colour (the default on a dispersive scene) differ by up to
    // SPECTRAL_FLUX_REL of their largest channel in every channel
    let spectral = if scene.materials.values().any(|m| m.is_dispersive()) {
        SPECTRAL_FLUX_REL
    } else {
        0.0
    };
    let all = |f: [f64; 3]| f[0] + f[1] + f[2];
    for ch in 0..3 {
        let (x, y) = (sa.stored_flux[ch], sb.stored_flux[ch]);
        let bound = allow_stored as f64 * max_photon_flux
            + PHOTON_FLUX_REL * x.max(y)
            + spectral * all(sa.stored_flux).max(all(sb.stored_flux));
        v.check((x - y).abs() <= bound, || {
            format!("stored flux[{ch}] {y:.6e}, cpu {x:.6e} (allowed {bound:.3e})")
        });
    }
    v.check(
        sa.fixed_point_saturated == 0 && sb.fixed_point_saturated == 0,
        || {
            format!(
                "fixed-point saturation: {} (cpu {})",
                sb.fixed_point_saturated, sa.fixed_point_saturated
            )
        },
    );
    // Images.
    let image_bound = if n_dep == 0 {
        0.0
    } else {
        (2.0 * allow_dep as f64 / n_dep as f64).sqrt() + 1e-4
    };
    for (name, x, y) in [
        ("raw caustics", &a.raw, &b.raw),
        ("filtered caustics", &a.filtered, &b.filtered),
    ] {
        let e = relative_l2(&x.pixels, &y.pixels, Some(&agree));
        v.check(e <= image_bound, || {
            format!("{name}: relative L2 error {e:.3e} (allowed {image_bound:.3e})")
        });
        v.note(format!(
            "{name}: relative L2 {e:.3e} (allowed {image_bound:.3e})"
        ));
        for (who, img) in [("cpu", x), ("candidate", y)] {
            v.check(img.all_finite(), || format!("{who}: {name} has NaN/Inf"));
        }
    }
    v.absorb(compare_direct(
        "direct",
        cam.width,
        &a.direct.pixels,
        &b.direct.pixels,
        Some(&agree),
    ));
    v.note(format!(
        "emitted {}, stored {} vs cpu {}, deposited {} vs cpu {}; G-buffer disagrees on {disagree} pixels",
        sa.photons_emitted, sb.photons_stored, sa.photons_stored, sb.photons_deposited, sa.photons_deposited
    ));
    v
}

/// Renders `scene` with `settings` on both backends and compares the frames.
pub fn check_frame(
    reference: &mut dyn Backend,
    candidate: &mut dyn Backend,
    scene: &Scene,
    settings: &SspmSettings,
) -> Result<Verdict, String> {
    let a = render_frame(reference, scene, settings)?;
    let b = render_frame(candidate, scene, settings)?;
    Ok(compare_frames(scene, &a, &b))
}

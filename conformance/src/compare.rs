//! Backend-generic comparison of any backend with the CPU reference (DESIGN 3 and 4).
//!
//! Two levels, as DESIGN 4 asks:
//!
//! - **per kernel, on fixed inputs**: each kernel is driven through a [`Recording`] on both
//!   backends with *the same* input buffers (the scene, and for the later kernels the
//!   CPU's G-buffer, photon list, photon map and images, uploaded to both), so that only
//!   the kernel itself can make the outputs differ. Tolerances are tight and argued from
//!   floating-point facts below.
//! - **per technique**: a whole [`Sspm`] frame on each backend, compared by photon
//!   statistics (emitted equal, stored and deposited within a path-divergence allowance,
//!   total flux) and image relative L2 error.
//!
//! # Floating-point facts the tolerances rest on
//!
//! - f32 unit roundoff is `2^-24 ~ 6e-8` ([`F32_ROUNDOFF`]): a correctly rounded operation
//!   errs by at most that relative amount. Rust on the CPU rounds `+ - * /` and `sqrt`
//!   correctly and never contracts `a * b + c` into an FMA unless asked.
//! - OpenCL C 1.2 single precision (spec. section 7.4) allows `x / y` and `1 / x` 2.5 ulp,
//!   `sqrt` 3 ulp, `exp` 3 ulp, `sin`/`cos` 4 ulp and `pow` 16 ulp; GPU compilers contract
//!   `a * b + c` into FMAs (1 rounding instead of 2) and may flush subnormals to zero.
//!   WGSL and Vulkan SPIR-V give similar or looser bounds.
//! - So an expression of ~10 operations agrees across backends to ~10-30 ulp ~ 1e-6
//!   relative, unless it cancels (a difference of nearly equal numbers, a dot product of
//!   nearly orthogonal vectors), where the *absolute* error stays ~ulp of the operands.
//! - A ray whose direction differs by ~1e-6 follows the same path unless it passes within
//!   ~1e-6 (relative) of a discrete decision: a triangle edge between faces with different
//!   normals, a silhouette, a Fresnel choice `xi < F`, the total-internal-reflection
//!   boundary, a pixel boundary, a depth-test threshold. Refraction through curved
//!   surfaces amplifies a direction error by ~`1 + L / R` per interaction, so a long
//!   chain widens these bands; still only a small fraction of photon paths diverge
//!   ([`PATH_DIVERGENCE`]), and each diverged path changes a count by at most one photon
//!   and a flux by at most one photon's flux.
//! - Integer sums (the fixed-point photon map and counters) are exact and
//!   order-independent on every backend: inputs that agree give bitwise-equal sums.
//!
//! A tolerance is never widened to make a backend pass (DESIGN 4): a failure is a bug in
//! the backend, in the CPU reference, or in an argument here, to be understood first.

use crate::strategies::MIN_CURVATURE_RADIUS;
use caustica_core::kernels::{BilateralGather, Composite, DepositScreen, DirectLight, PrimaryGbuffer, ResolveCaustics, TileHitDistance, TracePhotons};
use caustica_core::backend::{read_buf, Backend, BackendError};
use caustica_core::device::device_scene::DeviceScene;
use caustica_core::math::fixed_point::{join_u64, MAX_PHOTON_QUANTA};
use caustica_core::math::footprint::MIN_COSINE;
use caustica_core::device::layout::{
    camera_ray, counter, gbuffer_flags, DepositTexel, GBufferTexel, GpuCamera, Photon, NO_MATERIAL,
};
use caustica_core::frame::image::Image;
use caustica_core::device::handle::SceneArgs;
use caustica_core::kernels::Kernel;
use caustica_core::recording::{Recording, Step};
use caustica_core::scene::Scene;
use caustica_core::techniques::sspm::FrameConstants;
use caustica_core::{FrameStats, Output, Sspm, SspmSettings};
use caustica_cpu::CpuBackend;
use glam::Vec3;
use std::collections::HashMap;
use std::fmt;
use std::io::Write;

// ---------------------------------------------------------------------------------------
// Tolerances, each with its argument.
// ---------------------------------------------------------------------------------------

/// f32 unit roundoff, `2^-24`.
pub const F32_ROUNDOFF: f64 = 5.960_464_477_539_063e-8;

/// `primary_gbuffer`: fraction of pixels whose material id must agree (99.5%).
///
/// A pixel's material can differ only where its camera ray passes within a few ulps of a
/// silhouette or of a triangle edge (core's Moller-Trumbore test is not watertight, so a
/// ray exactly through a shared edge may slip between both triangles, which a watertight
/// hardware test never does). The camera ray is a handful of operations ending in a
/// normalisation (3-ulp sqrt, 2.5-ulp divide): directions agree to ~5e-7 rad, which at
/// these resolutions (~0.01 rad per pixel) is ~5e-5 of a pixel. For cameras in general
/// position the expected number of affected pixels is far below one per image; 0.5% is
/// the margin for edges that line up with pixel centres by symmetry (a whole row or
/// diagonal of exact ties: see [`BUILTIN_SIZE`] for the one the built-ins have, which the
/// fixed inputs avoid).
pub const GBUFFER_MATERIAL_AGREEMENT: f64 = 0.995;

/// `primary_gbuffer`: positions, view depth and view distance must agree within
/// `GBUFFER_POSITION_REL * (t / max(|cos|, GBUFFER_MIN_COS) + |p|)`, where `t` is the view
/// distance, `cos` the cosine between the camera ray and the surface normal, `|p|` the
/// largest coordinate.
///
/// Argument: a ~5e-7 rad direction difference moves the hit point along the surface by
/// `t * 5e-7 / |cos|`; the ray/triangle test (two cross products, three dots, a ~2.5-ulp
/// reciprocal: ~10 ulp ~ 6e-7 relative) adds `t * 6e-7 / |cos|` (its determinant scales
/// with `cos`); interpolating the position from barycentrics adds ~3 ulp of `|p|`. Sum:
/// `~1.1e-6 * t / |cos| + 2e-7 * |p|`; 1e-5 leaves a 9x margin. Rays more grazing than
/// `GBUFFER_MIN_COS` get no further slack and count among the outliers
/// ([`GBUFFER_GEOMETRY_AGREEMENT`]).
pub const GBUFFER_POSITION_REL: f32 = 1e-5;
/// See [`GBUFFER_POSITION_REL`].
pub const GBUFFER_MIN_COS: f32 = 1e-3;

/// `primary_gbuffer`: how fast the interpolated shading normal can turn per scene unit
/// along a surface (rad per unit). Flat faces: 0 (normals agree to normalisation rounding,
/// ~3e-7). Smooth tessellated spheres: `1 / R`, and the smallest radius generated or built
/// in is [`MIN_CURVATURE_RADIUS`] = 0.1 (the pool's waves curve with radius >= 0.3), so 10;
/// twice that for margin. Normals must agree within `1e-5 + NORMAL_GRADIENT * position
/// tolerance`.
pub const NORMAL_GRADIENT: f32 = 2.0 / MIN_CURVATURE_RADIUS;

/// `primary_gbuffer`: the same for texture coordinates (uv per scene unit). The worst case
/// is a UV sphere's polar triangles, where u spans `1 / segments` over a ring edge of length
/// `2 pi R sin(pi / rings) / segments`: gradient `1 / (2 pi R sin(pi / rings))`, at most
/// ~12 for the generated spheres (R >= 0.1, <= 24 rings) and ~10 for the built-ins; 50
/// leaves a 4x margin.
pub const UV_GRADIENT: f32 = 50.0;

/// `primary_gbuffer`: among pixels with equal material, the fraction whose geometry must
/// agree within the tolerances above (99.9%). The rest are rays within a few ulps of an
/// edge between faces with different normals (a box or prism edge: the position agrees but
/// the normal jumps) or more grazing than `GBUFFER_MIN_COS`; as for materials, the
/// expected count is far below one pixel per image.
pub const GBUFFER_GEOMETRY_AGREEMENT: f64 = 0.999;

/// Fraction of photon paths that may diverge between two correct backends (1%).
///
/// Emission directions come from `sin`/`cos` (4 ulp in OpenCL) and a normalisation, so
/// they agree to a few 1e-7. A path diverges only where a perturbation of that size, grown
/// by ~`1 + L / R` per curved interaction, crosses a discrete decision (module docs):
/// per decision the chance is the band width over the decision variable's range, ~1e-6
/// for the first interactions and at most ~1e-3 after a dozen amplifying ones (the bounce
/// limit is 12). Expected divergence is therefore well below 0.1% of the paths; 1% is a
/// 10x margin. Each diverged path moves one photon (count +-1, flux +- one photon's flux),
/// hence [`divergence_allowance`].
pub const PATH_DIVERGENCE: f64 = 0.01;

/// Photon count difference allowed among `n` photons: `ceil(PATH_DIVERGENCE * n) + 2` (the
/// `+ 2`: one diverged path in each direction must not fail a case with a handful of
/// photons).
pub fn divergence_allowance(n: u64) -> u64 {
    (PATH_DIVERGENCE * n as f64).ceil() as u64 + 2
}

/// `trace_photons`: a photon of one backend *matches* when the other stored a photon
/// within `PHOTON_POSITION_REL * scene diagonal` whose flux agrees within
/// [`photon_flux_match_rel`]. A non-diverged path's landing point
/// differs by its initial ~1e-6 relative error times the chaotic amplification, ~3 per
/// curved interaction (`1 + L / R` with `L ~ 2R` inside a ball): <= 3^4 = 81 for the <= 4
/// interactions of nearly every stored photon, i.e. < 1e-4 relative; 1e-3 is a 10x margin.
/// Longer chains that stray further are part of the [`PATH_DIVERGENCE`] allowance.
pub const PHOTON_POSITION_REL: f32 = 1e-3;

/// `trace_photons`: fraction of each backend's photons that must match one of the other's
/// (99%, from [`PATH_DIVERGENCE`]), plus 2 photons of slack.
pub const PHOTON_MATCH: f64 = 1.0 - PATH_DIVERGENCE;

/// Relative flux tolerance of a photon match: [`PHOTON_FLUX_REL`] plus Beer-Lambert over
/// a path inside a medium whose length differs by up to twice the position tolerance `tol`
/// (entry and exit points each within `tol`): `exp(2 sigma_max tol) - 1`, `sigma_max` the
/// largest absorption coefficient of the scene. Channel choice (dispersion), mirror
/// reflectances and the Fresnel branch are the same on a non-diverged path.
pub fn photon_flux_match_rel(scene: &Scene, tol: f32) -> f32 {
    let sigma_max = scene
        .materials
        .values()
        .map(|m| match m {
            caustica_core::scene::Material::Dielectric { absorption, .. } => {
                absorption.max_element()
            }
            _ => 0.0,
        })
        .fold(0.0f32, f32::max);
    PHOTON_FLUX_REL as f32 + (2.0 * sigma_max * tol).exp_m1()
}

/// Relative flux difference of a non-diverged photon: at most 12 interactions, each a
/// Beer-Lambert `exp` (3 ulp) and a couple of multiplies: ~60 ulp ~ 4e-6; 1e-5 is the
/// bound used for flux sums on top of the diverged photons' whole flux.
pub const PHOTON_FLUX_REL: f64 = 1e-5;

/// `deposit_screen` on the same photons and G-buffer: fraction of photon-map texels that
/// must be bitwise equal (99.9%). The sums are integers, so a texel differs only when a
/// photon's outcome differs: its projected pixel coordinate (two dots and a 2.5-ulp
/// division) within a few ulps of a pixel boundary, its view depth within a few ulps of
/// the depth-test threshold, or its direction within a few ulps of perpendicular to the
/// normal. Each band is ~1e-6 of its variable's range, so ~1e-5 of the photons at most;
/// each changes at most two texels.
pub const DEPOSIT_TEXEL_AGREEMENT: f64 = 0.999;

/// `deposit_screen`: photons whose outcome may differ, as a fraction of the photons (see
/// [`DEPOSIT_TEXEL_AGREEMENT`]: ~1e-5 expected, 1e-3 allowed), plus 2.
pub const DEPOSIT_PHOTON_CHANGES: f64 = 1e-3;

/// `resolve_caustics` on bitwise-equal texels: relative radiance tolerance
/// `RESOLVE_REL + RESOLVE_COS_REL / max(|cos|, MIN_COSINE)`. Radiance is
/// `units * quantum * albedo / (pi * area)` with `area` from the pixel footprint (~6
/// operations, one division) and the obliquity `|ray . f| / |ray . n|`: u64 -> float
/// conversion 0.5 ulp, ~10 roundings plus two 2.5-ulp divisions and the camera ray's
/// normalisation: ~20 ulp ~ 1.2e-6, hence 1e-5. The dot `ray . n` has an absolute error of
/// a few ulps (~2.4e-7), a relative one of `2.4e-7 / |cos|`: hence 1e-6 / |cos|.
pub const RESOLVE_REL: f32 = 1e-5;
/// See [`RESOLVE_REL`].
pub const RESOLVE_COS_REL: f32 = 1e-6;

/// `tile_hit_distance`: relative tolerance. Integer sums of the same photon map are exact;
/// the mean is two conversions, a multiply and a 2.5-ulp division: ~4 ulp; 1e-5 is ~40x.
pub const TILE_REL: f32 = 1e-5;

/// `bilateral_gather` on the same inputs: relative tolerance per pixel and channel.
///
/// The output is a normalised weighted mean `sum(w x) / sum(w)` of non-negative inputs with
/// weights `exp(.) * exp(.) * pow(.)` (3 + 3 + 16 ulp in OpenCL, plus the products: ~25 ulp
/// ~ 1.5e-6 each). For non-negative terms a relative weight error `e` changes the mean by at
/// most `2 e` relative, and summing <= 33 taps in another order by at most ~33 ulp ~ 2e-6:
/// ~5e-6 in all, so 1e-5. Pixels whose radius `r` lies within 1e-5 of an integer are left
/// out: there `ceil(r)`, the number of taps, is not determined by floating point, and the
/// extra tap's weight `exp(-2 ceil(r)^2 / r^2) ~ 0.13` is not small.
pub const GATHER_REL: f32 = 1e-5;

/// `direct_light` on the same G-buffer: a pixel agrees when
/// `|a - b| <= DIRECT_REL * max(|a|, |b|) + DIRECT_FLOOR * (channel maximum)`.
///
/// Diffuse pixels: `albedo / pi * I * cos * falloff / d^2` with a sqrt, a divide and a dot:
/// ~10 ulp ~ 1e-6. The spot smoothstep divides by `cos_inner - cos_outer` (>= 0.005 for the
/// cones generated, half-angles 0.5 degrees apart at 40), amplifying the ~1e-7 cosine error
/// to <= 2e-5. Mirror and glass pixels follow a chain whose end point moves by ~1e-6 times
/// ~3 per curved interaction; the branches that carry weight are the first 2-3 (Fresnel
/// weights fall as `F^k`): <= 3e-5. Hence 1e-4. The floor covers values near zero whose
/// relative error is unbounded (the outer edge of a spot cone, where the smoothstep ~ 3t^2).
pub const DIRECT_REL: f32 = 1e-4;
/// See [`DIRECT_REL`].
pub const DIRECT_FLOOR: f32 = 1e-6;

/// `direct_light`: fraction of pixels that must agree (99%). The others are pixels whose
/// shadow ray or specular chain passes within a few (amplified) ulps of an occluder's
/// silhouette or a triangle edge, or crosses a total-internal-reflection or `min_weight`
/// decision, or sits on the hard edge of a spot whose inner and outer angles are equal;
/// silhouettes cover a few percent of the pixels and the flip band is ~1e-4 of a pixel
/// wide, so 1% is a wide margin.
pub const DIRECT_AGREEMENT: f64 = 0.99;

// ---------------------------------------------------------------------------------------
// Backends under test.
// ---------------------------------------------------------------------------------------

/// A backend compared against the CPU reference.
pub struct Candidate {
    /// Backend name (`opencl`, ...), or `cpu[1 thread]` when no other backend exists.
    pub name: String,
    pub device: String,
    pub backend: Box<dyn Backend>,
}

/// Prints to the process's stderr even while the test harness captures output.
pub fn loud(msg: &str) {
    let _ = writeln!(std::io::stderr().lock(), "\n*** {msg} ***");
}

/// Every backend of [`crate::backends`] except `cpu`. With none, a fresh 1-thread
/// [`CpuBackend`] stands in, so that every comparison still runs and asserts something
/// (and the suite itself is tested). Announces, loudly, what is compared with what.
pub fn candidates(test: &str) -> Vec<Candidate> {
    let mut out: Vec<Candidate> = crate::backends()
        .into_iter()
        .filter(|(name, _)| *name != "cpu")
        .map(|(name, b)| Candidate {
            name: name.to_string(),
            device: b.capabilities().device,
            backend: b,
        })
        .collect();
    if out.is_empty() {
        let b = CpuBackend::with_threads(1).expect("a 1-thread CPU backend");
        out.push(Candidate {
            name: "cpu[1 thread]".into(),
            device: b.capabilities().device,
            backend: Box::new(b),
        });
        loud(&format!(
            "{test}: NO BACKEND OTHER THAN cpu IS AVAILABLE; comparing a second, 1-thread \
             cpu backend with the cpu reference (this checks the suite, not a backend)"
        ));
    }
    let list: Vec<String> = out
        .iter()
        .map(|c| format!("{} ({})", c.name, c.device))
        .collect();
    loud(&format!(
        "{test}: comparing [{}] against the cpu reference",
        list.join(", ")
    ));
    out
}

/// The reference: the CPU backend on every core.
pub fn reference() -> CpuBackend {
    CpuBackend::new().expect("the CPU reference backend")
}

// ---------------------------------------------------------------------------------------
// Verdicts and reports.
// ---------------------------------------------------------------------------------------

/// The outcome of one comparison: measured numbers (notes) and failed checks.
#[derive(Clone, Debug, Default)]
pub struct Verdict {
    pub what: String,
    pub notes: Vec<String>,
    pub failures: Vec<String>,
}

impl Verdict {
    pub fn new(what: impl Into<String>) -> Verdict {
        Verdict {
            what: what.into(),
            ..Default::default()
        }
    }

    pub fn note(&mut self, s: impl Into<String>) {
        self.notes.push(s.into());
    }

    /// Records a failure unless `ok`; returns `ok`.
    pub fn check(&mut self, ok: bool, msg: impl FnOnce() -> String) -> bool {
        if !ok {
            self.failures.push(msg());
        }
        ok
    }

    pub fn fail(&mut self, msg: impl Into<String>) {
        self.failures.push(msg.into());
    }

    /// Adds another verdict's notes and failures, prefixed with its name.
    pub fn absorb(&mut self, other: Verdict) {
        for n in other.notes {
            self.notes.push(format!("{}: {n}", other.what));
        }
        for f in other.failures {
            self.failures.push(format!("{}: {f}", other.what));
        }
    }

    pub fn passed(&self) -> bool {
        self.failures.is_empty()
    }
}

impl fmt::Display for Verdict {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let tag = if self.passed() { "ok  " } else { "FAIL" };
        writeln!(f, "[{tag}] {}", self.what)?;
        for n in &self.notes {
            writeln!(f, "         {n}")?;
        }
        for x in &self.failures {
            writeln!(f, "   !!!   {x}")?;
        }
        Ok(())
    }
}

/// Collects the verdicts of one test over backends and cases; [`Report::finish`] panics
/// with every failure at once, so a backend author sees all departures in one run.
pub struct Report {
    test: String,
    verdicts: Vec<Verdict>,
}

impl Report {
    pub fn new(test: &str) -> Report {
        Report {
            test: test.into(),
            verdicts: Vec::new(),
        }
    }

    /// Adds `v` as "`backend` / `case`: what".
    pub fn add(&mut self, backend: &str, case: &str, mut v: Verdict) {
        v.what = format!("{backend} / {case}: {}", v.what);
        eprint!("{v}");
        self.verdicts.push(v);
    }

    /// Adds an error that prevented a comparison.
    pub fn error(&mut self, backend: &str, case: &str, e: String) {
        let mut v = Verdict::new("could not run");
        v.fail(e);
        self.add(backend, case, v);
    }

    /// Names ("backend / case: what") of the verdicts that passed.
    pub fn passed_cases(&self) -> Vec<String> {
        self.verdicts
            .iter()
            .filter(|v| v.passed())
            .map(|v| v.what.clone())
            .collect()
    }

    pub fn finish(self) {
        let failed: Vec<&Verdict> = self.verdicts.iter().filter(|v| !v.passed()).collect();
        let msg = format!(
            "{}: {} comparisons, {} failed",
            self.test,
            self.verdicts.len(),
            failed.len()
        );
        loud(&msg);
        if !failed.is_empty() {
            let all: String = failed.iter().map(|v| v.to_string()).collect();
            panic!("{msg}\n{all}");
        }
    }
}

// ---------------------------------------------------------------------------------------
// Running kernels.
// ---------------------------------------------------------------------------------------

fn backend_err(kernel: &str, b: &dyn Backend) -> impl FnOnce(BackendError) -> String {
    let name = b.name();
    let kernel = kernel.to_string();
    move |e| format!("{kernel} on backend {name}: {e}")
}

/// Executes `rec`, reads what `read` asks for, then frees every buffer `rec` created.
fn run_and_free<T>(
    b: &mut dyn Backend,
    what: &str,
    rec: &Recording,
    read: impl FnOnce(&mut dyn Backend) -> Result<T, BackendError>,
) -> Result<T, String> {
    b.execute(rec).map_err(backend_err(what, b))?;
    let out = read(b).map_err(backend_err(what, b));
    let mut free = Recording::new();
    for s in &rec.steps {
        if let Step::Create { id, .. } | Step::Upload { id, .. } = s {
            free.steps.push(Step::Free { id: *id });
        }
    }
    b.execute(&free).map_err(backend_err("free", b))?;
    out
}

/// A scene uploaded (and `prepare_scene`d) on the reference and a candidate, with the
/// frame constants of `settings`.
pub struct Fixture {
    pub name: String,
    pub scene: Scene,
    pub settings: SspmSettings,
    pub ds: DeviceScene,
    pub args: SceneArgs,
    pub camera: GpuCamera,
    pub constants: FrameConstants,
    upload: Recording,
}

impl Fixture {
    pub fn new(
        name: &str,
        scene: &Scene,
        settings: &SspmSettings,
        reference: &mut dyn Backend,
        candidate: &mut dyn Backend,
    ) -> Result<Fixture, String> {
        scene
            .validate()
            .map_err(|p| format!("invalid scene {name}: {p:?}"))?;
        settings
            .validate()
            .map_err(|e| format!("invalid settings: {e}"))?;
        let ds = DeviceScene::build(scene);
        let mut rec = Recording::new();
        let args = ds.record_upload(&mut rec);
        reference
            .execute(&rec)
            .map_err(backend_err("prepare_scene", reference))?;
        candidate
            .execute(&rec)
            .map_err(backend_err("prepare_scene", candidate))?;
        Ok(Fixture {
            name: name.into(),
            constants: FrameConstants::new(scene, &ds, settings),
            scene: scene.clone(),
            settings: settings.clone(),
            camera: GpuCamera::from_camera(&scene.camera),
            ds,
            args,
            upload: rec,
        })
    }

    /// Frees the scene buffers on both backends.
    pub fn release(self, reference: &mut dyn Backend, candidate: &mut dyn Backend) {
        let mut free = Recording::new();
        for s in &self.upload.steps {
            if let Step::Upload { id, .. } = s {
                free.steps.push(Step::Free { id: *id });
            }
        }
        let _ = reference.execute(&free);
        let _ = candidate.execute(&free);
    }

    pub fn pixels(&self) -> u32 {
        self.camera.width * self.camera.height
    }

    pub fn tiles_len(&self) -> u32 {
        let ts = self.settings.tile_size;
        self.camera.width.div_ceil(ts) * self.camera.height.div_ceil(ts)
    }

    /// Runs `primary_gbuffer` on `b`.
    pub fn run_gbuffer(&self, b: &mut dyn Backend) -> Result<Vec<GBufferTexel>, String> {
        let mut rec = Recording::new();
        let g = rec.create(self.pixels(), "gbuffer");
        rec.kernel(Kernel::PrimaryGbuffer(PrimaryGbuffer {
            scene: self.args,
            camera: self.camera,
            gbuffer: g,
        }));
        run_and_free(b, "primary_gbuffer", &rec, |b| read_buf(b, g))
    }

    /// Runs `trace_photons` for every photon of light `domains[k]` in one batch; returns
    /// the stored photons and the counters.
    pub fn run_trace(
        &self,
        b: &mut dyn Backend,
        k: usize,
    ) -> Result<(Vec<Photon>, Vec<u32>), String> {
        let (light, d) = &self.constants.domains[k];
        let count = self.settings.photons_w * self.settings.photons_h;
        let params = self
            .constants
            .trace_params(&self.settings, *light, d, 0, count);
        let mut rec = Recording::new();
        let photons = rec.create(count, "photons");
        let photon_count = rec.create(1, "photon count");
        let counters = rec.create(counter::WORDS as u32, "counters");
        rec.kernel(Kernel::TracePhotons(TracePhotons {
            scene: self.args,
            // the variant a frame of this scene runs (the plan's)
            variant: caustica_core::frame::plan::SceneFeatures::of(&self.scene).trace_variant(),
            params,
            photons,
            photon_count,
            counters,
        }));
        run_and_free(b, "trace_photons", &rec, |b| {
            let n = read_buf(b, photon_count)?[0] as usize;
            let mut ph = read_buf(b, photons)?;
            ph.truncate(n.min(count as usize));
            Ok((ph, read_buf(b, counters)?))
        })
    }

    /// Runs `deposit_screen` then `resolve_caustics` on `b` for the given G-buffer and
    /// photons.
    pub fn run_deposit(
        &self,
        b: &mut dyn Backend,
        gbuffer: &[GBufferTexel],
        photons: &[Photon],
    ) -> Result<DepositOutput, String> {
        let mut rec = Recording::new();
        let g = rec.upload(gbuffer, "gbuffer");
        // A zero-length buffer is not a valid device buffer everywhere: keep one slot.
        let ph = if photons.is_empty() {
            rec.upload(&[Photon::default()], "photons")
        } else {
            rec.upload(photons, "photons")
        };
        let count = rec.upload(&[photons.len() as u32], "photon count");
        let counters = rec.create(counter::WORDS as u32, "counters");
        let map = rec.create(self.pixels(), "photon map");
        let out = rec.create(self.pixels(), "raw caustics");
        let params = self
            .constants
            .deposit_params(self.camera, &self.settings, ph.len);
        rec.kernel(Kernel::DepositScreen(DepositScreen {
            params,
            gbuffer: g,
            photons: ph,
            photon_count: count,
            counters,
            photon_map: map,
        }));
        rec.kernel(Kernel::ResolveCaustics(ResolveCaustics {
            params,
            gbuffer: g,
            photon_map: map,
            out,
        }));
        run_and_free(b, "deposit_screen + resolve_caustics", &rec, |b| {
            Ok(DepositOutput {
                photon_map: read_buf(b, map)?,
                counters: read_buf(b, counters)?,
                raw: read_buf(b, out)?,
            })
        })
    }

    /// Runs `tile_hit_distance` on `b`.
    pub fn run_tiles(&self, b: &mut dyn Backend, map: &[DepositTexel]) -> Result<Vec<f32>, String> {
        let mut rec = Recording::new();
        let m = rec.upload(map, "photon map");
        let tiles = rec.create(self.tiles_len(), "tiles");
        rec.kernel(Kernel::TileHitDistance(TileHitDistance {
            params: self.constants.gather_params(self.camera, &self.settings, 0),
            photon_map: m,
            tiles,
        }));
        run_and_free(b, "tile_hit_distance", &rec, |b| read_buf(b, tiles))
    }

    /// Runs one `bilateral_gather` pass (`axis` 0: horizontal, 1: vertical) on `b`.
    pub fn run_gather(
        &self,
        b: &mut dyn Backend,
        axis: u32,
        gbuffer: &[GBufferTexel],
        tiles: &[f32],
        input: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, String> {
        let mut rec = Recording::new();
        let g = rec.upload(gbuffer, "gbuffer");
        let t = rec.upload(tiles, "tiles");
        let i = rec.upload(input, "gather input");
        let out = rec.create(self.pixels(), "gather output");
        rec.kernel(Kernel::BilateralGather(BilateralGather {
            params: self
                .constants
                .gather_params(self.camera, &self.settings, axis),
            gbuffer: g,
            tiles: t,
            input: i,
            out,
        }));
        run_and_free(b, "bilateral_gather", &rec, |b| read_buf(b, out))
    }

    /// Runs `direct_light` on `b` with the given G-buffer.
    pub fn run_direct(
        &self,
        b: &mut dyn Backend,
        gbuffer: &[GBufferTexel],
    ) -> Result<Vec<[f32; 4]>, String> {
        let mut rec = Recording::new();
        let g = rec.upload(gbuffer, "gbuffer");
        let out = rec.create(self.pixels(), "direct");
        rec.kernel(Kernel::DirectLight(DirectLight {
            scene: self.args,
            params: FrameConstants::direct_params(
                self.camera,
                self.scene.lights.len() as u32,
                &self.settings,
            ),
            gbuffer: g,
            out,
        }));
        run_and_free(b, "direct_light", &rec, |b| read_buf(b, out))
    }
}

/// Runs `composite` on `b`.
pub fn run_composite(
    b: &mut dyn Backend,
    direct: &[[f32; 4]],
    caustics: &[[f32; 4]],
) -> Result<Vec<[f32; 4]>, String> {
    let mut rec = Recording::new();
    let d = rec.upload(direct, "direct");
    let c = rec.upload(caustics, "caustics");
    let out = rec.create(direct.len() as u32, "composite");
    rec.kernel(Kernel::Composite(Composite {
        direct: d,
        caustics: c,
        out,
    }));
    run_and_free(b, "composite", &rec, |b| read_buf(b, out))
}

/// What `deposit_screen` + `resolve_caustics` produce.
pub struct DepositOutput {
    pub photon_map: Vec<DepositTexel>,
    pub counters: Vec<u32>,
    /// Raw caustic radiance (alpha: mean hit distance).
    pub raw: Vec<[f32; 4]>,
}

/// Every intermediate of a frame, computed by the reference alone: the fixed inputs the
/// per-kernel checks upload to both backends.
pub struct ReferenceInputs {
    pub gbuffer: Vec<GBufferTexel>,
    /// Stored photons of every light, concatenated.
    pub photons: Vec<Photon>,
    pub photon_map: Vec<DepositTexel>,
    pub raw: Vec<[f32; 4]>,
    pub tiles: Vec<f32>,
    /// Horizontal then vertical gather of `raw`.
    pub filtered: Vec<[f32; 4]>,
    pub direct: Vec<[f32; 4]>,
}

impl ReferenceInputs {
    pub fn new(fx: &Fixture, r: &mut dyn Backend) -> Result<ReferenceInputs, String> {
        let gbuffer = fx.run_gbuffer(r)?;
        let mut photons = Vec::new();
        for k in 0..fx.constants.domains.len() {
            photons.extend(fx.run_trace(r, k)?.0);
        }
        let DepositOutput {
            photon_map, raw, ..
        } = fx.run_deposit(r, &gbuffer, &photons)?;
        let tiles = fx.run_tiles(r, &photon_map)?;
        let half = fx.run_gather(r, 0, &gbuffer, &tiles, &raw)?;
        let filtered = fx.run_gather(r, 1, &gbuffer, &tiles, &half)?;
        let direct = fx.run_direct(r, &gbuffer)?;
        Ok(ReferenceInputs {
            gbuffer,
            photons,
            photon_map,
            raw,
            tiles,
            filtered,
            direct,
        })
    }
}

// ---------------------------------------------------------------------------------------
// Per-kernel checks.
// ---------------------------------------------------------------------------------------

/// `|a - b| <= rel * max(|a|, |b|)`; false for NaN.
fn within_rel(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

fn pct(num: u64, den: u64) -> f64 {
    if den == 0 {
        100.0
    } else {
        100.0 * num as f64 / den as f64
    }
}

fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from(a)
}

/// Texel-by-texel comparison of two G-buffers of camera `cam` (reference first); also
/// returns which pixels agree (material equal and geometry within tolerance).
pub fn compare_gbuffers(
    cam: &GpuCamera,
    reference: &[GBufferTexel],
    candidate: &[GBufferTexel],
) -> (Verdict, Vec<bool>) {
    let mut v = Verdict::new("primary_gbuffer");
    let mut agree = vec![false; reference.len()];
    if !v.check(reference.len() == candidate.len(), || {
        format!("{} texels, expected {}", candidate.len(), reference.len())
    }) {
        return (v, agree);
    }
    let n = reference.len() as u64;
    let (mut same_material, mut hits, mut geometry_ok) = (0u64, 0u64, 0u64);
    let mut worst = (0.0f32, String::new());
    let mut exact_mismatch = Vec::new();
    for (i, (a, b)) in reference.iter().zip(candidate).enumerate() {
        if a.material != b.material {
            continue;
        }
        same_material += 1;
        let (x, y) = (i as u32 % cam.width, i as u32 / cam.width);
        if a.material == NO_MATERIAL {
            // a miss writes depth 0, no flags; the rest is unspecified
            if b.depth == 0.0 && b.flags == 0 {
                agree[i] = true;
            } else if exact_mismatch.len() < 3 {
                exact_mismatch.push(format!(
                    "({x},{y}) miss with depth {} flags {}",
                    b.depth, b.flags
                ));
            }
            continue;
        }
        hits += 1;
        // Exactly copied fields: material table entries and flags derived from them.
        if a.flags != b.flags || a.albedo != b.albedo || a.roughness != b.roughness {
            if exact_mismatch.len() < 3 {
                exact_mismatch.push(format!(
                    "({x},{y}) flags/albedo/roughness {:?}/{:?}/{} vs cpu {:?}/{:?}/{}",
                    b.flags, b.albedo, b.roughness, a.flags, a.albedo, a.roughness
                ));
            }
            continue;
        }
        let ray = camera_ray(cam, x, y);
        let cos = ray.dot(v3(a.normal)).abs().max(GBUFFER_MIN_COS);
        let tol =
            GBUFFER_POSITION_REL * (a.view_distance / cos + v3(a.position).abs().max_element());
        let errs = [
            (v3(a.position) - v3(b.position)).abs().max_element() / tol,
            (a.depth - b.depth).abs() / tol,
            (a.view_distance - b.view_distance).abs() / tol,
            (v3(a.normal) - v3(b.normal)).abs().max_element() / (1e-5 + NORMAL_GRADIENT * tol),
            (glam::Vec2::from(a.uv) - glam::Vec2::from(b.uv))
                .abs()
                .max_element()
                / (1e-5 + UV_GRADIENT * tol),
        ];
        let e = errs.iter().fold(
            0.0f32,
            |m, &x| if x.is_nan() { f32::INFINITY } else { m.max(x) },
        );
        if e <= 1.0 {
            geometry_ok += 1;
            agree[i] = true;
        }
        if e > worst.0 {
            worst = (
                e,
                format!(
                    "({x},{y}): position {:?} vs cpu {:?}, normal {:?} vs {:?}, depth {} vs {}",
                    b.position, a.position, b.normal, a.normal, b.depth, a.depth
                ),
            );
        }
    }
    v.note(format!(
        "material agrees on {same_material}/{n} ({:.3}%); geometry within tolerance on \
         {geometry_ok}/{hits} hit pixels; worst error {:.3} of tolerance",
        pct(same_material, n),
        worst.0
    ));
    v.check(
        same_material as f64 >= GBUFFER_MATERIAL_AGREEMENT * n as f64,
        || {
            format!(
                "material id agrees on only {:.3}% of pixels (need {}%)",
                pct(same_material, n),
                100.0 * GBUFFER_MATERIAL_AGREEMENT
            )
        },
    );
    v.check(exact_mismatch.is_empty(), || {
        format!(
            "fields that must be exact differ: {}",
            exact_mismatch.join("; ")
        )
    });
    v.check(
        geometry_ok as f64 >= GBUFFER_GEOMETRY_AGREEMENT * hits as f64,
        || {
            format!(
                "geometry within tolerance on only {:.3}% of same-material pixels (need {}%); \
             worst {:.3e} x tolerance at {}",
                pct(geometry_ok, hits),
                100.0 * GBUFFER_GEOMETRY_AGREEMENT,
                worst.0,
                worst.1
            )
        },
    );
    (v, agree)
}

/// `primary_gbuffer` on the fixture's scene and camera.
pub fn check_gbuffer(
    fx: &Fixture,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let a = fx.run_gbuffer(r)?;
    let b = fx.run_gbuffer(c)?;
    Ok(compare_gbuffers(&fx.camera, &a, &b).0)
}

/// Spatial hash of photons for "is there a matching photon nearby" queries.
struct PhotonGrid<'a> {
    cell: f32,
    cells: HashMap<[i32; 3], Vec<&'a Photon>>,
}

impl<'a> PhotonGrid<'a> {
    fn new(photons: &'a [Photon], tol: f32) -> PhotonGrid<'a> {
        let cell = tol.max(f32::MIN_POSITIVE);
        let mut cells: HashMap<[i32; 3], Vec<&Photon>> = HashMap::new();
        for p in photons {
            cells
                .entry(Self::key(v3(p.position), cell))
                .or_default()
                .push(p);
        }
        PhotonGrid { cell, cells }
    }

    fn key(p: Vec3, cell: f32) -> [i32; 3] {
        let k = (p / cell).floor();
        [k.x as i32, k.y as i32, k.z as i32]
    }

    /// True when a photon lies within `tol` of `p` with every flux channel within
    /// `flux_rel` (relative) of `p`'s.
    fn has_match(&self, p: &Photon, tol: f32, flux_rel: f32) -> bool {
        let pos = v3(p.position);
        let k = Self::key(pos, self.cell);
        let flux_ok = |q: &Photon| {
            (0..3).all(|c| {
                (p.flux[c] - q.flux[c]).abs() <= flux_rel * p.flux[c].abs().max(q.flux[c].abs())
            })
        };
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(v) = self.cells.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        if v.iter()
                            .any(|q| v3(q.position).distance(pos) <= tol && flux_ok(q))
                        {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

/// Number of photons of `a` with no match in `b` (see [`PhotonGrid::has_match`]).
fn unmatched(a: &[Photon], b: &[Photon], tol: f32, flux_rel: f32) -> u64 {
    let grid = PhotonGrid::new(b, tol);
    a.iter()
        .filter(|p| !grid.has_match(p, tol, flux_rel))
        .count() as u64
}

fn flux_sum(photons: &[Photon]) -> [f64; 3] {
    let mut s = [0.0f64; 3];
    for p in photons {
        for (c, v) in s.iter_mut().enumerate() {
            *v += p.flux[c] as f64;
        }
    }
    s
}

/// Checks the accounting of one backend's trace counters for `emitted` photons.
fn trace_accounting(v: &mut Verdict, who: &str, counters: &[u32], stored: usize, emitted: u64) {
    let ends = [
        counter::STORED,
        counter::NO_SPECULAR,
        counter::ESCAPED,
        counter::NEGLIGIBLE,
        counter::BOUNCE_LIMIT,
    ];
    let sum: u64 = ends.iter().map(|&i| counters[i] as u64).sum();
    v.check(sum == emitted, || {
        format!("{who}: path ends add up to {sum}, {emitted} photons were emitted")
    });
    v.check(counters[counter::STORED] as usize == stored, || {
        format!(
            "{who}: STORED counter {} but {stored} photons in the buffer",
            counters[counter::STORED]
        )
    });
    for w in [
        counter::OFF_SCREEN,
        counter::DEPTH_MISMATCH,
        counter::DEPOSITED,
        counter::UNDERFLOW,
        counter::SATURATED,
    ] {
        v.check(counters[w] == 0, || {
            format!("{who}: trace_photons wrote deposit counter word {w}")
        });
    }
}

/// `trace_photons` for every emitting light of the fixture, compared as multisets.
pub fn check_trace(
    fx: &Fixture,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut all = Verdict::new("trace_photons");
    if fx.constants.domains.is_empty() {
        all.note("no light emits photons (no caster): nothing to trace");
        return Ok(all);
    }
    let emitted = fx.settings.photons_w as u64 * fx.settings.photons_h as u64;
    let tol = PHOTON_POSITION_REL * fx.ds.bounds.diagonal();
    let flux_rel = photon_flux_match_rel(&fx.scene, tol);
    for k in 0..fx.constants.domains.len() {
        let light = fx.constants.domains[k].0;
        let (pa, ca) = fx.run_trace(r, k)?;
        let (pb, cb) = fx.run_trace(c, k)?;
        let mut v = Verdict::new(format!("light {light}"));
        trace_accounting(&mut v, "cpu", &ca, pa.len(), emitted);
        trace_accounting(&mut v, "candidate", &cb, pb.len(), emitted);
        let n = pa.len().max(pb.len()) as u64;
        let allow = divergence_allowance(n);
        let d = (pa.len() as i64 - pb.len() as i64).unsigned_abs();
        v.check(d <= allow, || {
            format!(
                "stored {} photons, cpu {} (allowed difference {allow})",
                pb.len(),
                pa.len()
            )
        });
        // Every path ends in one category: a diverged path moves one count between two.
        let allow_paths = divergence_allowance(emitted);
        for (w, name) in [
            (counter::NO_SPECULAR, "no_specular"),
            (counter::ESCAPED, "escaped"),
            (counter::NEGLIGIBLE, "negligible"),
            (counter::BOUNCE_LIMIT, "bounce_limit"),
        ] {
            let d = (ca[w] as i64 - cb[w] as i64).unsigned_abs();
            v.check(d <= allow_paths, || {
                format!(
                    "{name}: {} vs cpu {} (allowed difference {allow_paths})",
                    cb[w], ca[w]
                )
            });
        }
        // Ray segments: a diverged path may trace up to max_bounces more or fewer.
        let rays = |c: &[u32]| join_u64([c[counter::RAYS], c[counter::RAYS + 1]]);
        let d = (rays(&ca) as i64 - rays(&cb) as i64).unsigned_abs();
        let allow_rays = allow_paths * fx.settings.max_bounces as u64;
        v.check(d <= allow_rays, || {
            format!(
                "rays traced {} vs cpu {} (allowed {allow_rays})",
                rays(&cb),
                rays(&ca)
            )
        });
        // Flux: the diverged photons' whole flux plus rounding of the others.
        let max_photon_flux = fx.constants.max_photon_flux as f64;
        let (fa, fb) = (flux_sum(&pa), flux_sum(&pb));
        for ch in 0..3 {
            let bound = allow as f64 * max_photon_flux + PHOTON_FLUX_REL * fa[ch].max(fb[ch]);
            v.check((fa[ch] - fb[ch]).abs() <= bound, || {
                format!(
                    "flux[{ch}] {:.6e} vs cpu {:.6e} (allowed {bound:.3e})",
                    fb[ch], fa[ch]
                )
            });
            // The fixed-point stored-flux counter (units of the quantum, <= 2^24 per
            // photon) follows the same argument, plus one rounding unit per photon.
            let q = |c: &[u32]| {
                join_u64([
                    c[counter::STORED_FLUX + 2 * ch],
                    c[counter::STORED_FLUX + 2 * ch + 1],
                ])
            };
            let dq = (q(&ca) as i64 - q(&cb) as i64).unsigned_abs() as f64;
            let max_q = max_photon_flux / fx.constants.flux_quantum as f64;
            let bound_q = allow as f64 * max_q + n as f64 * (1.0 + PHOTON_FLUX_REL * max_q);
            v.check(dq <= bound_q, || {
                format!(
                    "stored-flux counter[{ch}] {} vs cpu {} (allowed {bound_q:.3e})",
                    q(&cb),
                    q(&ca)
                )
            });
        }
        // Multiset match in both directions, on position and flux.
        let (ua, ub) = (
            unmatched(&pb, &pa, tol, flux_rel),
            unmatched(&pa, &pb, tol, flux_rel),
        );
        for (u, len, who) in [(ua, pb.len(), "candidate"), (ub, pa.len(), "cpu")] {
            let allowed = ((1.0 - PHOTON_MATCH) * len as f64).ceil() as u64 + 2;
            v.check(u <= allowed, || {
                format!(
                    "{u} of {len} {who} photons have no counterpart within {tol:.2e} (allowed {allowed})"
                )
            });
        }
        v.note(format!(
            "stored {} vs cpu {}; unmatched {ua} / {ub} within {tol:.2e}; flux {:.4e} vs {:.4e}",
            pb.len(),
            pa.len(),
            fb.iter().sum::<f64>(),
            fa.iter().sum::<f64>()
        ));
        all.absorb(v);
    }
    Ok(all)
}

/// `deposit_screen` + `resolve_caustics` on the reference's G-buffer and photon list.
pub fn check_deposit(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("deposit_screen + resolve_caustics");
    let a = fx.run_deposit(r, &inputs.gbuffer, &inputs.photons)?;
    let b = fx.run_deposit(c, &inputs.gbuffer, &inputs.photons)?;
    let (ma, ca, ia) = (a.photon_map, a.counters, a.raw);
    let (mb, cb, ib) = (b.photon_map, b.counters, b.raw);
    let n = inputs.photons.len() as u64;
    for (who, m, cn) in [("cpu", &ma, &ca), ("candidate", &mb, &cb)] {
        let outcomes = cn[counter::DEPOSITED] as u64
            + cn[counter::OFF_SCREEN] as u64
            + cn[counter::DEPTH_MISMATCH] as u64;
        v.check(outcomes == n, || {
            format!("{who}: deposited + off_screen + depth_mismatch = {outcomes}, {n} photons")
        });
        let in_map: u64 = m.iter().map(|t| join_u64(t.photons)).sum();
        v.check(in_map == cn[counter::DEPOSITED] as u64, || {
            format!(
                "{who}: the map holds {in_map} photons, DEPOSITED says {}",
                cn[counter::DEPOSITED]
            )
        });
        for w in [
            counter::STORED,
            counter::NO_SPECULAR,
            counter::ESCAPED,
            counter::NEGLIGIBLE,
            counter::BOUNCE_LIMIT,
            counter::RAYS,
            counter::STORED_FLUX,
        ] {
            v.check(cn[w] == 0, || {
                format!("{who}: deposit_screen wrote trace counter word {w}")
            });
        }
    }
    let texels = ma.len() as u64;
    let equal = ma.iter().zip(&mb).filter(|(a, b)| a == b).count() as u64;
    let moved: u64 = ma
        .iter()
        .zip(&mb)
        .map(|(a, b)| (join_u64(a.photons) as i64 - join_u64(b.photons) as i64).unsigned_abs())
        .sum();
    v.check(
        equal as f64 >= DEPOSIT_TEXEL_AGREEMENT * texels as f64,
        || {
            format!(
                "photon map bitwise equal on only {equal}/{texels} texels (need {}%)",
                100.0 * DEPOSIT_TEXEL_AGREEMENT
            )
        },
    );
    let allowed = (DEPOSIT_PHOTON_CHANGES * n as f64).ceil() as u64 + 2;
    v.check(moved <= allowed, || {
        format!(
            "per-texel photon counts differ by {moved} in all (allowed {allowed} of {n} photons)"
        )
    });
    // A photon counted by one backend and not the other (or elsewhere) shows in `moved`;
    // each has at most 3 channels that may underflow or saturate.
    for (w, name) in [
        (counter::UNDERFLOW, "underflow"),
        (counter::SATURATED, "saturated"),
    ] {
        let d = (ca[w] as i64 - cb[w] as i64).unsigned_abs();
        v.check(d <= 3 * moved, || {
            format!("{name} {} vs cpu {}", cb[w], ca[w])
        });
    }
    // Resolve, on texels whose sums are bitwise equal.
    let cam = &fx.camera;
    let (mut checked, mut bad, mut worst, mut first_bad) = (0u64, 0u64, 0.0f32, None);
    for (i, g) in inputs.gbuffer.iter().enumerate() {
        if ma[i] != mb[i] {
            continue;
        }
        checked += 1;
        let (a, b) = (ia[i], ib[i]);
        let empty = join_u64(ma[i].photons) == 0 || g.flags & gbuffer_flags::RECEIVER == 0;
        let ok = if empty {
            a == [0.0; 4] && b == [0.0; 4]
        } else {
            let ray = camera_ray(cam, i as u32 % cam.width, i as u32 / cam.width);
            let cos = ray.dot(v3(g.normal)).abs().max(MIN_COSINE);
            let rel = RESOLVE_REL + RESOLVE_COS_REL / cos;
            let mut e = 0.0f32;
            for ch in 0..4 {
                let d = (a[ch] - b[ch]).abs();
                let x = if d == 0.0 {
                    0.0
                } else {
                    d / (rel * a[ch].abs().max(b[ch].abs()))
                };
                e = e.max(if x.is_nan() { f32::INFINITY } else { x });
            }
            worst = worst.max(e);
            e <= 1.0
        };
        if !ok {
            bad += 1;
            first_bad.get_or_insert(format!(
                "({}, {}): {b:?} vs cpu {a:?}",
                i as u32 % cam.width,
                i as u32 / cam.width
            ));
        }
    }
    v.check(bad == 0, || {
        format!(
            "resolve_caustics differs on {bad} of {checked} texels with equal sums, first {}",
            first_bad.unwrap_or_default()
        )
    });
    v.note(format!(
        "{n} photons, deposited {} vs cpu {}; map equal on {equal}/{texels} texels, counts \
         moved {moved}; resolve worst {worst:.3} of tolerance",
        cb[counter::DEPOSITED],
        ca[counter::DEPOSITED]
    ));
    Ok(v)
}

/// `tile_hit_distance` and both `bilateral_gather` directions on the reference's photon
/// map, raw caustics, G-buffer and tiles.
pub fn check_gather(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("tile_hit_distance + bilateral_gather");
    let ta = fx.run_tiles(r, &inputs.photon_map)?;
    let tb = fx.run_tiles(c, &inputs.photon_map)?;
    let bad_tiles = ta
        .iter()
        .zip(&tb)
        .filter(|(a, b)| !within_rel(**a, **b, TILE_REL))
        .count();
    v.check(bad_tiles == 0, || {
        format!(
            "tile_hit_distance differs on {bad_tiles} of {} tiles",
            ta.len()
        )
    });
    let cam = &fx.camera;
    let ts = fx.settings.tile_size;
    let tw = cam.width.div_ceil(ts);
    for axis in 0..2u32 {
        let params = fx.constants.gather_params(*cam, &fx.settings, axis);
        let a = fx.run_gather(r, axis, &inputs.gbuffer, &inputs.tiles, &inputs.raw)?;
        let b = fx.run_gather(c, axis, &inputs.gbuffer, &inputs.tiles, &inputs.raw)?;
        let (mut ambiguous, mut bad, mut worst, mut first_bad) = (0u64, 0u64, 0.0f32, None);
        for i in 0..a.len() {
            let (x, y) = (i as u32 % cam.width, i as u32 / cam.width);
            let g = &inputs.gbuffer[i];
            if g.flags & gbuffer_flags::RECEIVER != 0 {
                let tile = inputs.tiles[((y / ts) * tw + x / ts) as usize];
                let rad = caustica_cpu::kernels::gather::gather_radius_px(&params, g, tile);
                if rad < params.max_radius_px as f32
                    && (rad - rad.round()).abs() <= GATHER_REL * rad.max(1.0)
                {
                    ambiguous += 1;
                    continue;
                }
            }
            let mut e = 0.0f32;
            for ch in 0..3 {
                let scale = a[i][ch].abs().max(b[i][ch].abs());
                let d = (a[i][ch] - b[i][ch]).abs();
                let x = if d == 0.0 {
                    0.0
                } else {
                    d / (GATHER_REL * scale)
                };
                e = e.max(if x.is_nan() { f32::INFINITY } else { x });
            }
            // alpha (mean hit distance) passes through unchanged
            if a[i][3].to_bits() != b[i][3].to_bits() {
                e = f32::INFINITY;
            }
            worst = worst.max(e);
            if e > 1.0 {
                bad += 1;
                first_bad.get_or_insert(format!("({x},{y}): {:?} vs cpu {:?}", b[i], a[i]));
            }
        }
        v.check(bad == 0, || {
            format!(
                "bilateral_gather axis {axis} differs on {bad} pixels, first {}",
                first_bad.unwrap_or_default()
            )
        });
        v.note(format!(
            "axis {axis}: worst {worst:.3} of tolerance; {ambiguous} pixels with an integer radius skipped"
        ));
    }
    Ok(v)
}

/// True when `a` and `b` agree as [`DIRECT_REL`] says; `floor` is per channel.
fn direct_pixel_agrees(a: [f32; 4], b: [f32; 4], floor: [f32; 3]) -> bool {
    (0..3).all(|ch| (a[ch] - b[ch]).abs() <= DIRECT_REL * a[ch].abs().max(b[ch].abs()) + floor[ch])
        && a[3].to_bits() == b[3].to_bits()
}

fn channel_max(img: &[[f32; 4]]) -> [f32; 3] {
    let mut m = [0.0f32; 3];
    for p in img {
        for ch in 0..3 {
            if p[ch].is_finite() {
                m[ch] = m[ch].max(p[ch].abs());
            }
        }
    }
    m
}

/// Per-pixel comparison of two direct-light images over the pixels `mask` selects.
fn compare_direct(
    what: &str,
    width: u32,
    a: &[[f32; 4]],
    b: &[[f32; 4]],
    mask: Option<&[bool]>,
) -> Verdict {
    let mut v = Verdict::new(what);
    let floor = channel_max(a).map(|m| DIRECT_FLOOR * m);
    let (mut n, mut good, mut first_bad) = (0u64, 0u64, None);
    for i in 0..a.len() {
        if mask.is_some_and(|m| !m[i]) {
            continue;
        }
        n += 1;
        if direct_pixel_agrees(a[i], b[i], floor) {
            good += 1;
        } else {
            first_bad.get_or_insert(format!(
                "({}, {}): {:?} vs cpu {:?}",
                i as u32 % width,
                i as u32 / width,
                b[i],
                a[i]
            ));
        }
    }
    let l2 = relative_l2(a, b, mask);
    v.check(good as f64 >= DIRECT_AGREEMENT * n as f64, || {
        format!(
            "agrees on only {good}/{n} pixels (need {}%), first {}",
            100.0 * DIRECT_AGREEMENT,
            first_bad.clone().unwrap_or_default()
        )
    });
    v.note(format!(
        "agrees on {good}/{n} pixels ({:.3}%); relative L2 {l2:.3e}",
        pct(good, n)
    ));
    v
}

/// `direct_light` on the reference's G-buffer.
pub fn check_direct(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let a = fx.run_direct(r, &inputs.gbuffer)?;
    let b = fx.run_direct(c, &inputs.gbuffer)?;
    Ok(compare_direct(
        "direct_light",
        fx.camera.width,
        &a,
        &b,
        None,
    ))
}

/// `composite` on the reference's direct and filtered images: exact. Each output channel
/// is one IEEE addition, correctly rounded on every backend (nothing to contract into an
/// FMA); alpha is the constant 1. The only licence is subnormal flushing: a channel whose
/// operands or sum are subnormal may come back as zero on a GPU.
pub fn check_composite(
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("composite");
    let a = run_composite(r, &inputs.direct, &inputs.filtered)?;
    let b = run_composite(c, &inputs.direct, &inputs.filtered)?;
    let subnormal = |x: f32| x != 0.0 && x.abs() < f32::MIN_POSITIVE;
    let mut differ = 0u64;
    for i in 0..a.len() {
        for ch in 0..4 {
            let (x, y) = (a[i][ch], b[i][ch]);
            let flushed = ch < 3
                && (subnormal(inputs.direct[i][ch])
                    || subnormal(inputs.filtered[i][ch])
                    || subnormal(x))
                && y.abs() < f32::MIN_POSITIVE;
            if x.to_bits() != y.to_bits() && !flushed {
                differ += 1;
            }
        }
    }
    v.check(differ == 0, || {
        format!("{differ} channels are not bitwise equal")
    });
    v.note(format!("{} pixels, {differ} channels differ", a.len()));
    Ok(v)
}

// ---------------------------------------------------------------------------------------
// Whole technique.
// ---------------------------------------------------------------------------------------

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
        gbuffer: read_buf(b, s.gbuffer()).map_err(|e| format!("reading the G-buffer: {e}"))?,
        composite: s.read_output(b, Output::Composite).map_err(err)?,
        raw: s.read_output(b, Output::RawCaustics).map_err(err)?,
        filtered: s.read_output(b, Output::FilteredCaustics).map_err(err)?,
        direct: s.read_output(b, Output::Direct).map_err(err)?,
    };
    s.free(b).map_err(err)?;
    Ok(frame)
}

/// Relative L2 error `||b - a|| / ||a||` over the rgb channels of the pixels `mask` selects
/// (`a` is the reference). 0 when both are zero, infinite when only `a` is.
pub fn relative_l2(a: &[[f32; 4]], b: &[[f32; 4]], mask: Option<&[bool]>) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for i in 0..a.len().min(b.len()) {
        if mask.is_some_and(|m| !m[i]) {
            continue;
        }
        for ch in 0..3 {
            let (x, y) = (a[i][ch] as f64, b[i][ch] as f64);
            num += (x - y) * (x - y);
            den += x * x;
        }
    }
    if num == 0.0 {
        0.0
    } else if den == 0.0 {
        f64::INFINITY
    } else {
        (num / den).sqrt()
    }
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
pub fn compare_frames(scene: &Scene, a: &Frame, b: &Frame) -> Verdict {
    let mut v = Verdict::new("sspm frame");
    let cam = GpuCamera::from_camera(&scene.camera);
    let (gv, agree) = compare_gbuffers(&cam, &a.gbuffer, &b.gbuffer);
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
    for ch in 0..3 {
        let (x, y) = (sa.stored_flux[ch], sb.stored_flux[ch]);
        let bound = allow_stored as f64 * max_photon_flux + PHOTON_FLUX_REL * x.max(y);
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

// ---------------------------------------------------------------------------------------
// Test drivers: the same loops for every candidate.
// ---------------------------------------------------------------------------------------

/// Resolution of the built-in scenes in the cross-backend tests (about their 16:9).
///
/// `width - height` is odd on purpose. The `cornell` camera is centred on the box, so the
/// box's four wall-ceiling and wall-floor edges project exactly onto the image diagonals
/// through the centre, `px - py = (width - height) / 2` in pixel units; with an even
/// difference (96x54) some 100 pixel centres lie exactly on an edge shared by two faces,
/// where the closest hit is a tie that any rounding difference breaks either way (or, the
/// ray/triangle test not being watertight, lets the ray escape between the faces): seen
/// with the `UlpNoise` mutant of `tests/suite_sensitivity.rs`, 15 such pixels changed
/// material. No pixel centre is on those diagonals when the difference is odd.
pub const BUILTIN_SIZE: (u32, u32) = (96, 55);

/// Built-in scene `name` at `BUILTIN_SIZE`.
pub fn builtin_small(name: &str) -> Scene {
    let mut s = caustica_core::scene::builtin::builtin(name).expect("a built-in scene");
    (s.camera.width, s.camera.height) = BUILTIN_SIZE;
    s
}

/// The fixed inputs of the per-kernel checks: every built-in scene with a 96x96 photon grid
/// (default settings otherwise), and four generated scenes with generated settings, drawn
/// from [`crate::strategies`] with proptest's deterministic RNG (the same every run).
pub fn kernel_cases() -> Vec<(String, Scene, SspmSettings)> {
    use proptest::strategy::{Strategy, ValueTree};
    let mut cases: Vec<(String, Scene, SspmSettings)> =
        caustica_core::scene::builtin::BUILTIN_SCENES
            .iter()
            .map(|n| (n.to_string(), builtin_small(n), crate::small_settings(96)))
            .collect();
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let strategy = (
        crate::strategies::scene(),
        crate::strategies::sspm_settings(),
    );
    for i in 0..4 {
        let (scene, settings) = strategy
            .new_tree(&mut runner)
            .expect("a generated case")
            .current();
        cases.push((format!("generated#{i}"), scene, settings));
    }
    cases
}

/// A per-kernel check on fixed inputs (reference first, candidate second).
pub type KernelCheck = dyn Fn(
    &Fixture,
    &ReferenceInputs,
    &mut dyn Backend,
    &mut dyn Backend,
) -> Result<Verdict, String>;

/// Runs `check` for `candidate` on every case, adding one verdict per case to `report`.
pub fn check_kernel_cases(
    report: &mut Report,
    reference: &mut dyn Backend,
    candidate: &mut Candidate,
    cases: &[(String, Scene, SspmSettings)],
    check: &KernelCheck,
) {
    let c = candidate.backend.as_mut();
    for (name, scene, settings) in cases {
        let fx = match Fixture::new(name, scene, settings, reference, c) {
            Ok(fx) => fx,
            Err(e) => {
                report.error(&candidate.name, name, e);
                continue;
            }
        };
        let result = ReferenceInputs::new(&fx, reference)
            .and_then(|inputs| check(&fx, &inputs, reference, c));
        match result {
            Ok(v) => report.add(&candidate.name, name, v),
            Err(e) => report.error(&candidate.name, name, e),
        }
        fx.release(reference, c);
    }
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

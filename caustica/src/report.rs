//! Error against run time: for every scene x technique x backend x photon budget x
//! frames accumulated (any registered technique, created by name), the median time and
//! per-pass times over repeated runs (device timestamps where the backend has them) and
//! the error of the technique's filtered and raw estimates against two references of the
//! same scene and camera:
//!
//! - **the independent f64 light tracer** ([`crate::reference::light_tracer`]) for the
//!   caustic techniques (Sspm, CausticMap, AdaptiveCaustics), with the tracer's own
//!   relative standard error beside it and its silhouette definition
//!   ([`SilhouetteDefinition`]) named; PhotonGi's indirect light is outside the tracer's
//!   path class and has no such column;
//! - **the technique's own converged estimate** ([`crate::reference`]: the progressive
//!   mean of the unfiltered estimate, Sspm's raw deposit for the caustic techniques,
//!   PhotonGi's deposit for PhotonGi), against which the peak ratios, FLIP, bias and
//!   variance over the repeats' seeds are measured too.
//!
//! A run of `frames` > 1 accumulates that many frames of the budget (`accumulate: true`,
//! a fresh technique per repeat) and is timed to its last frame. Writes one JSON record
//! per combination and a log-log plot of relative MSE against time per scene.

use crate::reference::light_tracer::{
    self, LightTracerError, LightTracerSpec, SilhouetteDefinition, SphereModel,
};
use crate::reference::{self, ReferenceSpec};
use caustica_core::frame::image::Image;
use caustica_core::frame::metrics::{bias_variance, peak_ratio, relative_mse, CausticMask};
use caustica_core::techniques::{create, FilterSetting, TECHNIQUES};

/// The filter label of a technique that has no `filter` setting (its own filter runs).
pub const OWN_FILTER: &str = "own";
use caustica_core::Scene;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// Why a report stopped.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The plan names something that cannot run (a technique spec, its settings).
    #[error("{0}")]
    Plan(String),
    /// A backend did not open.
    #[error(transparent)]
    Backend(#[from] crate::BackendError),
    /// A technique failed to be made, to render or to be read.
    #[error(transparent)]
    Technique(#[from] crate::Error),
    /// A technique's own reference could not be loaded or computed.
    #[error("{0}")]
    Reference(String),
    /// The reference cache folder cannot be made or written.
    #[error("reference cache {0}")]
    Cache(String),
    /// The light-tracer reference could not be loaded or computed.
    #[error(transparent)]
    LightTracer(#[from] LightTracerError),
    /// A technique's image and the light tracer's differ in size (pixels).
    #[error(
        "{technique}: a {}x{} estimate against the light tracer's {}x{} image",
        estimate.0, estimate.1, tracer.0, tracer.1
    )]
    SizeMismatch {
        /// The technique spec.
        technique: String,
        /// The estimate's width and height.
        estimate: (u32, u32),
        /// The light tracer image's width and height.
        tracer: (u32, u32),
    },
    /// The light tracer's image or noise has a NaN or an infinity.
    #[error("{scene}: the light tracer's image or its noise is not finite")]
    NotFinite {
        /// Scene name.
        scene: String,
    },
}

impl From<ReportError> for String {
    fn from(e: ReportError) -> String {
        e.to_string()
    }
}

/// One combination: measured, or left out with the reason in [`Record::skipped`].
#[derive(Clone, Debug, Serialize)]
pub struct Record {
    /// Scene name.
    pub scene: String,
    /// Technique name.
    pub technique: String,
    /// The caustic filter (Sspm's `filter` setting: `density` or `bilateral`; CausticMap's
    /// `gather`: `box` or `density`; `own` for a technique with one filter).
    pub filter: String,
    /// Backend name.
    pub backend: String,
    /// Device description.
    pub device: String,
    /// Photon grid per light.
    pub budget: String,
    /// Photons emitted per frame.
    pub photons: u64,
    /// Frames accumulated (1: a single frame); `frame_ms` and the pass times are the
    /// sums over them, the errors the last frame's.
    pub frames: usize,
    /// Image size (pixels).
    pub width: u32,
    /// Image size (pixels).
    pub height: u32,
    /// Frames measured.
    pub repeats: usize,
    /// "device timestamps" or "host wall clock" (per-pass times).
    pub timing: String,
    /// Median whole-frame host wall time (ms).
    pub frame_ms: f64,
    /// Median per-pass times (ms).
    pub pass_ms: BTreeMap<String, f64>,
    /// Median over repeats of the filtered caustics' error against the reference.
    pub relative_mse: f64,
    /// The same for the raw (unfiltered) caustics: the estimator's own noise, without the
    /// gather's blur.
    pub raw_relative_mse: f64,
    /// Median RMSE against the reference (radiance units).
    pub rmse: f64,
    /// Median peak ratio of the filtered caustics: their largest luminance over the
    /// reference's (`metrics::peak_ratio`).
    pub peak_ratio: f64,
    /// The same for the raw deposit.
    pub raw_peak_ratio: f64,
    /// Median mean FLIP over the caustic pixels (with the `flip` feature).
    pub flip: Option<f64>,
    /// Relative bias of the mean over the repeats (seeds 1..=repeats).
    pub relative_bias: f64,
    /// Relative variance over the repeats; NaN (`null` in report.json) from a single
    /// repeat, which has no variance.
    pub relative_variance: f64,
    /// Photons behind the reference.
    pub reference_photons: u64,
    /// Relative standard error the reference reached (NaN, `null` in report.json, for
    /// a reference in which no pixel carries signal: [`ReferenceInfo::noise`]).
    ///
    /// [`ReferenceInfo::noise`]: crate::reference::ReferenceInfo::noise
    pub reference_noise: f64,
    /// The errors against the independent light tracer; `None` for a technique whose
    /// light the tracer does not cover (PhotonGi's indirect light,
    /// [`reference::traced_by_light_tracer`]) and in a skipped record.
    pub tracer: Option<TracerErrors>,
    /// Why the combination was left out (its reference holds no caustic: nothing to
    /// measure against; the technique could not be made for accumulated frames); `None` (absent from
    /// report.json) for a measured one. A skipped record's measurements are NaN (`null`
    /// in report.json), its `repeats` 0.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skipped: Option<String>,
}

/// One combination's errors against the independent f64 light tracer's image of the same
/// scene and camera, over the tracer's caustic pixels (`CausticMask::from_reference` of
/// its mean).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TracerErrors {
    /// Median over the repeats of the filtered caustics' relative MSE (dimensionless).
    pub relative_mse: f64,
    /// The same for the raw (unfiltered) caustics.
    pub raw_relative_mse: f64,
    /// The tracer's relative standard error of the mean (RMS over its caustic pixels of
    /// the per-pixel standard error from its batches' spread, relative to the RMS of the
    /// mean): its square is what the tracer's own noise adds to a relative MSE.
    pub noise: f64,
    /// Photons the tracer emitted over all batches and lights.
    pub photons: u64,
    /// Independent batches behind the error bar.
    pub batches: u32,
    /// What a silhouette pixel measures in the tracer's image.
    pub silhouette: SilhouetteDefinition,
    /// Spheres as the tracer traced them.
    pub spheres: SphereModel,
}

impl Record {
    /// The headline errors (filtered, raw): against the light tracer where the record has
    /// them, else against the technique's own reference.
    pub fn headline_errors(&self) -> (f64, f64) {
        match &self.tracer {
            Some(t) => (t.relative_mse, t.raw_relative_mse),
            None => (self.relative_mse, self.raw_relative_mse),
        }
    }
}

/// What to measure.
pub struct ReportPlan {
    /// Scenes (their cameras' sizes are replaced by the reference's).
    pub scenes: Vec<Scene>,
    /// Technique specs: a registry name, optionally with setting overrides
    /// (`adaptive-caustics:deposit=screen+metric=level`, see [`technique_spec`]); the
    /// spec names the technique in the records.
    pub techniques: Vec<String>,
    /// Backend names.
    pub backends: Vec<String>,
    /// Photon grids per light.
    pub budgets: Vec<(u32, u32)>,
    /// Frames accumulated per run (1: single frames; more needs a technique with
    /// `accumulate`, the others are skipped: a log line and a [`Record::skipped`]
    /// record).
    pub frames: Vec<usize>,
    /// Caustic filters to compare (Sspm's `filter`: density, bilateral; CausticMap's
    /// `gather`: box, density), each measured on its own; a technique runs those it has,
    /// or its default where it has none of them.
    pub filters: Vec<String>,
    /// Settings every combination starts from (a JSON object of the technique's fields;
    /// the budget and the filter are set over it).
    pub settings: serde_json::Map<String, serde_json::Value>,
    /// Frames measured per combination (after a warm-up).
    pub repeats: usize,
    /// How the techniques' own references are computed.
    pub reference: ReferenceSpec,
    /// How the light-tracer reference of the caustic techniques is computed (its width
    /// and height are replaced by `reference`'s, the size every technique renders at).
    pub tracer: LightTracerSpec,
}

pub use crate::technique_spec::technique_spec;
use crate::technique_spec::{merge_settings, put_setting};

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// The filter setting of technique `name` under `settings` (its path and its values, the
/// default first), `None` for a technique with one filter or an unknown name.
fn filter_setting(
    name: &str,
    settings: &serde_json::Map<String, serde_json::Value>,
) -> Option<FilterSetting> {
    TECHNIQUES
        .iter()
        .find(|t| t.name == name)
        .and_then(|t| (t.filter_setting)(settings))
}

/// The plan's settings with a technique spec's `overrides` over them.
fn spec_settings(
    plan: &ReportPlan,
    overrides: &serde_json::Map<String, serde_json::Value>,
) -> serde_json::Map<String, serde_json::Value> {
    let mut settings = plan.settings.clone();
    merge_settings(&mut settings, overrides.clone());
    settings
}

/// The filters technique `name` runs under `settings` of those `asked`: the asked ones
/// it has (Sspm's `filter`, CausticMap's `gather`), its default filter where it has none
/// of them, and [`OWN_FILTER`] once for a technique with one filter.
fn filters_for(
    name: &str,
    settings: &serde_json::Map<String, serde_json::Value>,
    asked: &[String],
) -> Vec<String> {
    match filter_setting(name, settings) {
        Some((_, values)) => {
            let asked: Vec<String> = asked
                .iter()
                .filter(|f| values.contains(&f.as_str()))
                .cloned()
                .collect();
            if asked.is_empty() {
                values.iter().take(1).map(|v| v.to_string()).collect()
            } else {
                asked
            }
        }
        None => vec![OWN_FILTER.to_string()],
    }
}

/// Every filter name some technique has under its default settings (`density`,
/// `bilateral`, `box`), each once.
fn known_filters() -> Vec<&'static str> {
    let mut known: Vec<&'static str> = Vec::new();
    let defaults = serde_json::Map::new();
    for (_, values) in TECHNIQUES
        .iter()
        .filter_map(|t| (t.filter_setting)(&defaults))
    {
        for v in values.iter() {
            if !known.contains(v) {
                known.push(v);
            }
        }
    }
    known
}

/// Every (filter, budget, frames) of one technique and backend, in the order they are
/// measured (frames of at least 1; a plan without a frames axis measures single frames).
fn combinations(filters: &[String], plan: &ReportPlan) -> Vec<(String, (u32, u32), usize)> {
    let frames_axis: Vec<usize> = if plan.frames.is_empty() {
        vec![1]
    } else {
        plan.frames.iter().map(|&n| n.max(1)).collect()
    };
    let mut all = Vec::new();
    for f in filters {
        for &b in &plan.budgets {
            for &n in &frames_axis {
                all.push((f.clone(), b, n));
            }
        }
    }
    all
}

/// The settings one combination of technique `name` runs with, a JSON object: the plan's
/// settings, the technique spec's `overrides` over them, then the photon budget, the
/// filter (where `name` has a filter setting) and, beyond one frame, accumulation.
fn combination_settings(
    plan: &ReportPlan,
    overrides: &serde_json::Map<String, serde_json::Value>,
    name: &str,
    filter: &str,
    (pw, ph): (u32, u32),
    frames: usize,
) -> serde_json::Value {
    let mut settings = spec_settings(plan, overrides);
    put_setting(&mut settings, "frame.photons_w", pw.into());
    put_setting(&mut settings, "frame.photons_h", ph.into());
    if let Some((path, _)) = filter_setting(name, &spec_settings(plan, overrides)) {
        put_setting(&mut settings, path, filter.into());
    }
    if frames > 1 {
        put_setting(&mut settings, "frame.accumulate", true.into());
    }
    serde_json::Value::Object(settings)
}

/// Parses and validates `settings` for technique `name` as making it does
/// ([`caustica_core::techniques::create`]: the pipeline's `parse_settings`, then its
/// `validate`), without a backend or a scene. A technique this does not know (one
/// registered later) passes here and is checked when it is made.
fn check_settings(name: &str, settings: &serde_json::Value) -> Result<(), crate::Error> {
    use caustica_core::frame::pipeline::Pipeline;
    use caustica_core::techniques::{adaptive_caustics, caustic_map, photon_gi, sspm};
    fn parse_and_validate<P: Pipeline>(settings: &serde_json::Value) -> Result<(), crate::Error> {
        P::validate(&P::parse_settings(settings)?)
    }
    match name {
        "sspm" => parse_and_validate::<sspm::SspmPipeline>(settings),
        "caustic-map" => parse_and_validate::<caustic_map::CausticMapPipeline>(settings),
        "adaptive-caustics" => {
            parse_and_validate::<adaptive_caustics::AdaptiveCausticsPipeline>(settings)
        }
        "photon-gi" => parse_and_validate::<photon_gi::PhotonGiPipeline>(settings),
        _ => Ok(()),
    }
}

/// The positions of the first entry of `items` whose `key` equals an earlier entry's, and
/// of that earlier entry.
fn first_repeat<T, K: PartialEq>(items: &[T], key: impl Fn(&T) -> K) -> Option<(usize, usize)> {
    let keys: Vec<K> = items.iter().map(key).collect();
    (1..keys.len()).find_map(|j| (0..j).find(|&i| keys[i] == keys[j]).map(|i| (i, j)))
}

/// Checks everything in `plan` that can be checked before any reference is computed, and
/// returns the first problem, naming the entry or combination:
///
/// - no scene twice by name (or by the file name its plot takes): two such scenes'
///   records could not be told apart and they would write one plot file;
/// - no technique spec, filter, budget, backend or frames entry twice;
/// - every filter one that some technique has (a technique without it runs its default);
/// - a technique spec with settings after a `:` has some (`sspm:` is refused);
/// - every technique's settings for every filter and budget, and its reference's, parse
///   and validate as the technique will parse and validate them when it is made;
/// - a reference has at least 2 frames (its noise is their spread);
/// - no list is empty, every backend is one caustica has, and the light tracer's settings
///   (at the references' size) can give an estimate with an error bar.
pub fn validate(plan: &ReportPlan) -> Result<(), ReportError> {
    let plan_err = |m: String| Err(ReportError::Plan(m));
    for (what, empty) in [
        ("scenes", plan.scenes.is_empty()),
        ("techniques", plan.techniques.is_empty()),
        ("backends", plan.backends.is_empty()),
        ("budgets", plan.budgets.is_empty()),
        ("frames", plan.frames.is_empty()),
    ] {
        if empty {
            return plan_err(format!("the list of {what} is empty: nothing to measure"));
        }
    }
    if let Some(b) = plan
        .backends
        .iter()
        .find(|b| !crate::BACKEND_NAMES.contains(&b.as_str()))
    {
        return plan_err(format!(
            "unknown backend '{b}'; caustica's: {}",
            crate::BACKEND_NAMES.join(", ")
        ));
    }
    light_tracer::validate(&LightTracerSpec {
        width: plan.reference.width,
        height: plan.reference.height,
        ..plan.tracer.clone()
    })?;
    if let Some((i, j)) = first_repeat(&plan.scenes, |s| crate::output::file_stem(&s.name)) {
        let (a, b) = (&plan.scenes[i].name, &plan.scenes[j].name);
        return plan_err(if a == b {
            format!(
                "scenes {} and {} of the list are both named '{a}': their records and plots \
                 could not be told apart (list a scene once; give different scenes different \
                 names)",
                i + 1,
                j + 1
            )
        } else {
            format!(
                "scenes '{a}' and '{b}' would write the same plot file error_vs_time_{}.png \
                 (give them names that differ in letters or digits)",
                crate::output::file_stem(a)
            )
        });
    }
    let budgets: Vec<String> = plan
        .budgets
        .iter()
        .map(|(w, h)| format!("{w}x{h}"))
        .collect();
    let frames: Vec<String> = plan.frames.iter().map(|n| n.to_string()).collect();
    for (what, list) in [
        ("technique", &plan.techniques),
        ("filter", &plan.filters),
        ("budget", &budgets),
        ("backend", &plan.backends),
        ("frames entry", &frames),
    ] {
        if let Some((_, j)) = first_repeat(list, |s| s.clone()) {
            return plan_err(format!("{what} '{}' is listed twice", list[j]));
        }
    }
    let known = known_filters();
    if let Some(f) = plan.filters.iter().find(|f| !known.contains(&f.as_str())) {
        return plan_err(format!(
            "unknown filter '{f}'; available: {}",
            known.join(", ")
        ));
    }
    if plan.reference.max_frames < 2 {
        return plan_err(format!(
            "a reference needs at least 2 frames, its noise being their spread \
             (--reference-frames {})",
            plan.reference.max_frames
        ));
    }
    for t in &plan.techniques {
        let (name, overrides) = technique_spec(t).map_err(ReportError::Plan)?;
        if t.split_once(':')
            .is_some_and(|(_, rest)| rest.trim().is_empty())
        {
            return plan_err(format!(
                "technique '{t}': no settings after ':' (write '{name}' for its default \
                 settings)"
            ));
        }
        for filter in filters_for(name, &spec_settings(plan, &overrides), &plan.filters) {
            for &(pw, ph) in &plan.budgets {
                let settings = combination_settings(plan, &overrides, name, &filter, (pw, ph), 1);
                check_settings(name, &settings).map_err(|e| {
                    let filter = if filter == OWN_FILTER {
                        String::new()
                    } else {
                        format!("filter {filter}, ")
                    };
                    ReportError::Plan(format!("technique '{t}' ({filter}budget {pw}x{ph}): {e}"))
                })?;
            }
        }
        let spec = reference::reference_for(name, &plan.reference);
        let (reference_name, settings) =
            reference::reference_settings(&spec).map_err(ReportError::Plan)?;
        check_settings(reference_name, &settings).map_err(|e| {
            ReportError::Plan(format!(
                "the reference of technique '{t}' ({}): {e}",
                spec.technique
            ))
        })?;
    }
    Ok(())
}

/// Why technique `name` has nothing to be measured against in `scene`: its own
/// reference `own` holds no signal; `None` where it holds some. (A light tracer's image
/// without signal only leaves out the errors against it: [`measured_tracer`].)
fn nothing_to_measure(scene: &str, name: &str, own: &reference::Reference) -> Option<String> {
    if !reference::holds_signal(&own.image) {
        let light = if reference::traced_by_light_tracer(name) {
            "caustic"
        } else {
            "indirect light"
        };
        return Some(format!(
            "the reference of {scene} holds no {light}: nothing to measure against"
        ));
    }
    None
}

/// The light tracer's image to measure against, `None` where it holds no caustic (with a
/// log line: the errors against it are left out, those against the technique's own
/// reference are still measured).
fn measured_tracer<'a>(
    scene: &str,
    tracer: Option<&'a Traced>,
    log: &mut dyn FnMut(&str),
) -> Option<&'a Traced> {
    match tracer {
        Some(t) if t.mask.count == 0 => {
            log(&format!(
                "{scene}: the light tracer's image holds no caustic ({} photons, {} \
                 connected): no errors against it",
                t.info.photons, t.info.connected
            ));
            None
        }
        other => other,
    }
}

/// A noise for a log line: the number, or `n/a` where there is none to give (not finite,
/// or not positive: the light tracer's 0 is an image in which no pixel carries signal).
fn noise_text(noise: f64, digits: usize) -> String {
    if noise.is_finite() && noise > 0.0 {
        format!("{noise:.digits$}")
    } else {
        "n/a".into()
    }
}

/// One combination's place in the plan: what its record names.
struct Combination<'a> {
    /// The scene at the report's size.
    scene: &'a Scene,
    technique: &'a str,
    filter: &'a str,
    backend: &'a str,
    budget: (u32, u32),
    frames: usize,
}

impl Combination<'_> {
    /// The record of this combination left out for `reason`: no measurement (NaN, `null`
    /// in report.json), no repeats.
    fn skipped(&self, reason: &str, reference_photons: u64) -> Record {
        Record {
            scene: self.scene.name.clone(),
            technique: self.technique.to_string(),
            filter: self.filter.to_string(),
            backend: self.backend.to_string(),
            device: String::new(),
            budget: format!("{}x{}", self.budget.0, self.budget.1),
            photons: 0,
            frames: self.frames,
            width: self.scene.camera.width,
            height: self.scene.camera.height,
            repeats: 0,
            timing: String::new(),
            frame_ms: f64::NAN,
            pass_ms: BTreeMap::new(),
            relative_mse: f64::NAN,
            raw_relative_mse: f64::NAN,
            rmse: f64::NAN,
            peak_ratio: f64::NAN,
            raw_peak_ratio: f64::NAN,
            flip: None,
            relative_bias: f64::NAN,
            relative_variance: f64::NAN,
            reference_photons,
            reference_noise: f64::NAN,
            tracer: None,
            skipped: Some(reason.to_string()),
        }
    }
}

/// Runs the plan; references are cached under `cache`. `log` receives progress lines.
/// The plan is checked first ([`validate`]) and the cache folder made and tried, before
/// any reference is computed; a cache that cannot be written to is taken where it holds
/// every reference the plan needs (a line in `log` says so) and refused, naming the ones
/// it lacks, where it does not. A combination with nothing to measure against (a reference
/// that holds no caustic) or that cannot be made for accumulated frames is not measured: its
/// record says why ([`Record::skipped`]), and the others go on.
pub fn run(
    plan: &ReportPlan,
    cache: &Path,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<Record>, ReportError> {
    validate(plan)?;
    crate::output::make_folder(cache).map_err(ReportError::Cache)?;
    if let Err(e) = crate::output::check_writable(cache) {
        let missing = missing_references(plan, cache)?;
        if !missing.is_empty() {
            return Err(ReportError::Cache(format!(
                "{e}; it lacks {}",
                missing.join(", ")
            )));
        }
        log(&format!(
            "reference cache {e}; it holds every reference the plan needs"
        ));
    }
    let mut cpu = crate::open_backend("cpu")?;
    let mut records = Vec::new();
    for original in &plan.scenes {
        // one reference per estimator the techniques need (the caustics' for the caustic
        // techniques, the indirect light's for PhotonGi), computed or loaded once
        let mut references: Vec<reference::Reference> = Vec::new();
        let mut scene = original.clone();
        scene.camera.width = plan.reference.width;
        scene.camera.height = plan.reference.height;
        // the light tracer's image, computed or loaded once, for the caustic techniques
        let mut traced: Option<Traced> = None;
        for technique in &plan.techniques {
            let (name, overrides) = technique_spec(technique).map_err(ReportError::Plan)?;
            if traced.is_none() && reference::traced_by_light_tracer(name) {
                traced = Some(trace_reference(plan, original, cache, log)?);
            }
            let tracer = traced
                .as_ref()
                .filter(|_| reference::traced_by_light_tracer(name));
            let spec = reference::reference_for(name, &plan.reference);
            if !references.iter().any(|r| r.info.spec == spec) {
                log(&format!(
                    "{}: reference {} ({}x{}, target noise {})",
                    scene.name, spec.technique, spec.width, spec.height, spec.target_noise
                ));
                let r = reference::load_or_compute(
                    cache,
                    original,
                    &spec,
                    cpu.as_mut(),
                    &mut |k, max, noise| {
                        if k % 8 == 0 || k == max {
                            log(&format!(
                                "  reference frame {k}/{max}: noise {}",
                                noise_text(noise, 4)
                            ));
                        }
                    },
                )
                .map_err(ReportError::Reference)?;
                let empty = if reference::holds_signal(&r.image) {
                    ""
                } else {
                    " (no pixel carries signal)"
                };
                log(&format!(
                    "  reference: {} photons over {} frames, noise {}{empty}",
                    r.info.photons,
                    r.info.frames,
                    noise_text(r.info.noise, 4)
                ));
                references.push(r);
            }
            let r = references
                .iter()
                .find(|r| r.info.spec == spec)
                .expect("computed above");
            let filters = filters_for(name, &spec_settings(plan, &overrides), &plan.filters);
            let combos = combinations(&filters, plan);
            let tracer = measured_tracer(&scene.name, tracer, log);
            if let Some(reason) = nothing_to_measure(&scene.name, name, r) {
                log(&format!("{}: {technique}: skipped: {reason}", scene.name));
                for backend_name in &plan.backends {
                    for (filter, budget, frames) in &combos {
                        let c = Combination {
                            scene: &scene,
                            technique,
                            filter,
                            backend: backend_name,
                            budget: *budget,
                            frames: *frames,
                        };
                        records.push(c.skipped(&reason, r.info.photons));
                    }
                }
                continue;
            }
            let mask = CausticMask::from_reference(&r.image);
            for backend_name in &plan.backends {
                let mut backend = crate::open_backend(backend_name)?;
                for (filter, (pw, ph), frames) in &combos {
                    let (filter, pw, ph, frames) = (filter, *pw, *ph, *frames);
                    let settings =
                        combination_settings(plan, &overrides, name, filter, (pw, ph), frames);
                    let made = create(name, backend.as_mut(), &scene, &settings);
                    let mut sspm = match made {
                        Ok(t) => t,
                        Err(e) if frames > 1 => {
                            log(&format!(
                                "  {technique}/{filter}/{backend_name} {pw}x{ph} x {frames} frames: skipped ({e})"
                            ));
                            let c = Combination {
                                scene: &scene,
                                technique,
                                filter,
                                backend: backend_name,
                                budget: (pw, ph),
                                frames,
                            };
                            let reason = format!("not made for {frames} accumulated frames: {e}");
                            records.push(c.skipped(&reason, r.info.photons));
                            continue;
                        }
                        Err(e) => return Err(e.into()),
                    };
                    let (filtered_output, raw_output) = sspm.estimate_outputs();
                    sspm.set_reference(Some(r.image.clone()))?;
                    // warm-up frame (pipeline caches, first-touch allocations)
                    sspm.frame(backend.as_mut(), &mut |_| {})?;
                    let (mut frame_ms, mut rel, mut rmse, mut flip) =
                        (vec![], vec![], vec![], vec![]);
                    let (mut raw_rel, mut peak, mut raw_peak) = (vec![], vec![], vec![]);
                    let (mut tracer_rel, mut tracer_raw_rel) = (vec![], vec![]);
                    let mut passes: BTreeMap<String, Vec<f64>> = BTreeMap::new();
                    let mut images: Vec<Image> = Vec::new();
                    let (mut timing, mut photons, mut device) = (String::new(), 0, String::new());
                    for k in 0..plan.repeats.max(1) {
                        if frames > 1 {
                            // an accumulation of its own from the first frame
                            sspm.free(backend.as_mut())?;
                            sspm = create(name, backend.as_mut(), &scene, &settings)?;
                            sspm.set_reference(Some(r.image.clone()))?;
                        }
                        sspm.set_seed(k as u32 + 1);
                        let (mut ms, mut pass_sums) = (0.0, BTreeMap::<String, f64>::new());
                        let mut last = None;
                        for _ in 0..frames {
                            let st = sspm.frame(backend.as_mut(), &mut |_| {})?;
                            ms += st.frame_ms;
                            for (p, t) in &st.pass_ms {
                                *pass_sums.entry(p.clone()).or_default() += *t;
                            }
                            last = Some(st);
                        }
                        let st = last.expect("at least one frame");
                        frame_ms.push(ms);
                        for (p, t) in pass_sums {
                            passes.entry(p).or_default().push(t);
                        }
                        if let Some(e) = &st.error {
                            rel.push(e.relative_mse);
                            rmse.push(e.rmse);
                            if let Some(f) = e.flip {
                                flip.push(f);
                            }
                        }
                        let filtered = sspm.read_output(backend.as_mut(), filtered_output)?;
                        let raw = sspm.read_output(backend.as_mut(), raw_output)?;
                        raw_rel.push(relative_mse(&raw, &r.image, &mask));
                        if let Some(t) = tracer {
                            for img in [&filtered, &raw] {
                                if (img.width, img.height) != (t.image.width, t.image.height) {
                                    return Err(ReportError::SizeMismatch {
                                        technique: technique.clone(),
                                        estimate: (img.width, img.height),
                                        tracer: (t.image.width, t.image.height),
                                    });
                                }
                            }
                            tracer_rel.push(relative_mse(&filtered, &t.image, &t.mask));
                            tracer_raw_rel.push(relative_mse(&raw, &t.image, &t.mask));
                        }
                        peak.push(peak_ratio(&filtered, &r.image, &mask));
                        raw_peak.push(peak_ratio(&raw, &r.image, &mask));
                        images.push(filtered);
                        (timing, photons, device) =
                            (st.timing.clone(), st.photons_emitted, st.device.clone());
                    }
                    sspm.free(backend.as_mut())?;
                    let bv = bias_variance(&images, &r.image, &mask);
                    let rec = Record {
                        scene: scene.name.clone(),
                        technique: technique.clone(),
                        filter: filter.clone(),
                        backend: backend_name.clone(),
                        device,
                        budget: format!("{pw}x{ph}"),
                        photons,
                        frames,
                        width: scene.camera.width,
                        height: scene.camera.height,
                        repeats: plan.repeats.max(1),
                        timing,
                        frame_ms: median(&mut frame_ms),
                        pass_ms: passes
                            .into_iter()
                            .map(|(k, mut v)| (k, median(&mut v)))
                            .collect(),
                        relative_mse: median(&mut rel),
                        raw_relative_mse: median(&mut raw_rel),
                        rmse: median(&mut rmse),
                        peak_ratio: median(&mut peak),
                        raw_peak_ratio: median(&mut raw_peak),
                        flip: (!flip.is_empty()).then(|| median(&mut flip)),
                        relative_bias: bv.relative_bias,
                        // one sample has no variance
                        relative_variance: if images.len() > 1 {
                            bv.relative_variance
                        } else {
                            f64::NAN
                        },
                        reference_photons: r.info.photons,
                        reference_noise: r.info.noise,
                        tracer: tracer.map(|t| TracerErrors {
                            relative_mse: median(&mut tracer_rel),
                            raw_relative_mse: median(&mut tracer_raw_rel),
                            noise: t.info.noise,
                            photons: t.info.photons,
                            batches: t.info.spec.batches,
                            silhouette: t.info.spec.silhouette,
                            spheres: t.info.spec.spheres,
                        }),
                        skipped: None,
                    };
                    let against_tracer = rec.tracer.as_ref().map_or(String::new(), |t| {
                        format!(
                            "; against the light tracer {:.3e} (raw {:.3e})",
                            t.relative_mse, t.raw_relative_mse
                        )
                    });
                    log(&format!(
                        "  {technique}/{filter}/{backend_name} {pw}x{ph} x {frames} frames: {:.2} ms, relMSE {:.3e} (raw {:.3e}) against its own reference{against_tracer}",
                        rec.frame_ms, rec.relative_mse, rec.raw_relative_mse
                    ));
                    records.push(rec);
                }
            }
        }
    }
    Ok(records)
}

/// The light tracer's image of one scene, with its caustic mask.
struct Traced {
    image: Image,
    mask: CausticMask,
    info: light_tracer::LightTracerInfo,
}

/// Loads or computes the light-tracer reference of `scene` at the plan's size.
/// The light tracer's settings of the plan's reference images.
fn tracer_spec(plan: &ReportPlan) -> LightTracerSpec {
    LightTracerSpec {
        width: plan.reference.width,
        height: plan.reference.height,
        ..plan.tracer.clone()
    }
}

/// The cache files of the references the plan needs that `cache` lacks, each with the
/// scene and what it is, in the order [`run`] would make them.
fn missing_references(plan: &ReportPlan, cache: &Path) -> Result<Vec<String>, ReportError> {
    let mut missing = Vec::new();
    for scene in &plan.scenes {
        let mut specs = Vec::new();
        let mut traced = false;
        for technique in &plan.techniques {
            let (name, _) = technique_spec(technique).map_err(ReportError::Plan)?;
            if !traced && reference::traced_by_light_tracer(name) {
                traced = true;
                if let Some(f) = light_tracer::missing_from_cache(cache, scene, &tracer_spec(plan))
                {
                    missing.push(format!("{f} ({}: light tracer)", scene.name));
                }
            }
            let spec = reference::reference_for(name, &plan.reference);
            if !specs.contains(&spec) {
                if let Some(f) = reference::missing_from_cache(cache, scene, &spec) {
                    missing.push(format!(
                        "{f} ({}: reference {})",
                        scene.name, spec.technique
                    ));
                }
                specs.push(spec);
            }
        }
    }
    Ok(missing)
}

fn trace_reference(
    plan: &ReportPlan,
    scene: &Scene,
    cache: &Path,
    log: &mut dyn FnMut(&str),
) -> Result<Traced, ReportError> {
    let spec = tracer_spec(plan);
    log(&format!(
        "{}: light tracer ({}x{}, {} batches of {} photons per light, {} spheres, silhouette \
         pixels {})",
        scene.name,
        spec.width,
        spec.height,
        spec.batches,
        spec.photons,
        spec.spheres.name(),
        spec.silhouette
    ));
    let (image, info) = light_tracer::load_or_compute(cache, scene, &spec, &mut |k, n, noise| {
        if k % 4 == 0 || k == n {
            log(&format!(
                "  light tracer batch {k}/{n}: noise {}",
                noise_text(noise, 5)
            ));
        }
    })?;
    let mask = CausticMask::from_reference(&image);
    let empty = if mask.count == 0 {
        " (no pixel carries signal)"
    } else {
        ""
    };
    log(&format!(
        "  light tracer: {} photons, {} connected, noise {}{empty}",
        info.photons,
        info.connected,
        noise_text(info.noise, 5)
    ));
    if !info.noise.is_finite()
        || image
            .pixels
            .iter()
            .any(|p| !p.iter().all(|v| v.is_finite()))
    {
        return Err(ReportError::NotFinite {
            scene: scene.name.clone(),
        });
    }
    Ok(Traced { mask, image, info })
}

/// A number for a table cell: `-` where the record has no such column (PhotonGi's
/// tracer columns), `n/a` where the value is undefined (not finite).
fn cell(v: Option<f64>, fmt: fn(f64) -> String) -> String {
    v.map_or("-".into(), |v| num(v, fmt))
}

/// A number for a table cell: `n/a` where it is undefined (not finite: a ratio of two
/// zeros, the variance of one repeat).
fn num(v: f64, fmt: fn(f64) -> String) -> String {
    if v.is_finite() {
        fmt(v)
    } else {
        "n/a".into()
    }
}

/// The paragraph above [`table`]'s rows: what each error column is measured against,
/// and what a silhouette pixel is in the light tracer's image.
pub fn caption(records: &[Record]) -> String {
    let mut defs: Vec<SilhouetteDefinition> = Vec::new();
    let mut budgets: Vec<(u64, u32, SphereModel)> = Vec::new();
    for t in records.iter().filter_map(|r| r.tracer.as_ref()) {
        if !defs.contains(&t.silhouette) {
            defs.push(t.silhouette);
        }
        if !budgets.contains(&(t.photons, t.batches, t.spheres)) {
            budgets.push((t.photons, t.batches, t.spheres));
        }
    }
    let tracer = if defs.is_empty() {
        "no technique here is one the light tracer covers".to_string()
    } else {
        let defs: Vec<String> = defs
            .iter()
            .map(|d| format!("{d}: {}", d.describe()))
            .collect();
        let budgets: Vec<String> = budgets
            .iter()
            .map(|(p, b, s)| format!("{p} photons in {b} batches, {} spheres", s.name()))
            .collect();
        format!(
            "silhouette pixels {}; {}",
            defs.join("; "),
            budgets.join("; ")
        )
    };
    format!(
        "Relative MSE over the reference's caustic pixels. *vs tracer*: against the \
         independent f64 light tracer's image of the same scene and camera ({tracer}); \
         *tracer noise²*: the square of its relative standard error, what its own noise \
         adds to a relative MSE. *vs own*: against the technique's converged unfiltered \
         estimate (Sspm's raw deposit for the caustic techniques; PhotonGi's deposit for \
         PhotonGi, whose indirect light the tracer does not cover: `-` in the tracer \
         columns). Peaks, FLIP, bias and variance are against the own reference.\n"
    )
}

/// The records as a Markdown table after its [`caption`]: relative MSE of the filtered
/// caustics and of the raw deposit against the light tracer (with the tracer's noise)
/// and against the technique's own reference, their ratio, and the peak ratios.
pub fn table(records: &[Record]) -> String {
    let mut s = caption(records);
    s.push_str(
        "\n| scene | technique (filter) | backend | photons | frames | ms | relMSE vs tracer | \
         tracer noise² | relMSE vs own | raw vs tracer | raw vs own | filtered / raw (own) | \
         peak filtered | peak raw | FLIP | bias | variance |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    let sci3 = |v: f64| format!("{v:.3e}");
    let sci2 = |v: f64| format!("{v:.2e}");
    let fix1 = |v: f64| format!("{v:.1}");
    let fix3 = |v: f64| format!("{v:.3}");
    let signed4 = |v: f64| format!("{v:+.4}");
    let mut skipped: Vec<String> = Vec::new();
    for r in records {
        let t = r.tracer.as_ref();
        let cells: Vec<String> = if let Some(why) = &r.skipped {
            let line = format!("- {} / {}: {why}", r.scene, r.technique);
            if !skipped.contains(&line) {
                skipped.push(line);
            }
            std::iter::once("skipped".to_string())
                .chain(std::iter::repeat_n("n/a".to_string(), 11))
                .collect()
        } else {
            let ratio = if r.raw_relative_mse > 0.0 {
                r.relative_mse / r.raw_relative_mse
            } else {
                f64::NAN
            };
            vec![
                num(r.frame_ms, fix1),
                cell(t.map(|t| t.relative_mse), sci3),
                cell(t.map(|t| t.noise * t.noise), sci2),
                num(r.relative_mse, sci3),
                cell(t.map(|t| t.raw_relative_mse), sci3),
                num(r.raw_relative_mse, sci3),
                num(ratio, fix3),
                num(r.peak_ratio, fix3),
                num(r.raw_peak_ratio, fix3),
                r.flip.map_or("-".into(), |f| num(f, fix3)),
                num(r.relative_bias, signed4),
                num(r.relative_variance, sci2),
            ]
        };
        s.push_str(&format!(
            "| {} | {} ({}) | {} | {} | {} | {} |\n",
            r.scene,
            r.technique,
            r.filter,
            r.backend,
            r.budget,
            r.frames,
            cells.join(" | ")
        ));
    }
    if !skipped.is_empty() {
        s.push_str("\nNot measured (`skipped` in report.json):\n");
        for line in skipped {
            s.push_str(&line);
            s.push('\n');
        }
    }
    s
}

/// Whole decades around the data, so that every log axis has labelled ticks.
fn decade_below(x: f64) -> f64 {
    10f64.powf(x.log10().floor())
}

fn decade_above(x: f64) -> f64 {
    10f64.powf(x.log10().ceil()).max(decade_below(x) * 10.0)
}

/// Log-log plot of relative MSE against frame time, one curve per technique x backend,
/// for `scene`'s records: each record's [`Record::headline_errors`] (against the light
/// tracer for the caustic techniques, against its own reference for PhotonGi), as the
/// caption says. Needs a TrueType font (DejaVu Sans from fonts-dejavu-core).
pub fn plot(records: &[Record], scene: &str, path: &Path) -> Result<(), String> {
    use plotters::prelude::*;
    let font = ["/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf"]
        .iter()
        .find_map(|p| std::fs::read(p).ok())
        .ok_or("no DejaVuSans.ttf for the plot's text (install fonts-dejavu-core)")?;
    let font: &'static [u8] = Box::leak(font.into_boxed_slice());
    plotters::style::register_font("sans-serif", FontStyle::Normal, font)
        .map_err(|_| "could not load the plot font".to_string())?;
    let rs: Vec<&Record> = records
        .iter()
        .filter(|r| r.scene == scene && r.skipped.is_none())
        .filter(|r| r.frame_ms > 0.0 && r.headline_errors().0 > 0.0)
        .collect();
    if rs.is_empty() {
        let why: Vec<&str> = records
            .iter()
            .filter(|r| r.scene == scene)
            .filter_map(|r| r.skipped.as_deref())
            .collect();
        return Err(match why.first() {
            Some(why) => format!("nothing measured for {scene}: {why}"),
            None => format!("no records with positive time and error for {scene}"),
        });
    }
    let (tmin, tmax) = rs.iter().fold((f64::MAX, 0.0f64), |(a, b), r| {
        (a.min(r.frame_ms), b.max(r.frame_ms))
    });
    let (emin, emax) = rs.iter().fold((f64::MAX, 0.0f64), |(a, b), r| {
        let (filtered, raw) = r.headline_errors();
        let raw = if raw > 0.0 { raw } else { filtered };
        (a.min(filtered).min(raw), b.max(filtered).max(raw))
    });
    let traced = rs.iter().filter(|r| r.tracer.is_some()).count();
    let against = if traced == rs.len() {
        "against the f64 light tracer"
    } else if traced == 0 {
        "against each technique's converged estimate"
    } else {
        "against the light tracer (photon-gi: its deposit)"
    };
    let root = BitMapBackend::new(path, (800, 560)).into_drawing_area();
    let err = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{scene}: error {against} by frame time"),
            ("sans-serif", 22),
        )
        .margin(16)
        .x_label_area_size(44)
        .y_label_area_size(64)
        .build_cartesian_2d(
            (decade_below(tmin)..decade_above(tmax)).log_scale(),
            (decade_below(emin)..decade_above(emax)).log_scale(),
        )
        .map_err(|e| err(&e))?;
    chart
        .configure_mesh()
        .x_desc("frame time (ms)")
        .y_desc("relative MSE (solid: filtered caustics, dashed: raw)")
        .label_style(("sans-serif", 14))
        .x_labels(8)
        .y_labels(8)
        .x_label_formatter(&|v| format!("{v:.3}"))
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(|e| err(&e))?;
    let mut curves: BTreeMap<String, Vec<(f64, f64, f64)>> = BTreeMap::new();
    for r in rs {
        curves
            .entry(if r.frames > 1 {
                // an accumulation's points (one per budget) are a series of their own
                format!(
                    "{} {} / {}, {} frames",
                    r.technique, r.filter, r.backend, r.frames
                )
            } else {
                format!("{} {} / {}", r.technique, r.filter, r.backend)
            })
            .or_default()
            .push((r.frame_ms, r.headline_errors().0, r.headline_errors().1));
    }
    for (i, (name, mut all)) in curves.into_iter().enumerate() {
        all.sort_by(|a, b| a.0.total_cmp(&b.0));
        let color = Palette99::pick(i).to_rgba();
        let raw: Vec<(f64, f64)> = all
            .iter()
            .filter(|p| p.2 > 0.0)
            .map(|p| (p.0, p.2))
            .collect();
        chart
            .draw_series(DashedLineSeries::new(raw, 6, 4, color.stroke_width(1)))
            .map_err(|e| err(&e))?;
        let pts: Vec<(f64, f64)> = all.iter().map(|p| (p.0, p.1)).collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(|e| err(&e))?
            .label(name)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
        chart
            .draw_series(pts.into_iter().map(|p| Circle::new(p, 4, color.filled())))
            .map_err(|e| err(&e))?;
    }
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::UpperRight)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(|e| err(&e))?;
    root.present().map_err(|e| err(&e))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin::builtin;

    /// A tiny plan of `sphere` with Sspm at 16x16 photons.
    fn plan() -> ReportPlan {
        ReportPlan {
            scenes: vec![builtin("sphere").expect("built-in")],
            techniques: vec!["sspm".into()],
            backends: vec!["cpu".into()],
            budgets: vec![(16, 16)],
            frames: vec![1],
            filters: vec!["density".into()],
            settings: serde_json::Map::new(),
            repeats: 1,
            reference: ReferenceSpec {
                width: 32,
                height: 18,
                max_frames: 2,
                ..ReferenceSpec::default()
            },
            tracer: LightTracerSpec::default(),
        }
    }

    /// The error `validate` gives for `plan` changed by `change`.
    fn refused(change: impl FnOnce(&mut ReportPlan)) -> String {
        let mut p = plan();
        change(&mut p);
        match validate(&p) {
            Err(e) => e.to_string(),
            Ok(()) => panic!("the plan was accepted"),
        }
    }

    #[test]
    fn a_report_plan_is_checked_before_any_work() {
        assert!(validate(&plan()).is_ok());
        let e = refused(|p| p.techniques = vec!["sspm:foo=1".into()]);
        assert!(
            e.contains("technique 'sspm:foo=1' (filter density, budget 16x16)"),
            "{e}"
        );
        assert!(e.contains("unknown field `foo`"), "{e}");
        let e = refused(|p| p.techniques = vec!["adaptive-caustics".into()]);
        assert!(e.contains("times a power of two"), "{e}");
        let e = refused(|p| p.techniques = vec!["photon-gi:bogus=1".into()]);
        assert!(
            e.contains("technique 'photon-gi:bogus=1' (budget 16x16)"),
            "{e}"
        );
        let e = refused(|p| p.techniques = vec!["sspm:".into()]);
        assert!(e.contains("no settings after ':'"), "{e}");
        let e = refused(|p| p.filters = vec!["foo".into()]);
        assert_eq!(
            e,
            "unknown filter 'foo'; available: density, bilateral, box"
        );
        let e = refused(|p| p.reference.max_frames = 1);
        assert!(e.contains("at least 2 frames"), "{e}");
        let e = refused(|p| p.backends = vec!["quantum".into()]);
        assert!(e.contains("unknown backend 'quantum'"), "{e}");
        let e = refused(|p| p.budgets.clear());
        assert!(e.contains("the list of budgets is empty"), "{e}");
        let e = refused(|p| p.tracer.photons = u64::MAX);
        assert!(e.contains("photons per batch must be at most"), "{e}");
        let e = refused(|p| p.scenes.push(builtin("sphere").expect("built-in")));
        assert!(
            e.contains("scenes 1 and 2 of the list are both named 'sphere'"),
            "{e}"
        );
        let e = refused(|p| {
            let mut other = builtin("cornell").expect("built-in");
            other.name = "sphere 1".into();
            p.scenes[0].name = "sphere_1".into();
            p.scenes.push(other);
        });
        assert!(
            e.contains("would write the same plot file error_vs_time_sphere_1.png"),
            "{e}"
        );
        let e = refused(|p| p.budgets.push((16, 16)));
        assert_eq!(e, "budget '16x16' is listed twice");
        let e = refused(|p| {
            p.settings
                .insert("frame".into(), serde_json::json!({"seed": "x"}));
        });
        assert!(e.contains("technique 'sspm'"), "{e}");
    }

    /// A measured record of `plan()`'s combination.
    fn record() -> Record {
        let scene = builtin("sphere").expect("built-in");
        let c = Combination {
            scene: &scene,
            technique: "sspm",
            filter: "density",
            backend: "cpu",
            budget: (16, 16),
            frames: 1,
        };
        Record {
            skipped: None,
            repeats: 1,
            frame_ms: 1.5,
            relative_mse: 0.25,
            raw_relative_mse: 0.0,
            rmse: 0.1,
            peak_ratio: 1.0,
            raw_peak_ratio: 1.0,
            relative_bias: 0.01,
            relative_variance: f64::NAN,
            reference_noise: 0.02,
            ..c.skipped("", 1)
        }
    }

    #[test]
    fn the_table_has_no_nan() {
        let measured = record();
        let mut empty = record();
        empty.scene = "plain".into();
        empty.skipped = Some("the reference of plain holds no caustic".into());
        let text = table(&[measured, empty]);
        assert!(!text.to_lowercase().contains("nan"), "{text}");
        let rows: Vec<&str> = text.lines().filter(|l| l.starts_with("| ")).collect();
        // header, rule, two rows, each with the header's columns
        assert_eq!(rows.len(), 4, "{text}");
        let columns = rows[0].matches('|').count();
        assert!(
            rows.iter().all(|r| r.matches('|').count() == columns),
            "{text}"
        );
        // filtered / raw of a zero raw error, and one repeat's variance: n/a
        let cells: Vec<&str> = rows[2].split('|').map(str::trim).collect();
        assert_eq!(cells[12], "n/a", "{}", rows[2]);
        assert_eq!(cells[17], "n/a", "{}", rows[2]);
        assert!(rows[3].contains("| skipped |"), "{}", rows[3]);
        assert!(text.contains("- plain / sspm: the reference of plain holds no caustic"));
    }
}

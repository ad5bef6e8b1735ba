//! Error against run time: for every scene x technique x backend x photon budget x
//! frames accumulated (any registered technique, created by name), the median time and
//! per-pass times over repeated runs (device timestamps where the backend has them) and
//! the error of the filtered caustics against the scene's reference, with bias and
//! variance over the repeats' seeds. A run of `frames` > 1 accumulates that many frames
//! of the budget (`accumulate: true`, a fresh technique per repeat) and is timed to its
//! last frame. Writes one JSON record per combination and a log-log plot of relative MSE
//! against time per scene.

use crate::reference::{self, ReferenceSpec};
use caustica_core::frame::image::Image;
use caustica_core::frame::metrics::{bias_variance, peak_ratio, relative_mse, CausticMask};
use caustica_core::techniques::{create, TECHNIQUES};

/// The filter label of a technique that has no `filter` setting (its own filter runs).
pub const OWN_FILTER: &str = "own";
use caustica_core::Scene;
use serde::Serialize;
use std::collections::BTreeMap;
use std::path::Path;

/// One measured combination.
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
    /// Relative variance over the repeats.
    pub relative_variance: f64,
    /// Photons behind the reference.
    pub reference_photons: u64,
    /// Relative standard error the reference reached.
    pub reference_noise: f64,
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
    /// `accumulate`, the others are skipped with a log line).
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
    /// How references are computed.
    pub reference: ReferenceSpec,
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

/// Runs the plan; references are cached under `cache`. `log` receives progress lines.
pub fn run(
    plan: &ReportPlan,
    cache: &Path,
    log: &mut dyn FnMut(&str),
) -> Result<Vec<Record>, String> {
    for t in &plan.techniques {
        technique_spec(t)?;
    }
    let mut cpu = crate::open_backend("cpu").map_err(|e| e.to_string())?;
    let mut records = Vec::new();
    for original in &plan.scenes {
        // one reference per estimator the techniques need (the caustics' for the caustic
        // techniques, the indirect light's for PhotonGi), computed or loaded once
        let mut references: Vec<reference::Reference> = Vec::new();
        let mut scene = original.clone();
        scene.camera.width = plan.reference.width;
        scene.camera.height = plan.reference.height;
        for technique in &plan.techniques {
            let (name, overrides) = technique_spec(technique)?;
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
                            log(&format!("  reference frame {k}/{max}: noise {noise:.4}"));
                        }
                    },
                )?;
                log(&format!(
                    "  reference: {} photons over {} frames, noise {:.4}",
                    r.info.photons, r.info.frames, r.info.noise
                ));
                references.push(r);
            }
            let r = references
                .iter()
                .find(|r| r.info.spec == spec)
                .expect("computed above");
            let mask = CausticMask::from_reference(&r.image);
            // each technique runs the asked filters it has (Sspm's `filter`, CausticMap's
            // `gather`), its default filter where it has none of them, and a technique
            // with one filter runs it once as "own"
            let filter_setting = TECHNIQUES
                .iter()
                .find(|t| t.name == name)
                .and_then(|t| t.filter_setting);
            let filters: Vec<String> = match filter_setting {
                Some((_, values)) => {
                    let asked: Vec<String> = plan
                        .filters
                        .iter()
                        .filter(|f| values.contains(&f.as_str()))
                        .cloned()
                        .collect();
                    if asked.is_empty() {
                        vec![values[0].to_string()]
                    } else {
                        asked
                    }
                }
                None => vec![OWN_FILTER.to_string()],
            };
            for backend_name in &plan.backends {
                let mut backend = crate::open_backend(backend_name).map_err(|e| e.to_string())?;
                let frames_axis: Vec<usize> = if plan.frames.is_empty() {
                    vec![1]
                } else {
                    plan.frames.clone()
                };
                for (filter, &(pw, ph), &frames) in filters.iter().flat_map(|f| {
                    plan.budgets
                        .iter()
                        .flat_map(|b| frames_axis.iter().map(move |n| (b, n)))
                        .map(move |(b, n)| (f, b, n))
                }) {
                    let frames = frames.max(1);
                    let mut settings = plan.settings.clone();
                    merge_settings(&mut settings, overrides.clone());
                    put_setting(&mut settings, "frame.photons_w", pw.into());
                    put_setting(&mut settings, "frame.photons_h", ph.into());
                    if let Some((path, _)) = filter_setting {
                        put_setting(&mut settings, path, filter.as_str().into());
                    }
                    if frames > 1 {
                        put_setting(&mut settings, "frame.accumulate", true.into());
                    }
                    let settings = serde_json::Value::Object(settings);
                    let made = create(name, backend.as_mut(), &scene, &settings);
                    let mut sspm = match made {
                        Ok(t) => t,
                        Err(e) if frames > 1 => {
                            log(&format!(
                                "  {technique}/{filter}/{backend_name} {pw}x{ph} x {frames} frames: skipped ({e})"
                            ));
                            continue;
                        }
                        Err(e) => return Err(e.to_string()),
                    };
                    let (filtered_output, raw_output) = sspm.estimate_outputs();
                    sspm.set_reference(Some(r.image.clone()))
                        .map_err(|e| e.to_string())?;
                    // warm-up frame (pipeline caches, first-touch allocations)
                    sspm.frame(backend.as_mut(), &mut |_| {})
                        .map_err(|e| e.to_string())?;
                    let (mut frame_ms, mut rel, mut rmse, mut flip) =
                        (vec![], vec![], vec![], vec![]);
                    let (mut raw_rel, mut peak, mut raw_peak) = (vec![], vec![], vec![]);
                    let mut passes: BTreeMap<String, Vec<f64>> = BTreeMap::new();
                    let mut images: Vec<Image> = Vec::new();
                    let (mut timing, mut photons, mut device) = (String::new(), 0, String::new());
                    for k in 0..plan.repeats.max(1) {
                        if frames > 1 {
                            // an accumulation of its own from the first frame
                            sspm.free(backend.as_mut()).map_err(|e| e.to_string())?;
                            sspm = create(name, backend.as_mut(), &scene, &settings)
                                .map_err(|e| e.to_string())?;
                            sspm.set_reference(Some(r.image.clone()))
                                .map_err(|e| e.to_string())?;
                        }
                        sspm.set_seed(k as u32 + 1);
                        let (mut ms, mut pass_sums) = (0.0, BTreeMap::<String, f64>::new());
                        let mut last = None;
                        for _ in 0..frames {
                            let st = sspm
                                .frame(backend.as_mut(), &mut |_| {})
                                .map_err(|e| e.to_string())?;
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
                        let filtered = sspm
                            .read_output(backend.as_mut(), filtered_output)
                            .map_err(|e| e.to_string())?;
                        let raw = sspm
                            .read_output(backend.as_mut(), raw_output)
                            .map_err(|e| e.to_string())?;
                        raw_rel.push(relative_mse(&raw, &r.image, &mask));
                        peak.push(peak_ratio(&filtered, &r.image, &mask));
                        raw_peak.push(peak_ratio(&raw, &r.image, &mask));
                        images.push(filtered);
                        (timing, photons, device) =
                            (st.timing.clone(), st.photons_emitted, st.device.clone());
                    }
                    sspm.free(backend.as_mut()).map_err(|e| e.to_string())?;
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
                        relative_variance: bv.relative_variance,
                        reference_photons: r.info.photons,
                        reference_noise: r.info.noise,
                    };
                    log(&format!(
                        "  {technique}/{filter}/{backend_name} {pw}x{ph} x {frames} frames: {:.2} ms, relMSE {:.5} (raw {:.5})",
                        rec.frame_ms, rec.relative_mse, rec.raw_relative_mse
                    ));
                    records.push(rec);
                }
            }
        }
    }
    Ok(records)
}

/// The records as a Markdown table (the README's): relative MSE of the filtered
/// caustics and of the raw deposit, their ratio, and the peak ratios.
pub fn table(records: &[Record]) -> String {
    let mut s = String::from(
        "| scene | technique (filter) | backend | photons | frames | ms | relMSE filtered | relMSE raw | \
         filtered / raw | peak filtered | peak raw | FLIP | bias | variance |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for r in records {
        s.push_str(&format!(
            "| {} | {} ({}) | {} | {} | {} | {:.1} | {:.3e} | {:.3e} | {:.3} | {:.3} | {:.3} | {} | {:+.4} | {:.2e} |\n",
            r.scene,
            r.technique,
            r.filter,
            r.backend,
            r.budget,
            r.frames,
            r.frame_ms,
            r.relative_mse,
            r.raw_relative_mse,
            if r.raw_relative_mse > 0.0 {
                r.relative_mse / r.raw_relative_mse
            } else {
                f64::NAN
            },
            r.peak_ratio,
            r.raw_peak_ratio,
            r.flip.map_or("-".into(), |f| format!("{f:.3}")),
            r.relative_bias,
            r.relative_variance,
        ));
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
/// for `scene`'s records. Needs a TrueType font (DejaVu Sans from fonts-dejavu-core).
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
        .filter(|r| r.scene == scene && r.frame_ms > 0.0 && r.relative_mse > 0.0)
        .collect();
    if rs.is_empty() {
        return Err(format!(
            "no records with positive time and error for {scene}"
        ));
    }
    let (tmin, tmax) = rs.iter().fold((f64::MAX, 0.0f64), |(a, b), r| {
        (a.min(r.frame_ms), b.max(r.frame_ms))
    });
    let (emin, emax) = rs.iter().fold((f64::MAX, 0.0f64), |(a, b), r| {
        let raw = if r.raw_relative_mse > 0.0 {
            r.raw_relative_mse
        } else {
            r.relative_mse
        };
        (
            a.min(r.relative_mse).min(raw),
            b.max(r.relative_mse).max(raw),
        )
    });
    let root = BitMapBackend::new(path, (800, 560)).into_drawing_area();
    let err = |e: &dyn std::fmt::Display| format!("{}: {e}", path.display());
    root.fill(&WHITE).map_err(|e| err(&e))?;
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{scene}: caustic error against frame time"),
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
            .push((r.frame_ms, r.relative_mse, r.raw_relative_mse));
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

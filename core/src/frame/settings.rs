//! The settings every technique shares, with one name and one place in each technique's
//! settings: `frame` ([`FrameSettings`]: the photon grid, seed, accumulation, the
//! temporal and A-Trous filter chain, outputs, pruning, the camera's specular chains and
//! the triangle budget) and, for the three caustic techniques, `trace`
//! ([`TraceSettings`]: how far photons are followed and how many are traced at once).
//! What is a technique's or a receiver's own sits in its own block (`screen`, `atlas`,
//! `planes`, ...) or at the top level of its settings.
//!
//! The JSON form has the same shape (`{"frame": {"photons_w": 2048, "photons_h": 2048},
//! "screen": {"filter": "bilateral"}}`) and is read over the technique's defaults
//! ([`from_json`]): a field left out keeps the technique's default, an unknown one is an
//! error that names it. The flat objects of earlier versions (`{"photons_w": 2048,
//! "filter": "bilateral"}`) still load: a top-level field that names exactly one field of
//! a block is read as that field; one that names fields of two blocks (AdaptiveCaustics'
//! `knn_photons`: `atlas.knn_photons` and `screen.knn_photons`) is an error naming both.

use crate::frame::error::Error;
use crate::frame::output::{Output, Outputs};
use crate::kernels::MAX_SPECULAR_DEPTH;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

/// The knobs every technique shares. Each technique's `Default` sets them to its own
/// defaults (its seed, and PhotonGi's temporal blend and A-Trous iterations), so start
/// from a technique's settings rather than from [`FrameSettings::default`] when its
/// defaults matter: `SspmSettings::default().with_photons(2048, 2048)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrameSettings {
    /// Photon grid width per light (photons): each light emits `photons_w x photons_h`
    /// photons (AdaptiveCaustics: the finest level of its pyramid, the dense-equivalent
    /// grid; PhotonGi: split among the lights by power).
    pub photons_w: u32,
    /// Photon grid height per light (photons).
    pub photons_h: u32,
    /// Frame seed of the counter-based random numbers.
    pub seed: u32,
    /// Progressive accumulation: while the camera, lights, scene and settings stay, every
    /// frame adds its photons (traced with a new seed) to those of the frames before, and
    /// the estimate reads the sum as one frame of all their photons (N frames of M
    /// photons: the estimate of one frame of N x M). Any change starts again from the
    /// next frame's photons.
    pub accumulate: bool,
    /// Blends each frame's filtered estimate with the reprojected history of the earlier
    /// frames (Smal 2019, section 24.4.1's temporal accumulation: alpha 0.95 x depth and
    /// normal weights). Off: a frame is a function of its seed alone. The history is
    /// forgotten when the lights, materials, settings or image size change.
    pub temporal: bool,
    /// Iterations of the edge-avoiding A-Trous filter with variance clipping of its detail
    /// coefficients (Smal 2019, section 24.4.2) on the filtered (and blended) estimate: 0
    /// runs none, the chapter runs 4. At most 8.
    pub atrous_iterations: u32,
    /// Standard deviations of the A-Trous kernel's values that a detail coefficient may
    /// keep (Eq. 18's bounds; the chapter gives no value: 1). 0 keeps none, a large value
    /// keeps all.
    pub atrous_clip_sigmas: f32,
    /// The images the caller wants ([`Outputs`]; every one of the technique's by
    /// default); passes and buffers no requested image needs are left out.
    pub outputs: Outputs,
    /// Leave out passes, kernel features, buffers and lights the scene and the outputs do
    /// not need (default). Off: everything runs, the baseline pruning is checked against.
    pub prune: bool,
    /// Longest specular chain the camera follows from a mirror or glass pixel (direct
    /// light, and the caustic atlas's lookup).
    pub max_specular_depth: u32,
    /// Most triangles the tessellated scene may have; checked before anything is
    /// allocated (default [`crate::scene::limits::DEFAULT_MAX_TRIANGLES`], 2^24).
    pub max_triangles: u64,
    /// How photons through dispersive glass take a colour ([`Dispersion`]; JSON
    /// `"spectral"`, the default, or `"three_bands"`).
    pub dispersion: Dispersion,
}

/// How a photon takes a colour at its first dispersive surface (`frame.dispersion`; the
/// method is in [`crate::math::spectrum`]'s module doc).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Dispersion {
    /// One wavelength per photon, stratified over 380-780 nm across the photon grid;
    /// its power becomes linear sRGB through the CIE 1931 colour-matching functions.
    #[default]
    Spectral,
    /// Vanderstichelen 2021's three-way split: each photon keeps one colour channel (x3)
    /// and refracts with that channel's wavelength (650, 550, 450 nm); for comparison
    /// with the publications.
    ThreeBands,
}

impl Dispersion {
    /// How much brighter than its emitted flux one channel of a photon can get at a
    /// dispersive surface (1 when the scene has none, `has_dispersion` false): 3 for the
    /// three-way split, [`MAX_CHANNEL_WEIGHT`](crate::math::spectrum::MAX_CHANNEL_WEIGHT)
    /// for spectral photons. The fixed-point quanta allow for it.
    pub fn flux_gain(self, has_dispersion: bool) -> f32 {
        match (has_dispersion, self) {
            (false, _) => 1.0,
            (true, Dispersion::ThreeBands) => 3.0,
            (true, Dispersion::Spectral) => crate::math::spectrum::MAX_CHANNEL_WEIGHT,
        }
    }

    /// The kernels' `dispersion_mode` value
    /// ([`dispersion_mode`](crate::math::spectrum::dispersion_mode)).
    pub fn kernel_value(self) -> u32 {
        match self {
            Dispersion::Spectral => crate::math::spectrum::dispersion_mode::SPECTRAL,
            Dispersion::ThreeBands => crate::math::spectrum::dispersion_mode::THREE_BANDS,
        }
    }
}

impl Default for FrameSettings {
    fn default() -> Self {
        FrameSettings {
            photons_w: 1024,
            photons_h: 1024,
            seed: 0,
            accumulate: false,
            temporal: false,
            atrous_iterations: 0,
            atrous_clip_sigmas: 1.0,
            outputs: Outputs::ALL,
            prune: true,
            max_specular_depth: 6,
            max_triangles: crate::scene::limits::DEFAULT_MAX_TRIANGLES,
            dispersion: Dispersion::Spectral,
        }
    }
}

impl FrameSettings {
    /// Checks that `outputs` asks for at least one of `own` (the technique's outputs);
    /// `technique` names it in the error.
    pub fn check_outputs(&self, technique: &str, own: &[Output]) -> Result<(), Error> {
        if self.outputs.any_of(own) {
            Ok(())
        } else if self.outputs == Outputs::NONE {
            Err(Error::InvalidParameter(format!(
                "frame.outputs is empty; request at least one of {technique}'s outputs ({}) \
                 or \"all\"",
                crate::frame::output::stems(own)
            )))
        } else {
            let asked: Vec<&str> = self.outputs.list().iter().map(|o| o.stem()).collect();
            Err(Error::InvalidParameter(format!(
                "frame.outputs: {} {} not among {technique}'s outputs; request at least one \
                 of them ({})",
                asked.join(", "),
                if asked.len() == 1 { "is" } else { "are" },
                crate::frame::output::stems(own)
            )))
        }
    }

    /// The shared defaults with frame seed `seed`.
    pub fn seeded(seed: u32) -> FrameSettings {
        FrameSettings {
            seed,
            ..FrameSettings::default()
        }
    }

    /// Photons per light (`photons_w x photons_h`).
    pub fn photons(&self) -> u64 {
        self.photons_w as u64 * self.photons_h as u64
    }

    /// Rejects values no technique can use (each technique checks its own bounds on the
    /// photon grid).
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |what: String| Err(Error::InvalidParameter(format!("frame.{what}")));
        if self.photons_w == 0 || self.photons_h == 0 || self.photons() > u32::MAX as u64 {
            return bad(
                "photons_w x photons_h must be at least 1x1 and at most 2^32 - 1 photons per \
                 light"
                    .into(),
            );
        }
        if self.atrous_iterations > 8 {
            return bad("atrous_iterations must be <= 8 (taps 128 pixels apart)".into());
        }
        if !(self.atrous_clip_sigmas >= 0.0 && self.atrous_clip_sigmas.is_finite()) {
            return bad("atrous_clip_sigmas must be a finite number >= 0".into());
        }
        if self.max_specular_depth > MAX_SPECULAR_DEPTH {
            return bad(format!(
                "max_specular_depth must be <= {MAX_SPECULAR_DEPTH}"
            ));
        }
        if self.max_triangles == 0 {
            return bad("max_triangles must be >= 1".into());
        }
        Ok(())
    }
}

/// How the caustic techniques follow their photons (`trace` in their settings).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TraceSettings {
    /// Maximum ray segments per photon path.
    pub max_bounces: u32,
    /// A photon whose largest channel falls below this fraction of its emitted flux is
    /// dropped as negligible (Kim 2019, condition 1).
    pub min_relative_power: f32,
    /// Memory limit: photons traced per batch (default
    /// [`crate::frame::allocation::DEFAULT_PHOTONS_PER_BATCH`], at most what the device's
    /// largest buffer holds). AdaptiveCaustics sizes its batches by
    /// `traversal.max_traversal_bytes` instead and does not read it.
    pub max_photons_per_batch: u32,
}

impl Default for TraceSettings {
    fn default() -> Self {
        TraceSettings {
            max_bounces: 12,
            min_relative_power: 1e-4,
            max_photons_per_batch: crate::frame::allocation::DEFAULT_PHOTONS_PER_BATCH,
        }
    }
}

impl TraceSettings {
    /// Rejects values that cannot give a meaningful frame.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |what: &str| Err(Error::InvalidParameter(format!("trace.{what}")));
        if self.max_bounces == 0 || self.max_bounces > 1024 {
            return bad("max_bounces must be in 1..=1024");
        }
        if !(self.min_relative_power >= 0.0 && self.min_relative_power < 1.0) {
            return bad("min_relative_power must be in [0, 1)");
        }
        if self.max_photons_per_batch == 0 {
            return bad("max_photons_per_batch must be >= 1");
        }
        Ok(())
    }
}

/// What every technique's settings offer a host that drives any of them: the shared
/// block, and shorthands that set it.
pub trait TechniqueSettings: Sized {
    /// The shared block.
    fn frame(&self) -> &FrameSettings;
    /// The shared block, to change.
    fn frame_mut(&mut self) -> &mut FrameSettings;

    /// These settings with a photon grid of `w x h` per light.
    fn with_photons(mut self, w: u32, h: u32) -> Self {
        let f = self.frame_mut();
        (f.photons_w, f.photons_h) = (w, h);
        self
    }

    /// These settings with frame seed `seed`.
    fn with_seed(mut self, seed: u32) -> Self {
        self.frame_mut().seed = seed;
        self
    }

    /// These settings asking for `outputs`.
    fn with_outputs(mut self, outputs: Outputs) -> Self {
        self.frame_mut().outputs = outputs;
        self
    }

    /// These settings with progressive accumulation on or off.
    fn with_accumulate(mut self, accumulate: bool) -> Self {
        self.frame_mut().accumulate = accumulate;
        self
    }
}

/// Reads settings `T` from a JSON object laid over `defaults` (the technique's): every
/// field given replaces the default's at the same path, blocks merge field by field, a
/// field left out keeps the default; a block given as anything but an object is an
/// error. A top-level field that is not one of `T`'s but names
/// exactly one field inside a block (the flat form of earlier versions) is read as that
/// field; an unknown field, or one that names fields of several blocks, is an error
/// naming its path and the candidates. `technique` names the technique in errors.
pub fn from_json<T: Serialize + DeserializeOwned>(
    technique: &str,
    defaults: &T,
    given: &serde_json::Value,
) -> Result<T, Error> {
    let bad = |why: String| Error::InvalidParameter(format!("{technique} settings: {why}"));
    let mut base = serde_json::to_value(defaults).map_err(|e| bad(e.to_string()))?;
    let given = nest_flat_fields(&base, given).map_err(bad)?;
    let whole = base.clone();
    merge(&mut base, &given, "", &whole).map_err(bad)?;
    serde_json::from_value(base).map_err(|e| bad(e.to_string()))
}

/// `given` with each top-level field that `base` lacks at its top level but holds once
/// inside a block moved into that block (`{"photons_w": 64}` -> `{"frame":
/// {"photons_w": 64}}`).
fn nest_flat_fields(
    base: &serde_json::Value,
    given: &serde_json::Value,
) -> Result<serde_json::Value, String> {
    use serde_json::Value;
    let (Value::Object(b), Value::Object(g)) = (base, given) else {
        return Err(format!("expected a JSON object, found {given}"));
    };
    let mut out = serde_json::Map::new();
    let mut moved = Vec::new();
    for (k, v) in g {
        if b.contains_key(k) {
            out.insert(k.clone(), v.clone());
            continue;
        }
        // the earlier flat form held only fields one block deep
        let mut found = Vec::new();
        find_field(base, k, "", &mut found);
        found.retain(|p| p.matches('.').count() == 1);
        match found.as_slice() {
            [one] => moved.push((one.clone(), v.clone())),
            [] => {
                out.insert(k.clone(), v.clone()); // `merge` names it as unknown
            }
            many => {
                return Err(format!(
                    "field `{k}` is ambiguous: it is one of {}",
                    many.iter()
                        .map(|p| format!("`{p}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            }
        }
    }
    for (path, v) in moved {
        let (block, field) = path.split_once('.').expect("a block's field");
        let slot = out
            .entry(block.to_string())
            .or_insert_with(|| Value::Object(Default::default()));
        let Value::Object(m) = slot else {
            return Err(format!("`{block}` must be an object"));
        };
        if m.contains_key(field) {
            return Err(format!(
                "`{field}` is given twice (at the top and as `{path}`)"
            ));
        }
        m.insert(field.to_string(), v);
    }
    Ok(Value::Object(out))
}

/// Lays `given` over `base` at `path` (see [`from_json`]); `whole` is the whole default
/// tree, searched for a moved field.
fn merge(
    base: &mut serde_json::Value,
    given: &serde_json::Value,
    path: &str,
    whole: &serde_json::Value,
) -> Result<(), String> {
    use serde_json::Value;
    match (base, given) {
        (Value::Object(b), Value::Object(g)) => {
            for (k, v) in g {
                let here = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                match b.get_mut(k) {
                    // an object over a block merges; anything else replaces
                    Some(slot) if slot.is_object() && v.is_object() => {
                        merge(slot, v, &here, whole)?
                    }
                    // (serde would read a list as the block's fields in order, or name
                    // its Rust type)
                    Some(slot) if slot.is_object() => {
                        return Err(format!(
                            "`{here}` is a block of settings and must be a JSON object of \
                             its fields, got {v}"
                        ))
                    }
                    Some(slot) => *slot = v.clone(),
                    None => {
                        let mut found = Vec::new();
                        find_field(whole, k, "", &mut found);
                        let known: Vec<String> = b.keys().map(|n| format!("`{n}`")).collect();
                        return Err(match found.first() {
                            Some(moved) => {
                                format!("unknown field `{here}`: it is now `{moved}`")
                            }
                            None => format!(
                                "unknown field `{here}`, expected one of {}",
                                known.join(", ")
                            ),
                        });
                    }
                }
            }
            Ok(())
        }
        (b, g) => {
            *b = g.clone();
            Ok(())
        }
    }
}

/// The paths of every field named `name` in `tree`.
fn find_field(tree: &serde_json::Value, name: &str, path: &str, found: &mut Vec<String>) {
    if let serde_json::Value::Object(m) = tree {
        for (k, v) in m {
            let here = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            if k == name {
                found.push(here.clone());
            }
            find_field(v, name, &here, found);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
    #[serde(default, deny_unknown_fields)]
    struct Example {
        frame: FrameSettings,
        trace: TraceSettings,
        own: u32,
    }

    impl Default for Example {
        fn default() -> Self {
            Example {
                frame: FrameSettings {
                    temporal: true,
                    ..FrameSettings::seeded(7)
                },
                trace: TraceSettings::default(),
                own: 3,
            }
        }
    }

    #[test]
    fn dispersion_is_spectral_by_default_and_reads_from_json() {
        assert_eq!(FrameSettings::default().dispersion, Dispersion::Spectral);
        let e: Example = from_json(
            "example",
            &Example::default(),
            &serde_json::json!({ "frame": { "dispersion": "three_bands" } }),
        )
        .unwrap();
        assert_eq!(e.frame.dispersion, Dispersion::ThreeBands);
        assert_eq!(
            e.frame.dispersion.kernel_value(),
            crate::math::spectrum::dispersion_mode::THREE_BANDS
        );
        let bad = from_json::<Example>(
            "example",
            &Example::default(),
            &serde_json::json!({ "frame": { "dispersion": "hero" } }),
        )
        .unwrap_err()
        .to_string();
        assert!(bad.contains("hero") && bad.contains("three_bands"), "{bad}");
        // the quanta's gain
        assert_eq!(Dispersion::Spectral.flux_gain(false), 1.0);
        assert_eq!(Dispersion::ThreeBands.flux_gain(true), 3.0);
        assert_eq!(Dispersion::Spectral.flux_gain(true), 7.0);
    }

    #[test]
    fn a_value_where_a_block_goes_is_named_by_its_path() {
        for (given, path) in [
            (serde_json::json!({ "trace": 7 }), "`trace`"),
            (serde_json::json!({ "frame": [1, 2] }), "`frame`"),
            (serde_json::json!({ "frame": null, "own": 4 }), "`frame`"),
        ] {
            let e = from_json::<Example>("example", &Example::default(), &given)
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(path) && e.contains("must be a JSON object") && !e.contains("struct"),
                "{given}: {e}"
            );
        }
    }

    #[test]
    fn given_fields_lie_over_the_techniques_defaults() {
        let e: Example = from_json(
            "example",
            &Example::default(),
            &serde_json::json!({ "frame": { "photons_w": 64 }, "own": 5 }),
        )
        .unwrap();
        assert_eq!((e.frame.photons_w, e.frame.photons_h), (64, 1024));
        // a block given in part keeps the technique's defaults, not the block's own
        assert_eq!((e.frame.seed, e.frame.temporal, e.own), (7, true, 5));
    }

    #[test]
    fn the_flat_form_still_loads_and_unknown_fields_are_named() {
        let e: Example = from_json(
            "example",
            &Example::default(),
            &serde_json::json!({ "photons_w": 64, "max_bounces": 3, "own": 1 }),
        )
        .unwrap();
        assert_eq!((e.frame.photons_w, e.trace.max_bounces, e.own), (64, 3, 1));
        let e = from_json(
            "example",
            &Example::default(),
            &serde_json::json!({ "photons_w": 64, "frame": { "photons_w": 32 } }),
        );
        assert!(e.unwrap_err().to_string().contains("given twice"));
        let e = from_json(
            "example",
            &Example::default(),
            &serde_json::json!({ "trace": { "bounces": 3 } }),
        );
        let msg = e.unwrap_err().to_string();
        assert!(
            msg.contains("trace.bounces") && msg.contains("max_bounces"),
            "{msg}"
        );
        let e = from_json(
            "example",
            &Example::default(),
            &serde_json::json!({ "photon_w": 1 }),
        );
        assert!(e.unwrap_err().to_string().contains("`photon_w`"));
        assert!(from_json("example", &Example::default(), &serde_json::json!([1])).is_err());
    }

    #[test]
    fn a_flat_field_of_two_blocks_names_both() {
        #[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
        #[serde(default, deny_unknown_fields)]
        struct Two {
            a: TraceSettings,
            b: TraceSettings,
        }
        let e = from_json(
            "two",
            &Two::default(),
            &serde_json::json!({ "max_bounces": 3 }),
        );
        let msg = e.unwrap_err().to_string();
        assert!(
            msg.contains("`a.max_bounces`") && msg.contains("`b.max_bounces`"),
            "{msg}"
        );
    }
}

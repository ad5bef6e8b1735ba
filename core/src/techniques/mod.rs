//! The techniques, one folder each, and the one place that maps technique names to
//! types ([`TECHNIQUES`]). The library, the CLI, `report`, references, benches and
//! conformance create techniques by name through [`create`] and drive them through
//! [`crate::frame::technique::Technique`].

pub mod adaptive_caustics;
pub mod caustic_map;
pub mod photon_gi;
pub mod sspm;

use crate::backend::Backend;
use crate::frame::error::Error;
use crate::frame::technique::Technique;
use crate::scene::Scene;

/// A technique's constructor: on `backend`, for `scene`, with `settings` (a JSON object
/// of the technique's settings fields).
pub type CreateFn =
    fn(&mut dyn Backend, &Scene, &serde_json::Value) -> Result<Box<dyn Technique>, Error>;

/// A registered technique.
#[derive(Clone, Copy)]
pub struct TechniqueEntry {
    /// Name on the command line and in reports.
    pub name: &'static str,
    /// One line: what it is and where it comes from.
    pub title: &'static str,
    /// Creates it on `backend` for `scene` with `settings`, a JSON object of the
    /// technique's settings (missing fields take their defaults; every technique has the
    /// shared `frame` block: `frame.photons_w`, `frame.seed`, ...).
    pub create: CreateFn,
    /// The default settings (serialised).
    pub default_settings: fn() -> serde_json::Value,
    /// The setting that picks the caustic filter under the given settings (a JSON object
    /// of the technique's settings, missing fields at their defaults): its path
    /// (`screen.filter`) and its values (the first is the default), so that the command
    /// line and `report` can set and compare filters; `None` where the technique has one
    /// filter.
    pub filter_setting: fn(&serde_json::Map<String, serde_json::Value>) -> Option<FilterSetting>,
}

/// A technique's filter setting: its path in the settings and its values, the default
/// first.
pub type FilterSetting = (&'static str, &'static [&'static str]);

/// The screen photon map's filters (`screen.filter`).
const SCREEN_FILTER: FilterSetting = ("screen.filter", &["density", "bilateral"]);
/// The caustic atlas's gathers (`atlas.gather`).
const ATLAS_GATHER: FilterSetting = ("atlas.gather", &["density", "box"]);

/// Every technique, by name: the registry.
pub const TECHNIQUES: &[TechniqueEntry] = &[
    TechniqueEntry {
        name: "sspm",
        title: "screen-space photon mapping (Kim 2019, Ray Tracing Gems ch. 30)",
        create: sspm::create,
        default_settings: || {
            serde_json::to_value(sspm::SspmSettings::default()).unwrap_or(serde_json::Value::Null)
        },
        filter_setting: |_| Some(SCREEN_FILTER),
    },
    TechniqueEntry {
        name: "caustic-map",
        title: "texture-space caustic maps from light view planes (Vanderstichelen 2021)",
        create: caustic_map::create,
        default_settings: || {
            serde_json::to_value(caustic_map::CausticMapSettings::default())
                .unwrap_or(serde_json::Value::Null)
        },
        filter_setting: |_| Some(ATLAS_GATHER),
    },
    TechniqueEntry {
        name: "adaptive-caustics",
        title: "coarse-to-fine photon emission into caustic maps (Wyman 2009)",
        create: adaptive_caustics::create,
        default_settings: || {
            serde_json::to_value(adaptive_caustics::AdaptiveCausticsSettings::default())
                .unwrap_or(serde_json::Value::Null)
        },
        // the receiver `deposit` picks: the atlas (default) or the screen photon map
        filter_setting: |s| match s.get("deposit").and_then(|d| d.as_str()) {
            Some("screen") => Some(SCREEN_FILTER),
            _ => Some(ATLAS_GATHER),
        },
    },
    TechniqueEntry {
        name: "photon-gi",
        title: "multi-bounce indirect light by photon splatting (Smal 2019, Ray Tracing Gems \
                ch. 24)",
        create: photon_gi::create,
        default_settings: || {
            serde_json::to_value(photon_gi::PhotonGiSettings::default())
                .unwrap_or(serde_json::Value::Null)
        },
        filter_setting: |_| None,
    },
];

/// Names of every registered technique.
pub fn technique_names() -> Vec<&'static str> {
    TECHNIQUES.iter().map(|t| t.name).collect()
}

/// Creates technique `name` (see [`TechniqueEntry::create`]).
pub fn create(
    name: &str,
    backend: &mut dyn Backend,
    scene: &Scene,
    settings: &serde_json::Value,
) -> Result<Box<dyn Technique>, Error> {
    let entry = TECHNIQUES.iter().find(|t| t.name == name).ok_or_else(|| {
        Error::InvalidParameter(format!(
            "unknown technique '{name}'; available: {}",
            technique_names().join(", ")
        ))
    })?;
    (entry.create)(backend, scene, settings)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_technique_takes_the_common_settings() {
        let shared = serde_json::to_value(crate::frame::settings::FrameSettings::default())
            .expect("serialisable");
        for t in TECHNIQUES {
            let d = (t.default_settings)();
            // the shared block, with every field, in every technique
            for key in shared.as_object().expect("an object").keys() {
                assert!(
                    d["frame"].get(key).is_some(),
                    "{} lacks frame.{key}",
                    t.name
                );
            }
        }
    }
}

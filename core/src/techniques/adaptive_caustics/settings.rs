//! Every parameter of AdaptiveCaustics, with its defaults and validation.

use super::traversal::TraversalSettings;
pub use super::traversal::{
    AdaptiveMetric, ClusterRelevance, TraversalSizes, LIST_BYTES_PER_ENTRY, MAX_PASSES_PER_LEVEL,
    SLOT_BYTES_PER_CLUSTER,
};
use crate::frame::error::Error;
use crate::frame::receivers::atlas::settings::{
    AtlasConfig, AtlasSettings, FresnelSplit, PlaneSettings,
};
use crate::frame::receivers::screen::ScreenSettings;
use crate::frame::settings::{FrameSettings, TechniqueSettings, TraceSettings};
use serde::{Deserialize, Serialize};

/// The map the traversal's photons are deposited into (so that a comparison
/// can isolate what adaptive emission buys in each).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AdaptiveDeposit {
    /// CausticMap's texture-space caustic atlas, its gather and final pass (the default:
    /// Wyman 2009 splats into a caustic map, and the atlas is the map kind here).
    #[default]
    Atlas,
    /// Sspm's screen-space photon map, its resolve, filter and composite (the `screen`
    /// settings): the photons of Kim 2019 replaced by the traversal's.
    Screen,
}

/// AdaptiveCaustics' settings: the shared `frame` and `trace` blocks, with
/// `frame.photons_w` = `frame.photons_h` the side of the dense-equivalent grid (the
/// finest level, a power-of-two multiple of `start_grid`); CausticMap's light view
/// planes (`planes`; `fresnel_split` must be `stochastic`); the receiver its `deposit`
/// names, with its block (`atlas`: CausticMap's atlas, gather and final pass; `screen`:
/// Sspm's screen photon map; the block of the receiver not named is not read, so that a
/// comparison can switch `deposit` alone); and the traversal's own `traversal` block.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AdaptiveCausticsSettings {
    /// What every technique shares: photon grid (the finest level), seed, accumulation,
    /// filter chain, outputs, pruning, the camera's specular chains.
    pub frame: FrameSettings,
    /// How photons are followed.
    pub trace: TraceSettings,
    /// The light view planes and the photons' optics.
    pub planes: PlaneSettings,
    /// The receiver the traversal's photons land in.
    pub deposit: AdaptiveDeposit,
    /// The caustic atlas (with `deposit: atlas`).
    pub atlas: AtlasSettings,
    /// The screen photon map (with `deposit: screen`).
    pub screen: ScreenSettings,
    /// The traversal: its stop metric, start grid and memory.
    pub traversal: TraversalSettings,
}

impl Default for AdaptiveCausticsSettings {
    fn default() -> Self {
        AdaptiveCausticsSettings {
            // CausticMap's seed: the same photons where the traversal reaches the finest
            // level
            frame: FrameSettings::seeded(0x434d_4150),
            trace: TraceSettings::default(),
            planes: PlaneSettings::default(),
            deposit: AdaptiveDeposit::Atlas,
            atlas: AtlasSettings::default(),
            screen: ScreenSettings::default(),
            traversal: TraversalSettings::default(),
        }
    }
}

impl TechniqueSettings for AdaptiveCausticsSettings {
    fn frame(&self) -> &FrameSettings {
        &self.frame
    }

    fn frame_mut(&mut self) -> &mut FrameSettings {
        &mut self.frame
    }
}

impl AdaptiveCausticsSettings {
    /// What the atlas receiver is made with.
    pub fn atlas_config(&self) -> AtlasConfig {
        AtlasConfig {
            frame: self.frame.clone(),
            planes: self.planes,
            atlas: self.atlas,
        }
    }

    /// The traversal's settings.
    pub fn traversal(&self) -> TraversalSettings {
        self.traversal
    }

    /// The finest level (the start grid is level 0): `photons_w = start_grid * 2^finest`.
    pub fn finest_level(&self) -> u32 {
        (self.frame.photons_w / self.traversal.start_grid.max(1))
            .max(1)
            .ilog2()
    }

    /// The first level at which the error metric is checked.
    pub fn error_from_level(&self) -> u32 {
        self.traversal().error_from_level()
    }

    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |what: String| Err(Error::InvalidParameter(what));
        self.frame.validate()?;
        self.trace.validate()?;
        self.planes.validate()?;
        let screen = self.deposit == AdaptiveDeposit::Screen;
        if screen {
            self.frame.check_outputs(
                "adaptive-caustics (deposit screen)",
                &crate::frame::receivers::screen::ScreenReceiver::OUTPUTS,
            )?;
            self.screen.validate()?;
        } else {
            self.frame.check_outputs(
                "adaptive-caustics",
                &crate::frame::receivers::atlas::OUTPUTS,
            )?;
            self.atlas.validate()?;
        }
        if self.planes.fresnel_split != FresnelSplit::Stochastic {
            return bad(
                "adaptive-caustics traces one stored photon per emitted photon: \
                 planes.fresnel_split must be \"stochastic\""
                    .into(),
            );
        }
        let t = &self.traversal;
        if t.start_grid < 2 || !t.start_grid.is_power_of_two() || t.start_grid > 4096 {
            return bad("traversal.start_grid must be a power of two in 2..=4096".into());
        }
        let (w, h) = (self.frame.photons_w, self.frame.photons_h);
        let k = self.finest_level();
        if w != h || w < t.start_grid || (t.start_grid as u64) << k != w as u64 {
            return bad(format!(
                "frame.photons_w and frame.photons_h ({w}x{h}) must be equal and \
                 traversal.start_grid ({}) times a power of two: the dense-equivalent grid is \
                 the finest level of the pyramid",
                t.start_grid
            ));
        }
        if w > 65536 {
            return bad(
                "frame.photons_w must be <= 65536 (the cluster ids of a level fit a u32)".into(),
            );
        }
        let max = crate::math::photon_clusters::MAX_ERROR_TEXELS;
        if t.error_texels == 0 || t.error_texels > max {
            return bad(format!("traversal.error_texels must be in 1..={max}"));
        }
        if t.error_texels > 1 && screen {
            return bad(
                "traversal.error_texels above 1 splats converged photons over atlas texels: it \
                 needs deposit \"atlas\""
                    .into(),
            );
        }
        if t.max_traversal_bytes < self.min_traversal_bytes() {
            return bad(format!(
                "traversal.max_traversal_bytes must hold the start grid's list and a batch of \
                 one cluster: at least {} bytes",
                self.min_traversal_bytes()
            ));
        }
        Ok(())
    }

    /// Clusters of the start grid.
    pub fn start_clusters(&self) -> u64 {
        self.traversal().start_clusters()
    }

    /// Fixed bytes plus one cluster's.
    fn min_traversal_bytes(&self) -> u64 {
        let screen = self.deposit == AdaptiveDeposit::Screen;
        self.traversal().min_bytes(self.finest_level(), screen)
    }

    /// The split of `max_traversal_bytes` into passes and lists
    /// ([`TraversalSettings::sizes`]) for this photon grid's pyramid, on a device whose
    /// largest buffer holds `max_buffer_bytes`.
    pub fn traversal_sizes(&self, max_buffer_bytes: u64) -> TraversalSizes {
        let screen = self.deposit == AdaptiveDeposit::Screen;
        self.traversal()
            .sizes(self.finest_level(), screen, max_buffer_bytes)
    }
}

/// The fields the screen block held in earlier versions and `frame` holds now.
const SCREEN_FIELDS_NOW_SHARED: [&str; 7] = [
    "outputs",
    "prune",
    "temporal",
    "atrous_iterations",
    "atrous_clip_sigmas",
    "accumulate",
    "max_specular_depth",
];

/// The settings JSON of earlier versions in today's places, where the generic reading of
/// the flat form cannot tell: a top-level `knn_photons` was the atlas's (CausticMap's
/// fields sat at the top, the screen's in `screen`), and the screen block's shared fields
/// (outputs, filters, accumulation) now sit in `frame`: with `deposit: screen` they move
/// there (unless `frame` or the top level gives them), otherwise they were not read and
/// are dropped. The traversal's boolean `probe_coarse_levels` is now `probe_levels`
/// (`true`: `first_segment`, `false`: `traced`).
pub(super) fn earlier_form(json: &serde_json::Value) -> serde_json::Value {
    let Some(given) = json.as_object() else {
        return json.clone();
    };
    let mut out = given.clone();
    if let Some(t) = out.get_mut("traversal").and_then(|t| t.as_object_mut()) {
        if let Some(flag) = t.get("probe_coarse_levels").and_then(|f| f.as_bool()) {
            t.remove("probe_coarse_levels");
            let name = if flag { "first_segment" } else { "traced" };
            t.entry("probe_levels").or_insert(name.into());
        }
    }
    if let Some(k) = out.remove("knn_photons") {
        let atlas = out
            .entry("atlas")
            .or_insert_with(|| serde_json::Value::Object(Default::default()));
        if let Some(a) = atlas.as_object_mut() {
            a.entry("knn_photons").or_insert(k);
        }
    }
    let screen_deposit = out.get("deposit").and_then(|d| d.as_str()) == Some("screen");
    let mut moved = serde_json::Map::new();
    if let Some(screen) = out.get_mut("screen").and_then(|s| s.as_object_mut()) {
        for field in SCREEN_FIELDS_NOW_SHARED {
            if let Some(v) = screen.remove(field) {
                moved.insert(field.to_string(), v);
            }
        }
    }
    if screen_deposit && !moved.is_empty() {
        let given_elsewhere = |f: &str, out: &serde_json::Map<String, serde_json::Value>| {
            out.contains_key(f) || out.get("frame").and_then(|b| b.get(f)).is_some()
        };
        let keep: Vec<(String, serde_json::Value)> = moved
            .into_iter()
            .filter(|(f, _)| !given_elsewhere(f, &out))
            .collect();
        let frame = out
            .entry("frame")
            .or_insert_with(|| serde_json::Value::Object(Default::default()));
        if let Some(b) = frame.as_object_mut() {
            b.extend(keep);
        }
    }
    serde_json::Value::Object(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::techniques::adaptive_caustics::traversal::ProbeLevels;

    #[test]
    fn json_lays_blocks_over_the_defaults_and_names_moved_fields() {
        let parse = |v: serde_json::Value| {
            crate::frame::settings::from_json(
                "adaptive-caustics",
                &AdaptiveCausticsSettings::default(),
                &earlier_form(&v),
            )
        };
        let s: AdaptiveCausticsSettings = parse(serde_json::json!({
            "frame": { "photons_w": 512, "photons_h": 512 },
            "traversal": { "metric": "level" },
            "atlas": { "atlas_size": 256 }
        }))
        .unwrap();
        assert_eq!(s.frame.photons_w, 512);
        assert_eq!(s.frame.seed, AdaptiveCausticsSettings::default().frame.seed);
        assert_eq!(s.atlas.atlas_size, 256);
        assert_eq!(s.traversal.metric, AdaptiveMetric::Level);
        assert_eq!(s.finest_level(), 3);
        s.validate().unwrap();
        // the form of earlier versions: CausticMap's fields at the top (`knn_photons` the
        // atlas's), the screen's shared fields in `screen`
        let flat = parse(serde_json::json!({
            "photons_w": 512, "metric": "level", "knn_photons": 8
        }))
        .unwrap();
        assert_eq!(
            (flat.frame.photons_w, flat.traversal.metric),
            (512, AdaptiveMetric::Level)
        );
        assert_eq!((flat.atlas.knn_photons, flat.screen.knn_photons), (8, 32));
        let screen = parse(serde_json::json!({
            "deposit": "screen", "screen": { "temporal": true, "filter": "bilateral" }
        }))
        .unwrap();
        assert!(screen.frame.temporal);
        assert_eq!(
            screen.screen.filter,
            crate::frame::receivers::screen::GatherFilter::Bilateral
        );
        let e = parse(serde_json::json!({ "photon_w": 512 }));
        assert!(matches!(&e, Err(Error::InvalidParameter(w)) if w.contains("photon_w")));
        // the probe levels by name, or the older boolean
        let probes = |v: serde_json::Value| {
            parse(serde_json::json!({ "traversal": v })).map(|s| s.traversal.probe_levels)
        };
        use super::super::ProbeLevels;
        let named = probes(serde_json::json!({ "probe_levels": "traced" }));
        assert_eq!(named.unwrap(), ProbeLevels::Traced);
        let older = probes(serde_json::json!({ "probe_coarse_levels": true }));
        assert_eq!(older.unwrap(), ProbeLevels::FirstSegment);
        let older = probes(serde_json::json!({ "probe_coarse_levels": false }));
        assert_eq!(older.unwrap(), ProbeLevels::Traced);
        assert!(probes(serde_json::json!({ "probe_levels": "all" })).is_err());
    }

    #[test]
    fn the_grid_must_be_a_pyramid() {
        let mut s = AdaptiveCausticsSettings::default();
        s.validate().unwrap();
        assert_eq!(s.finest_level(), 4);
        assert_eq!(s.error_from_level(), 3);
        (s.frame.photons_w, s.frame.photons_h) = (1000, 1000);
        assert!(s.validate().is_err());
        (s.frame.photons_w, s.frame.photons_h) = (1024, 512);
        assert!(s.validate().is_err());
        s.frame.photons_h = 1024;
        s.planes.fresnel_split = FresnelSplit::Deterministic;
        assert!(s.validate().is_err());
    }

    /// [`TraversalSettings::sizes`] of `t` under a limit of 1 TiB, on a device whose
    /// largest buffer holds `max_buffer_bytes`.
    fn huge_sizes(t: &TraversalSettings, max_buffer_bytes: u64) -> TraversalSizes {
        TraversalSettings {
            max_traversal_bytes: 1 << 40,
            ..*t
        }
        .sizes(4, false, max_buffer_bytes)
    }

    #[test]
    fn a_traversal_that_writes_no_slots_takes_each_level_in_one_pass() {
        let t = AdaptiveCausticsSettings::default().traversal();
        // the defaults: the bounds seed down to the finest level, which deposits itself
        assert!(!t.writes_slots(4) && !t.writes_slots(0));
        let z = t.sizes(4, true, u64::MAX);
        assert!(!z.slots && !z.lists_capped);
        assert_eq!(z.pass_clusters as u64, t.dense_clusters(4));
        // slots where a traced level is judged from them
        for judged in [
            TraversalSettings {
                fused_finest: false,
                ..t
            },
            TraversalSettings {
                metric: AdaptiveMetric::Error,
                error_from_grid: t.start_grid << 2,
                ..t
            },
            TraversalSettings {
                probe_levels: ProbeLevels::FirstSegment,
                ..t
            },
        ] {
            assert!(judged.writes_slots(4), "{judged:?}");
            assert!(judged.sizes(4, false, u64::MAX).slots);
        }
        // the error metric from the finest level on: its levels above are probe levels
        let late = TraversalSettings {
            metric: AdaptiveMetric::Error,
            error_from_grid: t.start_grid << 4,
            ..t
        };
        assert!(!late.writes_slots(4) && late.writes_slots(5));
        // lists that do not fit: capped, with slots (every level traced)
        let tight = TraversalSettings {
            max_traversal_bytes: t.full_list_bytes(4) / 2,
            ..t
        };
        let z = tight.sizes(4, false, u64::MAX);
        assert!(z.lists_capped && z.slots);
    }

    #[test]
    fn the_passes_and_lists_follow_the_byte_limit() {
        let t = TraversalSettings {
            fused_finest: false,
            ..AdaptiveCausticsSettings::default().traversal()
        };
        // whole lists beside passes of 5000 clusters (at least 1/64 of the finest level)
        assert!(5000 >= t.dense_clusters(4).div_ceil(MAX_PASSES_PER_LEVEL));
        let whole = TraversalSettings {
            max_traversal_bytes: t.bytes_for_pass(4, false, 5000),
            ..t
        };
        let z = whole.sizes(4, false, u64::MAX);
        assert_eq!(z.pass_clusters, 5000);
        assert!(!z.lists_capped);
        assert_eq!(z.list_capacity[3] as u64, t.dense_clusters(4));
        // the screen target's passes also hold four output photons a cluster
        assert!(whole.sizes(4, true, u64::MAX).pass_clusters < 5000);
        // a limit below whole lists caps them, in multiples of 4, and the passes take at
        // most half (or the fewest clusters that keep a level to 64 passes)
        let tight = TraversalSettings {
            max_traversal_bytes: t.full_list_bytes(4) / 2,
            ..t
        };
        let z = tight.sizes(4, false, u64::MAX);
        assert!(z.lists_capped);
        assert!(z.list_capacity.iter().all(|&n| n % 4 == 0 && n >= 4));
        let min_pass = t.dense_clusters(4).div_ceil(MAX_PASSES_PER_LEVEL);
        assert!(z.pass_clusters as u64 <= (tight.max_traversal_bytes / 2 / 132).max(min_pass));
        // the device's largest buffer bounds a pass's slots and a list
        let mib = 1u64 << 20;
        let z = huge_sizes(&t, 4 * mib);
        assert_eq!(z.pass_clusters as u64, 4 * mib / SLOT_BYTES_PER_CLUSTER);
        assert!(!z.lists_capped);
        let entries = t.dense_clusters(4) / 2 / 4 * 4;
        let z = huge_sizes(&t, entries * LIST_BYTES_PER_ENTRY);
        assert!(z.lists_capped && z.slots);
        assert_eq!(z.list_capacity[3] as u64, entries);
        // and without slots, the list alone
        let fused = TraversalSettings {
            fused_finest: true,
            ..t
        };
        assert!(!huge_sizes(&fused, 4 * mib).slots);
        assert!(huge_sizes(&fused, entries * LIST_BYTES_PER_ENTRY).lists_capped);
        // a huge limit: one pass per level
        let huge = TraversalSettings {
            max_traversal_bytes: 1 << 40,
            ..t
        };
        assert_eq!(
            huge.sizes(4, false, u64::MAX).pass_clusters as u64,
            t.dense_clusters(4)
        );
    }
}

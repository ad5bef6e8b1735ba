//! Every parameter of AdaptiveCaustics, with its defaults and validation.

use crate::frame::emission::adaptive::TraversalSettings;
pub use crate::frame::emission::adaptive::{
    AdaptiveMetric, ClusterRelevance, TraversalSizes, LIST_BYTES_PER_ENTRY, MAX_PASSES_PER_LEVEL,
    SLOT_BYTES_PER_CLUSTER,
};
use crate::frame::error::Error;
use crate::frame::receivers::atlas::settings::{CausticMapSettings, FresnelSplit};
use crate::frame::receivers::screen::ScreenSettings;
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

/// AdaptiveCaustics' settings: CausticMap's (the same atlas, gather and final pass), with
/// `photons_w` = `photons_h` the side of the dense-equivalent grid (the finest level, a
/// power-of-two multiple of `start_grid`), plus the traversal's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct AdaptiveCausticsSettings {
    /// The caustic map, its gather, the optics and the outputs (CausticMap's fields, at
    /// the top level of the JSON object; `fresnel_split` must be `stochastic`).
    #[serde(flatten)]
    pub map: CausticMapSettings,
    /// The stop metric.
    pub metric: AdaptiveMetric,
    /// What keeps a cluster from being discarded: `bounds` (the default) or 004's
    /// `photons`.
    pub relevance: ClusterRelevance,
    /// Texels a side of the start grid (004 section 4.2: 64, enough photons to keep a
    /// GPU busy from the first step; a power of two).
    pub start_grid: u32,
    /// Grid side from which the error metric is checked; coarser levels use the
    /// traversal-level metric (004 section 4.2: from 512^2 on, since coarse photons
    /// rarely converge).
    pub error_from_grid: u32,
    /// The error metric's tolerance (texels): a cluster converges when its four photons
    /// land in a square of at most this many caustic-map texels a side on one receiver,
    /// and its photons are then splatted over a window that size (Wyman 2009, section 3.2.2's
    /// alternative: "photon divergence greater than a single texel but less than a
    /// user-defined tolerance", with its multi-resolution map). 1 (the default) is 004's
    /// metric: one texel, and a one-texel splat. At most 4; above 1 only with the atlas
    /// target.
    pub error_texels: u32,
    /// Device bytes the traversal may hold (004 section 4.3): the photon slots of a batch
    /// (128 bytes per cluster) and one cluster list per level (16 bytes per cluster of a
    /// batch each), plus the start grid's list. The batch size follows from it; the
    /// result is bitwise the same for any value. The screen target also holds a list of
    /// the batch's output photons (another 128 bytes per cluster).
    pub max_traversal_bytes: u64,
    /// Where output photons are deposited: `atlas` (the default) or `screen`.
    pub deposit: AdaptiveDeposit,
    /// The screen receiver's settings for the screen target: depth tolerance, filter,
    /// outputs and the rest of what follows the deposit (the photons are the traversal's,
    /// set at the top level). Unused with the atlas target.
    pub screen: ScreenSettings,
}

impl Default for AdaptiveCausticsSettings {
    fn default() -> Self {
        AdaptiveCausticsSettings {
            map: CausticMapSettings::default(),
            metric: AdaptiveMetric::Error,
            relevance: ClusterRelevance::Bounds,
            start_grid: 64,
            error_from_grid: 512,
            error_texels: 1,
            max_traversal_bytes: 64 << 20,
            deposit: AdaptiveDeposit::Atlas,
            screen: ScreenSettings::default(),
        }
    }
}

impl AdaptiveCausticsSettings {
    /// The settings from a JSON object of their fields (CausticMap's at the top level);
    /// missing fields take their defaults, and an unknown field is an error (serde's
    /// `deny_unknown_fields` does not reach through `flatten`, so the names are checked
    /// here against the defaults' serialisation).
    pub fn from_json(value: &serde_json::Value) -> Result<Self, Error> {
        let bad =
            |why: String| Error::InvalidParameter(format!("adaptive-caustics settings: {why}"));
        let known = serde_json::to_value(AdaptiveCausticsSettings::default())
            .map_err(|e| bad(e.to_string()))?;
        if let (Some(given), Some(known)) = (value.as_object(), known.as_object()) {
            if let Some(k) = given.keys().find(|k| !known.contains_key(*k)) {
                let mut names: Vec<&String> = known.keys().collect();
                names.sort();
                return Err(bad(format!(
                    "unknown field `{k}`, expected one of {}",
                    names
                        .iter()
                        .map(|n| format!("`{n}`"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )));
            }
        }
        serde_json::from_value(value.clone()).map_err(|e| bad(e.to_string()))
    }

    /// The traversal's settings.
    pub fn traversal(&self) -> TraversalSettings {
        TraversalSettings {
            metric: self.metric,
            relevance: self.relevance,
            start_grid: self.start_grid,
            error_from_grid: self.error_from_grid,
            error_texels: self.error_texels,
            max_traversal_bytes: self.max_traversal_bytes,
        }
    }

    /// The finest level (the start grid is level 0): `photons_w = start_grid * 2^finest`.
    pub fn finest_level(&self) -> u32 {
        (self.map.photons_w / self.start_grid.max(1)).max(1).ilog2()
    }

    /// The first level at which the error metric is checked.
    pub fn error_from_level(&self) -> u32 {
        self.traversal().error_from_level()
    }

    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), Error> {
        self.map.validate()?;
        let bad = |what: String| Err(Error::InvalidParameter(what));
        if self.map.fresnel_split != FresnelSplit::Stochastic {
            return bad(
                "adaptive-caustics traces one stored photon per emitted photon: fresnel_split \
                 must be \"stochastic\""
                    .into(),
            );
        }
        if self.start_grid < 2 || !self.start_grid.is_power_of_two() || self.start_grid > 4096 {
            return bad("start_grid must be a power of two in 2..=4096".into());
        }
        let (w, h) = (self.map.photons_w, self.map.photons_h);
        let k = self.finest_level();
        if w != h || w < self.start_grid || (self.start_grid as u64) << k != w as u64 {
            return bad(format!(
                "photons_w and photons_h ({w}x{h}) must be equal and start_grid ({}) times a \
                 power of two: the dense-equivalent grid is the finest level of the pyramid",
                self.start_grid
            ));
        }
        if w > 65536 {
            return bad("photons_w must be <= 65536 (the cluster ids of a level fit a u32)".into());
        }
        if self.deposit == AdaptiveDeposit::Screen {
            self.screen.validate()?;
        }
        let max = crate::math::photon_clusters::MAX_ERROR_TEXELS;
        if self.error_texels == 0 || self.error_texels > max {
            return bad(format!("error_texels must be in 1..={max}"));
        }
        if self.error_texels > 1 && self.deposit == AdaptiveDeposit::Screen {
            return bad(
                "error_texels above 1 splats converged photons over atlas texels: it needs \
                 deposit \"atlas\""
                    .into(),
            );
        }
        if self.max_traversal_bytes < self.min_traversal_bytes() {
            return bad(format!(
                "max_traversal_bytes must hold the start grid's list and a batch of one \
                 cluster: at least {} bytes",
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
    /// ([`TraversalSettings::sizes`]) for this photon grid's pyramid.
    pub fn traversal_sizes(&self) -> TraversalSizes {
        let screen = self.deposit == AdaptiveDeposit::Screen;
        self.traversal().sizes(self.finest_level(), screen)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_takes_caustic_map_fields_at_the_top_and_refuses_unknown_ones() {
        let s = AdaptiveCausticsSettings::from_json(&serde_json::json!({
            "photons_w": 512, "photons_h": 512, "metric": "level", "atlas_size": 256
        }))
        .unwrap();
        assert_eq!(s.map.photons_w, 512);
        assert_eq!(s.map.atlas_size, 256);
        assert_eq!(s.metric, AdaptiveMetric::Level);
        assert_eq!(s.finest_level(), 3);
        s.validate().unwrap();
        let e = AdaptiveCausticsSettings::from_json(&serde_json::json!({ "photon_w": 512 }));
        assert!(
            matches!(&e, Err(Error::InvalidParameter(w)) if w.contains("photon_w")),
            "an unknown field must be refused by name: {e:?}"
        );
        let ok = AdaptiveCausticsSettings::from_json(&serde_json::json!({ "photons_w": 512 }));
        assert_eq!(ok.map(|s| s.map.photons_w).ok(), Some(512));
    }

    #[test]
    fn the_grid_must_be_a_pyramid() {
        let mut s = AdaptiveCausticsSettings::default();
        s.validate().unwrap();
        assert_eq!(s.finest_level(), 4);
        assert_eq!(s.error_from_level(), 3);
        s.map.photons_w = 1000;
        s.map.photons_h = 1000;
        assert!(s.validate().is_err());
        s.map.photons_w = 1024;
        s.map.photons_h = 512;
        assert!(s.validate().is_err());
        s.map.photons_h = 1024;
        s.map.fresnel_split = FresnelSplit::Deterministic;
        assert!(s.validate().is_err());
    }

    #[test]
    fn the_passes_and_lists_follow_the_byte_limit() {
        let t = AdaptiveCausticsSettings::default().traversal();
        // whole lists beside passes of 5000 clusters (at least 1/64 of the finest level)
        assert!(5000 >= t.dense_clusters(4).div_ceil(MAX_PASSES_PER_LEVEL));
        let whole = TraversalSettings {
            max_traversal_bytes: t.bytes_for_pass(4, false, 5000),
            ..t
        };
        let z = whole.sizes(4, false);
        assert_eq!(z.pass_clusters, 5000);
        assert!(!z.lists_capped);
        assert_eq!(z.list_capacity[3] as u64, t.dense_clusters(4));
        // the screen target's passes also hold four output photons a cluster
        assert!(whole.sizes(4, true).pass_clusters < 5000);
        // a limit below whole lists caps them, in multiples of 4, and the passes take at
        // most half (or the fewest clusters that keep a level to 64 passes)
        let tight = TraversalSettings {
            max_traversal_bytes: t.full_list_bytes(4) / 2,
            ..t
        };
        let z = tight.sizes(4, false);
        assert!(z.lists_capped);
        assert!(z.list_capacity.iter().all(|&n| n % 4 == 0 && n >= 4));
        let min_pass = t.dense_clusters(4).div_ceil(MAX_PASSES_PER_LEVEL);
        assert!(z.pass_clusters as u64 <= (tight.max_traversal_bytes / 2 / 132).max(min_pass));
        // a huge limit: one pass per level
        let huge = TraversalSettings {
            max_traversal_bytes: 1 << 40,
            ..t
        };
        assert_eq!(
            huge.sizes(4, false).pass_clusters as u64,
            t.dense_clusters(4)
        );
    }
}

//! Every parameter of AdaptiveCaustics, with its defaults and validation.

use crate::frame::error::Error;
use crate::techniques::caustic_map::{CausticMapSettings, FresnelSplit};
use crate::techniques::sspm::SspmSettings;
use serde::{Deserialize, Serialize};

/// When a relevant cluster stops being refined (seed 004 sections 3.2.1-2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AdaptiveMetric {
    /// Maximal traversal level: every cluster that met a caster is refined down to the
    /// finest level, where all its photons are output. The photons output are exactly the
    /// dense grid's over the clusters kept (the same seed and jitter), so the map differs
    /// from CausticMap's only where a coarse cluster missed a caster its finer photons
    /// would have met.
    Level,
    /// Maximal caustic map error: from `error_from_grid` on, a cluster whose four photons
    /// all stored in one caustic-map texel is output at once (its photons carry their
    /// coarse texels' flux, the cluster's solid angle or area); the rest is refined, and
    /// output at the finest level (004's third condition). The default: it traces the
    /// fewest photons (004 Figure 7), and here both metrics cost one kernel per step.
    #[default]
    Error,
}

/// What keeps a traced cluster from being discarded (seed 004 section 3.2's first
/// condition, and a conservative one).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClusterRelevance {
    /// A cluster is kept when one of its photons met a caster, or when its footprint on
    /// the view plane overlaps the projection of a caster's bounding box. No photon that
    /// can meet a caster is lost: the level metric outputs exactly the dense grid's
    /// photons (bitwise the same atlas), and a caster smaller than a start-grid cell is
    /// found. The default: 004's own test lost 0.2 to 1.9% of the stored flux on the
    /// built-in scenes at 256^2 (`cornell` the most), at the casters' silhouettes.
    #[default]
    Bounds,
    /// 004's test: kept when at least one of its four photons met a caster. Traces fewer
    /// photons; loses what the coarse photons straddle.
    Photons,
}

impl ClusterRelevance {
    /// The kernels' `relevance` value
    /// ([`cluster_relevance`](crate::math::photon_clusters::cluster_relevance)).
    pub fn kernel_value(self) -> u32 {
        match self {
            ClusterRelevance::Bounds => crate::math::photon_clusters::cluster_relevance::BOUNDS,
            ClusterRelevance::Photons => crate::math::photon_clusters::cluster_relevance::PHOTONS,
        }
    }
}

/// The map the traversal's photons are deposited into (issue 17: so that a comparison
/// can isolate what adaptive emission buys in each).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AdaptiveDeposit {
    /// CausticMap's texture-space caustic atlas, its gather and final pass (the default:
    /// seed 004 splats into a caustic map, and the atlas is the map kind here).
    #[default]
    Atlas,
    /// Sspm's screen-space photon map, its resolve, filter and composite (the `screen`
    /// settings): the photons of seed 000 replaced by the traversal's.
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
    /// and its photons are then splatted over a window that size (seed 004 section 3.2.2's
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
    /// Sspm's settings for the screen target: depth tolerance, filter, outputs and the
    /// rest of what follows the deposit. The photons are the traversal's: the photon
    /// fields (`photons_w`, `photons_h`, `max_bounces`, `min_relative_power`, `seed`,
    /// `point_emission`, `max_photons_per_batch`, `max_triangles`) are set at the top
    /// level and must be left at their defaults here. Unused with the atlas target.
    pub screen: SspmSettings,
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
            screen: SspmSettings::default(),
        }
    }
}

/// Device bytes per cluster of a batch: four 32-byte photon slots.
pub const SLOT_BYTES_PER_CLUSTER: u64 = 128;
/// Device bytes per cluster of a batch per level below the start grid: room for four
/// 4-byte children.
pub const LIST_BYTES_PER_CLUSTER: u64 = 16;

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

    /// The Sspm settings of the screen target: `screen`, with the photon fields of the top
    /// level (the optics of the trace; `photons_w` and `photons_h` the dense-equivalent
    /// grid).
    pub fn screen_settings(&self) -> SspmSettings {
        let m = &self.map;
        SspmSettings {
            photons_w: m.photons_w,
            photons_h: m.photons_h,
            max_bounces: m.max_bounces,
            min_relative_power: m.min_relative_power,
            seed: m.seed,
            max_triangles: m.max_triangles,
            ..self.screen.clone()
        }
    }

    /// The finest level (the start grid is level 0): `photons_w = start_grid * 2^finest`.
    pub fn finest_level(&self) -> u32 {
        (self.map.photons_w / self.start_grid.max(1)).max(1).ilog2()
    }

    /// The first level at which the error metric is checked.
    pub fn error_from_level(&self) -> u32 {
        let mut l = 0;
        while (self.start_grid as u64) << l < self.error_from_grid as u64 && l < 31 {
            l += 1;
        }
        l
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
        let d = SspmSettings::default();
        let s = &self.screen;
        for (field, default) in [
            ("photons_w", s.photons_w == d.photons_w),
            ("photons_h", s.photons_h == d.photons_h),
            ("max_bounces", s.max_bounces == d.max_bounces),
            (
                "min_relative_power",
                s.min_relative_power == d.min_relative_power,
            ),
            ("seed", s.seed == d.seed),
            ("point_emission", s.point_emission == d.point_emission),
            (
                "max_photons_per_batch",
                s.max_photons_per_batch == d.max_photons_per_batch,
            ),
            ("max_triangles", s.max_triangles == d.max_triangles),
        ] {
            if !default {
                return bad(format!(
                    "screen.{field}: the photons are the traversal's; set `{field}` at the top \
                     level (where it exists) instead"
                ));
            }
        }
        if self.deposit == AdaptiveDeposit::Screen {
            self.screen_settings().validate()?;
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
        (self.start_grid as u64 / 2).pow(2)
    }

    /// Fixed bytes plus one cluster's.
    fn min_traversal_bytes(&self) -> u64 {
        let outputs = match self.deposit {
            AdaptiveDeposit::Screen => SLOT_BYTES_PER_CLUSTER,
            AdaptiveDeposit::Atlas => 0,
        };
        4 * self.start_clusters()
            + SLOT_BYTES_PER_CLUSTER
            + outputs
            + LIST_BYTES_PER_CLUSTER * self.finest_level() as u64
    }

    /// Clusters per batch under `max_traversal_bytes`, at most what the finest level can
    /// need in one step (`dense_clusters`); the screen target (`screen`) also holds an
    /// output list of four photons per cluster.
    pub fn batch_clusters(&self, finest: u32, dense_clusters: u64, screen: bool) -> u32 {
        let fixed = 4 * self.start_clusters();
        let outputs = if screen { SLOT_BYTES_PER_CLUSTER } else { 0 };
        let per = SLOT_BYTES_PER_CLUSTER + outputs + LIST_BYTES_PER_CLUSTER * finest as u64;
        let c = self.max_traversal_bytes.saturating_sub(fixed) / per;
        c.clamp(1, dense_clusters.clamp(1, u32::MAX as u64 / 4)) as u32
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
    fn the_batch_follows_the_byte_limit() {
        let s = AdaptiveCausticsSettings {
            max_traversal_bytes: 4 * 1024 + 10 * (128 + 16 * 4),
            ..Default::default()
        };
        assert_eq!(s.batch_clusters(4, 1 << 20, false), 10);
        assert_eq!(s.batch_clusters(4, 3, false), 3);
        assert_eq!(s.batch_clusters(4, 1 << 20, true), 6);
    }
}

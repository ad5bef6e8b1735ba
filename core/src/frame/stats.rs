//! Per-frame statistics: time per pass, photon accounting, fixed-point health, memory.

use serde::Serialize;
use std::collections::BTreeMap;

/// Why photons were not stored in the screen-space photon map (Kim 2019, section 30.3.1.2
/// lists four conditions; escaped and bounce-limit photons are counted apart).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Discards {
    /// Reached a diffuse surface without any specular interaction (direct light), or
    /// ended before its first ray because that ray meets no caster ball
    /// ([`crate::device::caster_spheres`]): it could meet a diffuse surface or nothing.
    pub no_specular: u64,
    /// Left the scene without hitting anything after at least one specular interaction
    /// (or on a first segment that the caster-ball test did not end).
    pub escaped: u64,
    /// Power fell below the negligible threshold (absorption, reflectance).
    pub negligible_power: u64,
    /// Still bouncing at the bounce limit.
    pub bounce_limit: u64,
    /// Landed outside the view (or behind the camera).
    pub off_screen: u64,
    /// Landed on a pixel that sees no diffuse surface, another surface (depth test
    /// failed), or the surface's back side.
    pub depth_mismatch: u64,
}

/// A pass that ran, with its time.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PassStat {
    /// Kernel name of the pass.
    pub name: String,
    /// Sum over all its dispatches this frame (milliseconds, host wall time or device
    /// timestamps as `timing` says).
    pub ms: f64,
    /// Number of dispatches this frame.
    pub dispatches: u32,
}

/// A pass that did not run, and why.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct SkippedPass {
    /// Kernel name of the pass.
    pub name: String,
    /// Why it did not run.
    pub reason: String,
}

/// Everything measured about one frame.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrameStats {
    /// Registry name of the technique (`sspm`, ...).
    pub technique: String,
    /// Name of the backend (`cpu`, `opencl`, `wgpu`, `vulkan`).
    pub backend: String,
    /// The device's name, as the backend reports it.
    pub device: String,
    /// Image width (pixels).
    pub width: u32,
    /// Image height (pixels).
    pub height: u32,
    /// Wall time of the whole frame (ms), including host work and readback of counters.
    pub frame_ms: f64,
    /// "host wall clock" or "device timestamps".
    pub timing: String,
    /// The passes that ran, in the order they first ran, with their times.
    pub passes: Vec<PassStat>,
    /// Passes the frame plan left out, each with its reason.
    pub skipped: Vec<SkippedPass>,
    /// Compiled kernel variants the frame ran (`kernel[SWITCH=0/1,...]`).
    pub variants: Vec<String>,
    /// The frame plan: every pass with why it runs or not, the lights that emit, the
    /// scene's material features, the requested outputs and the buffers created.
    pub plan: Option<crate::frame::plan::FramePlan>,
    /// Photons emitted: the photon grid size times the number of emitting lights.
    pub photons_emitted: u64,
    /// Photons emitted per light, in scene order, where a technique allocates them by
    /// power (PhotonGi); empty otherwise.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub photons_per_light: Vec<u64>,
    /// Ray segments traced for photons (every bounce counts).
    pub photon_rays_traced: u64,
    /// Photons that ended on a diffuse surface after at least one specular interaction.
    pub photons_stored: u64,
    /// Branches added by deterministic splits (CausticMap's `fresnel_split`): the path
    /// ends add up to `photons_emitted + photon_splits`.
    pub photon_splits: u64,
    /// Stored photons that passed the screen tests and were added to the photon map.
    pub photons_deposited: u64,
    /// Photons neither stored nor deposited, by reason.
    pub discarded: Discards,
    /// Emitted flux (W per channel) over all emission domains: per light given photons,
    /// its intensity times the solid angle of the domain (a cone, a sphere) or its
    /// irradiance times the area (a rectangle, PhotonGi's orthographic RSM face), before
    /// a spot's falloff; PhotonGi's domain is each light's RSM (`I x 4 pi` for a point
    /// light, the outer cone for a spot).
    pub emitted_flux: [f64; 3],
    /// Flux of the stored photons (W per channel), from the fixed-point counters.
    pub stored_flux: [f64; 3],
    /// Photon channel values clamped in the fixed-point deposit (never silent).
    pub fixed_point_saturated: u64,
    /// Positive photon channel values that rounded to zero units.
    pub fixed_point_underflow: u64,
    /// Flux quantum of the fixed-point deposit (W).
    pub flux_quantum: f64,
    /// Triangles of the scene dropped before the BVH build because their area is zero in
    /// f32 (collapsed vertices; see [`crate::scene::limits`]).
    pub degenerate_triangles: u64,
    /// Device bytes held by the technique this frame (peak).
    pub bytes_allocated: u64,
    /// Trace-and-deposit batches run.
    pub batches: u32,
    /// Times the host waited for the device while it recorded the frame (a blocking
    /// readback or a run-and-wait whose result the rest of the frame depends on); 0 for a
    /// frame recorded whole.
    pub host_waits: u32,
    /// Frames whose photons the receiver holds, this one included, with progressive
    /// accumulation (`accumulate`; 0 without it): N frames of M photons estimate as one
    /// frame of N x M photons.
    pub accumulated_frames: u32,
    /// Per-pass timing by kernel name (ms), for quick lookup.
    pub pass_ms: BTreeMap<String, f64>,
    /// Error of the filtered caustics against the reference set with
    /// `Sspm::set_reference` (computed after the frame; not part of `frame_ms`).
    pub error: Option<crate::frame::metrics::ErrorStats>,
    /// A technique's own statistics, by name, in their serialised form (AdaptiveCaustics'
    /// traversal: `adaptive`, read typed with its `AdaptiveStats::of`; PhotonGi's waves:
    /// `photon_gi`, `PhotonGiStats::of`); written at the top level of the JSON form
    /// ([`FrameStats::own_stats`], [`FrameStats::put_own`]).
    #[serde(flatten)]
    pub own: std::collections::BTreeMap<String, serde_json::Value>,
}

impl FrameStats {
    /// A technique's own statistics under `key` in [`FrameStats::own`], typed: `None`
    /// where the frame has none (another technique's frame) or they do not read as `T`.
    pub fn own_stats<T: serde::de::DeserializeOwned>(&self, key: &str) -> Option<T> {
        self.own
            .get(key)
            .and_then(|v| serde_json::from_value(v.clone()).ok())
    }

    /// Puts a technique's own statistics into [`FrameStats::own`] under `key`.
    pub fn put_own<T: Serialize>(&mut self, key: &str, value: &T) {
        if let Ok(v) = serde_json::to_value(value) {
            self.own.insert(key.into(), v);
        }
    }

    /// Adds a kernel time to its pass.
    pub fn add_pass_time(&mut self, name: &str, seconds: f64) {
        let ms = seconds * 1e3;
        if let Some(p) = self.passes.iter_mut().find(|p| p.name == name) {
            p.ms += ms;
            p.dispatches += 1;
        } else {
            self.passes.push(PassStat {
                name: name.into(),
                ms,
                dispatches: 1,
            });
        }
        *self.pass_ms.entry(name.into()).or_default() += ms;
    }

    /// Fills the photon accounting from the device's photon counters `c`
    /// ([`crate::device::layout::counter`], `counter::WORDS` words as read back); a
    /// counter a technique's kernels never bump reads 0. Stored flux in W from the
    /// counters' fixed-point units of `flux_quantum`.
    pub fn read_counters(&mut self, c: &[u32], flux_quantum: f32) {
        use crate::device::layout::counter;
        let word = |i: usize| c.get(i).copied().unwrap_or(0) as u64;
        let c64 =
            |i: usize| crate::math::fixed_point::join_u64([word(i) as u32, word(i + 1) as u32]);
        self.photons_stored = word(counter::STORED);
        self.photons_deposited = word(counter::DEPOSITED);
        self.discarded.no_specular = word(counter::NO_SPECULAR);
        self.discarded.escaped = word(counter::ESCAPED);
        self.discarded.negligible_power = word(counter::NEGLIGIBLE);
        self.discarded.bounce_limit = word(counter::BOUNCE_LIMIT);
        self.discarded.off_screen = word(counter::OFF_SCREEN);
        self.discarded.depth_mismatch = word(counter::DEPTH_MISMATCH);
        self.fixed_point_underflow = word(counter::UNDERFLOW);
        self.fixed_point_saturated = word(counter::SATURATED);
        self.photon_rays_traced = c64(counter::RAYS);
        self.photon_splits = word(counter::SPLITS);
        for ch in 0..3 {
            self.stored_flux[ch] = c64(counter::STORED_FLUX + 2 * ch) as f64 * flux_quantum as f64;
        }
    }

    /// Adds the pass times (and dispatches) of `other` to this frame's: work the frame
    /// did twice, counted once in the accounting and twice in the time.
    pub fn absorb_pass_times(&mut self, other: &FrameStats) {
        for p in &other.passes {
            if let Some(q) = self.passes.iter_mut().find(|q| q.name == p.name) {
                q.ms += p.ms;
                q.dispatches += p.dispatches;
            } else {
                self.passes.push(p.clone());
            }
            *self.pass_ms.entry(p.name.clone()).or_default() += p.ms;
        }
    }

    /// Records pass `name` as skipped, with its reason.
    pub fn skip(&mut self, name: &str, reason: impl Into<String>) {
        self.skipped.push(SkippedPass {
            name: name.into(),
            reason: reason.into(),
        });
    }
}

/// Progress of a frame's photon work (called after every batch).
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Photons traced and deposited so far this frame.
    pub photons_done: u64,
    /// Photons the frame emits in all.
    pub photons_total: u64,
}

//! `trace_indirect`: PhotonGi's photon paths with Russian roulette (Smal 2019, section
//! 24.2.2).

use super::{bind, bytes, with_scene, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, GBufferPlanes, SceneArgs};
use crate::device::layout::{IndirectPath, IndirectTraceParams, RsmPhoton};
use crate::math::gi_photon::screen_tiles;
use crate::math::path_sort::{PathKey, PATH_SORT_BUCKETS};
use crate::math::rsm::chunk_photons;

/// Traces photons `params.first .. first + count` of `rsm_photons` (`sample_rsm`'s), or
/// the launch's chunk of them (`chunk_first`, `chunk_size`: [`chunk_photons`], so that a
/// light's photons can go through the waves in chunks that bounded queues hold).
/// At a diffuse hit a photon that has bounced diffusely at least once (all do: the RSM
/// point is the first bounce, or a specular RSM point leads to a later one) is stored
/// if the hit faces the camera, projects inside its view and the camera sees it there (a
/// receiver pixel whose tangent plane it lies on, `layout::off_surface` with
/// [`VISIBLE_TOLERANCE`](crate::device::layout::VISIBLE_TOLERANCE)) (`GiPhoton`s, or float `Photon`s with `params.store` =
/// `gi_store::FLOAT`), and its screen tile's count in `tile_counts` goes up; then, below `params.max_bounces` diffuse bounces, it survives
/// Jensen's roulette (`math::rsm::russian_roulette`) and leaves in a cosine direction.
/// Mirrors scale the flux by their colour; dielectrics reflect or refract by Fresnel
/// (`math::optics::dielectric_scatter`), with Beer-Lambert inside and, from the first
/// dispersive one on, a wavelength and its colour (`math::spectrum::disperse` with
/// `params.dispersion_mode`, the photon's point of the wavelength sequence) and that
/// wavelength's index (`math::optics::dispersive_ior`), as `trace_photons` does.
///
/// Random dimensions (`rng::random_f32(seed, first + i, segment, d)` for photon
/// `first + i`): d 0, 1 the bounce direction, d 2 the roulette, d 3 the Fresnel choice, d 4
/// the channel (three bands); a spectral wavelength is `spectrum::spectral_sample(seed,
/// first + i)`. GPU thread `t` traces photon `first + chunk_first +
/// math::rsm::coherent_sample_order(t, n)` of the chunk's `n` photons (a warp's samples
/// near each other); the CPU traces them in order. A path depends on its photon alone, so only the order of the
/// appended photons differs.
///
/// Counters ([`crate::device::layout::counter`], read for this kernel as): `STORED`
/// photons stored, `ESCAPED` paths that left the scene, `NEGLIGIBLE` paths ended by the
/// roulette or without flux, `BOUNCE_LIMIT` paths ended after `max_bounces` bounces or
/// `max_segments` segments, `OFF_SCREEN` hits outside the view, `DEPTH_MISMATCH` hits
/// turned away from the camera or hidden from it, `RAYS`, `STORED_FLUX`, `UNDERFLOW` (a
/// stored power that packs to zero).
///
/// Schedules: a path is traced over segments `params.segment_first .. segment_end`. The
/// single launch (`waves: None`) traces every path from its RSM photon to its end (0 ..
/// `max_segments`). The `WAVES` variant ([`IndirectWave`]) traces one wave: from the RSM
/// photons (`segment_first` 0, threads as above) or from the `path_counts[segment_first]`
/// paths of `paths_in` (thread `t` takes path `t`), and appends each path still going
/// after `segment_end - 1` (below `max_segments`) to `paths_out`, its slot from
/// `path_counts[segment_end]`. Sorted ([`WaveKeys`], the `sorted_waves` schedule): with
/// `params.queue_keys` each queued path's key
/// ([`path_sort_key`](crate::math::path_sort::path_sort_key) of its next ray under
/// `key_origin_min`, `key_origin_scale`) and its rank among the queue's paths of that
/// key (the key's count in `buckets`, atomic) go to `path_keys` at its slot; with
/// `params.queue_order` thread `t` continues path `order[t]` of `paths_in`
/// (`sort_indirect_paths`'). A path's random numbers are keyed by its photon and
/// segment, and its state is carried in full precision, so the waves store exactly the
/// single launch's photons (in another order) and count the same.

#[derive(Clone, Copy, Debug)]
pub struct TraceIndirect {
    /// The uploaded scene.
    pub scene: SceneArgs,
    /// Camera, range, seed, bounce limits, tiles, store format.
    pub params: IndirectTraceParams,
    /// The photons leaving the RSM points.
    pub rsm_photons: Buf<RsmPhoton>,
    /// Output: stored photons (32 bytes each, `GiPhoton` or `Photon`), appended.
    pub photons: Buf<[u32; 8]>,
    /// `[0]`: next free slot in `photons` (the caller clears it).
    pub photon_count: Buf<u32>,
    /// Stored photons per screen tile (`math::gi_photon::screen_tile`; the caller clears
    /// it).
    pub tile_counts: Buf<u32>,
    /// Photon counters the kernel adds to.
    pub counters: Buf<u32>,
    /// The camera's G-buffer (planes 0, 1 and 3: position and depth, normal, flags): a
    /// photon is stored only where the camera sees its surface.
    pub gbuffer: GBufferPlanes,
    /// Where the launch's shape is on the device (a `dispatch_args` record of the live
    /// photon count; `params.count` is then the bound and the kernel's count comes from
    /// the device too, [`crate::device::launch::ParamPatch`]); `None`: a direct launch of
    /// the chunk's photons ([`chunk_photons`]; a later wave: no more than its queue holds).
    pub dispatch: Option<super::DispatchRecord>,
    /// The `WAVES` variant's path queues; `None`: the single launch.
    pub waves: Option<IndirectWave>,
}

/// The queues of one wave of `trace_indirect` (the `WAVES` variant).
#[derive(Clone, Copy, Debug)]
pub struct IndirectWave {
    /// The paths this wave continues (`segment_first > 0`; its first
    /// `min(path_counts[segment_first], path_capacity)` entries; at least as long as
    /// `paths_out`).
    pub paths_in: Buf<IndirectPath>,
    /// Output: the paths still going after the wave, appended from slot
    /// `path_counts[segment_end]` (sized for every path of the launch, so none is lost;
    /// a slot past its end is not written).
    pub paths_out: Buf<IndirectPath>,
    /// Per segment `k` the paths queued for the wave that starts there (the caller
    /// clears them before the first wave); read at `segment_first` (above 0), appended
    /// to at `segment_end` (below `max_segments`).
    pub path_counts: Buf<u32>,
    /// The `sorted_waves` schedule's keys and order (`params.queue_keys`,
    /// `params.queue_order`); `None`: the paths in queue order, no keys.
    pub keys: Option<WaveKeys>,
}

/// What a wave of the `sorted_waves` schedule writes for the sort of its queue and reads
/// of the sort of its own.
#[derive(Clone, Copy, Debug)]
pub struct WaveKeys {
    /// Output (`queue_keys`): per slot of `paths_out` its path's sort key and rank among
    /// the queue's paths of that key (exactly as long as `paths_out`).
    pub path_keys: Buf<PathKey>,
    /// [`PATH_SORT_BUCKETS`] counts (`queue_keys`): the queued paths of each key (the
    /// caller clears them before the wave).
    pub buckets: Buf<u32>,
    /// `queue_order`: the slots of `paths_in` in the order the wave's threads take them
    /// (`sort_indirect_paths`'; exactly as long as `paths_out`; an entry past the queue
    /// is no path).
    pub order: Buf<u32>,
}

/// `trace_indirect`'s compiled switches: `WAVES` (1: one wave with path queues).
pub const TRACE_INDIRECT_SWITCHES: [&str; 1] = ["WAVES"];

const BINDINGS: [Binding; 23] = with_scene([
    bind("params", Params),
    bind("rsm_photons", Read),
    bind("photons", ReadWrite),
    bind("photon_capacity", Count),
    bind("photon_count", ReadWrite),
    bind("tile_counts", ReadWrite),
    bind("counters", ReadWrite),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer3", Read),
    bind("paths_in", Read),
    bind("paths_out", ReadWrite),
    bind("path_capacity", Count),
    bind("path_counts", ReadWrite),
    bind("path_keys", ReadWrite),
    bind("buckets", ReadWrite),
    bind("order", Read),
]);

impl KernelDecl for TraceIndirect {
    const INFO: KernelInfo = KernelInfo::traced(
        "trace_indirect",
        &BINDINGS,
        &TRACE_INDIRECT_SWITCHES,
        "PhotonGi",
    );

    fn switch_values(&self) -> Vec<u32> {
        vec![self.waves.is_some() as u32]
    }

    /// Its parameters may come partly from the device ([`crate::device::launch::ParamPatch`]).
    fn params_mut(&mut self) -> Option<&mut [u8]> {
        Some(bytemuck::bytes_of_mut(&mut self.params))
    }

    fn scene(&self) -> Option<&SceneArgs> {
        Some(&self.scene)
    }

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        let c = &p.camera;
        let fits = match self.waves {
            // the single launch traces every segment of every path
            None => p.segment_first == 0 && p.segment_end == p.max_segments,
            Some(_) => p.segment_first < p.segment_end && p.segment_end <= p.max_segments,
        };
        if !fits {
            return Err(BackendError::BadArgument(format!(
                "trace_indirect: segments {} .. {} of {} ({})",
                p.segment_first,
                p.segment_end,
                p.max_segments,
                if self.waves.is_some() {
                    "a wave"
                } else {
                    "the single launch traces them all"
                }
            )));
        }
        // the queue lengths a wave reads (`segment_first`) and appends to (`segment_end`,
        // unless it is the paths' last segment)
        let last_count = if p.segment_end < p.max_segments {
            p.segment_end
        } else {
            p.segment_first
        };
        if let Some(w) = &self.waves {
            // a first wave's paths must fit the queue it appends to
            let first_wave = chunk_photons(p.count, p.chunk_first, p.chunk_size);
            if p.segment_first == 0 && first_wave > w.paths_out.len {
                return Err(BackendError::BadArgument(format!(
                    "trace_indirect: a first wave of {first_wave} photons over a queue of {} \
                     paths (a chunk must fit the queues)",
                    w.paths_out.len
                )));
            }
            if w.path_counts.len <= last_count || w.paths_in.len < w.paths_out.len {
                return Err(BackendError::BadArgument(format!(
                    "trace_indirect: {} path counts for a wave ending at segment {}, queues of \
                     {} and {} paths",
                    w.path_counts.len, p.segment_end, w.paths_in.len, w.paths_out.len
                )));
            }
        }
        a.scene(&self.scene)?
            .params("params", p)?
            .buf(
                "rsm_photons",
                self.rsm_photons,
                (p.first as u64 + p.count as u64) * bytes::RSM_PHOTON,
            )?
            .buf(
                "photons",
                self.photons,
                self.photons.len as u64 * bytes::GI_PHOTON,
            )?
            .count("photon_capacity", self.photons.len)?
            .buf("photon_count", self.photon_count, 4)?
            .buf(
                "tile_counts",
                self.tile_counts,
                screen_tiles(c.width, c.height, p.tile_size) as u64 * 4,
            )?
            .buf("counters", self.counters, bytes::COUNTERS)?
            .gather_gbuffer(&self.gbuffer, c.width as u64 * c.height as u64)?;
        match &self.waves {
            Some(w) => {
                a.buf(
                    "paths_in",
                    w.paths_in,
                    w.paths_out.len as u64 * bytes::INDIRECT_PATH,
                )?
                .buf(
                    "paths_out",
                    w.paths_out,
                    w.paths_out.len as u64 * bytes::INDIRECT_PATH,
                )?
                .count("path_capacity", w.paths_out.len)?
                .buf("path_counts", w.path_counts, (last_count as u64 + 1) * 4)?;
            }
            // the single launch reads and writes no queue: stand-ins of the same access
            None => {
                a.buf("paths_in", self.rsm_photons, 0)?
                    .buf("paths_out", self.tile_counts, 0)?
                    .count("path_capacity", 0)?
                    .buf("path_counts", self.tile_counts, 0)?;
            }
        }
        // the sorted waves' keys and order (stand-ins without them)
        match self.waves.and_then(|w| w.keys.map(|k| (w, k))) {
            Some((w, k)) => {
                // as long as the queue: the sort's capacity is the keys'
                if k.path_keys.len != w.paths_out.len
                    || k.order.len != w.paths_out.len
                    || k.buckets.len < PATH_SORT_BUCKETS
                {
                    return Err(BackendError::BadArgument(format!(
                        "trace_indirect: {} path keys, {} order slots and {} buckets for \
                         queues of {} paths",
                        k.path_keys.len, k.order.len, k.buckets.len, w.paths_out.len
                    )));
                }
                a.buf("path_keys", k.path_keys, w.paths_out.len as u64 * 8)?
                    .buf("buckets", k.buckets, PATH_SORT_BUCKETS as u64 * 4)?
                    .buf("order", k.order, w.paths_out.len as u64 * 4)?;
            }
            None => {
                if p.queue_keys != 0 || p.queue_order != 0 {
                    return Err(BackendError::BadArgument(
                        "trace_indirect: queue keys or order without the sorted waves' buffers"
                            .into(),
                    ));
                }
                a.buf("path_keys", self.tile_counts, 0)?
                    .buf("buckets", self.tile_counts, 0)?
                    .buf("order", self.rsm_photons, 0)?;
            }
        }
        a.indirect(self.dispatch)?;
        // threads: the chunk's photons, of which a later wave continues some
        let threads = chunk_photons(p.count, p.chunk_first, p.chunk_size);
        let threads = match &self.waves {
            Some(w) if p.segment_first > 0 => threads.min(w.paths_out.len),
            _ => threads,
        };
        Ok(Some(threads as u64))
    }
}

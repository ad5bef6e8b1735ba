//! PhotonGi (Smal 2019: Smal and Aizenshtein, "Real-Time Global Illumination with Photon
//! Mapping", Ray Tracing Gems ch. 24): multi-bounce indirect light by photon splatting.
//! One frame:
//!
//! 1. `primary_gbuffer` and `direct_light` from the camera (the frame host's);
//! 2. the photon plan on the device (in the frame after a change): per light with power
//!    its RSM (per face `primary_gbuffer` from the light and `rsm_importance` level 0, the
//!    pyramid's levels) and `select_photon_plan`, which notes whether the RSM sees a texel
//!    that leaves flux and copies the host's plan row for the lights seen so far (photons
//!    allocated over them by power, [`crate::math::photon_allocation`]; the `rsm`
//!    module's plan table);
//! 3. per light with power (with photons, once the plan is read back): its RSM (kept
//!    from step 2 for the last light), `sample_rsm` (section 24.2.1) and
//!    `trace_indirect` (24.2.2: roulette, photons stored after the first bounce, culled
//!    to the view, counted per screen tile), their photon counts and quanta copied from
//!    the device plan into their parameters ([`crate::device::launch::ParamPatch`]);
//! 4. `splat_photons` (24.3) into the screen photon map (and, for Eq. 20, each splat's
//!    light direction into the direction map), `resolve_caustics` (irradiance times albedo
//!    / pi: the raw indirect light), `temporal_blend` and `atrous_filter` (24.4, each a
//!    setting);
//! 5. `shading_normal_correction` (24.4.3, Eq. 20) where the scene has vertex normals that
//!    depart from the geometric ones: the splats' power-weighted mean light direction
//!    against the shading normal instead of the geometric one; then the host's
//!    `composite` with the direct light.
//!
//! A light, instance or material change therefore costs the host the plan's text and the
//! face cameras (and the table where the lights' powers changed), never a wait: the
//! frame's statistics and the plan's reasons get the device's counts when the frame's
//! end is read back.

mod rsm;
mod settings;
mod stats;

pub use rsm::{rsm_faces, LightRsm};
pub use settings::{IndirectEstimator, IndirectSchedule, PhotonGiSettings, RsmSampling};
pub use stats::PhotonGiStats;

use crate::backend::Backend;
use crate::device::device_scene::SceneInstances;
use crate::device::handle::{Buf, GBufferPlanes, ImageBuf, PhotonMapPlanes};
use crate::device::launch::{ParamPatch, DISPATCH_RECORD_WORDS};
use crate::device::layout::{
    counter, photon_plan_word, CorrectionParams, DepositParams, GpuCamera, IndirectPath,
    IndirectTraceParams, PathSortParams, PlanParams, RsmParams, SplatParams, NO_PLAN_BIT,
};
use crate::frame::allocation::{allocate, Allocation};
use crate::frame::error::Error;
use crate::frame::host::{FrameHost, HostOptions};
use crate::frame::irradiance_passes::{
    record_atrous, record_temporal_blend, AtrousScratch, History,
};
use crate::frame::output::{Output, Outputs};
use crate::frame::pipeline::{Change, FrameBuilder, Hosted, Pipeline, Reaction};
use crate::frame::plan::{BufferPlan, FramePlan, LightPlan, PassPlan, SceneFeatures};
use crate::frame::screen::{DirectLighting, ScreenNeeds};
use crate::frame::submitted::{EndRead, FrameEnd};
use crate::frame::temporal::PingPong;
use crate::kernels::{
    DepositScreen, DispatchArgs, DispatchRecord, IndirectWave, ResolveCaustics, SampleRsm,
    SelectPhotonPlan, ShadingNormalCorrection, SortIndirectPaths, SplatPhotons, TraceIndirect,
    WaveKeys,
};
use crate::math::gi_photon::{gi_store, screen_tiles};
use crate::math::path_sort::{path_sort_phase, PATH_SORT_BITS, PATH_SORT_BUCKETS};
use crate::recording::Recording;
use rsm::{PhotonPlan, PlanTable, RsmBuffers};
use std::mem::offset_of;
use std::sync::{Arc, Mutex};

/// Lights the photon plan's device buffers hold at least (more lights make them anew).
const MIN_LIGHT_CAPACITY: usize = 8;

/// Eq. 20's `epsilon`: keeps the factor finite where the mean light direction grazes the
/// geometric normal (there `s_max` bounds it anyway).
pub const SHADING_EPSILON: f32 = 1e-4;

/// PhotonGi's outputs (linear radiance, W/(sr m^2), the camera's size).
pub const OUTPUTS: [Output; 4] = [
    Output::Composite,
    Output::Direct,
    Output::RawIndirect,
    Output::FilteredIndirect,
];

/// PhotonGi on one backend, for one scene: the frame host and [`PhotonGiPipeline`].
pub type PhotonGi = Hosted<PhotonGiPipeline>;

/// Whether Eq. 20's shading-normal correction runs: the setting, the splat estimator
/// (the raw deposit has no splats to carry a direction), and a scene where some
/// triangle's vertex normals depart from its geometric normal (elsewhere the shading and
/// geometric normals agree and the factor is 1 up to `eps`:
/// [`crate::device::acceleration::Level::smooth_normals`]).
fn shading_correction(s: &PhotonGiSettings, instances: &SceneInstances) -> bool {
    s.shading_normals && s.estimator == IndirectEstimator::Splat && instances.smooth_normals()
}

/// The length of the scene box's diagonal (scene units; at least the smallest positive
/// f32).
fn scene_diagonal(b: &crate::math::geometry::Aabb) -> f32 {
    (b.max - b.min).length().max(f32::MIN_POSITIVE)
}

/// The scene box's largest absolute coordinate (scene units; the splat's rounding margin,
/// `layout::splat_box_margin`).
fn scene_magnitude(b: &crate::math::geometry::Aabb) -> f32 {
    b.min.abs().max(b.max.abs()).max_element()
}

/// The camera images PhotonGi asks the host for: the G-buffer, and as the requested
/// outputs need them the direct light with its specular chains and the composite.
fn screen_needs(s: &PhotonGiSettings) -> ScreenNeeds {
    let keep = |requested: bool| requested || !s.frame.prune;
    ScreenNeeds {
        gbuffer: true,
        direct: keep(s.frame.outputs.any_of(&[Output::Direct, Output::Composite])).then_some(
            DirectLighting {
                max_specular_depth: s.frame.max_specular_depth,
                min_weight: 1e-4,
                fresnel_model: s.fresnel_model,
            },
        ),
        composite: keep(s.frame.outputs.has(Output::Composite)),
    }
}

/// PhotonGi's own device buffers (the camera's G-buffer, direct and composite images are
/// the host's).
#[derive(Clone, Copy, Debug)]
struct Buffers {
    rsm: RsmBuffers,
    /// The photon plan ([`photon_plan_word`]) for [`Buffers::lights`] lights.
    plan: Buf<u32>,
    /// The plan table (`rsm::PlanTable`'s words, room for every set of
    /// [`rsm::MAX_PLANNED_LIGHTS`] lights).
    table: Buf<u32>,
    /// Lights the plan and table have room for.
    lights: usize,
    /// Per light `k` the row `[0, every initial photon, 1, photon_plan_word::COUNTS + k]`
    /// of `dispatch_args` over the plan, and the launch records it writes (the lights'
    /// `sample_rsm` and `trace_indirect` launches while the plan is on the device only).
    dispatch_rows: Buf<[u32; 4]>,
    dispatch: Buf<u32>,
    photons: Buf<[u32; 8]>,
    photon_count: Buf<u32>,
    tile_counts: Buf<u32>,
    counters: Buf<u32>,
    photon_map: PhotonMapPlanes,
    /// The splats' light directions (Eq. 20): per pixel with the correction, one texel
    /// (bound, never written) without.
    direction_map: PhotonMapPlanes,
    raw: ImageBuf,
    /// The filters' output before Eq. 20's correction (with the correction; `raw` when
    /// no filter runs).
    uncorrected: Option<ImageBuf>,
    indirect: ImageBuf,
    temporal: Option<TemporalBuffers>,
    atrous: Option<AtrousBuffers>,
    /// The path queues of the `waves` schedule (with more than one wave).
    waves: Option<WaveBuffers>,
}

/// The `waves` schedule's queues: two of every path of a chunk of a light's photons
/// (wave `k` reads `paths[k % 2]` and appends to the other: no path is ever lost), the
/// per-segment queue lengths, the later waves' launch records (`dispatch_args` over
/// `rows`, row `k - 1` = `[0, the queue's paths, 1, k]` for wave `k`), and the sort's
/// keys, buckets and order (`sorted_waves`: a wave keys the paths it queues, the sort
/// orders the keys, the next wave takes its paths in that order). A light's photons go
/// through the waves in `chunks` chunks of `chunk` photons (`indirect_queue_paths`);
/// with more than one, the chunks' first waves launch from records of their own
/// (`chunk_rows`: per light `k` and chunk `c`, row `k * chunks + c` = `[c * chunk,
/// chunk, 1, the light's count]`).
#[derive(Clone, Copy, Debug)]
struct WaveBuffers {
    paths: [Buf<IndirectPath>; 2],
    path_counts: Buf<u32>,
    rows: Buf<[u32; 4]>,
    dispatch: Buf<u32>,
    keys: Option<WaveKeys>,
    chunk: u32,
    chunks: u32,
    chunk_rows: Option<(Buf<[u32; 4]>, Buf<u32>)>,
}

impl WaveBuffers {
    /// Records the creation of the queues of `waves` waves (more than one) for lights of
    /// at most `bound` photons each (`lights` of them), taken in chunks of at most
    /// `queue_paths` photons.
    fn create(
        rec: &mut Recording,
        (bound, lights): (u32, usize),
        queue_paths: u32,
        waves: u32,
        sorted: bool,
    ) -> WaveBuffers {
        let later = waves - 1;
        let total = bound.min(queue_paths).max(1);
        let chunks = bound.div_ceil(total).max(1);
        let chunk_rows = (chunks > 1).then(|| {
            let rows: Vec<[u32; 4]> = (0..lights)
                .flat_map(|k| {
                    (0..chunks)
                        .map(move |c| [c * total, total, 1, (photon_plan_word::COUNTS + k) as u32])
                })
                .collect();
            (
                rec.upload(&rows, "indirect chunk launch rows (per light and chunk)"),
                rec.create(
                    rows.len() as u32 * DISPATCH_RECORD_WORDS as u32,
                    "indirect chunk launch records",
                ),
            )
        });
        WaveBuffers {
            chunk: total,
            chunks,
            chunk_rows,
            paths: [
                rec.create(total.max(1), "indirect path queue a"),
                rec.create(total.max(1), "indirect path queue b"),
            ],
            path_counts: rec.create(waves + 1, "indirect paths per wave"),
            rows: rec.upload(
                &(1..waves).map(|k| [0, total, 1, k]).collect::<Vec<_>>(),
                "indirect wave launch rows (per wave its queue length's word)",
            ),
            dispatch: rec.create(
                later * DISPATCH_RECORD_WORDS as u32,
                "indirect wave launch records",
            ),
            keys: sorted.then(|| WaveKeys {
                path_keys: rec.create(total.max(1), "indirect path sort keys"),
                buckets: rec.create(PATH_SORT_BUCKETS, "indirect path sort buckets"),
                order: rec.create(total.max(1), "indirect path order"),
            }),
        }
    }
}

#[derive(Clone, Copy, Debug)]
struct TemporalBuffers {
    image: PingPong<[f32; 4]>,
    edge: PingPong<[f32; 4]>,
    previous: GpuCamera,
}

#[derive(Clone, Copy, Debug)]
struct AtrousBuffers {
    input: ImageBuf,
    scratch: AtrousScratch,
}

impl Buffers {
    /// Records the creation of every buffer for `settings` and `camera`'s image (with
    /// Eq. 20's correction when `correct`): the per-pixel ones, then the RSM's and the
    /// photons' (with room for any light's RSM and photons, so that lights can change
    /// without new buffers).
    fn create(
        rec: &mut Recording,
        camera: GpuCamera,
        (settings, schedule): (&PhotonGiSettings, IndirectSchedule),
        correct: bool,
        lights: usize,
    ) -> Buffers {
        let lights = lights.max(MIN_LIGHT_CAPACITY);
        let row = photon_plan_word::COUNTS - photon_plan_word::ROW + lights;
        let pixels = camera.width * camera.height;
        let temporal =
            (settings.frame.temporal && !settings.frame.accumulate).then(|| TemporalBuffers {
                image: PingPong::create(rec, pixels, "temporal indirect history"),
                edge: PingPong::create(rec, pixels, "temporal edge history"),
                previous: camera,
            });
        let atrous = (settings.frame.atrous_iterations > 0).then(|| AtrousBuffers {
            input: rec.create(pixels, "A-Trous input image"),
            scratch: AtrousScratch {
                a: rec.create(pixels, "A-Trous image a"),
                b: rec.create(pixels, "A-Trous image b"),
                details: rec.create(pixels, "A-Trous clipped details"),
                edge: rec.create(pixels, "A-Trous edge texels"),
            },
        });
        let raw = rec.create(pixels, "raw indirect image");
        let filtered = temporal.is_some() || atrous.is_some();
        let tile_counts = rec.create(
            screen_tiles(camera.width, camera.height, settings.tile_size),
            "photons per screen tile",
        );
        let photon_map = rec.create_photon_map(pixels);
        let direction_map = rec.create_photon_map(if correct { pixels } else { 1 });
        let uncorrected = (correct && filtered)
            .then(|| rec.create(pixels, "uncorrected indirect image"))
            .or(correct.then_some(raw));
        let indirect = if filtered || correct {
            rec.create(pixels, "indirect image")
        } else {
            raw
        };
        let total = settings.total_photons();
        let capacity = (total * settings.bounces as u64).min(u32::MAX as u64) as u32;
        let rsm = RsmBuffers::create(rec, settings);
        let bound = total.min(u32::MAX as u64) as u32;
        let sorted = schedule == IndirectSchedule::SortedWaves;
        let waves = (settings.waves(schedule) > 1).then(|| {
            WaveBuffers::create(
                rec,
                (bound, lights),
                settings.indirect_queue_paths,
                settings.waves(schedule),
                sorted,
            )
        });
        Buffers {
            rsm,
            plan: rec.create(
                (photon_plan_word::ROW + row) as u32,
                "photon plan (mask, quanta, photons per light)",
            ),
            table: rec.create(
                ((1usize << rsm::MAX_PLANNED_LIGHTS) * row) as u32,
                "photon plan table (a row per set of lights seeing something)",
            ),
            lights,
            dispatch_rows: rec.upload(
                &(0..lights)
                    .map(|k| {
                        let bound = total.min(u32::MAX as u64) as u32;
                        [0, bound, 1, (photon_plan_word::COUNTS + k) as u32]
                    })
                    .collect::<Vec<_>>(),
                "photon plan launch rows (per light its count's word)",
            ),
            dispatch: rec.create(
                (lights * DISPATCH_RECORD_WORDS) as u32,
                "photon plan launch records (per light)",
            ),
            photons: rec.create(capacity.max(1), "indirect photons"),
            photon_count: rec.create(1, "indirect photon count"),
            tile_counts,
            counters: rec.create(counter::WORDS as u32, "photon counters"),
            photon_map,
            direction_map,
            raw,
            uncorrected,
            indirect,
            temporal,
            atrous,
            waves,
        }
    }
}

/// PhotonGi's own state over the frame host: its RSMs and photon plan, its splat, its
/// filters (temporal, A-Trous) and their history.
pub struct PhotonGiPipeline {
    settings: PhotonGiSettings,
    /// `settings`' schedule of `trace_indirect` on this pipeline's device (`auto`
    /// resolved).
    schedule: IndirectSchedule,
    /// The lights' RSMs and photons, the packed power's unit and the flux quantum: the
    /// device's plan where [`PhotonGiPipeline::known`], else the plan where every light
    /// with power sees something.
    photons: PhotonPlan,
    /// The plan of every set of lights with power, which the device selects from; `None`
    /// beyond [`rsm::MAX_PLANNED_LIGHTS`] lights with power (the plan is probed on the
    /// host then, and known).
    table: Option<PlanTable>,
    /// The accumulation's frame count whose resolve quanta the device's table holds
    /// (`None`: the table is still to be written).
    table_frames: Option<u32>,
    /// The next frame renders the lights' RSMs and selects the plan first (a change since
    /// the last selection).
    stale: bool,
    /// [`PhotonGiPipeline::photons`] is the device's plan (read back, or probed on the
    /// host).
    known: bool,
    /// Changes followed so far: a plan read back from a frame recorded before the last
    /// change is not the current one.
    generation: u64,
    /// The latest plan read back at a frame's end: its generation and mask.
    decided: Arc<Mutex<Option<(u64, u32)>>>,
    /// Scene bounding-box diagonal (scene units): the splat constants scale with it.
    diagonal: f32,
    /// The scene box's largest absolute coordinate (scene units).
    magnitude: f32,
    buffers: Buffers,
    plan: FramePlan,
    /// Its own buffers.
    owned: Allocation,
    /// Frames whose photons the photon map holds (progressive accumulation).
    accumulated: u32,
}

/// The frame's emitted flux (W per channel): the flux into their RSMs' faces of the lights
/// given photons, from (photons, flux) per light.
fn emitted_flux(lights: impl Iterator<Item = (u64, [f64; 3])>) -> [f64; 3] {
    let mut sum = [0.0; 3];
    for (_, flux) in lights.filter(|(photons, _)| *photons > 0) {
        for (s, f) in sum.iter_mut().zip(flux) {
            *s += f;
        }
    }
    sum
}

/// Light `light`'s line in the frame plan: its photons and RSM faces (`faces` of `side`^2),
/// whether its RSM sees a texel that leaves flux, and whether the device's plan is known
/// yet (`known`; else the photons are those it gets if every light with power sees
/// something).
fn light_plan(
    light: u32,
    photons: u32,
    faces: usize,
    side: u32,
    sees: bool,
    known: bool,
) -> LightPlan {
    let reason = if !sees {
        format!(
            "no photons: its RSM ({faces} faces of {side}^2) sees no texel that leaves flux \
             (flux x albedo is zero on every one), so none could carry any; the other \
             lights share the budget by power"
        )
    } else if known {
        format!("{photons} photons by power, {faces} RSM faces of {side}^2")
    } else {
        format!(
            "{photons} photons by power where every light's RSM sees something, {faces} RSM \
             faces of {side}^2 (which RSMs see something is decided on the device in the \
             next frame and read back at its end)"
        )
    };
    LightPlan {
        light,
        emits: photons > 0,
        reason,
    }
}

/// The frame plan of `host`'s scene with `s`: the lights' photons and RSMs (`known`: the
/// device's plan; `planned`: the device selects it from the plan table), every pass with
/// its reason, and `buffers`.
fn make_plan(
    host: &FrameHost,
    (s, schedule): (&PhotonGiSettings, IndirectSchedule),
    rsms: &[LightRsm],
    (known, planned): (bool, bool),
    buffers: Vec<BufferPlan>,
    correct: bool,
) -> FramePlan {
    let any = rsms.iter().any(|r| r.photons > 0);
    // each light's launches a chunk of its photons (1: the single kernel)
    let launches: Vec<u32> = rsms
        .iter()
        .filter(|r| r.photons > 0)
        .map(|r| s.light_waves(schedule, known.then_some(r.photons)))
        .collect();
    let waves = launches.iter().copied().max().unwrap_or(1);
    let some_single = launches.contains(&1);
    let pass = |name: &str, runs: bool, reason: &str| PassPlan {
        name: name.into(),
        runs,
        reason: reason.into(),
    };
    let photons = if any {
        "some light has power"
    } else {
        "no light has power"
    };
    let splat = s.estimator == IndirectEstimator::Splat;
    let deposit = s.estimator == IndirectEstimator::Deposit;
    let atrous = s.frame.atrous_iterations > 0;
    FramePlan {
        prune: s.frame.prune,
        features: SceneFeatures::of(host.model()),
        outputs: s.frame.outputs.names(&OUTPUTS),
        lights: rsms
            .iter()
            .map(|r| light_plan(r.light, r.photons, r.faces.len(), s.rsm_size, r.sees, known))
            .collect(),
        trace_variant: None,
        passes: vec![
            pass("primary_gbuffer", true, "camera and RSM faces"),
            if !s.frame.prune {
                pass("direct_light", true, "pruning off: every pass runs")
            } else if s.frame.outputs.any_of(&[Output::Direct, Output::Composite]) {
                pass("direct_light", true, "direct or composite requested")
            } else {
                pass(
                    "direct_light",
                    false,
                    "neither direct nor composite requested",
                )
            },
            pass("rsm_importance", any, photons),
            if planned {
                pass(
                    "select_photon_plan",
                    any,
                    "after each light's RSM in the frame after a light, instance or material \
                     change: which lights' RSMs see something, decided on the device",
                )
            } else {
                pass(
                    "select_photon_plan",
                    false,
                    "more lights with power than the plan table covers: the host probes \
                     their RSMs on a change",
                )
            },
            pass(
                "dispatch_args",
                (planned || waves > 1) && any,
                if waves > 1 {
                    "the indirect waves' launches from their queues' lengths (and the lights' \
                     from the device plan's counts until it is read back)"
                } else if planned {
                    "the lights' launch records from the device plan's counts, until it is \
                     read back"
                } else {
                    "the plan is the host's: the lights launch their photons directly"
                },
            ),
            pass("sample_rsm", any, photons),
            pass(
                "trace_indirect",
                any,
                if waves > 1 && some_single {
                    "some light has power; its paths in per-bounce waves, a light of at \
                     most auto_waves_above_photons photons in one launch"
                } else if waves > 1 {
                    "some light has power; its paths in per-bounce waves"
                } else {
                    photons
                },
            ),
            pass(
                "sort_indirect_paths",
                any && waves > 1 && schedule == IndirectSchedule::SortedWaves,
                if schedule != IndirectSchedule::SortedWaves {
                    "indirect_schedule is not sorted_waves"
                } else if waves > 1 {
                    "each indirect wave's queue in key order (direction octant, origin cell)"
                } else {
                    "a single wave: no queue"
                },
            ),
            pass(
                "splat_photons",
                any && splat,
                if splat {
                    photons
                } else {
                    "estimator deposit: the photons are deposited, not splatted"
                },
            ),
            pass(
                "deposit_screen",
                any && deposit,
                if deposit {
                    "estimator deposit (the indirect reference's estimator)"
                } else {
                    "estimator splat"
                },
            ),
            pass("resolve_caustics", true, "irradiance to radiance"),
            pass(
                "temporal_blend",
                s.frame.temporal && !s.frame.accumulate,
                if s.frame.accumulate {
                    "accumulate: the photon map holds the frames' photons"
                } else if s.frame.temporal {
                    "setting temporal"
                } else {
                    "temporal off"
                },
            ),
            pass(
                "atrous_filter",
                atrous,
                if atrous {
                    "setting atrous_iterations"
                } else {
                    "atrous_iterations = 0"
                },
            ),
            pass(
                "shading_normal_correction",
                correct,
                if correct {
                    "Eq. 20: the scene has vertex normals that depart from the geometric ones"
                } else if !s.shading_normals {
                    "shading_normals off"
                } else if !splat {
                    "estimator deposit: no splats carry a light direction"
                } else {
                    "every vertex normal is its triangle's geometric normal: the factor is 1"
                },
            ),
            if !s.frame.prune {
                pass("composite", true, "pruning off: every pass runs")
            } else if s.frame.outputs.has(Output::Composite) {
                pass("composite", true, "direct plus indirect")
            } else {
                pass("composite", false, "composite not requested")
            },
        ],
        buffers,
    }
}

/// The camera's G-buffer (PhotonGi always asks the host for it: [`screen_needs`]).
fn gbuffer(host: &FrameHost) -> GBufferPlanes {
    host.screen()
        .gbuffer
        .expect("PhotonGi makes the camera's G-buffer")
}

impl PhotonGiPipeline {
    /// Whether Eq. 20's correction runs (its buffers were made).
    fn correct(&self) -> bool {
        self.buffers.uncorrected.is_some()
    }

    /// Plans the photons anew over the host's scene, with the scene's diagonal, and
    /// states it in the plan: the face cameras and (where the lights' powers changed) the
    /// plan table on the host, which lights see something on the device in the next
    /// frame; beyond [`rsm::MAX_PLANNED_LIGHTS`] lights with power the RSMs are probed on
    /// the host (a wait). `Rebuild` where the plan's buffers have no room for the lights.
    /// On an error nothing changes.
    fn replan(
        &mut self,
        backend: &mut dyn Backend,
        host: &mut FrameHost,
    ) -> Result<Reaction, Error> {
        let lights = rsm::host_lights(host);
        if lights.len() > self.buffers.lights {
            return Ok(Reaction::Rebuild);
        }
        let total = self.settings.total_photons();
        // the table holds while the lights' powers do (a move keeps it)
        let keep = self
            .table
            .as_ref()
            .is_some_and(|t| t.holds_for(&lights, total));
        let remade = (!keep).then(|| PlanTable::new(&lights, total));
        let planned = keep || remade.as_ref().is_some_and(Option::is_some);
        let (photons, known) = if planned {
            let side = self.settings.rsm_size;
            let bounds = host.geometry().bounds;
            (rsm::plan_lights(&lights, total, side, &bounds, &[]), false)
        } else {
            let b = &self.buffers.rsm;
            (rsm::plan_photons(backend, host, b, &self.settings)?, true)
        };
        if let Some(table) = remade {
            self.table = table;
            self.table_frames = None;
        }
        self.stale = planned;
        self.known = known;
        self.generation += 1;
        let buffers = self.plan_buffers(host);
        self.plan = make_plan(
            host,
            (&self.settings, self.schedule),
            &photons.rsms,
            (known, planned),
            buffers,
            self.correct(),
        );
        self.photons = photons;
        self.diagonal = scene_diagonal(&host.geometry().bounds);
        self.magnitude = scene_magnitude(&host.geometry().bounds);
        Ok(Reaction::Kept)
    }

    /// Takes the device's plan where a frame's end read it back since the last change:
    /// the host's photons, statistics and plan reasons are then exact before the device
    /// reports them.
    fn learn(&mut self, host: &FrameHost) {
        let decided = self.decided.lock().ok().and_then(|mut d| d.take());
        let (Some((generation, mask)), Some(table)) = (decided, &self.table) else {
            return;
        };
        if generation != self.generation || self.known {
            return;
        }
        let lights = rsm::host_lights(host);
        let (side, bounds) = (self.settings.rsm_size, host.geometry().bounds);
        let total = self.settings.total_photons();
        self.photons = rsm::plan_lights(&lights, total, side, &bounds, &table.sees(mask));
        self.known = true;
        let buffers = self.plan_buffers(host);
        self.plan = make_plan(
            host,
            (&self.settings, self.schedule),
            &self.photons.rsms,
            (true, true),
            buffers,
            self.correct(),
        );
    }

    /// The host's buffers and this technique's, for the plan.
    fn plan_buffers(&self, host: &FrameHost) -> Vec<BufferPlan> {
        host.buffer_plans()
            .into_iter()
            .chain(self.owned.buffers.iter().cloned())
            .collect()
    }

    /// Forgets the temporal history (the next frame is not blended).
    fn reset_history(&mut self) {
        if let Some(t) = &mut self.buffers.temporal {
            t.image.reset();
            t.edge.reset();
        }
        self.accumulated = 0;
    }

    /// With progressive accumulation, this frame's index among those the photon map holds
    /// (0 without, and at an accumulation's first frame).
    fn frame_index(&self) -> u32 {
        if self.settings.frame.accumulate {
            self.accumulated
        } else {
            0
        }
    }

    /// This frame's photon seed (a new one for every frame an accumulation adds).
    fn frame_seed(&self) -> u32 {
        crate::frame::receivers::accumulation_seed(self.settings.frame.seed, self.frame_index())
    }

    /// The splat's parameters for camera `cam`.
    fn splat_params(&self, cam: GpuCamera) -> SplatParams {
        let s = &self.settings;
        SplatParams {
            camera: cam,
            tile_size: s.tile_size,
            power_scale: self.photons.power_scale,
            flux_quantum: self.photons.flux_quantum,
            max_splat_px: s.max_splat_px,
            max_ray_length: s.max_ray_length * self.diagonal,
            min_length_scale: 0.1,
            density_radius_min: s.density_radius_min * self.diagonal,
            density_radius_max: s.density_radius_max * self.diagonal,
            photons_per_pixel: s.photons_per_pixel,
            normal_compression: s.normal_compression,
            max_stretch: s.max_stretch,
            tile_constant: crate::math::photon_splat::tile_area_constant(
                cam.tan_half_fov_x,
                cam.tan_half_fov_y,
                (s.tile_size, s.tile_size),
                (cam.width, cam.height),
            ),
            min_splat_px: s.min_splat_px,
            light_direction: self.correct() as u32,
            scene_magnitude: self.magnitude,
            _pad: [0],
        }
    }

    /// The trace's parameters for a light's photons `first .. first + count`.
    fn trace_params(
        &self,
        cam: GpuCamera,
        first: u32,
        count: u32,
        store: u32,
    ) -> IndirectTraceParams {
        IndirectTraceParams {
            camera: cam,
            first,
            count,
            seed: self.frame_seed(),
            max_bounces: self.settings.bounces,
            max_segments: self.settings.max_segments,
            tile_size: self.settings.tile_size,
            store,
            fresnel_model: self.settings.fresnel_model,
            power_scale: self.photons.power_scale,
            flux_quantum: self.photons.flux_quantum,
            dispersion_mode: self.settings.frame.dispersion.kernel_value(),
            segment_first: 0,
            segment_end: self.settings.max_segments,
            chunk_first: 0,
            chunk_size: u32::MAX,
            queue_keys: 0,
            key_origin_min: [0.0; 3],
            queue_order: 0,
            key_origin_scale: [0.0; 3],
            _pad: 0,
        }
    }

    fn deposit_params(&self, cam: GpuCamera) -> DepositParams {
        DepositParams {
            camera: cam,
            flux_quantum: self.photons.flux_quantum,
            hit_distance_quantum: 1.0,
            // the tangent-plane test (`layout::off_surface`): within 1% of the depth of
            // the pixel's tangent plane, so a surface seen at any angle keeps its photons
            // (a curved receiver of radius R departs from the plane by ~(pixel size)^2 /
            // 2R within a pixel: 2e-3 of the depth for R = z / 10 at 54 rows)
            depth_tolerance: -0.01,
            photon_capacity: self.buffers.photons.len,
        }
    }

    /// A patch of `words` parameter words at byte `offset` from the device plan's word
    /// `word`.
    fn plan_patch(&self, offset: usize, word: usize) -> ParamPatch {
        ParamPatch {
            offset: offset as u32,
            src: self.buffers.plan.id,
            src_word: word as u32,
            words: 1,
        }
    }

    /// Records the RSM (unless the buffers hold it: `rendered`) and the trace passes of
    /// light `r` (the photons go to `b.photons`): `bound` threads each, or launched
    /// from the light's record of `b.dispatch` with `bound` as the limit (`indirect`),
    /// the light's photon count and the quanta from the device plan. Returns each
    /// chunk's launches of `trace_indirect` (1: the single kernel; more: the waves), in
    /// recorded order.
    fn record_light(
        &self,
        rec: &mut Recording,
        host: &FrameHost,
        seeded: &PhotonGiSettings,
        r: &LightRsm,
        (bound, indirect, rendered): (u32, bool, bool),
        store: u32,
    ) -> Vec<u32> {
        let b = &self.buffers;
        let scene = host.scene();
        let dispatch = indirect.then_some(DispatchRecord {
            args: b.dispatch,
            record: r.light,
        });
        let params = if rendered {
            rsm::rsm_params(seeded, r)
        } else {
            rsm::record_rsm(rec, scene, &b.rsm, seeded, r)
        };
        let count = photon_plan_word::COUNTS + r.light as usize;
        rec.kernel_patched(
            SampleRsm {
                params: RsmParams {
                    // the orthographic face's plane, for a directional light's photons
                    face_camera: r.faces[0],
                    face: 0,
                    face_count: r.faces.len() as u32,
                    first_sample: 0,
                    sample_count: bound,
                    level: 0,
                    ..params
                },
                lights: scene.lights,
                texels: b.rsm.texels,
                pyramid: b.rsm.pyramid,
                photons: b.rsm.photons,
                dispatch,
            },
            vec![self.plan_patch(offset_of!(RsmParams, sample_count), count)],
        );
        let patches = vec![
            self.plan_patch(offset_of!(IndirectTraceParams, count), count),
            self.plan_patch(
                offset_of!(IndirectTraceParams, power_scale),
                photon_plan_word::POWER_SCALE,
            ),
            self.plan_patch(
                offset_of!(IndirectTraceParams, flux_quantum),
                photon_plan_word::FLUX_QUANTUM,
            ),
        ];
        let single = TraceIndirect {
            scene,
            params: self.trace_params(host.camera(), 0, bound, store),
            rsm_photons: b.rsm.photons,
            photons: b.photons,
            photon_count: b.photon_count,
            tile_counts: b.tile_counts,
            counters: b.counters,
            gbuffer: gbuffer(host),
            dispatch,
            waves: None,
        };
        // the single kernel also for a light of few photons under `auto` (its count
        // known on the host: `bound`)
        let waves = self
            .settings
            .light_waves(self.schedule, (!indirect).then_some(bound));
        let Some(w) = b.waves.as_ref().filter(|_| waves > 1) else {
            rec.kernel_patched(single, patches);
            return vec![1];
        };
        // per-bounce waves: wave k traces segment k of the paths queued for it (the last
        // wave the rest of each path), launched from its queue's length on the device;
        // chunk by chunk of the light's photons when the queues hold fewer (every chunk
        // of the bound where the count is the device's, empty ones launching nothing)
        let light_chunks = if indirect {
            w.chunks
        } else {
            bound.div_ceil(w.chunk).clamp(1, w.chunks)
        };
        for c in 0..light_chunks {
            // the chunk's first wave: the light's record, or the chunk's own
            let first_wave = match (dispatch, w.chunk_rows) {
                (Some(_), Some((_, args))) => Some(DispatchRecord {
                    args,
                    record: r.light * w.chunks + c,
                }),
                (d, _) => d,
            };
            let chunk = TraceIndirect {
                params: IndirectTraceParams {
                    chunk_first: c * w.chunk,
                    chunk_size: w.chunk,
                    ..single.params
                },
                ..single
            };
            self.record_waves(rec, host, w, chunk, (first_wave, waves), &patches);
        }
        vec![waves; light_chunks as usize]
    }

    /// Records the waves of one chunk of a light's photons (`single`'s parameters, its
    /// first wave launched from `first_wave`), its queues cleared first.
    fn record_waves(
        &self,
        rec: &mut Recording,
        host: &FrameHost,
        w: &WaveBuffers,
        single: TraceIndirect,
        (first_wave, waves): (Option<DispatchRecord>, u32),
        patches: &[ParamPatch],
    ) {
        let max_segments = self.settings.max_segments;
        rec.clear(w.path_counts);
        // sorted: the key's origin cells over the scene's box
        let (key_origin_min, key_origin_scale) = {
            let b = host.geometry().bounds;
            let cells = (1u32 << PATH_SORT_BITS) as f32;
            let extent = (b.max - b.min).max(glam::Vec3::splat(f32::MIN_POSITIVE));
            (b.min.to_array(), (cells / extent).to_array())
        };
        for k in 0..waves {
            let dispatch = if k == 0 {
                first_wave
            } else {
                // every row again: those of earlier waves read final lengths, so their
                // records are rewritten with the same words
                rec.kernel(DispatchArgs {
                    table: w.rows,
                    counts: w.path_counts,
                    args: w.dispatch,
                });
                let record = DispatchRecord {
                    args: w.dispatch,
                    record: k - 1,
                };
                if let Some(keys) = w.keys {
                    self.record_sort(rec, keys, w.path_counts, k, record);
                }
                Some(record)
            };
            let end = if k + 1 == waves { max_segments } else { k + 1 };
            let sorted = w.keys.is_some();
            // the buckets count the keys of the paths this wave queues
            if let Some(keys) = w.keys.filter(|_| end < max_segments) {
                rec.clear(keys.buckets);
            }
            rec.kernel_patched(
                TraceIndirect {
                    params: IndirectTraceParams {
                        segment_first: k,
                        segment_end: end,
                        queue_keys: (sorted && end < max_segments) as u32,
                        key_origin_min,
                        queue_order: (sorted && k > 0) as u32,
                        key_origin_scale,
                        ..single.params
                    },
                    dispatch,
                    waves: Some(IndirectWave {
                        paths_in: w.paths[k as usize % 2],
                        paths_out: w.paths[(k as usize + 1) % 2],
                        path_counts: w.path_counts,
                        keys: w.keys,
                    }),
                    ..single
                },
                patches.to_vec(),
            );
        }
    }

    /// Records the sort of the keys of the queue wave `k` continues (its length at word
    /// `k` of `path_counts`) into the order that wave takes its paths in, launched from
    /// `record` (its length's launch record).
    fn record_sort(
        &self,
        rec: &mut Recording,
        keys: WaveKeys,
        path_counts: Buf<u32>,
        k: u32,
        record: DispatchRecord,
    ) {
        let sort = |phase| SortIndirectPaths {
            params: PathSortParams {
                phase,
                count_word: k,
                _pad: [0; 2],
            },
            path_keys: keys.path_keys,
            path_counts,
            order: keys.order,
            buckets: keys.buckets,
            dispatch: Some(record),
        };
        rec.kernel(sort(path_sort_phase::SCAN));
        rec.kernel(sort(path_sort_phase::SCATTER));
    }

    /// Records the lights' launch records from the device plan's counts (`dispatch_args`
    /// over every light's row).
    fn record_launches(&self, rec: &mut Recording) {
        let b = &self.buffers;
        rec.kernel(DispatchArgs {
            table: b.dispatch_rows,
            counts: b.plan,
            args: b.dispatch,
        });
        if let Some((table, args)) = b.waves.and_then(|w| w.chunk_rows) {
            rec.kernel(DispatchArgs {
                table,
                counts: b.plan,
                args,
            });
        }
    }

    /// Records `select_photon_plan` after light `bit`'s RSM (`r`; `None`: no RSM, the row
    /// selected again).
    fn record_select(&self, rec: &mut Recording, noted: Option<(u32, &LightRsm)>) {
        let (bit, faces) = noted.map_or((NO_PLAN_BIT, 0), |(k, r)| (k, r.faces.len() as u32));
        let row_words = self.table.as_ref().map_or(0, PlanTable::row_words);
        rec.kernel(SelectPhotonPlan {
            params: PlanParams {
                side: self.settings.rsm_size,
                faces,
                bit,
                row_words,
                table_words: self.buffers.table.len,
                _pad: [0; 3],
            },
            pyramid: self.buffers.rsm.pyramid,
            table: self.buffers.table,
            plan: self.buffers.plan,
        });
    }

    /// The temporal blend and the A-Trous iterations from `raw` to `indirect` (each
    /// optional: the last that runs writes `indirect`; with neither, `indirect` is `raw`).
    fn record_filters(&self, rec: &mut Recording, cam: GpuCamera, gbuffer: GBufferPlanes) {
        let b = &self.buffers;
        // the filters' last output: before Eq. 20's correction where it runs
        let target = b.uncorrected.unwrap_or(b.indirect);
        let blended = b.atrous.map_or(target, |a| a.input);
        let mut input = b.raw;
        if let Some(t) = &b.temporal {
            let history = History {
                image: &t.image,
                edge: &t.edge,
                previous: t.previous,
            };
            record_temporal_blend(rec, cam, gbuffer, history, b.raw, blended);
            input = blended;
        }
        // with neither filter `indirect` is the raw image's buffer
        if let Some(a) = b.atrous {
            record_atrous(
                rec,
                cam,
                gbuffer,
                a.scratch,
                self.settings.frame.atrous_iterations,
                self.settings.frame.atrous_clip_sigmas,
                input,
                target,
            );
        }
    }

    /// Records the splat (or nothing with the deposit estimator), the resolve, the
    /// filters, Eq. 20's correction and the host's composite.
    fn record_resolve(&self, rec: &mut Recording, host: &FrameHost) {
        let (cam, g, b) = (host.camera(), gbuffer(host), &self.buffers);
        if self.settings.estimator != IndirectEstimator::Deposit {
            rec.kernel_patched(
                SplatPhotons {
                    params: self.splat_params(cam),
                    gbuffer: g,
                    photons: b.photons.reinterpret(),
                    photon_count: b.photon_count,
                    tile_counts: b.tile_counts,
                    counters: b.counters,
                    photon_map: b.photon_map,
                    direction_map: b.direction_map,
                },
                vec![
                    self.plan_patch(
                        offset_of!(SplatParams, power_scale),
                        photon_plan_word::POWER_SCALE,
                    ),
                    self.plan_patch(
                        offset_of!(SplatParams, flux_quantum),
                        photon_plan_word::FLUX_QUANTUM,
                    ),
                ],
            );
        }
        // an accumulation's sums read as one frame of all their photons (the plan's
        // resolve quantum: its flux quantum over the frames)
        let frames = self.frame_index() + 1;
        rec.kernel_patched(
            ResolveCaustics {
                params: DepositParams {
                    flux_quantum: self.photons.flux_quantum / frames as f32,
                    ..self.deposit_params(cam)
                },
                gbuffer: g,
                photon_map: b.photon_map,
                out: b.raw,
            },
            vec![self.plan_patch(
                offset_of!(DepositParams, flux_quantum),
                photon_plan_word::RESOLVE_QUANTUM,
            )],
        );
        self.record_filters(rec, cam, g);
        if let Some(uncorrected) = b.uncorrected {
            rec.kernel(ShadingNormalCorrection {
                params: CorrectionParams {
                    width: cam.width,
                    height: cam.height,
                    max_stretch: self.settings.max_stretch,
                    epsilon: SHADING_EPSILON,
                },
                gbuffer: g,
                direction_map: b.direction_map,
                input: uncorrected,
                out: b.indirect,
            });
        }
        host.record_composite(rec, b.indirect);
    }
}

impl Pipeline for PhotonGiPipeline {
    type Settings = PhotonGiSettings;

    const NAME: &'static str = "photon-gi";

    fn validate(settings: &PhotonGiSettings) -> Result<(), Error> {
        settings.validate()
    }

    fn host_options(settings: &PhotonGiSettings) -> HostOptions {
        HostOptions {
            max_triangles: settings.frame.max_triangles,
            atlas_receivers: false,
        }
    }

    /// The camera images from the host, then every own buffer (each checked against the
    /// device first), the lights planned (which RSMs see something: on the device in the
    /// first frame, or probed here beyond [`rsm::MAX_PLANNED_LIGHTS`] lights with power).
    fn create(
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        settings: PhotonGiSettings,
    ) -> Result<PhotonGiPipeline, Error> {
        // `auto` becomes this device's schedule
        let schedule = settings.schedule(backend.capabilities().device_type);
        host.make_screen(backend, screen_needs(&settings))?;
        let camera = host.camera();
        let correct = shading_correction(&settings, host.instances());
        let lights = host.model().lights.len();
        let mut rec = Recording::new();
        let buffers = Buffers::create(&mut rec, camera, (&settings, schedule), correct, lights);
        let owned = allocate(backend, &rec, Some((camera.width, camera.height)))?;
        let mut p = PhotonGiPipeline {
            plan: make_plan(
                host,
                (&settings, schedule),
                &[],
                (false, true),
                Vec::new(),
                correct,
            ),
            settings,
            schedule,
            photons: PhotonPlan {
                rsms: Vec::new(),
                power_scale: 1.0,
                flux_quantum: 1.0,
            },
            table: None,
            table_frames: None,
            stale: false,
            known: false,
            generation: 0,
            decided: Arc::new(Mutex::new(None)),
            diagonal: scene_diagonal(&host.geometry().bounds),
            magnitude: scene_magnitude(&host.geometry().bounds),
            buffers,
            owned,
            accumulated: 0,
        };
        if let Err(e) = p.replan(backend, host) {
            let _ = p.owned.free(backend);
            return Err(e);
        }
        Ok(p)
    }

    fn settings(&self) -> &PhotonGiSettings {
        &self.settings
    }

    fn set_seed(&mut self, seed: u32) {
        if seed != self.settings.frame.seed {
            self.accumulated = 0;
        }
        self.settings.frame.seed = seed;
    }

    /// The frame's recordings in order, each with the photons it traces: visibility and
    /// clears; the plan table where it changed; after a change, the lights' RSMs and the
    /// plan's selection; per light with power (with photons, once the plan is known), its
    /// photons (deposited at once with the deposit estimator); the splat, resolve,
    /// filters, Eq. 20's correction and the composite; the plan and the counters read at
    /// the frame's end.
    fn record(
        &mut self,
        _backend: &mut dyn Backend,
        host: &mut FrameHost,
        frame: &mut FrameBuilder,
    ) -> Result<(), Error> {
        self.learn(host);
        let rsms = &self.photons.rsms;
        frame.stats.flux_quantum = self.photons.flux_quantum as f64;
        frame.stats.photons_emitted = rsms.iter().map(|r| r.photons as u64).sum();
        frame.stats.photons_per_light = rsms.iter().map(|r| r.photons as u64).collect();
        frame.stats.emitted_flux = emitted_flux(rsms.iter().map(|r| (r.photons as u64, r.flux)));
        let (cam, b) = (host.camera(), self.buffers);
        host.record_visibility(frame.rec());
        let first = self.frame_index() == 0;
        let frames = self.frame_index() + 1;
        let rec = frame.rec();
        // an accumulating photon map keeps the frames before
        if first {
            rec.clear_photon_map(&b.photon_map);
            if b.uncorrected.is_some() {
                rec.clear_photon_map(&b.direction_map);
            }
        }
        rec.clear(b.counters);
        rec.clear(b.photon_count);
        rec.clear(b.tile_counts);

        // the plan on the device: the table's row for the lights whose RSM sees
        // something, or the host's plan where it probed them
        let mut seeded = self.settings.clone();
        seeded.frame.seed = self.frame_seed();
        let mut reselect = false;
        match &self.table {
            Some(t) if self.table_frames != Some(frames) => {
                rec.write(b.table, 0, &t.words(frames), "photon plan table")?;
                reselect = true;
            }
            Some(_) => {}
            None => rec.write(
                b.plan,
                0,
                &rsm::plan_words(0, &self.photons, frames),
                "photon plan",
            )?,
        }
        if self.table.is_some() {
            self.table_frames = Some(frames);
        }
        // the light whose RSM the buffers hold after the plan's selection
        let mut held = None;
        let lit = self.table.as_ref().map_or(&[][..], |t| &t.lit[..]);
        let probed = self.stale && self.table.is_some();
        if probed {
            let mut rec = Recording::new();
            rec.write(
                b.plan,
                photon_plan_word::MASK as u32,
                &[0u32],
                "photon plan",
            )?;
            // (the table and the lights' RSMs come from the same lights)
            for (k, r) in lit
                .iter()
                .enumerate()
                .filter_map(|(k, &i)| Some((k as u32, rsms.get(i as usize)?)))
            {
                rsm::record_rsm(&mut rec, host.scene(), &b.rsm, &seeded, r);
                self.record_select(&mut rec, Some((k, r)));
                held = Some(r.light);
            }
            reselect = lit.is_empty();
            frame.push(rec, 0);
        }
        if reselect {
            self.record_select(frame.rec(), None);
        }
        // the lights' launches from the plan's counts while the host does not know them
        let known = self.known || self.table.is_none();
        if !known && (probed || reselect) {
            self.record_launches(frame.rec());
        }

        // the lights traced: those with power until the device's plan is known, then
        // those with photons; in reverse, so that the last RSM of the selection is used
        let traced: Vec<u32> = if known {
            rsms.iter()
                .filter(|r| r.photons > 0)
                .map(|r| r.light)
                .collect()
        } else {
            self.table.as_ref().map_or(Vec::new(), |t| t.traced.clone())
        };
        let total = self.settings.total_photons().min(u32::MAX as u64) as u32;
        let deposit = self.settings.estimator == IndirectEstimator::Deposit;
        // each chunk's launches of `trace_indirect`, for the frame's wave statistics
        let mut chunks = Vec::new();
        for r in traced.iter().rev().filter_map(|&i| rsms.get(i as usize)) {
            let i = r.light;
            // threads: the light's photons where known, else the device plan's count
            // (launched from its record; OpenCL launches the bound, every initial photon,
            // and the kernels leave past the count)
            let bound = if known { r.photons } else { total };
            let launch = (bound, !known, held == Some(i));
            held = None;
            let mut rec = Recording::new();
            if deposit {
                // each light's float photons deposited before the next light's are traced
                rec.clear(b.photon_count);
                chunks.extend(self.record_light(
                    &mut rec,
                    host,
                    &seeded,
                    r,
                    launch,
                    gi_store::FLOAT,
                ));
                rec.kernel_patched(
                    DepositScreen {
                        params: self.deposit_params(cam),
                        gbuffer: gbuffer(host),
                        photons: b.photons.reinterpret(),
                        photon_count: b.photon_count,
                        counters: b.counters,
                        photon_map: b.photon_map,
                    },
                    vec![self.plan_patch(
                        offset_of!(DepositParams, flux_quantum),
                        photon_plan_word::FLUX_QUANTUM,
                    )],
                );
            } else {
                chunks.extend(self.record_light(
                    &mut rec,
                    host,
                    &seeded,
                    r,
                    launch,
                    gi_store::PACKED,
                ));
            }
            frame.stats.batches += 1;
            frame.push(rec, r.photons as u64);
        }
        self.stale = false;

        let mut rec = Recording::new();
        self.record_resolve(&mut rec, host);
        frame.push(rec, 0);
        let end = PlanEnd {
            counters: frame.read_at_end(b.counters),
            plan: frame.read_at_end(b.plan),
            generation: self.generation,
            lit: self.table.as_ref().map(|t| t.lit.clone()),
            lights: rsms.iter().map(|r| (r.faces.len(), r.sees)).collect(),
            flux: rsms.iter().map(|r| r.flux).collect(),
            side: self.settings.rsm_size,
            decided: Arc::clone(&self.decided),
            chunks,
            sorted: b.waves.is_some_and(|w| w.keys.is_some()),
        };
        frame.end_read(EndRead::Own(Arc::new(end)));
        // this frame's blend is the next frame's history
        if let Some(t) = &mut self.buffers.temporal {
            t.image.swap();
            t.edge.swap();
            t.previous = cam;
        }
        if self.settings.frame.accumulate {
            self.accumulated += 1;
            frame.stats.accumulated_frames = self.accumulated;
        }
        Ok(())
    }

    /// A camera move at the same size keeps the history (it reprojects across the move);
    /// lights, instances and materials re-plan the photons in place (the buffers hold
    /// any light's six faces and every photon) and reset the history. Buffers are made
    /// anew at a new image size and where instances switch Eq. 20's correction on or
    /// off.
    fn react(
        &mut self,
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        change: Change,
    ) -> Result<Reaction, Error> {
        match change {
            Change::Camera => {
                // the photon map is the camera's: an accumulation starts again
                self.accumulated = 0;
                return Ok(Reaction::Kept);
            }
            // every per-pixel buffer and the filters' history anew, at the new size
            Change::Resized => return Ok(Reaction::Rebuild),
            Change::Instances { .. }
                if shading_correction(&self.settings, host.instances()) != self.correct() =>
            {
                return Ok(Reaction::Rebuild)
            }
            // albedos decide what the RSMs see
            Change::Lights | Change::Instances { .. } | Change::Materials { .. } => {}
        }
        let reaction = self.replan(backend, host)?;
        self.reset_history();
        Ok(reaction)
    }

    fn plan(&self) -> &FramePlan {
        &self.plan
    }

    fn own_outputs(&self) -> &'static [Output] {
        &OUTPUTS
    }

    fn requested_outputs(&self) -> Outputs {
        self.settings.frame.outputs
    }

    fn output_image(&self, host: &FrameHost, output: Output) -> Option<ImageBuf> {
        let b = &self.buffers;
        match output {
            Output::Composite => host.screen().composite,
            Output::Direct => host.screen().direct,
            Output::RawIndirect => Some(b.raw),
            Output::FilteredIndirect => Some(b.indirect),
            _ => None,
        }
    }

    fn estimate_outputs(&self) -> (Output, Output) {
        (Output::FilteredIndirect, Output::RawIndirect)
    }

    fn free(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        Ok(self.owned.free(backend)?)
    }

    fn owned(&self) -> (usize, u64) {
        self.owned.count()
    }
}

/// A frame's end: the device's photon plan and the photon counters, read back, into the
/// frame's statistics (photons per light, the flux quantum, the plan's lines for the
/// lights) and, for the next frames' host, into `decided`.
#[derive(Debug)]
struct PlanEnd {
    /// Indices of the counters and of the plan among the frame's readbacks.
    counters: usize,
    plan: usize,
    /// The changes followed when the frame was recorded.
    generation: u64,
    /// The probed lights, bit by bit of the plan's mask (`None`: the plan was the
    /// host's, probed).
    lit: Option<Vec<u32>>,
    /// Per light its RSM faces and whether it sees something in the host's plan.
    lights: Vec<(usize, bool)>,
    /// Per light its flux into its RSM's faces (W per channel, `rsm::rsm_flux`).
    flux: Vec<[f64; 3]>,
    /// RSM side (texels).
    side: u32,
    decided: Arc<Mutex<Option<(u64, u32)>>>,
    /// Each chunk's launches of `trace_indirect` in recorded order (1: a single launch;
    /// more: waves) and whether each queue is sorted.
    chunks: Vec<u32>,
    sorted: bool,
}

impl FrameEnd for PlanEnd {
    fn apply(
        &self,
        readbacks: &[Vec<u8>],
        times: &[crate::backend::PassTime],
        stats: &mut crate::frame::stats::FrameStats,
    ) {
        if let Some(s) = PhotonGiStats::from_times(&self.chunks, self.sorted, times) {
            s.put(stats);
        }
        let words = |at: usize| -> Vec<u32> {
            readbacks
                .get(at)
                .map(|c| bytemuck::pod_collect_to_vec(c))
                .unwrap_or_default()
        };
        let plan = words(self.plan);
        let word = |w: usize| plan.get(w).copied().unwrap_or(0);
        let quantum = f32::from_bits(word(photon_plan_word::FLUX_QUANTUM));
        let mask = word(photon_plan_word::MASK);
        let counts: Vec<u64> = (0..self.lights.len())
            .map(|i| word(photon_plan_word::COUNTS + i) as u64)
            .collect();
        stats.flux_quantum = quantum as f64;
        stats.photons_emitted = counts.iter().sum();
        stats.emitted_flux = emitted_flux(counts.iter().copied().zip(self.flux.iter().copied()));
        stats.read_counters(&words(self.counters), quantum);
        let mut sees: Vec<bool> = self.lights.iter().map(|l| l.1).collect();
        if let Some(lit) = &self.lit {
            for (k, &i) in lit.iter().enumerate() {
                if let Some(s) = sees.get_mut(i as usize) {
                    *s = mask & (1 << k) != 0;
                }
            }
        }
        if let Some(p) = &mut stats.plan {
            p.lights = (0..self.lights.len())
                .map(|i| {
                    light_plan(
                        i as u32,
                        counts[i] as u32,
                        self.lights[i].0,
                        self.side,
                        sees[i],
                        true,
                    )
                })
                .collect();
        }
        stats.photons_per_light = counts;
        if self.lit.is_some() {
            if let Ok(mut d) = self.decided.lock() {
                if d.is_none_or(|(g, _)| g <= self.generation) {
                    *d = Some((self.generation, mask));
                }
            }
        }
    }
}

impl Hosted<PhotonGiPipeline> {
    /// The lights' RSMs and photon counts: the device's plan once a frame's end has
    /// reported it since the last change (which lights' RSMs see something is decided on
    /// the device), else the counts where every light with power sees something.
    pub fn light_rsms(&self) -> &[LightRsm] {
        &self.pipeline().photons.rsms
    }
}

/// The registry's constructor: `settings` is a JSON object of [`PhotonGiSettings`]
/// fields.
pub fn create(
    backend: &mut dyn Backend,
    scene: &crate::scene::Scene,
    settings: &serde_json::Value,
) -> Result<Box<dyn crate::frame::technique::Technique>, Error> {
    crate::frame::pipeline::create::<PhotonGiPipeline>(backend, scene, settings)
}

//! Kim 2019's screen receiver: photons deposited into a screen-space photon map (one
//! photon, one pixel, fixed-point integer sums; Kim 2019, section 30.3.1.3), resolved to
//! radiance (`resolve_caustics`, Kim 2019, Eq. 5: the raw caustics), filtered ([`GatherFilter`]:
//! the density-adaptive, flux-keeping gather or Kim 2019's bilateral gather, Kim 2019, section
//! 30.3.2), optionally blended with the reprojected history and A-Trous filtered, and
//! composited over the frame host's direct light (Kim 2019, section 30.3.3).
//!
//! The receiver does not know where its photons come from: Sspm deposits the photons of
//! its projection volumes, AdaptiveCaustics those its traversal outputs. The G-buffer,
//! the direct image and the composite image are the frame host's.

pub mod outputs;
pub mod plan;
pub mod settings;

pub use outputs::FrameImages;

use crate::frame::output::Output;
use crate::frame::settings::FrameSettings;
pub use plan::{plan_frame, Needs};
pub use settings::{GatherFilter, ScreenSettings};

use crate::device::handle::{Buf, GBufferPlanes, ImageBuf, PhotonMapPlanes};
use crate::device::layout::{counter, DepositParams, GatherParams, GpuCamera};
use crate::frame::irradiance_passes::FilterChain;
use crate::frame::plan::FramePlan;
use crate::frame::screen::{ScreenNeeds, ScreenTargets};
use crate::kernels::{
    BilateralGather, DensityGather, GatherFootprint, PhotonCountTable, ResolveCaustics,
    TileHitDistance,
};
use crate::math::fixed_point::power_of_two_quantum;
use crate::math::geometry::Aabb;
use crate::recording::Recording;

/// The fixed-point quanta and the gather's hit-distance clamp of a screen frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenQuanta {
    /// Flux per fixed-point unit of the photon map (W), a power of two (the emission's).
    pub flux_quantum: f32,
    /// Hit distance per fixed-point unit (scene units), a power of two.
    pub hit_distance_quantum: f32,
    /// Lower clamp of the gather's hit distance (scene units; default 5% of the scene
    /// diagonal).
    pub hit_distance_min: f32,
    /// Upper clamp of the gather's hit distance (scene units; default 50% of the scene
    /// diagonal, never below `hit_distance_min`).
    pub hit_distance_max: f32,
}

impl ScreenQuanta {
    /// The quanta of a scene with `bounds` whose brightest photon is quantised with
    /// `flux_quantum`: the hit distance's quantum puts the scene diagonal at 2^24 to
    /// 2^25 units, its clamp comes from `settings` or the diagonal.
    pub fn new(bounds: Aabb, flux_quantum: f32, settings: &ScreenSettings) -> ScreenQuanta {
        let diag = bounds.diagonal().max(f32::MIN_POSITIVE);
        let hit_distance_min = settings.hit_distance_min.unwrap_or(0.05 * diag);
        ScreenQuanta {
            flux_quantum,
            hit_distance_quantum: power_of_two_quantum(diag),
            hit_distance_min,
            hit_distance_max: settings
                .hit_distance_max
                .unwrap_or(0.5 * diag)
                .max(hit_distance_min),
        }
    }

    /// `deposit_screen` / `resolve_caustics` parameters.
    pub fn deposit_params(
        &self,
        camera: GpuCamera,
        settings: &ScreenSettings,
        photon_capacity: u32,
    ) -> DepositParams {
        DepositParams {
            camera,
            flux_quantum: self.flux_quantum,
            hit_distance_quantum: self.hit_distance_quantum,
            depth_tolerance: settings.depth_tolerance,
            photon_capacity,
        }
    }

    /// The gathers' parameters (`axis` 0: horizontal pass).
    pub fn gather_params(
        &self,
        camera: GpuCamera,
        settings: &ScreenSettings,
        axis: u32,
    ) -> GatherParams {
        GatherParams {
            camera,
            roughness: settings.roughness,
            hit_distance_min: self.hit_distance_min,
            hit_distance_max: self.hit_distance_max,
            max_radius_px: settings.max_radius_px,
            sigma_depth: settings.sigma_depth,
            normal_power: settings.normal_power,
            axis,
            tile_size: settings.tile_size,
            hit_distance_quantum: self.hit_distance_quantum,
            knn_photons: settings.knn_photons,
            flux_quantum: self.flux_quantum,
            table_block: crate::math::density_gather::table_block(settings.max_radius_px),
            surface: crate::device::layout::gather_surface::SCREEN,
            _pad: [0; 3],
        }
    }
}

/// Device buffers of the filter (exist only when filtered caustics are needed).
#[derive(Clone, Copy, Debug)]
enum GatherBuffers {
    /// The density gather: the photon counts' summed-area table, the edge texels and the
    /// image between its two passes (the footprint pass writes into the filtered image,
    /// which the last pass overwrites).
    Density {
        table: Buf<u32>,
        edge: ImageBuf,
        scratch: ImageBuf,
        /// The passes' source index (`math::density_gather::source_index_len`).
        source_index: Buf<u32>,
    },
    /// The bilateral gather: hit-distance tiles and the image between its two passes.
    Bilateral { tiles: Buf<f32>, scratch: ImageBuf },
}

/// The screen photon map and its counters (exist only with photon passes).
#[derive(Clone, Copy, Debug)]
pub struct PhotonMap {
    /// Per-pixel fixed-point flux and hit-distance sums.
    pub planes: PhotonMapPlanes,
    /// The photon counters (`layout::counter`).
    pub counters: Buf<u32>,
}

/// How the direct image of a screen-receiver frame is lit: specular chains up to the
/// frame's `max_specular_depth`, exact Fresnel, chains below 1e-3 of the pixel's weight
/// stopped.
pub fn direct_lighting(frame: &FrameSettings) -> crate::frame::screen::DirectLighting {
    crate::frame::screen::DirectLighting {
        max_specular_depth: frame.max_specular_depth,
        min_weight: 1e-3,
        fresnel_model: crate::math::optics::fresnel_model::EXACT,
    }
}

/// The screen receiver of one frame size.
#[derive(Clone, Debug)]
pub struct ScreenReceiver {
    /// The technique's shared settings (outputs, pruning, filter chain, accumulation).
    frame: FrameSettings,
    settings: ScreenSettings,
    quanta: ScreenQuanta,
    needs: Needs,
    map: Option<PhotonMap>,
    raw: Option<ImageBuf>,
    gather: Option<GatherBuffers>,
    filtered: Option<ImageBuf>,
    /// The opt-in temporal blend and A-Trous iterations on the filtered caustics.
    filters: Option<FilterChain>,
    /// Frames whose photons the photon map holds (progressive accumulation).
    accumulated: u32,
}

impl ScreenReceiver {
    /// The camera images the frame host must make for `needs` (the G-buffer always: every
    /// output is shaded from it).
    pub fn screen_needs(needs: Needs, frame: &FrameSettings) -> ScreenNeeds {
        ScreenNeeds {
            gbuffer: true,
            direct: needs.direct_light.then(|| direct_lighting(frame)),
            composite: needs.composite,
        }
    }

    /// Records the creation of the receiver's buffers for `plan` (made by [`plan_frame`])
    /// at `camera`'s size; the caller allocates and executes the recording.
    pub fn create(
        rec: &mut Recording,
        camera: GpuCamera,
        plan: &FramePlan,
        frame: &FrameSettings,
        settings: ScreenSettings,
        quanta: ScreenQuanta,
    ) -> ScreenReceiver {
        let needs = Needs::of_plan(plan);
        let (w, h) = (camera.width, camera.height);
        let pixels = w * h;
        let map = needs.photons.then(|| PhotonMap {
            planes: rec.create_photon_map(pixels),
            counters: rec.create(counter::WORDS as u32, "photon counters"),
        });
        let raw = needs
            .photons
            .then(|| rec.create(pixels, "raw caustics image"));
        let gather = needs.gather.then(|| match settings.filter {
            GatherFilter::Density => GatherBuffers::Density {
                table: rec.create(pixels, "photon count table"),
                edge: rec.create(pixels, "gather edge texels"),
                scratch: rec.create(pixels, "gather scratch image"),
                source_index: rec.create(
                    crate::math::density_gather::source_index_len(w, h),
                    "gather source index",
                ),
            },
            GatherFilter::Bilateral => GatherBuffers::Bilateral {
                tiles: rec.create(
                    w.div_ceil(settings.tile_size) * h.div_ceil(settings.tile_size),
                    "hit distance tiles",
                ),
                scratch: rec.create(pixels, "gather scratch image"),
            },
        });
        let filtered = needs
            .gather
            .then(|| rec.create(pixels, "filtered caustics image"));
        let (temporal, atrous) = (plan.runs("temporal_blend"), plan.runs("atrous_filter"));
        let filters = (temporal || atrous)
            .then(|| FilterChain::create(rec, pixels, camera, temporal, atrous));
        ScreenReceiver {
            frame: frame.clone(),
            settings,
            quanta,
            needs,
            map,
            raw,
            gather,
            filtered,
            filters,
            accumulated: 0,
        }
    }

    /// The settings it was made with.
    pub fn settings(&self) -> &ScreenSettings {
        &self.settings
    }

    /// The quanta in effect.
    pub fn quanta(&self) -> ScreenQuanta {
        self.quanta
    }

    /// Re-plans for new quanta (moved lights or casters) and forgets the history; the
    /// buffers stay.
    pub fn set_quanta(&mut self, quanta: ScreenQuanta) {
        self.quanta = quanta;
        self.reset_history();
    }

    /// With progressive accumulation, the index of this frame among those the photon map
    /// accumulates (its photons' seed: [`crate::frame::receivers::accumulation_seed`]);
    /// 0 without.
    pub fn frame_index(&self) -> u32 {
        if self.frame.accumulate {
            self.accumulated
        } else {
            0
        }
    }

    /// Frames the resolve reads as one, this one included (1 without accumulation).
    fn frames_read(&self) -> u32 {
        self.frame_index() + 1
    }

    /// Starts the accumulation again from the next frame (a moved camera).
    pub fn restart_accumulation(&mut self) {
        self.accumulated = 0;
    }

    /// The quanta the resolve and filter read the photon map with: the deposit's flux
    /// quantum over the frames it holds (their mean).
    fn read_quanta(&self) -> ScreenQuanta {
        ScreenQuanta {
            flux_quantum: self.quanta.flux_quantum / self.frames_read() as f32,
            ..self.quanta
        }
    }

    /// The pass groups it was made for.
    pub fn needs(&self) -> Needs {
        self.needs
    }

    /// The photon map and counters (with photon passes).
    pub fn photon_map(&self) -> Option<PhotonMap> {
        self.map
    }

    /// `deposit_screen` / `resolve_caustics` parameters for photon buffers of
    /// `photon_capacity` photons.
    pub fn deposit_params(&self, camera: GpuCamera, photon_capacity: u32) -> DepositParams {
        self.quanta
            .deposit_params(camera, &self.settings, photon_capacity)
    }

    /// The frame's device images over the host's `screen` images, by what `settings`
    /// asked for (an image not requested has a handle only with pruning off).
    pub fn images(&self, camera: GpuCamera, screen: &ScreenTargets) -> FrameImages {
        let out = self.frame.outputs;
        let keep = |requested: bool| requested || !self.frame.prune;
        let composite = if screen.composite.is_some() {
            screen.composite
        } else if out.has(Output::Composite) {
            screen.direct // no caustics: the composite is the direct image
        } else {
            None
        };
        FrameImages {
            width: camera.width,
            height: camera.height,
            composite,
            direct: screen.direct.filter(|_| keep(out.has(Output::Direct))),
            raw_caustics: self.raw.filter(|_| keep(out.has(Output::RawCaustics))),
            filtered_caustics: self
                .filtered
                .filter(|_| keep(out.has(Output::FilteredCaustics))),
        }
    }

    /// Records the photon map and counters cleared (the frame's start); with progressive
    /// accumulation the photon map keeps the frames before.
    pub fn record_clear(&self, rec: &mut Recording) {
        if let Some(m) = self.map {
            if self.frame_index() == 0 {
                rec.clear_photon_map(&m.planes);
            }
            rec.clear(m.counters);
        }
    }

    /// Records the resolve, the filter chain and the composite over the host's `screen`
    /// images (`photon_capacity`: as the deposits were parameterised).
    pub fn record_resolve(
        &self,
        rec: &mut Recording,
        camera: GpuCamera,
        screen: &ScreenTargets,
        photon_capacity: u32,
    ) {
        let (Some(m), Some(raw), Some(gbuffer)) = (self.map, self.raw, screen.gbuffer) else {
            return;
        };
        rec.kernel(ResolveCaustics {
            params: self
                .read_quanta()
                .deposit_params(camera, &self.settings, photon_capacity),
            gbuffer,
            photon_map: m.planes,
            out: raw,
        });
        let (Some(g), Some(filtered)) = (self.gather, self.filtered) else {
            return;
        };
        // the filter, then the temporal blend, then the A-Trous iterations, each opt-in;
        // the last that runs writes `filtered`
        let last = self.filters.map_or(filtered, |f| f.input(filtered));
        self.record_gather(rec, camera, gbuffer, m.planes, g, (raw, filtered, last));
        if let Some(f) = &self.filters {
            let s = &self.frame;
            let iterations = (s.atrous_iterations, s.atrous_clip_sigmas);
            f.record(rec, camera, gbuffer, iterations, filtered);
        }
        if self.needs.composite {
            screen.record_composite(rec, filtered);
        }
    }

    /// The gather's passes from the photon map (`raw`: the resolved image the bilateral
    /// gather filters; `filtered`: the density gather's footprint image; `last`: what the
    /// gather writes).
    fn record_gather(
        &self,
        rec: &mut Recording,
        camera: GpuCamera,
        gbuffer: GBufferPlanes,
        photon_map: PhotonMapPlanes,
        g: GatherBuffers,
        (raw, filtered, last): (ImageBuf, ImageBuf, ImageBuf),
    ) {
        let gather = self.read_quanta().gather_params(camera, &self.settings, 0);
        let columns = GatherParams { axis: 1, ..gather };
        match g {
            GatherBuffers::Density {
                table,
                edge,
                scratch,
                source_index,
            } => {
                for params in [gather, columns] {
                    rec.kernel(PhotonCountTable {
                        params,
                        photon_map,
                        table,
                        gbuffer,
                        edge,
                    });
                }
                rec.clear(source_index);
                rec.kernel(GatherFootprint {
                    params: gather,
                    photon_map,
                    table,
                    out: filtered,
                    edge,
                    source_index,
                });
                rec.kernel(DensityGather {
                    params: gather,
                    gbuffer,
                    edge,
                    input: filtered,
                    out: scratch,
                    source_index,
                });
                rec.kernel(DensityGather {
                    params: columns,
                    gbuffer,
                    edge,
                    input: scratch,
                    out: last,
                    source_index,
                });
            }
            GatherBuffers::Bilateral { tiles, scratch } => {
                rec.kernel(TileHitDistance {
                    params: gather,
                    photon_map,
                    tiles,
                });
                rec.kernel(BilateralGather {
                    params: gather,
                    gbuffer,
                    tiles,
                    input: raw,
                    out: scratch,
                });
                rec.kernel(BilateralGather {
                    params: columns,
                    gbuffer,
                    tiles,
                    input: scratch,
                    out: last,
                });
            }
        }
    }

    /// After a frame with photon passes seen by `camera`: its blend is the next frame's
    /// history, and its photons stay in an accumulating photon map. Returns the frames
    /// the frame's estimate holds with accumulation (0 without).
    pub fn end_frame(&mut self, camera: GpuCamera) -> u32 {
        if let Some(f) = &mut self.filters {
            f.end_frame(camera);
        }
        if self.frame.accumulate {
            self.accumulated += 1;
            self.accumulated
        } else {
            0
        }
    }

    /// The outputs the screen receiver gives a technique ([`outputs::OUTPUTS`]).
    pub const OUTPUTS: [Output; 4] = outputs::OUTPUTS;

    /// The device image of `output` (camera-sized, linear radiance, row-major from the
    /// top-left pixel): `None` where the plan knows it is zero, or for an output the
    /// screen receiver does not make.
    pub fn image(&self, host: &crate::frame::host::FrameHost, output: Output) -> Option<ImageBuf> {
        self.images(host.camera(), host.screen()).get(output)
    }

    /// Forgets the temporal history and the accumulated photons (the next frame is not
    /// blended and starts a new accumulation).
    pub fn reset_history(&mut self) {
        if let Some(f) = &mut self.filters {
            f.reset();
        }
        self.restart_accumulation();
    }
}

//! Screen-space photon mapping (`Sspm`, seed 000) as a sequence of passes:
//!
//! 1. `primary_gbuffer`, `direct_light` (once per frame);
//! 2. per light and per batch: `trace_photons` (emit, trace through specular chains, store
//!    photons on diffuse surfaces after >= 1 specular interaction) then `deposit_screen`
//!    (one photon -> one pixel, fixed-point integer sums; section 30.3.1.3);
//! 3. `resolve_caustics` (flux -> radiance, Eq. 5), `tile_hit_distance`, two
//!    `bilateral_gather` passes (section 30.3.2), `composite` (section 30.3.3).
//!
//! Photons are processed in batches of at most `max_photons_per_batch`, so the photon
//! buffer never exceeds `32 * max_photons_per_batch` bytes; every batch is deposited before
//! the next is traced, so nothing is dropped when a buffer is "full".

use crate::backend::{read_buf, Backend};
use crate::device_scene::DeviceScene;
use crate::emission::{
    emission_domain, unpruned_domain, EmissionDomain, NoEmission, PointEmission,
};
use crate::fixed_point::{join_u64, power_of_two_quantum};
use crate::gpu::*;
use crate::image::Image;
use crate::plan::{FramePlan, Output, Outputs};
use crate::recording::{Buf, ImageBuf, Kernel, Recording, ResourceId, SceneArgs, Step};
use crate::rng::pcg_hash;
use crate::scene::Scene;
use crate::stats::FrameStats;
use crate::Error;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// Every parameter of the technique; defaults from seed 000 where it gives them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct SspmSettings {
    /// Photon grid per light, `pw x ph` (seed 000: 2k x 2k in its figures).
    pub photons_w: u32,
    pub photons_h: u32,
    /// Maximum ray segments per photon path.
    pub max_bounces: u32,
    /// A photon whose largest channel falls below this fraction of its emitted flux is
    /// dropped as negligible (seed 000 condition 1).
    pub min_relative_power: f32,
    /// Point-light emission domain.
    pub point_emission: PointEmission,
    /// Relative view-depth tolerance of the store test (condition 3).
    pub depth_tolerance: f32,
    /// Gather blur per unit hit distance (the source's denoiser "roughness", 0.07).
    pub roughness: f32,
    /// Hit-distance clamp (scene units); `None`: 5% and 50% of the scene's diagonal (the
    /// source clamps to [300, 2000] in its scene units and asks for a per-scene choice).
    pub hit_distance_min: Option<f32>,
    pub hit_distance_max: Option<f32>,
    /// Largest gather radius in pixels.
    pub max_radius_px: u32,
    /// Bilateral depth weight `exp(-|dz| / (sigma_depth z))`.
    pub sigma_depth: f32,
    /// Bilateral normal weight exponent (0 disables it).
    pub normal_power: f32,
    /// Tile size (pixels) of the hit-distance tiles that set the gather radius.
    pub tile_size: u32,
    /// Longest specular chain followed from a mirror/glass pixel in `direct_light`.
    pub max_specular_depth: u32,
    /// Frame seed of the counter-based RNG.
    pub seed: u32,
    /// Memory limit: photons traced per batch (photon buffer = 32 bytes each).
    pub max_photons_per_batch: u32,
    /// The images the caller wants; passes and buffers that no requested image needs are
    /// left out (see [`crate::plan`]).
    pub outputs: Outputs,
    /// Leave out passes, kernel features, buffers and lights the scene and outputs do
    /// not need (default). Off: everything runs, the baseline pruning is checked against.
    pub prune: bool,
}

impl Default for SspmSettings {
    fn default() -> Self {
        SspmSettings {
            photons_w: 1024,
            photons_h: 1024,
            max_bounces: 12,
            min_relative_power: 1e-4,
            point_emission: PointEmission::CasterCone,
            depth_tolerance: 0.01,
            roughness: 0.07,
            hit_distance_min: None,
            hit_distance_max: None,
            max_radius_px: 16,
            sigma_depth: 0.02,
            normal_power: 8.0,
            tile_size: 8,
            max_specular_depth: 6,
            seed: 0x5350_4d31,
            max_photons_per_batch: 1 << 20,
            outputs: Outputs::default(),
            prune: true,
        }
    }
}

impl SspmSettings {
    /// Rejects parameters that cannot give a meaningful frame.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |what: &str| Err(Error::InvalidParameter(what.to_string()));
        let total = self.photons_w as u64 * self.photons_h as u64;
        if self.photons_w == 0 || self.photons_h == 0 || total > u32::MAX as u64 {
            return bad("photon grid must be at least 1x1 and at most 2^32 - 1 photons per light");
        }
        if self.max_bounces == 0 || self.max_bounces > 1024 {
            return bad("max_bounces must be in 1..=1024");
        }
        if !(self.min_relative_power >= 0.0 && self.min_relative_power < 1.0) {
            return bad("min_relative_power must be in [0, 1)");
        }
        if !(self.depth_tolerance > 0.0 && self.depth_tolerance.is_finite()) {
            return bad("depth_tolerance must be > 0");
        }
        if !(self.roughness >= 0.0 && self.roughness.is_finite()) {
            return bad("roughness must be >= 0");
        }
        for (name, v) in [
            ("hit_distance_min", self.hit_distance_min),
            ("hit_distance_max", self.hit_distance_max),
        ] {
            if let Some(v) = v {
                if !(v > 0.0 && v.is_finite()) {
                    return bad(&format!("{name} must be > 0"));
                }
            }
        }
        if let (Some(a), Some(b)) = (self.hit_distance_min, self.hit_distance_max) {
            if a > b {
                return bad("hit_distance_min exceeds hit_distance_max");
            }
        }
        if self.max_radius_px > 256 {
            return bad("max_radius_px must be <= 256");
        }
        if !(self.sigma_depth > 0.0 && self.sigma_depth.is_finite())
            || !(self.normal_power >= 0.0 && self.normal_power.is_finite())
        {
            return bad("sigma_depth must be > 0 and normal_power >= 0");
        }
        if self.tile_size == 0 || self.tile_size > 256 {
            return bad("tile_size must be in 1..=256");
        }
        if !self.outputs.any() {
            return bad("outputs: at least one output must be requested");
        }
        if self.max_photons_per_batch == 0 {
            return bad("max_photons_per_batch must be >= 1");
        }
        if self.max_specular_depth > MAX_SPECULAR_DEPTH {
            return bad(&format!(
                "max_specular_depth must be <= {MAX_SPECULAR_DEPTH}"
            ));
        }
        Ok(())
    }
}

/// Largest `max_specular_depth`: GPU kernels walk the specular ray tree with a fixed
/// stack of `MAX_SPECULAR_DEPTH + 1` entries (a depth-first walk of a binary tree of depth
/// `d` holds at most `d + 1` pending rays).
pub const MAX_SPECULAR_DEPTH: u32 = 30;

/// Device images of a frame (handles; read them with [`Sspm::read_output`]). An image
/// is `None` when it was not requested, or when the plan knows it is zero (no light emits
/// photons): [`Sspm::read_output`] then returns zeros without a device buffer.
#[derive(Clone, Copy, Debug)]
pub struct FrameImages {
    pub width: u32,
    pub height: u32,
    /// Direct light + filtered caustics (the direct image's handle when there are no
    /// caustics).
    pub composite: Option<ImageBuf>,
    /// Direct light only (shadow rays, specular chains from mirror/glass pixels).
    pub direct: Option<ImageBuf>,
    /// Caustic radiance straight from the photon map (alpha: mean hit distance).
    pub raw_caustics: Option<ImageBuf>,
    /// Caustic radiance after the bilateral gather.
    pub filtered_caustics: Option<ImageBuf>,
}

impl FrameImages {
    /// The handle of `output`, if it has a device buffer.
    pub fn get(&self, output: Output) -> Option<ImageBuf> {
        match output {
            Output::Composite => self.composite,
            Output::Direct => self.direct,
            Output::RawCaustics => self.raw_caustics,
            Output::FilteredCaustics => self.filtered_caustics,
        }
    }
}

/// Progress of a frame's photon work.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    pub photons_done: u64,
    pub photons_total: u64,
}

/// What a frame's kernels are parameterised with, derived from the scene and settings
/// before any work: each light's emission domain (or why it emits nothing), the
/// fixed-point quanta and the gather's hit-distance clamp. [`Sspm`] records its kernels
/// with these; tests that drive single kernels build the same parameters from them.
#[derive(Clone, Debug)]
pub struct FrameConstants {
    /// (light index, emission domain) of every light that emits photons.
    pub domains: Vec<(u32, EmissionDomain)>,
    /// Lights that emit no photons, and why.
    pub skipped_lights: Vec<(u32, NoEmission)>,
    /// Lights in `domains` that emit their whole domain only because pruning is off.
    pub unpruned: Vec<u32>,
    /// Flux of the brightest photon the frame can store (W, one channel): the largest
    /// per-photon emitted flux, x3 when a dispersive material can concentrate a photon
    /// into one channel.
    pub max_photon_flux: f32,
    /// Flux per fixed-point unit (W), a power of two: the brightest photon of the frame
    /// (x3 when a dispersive material can concentrate a photon into one channel) is
    /// 2^24 to 2^25 units.
    pub flux_quantum: f32,
    /// Hit distance per fixed-point unit (scene units), a power of two: the scene diagonal
    /// is 2^24 to 2^25 units.
    pub hit_distance_quantum: f32,
    /// Clamp of the gather's hit distance (scene units; defaults 5% and 50% of the scene
    /// diagonal).
    pub hit_distance_min: f32,
    pub hit_distance_max: f32,
}

impl FrameConstants {
    pub fn new(scene: &Scene, ds: &DeviceScene, settings: &SspmSettings) -> FrameConstants {
        let mut domains = Vec::new();
        let mut skipped_lights = Vec::new();
        let mut unpruned = Vec::new();
        for (i, l) in scene.lights.iter().enumerate() {
            let i = i as u32;
            match emission_domain(l, ds.caster_bounds, ds.bounds, settings.point_emission) {
                Ok(domain) => domains.push((i, domain)),
                Err(why) => match unpruned_domain(l, ds.bounds).filter(|_| !settings.prune) {
                    Some(domain) => {
                        domains.push((i, domain));
                        unpruned.push(i);
                    }
                    None => skipped_lights.push((i, why)),
                },
            }
        }
        let photons_per_light = settings.photons_w as f32 * settings.photons_h as f32;
        let dispersion_gain = if ds.has_dispersion { 3.0 } else { 1.0 };
        // Lights that emit only because pruning is off store no photon (that is why the
        // plan prunes them), so the quantum ignores them and stays the pruned frame's:
        // pruning on and off give the same fixed-point sums.
        let max_photon_flux = domains
            .iter()
            .filter(|(i, _)| !unpruned.contains(i))
            .map(|(_, d)| d.flux.max_element() / photons_per_light)
            .fold(0.0f32, f32::max)
            * dispersion_gain;
        let flux_quantum = power_of_two_quantum(max_photon_flux);
        let diag = ds.bounds.diagonal().max(f32::MIN_POSITIVE);
        let hit_distance_min = settings.hit_distance_min.unwrap_or(0.05 * diag);
        FrameConstants {
            domains,
            skipped_lights,
            unpruned,
            max_photon_flux,
            flux_quantum,
            hit_distance_quantum: power_of_two_quantum(diag),
            hit_distance_min,
            hit_distance_max: settings
                .hit_distance_max
                .unwrap_or(0.5 * diag)
                .max(hit_distance_min),
        }
    }

    /// `trace_photons` parameters for photons `first .. first + count` of light `light`
    /// with emission domain `d`: the light's seed is the frame seed hashed with its index.
    pub fn trace_params(
        &self,
        settings: &SspmSettings,
        light: u32,
        d: &EmissionDomain,
        first: u32,
        count: u32,
    ) -> TraceParams {
        d.trace_params(
            light,
            (settings.photons_w, settings.photons_h),
            (first, count),
            settings.seed ^ pcg_hash(light.wrapping_add(0x6c62_272e)),
            settings.max_bounces,
            settings.min_relative_power,
            self.flux_quantum,
        )
    }

    /// `deposit_screen` / `resolve_caustics` parameters.
    pub fn deposit_params(
        &self,
        camera: GpuCamera,
        settings: &SspmSettings,
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

    /// `tile_hit_distance` / `bilateral_gather` parameters (`axis` 0: horizontal pass).
    pub fn gather_params(
        &self,
        camera: GpuCamera,
        settings: &SspmSettings,
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
            _pad: [0; 3],
        }
    }

    /// `direct_light` parameters.
    pub fn direct_params(
        camera: GpuCamera,
        light_count: u32,
        settings: &SspmSettings,
    ) -> DirectParams {
        DirectParams {
            camera,
            light_count,
            max_specular_depth: settings.max_specular_depth,
            min_weight: 1e-3,
            _pad: 0,
        }
    }
}

/// Device buffers of the photon passes (exist only when some light emits photons).
#[derive(Clone, Copy, Debug)]
struct PhotonBuffers {
    photons: Buf<Photon>,
    photon_count: Buf<u32>,
    photon_map: Buf<DepositTexel>,
    counters: Buf<u32>,
}

/// Device buffers of the gather (exist only when filtered caustics are needed).
#[derive(Clone, Copy, Debug)]
struct GatherBuffers {
    tiles: Buf<f32>,
    scratch: ImageBuf,
}

/// Screen-space photon mapping on one backend, for one scene.
pub struct Sspm {
    settings: SspmSettings,
    scene: SceneArgs,
    camera: GpuCamera,
    light_count: u32,
    constants: FrameConstants,
    plan: FramePlan,
    gbuffer: Buf<GBufferTexel>,
    photon: Option<PhotonBuffers>,
    gather: Option<GatherBuffers>,
    images: FrameImages,
    /// Every image buffer the plan created, by [`Output`], requested or not.
    image_buffers: [Option<ImageBuf>; 4],
    /// Every buffer this technique created (freed by [`Sspm::free`]).
    owned: Vec<ResourceId>,
    bytes: u64,
    reference: Option<Image>,
}

impl Sspm {
    /// Validates the scene and settings, plans the frame ([`crate::plan`]), uploads the
    /// scene and creates the buffers the plan needs.
    pub fn new(
        backend: &mut dyn Backend,
        scene: &Scene,
        settings: SspmSettings,
    ) -> Result<Sspm, Error> {
        settings.validate()?;
        scene
            .validate()
            .map_err(|p| Error::InvalidScene(format!("{}: {}", p[0].path, p[0].reason)))?;
        let ds = DeviceScene::build(scene);
        let mut rec = Recording::new();
        let scene_args = ds.record_upload(&mut rec);

        let constants = FrameConstants::new(scene, &ds, &settings);
        let mut plan = FramePlan::new(scene, &constants, settings.outputs, settings.prune);
        let needs = plan.needs();
        let out = settings.outputs;
        let keep = |requested: bool| requested || !settings.prune;

        let camera = GpuCamera::from_camera(&scene.camera);
        let (w, h) = (camera.width, camera.height);
        let pixels = w * h;
        let gbuffer = rec.create(pixels, "gbuffer");
        let direct = needs
            .direct_light
            .then(|| rec.create(pixels, "direct image"));
        let photon = needs.photons.then(|| {
            let per_light = settings.photons_w as u64 * settings.photons_h as u64;
            let cap = per_light.min(settings.max_photons_per_batch as u64) as u32;
            PhotonBuffers {
                photons: rec.create(cap, "photons"),
                photon_count: rec.create(1, "photon count"),
                photon_map: rec.create(pixels, "screen photon map"),
                counters: rec.create(counter::WORDS as u32, "photon counters"),
            }
        });
        let raw_caustics = needs
            .photons
            .then(|| rec.create(pixels, "raw caustics image"));
        let gather = needs.gather.then(|| GatherBuffers {
            tiles: rec.create(
                w.div_ceil(settings.tile_size) * h.div_ceil(settings.tile_size),
                "hit distance tiles",
            ),
            scratch: rec.create(pixels, "gather scratch image"),
        });
        let filtered_caustics = needs
            .gather
            .then(|| rec.create(pixels, "filtered caustics image"));
        let own_composite = needs
            .composite
            .then(|| rec.create(pixels, "composite image"));
        let composite = if own_composite.is_some() {
            own_composite
        } else if out.composite {
            direct // no caustics: the composite is the direct image
        } else {
            None
        };
        let images = FrameImages {
            width: w,
            height: h,
            composite,
            direct: direct.filter(|_| keep(out.direct)),
            raw_caustics: raw_caustics.filter(|_| keep(out.raw_caustics)),
            filtered_caustics: filtered_caustics.filter(|_| keep(out.filtered_caustics)),
        };
        let mut bytes = 0u64;
        let mut owned = Vec::new();
        // Every planned buffer must fit the device's largest buffer (and, on wgpu and
        // Vulkan, its largest storage binding): checked before any work, so that an
        // oversized frame is a typed error naming the buffer, never an invalid binding.
        let largest = backend.capabilities().max_buffer_bytes;
        for s in &rec.steps {
            let (id, b, label) = match s {
                Step::Create { id, bytes, label } => (*id, *bytes, *label),
                Step::Upload { id, data, label } => (*id, data.len() as u64, *label),
                _ => continue,
            };
            if b > largest {
                return Err(Error::Backend(crate::BackendError::OutOfMemory {
                    bytes: b,
                    what: format!(
                        "{label}: the {} backend's device binds at most {largest} bytes per buffer",
                        backend.name()
                    ),
                }));
            }
            bytes += b;
            owned.push(id);
            plan.buffers.push(crate::plan::BufferPlan {
                name: label.into(),
                bytes: b,
            });
        }
        backend.execute(&rec)?;
        Ok(Sspm {
            settings,
            scene: scene_args,
            camera,
            light_count: scene.lights.len() as u32,
            constants,
            plan,
            gbuffer,
            photon,
            gather,
            images,
            image_buffers: [own_composite, direct, raw_caustics, filtered_caustics],
            owned,
            bytes,
            reference: None,
        })
    }

    /// The frame plan: passes run and skipped with reasons, the photon kernel's variant,
    /// the lights that emit, the buffers created.
    pub fn plan(&self) -> &FramePlan {
        &self.plan
    }

    /// Sets the frame seed of the next frames (progressive rendering, repeated
    /// measurements); nothing else of the settings can change after `new`.
    pub fn set_seed(&mut self, seed: u32) {
        self.settings.seed = seed;
    }

    pub fn settings(&self) -> &SspmSettings {
        &self.settings
    }

    /// The frame's device images.
    pub fn images(&self) -> FrameImages {
        self.images
    }

    /// The G-buffer handle (for conformance and embedding).
    pub fn gbuffer(&self) -> Buf<GBufferTexel> {
        self.gbuffer
    }

    /// The stored-photon buffer and its count (absent when no light emits photons). After
    /// a frame they hold the last batch.
    pub fn photon_buffers(&self) -> Option<(Buf<Photon>, Buf<u32>)> {
        self.photon.map(|p| (p.photons, p.photon_count))
    }

    /// Renders one frame: the planned passes, nothing else. `progress` is called after
    /// every photon batch.
    pub fn frame(
        &mut self,
        backend: &mut dyn Backend,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<FrameStats, Error> {
        let start = Instant::now();
        let caps = backend.capabilities();
        let mut stats = FrameStats {
            technique: "sspm".into(),
            backend: backend.name().into(),
            device: caps.device.clone(),
            width: self.camera.width,
            height: self.camera.height,
            timing: if caps.timestamps {
                "device timestamps".into()
            } else {
                "host wall clock".into()
            },
            flux_quantum: self.constants.flux_quantum as f64,
            bytes_allocated: self.bytes,
            plan: Some(self.plan.clone()),
            ..Default::default()
        };
        for p in self.plan.passes.iter().filter(|p| !p.runs) {
            stats.skip(&p.name, p.reason.clone());
        }
        let cam = self.camera;

        // 1. visibility and direct light
        let mut rec = Recording::new();
        rec.kernel(Kernel::PrimaryGbuffer {
            scene: self.scene,
            camera: cam,
            gbuffer: self.gbuffer,
        });
        if let Some(direct) = self.direct_image() {
            rec.kernel(Kernel::DirectLight {
                scene: self.scene,
                params: FrameConstants::direct_params(cam, self.light_count, &self.settings),
                gbuffer: self.gbuffer,
                out: direct,
            });
        }
        if let Some(p) = self.photon {
            rec.clear(p.photon_map);
            rec.clear(p.counters);
        }
        self.run(backend, &rec, &mut stats)?;

        // 2. photons, per emitting light, in batches
        if let (Some(p), Some(variant)) = (self.photon, self.plan.trace_variant) {
            stats.variants.push(crate::kernels::variant_label(
                "trace_photons",
                &variant.constants(),
            ));
            let deposit_params = self
                .constants
                .deposit_params(cam, &self.settings, p.photons.len);
            let per_light = self.settings.photons_w as u64 * self.settings.photons_h as u64;
            let total = per_light * self.constants.domains.len() as u64;
            let mut done = 0u64;
            for (light, d) in &self.constants.domains {
                stats.photons_emitted += per_light;
                for c in 0..3 {
                    stats.emitted_flux[c] += d.flux[c] as f64;
                }
                let mut first = 0u64;
                while first < per_light {
                    let count = (per_light - first).min(p.photons.len as u64) as u32;
                    let mut rec = Recording::new();
                    rec.clear(p.photon_count);
                    rec.kernel(Kernel::TracePhotons {
                        scene: self.scene,
                        variant,
                        params: self.constants.trace_params(
                            &self.settings,
                            *light,
                            d,
                            first as u32,
                            count,
                        ),
                        photons: p.photons,
                        photon_count: p.photon_count,
                        counters: p.counters,
                    });
                    rec.kernel(Kernel::DepositScreen {
                        params: deposit_params,
                        gbuffer: self.gbuffer,
                        photons: p.photons,
                        photon_count: p.photon_count,
                        counters: p.counters,
                        photon_map: p.photon_map,
                    });
                    self.run(backend, &rec, &mut stats)?;
                    stats.batches += 1;
                    first += count as u64;
                    done += count as u64;
                    progress(Progress {
                        photons_done: done,
                        photons_total: total,
                    });
                }
            }

            // 3. resolve, gather, composite
            let mut rec = Recording::new();
            let raw = self.raw_image().expect("planned with the photon passes");
            rec.kernel(Kernel::ResolveCaustics {
                params: deposit_params,
                gbuffer: self.gbuffer,
                photon_map: p.photon_map,
                out: raw,
            });
            if let (Some(g), Some(filtered)) = (self.gather, self.filtered_image()) {
                let gather = self.constants.gather_params(cam, &self.settings, 0);
                rec.kernel(Kernel::TileHitDistance {
                    params: gather,
                    photon_map: p.photon_map,
                    tiles: g.tiles,
                });
                rec.kernel(Kernel::BilateralGather {
                    params: gather,
                    gbuffer: self.gbuffer,
                    tiles: g.tiles,
                    input: raw,
                    out: g.scratch,
                });
                rec.kernel(Kernel::BilateralGather {
                    params: GatherParams { axis: 1, ..gather },
                    gbuffer: self.gbuffer,
                    tiles: g.tiles,
                    input: g.scratch,
                    out: filtered,
                });
                if let (true, Some(direct), Some(out)) = (
                    self.plan.needs().composite,
                    self.direct_image(),
                    self.images.composite,
                ) {
                    rec.kernel(Kernel::Composite {
                        direct,
                        caustics: filtered,
                        out,
                    });
                }
            }
            self.run(backend, &rec, &mut stats)?;

            // 4. counters
            let c = read_buf(backend, p.counters)?;
            let c64 = |i: usize| join_u64([c[i], c[i + 1]]);
            stats.photons_stored = c[counter::STORED] as u64;
            stats.photons_deposited = c[counter::DEPOSITED] as u64;
            stats.discarded.no_specular = c[counter::NO_SPECULAR] as u64;
            stats.discarded.escaped = c[counter::ESCAPED] as u64;
            stats.discarded.negligible_power = c[counter::NEGLIGIBLE] as u64;
            stats.discarded.bounce_limit = c[counter::BOUNCE_LIMIT] as u64;
            stats.discarded.off_screen = c[counter::OFF_SCREEN] as u64;
            stats.discarded.depth_mismatch = c[counter::DEPTH_MISMATCH] as u64;
            stats.fixed_point_underflow = c[counter::UNDERFLOW] as u64;
            stats.fixed_point_saturated = c[counter::SATURATED] as u64;
            stats.photon_rays_traced = c64(counter::RAYS);
            for ch in 0..3 {
                stats.stored_flux[ch] =
                    c64(counter::STORED_FLUX + 2 * ch) as f64 * self.constants.flux_quantum as f64;
            }
        }
        stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        if let Some(r) = &self.reference {
            let filtered = self.read_output(backend, Output::FilteredCaustics)?;
            stats.error = Some(crate::metrics::compare(&filtered, r));
        }
        Ok(stats)
    }

    /// The direct-light image buffer (also when only the composite needs it).
    fn direct_image(&self) -> Option<ImageBuf> {
        self.internal(Output::Direct)
    }

    fn raw_image(&self) -> Option<ImageBuf> {
        self.internal(Output::RawCaustics)
    }

    fn filtered_image(&self) -> Option<ImageBuf> {
        self.internal(Output::FilteredCaustics)
    }

    /// An image's buffer whether or not the caller asked for it (the composite needs the
    /// direct and filtered images): recovered from the buffers the plan created.
    fn internal(&self, output: Output) -> Option<ImageBuf> {
        self.image_buffers[output as usize]
    }

    fn run(
        &self,
        backend: &mut dyn Backend,
        rec: &Recording,
        stats: &mut FrameStats,
    ) -> Result<(), Error> {
        for t in backend.execute(rec)? {
            stats.add_pass_time(t.kernel, t.seconds);
        }
        Ok(())
    }

    /// Sets (or clears) the reference image of the caustics (linear radiance, the frame's
    /// size): every later [`Sspm::frame`] reads its filtered caustics back and puts their
    /// error against it in [`FrameStats::error`].
    pub fn set_reference(&mut self, reference: Option<Image>) -> Result<(), Error> {
        if let Some(r) = &reference {
            if (r.width, r.height) != (self.images.width, self.images.height) {
                return Err(Error::InvalidParameter(format!(
                    "reference is {}x{}, the frame {}x{}",
                    r.width, r.height, self.images.width, self.images.height
                )));
            }
        }
        self.reference = reference;
        Ok(())
    }

    /// Reads a device image back to the host.
    pub fn read_image(&self, backend: &mut dyn Backend, image: ImageBuf) -> Result<Image, Error> {
        let px = read_buf(backend, image)?;
        Ok(Image::new(self.images.width, self.images.height, px))
    }

    /// Reads one of the frame's outputs back. An output the plan knows to be zero (no
    /// light emits photons) has no device buffer and reads as zeros; one that was not
    /// requested in [`SspmSettings::outputs`] is an error.
    pub fn read_output(&self, backend: &mut dyn Backend, output: Output) -> Result<Image, Error> {
        if !output.requested(&self.settings.outputs) {
            return Err(Error::InvalidParameter(format!(
                "output '{}' was not requested (SspmSettings::outputs)",
                output.stem()
            )));
        }
        match self.images.get(output) {
            Some(h) => self.read_image(backend, h),
            None => Ok(Image::new(
                self.images.width,
                self.images.height,
                vec![[0.0; 4]; self.images.width as usize * self.images.height as usize],
            )),
        }
    }

    /// Releases every device buffer of this technique.
    pub fn free(self, backend: &mut dyn Backend) -> Result<(), Error> {
        let mut rec = Recording::new();
        for id in self.owned {
            rec.steps.push(Step::Free { id });
        }
        backend.execute(&rec)?;
        Ok(())
    }
}

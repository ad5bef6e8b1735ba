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
use crate::emission::{emission_domain, EmissionDomain, NoEmission, PointEmission};
use crate::fixed_point::{join_u64, power_of_two_quantum};
use crate::gpu::*;
use crate::image::Image;
use crate::recording::{Buf, ImageBuf, Kernel, Recording, SceneArgs};
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

/// Device images of a frame (handles; read them with [`Sspm::read_image`]).
#[derive(Clone, Copy, Debug)]
pub struct FrameImages {
    pub width: u32,
    pub height: u32,
    /// Direct light + filtered caustics.
    pub composite: ImageBuf,
    /// Direct light only (shadow rays, specular chains from mirror/glass pixels).
    pub direct: ImageBuf,
    /// Caustic radiance straight from the photon map (alpha: mean hit distance).
    pub raw_caustics: ImageBuf,
    /// Caustic radiance after the bilateral gather.
    pub filtered_caustics: ImageBuf,
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
        for (i, l) in scene.lights.iter().enumerate() {
            match emission_domain(l, ds.caster_bounds, ds.bounds, settings.point_emission) {
                Ok(domain) => domains.push((i as u32, domain)),
                Err(why) => skipped_lights.push((i as u32, why)),
            }
        }
        let photons_per_light = settings.photons_w as f32 * settings.photons_h as f32;
        let dispersion_gain = if ds.has_dispersion { 3.0 } else { 1.0 };
        let max_photon_flux = domains
            .iter()
            .map(|(_, d)| d.flux.max_element() / photons_per_light)
            .fold(0.0f32, f32::max)
            * dispersion_gain;
        let flux_quantum = power_of_two_quantum(max_photon_flux);
        let diag = ds.bounds.diagonal().max(f32::MIN_POSITIVE);
        let hit_distance_min = settings.hit_distance_min.unwrap_or(0.05 * diag);
        FrameConstants {
            domains,
            skipped_lights,
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

/// Screen-space photon mapping on one backend, for one scene.
pub struct Sspm {
    settings: SspmSettings,
    scene: SceneArgs,
    camera: GpuCamera,
    light_count: u32,
    constants: FrameConstants,
    gbuffer: Buf<GBufferTexel>,
    photon_map: Buf<DepositTexel>,
    photons: Option<(Buf<Photon>, Buf<u32>)>,
    counters: Buf<u32>,
    tiles: Buf<f32>,
    scratch: ImageBuf,
    images: FrameImages,
    bytes: u64,
    reference: Option<Image>,
}

impl Sspm {
    /// Validates the scene and settings, uploads the scene and creates the frame buffers.
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
        let photons_per_light = settings.photons_w as f32 * settings.photons_h as f32;

        let camera = GpuCamera::from_camera(&scene.camera);
        let (w, h) = (camera.width, camera.height);
        let pixels = w * h;
        let tiles_len = w.div_ceil(settings.tile_size) * h.div_ceil(settings.tile_size);
        let gbuffer = rec.create(pixels, "gbuffer");
        let photon_map = rec.create(pixels, "screen photon map");
        let counters = rec.create(counter::WORDS as u32, "photon counters");
        let tiles = rec.create(tiles_len, "hit distance tiles");
        let scratch = rec.create(pixels, "gather scratch");
        let images = FrameImages {
            width: w,
            height: h,
            composite: rec.create(pixels, "composite"),
            direct: rec.create(pixels, "direct"),
            raw_caustics: rec.create(pixels, "raw caustics"),
            filtered_caustics: rec.create(pixels, "filtered caustics"),
        };
        // The photon buffer exists only when some light emits photons.
        let photons = if constants.domains.is_empty() {
            None
        } else {
            let total = photons_per_light as u64;
            let cap = total.min(settings.max_photons_per_batch as u64) as u32;
            Some((rec.create(cap, "photons"), rec.create(1, "photon count")))
        };
        let mut bytes = 0u64;
        for s in &rec.steps {
            match s {
                crate::recording::Step::Create { bytes: b, .. } => bytes += b,
                crate::recording::Step::Upload { data, .. } => bytes += data.len() as u64,
                _ => {}
            }
        }
        backend.execute(&rec)?;
        Ok(Sspm {
            settings,
            scene: scene_args,
            camera,
            light_count: scene.lights.len() as u32,
            constants,
            gbuffer,
            photon_map,
            photons,
            counters,
            tiles,
            scratch,
            images,
            bytes,
            reference: None,
        })
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
        self.photons
    }

    /// Renders one frame. `progress` is called after every photon batch.
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
            ..Default::default()
        };
        let cam = self.camera;
        let deposit_params =
            self.constants
                .deposit_params(cam, &self.settings, self.photons.map_or(0, |p| p.0.len));

        // 1. visibility and direct light
        let mut rec = Recording::new();
        rec.kernel(Kernel::PrimaryGbuffer {
            scene: self.scene,
            camera: cam,
            gbuffer: self.gbuffer,
        });
        rec.kernel(Kernel::DirectLight {
            scene: self.scene,
            params: FrameConstants::direct_params(cam, self.light_count, &self.settings),
            gbuffer: self.gbuffer,
            out: self.images.direct,
        });
        rec.clear(self.photon_map);
        rec.clear(self.counters);
        self.run(backend, &rec, &mut stats)?;

        // 2. photons, in batches
        for (light, why) in &self.constants.skipped_lights {
            let reason = match why {
                NoEmission::NoCasters => "no specular surface (caustic caster) in the scene",
                NoEmission::ZeroPower => "light has zero power",
            };
            stats.skip(&format!("trace_photons[light {light}]"), reason);
        }
        let per_light = self.settings.photons_w as u64 * self.settings.photons_h as u64;
        let total = per_light * self.constants.domains.len() as u64;
        let mut done = 0u64;
        if let Some((photons, photon_count)) = self.photons {
            for (light, d) in &self.constants.domains {
                stats.photons_emitted += per_light;
                for c in 0..3 {
                    stats.emitted_flux[c] += d.flux[c] as f64;
                }
                let mut first = 0u64;
                while first < per_light {
                    let count = (per_light - first).min(photons.len as u64) as u32;
                    let mut rec = Recording::new();
                    rec.clear(photon_count);
                    rec.kernel(Kernel::TracePhotons {
                        scene: self.scene,
                        params: self.constants.trace_params(
                            &self.settings,
                            *light,
                            d,
                            first as u32,
                            count,
                        ),
                        photons,
                        photon_count,
                        counters: self.counters,
                    });
                    rec.kernel(Kernel::DepositScreen {
                        params: deposit_params,
                        gbuffer: self.gbuffer,
                        photons,
                        photon_count,
                        counters: self.counters,
                        photon_map: self.photon_map,
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
        }

        // 3. resolve, gather, composite
        let mut rec = Recording::new();
        let gather = self.constants.gather_params(cam, &self.settings, 0);
        if self.photons.is_some() {
            rec.kernel(Kernel::ResolveCaustics {
                params: deposit_params,
                gbuffer: self.gbuffer,
                photon_map: self.photon_map,
                out: self.images.raw_caustics,
            });
            rec.kernel(Kernel::TileHitDistance {
                params: gather,
                photon_map: self.photon_map,
                tiles: self.tiles,
            });
            rec.kernel(Kernel::BilateralGather {
                params: gather,
                gbuffer: self.gbuffer,
                tiles: self.tiles,
                input: self.images.raw_caustics,
                out: self.scratch,
            });
            rec.kernel(Kernel::BilateralGather {
                params: GatherParams { axis: 1, ..gather },
                gbuffer: self.gbuffer,
                tiles: self.tiles,
                input: self.scratch,
                out: self.images.filtered_caustics,
            });
        } else {
            for pass in [
                "deposit_screen",
                "resolve_caustics",
                "tile_hit_distance",
                "bilateral_gather",
            ] {
                stats.skip(pass, "no light emits photons");
            }
            rec.clear(self.images.raw_caustics);
            rec.clear(self.images.filtered_caustics);
        }
        rec.kernel(Kernel::Composite {
            direct: self.images.direct,
            caustics: self.images.filtered_caustics,
            out: self.images.composite,
        });
        self.run(backend, &rec, &mut stats)?;

        // 4. counters
        let c = read_buf(backend, self.counters)?;
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
        stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        if let Some(r) = &self.reference {
            let filtered = self.read_image(backend, self.images.filtered_caustics)?;
            stats.error = Some(crate::metrics::compare(&filtered, r));
        }
        Ok(stats)
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

    /// Reads one of the frame's images back to the host.
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

    pub fn read_image(&self, backend: &mut dyn Backend, image: ImageBuf) -> Result<Image, Error> {
        let px = read_buf(backend, image)?;
        Ok(Image::new(self.images.width, self.images.height, px))
    }

    /// Releases every device buffer of this technique.
    pub fn free(self, backend: &mut dyn Backend) -> Result<(), Error> {
        let mut rec = Recording::new();
        let s = self.scene;
        rec.free(s.vertices);
        rec.free(s.triangles);
        rec.free(s.materials);
        rec.free(s.lights);
        rec.free(s.bvh_nodes);
        rec.free(self.gbuffer);
        rec.free(self.photon_map);
        rec.free(self.counters);
        rec.free(self.tiles);
        rec.free(self.scratch);
        for img in [
            self.images.composite,
            self.images.direct,
            self.images.raw_caustics,
            self.images.filtered_caustics,
        ] {
            rec.free(img);
        }
        if let Some((p, c)) = self.photons {
            rec.free(p);
            rec.free(c);
        }
        backend.execute(&rec)?;
        Ok(())
    }
}

//! PhotonGi (seed 003: Smal and Aizenshtein, "Real-Time Global Illumination with Photon
//! Mapping", Ray Tracing Gems ch. 24): multi-bounce indirect light by photon splatting.
//! One frame:
//!
//! 1. `primary_gbuffer` and `direct_light` from the camera;
//! 2. per light with photons (allocated over the lights by power,
//!    [`crate::math::photon_allocation`], leaving out a light whose RSM sees no texel
//!    that leaves flux: `PhotonGi::probe_rsms`, at creation and on updates): per RSM face
//!    `primary_gbuffer` from the light and `rsm_importance` level 0, the pyramid's
//!    levels, then `sample_rsm` (section 24.2.1) and `trace_indirect` (24.2.2: roulette,
//!    photons stored after the first bounce, culled to the view, counted per screen tile);
//! 3. `splat_photons` (24.3) into the screen photon map (and, for Eq. 20, each splat's
//!    light direction into the direction map), `resolve_caustics` (irradiance times albedo
//!    / pi: the raw indirect light), `temporal_blend` and `atrous_filter` (24.4, each a
//!    setting);
//! 4. `shading_normal_correction` (24.4.3, Eq. 20) where the scene has vertex normals that
//!    depart from the geometric ones: the splats' power-weighted mean light direction
//!    against the shading normal instead of the geometric one; then `composite` with the
//!    direct light.

mod settings;

pub use settings::{IndirectEstimator, PhotonGiSettings, RsmSampling};

use crate::backend::{read_buf, Backend};
use crate::device::device_scene::{BuildBudget, DeviceScene, InstanceUpdate, SceneInstances};
use crate::device::handle::{Buf, GBufferPlanes, ImageBuf, PhotonMapPlanes, ResourceId, SceneArgs};
use crate::device::layout::*;
use crate::frame::allocation::planned_allocation;
use crate::frame::error::Error;
use crate::frame::image::Image;
use crate::frame::irradiance_passes::{
    record_atrous, record_temporal_blend, AtrousScratch, History,
};
use crate::frame::plan::{FramePlan, LightPlan, PassPlan, SceneFeatures};
use crate::frame::stats::FrameStats;
use crate::frame::submitted::RecordedFrame;
use crate::frame::technique::{OutputInfo, Progress, Technique};
use crate::frame::temporal::PingPong;
use crate::kernels::{
    Composite, DepositScreen, DirectLight, PrimaryGbuffer, ResolveCaustics, RsmImportance,
    SampleRsm, ShadingNormalCorrection, SplatPhotons, TraceIndirect,
};

/// Eq. 20's `epsilon`: keeps the factor finite where the mean light direction grazes the
/// geometric normal (there `s_max` bounds it anyway).
pub const SHADING_EPSILON: f32 = 1e-4;
use crate::math::gi_photon::{gi_store, screen_tiles};
use crate::math::rsm::{level_count, level_offset, luminance, pyramid_len};
use crate::recording::{Recording, Step};
use crate::scene::Scene;
use glam::Vec3;
use std::time::Instant;

/// The outputs, in order: name and what it holds (linear radiance, W/(sr m^2)).
pub const OUTPUTS: [(&str, &str); 4] = [
    ("composite", "direct light plus the filtered indirect light"),
    ("direct", "direct light (with specular chains)"),
    (
        "indirect_raw",
        "indirect light from the splats alone (no temporal or A-Trous filter)",
    ),
    (
        "indirect",
        "indirect light after the temporal and A-Trous filters",
    ),
];

/// A light's reflective shadow map: its face cameras and its photons this frame.
#[derive(Clone, Debug, PartialEq)]
pub struct LightRsm {
    /// Index of the light.
    pub light: u32,
    /// One pinhole per face (the light's position, `rsm_size` square).
    pub faces: Vec<GpuCamera>,
    /// Initial photons of this light per frame.
    pub photons: u32,
    /// False when the light's RSM sees no texel that leaves flux (every texel's flux x
    /// albedo is zero: it looks into empty space or onto black surfaces), so that none of
    /// its photons could carry any: it gets no photon, the others share its budget.
    pub sees: bool,
}

/// The faces of a light's RSM (see `crate::math::rsm`): six 90-degree faces around a
/// point light, one face over a spot's outer cone below 60 degrees (six above), one
/// orthographic face over the bounding sphere of `bounds` for a directional light.
pub fn rsm_faces(
    light: &GpuLight,
    side: u32,
    bounds: &crate::math::geometry::Aabb,
) -> Vec<GpuCamera> {
    let pos = Vec3::from_slice(&light.position[..3]);
    let face = |forward: Vec3, up_hint: Vec3, tan: f32| {
        let right = forward.cross(up_hint).normalize();
        let up = right.cross(forward);
        GpuCamera {
            position: pos.to_array(),
            tan_half_fov_x: tan,
            forward: forward.to_array(),
            tan_half_fov_y: tan,
            right: right.to_array(),
            width: side,
            up: up.to_array(),
            height: side,
        }
    };
    let cube = || {
        [
            (Vec3::X, Vec3::Y),
            (Vec3::NEG_X, Vec3::Y),
            (Vec3::Y, Vec3::Z),
            (Vec3::NEG_Y, Vec3::Z),
            (Vec3::Z, Vec3::Y),
            (Vec3::NEG_Z, Vec3::Y),
        ]
        .into_iter()
        .map(|(f, u)| face(f, u, 1.0))
        .collect()
    };
    match light.kind {
        light_kind::POINT => cube(),
        light_kind::SPOT => {
            let cos = light.cos_outer.clamp(-1.0, 1.0);
            if cos > 0.5 {
                let axis = Vec3::from_slice(&light.direction[..3]).normalize();
                let hint = if axis.y.abs() < 0.9 { Vec3::Y } else { Vec3::X };
                let tan = (1.0 - cos * cos).sqrt() / cos;
                vec![face(axis, hint, tan)]
            } else {
                cube()
            }
        }
        _ => {
            let forward = Vec3::from_slice(&light.direction[..3]).normalize();
            let hint = if forward.y.abs() < 0.9 {
                Vec3::Y
            } else {
                Vec3::X
            };
            let right = forward.cross(hint).normalize();
            let up = right.cross(forward);
            let centre = 0.5 * (bounds.min + bounds.max);
            let radius = (0.5 * (bounds.max - bounds.min).length()).max(f32::MIN_POSITIVE);
            vec![GpuCamera::orthographic(
                centre - 2.0 * radius * forward,
                forward,
                right,
                up,
                (radius, radius),
                (side, side),
            )]
        }
    }
}

/// A light's power for the allocation (003 section 24.2): the luminance of its
/// intensity times the solid angle it emits into (W).
fn light_power(l: &GpuLight) -> f64 {
    let i = luminance(Vec3::from_slice(&l.intensity[..3])).max(0.0) as f64;
    let omega = if l.kind == light_kind::SPOT {
        crate::math::sampling::cone_solid_angle(l.cos_outer) as f64
    } else {
        4.0 * std::f64::consts::PI
    };
    i * omega
}

/// The lights' RSMs and photon counts for `total` initial photons (allocated by power,
/// 003 section 24.2, over the lights whose RSM sees something: `sees`, one flag per
/// light, all true when not yet known), the unit of the packed photon power (the mean
/// emitted photon power, W) and the photon map's flux quantum (W).
fn plan_lights(
    lights: &[GpuLight],
    total: u64,
    side: u32,
    bounds: &crate::math::geometry::Aabb,
    sees: &[bool],
) -> (Vec<LightRsm>, f32, f32) {
    let sees_at = |i: usize| sees.get(i).copied().unwrap_or(true);
    let powers: Vec<f64> = lights
        .iter()
        .enumerate()
        .map(|(i, l)| if sees_at(i) { light_power(l) } else { 0.0 })
        .collect();
    let counts = crate::math::photon_allocation::allocate_photons(total, &powers);
    let rsms = lights
        .iter()
        .zip(&counts)
        .enumerate()
        .map(|(i, (l, &n))| LightRsm {
            light: i as u32,
            faces: rsm_faces(l, side, bounds),
            photons: n as u32,
            sees: sees_at(i),
        })
        .collect();
    let emitted: f64 = powers.iter().sum();
    let power_scale = ((emitted / total as f64) as f32).max(f32::MIN_POSITIVE);
    // a splat's share of a photon is at least 2^-20 of it in any pixel it reaches
    let flux_quantum = power_scale * (1.0 / 1_048_576.0);
    (rsms, power_scale, flux_quantum)
}

/// Whether Eq. 20's shading-normal correction runs: the setting, the splat estimator
/// (the raw deposit has no splats to carry a direction), and a scene where some
/// triangle's vertex normals depart from its geometric normal (elsewhere the shading and
/// geometric normals agree and the factor is 1 up to `eps`:
/// [`crate::device::device_scene::smooth_normals`]).
fn shading_correction(s: &PhotonGiSettings, instances: &SceneInstances) -> bool {
    s.shading_normals
        && s.estimator == IndirectEstimator::Splat
        && instances.smooth_normals().unwrap_or(true)
}

/// The length of the scene box's diagonal (scene units; at least the smallest positive
/// f32).
fn scene_diagonal(b: &crate::math::geometry::Aabb) -> f32 {
    (b.max - b.min).length().max(f32::MIN_POSITIVE)
}

/// Device buffers of the frame.
#[derive(Clone, Copy, Debug)]
struct Buffers {
    gbuffer: GBufferPlanes,
    direct: ImageBuf,
    rsm_gbuffer: GBufferPlanes,
    rsm_texels: Buf<RsmTexel>,
    pyramid: Buf<f32>,
    rsm_photons: Buf<RsmPhoton>,
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
    composite: ImageBuf,
    temporal: Option<TemporalBuffers>,
    atrous: Option<AtrousBuffers>,
}

/// The buffers whose size follows the image's (remade at a new image size).
#[derive(Clone, Copy, Debug)]
struct ScreenBuffers {
    gbuffer: GBufferPlanes,
    direct: ImageBuf,
    tile_counts: Buf<u32>,
    photon_map: PhotonMapPlanes,
    direction_map: PhotonMapPlanes,
    raw: ImageBuf,
    uncorrected: Option<ImageBuf>,
    indirect: ImageBuf,
    composite: ImageBuf,
    temporal: Option<TemporalBuffers>,
    atrous: Option<AtrousBuffers>,
}

impl ScreenBuffers {
    /// Records the creation of the per-pixel buffers for `camera`'s image (with Eq. 20's
    /// correction when `correct`).
    fn create(
        rec: &mut Recording,
        camera: GpuCamera,
        settings: &PhotonGiSettings,
        correct: bool,
    ) -> Self {
        let pixels = camera.width * camera.height;
        let temporal = settings.temporal.then(|| TemporalBuffers {
            image: PingPong::create(rec, pixels, "temporal indirect history"),
            edge: PingPong::create(rec, pixels, "temporal edge history"),
            previous: camera,
        });
        let atrous = (settings.atrous_iterations > 0).then(|| AtrousBuffers {
            input: rec.create(pixels, "A-Trous input image"),
            a: rec.create(pixels, "A-Trous image a"),
            b: rec.create(pixels, "A-Trous image b"),
            details: rec.create(pixels, "A-Trous clipped details"),
        });
        let raw = rec.create(pixels, "raw indirect image");
        let filtered = temporal.is_some() || atrous.is_some();
        ScreenBuffers {
            gbuffer: rec.create_gbuffer(pixels),
            direct: rec.create(pixels, "direct image"),
            tile_counts: rec.create(
                screen_tiles(camera.width, camera.height, settings.tile_size),
                "photons per screen tile",
            ),
            photon_map: rec.create_photon_map(pixels),
            direction_map: rec.create_photon_map(if correct { pixels } else { 1 }),
            raw,
            uncorrected: (correct && filtered)
                .then(|| rec.create(pixels, "uncorrected indirect image"))
                .or(correct.then_some(raw)),
            indirect: if filtered || correct {
                rec.create(pixels, "indirect image")
            } else {
                raw
            },
            composite: rec.create(pixels, "composite image"),
            temporal,
            atrous,
        }
    }
}

impl Buffers {
    /// The ids of the per-pixel buffers (`indirect` once where it is `raw`).
    /// Every frame buffer for `settings` (with room for any light's RSM and photons, so
    /// that lights can change without new buffers: six faces, every initial photon).
    fn create_all(
        rec: &mut Recording,
        camera: GpuCamera,
        settings: &PhotonGiSettings,
        correct: bool,
    ) -> Buffers {
        let side = settings.rsm_size;
        let total = settings.photons_w as u64 * settings.photons_h as u64;
        let max_faces = 6u32;
        let max_photons = total.min(u32::MAX as u64) as u32;
        let capacity = (total * settings.bounces as u64).min(u32::MAX as u64) as u32;
        let s = ScreenBuffers::create(rec, camera, settings, correct);
        Buffers {
            gbuffer: s.gbuffer,
            direct: s.direct,
            rsm_gbuffer: rec.create_gbuffer(side * side),
            rsm_texels: rec.create(max_faces * side * side, "RSM texels"),
            pyramid: rec.create(max_faces * pyramid_len(side), "RSM importance pyramid"),
            rsm_photons: rec.create(max_photons, "RSM photons"),
            photons: rec.create(capacity.max(1), "indirect photons"),
            photon_count: rec.create(1, "indirect photon count"),
            tile_counts: s.tile_counts,
            counters: rec.create(counter::WORDS as u32, "photon counters"),
            photon_map: s.photon_map,
            direction_map: s.direction_map,
            raw: s.raw,
            uncorrected: s.uncorrected,
            indirect: s.indirect,
            composite: s.composite,
            temporal: s.temporal,
            atrous: s.atrous,
        }
    }

    fn screen_ids(&self) -> Vec<ResourceId> {
        let mut ids: Vec<ResourceId> = self.gbuffer.planes.iter().map(|p| p.id).collect();
        ids.extend(self.photon_map.planes.iter().map(|p| p.id));
        ids.extend(self.direction_map.planes.iter().map(|p| p.id));
        if let Some(u) = self.uncorrected.filter(|u| u.id != self.raw.id) {
            ids.push(u.id);
        }
        ids.extend([
            self.direct.id,
            self.tile_counts.id,
            self.raw.id,
            self.composite.id,
        ]);
        if self.indirect.id != self.raw.id {
            ids.push(self.indirect.id);
        }
        if let Some(t) = &self.temporal {
            ids.extend(t.image.buffers().iter().map(|b| b.id));
            ids.extend(t.edge.buffers().iter().map(|b| b.id));
        }
        if let Some(a) = &self.atrous {
            ids.extend([a.input.id, a.a.id, a.b.id, a.details.id]);
        }
        ids
    }

    /// These buffers with the per-pixel ones replaced by `s`.
    fn with_screen(self, s: ScreenBuffers) -> Buffers {
        Buffers {
            gbuffer: s.gbuffer,
            direct: s.direct,
            tile_counts: s.tile_counts,
            photon_map: s.photon_map,
            direction_map: s.direction_map,
            raw: s.raw,
            uncorrected: s.uncorrected,
            indirect: s.indirect,
            composite: s.composite,
            temporal: s.temporal,
            atrous: s.atrous,
            ..self
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
    a: ImageBuf,
    b: ImageBuf,
    details: ImageBuf,
}

/// PhotonGi on one backend, for one scene.
pub struct PhotonGi {
    settings: PhotonGiSettings,
    scene: SceneArgs,
    model: Scene,
    camera: GpuCamera,
    lights: Vec<GpuLight>,
    /// Scene bounds (a directional light's orthographic face covers them).
    bounds: crate::math::geometry::Aabb,
    rsms: Vec<LightRsm>,
    /// Scene bounding-box diagonal (scene units): the splat constants scale with it.
    diagonal: f32,
    /// Unit of the packed photon power (W) and the photon map's flux quantum (W).
    power_scale: f32,
    flux_quantum: f32,
    buffers: Buffers,
    plan: FramePlan,
    owned: Vec<ResourceId>,
    bytes: u64,
    reference: Option<Image>,
    degenerate_triangles: u64,
    /// Triangles of the uploaded scene (checked against a new `max_triangles`).
    triangles: u64,
    /// The acceleration structure's levels, to move instances without a rebuild.
    instances: SceneInstances,
}

impl PhotonGi {
    /// Validates the scene and settings, uploads the scene and creates the frame's
    /// buffers (every one checked against the device first).
    pub fn new(
        backend: &mut dyn Backend,
        scene: &Scene,
        settings: PhotonGiSettings,
    ) -> Result<PhotonGi, Error> {
        settings.validate()?;
        scene
            .validate()
            .map_err(|p| Error::InvalidScene(format!("{}: {}", p[0].path, p[0].reason)))?;
        let ds = DeviceScene::build(
            scene,
            BuildBudget {
                max_triangles: settings.max_triangles,
            },
        )?;
        let camera = GpuCamera::from_camera(&scene.camera);
        let total = settings.photons_w as u64 * settings.photons_h as u64;
        let (rsms, power_scale, flux_quantum) =
            plan_lights(&ds.lights, total, settings.rsm_size, &ds.bounds, &[]);
        let diagonal = scene_diagonal(&ds.bounds);
        let mut rec = Recording::new();
        let scene_args = rec.upload_scene(&ds);
        let correct = shading_correction(&settings, &ds.instances);
        let buffers = Buffers::create_all(&mut rec, camera, &settings, correct);
        let allocation = planned_allocation(backend, &rec, Some((camera.width, camera.height)))?;
        backend.execute(&rec)?;
        let plan = PhotonGi::make_plan(scene, &settings, &rsms, &allocation.buffers, correct);
        let mut t = PhotonGi {
            settings,
            scene: scene_args,
            model: scene.clone(),
            camera,
            lights: ds.lights.clone(),
            bounds: ds.bounds,
            rsms,
            diagonal,
            power_scale,
            flux_quantum,
            buffers,
            plan,
            owned: allocation.owned,
            bytes: allocation.bytes,
            reference: None,
            degenerate_triangles: ds.degenerate_triangles,
            triangles: ds.triangles.len() as u64,
            instances: ds.instances,
        };
        if let Err(e) = t.plan_photons(backend) {
            let _ = t.free(backend);
            return Err(e);
        }
        Ok(t)
    }

    /// Replaces the settings for the next frames without touching the uploaded scene
    /// (issue 19 point 1): every frame buffer is made anew for them (photon and RSM
    /// capacities, screen buffers, filters), the lights re-planned and their RSMs probed;
    /// the next frame equals, bitwise, that of a technique created with these settings.
    /// A budget the scene exceeds (`max_triangles`), a bad setting or a failed allocation
    /// is an error that leaves the technique as it was.
    pub fn set_settings(
        &mut self,
        backend: &mut dyn Backend,
        settings: PhotonGiSettings,
    ) -> Result<(), Error> {
        settings.validate()?;
        if self.triangles > settings.max_triangles {
            return Err(Error::InvalidParameter(format!(
                "photon-gi: the scene has {} triangles, over max_triangles = {}",
                self.triangles, settings.max_triangles
            )));
        }
        let correct = shading_correction(&settings, &self.instances);
        let mut rec = Recording::new();
        let buffers = Buffers::create_all(&mut rec, self.camera, &settings, correct);
        let size = Some((self.camera.width, self.camera.height));
        let allocation = planned_allocation(backend, &rec, size)?;
        backend.execute(&rec)?;
        // the scene's buffers stay; the frame's are swapped (`owned[i]` is
        // `plan.buffers[i]`)
        let scene_ids = self.scene_ids();
        let (mut owned, mut plans, mut bytes) = (Vec::new(), Vec::new(), 0);
        let mut old_ids = Vec::new();
        for (id, plan) in self.owned.iter().zip(&self.plan.buffers) {
            if scene_ids.contains(id) {
                owned.push(*id);
                plans.push(plan.clone());
                bytes += plan.bytes;
            } else {
                old_ids.push(*id);
            }
        }
        owned.extend(allocation.owned);
        plans.extend(allocation.buffers);
        bytes += allocation.bytes;
        let plan = PhotonGi::make_plan(&self.model, &settings, &self.rsms, &plans, correct);
        let old = (
            std::mem::replace(&mut self.settings, settings),
            std::mem::replace(&mut self.buffers, buffers),
            std::mem::replace(&mut self.owned, owned),
            std::mem::replace(&mut self.plan, plan),
            std::mem::replace(&mut self.bytes, bytes),
            (self.rsms.clone(), self.power_scale, self.flux_quantum),
        );
        if let Err(e) = self.plan_photons(backend) {
            // the new buffers go, the old state comes back
            let mut free = Recording::new();
            for id in self.owned.iter().filter(|id| !scene_ids.contains(id)) {
                free.steps.push(Step::Free { id: *id });
            }
            let _ = backend.execute(&free);
            (
                self.settings,
                self.buffers,
                self.owned,
                self.plan,
                self.bytes,
                (self.rsms, self.power_scale, self.flux_quantum),
            ) = old;
            return Err(e);
        }
        let mut free = Recording::new();
        for id in old_ids {
            free.steps.push(Step::Free { id });
        }
        backend.execute(&free)?;
        Ok(())
    }

    /// The uploaded scene's buffers.
    fn scene_ids(&self) -> [ResourceId; 5] {
        let s = &self.scene;
        [
            s.vertices.id,
            s.triangles.id,
            s.materials.id,
            s.lights.id,
            s.bvh_nodes.id,
        ]
    }

    fn make_plan(
        scene: &Scene,
        s: &PhotonGiSettings,
        rsms: &[LightRsm],
        buffers: &[crate::frame::plan::BufferPlan],
        correct: bool,
    ) -> FramePlan {
        let any = rsms.iter().any(|r| r.photons > 0);
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
        FramePlan {
            prune: true,
            features: SceneFeatures::of(scene),
            outputs: OUTPUTS.iter().map(|o| o.0.to_string()).collect(),
            lights: rsms
                .iter()
                .map(|r| LightPlan {
                    light: r.light,
                    emits: r.photons > 0,
                    reason: if r.sees {
                        format!(
                            "{} photons by power, {} RSM faces of {}^2",
                            r.photons,
                            r.faces.len(),
                            s.rsm_size
                        )
                    } else {
                        format!(
                            "no photons: its RSM ({} faces of {}^2) sees no texel that \
                             leaves flux (flux x albedo is zero on every one), so none \
                             could carry any; the other lights share the budget by power",
                            r.faces.len(),
                            s.rsm_size
                        )
                    },
                })
                .collect(),
            trace_variant: None,
            passes: vec![
                pass("primary_gbuffer", true, "camera and RSM faces"),
                pass("direct_light", true, "the composite's direct part"),
                pass("rsm_importance", any, photons),
                pass("sample_rsm", any, photons),
                pass("trace_indirect", any, photons),
                pass(
                    "splat_photons",
                    any && s.estimator == IndirectEstimator::Splat,
                    if s.estimator == IndirectEstimator::Splat {
                        photons
                    } else {
                        "estimator deposit: the photons are deposited, not splatted"
                    },
                ),
                pass(
                    "deposit_screen",
                    any && s.estimator == IndirectEstimator::Deposit,
                    if s.estimator == IndirectEstimator::Deposit {
                        "estimator deposit (the indirect reference's estimator)"
                    } else {
                        "estimator splat"
                    },
                ),
                pass("resolve_caustics", true, "irradiance to radiance"),
                pass(
                    "temporal_blend",
                    s.temporal,
                    if s.temporal {
                        "setting temporal"
                    } else {
                        "temporal off"
                    },
                ),
                pass(
                    "atrous_filter",
                    s.atrous_iterations > 0,
                    if s.atrous_iterations > 0 {
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
                    } else if s.estimator != IndirectEstimator::Splat {
                        "estimator deposit: no splats carry a light direction"
                    } else {
                        "every vertex normal is its triangle's geometric normal: the factor is 1"
                    },
                ),
                pass("composite", true, "direct plus indirect"),
            ],
            buffers: buffers.to_vec(),
        }
    }

    /// The splat's parameters for camera `cam`.
    fn splat_params(&self, cam: GpuCamera) -> SplatParams {
        let s = &self.settings;
        SplatParams {
            camera: cam,
            tile_size: s.tile_size,
            power_scale: self.power_scale,
            flux_quantum: self.flux_quantum,
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
            light_direction: self.buffers.uncorrected.is_some() as u32,
            _pad: [0; 2],
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
            seed: self.settings.seed,
            max_bounces: self.settings.bounces,
            max_segments: self.settings.max_segments,
            tile_size: self.settings.tile_size,
            store,
            fresnel_model: self.settings.fresnel_model,
            power_scale: self.power_scale,
            flux_quantum: self.flux_quantum,
            _pad: [0; 2],
        }
    }

    /// Records the RSM and trace passes of light `r` (the photons go to `b.photons`).
    fn record_light(&self, rec: &mut Recording, r: &LightRsm, cam: GpuCamera, store: u32) {
        let b = &self.buffers;
        let params = self.record_rsm(rec, r);
        rec.kernel(SampleRsm {
            params: RsmParams {
                // the orthographic face's plane, for a directional light's photons
                face_camera: r.faces[0],
                face: 0,
                face_count: r.faces.len() as u32,
                first_sample: 0,
                sample_count: r.photons,
                level: 0,
                ..params
            },
            lights: self.scene.lights,
            texels: b.rsm_texels,
            pyramid: b.pyramid,
            photons: b.rsm_photons,
        });
        rec.kernel(TraceIndirect {
            scene: self.scene,
            params: self.trace_params(cam, 0, r.photons, store),
            rsm_photons: b.rsm_photons,
            photons: b.photons,
            photon_count: b.photon_count,
            tile_counts: b.tile_counts,
            counters: b.counters,
            gbuffer: b.gbuffer,
        });
    }

    /// Records light `r`'s RSM: per face the G-buffer from the light and the
    /// importance pyramid's level 0, then its upper levels; returns the parameters.
    fn record_rsm(&self, rec: &mut Recording, r: &LightRsm) -> RsmParams {
        let b = &self.buffers;
        let side = self.settings.rsm_size;
        let seed = crate::math::rng::random_u32(self.settings.seed, r.light, 0, 7);
        let mut params = RsmParams {
            light: r.light,
            side,
            seed,
            sampling: self.settings.rsm_sampling.code(),
            ..Default::default()
        };
        for (f, face) in r.faces.iter().enumerate() {
            rec.kernel(PrimaryGbuffer {
                scene: self.scene,
                camera: *face,
                gbuffer: b.rsm_gbuffer,
            });
            params.face_camera = *face;
            params.face = f as u32;
            params.level = 0;
            rec.kernel(RsmImportance {
                params,
                lights: self.scene.lights,
                gbuffer: b.rsm_gbuffer,
                texels: b.rsm_texels,
                pyramid: b.pyramid,
            });
        }
        for level in 1..level_count(side) {
            params.level = level;
            rec.kernel(RsmImportance {
                params,
                lights: self.scene.lights,
                gbuffer: b.rsm_gbuffer,
                texels: b.rsm_texels,
                pyramid: b.pyramid,
            });
        }
        params
    }

    /// Which lights' RSMs see a texel that leaves flux: each light with power renders
    /// its RSM and importance pyramid once, and the pyramid's top (per face: the sum of
    /// its level-0 entries, each zero exactly where the texel's flux x albedo is zero,
    /// under either sampling) is read back. The RSMs depend on the lights, the geometry
    /// and the albedos only, so this runs at creation and on light and material updates,
    /// never per frame.
    fn probe_rsms(&self, backend: &mut dyn Backend, rsms: &[LightRsm]) -> Result<Vec<bool>, Error> {
        let side = self.settings.rsm_size;
        let (len, top) = (pyramid_len(side), level_offset(side, level_count(side) - 1));
        let mut sees = vec![false; rsms.len()];
        for (k, r) in rsms.iter().enumerate() {
            if r.photons == 0 {
                continue; // no power: nothing to prove, it gets no photon anyway
            }
            let mut rec = Recording::new();
            self.record_rsm(&mut rec, r);
            backend.execute(&rec)?;
            let pyramid = read_buf(backend, self.buffers.pyramid)?;
            sees[k] = (0..r.faces.len()).any(|f| {
                pyramid
                    .get(f * len as usize + top as usize)
                    .is_some_and(|&t| t > 0.0)
            });
        }
        Ok(sees)
    }

    /// Allocates the photons over the lights by power, among those whose RSM sees
    /// something ([`PhotonGi::probe_rsms`]), and states it in the plan.
    fn plan_photons(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        let total = self.settings.photons_w as u64 * self.settings.photons_h as u64;
        let side = self.settings.rsm_size;
        let (by_power, _, _) = plan_lights(&self.lights, total, side, &self.bounds, &[]);
        let sees = self.probe_rsms(backend, &by_power)?;
        // a light without power keeps `sees: true` in the plan: it gets no photon for
        // that reason, not for its RSM
        let sees: Vec<bool> = by_power
            .iter()
            .zip(&sees)
            .map(|(r, &s)| s || r.photons == 0)
            .collect();
        (self.rsms, self.power_scale, self.flux_quantum) =
            plan_lights(&self.lights, total, side, &self.bounds, &sees);
        let buffers = std::mem::take(&mut self.plan.buffers);
        self.plan = PhotonGi::make_plan(
            &self.model,
            &self.settings,
            &self.rsms,
            &buffers,
            self.buffers.uncorrected.is_some(),
        );
        Ok(())
    }

    /// Renders one frame (see the module doc): the recordings of
    /// [`PhotonGi::record_frame`] submitted without a wait between them, waited for at the
    /// end; `progress` is called as each light's photons complete.
    pub fn frame(
        &mut self,
        backend: &mut dyn Backend,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<FrameStats, Error> {
        let start = Instant::now();
        let mut stats = self.frame_stats(&*backend);
        // submitted without a wait between them, waited for at the end
        let recordings = self.frame_recordings(&mut stats);
        let back = crate::frame::submitted::run_pipelined(
            backend,
            recordings,
            &[self.buffers.counters.id],
            &mut stats,
            progress,
        )?;
        let c: Vec<u32> = back
            .first()
            .map(|c| bytemuck::pod_collect_to_vec(c))
            .unwrap_or_default();
        stats.read_counters(&c, self.flux_quantum);
        self.end_frame();
        stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        if let Some(r) = &self.reference {
            let img = self.read_image(backend, self.buffers.indirect)?;
            stats.error = Some(crate::frame::metrics::compare(&img, r));
        }
        Ok(stats)
    }

    /// Records one whole frame without running it (issue 19 point 2): the passes of
    /// [`PhotonGi::frame`] in one [`Recording`], the photon counters copied to the host at
    /// its end ([`crate::frame::submitted`]). The temporal history advances as if the
    /// frame had run. No progress callback and no error against the reference.
    pub fn record_frame(&mut self, backend: &mut dyn Backend) -> Result<RecordedFrame, Error> {
        let start = Instant::now();
        let mut stats = self.frame_stats(backend);
        let mut recording = Recording::new();
        for (rec, _) in self.frame_recordings(&mut stats) {
            recording.steps.extend(rec.steps);
        }
        self.end_frame();
        stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(RecordedFrame {
            recording,
            readbacks: vec![self.buffers.counters.id],
            stats,
            counters: Some((0, self.flux_quantum)),
        })
    }

    /// A frame's statistics before anything runs: names, plan, skipped passes, photons
    /// per light.
    fn frame_stats(&self, backend: &dyn Backend) -> FrameStats {
        let caps = backend.capabilities();
        let cam = self.camera;
        let mut stats = FrameStats {
            technique: "photon-gi".into(),
            backend: backend.name().into(),
            device: caps.device.clone(),
            width: cam.width,
            height: cam.height,
            timing: if caps.timestamps {
                "device timestamps".into()
            } else {
                "host wall clock".into()
            },
            flux_quantum: self.flux_quantum as f64,
            bytes_allocated: self.bytes,
            degenerate_triangles: self.degenerate_triangles,
            plan: Some(self.plan.clone()),
            ..Default::default()
        };
        for p in self.plan.passes.iter().filter(|p| !p.runs) {
            stats.skip(&p.name, p.reason.clone());
        }
        stats.photons_emitted = self.rsms.iter().map(|r| r.photons as u64).sum();
        stats.photons_per_light = self.rsms.iter().map(|r| r.photons as u64).collect();
        stats
    }

    /// The frame's recordings in order, each with the photons it traces: visibility and
    /// clears; per lit light, its photons (deposited at once with the deposit estimator);
    /// the splat, resolve, filters, Eq. 20's correction and the composite.
    fn frame_recordings(&self, stats: &mut FrameStats) -> Vec<(Recording, u64)> {
        let cam = self.camera;
        let b = self.buffers;
        let mut out = Vec::new();
        let mut rec = Recording::new();
        rec.kernel(PrimaryGbuffer {
            scene: self.scene,
            camera: cam,
            gbuffer: b.gbuffer,
        });
        rec.kernel(DirectLight {
            scene: self.scene,
            params: DirectParams {
                camera: cam,
                light_count: self.lights.len() as u32,
                max_specular_depth: self.settings.max_specular_depth,
                min_weight: 1e-4,
                fresnel_model: self.settings.fresnel_model,
            },
            gbuffer: b.gbuffer,
            out: b.direct,
        });
        rec.clear_photon_map(&b.photon_map);
        if b.uncorrected.is_some() {
            rec.clear_photon_map(&b.direction_map);
        }
        rec.clear(b.counters);
        rec.clear(b.photon_count);
        rec.clear(b.tile_counts);
        out.push((rec, 0));

        let deposit = self.settings.estimator == IndirectEstimator::Deposit;
        for r in self.rsms.iter().filter(|r| r.photons > 0) {
            let mut rec = Recording::new();
            if deposit {
                // each light's float photons deposited before the next light's are traced
                rec.clear(b.photon_count);
                self.record_light(&mut rec, r, cam, gi_store::FLOAT);
                rec.kernel(DepositScreen {
                    params: self.deposit_params(cam),
                    gbuffer: b.gbuffer,
                    photons: b.photons.reinterpret(),
                    photon_count: b.photon_count,
                    counters: b.counters,
                    photon_map: b.photon_map,
                });
            } else {
                self.record_light(&mut rec, r, cam, gi_store::PACKED);
            }
            stats.batches += 1;
            out.push((rec, r.photons as u64));
        }

        let mut rec = Recording::new();
        if !deposit {
            rec.kernel(SplatPhotons {
                params: self.splat_params(cam),
                gbuffer: b.gbuffer,
                photons: b.photons.reinterpret(),
                photon_count: b.photon_count,
                tile_counts: b.tile_counts,
                counters: b.counters,
                photon_map: b.photon_map,
                direction_map: b.direction_map,
            });
        }
        rec.kernel(ResolveCaustics {
            params: self.deposit_params(cam),
            gbuffer: b.gbuffer,
            photon_map: b.photon_map,
            out: b.raw,
        });
        self.record_filters(&mut rec, cam);
        if let Some(uncorrected) = b.uncorrected {
            rec.kernel(ShadingNormalCorrection {
                params: CorrectionParams {
                    width: cam.width,
                    height: cam.height,
                    max_stretch: self.settings.max_stretch,
                    epsilon: SHADING_EPSILON,
                },
                gbuffer: b.gbuffer,
                direction_map: b.direction_map,
                input: uncorrected,
                out: b.indirect,
            });
        }
        rec.kernel(Composite {
            direct: b.direct,
            caustics: b.indirect,
            out: b.composite,
        });
        out.push((rec, 0));
        out
    }

    /// After a frame: this frame's blend is the next frame's history.
    fn end_frame(&mut self) {
        let cam = self.camera;
        if let Some(t) = &mut self.buffers.temporal {
            t.image.swap();
            t.edge.swap();
            t.previous = cam;
        }
    }

    fn deposit_params(&self, cam: GpuCamera) -> DepositParams {
        DepositParams {
            camera: cam,
            flux_quantum: self.flux_quantum,
            hit_distance_quantum: 1.0,
            // the tangent-plane test (`layout::off_surface`): within 1% of the depth of
            // the pixel's tangent plane, so a surface seen at any angle keeps its photons
            // (a curved receiver of radius R departs from the plane by ~(pixel size)^2 /
            // 2R within a pixel: 2e-3 of the depth for R = z / 10 at 54 rows)
            depth_tolerance: -0.01,
            photon_capacity: self.buffers.photons.len,
        }
    }

    /// The temporal blend and the A-Trous iterations from `raw` to `indirect` (each
    /// optional: the last that runs writes `indirect`; with neither, `indirect` is `raw`).
    fn record_filters(&self, rec: &mut Recording, cam: GpuCamera) {
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
            record_temporal_blend(rec, cam, b.gbuffer, history, b.raw, blended);
            input = blended;
        }
        // with neither filter `indirect` is the raw image's buffer
        if let Some(a) = b.atrous {
            let scratch = AtrousScratch {
                a: a.a,
                b: a.b,
                details: a.details,
            };
            record_atrous(
                rec,
                cam,
                b.gbuffer,
                scratch,
                self.settings.atrous_iterations,
                self.settings.atrous_clip_sigmas,
                input,
                target,
            );
        }
    }

    /// Reads a device image back.
    fn read_image(&self, backend: &mut dyn Backend, image: ImageBuf) -> Result<Image, Error> {
        let px = read_buf(backend, image)?;
        Ok(Image::new(self.camera.width, self.camera.height, px))
    }

    /// Replaces the lights for the next frames: photons re-allocated by power, RSM faces
    /// re-planned, the light buffer updated in place (or replaced when the count changes);
    /// no other buffer is made (they hold any light's six faces and every photon). The
    /// temporal history is reset.
    pub fn set_lights(
        &mut self,
        backend: &mut dyn Backend,
        lights: &[crate::scene::Light],
    ) -> Result<(), Error> {
        let model = crate::frame::technique::with_lights(&self.model, lights)?;
        let gpu: Vec<GpuLight> = lights
            .iter()
            .map(crate::device::device_scene::gpu_light)
            .collect();
        let mut rec = Recording::new();
        if gpu.len() == self.lights.len() {
            rec.update(self.scene.lights, &gpu, "lights")?;
            backend.execute(&rec)?;
        } else {
            let old = self.scene.lights;
            let new = rec.upload(&gpu, "lights");
            let alloc = planned_allocation(backend, &rec, None)?;
            rec.steps.push(Step::Free { id: old.id });
            backend.execute(&rec)?;
            self.scene.lights = new;
            for id in &mut self.owned {
                if *id == old.id {
                    *id = new.id;
                }
            }
            let old_bytes = old.len as u64 * std::mem::size_of::<GpuLight>() as u64;
            self.bytes = self.bytes - old_bytes + alloc.bytes;
            for b in &mut self.plan.buffers {
                if b.name == "lights" {
                    b.bytes = alloc.bytes;
                }
            }
        }
        self.lights = gpu;
        self.model = model;
        self.plan_photons(backend)?;
        self.reset_history();
        Ok(())
    }

    /// Moves instances for the next frames
    /// ([`crate::frame::technique::Technique::set_object_transforms`]): the moved objects'
    /// world vertices and the top level are rewritten in place, the RSMs re-planned over
    /// the new scene bounds, photons re-allocated, and the temporal history reset. Built
    /// anew (on the same backend) only when the move switches Eq. 20's correction pass on
    /// or off. On an error nothing changes.
    pub fn set_object_transforms(
        &mut self,
        backend: &mut dyn Backend,
        moves: &[(usize, crate::scene::Transform)],
    ) -> Result<(), Error> {
        let model = crate::frame::technique::with_transforms(&self.model, moves)?;
        let mut instances = self.instances.clone();
        let m = instances.move_instances(moves)?;
        self.update_instances(backend, model, instances, InstanceUpdate::Moved(m))
    }

    /// Deforms an instance for the next frames
    /// ([`crate::frame::technique::Technique::set_object_vertices`]): its BLAS rebuilt in
    /// place, then as a move (RSMs re-planned, photons re-allocated, history reset). On
    /// an error nothing changes.
    pub fn set_object_vertices(
        &mut self,
        backend: &mut dyn Backend,
        object: usize,
        positions: &[glam::Vec3],
        normals: &[glam::Vec3],
    ) -> Result<(), Error> {
        let d = crate::frame::technique::deformation(
            &self.model,
            &self.instances,
            object,
            positions,
            normals,
        )?;
        self.update_instances(backend, d.model, d.instances, d.update)
    }

    /// Applies an instance update already made to `instances` (a copy of the technique's)
    /// for `model`, the scene after it.
    fn update_instances(
        &mut self,
        backend: &mut dyn Backend,
        model: Scene,
        mut instances: SceneInstances,
        u: InstanceUpdate,
    ) -> Result<(), Error> {
        let m = u.moved();
        instances.refresh_smooth_normals(m);
        if shading_correction(&self.settings, &instances) != self.buffers.uncorrected.is_some() {
            let fresh = PhotonGi::new(backend, &model, self.settings.clone())?;
            let old = std::mem::replace(self, fresh);
            self.reference = old.reference.clone();
            return old.free(backend);
        }
        let mut rec = Recording::new();
        rec.update_instances(&u, &self.scene)?;
        backend.execute(&rec)?;
        self.instances = instances;
        self.bounds = m.bounds;
        self.diagonal = scene_diagonal(&m.bounds);
        self.model = model;
        self.plan_photons(backend)?;
        self.reset_history();
        Ok(())
    }

    /// Replaces the materials' parameters for the next frames (the same names, none
    /// switching between diffuse and specular: `frame::material_update`); the temporal
    /// history is reset.
    pub fn set_materials(
        &mut self,
        backend: &mut dyn Backend,
        materials: &std::collections::BTreeMap<String, crate::scene::Material>,
    ) -> Result<(), Error> {
        let u = crate::frame::material_update::material_update(&self.model, materials)?;
        let mut rec = Recording::new();
        rec.update(self.scene.materials, &u.gpu, "materials")?;
        backend.execute(&rec)?;
        self.model = u.model;
        // albedos decide what the RSMs see
        self.plan_photons(backend)?;
        self.reset_history();
        Ok(())
    }

    /// Moves the camera for the next frames. At the same image size no buffer is made (the
    /// temporal history reprojects across the move); a new size makes the per-pixel
    /// buffers anew (G-buffer, photon map, tile counts, images, the filters' history,
    /// which starts empty) and frees the old ones, keeping the scene, the RSMs and the
    /// photon buffers; the reference image (of the old size) is dropped. On an error
    /// nothing changes.
    pub fn set_camera(
        &mut self,
        backend: &mut dyn Backend,
        camera: &crate::scene::Camera,
    ) -> Result<(), Error> {
        let model = crate::frame::technique::with_camera(&self.model, camera)?;
        let gpu = GpuCamera::from_camera(camera);
        if (gpu.width, gpu.height) != (self.camera.width, self.camera.height) {
            let mut rec = Recording::new();
            let correct = self.buffers.uncorrected.is_some();
            let s = ScreenBuffers::create(&mut rec, gpu, &self.settings, correct);
            let alloc = planned_allocation(backend, &rec, Some((gpu.width, gpu.height)))?;
            backend.execute(&rec)?;
            // free the old per-pixel buffers; `owned[i]` is `plan.buffers[i]`
            let old = self.buffers.screen_ids();
            let mut free = Recording::new();
            let (mut owned, mut plans) = (Vec::new(), Vec::new());
            let buffers = std::mem::take(&mut self.plan.buffers);
            for (id, plan) in std::mem::take(&mut self.owned).into_iter().zip(buffers) {
                if old.contains(&id) {
                    free.steps.push(Step::Free { id });
                    self.bytes -= plan.bytes;
                } else {
                    owned.push(id);
                    plans.push(plan);
                }
            }
            owned.extend(alloc.owned);
            plans.extend(alloc.buffers);
            self.bytes += alloc.bytes;
            self.owned = owned;
            self.buffers = self.buffers.with_screen(s);
            self.plan = PhotonGi::make_plan(&model, &self.settings, &self.rsms, &plans, correct);
            self.reference = None;
            backend.execute(&free)?;
        }
        self.camera = gpu;
        self.model = model;
        Ok(())
    }

    /// Forgets the temporal history (the next frame is not blended).
    fn reset_history(&mut self) {
        if let Some(t) = &mut self.buffers.temporal {
            t.image.reset();
            t.edge.reset();
        }
    }

    /// The settings in effect.
    pub fn settings(&self) -> &PhotonGiSettings {
        &self.settings
    }

    /// The lights' RSMs and photon counts.
    pub fn light_rsms(&self) -> &[LightRsm] {
        &self.rsms
    }

    /// Releases every device buffer.
    pub fn free(mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        let mut rec = Recording::new();
        for id in std::mem::take(&mut self.owned) {
            rec.steps.push(Step::Free { id });
        }
        backend.execute(&rec)?;
        Ok(())
    }
}

impl Drop for PhotonGi {
    fn drop(&mut self) {
        crate::frame::technique::report_leak("photon-gi", self.owned.len(), self.bytes);
    }
}

impl Technique for PhotonGi {
    fn name(&self) -> &'static str {
        "photon-gi"
    }

    fn frame(
        &mut self,
        backend: &mut dyn Backend,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<FrameStats, Error> {
        PhotonGi::frame(self, backend, progress)
    }

    fn record_frame(&mut self, backend: &mut dyn Backend) -> Result<RecordedFrame, Error> {
        PhotonGi::record_frame(self, backend)
    }

    fn outputs(&self) -> Vec<OutputInfo> {
        OUTPUTS
            .iter()
            .map(|(name, description)| OutputInfo {
                name,
                description,
                requested: true,
                camera_space: true,
            })
            .collect()
    }

    fn read_output(&self, backend: &mut dyn Backend, name: &str) -> Result<Image, Error> {
        let b = &self.buffers;
        let buf = match name {
            "composite" => b.composite,
            "direct" => b.direct,
            "indirect_raw" => b.raw,
            "indirect" => b.indirect,
            _ => {
                return Err(Error::InvalidParameter(format!(
                    "photon-gi has no output '{name}'; outputs: {}",
                    OUTPUTS.map(|o| o.0).join(", ")
                )))
            }
        };
        self.read_image(backend, buf)
    }

    fn estimate_outputs(&self) -> (&'static str, &'static str) {
        ("indirect", "indirect_raw")
    }

    fn settings_json(&self) -> serde_json::Value {
        serde_json::to_value(&self.settings).unwrap_or(serde_json::Value::Null)
    }

    fn set_seed(&mut self, seed: u32) {
        self.settings.seed = seed;
    }

    fn set_camera(
        &mut self,
        backend: &mut dyn Backend,
        camera: &crate::scene::Camera,
    ) -> Result<(), Error> {
        PhotonGi::set_camera(self, backend, camera)
    }

    fn set_lights(
        &mut self,
        backend: &mut dyn Backend,
        lights: &[crate::scene::Light],
    ) -> Result<(), Error> {
        PhotonGi::set_lights(self, backend, lights)
    }

    fn set_object_transforms(
        &mut self,
        backend: &mut dyn Backend,
        moves: &[(usize, crate::scene::Transform)],
    ) -> Result<(), Error> {
        PhotonGi::set_object_transforms(self, backend, moves)
    }

    fn set_object_vertices(
        &mut self,
        backend: &mut dyn Backend,
        object: usize,
        positions: &[glam::Vec3],
        normals: &[glam::Vec3],
    ) -> Result<(), Error> {
        PhotonGi::set_object_vertices(self, backend, object, positions, normals)
    }

    fn set_materials(
        &mut self,
        backend: &mut dyn Backend,
        materials: &std::collections::BTreeMap<String, crate::scene::Material>,
    ) -> Result<(), Error> {
        PhotonGi::set_materials(self, backend, materials)
    }

    fn set_settings(
        &mut self,
        backend: &mut dyn Backend,
        settings: &serde_json::Value,
    ) -> Result<(), Error> {
        let next: PhotonGiSettings = serde_json::from_value(settings.clone())
            .map_err(|e| Error::InvalidParameter(format!("photon-gi settings: {e}")))?;
        PhotonGi::set_settings(self, backend, next)
    }

    fn set_reference(&mut self, reference: Option<Image>) -> Result<(), Error> {
        if let Some(r) = &reference {
            if (r.width, r.height) != (self.camera.width, self.camera.height) {
                return Err(Error::InvalidParameter(format!(
                    "reference is {}x{}, the frame {}x{}",
                    r.width, r.height, self.camera.width, self.camera.height
                )));
            }
        }
        self.reference = reference;
        Ok(())
    }

    fn plan(&self) -> &FramePlan {
        &self.plan
    }

    fn free(self: Box<Self>, backend: &mut dyn Backend) -> Result<(), Error> {
        PhotonGi::free(*self, backend)
    }
}

/// The registry's constructor: `settings` is a JSON object of [`PhotonGiSettings`]
/// fields.
pub fn create(
    backend: &mut dyn Backend,
    scene: &Scene,
    settings: &serde_json::Value,
) -> Result<Box<dyn Technique>, Error> {
    let settings: PhotonGiSettings = serde_json::from_value(settings.clone())
        .map_err(|e| Error::InvalidParameter(format!("photon-gi settings: {e}")))?;
    Ok(Box::new(PhotonGi::new(backend, scene, settings)?))
}

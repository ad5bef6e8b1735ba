//! PhotonGi's reflective shadow maps and photon planning (Smal 2019, section 24.2): each
//! light's RSM faces ([`rsm_faces`]), the photons allocated over the lights by power
//! ([`crate::math::photon_allocation`]), and the probe that leaves out a light whose RSM
//! sees no texel that leaves flux ([`plan_photons`], at creation and on updates, never per
//! frame).

use super::PhotonGiSettings;
use crate::backend::{read_buf, Backend};
use crate::device::handle::{Buf, GBufferPlanes, SceneArgs};
use crate::device::layout::{light_kind, GpuCamera, GpuLight, RsmParams, RsmPhoton, RsmTexel};
use crate::frame::error::Error;
use crate::frame::host::FrameHost;
use crate::kernels::{PrimaryGbuffer, RsmImportance};
use crate::math::rsm::{level_count, level_offset, luminance, pyramid_len};
use crate::recording::Recording;
use glam::Vec3;

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

/// A light's power for the allocation (Smal 2019, section 24.2): the luminance of its
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

/// The lights' RSMs and the photon quanta of one frame.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct PhotonPlan {
    /// Per light its RSM and photons.
    pub rsms: Vec<LightRsm>,
    /// Unit of the packed photon power (the mean emitted photon power, W).
    pub power_scale: f32,
    /// The photon map's flux quantum (W).
    pub flux_quantum: f32,
}

/// The lights' RSMs and photon counts for `total` initial photons (allocated by power,
/// Smal 2019, section 24.2, over the lights whose RSM sees something: `sees`, one flag per
/// light, all true when not yet known), the unit of the packed photon power and the
/// photon map's flux quantum.
fn plan_lights(
    lights: &[GpuLight],
    total: u64,
    side: u32,
    bounds: &crate::math::geometry::Aabb,
    sees: &[bool],
) -> PhotonPlan {
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
    PhotonPlan {
        rsms,
        power_scale,
        flux_quantum,
    }
}

/// The RSM's device buffers, with room for any light (six faces, every initial photon),
/// so that lights can change without new buffers.
#[derive(Clone, Copy, Debug)]
pub(super) struct RsmBuffers {
    /// One face's G-buffer from the light.
    pub gbuffer: GBufferPlanes,
    pub texels: Buf<RsmTexel>,
    pub pyramid: Buf<f32>,
    /// The sampled texels, one per initial photon.
    pub photons: Buf<RsmPhoton>,
}

impl RsmBuffers {
    /// Records the creation of the RSM buffers for `settings`.
    pub fn create(rec: &mut Recording, settings: &PhotonGiSettings) -> RsmBuffers {
        let side = settings.rsm_size;
        let total = settings.frame.photons_w as u64 * settings.frame.photons_h as u64;
        let max_faces = 6u32;
        let max_photons = total.min(u32::MAX as u64) as u32;
        RsmBuffers {
            gbuffer: rec.create_gbuffer(side * side),
            texels: rec.create(max_faces * side * side, "RSM texels"),
            pyramid: rec.create(max_faces * pyramid_len(side), "RSM importance pyramid"),
            photons: rec.create(max_photons, "RSM photons"),
        }
    }
}

/// Records light `r`'s RSM over `scene`: per face the G-buffer from the light and the
/// importance pyramid's level 0, then its upper levels; returns the parameters.
pub(super) fn record_rsm(
    rec: &mut Recording,
    scene: SceneArgs,
    b: &RsmBuffers,
    settings: &PhotonGiSettings,
    r: &LightRsm,
) -> RsmParams {
    let side = settings.rsm_size;
    let seed = crate::math::rng::random_u32(settings.frame.seed, r.light, 0, 7);
    let mut params = RsmParams {
        light: r.light,
        side,
        seed,
        sampling: settings.rsm_sampling.code(),
        ..Default::default()
    };
    for (f, face) in r.faces.iter().enumerate() {
        rec.kernel(PrimaryGbuffer {
            scene,
            camera: *face,
            gbuffer: b.gbuffer,
        });
        params.face_camera = *face;
        params.face = f as u32;
        params.level = 0;
        rec.kernel(RsmImportance {
            params,
            lights: scene.lights,
            gbuffer: b.gbuffer,
            texels: b.texels,
            pyramid: b.pyramid,
        });
    }
    for level in 1..level_count(side) {
        params.level = level;
        rec.kernel(RsmImportance {
            params,
            lights: scene.lights,
            gbuffer: b.gbuffer,
            texels: b.texels,
            pyramid: b.pyramid,
        });
    }
    params
}

/// Which lights' RSMs see a texel that leaves flux: each light with power renders its
/// RSM and importance pyramid once, and the pyramid's top (per face: the sum of its
/// level-0 entries, each zero exactly where the texel's flux x albedo is zero, under
/// either sampling) is read back.
fn probe_rsms(
    backend: &mut dyn Backend,
    scene: SceneArgs,
    b: &RsmBuffers,
    settings: &PhotonGiSettings,
    rsms: &[LightRsm],
) -> Result<Vec<bool>, Error> {
    let side = settings.rsm_size;
    let (len, top) = (pyramid_len(side), level_offset(side, level_count(side) - 1));
    let mut sees = vec![false; rsms.len()];
    for (k, r) in rsms.iter().enumerate() {
        if r.photons == 0 {
            continue; // no power: nothing to prove, it gets no photon anyway
        }
        let mut rec = Recording::new();
        record_rsm(&mut rec, scene, b, settings, r);
        backend.execute(&rec)?;
        let pyramid = read_buf(backend, b.pyramid)?;
        sees[k] = (0..r.faces.len()).any(|f| {
            pyramid
                .get(f * len as usize + top as usize)
                .is_some_and(|&t| t > 0.0)
        });
    }
    Ok(sees)
}

/// Allocates the photons over the host's lights by power, among those whose RSM sees
/// something ([`probe_rsms`]). The RSMs depend on the lights, the geometry and the
/// albedos only, so this runs at creation and on light, instance and material updates
/// (after the host's pending scene writes, which it runs first), never per frame.
pub(super) fn plan_photons(
    backend: &mut dyn Backend,
    host: &mut FrameHost,
    b: &RsmBuffers,
    settings: &PhotonGiSettings,
) -> Result<PhotonPlan, Error> {
    host.flush(backend)?;
    let lights: Vec<GpuLight> = host
        .model()
        .lights
        .iter()
        .map(crate::device::device_scene::gpu_light)
        .collect();
    let bounds = host.geometry().bounds;
    let total = settings.frame.photons_w as u64 * settings.frame.photons_h as u64;
    let side = settings.rsm_size;
    let by_power = plan_lights(&lights, total, side, &bounds, &[]);
    let sees = probe_rsms(backend, host.scene(), b, settings, &by_power.rsms)?;
    // a light without power keeps `sees: true` in the plan: it gets no photon for that
    // reason, not for its RSM
    let sees: Vec<bool> = by_power
        .rsms
        .iter()
        .zip(&sees)
        .map(|(r, &s)| s || r.photons == 0)
        .collect();
    Ok(plan_lights(&lights, total, side, &bounds, &sees))
}

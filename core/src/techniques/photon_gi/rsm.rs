//! PhotonGi's reflective shadow maps and photon planning (Smal 2019, section 24.2): each
//! light's RSM faces ([`rsm_faces`]), the photons allocated over the lights by power
//! ([`crate::math::photon_allocation`]) among those whose RSM sees a texel that leaves
//! flux. Which lights see something is decided on the device: the host tables the plan
//! of every set of lights with power ([`PlanTable`]), and `select_photon_plan` picks the
//! row after the lights' RSMs in the frame after a change, so an update reads nothing
//! back. Beyond [`MAX_PLANNED_LIGHTS`] lights with power the table would be too large:
//! there the lights' RSMs are probed on the host ([`plan_photons`]), at creation and on
//! updates.

use super::PhotonGiSettings;
use crate::backend::{read_buf, Backend};
use crate::device::handle::{Buf, GBufferPlanes, SceneArgs};
use crate::device::layout::{
    light_kind, photon_plan_word, GpuCamera, GpuLight, RsmParams, RsmPhoton, RsmTexel,
};
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
    /// The light's flux into its RSM's faces (W per channel, [`rsm_flux`]).
    pub flux: [f64; 3],
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
                let h = light.one_minus_cos_outer;
                let tan = if h < crate::math::sampling::NARROW_CONE {
                    // a narrow spot: from 1 - cos, whose cosine has cancelled
                    (h * (2.0 - h)).sqrt() / (1.0 - h)
                } else {
                    (1.0 - cos * cos).sqrt() / cos
                };
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

/// The flux light `l` sends into its RSM's `faces` (W per channel), as a caustic
/// technique's emission domain's: intensity times the solid angle it emits into (the
/// whole sphere for a point light, the outer cone for a spot, before the spot's falloff),
/// or for a directional light its irradiance times the area of its orthographic face.
/// Its photons carry this flux times the albedo of the surfaces they leave (and a spot's
/// falloff), so it bounds what they carry, and equals it on albedo-1 walls under a light
/// without falloff.
pub fn rsm_flux(l: &GpuLight, faces: &[GpuCamera]) -> [f64; 3] {
    let i = Vec3::from_slice(&l.intensity[..3]).as_dvec3();
    let measure = match (l.kind, faces.first()) {
        (light_kind::POINT, _) => 4.0 * std::f64::consts::PI,
        (light_kind::SPOT, _) => {
            let c = l.cos_outer.clamp(-1.0, 1.0);
            crate::math::sampling::cone_solid_angle(c, l.one_minus_cos_outer) as f64
        }
        // an orthographic face's half-extents are its negated tangents (GpuCamera::orthographic)
        (light_kind::DIRECTIONAL, Some(f)) => {
            4.0 * (-f.tan_half_fov_x as f64) * (-f.tan_half_fov_y as f64)
        }
        _ => 0.0,
    };
    (i.max(glam::DVec3::ZERO) * measure).to_array()
}

/// A light's power for the allocation (Smal 2019, section 24.2): the luminance of its
/// intensity times the solid angle it emits into (W).
fn light_power(l: &GpuLight) -> f64 {
    let i = luminance(Vec3::from_slice(&l.intensity[..3])).max(0.0) as f64;
    let omega = if l.kind == light_kind::SPOT {
        crate::math::sampling::cone_solid_angle(l.cos_outer, l.one_minus_cos_outer) as f64
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

/// Photon counts per light for `total` initial photons, allocated by power (Smal 2019,
/// section 24.2) over the lights whose RSM sees something (`sees`, one flag per light, all
/// true when not yet known), the unit of the packed photon power and the photon map's
/// flux quantum.
fn allocation(powers: &[f64], total: u64, sees: &[bool]) -> (Vec<u64>, f32, f32) {
    let sees_at = |i: usize| sees.get(i).copied().unwrap_or(true);
    let powers: Vec<f64> = powers
        .iter()
        .enumerate()
        .map(|(i, &p)| if sees_at(i) { p } else { 0.0 })
        .collect();
    let counts = crate::math::photon_allocation::allocate_photons(total, &powers);
    let emitted: f64 = powers.iter().sum();
    let power_scale = ((emitted / total as f64) as f32).max(f32::MIN_POSITIVE);
    // a splat's share of a photon is at least 2^-20 of it in any pixel it reaches
    let flux_quantum = power_scale * (1.0 / 1_048_576.0);
    (counts, power_scale, flux_quantum)
}

/// The lights' RSMs and photon counts for `total` initial photons ([`allocation`] with
/// `sees`), the unit of the packed photon power and the photon map's flux quantum.
pub(super) fn plan_lights(
    lights: &[GpuLight],
    total: u64,
    side: u32,
    bounds: &crate::math::geometry::Aabb,
    sees: &[bool],
) -> PhotonPlan {
    let powers: Vec<f64> = lights.iter().map(light_power).collect();
    let (counts, power_scale, flux_quantum) = allocation(&powers, total, sees);
    let rsms = lights
        .iter()
        .zip(&counts)
        .enumerate()
        .map(|(i, (l, &n))| {
            let faces = rsm_faces(l, side, bounds);
            LightRsm {
                light: i as u32,
                flux: rsm_flux(l, &faces),
                faces,
                photons: n as u32,
                sees: sees.get(i).copied().unwrap_or(true),
            }
        })
        .collect();
    PhotonPlan {
        rsms,
        power_scale,
        flux_quantum,
    }
}

/// Most lights with power whose photon plan the device picks: the plan table has a row
/// for each of the `2^n` sets of them (256 rows of a few words).
pub const MAX_PLANNED_LIGHTS: usize = 8;

/// Words of a plan table row before the per-light counts.
const ROW_HEAD: usize = photon_plan_word::COUNTS - photon_plan_word::ROW;

/// The plan of every set of probed lights, as the device selects it
/// (`select_photon_plan`): row `m` is the plan where exactly the probed lights whose bits
/// `m` sets see something (bit `k`: the `k`-th, [`PlanTable::lit`]),
/// laid out as the plan's words from `photon_plan_word::ROW` on: the packed power's unit,
/// the flux quantum, the resolve's quantum (the flux quantum over the frames an
/// accumulation holds) as `f32` bits, then each light's photons.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct PlanTable {
    /// The lights whose RSM the device probes, in light order (mask bit `k` is
    /// `lit[k]`): those with photons where every light sees something (a light without
    /// power gets none; nor does one that the allocation leaves without a photon when
    /// the lights outnumber the photons, which counts as seeing).
    pub lit: Vec<u32>,
    /// The lights with photons in some row (traced while the device's row is unknown).
    pub traced: Vec<u32>,
    /// The lights' powers (W) and the initial photons the table was made for.
    powers: Vec<f64>,
    total: u64,
    /// Per row: the flux quantum (the resolve's quantum is made from it per frame) and the
    /// row's words with the resolve's quantum of one frame.
    rows: Vec<(f32, Vec<u32>)>,
}

impl PlanTable {
    /// The table for `lights` and `total` initial photons, or `None` with more than
    /// [`MAX_PLANNED_LIGHTS`] probed lights.
    pub fn new(lights: &[GpuLight], total: u64) -> Option<PlanTable> {
        let powers: Vec<f64> = lights.iter().map(light_power).collect();
        let (by_power, _, _) = allocation(&powers, total, &[]);
        let lit: Vec<u32> = (0..lights.len() as u32)
            .filter(|&i| by_power[i as usize] > 0)
            .collect();
        if lit.len() > MAX_PLANNED_LIGHTS {
            return None;
        }
        let rows = (0..1u32 << lit.len())
            .map(|mask| {
                let sees = sees_of(mask, &lit, lights.len());
                let (counts, power_scale, flux_quantum) = allocation(&powers, total, &sees);
                let mut row = vec![
                    power_scale.to_bits(),
                    flux_quantum.to_bits(),
                    flux_quantum.to_bits(),
                ];
                row.extend(counts.iter().map(|&n| n as u32));
                (flux_quantum, row)
            })
            .collect::<Vec<_>>();
        let traced = (0..lights.len() as u32)
            .filter(|&i| rows.iter().any(|(_, row)| row[ROW_HEAD + i as usize] > 0))
            .collect();
        Some(PlanTable {
            lit,
            traced,
            powers,
            total,
            rows,
        })
    }

    /// Whether the table still holds for `lights` and `total` (their powers unchanged:
    /// moving a light keeps it).
    pub fn holds_for(&self, lights: &[GpuLight], total: u64) -> bool {
        self.total == total
            && self.powers.len() == lights.len()
            && lights
                .iter()
                .zip(&self.powers)
                .all(|(l, &p)| light_power(l).to_bits() == p.to_bits())
    }

    /// Words of a row.
    pub fn row_words(&self) -> u32 {
        (ROW_HEAD + self.powers.len()) as u32
    }

    /// The table's words with the resolve's quantum of an accumulation of `frames` frames
    /// (the flux quantum over `frames`, as the host divides it).
    pub fn words(&self, frames: u32) -> Vec<u32> {
        let resolve = photon_plan_word::RESOLVE_QUANTUM - photon_plan_word::ROW;
        self.rows
            .iter()
            .flat_map(|(q, row)| {
                let mut row = row.clone();
                row[resolve] = (q / frames.max(1) as f32).to_bits();
                row
            })
            .collect()
    }

    /// Which lights see something under `mask` (a light that is not probed counts as
    /// seeing: it gets no photon for its power, not for its RSM).
    pub fn sees(&self, mask: u32) -> Vec<bool> {
        sees_of(mask, &self.lit, self.powers.len())
    }
}

/// Per light whether it sees something under `mask` over the probed lights `lit`.
fn sees_of(mask: u32, lit: &[u32], lights: usize) -> Vec<bool> {
    let mut sees = vec![true; lights];
    for (k, &i) in lit.iter().enumerate() {
        sees[i as usize] = mask & (1 << k) != 0;
    }
    sees
}

/// The plan's words (from `photon_plan_word::MASK` on) for a plan known on the host:
/// `mask`, then [`PlanTable`]'s row layout for `plan` with the resolve's quantum of
/// `frames` frames.
pub(super) fn plan_words(mask: u32, plan: &PhotonPlan, frames: u32) -> Vec<u32> {
    let mut w = vec![
        mask,
        plan.power_scale.to_bits(),
        plan.flux_quantum.to_bits(),
        (plan.flux_quantum / frames.max(1) as f32).to_bits(),
    ];
    w.extend(plan.rsms.iter().map(|r| r.photons));
    w
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
        let total = settings.total_photons();
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

/// Light `r`'s RSM parameters common to its passes: light, side, seed, sampling.
pub(super) fn rsm_params(settings: &PhotonGiSettings, r: &LightRsm) -> RsmParams {
    RsmParams {
        light: r.light,
        side: settings.rsm_size,
        seed: crate::math::rng::random_u32(settings.frame.seed, r.light, 0, 7),
        sampling: settings.rsm_sampling.code(),
        ..Default::default()
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
    let mut params = rsm_params(settings, r);
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
/// something ([`probe_rsms`]): the host-side plan where the lights with power are more than
/// [`MAX_PLANNED_LIGHTS`]. It waits for the device (the host's pending scene writes run
/// first, then each light's RSM, read back).
pub(super) fn plan_photons(
    backend: &mut dyn Backend,
    host: &mut FrameHost,
    b: &RsmBuffers,
    settings: &PhotonGiSettings,
) -> Result<PhotonPlan, Error> {
    host.flush(backend)?;
    let lights = host_lights(host);
    let bounds = host.geometry().bounds;
    let total = settings.total_photons();
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

/// The host's lights as the device holds them.
pub(super) fn host_lights(host: &FrameHost) -> Vec<GpuLight> {
    host.model()
        .lights
        .iter()
        .map(crate::device::device_scene::gpu_light)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::geometry::Aabb;

    fn point(i: f32) -> GpuLight {
        GpuLight {
            kind: light_kind::POINT,
            one_minus_cos_outer: 2.0,
            intensity: [i, i, i, 0.0],
            ..Default::default()
        }
    }

    /// Row `m` of the table is the host's plan where the probed lights of `m` see
    /// something, word for word, for any accumulation length.
    fn rows_are_the_hosts_plans(lights: &[GpuLight], total: u64) -> PlanTable {
        let t = PlanTable::new(lights, total).expect("a table");
        let bounds = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let rw = t.row_words() as usize;
        for frames in [1, 3] {
            let words = t.words(frames);
            assert_eq!(words.len(), rw << t.lit.len());
            for mask in 0..1u32 << t.lit.len() {
                let p = plan_lights(lights, total, 32, &bounds, &t.sees(mask));
                let row = &words[mask as usize * rw..][..rw];
                assert_eq!(&plan_words(mask, &p, frames)[1..], row, "mask {mask}");
                for (i, r) in p.rsms.iter().enumerate() {
                    assert!(r.photons == 0 || t.traced.contains(&(i as u32)));
                }
            }
        }
        t
    }

    #[test]
    fn every_row_is_the_plan_of_its_lights() {
        let t = rows_are_the_hosts_plans(&[point(1.0), point(0.0), point(3.0), point(0.5)], 1000);
        // the light without power is neither probed nor traced
        assert_eq!(t.lit, vec![0, 2, 3]);
        assert_eq!(t.traced, vec![0, 2, 3]);
        // the row where only light 2 sees: every photon is its
        let row = &t.words(1)[0b010 * t.row_words() as usize..][..t.row_words() as usize];
        assert_eq!(&row[ROW_HEAD..], &[0, 0, 1000, 0]);
    }

    #[test]
    fn a_light_left_without_photons_by_power_is_not_probed() {
        // two photons over three lights: the dimmest gets none by power and counts as
        // seeing, but takes a photon where a brighter one is blind
        let t = rows_are_the_hosts_plans(&[point(5.0), point(1.0), point(4.0)], 2);
        assert_eq!(t.lit, vec![0, 2]);
        assert_eq!(t.traced, vec![0, 1, 2]);
    }

    #[test]
    fn more_lights_than_the_table_covers_have_none() {
        let many: Vec<GpuLight> = (0..=MAX_PLANNED_LIGHTS).map(|_| point(1.0)).collect();
        assert!(PlanTable::new(&many, 1000).is_none());
        assert!(PlanTable::new(&many[1..], 1000).is_some());
    }

    /// A light's flux into its RSM is what its faces' texels receive: summed over a point
    /// light's six faces the texels' arriving flux is `I x 4 pi`, a directional light's
    /// face `E` times its area; a spot's is its outer cone's.
    #[test]
    fn rsm_flux_is_what_the_faces_receive() {
        use crate::math::rsm::{ortho_texel_flux, texel_arriving_flux};
        let bounds = Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        };
        let side = 64;
        let l = GpuLight {
            intensity: [1.0, 2.0, 0.5, 0.0],
            ..point(1.0)
        };
        let faces = rsm_faces(&l, side, &bounds);
        let mut texels = 0.0f64;
        for _ in &faces {
            for iy in 0..side {
                for ix in 0..side {
                    texels += texel_arriving_flux(Vec3::ONE, 1.0, ix, iy, side, 1.0).x as f64;
                }
            }
        }
        let flux = rsm_flux(&l, &faces);
        let four_pi = 4.0 * std::f64::consts::PI;
        assert!((texels - four_pi).abs() < 1e-3 * four_pi, "{texels}");
        for (c, i) in [1.0, 2.0, 0.5].into_iter().enumerate() {
            assert!((flux[c] - i * four_pi).abs() < 1e-9 * four_pi);
        }
        let sun = GpuLight {
            kind: light_kind::DIRECTIONAL,
            direction: [0.0, -1.0, 0.0, 0.0],
            ..l
        };
        let faces = rsm_faces(&sun, side, &bounds);
        let half = -faces[0].tan_half_fov_x;
        let texels = ortho_texel_flux(Vec3::ONE, side, half).x as f64 * (side * side) as f64;
        let flux = rsm_flux(&sun, &faces);
        // the face spans the bounds' sphere: half = sqrt(3), area 12
        assert!((flux[1] - 2.0 * 12.0).abs() < 1e-5 * 24.0, "{flux:?}");
        assert!((texels - 12.0).abs() < 1e-4 * 12.0, "{texels}");
        let spot = GpuLight {
            kind: light_kind::SPOT,
            direction: [0.0, -1.0, 0.0, 0.0],
            cos_outer: 0.8,
            one_minus_cos_outer: 1.0 - 0.8,
            ..l
        };
        let flux = rsm_flux(&spot, &rsm_faces(&spot, side, &bounds));
        let cone = 2.0 * std::f64::consts::PI * (1.0 - 0.8);
        assert!((flux[0] - cone).abs() < 1e-5 * cone, "{flux:?}");
        // a light of no intensity emits nothing, whatever its faces
        let dark = rsm_flux(&point(0.0), &faces);
        assert_eq!(dark, [0.0; 3]);
    }
}

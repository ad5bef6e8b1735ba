//! `sample_rsm` (PhotonGi, Smal 2019, section 24.2.1): photons warped from the reflective
//! shadow map's importance pyramid. Method, units and sources in `caustica_core::math::rsm`
//! and the kernel's declaration.

use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{light_kind, GpuLight, RsmParams, RsmPhoton, RsmTexel};
use caustica_core::kernels::SampleRsm;
use caustica_core::math::geometry::offset_ray_origin;
use caustica_core::math::packing::{pack_unit_vector, unpack_unit_vector};
use caustica_core::math::rng::random_f32;
use caustica_core::math::rsm::{
    cosine_hemisphere, hammersley, ortho_origin, pyramid_len, rsm_texel_kind, warp_rsm,
};
use glam::{Vec2, Vec3};
use rayon::prelude::*;

/// Runs `sample_rsm` on the host ([`super::run`]'s arm): its buffers read from `cpu`, its
/// results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &SampleRsm) -> Result<(), BackendError> {
    let SampleRsm {
        params,
        lights,
        texels,
        pyramid,
        photons,
        // the CPU has no launch grid: the kernel bounds itself by its count
        dispatch: _,
    } = k;
    let light = *cpu
        .get(lights.id)?
        .as_slice::<GpuLight>(lights.len)?
        .get(params.light as usize)
        .ok_or_else(|| BackendError::BadArgument("sample_rsm: no such light".into()))?;
    let t = cpu.get(texels.id)?.as_slice(texels.len)?;
    let pyr = cpu.get(pyramid.id)?.as_slice(pyramid.len)?;
    reserve_temporary::<RsmPhoton>(params.sample_count as u64, "the RSM photons")?;
    let out = sample_rsm(params, &light, t, pyr);
    let first = params.first_sample as usize;
    cpu.get_mut(photons.id)?
        .as_mut_slice::<RsmPhoton>(photons.len)?[first..first + out.len()]
        .copy_from_slice(&out);
    Ok(())
}

/// `sample_rsm`: the light's photons (slot `i` of the returned vector is sample `i`).
pub fn sample_rsm(
    p: &RsmParams,
    light: &GpuLight,
    texels: &[RsmTexel],
    pyramid: &[f32],
) -> Vec<RsmPhoton> {
    (0..p.sample_count)
        .into_par_iter()
        .map(|i| rsm_photon(p, light, texels, pyramid, i))
        .collect()
}

/// Sample `i` of `sample_rsm`.
pub fn rsm_photon(
    p: &RsmParams,
    light: &GpuLight,
    texels: &[RsmTexel],
    pyramid: &[f32],
    i: u32,
) -> RsmPhoton {
    let shift = Vec2::new(
        random_f32(p.seed, p.light, 0, 0),
        random_f32(p.seed, p.light, 0, 1),
    );
    let u = hammersley(i, p.sample_count, shift);
    let plen = pyramid_len(p.side);
    let read = |f: u32, k: u32| pyramid[((p.face + f) * plen + k) as usize];
    let Some(c) = warp_rsm(read, p.face_count, p.side, u) else {
        return RsmPhoton::default();
    };
    let t =
        &texels[((p.face + c.face) * p.side * p.side + c.texel.1 * p.side + c.texel.0) as usize];
    let scale = 1.0 / (c.probability * p.sample_count as f32);
    let flux = Vec3::from(t.flux) * scale;
    if t.kind == rsm_texel_kind::DIFFUSE {
        let n = unpack_unit_vector(t.normal);
        RsmPhoton {
            origin: offset_ray_origin(Vec3::from(t.position), n).to_array(),
            direction: pack_unit_vector(cosine_hemisphere(c.within, n)),
            flux: flux.to_array(),
            bounces: 1,
        }
    } else if t.kind == rsm_texel_kind::SPECULAR {
        let origin = if light.kind == light_kind::DIRECTIONAL {
            ortho_origin(
                Vec3::from(t.position),
                Vec3::from(p.face_camera.position),
                Vec3::from(p.face_camera.forward),
            )
        } else {
            Vec3::from_slice(&light.position[..3])
        };
        RsmPhoton {
            origin: origin.to_array(),
            direction: pack_unit_vector((Vec3::from(t.position) - origin).normalize()),
            flux: flux.to_array(),
            bounces: 0,
        }
    } else {
        RsmPhoton::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kernels::rsm_importance::rsm_level;
    use caustica_core::math::rsm::luminance;

    /// The warped RSM photons are unbiased. Over 64 frame seeds, the
    /// mean flux the photons of each 4x4 block of two 16x16 faces carry equals that of
    /// uniform RSM sampling (texel uniformly at random, flux times the texel count), and
    /// both equal the block's leaving flux. Coloured, uneven texel fluxes (importance is
    /// the luminance, not each channel) and empty texels. Tolerance: a block's relative
    /// standard error over 64 x 2048 samples is below 2% for both estimators (the warp's
    /// is far smaller: its photons carry nearly equal luminance); 6% is three of them, on
    /// blocks holding at least 1% of the light. A pdf off by a power of the probability
    /// fails it by a factor of 20.
    #[test]
    fn warped_rsm_photons_are_unbiased_like_uniform_sampling() {
        let side = 16u32;
        let faces = 2u32;
        let n = (side * side) as usize;
        let mut texels = vec![RsmTexel::default(); faces as usize * n];
        let mut pyramid = vec![0.0f32; faces as usize * pyramid_len(side) as usize];
        for f in 0..faces as usize {
            for i in 0..n {
                let (x, y) = ((i % 16) as f32, (i / 16) as f32);
                let r = |k: u32| random_f32(5, (f * n + i) as u32, 0, k);
                let empty = r(3) < 0.2;
                let flux = if empty {
                    Vec3::ZERO
                } else {
                    Vec3::new(r(0), 0.5 * r(1), 2.0 * r(2)) * (1.0 + 4.0 * x / 16.0)
                };
                texels[f * n + i] = RsmTexel {
                    position: [100.0 * f as f32 + x + 0.5, y + 0.5, 0.0],
                    normal: pack_unit_vector(Vec3::Z),
                    flux: flux.to_array(),
                    kind: if empty {
                        rsm_texel_kind::NONE
                    } else {
                        rsm_texel_kind::DIFFUSE
                    },
                };
                pyramid[f * pyramid_len(side) as usize + i] = luminance(flux);
            }
        }
        for level in 1..caustica_core::math::rsm::level_count(side) {
            let p = RsmParams {
                side,
                level,
                face: faces - 1,
                ..Default::default()
            };
            rsm_level(&p, &mut pyramid);
        }
        let light = GpuLight::default();
        let block = |x: f32, y: f32, f: usize| f * 16 + (y as usize / 4) * 4 + x as usize / 4;
        let mut exact = [[0.0f64; 3]; 32];
        for f in 0..faces as usize {
            for i in 0..n {
                let t = &texels[f * n + i];
                let e = &mut exact[block((i % 16) as f32, (i / 16) as f32, f)];
                for (acc, v) in e.iter_mut().zip(t.flux) {
                    *acc += v as f64;
                }
            }
        }
        let (seeds, samples) = (64u32, 2048u32);
        let mut warped = [[0.0f64; 3]; 32];
        let mut uniform = [[0.0f64; 3]; 32];
        for seed in 0..seeds {
            let p = RsmParams {
                side,
                face: 0,
                face_count: faces,
                sample_count: samples,
                seed,
                ..Default::default()
            };
            for ph in sample_rsm(&p, &light, &texels, &pyramid) {
                if ph.flux == [0.0; 3] {
                    continue;
                }
                let f = (ph.origin[0] / 100.0) as usize;
                let b = block(ph.origin[0] - 100.0 * f as f32, ph.origin[1], f);
                for (acc, v) in warped[b].iter_mut().zip(ph.flux) {
                    *acc += v as f64 / seeds as f64;
                }
            }
            for k in 0..samples {
                let t =
                    (caustica_core::math::rng::random_u32(seed, k, 9, 0) as usize) % texels.len();
                let (f, i) = (t / n, t % n);
                let u = &mut uniform[block((i % 16) as f32, (i / 16) as f32, f)];
                for (acc, v) in u.iter_mut().zip(texels[t].flux) {
                    *acc += v as f64 * texels.len() as f64 / samples as f64 / seeds as f64;
                }
            }
        }
        let total: f64 = exact.iter().flatten().sum();
        let warped_total: f64 = warped.iter().flatten().sum();
        assert!(
            (warped_total / total - 1.0).abs() < 1e-3,
            "{warped_total} vs {total}"
        );
        for b in 0..32 {
            for c in 0..3 {
                let e = exact[b][c];
                if e < 0.01 * total / 3.0 {
                    continue;
                }
                let (w, u) = (warped[b][c], uniform[b][c]);
                assert!(
                    (w / e - 1.0).abs() < 0.06 && (u / e - 1.0).abs() < 0.06,
                    "block {b} channel {c}: warped {w}, uniform {u}, exact {e}"
                );
            }
        }
    }
}

//! `rsm_importance` (PhotonGi, Smal 2019, section 24.2.1): the reflective shadow map's
//! texels and the importance pyramid over them. Method, units and sources in
//! `caustica_core::math::rsm` and the kernel's declaration.

use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::device_scene::light_spot_falloff;
use caustica_core::device::layout::{
    camera_ray, gbuffer_flags, light_kind, GpuLight, RsmParams, RsmTexel, NO_MATERIAL,
};
use caustica_core::kernels::RsmImportance;
use caustica_core::math::packing::pack_unit_vector;
use caustica_core::math::rsm::{
    level_offset, luminance, ortho_texel_flux, pyramid_len, pyramid_sum, rsm_texel_kind,
    texel_arriving_flux,
};
use glam::Vec3;

/// Runs `rsm_importance` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &RsmImportance) -> Result<(), BackendError> {
    let RsmImportance {
        params,
        lights,
        gbuffer,
        texels,
        pyramid,
    } = k;
    let plen = caustica_core::math::rsm::pyramid_len(params.side) as usize;
    let f = params.face as usize;
    if params.level == 0 {
        let light = *cpu
            .get(lights.id)?
            .as_slice::<GpuLight>(lights.len)?
            .get(params.light as usize)
            .ok_or_else(|| BackendError::BadArgument("rsm_importance: no such light".into()))?;
        let g = cpu.gbuffer(gbuffer)?;
        let n = params.side as usize * params.side as usize;
        let (t, imp): (Vec<RsmTexel>, Vec<f32>) = {
            use rayon::prelude::*;
            (0..n)
                .into_par_iter()
                .map(|i| rsm_texel(params, &light, &g.load_gbuffer(i), i as u32))
                .unzip()
        };
        cpu.get_mut(texels.id)?
            .as_mut_slice::<RsmTexel>(texels.len)?[f * n..(f + 1) * n]
            .copy_from_slice(&t);
        cpu.get_mut(pyramid.id)?.as_mut_slice::<f32>(pyramid.len)?[f * plen..f * plen + n]
            .copy_from_slice(&imp);
    } else {
        rsm_level(params, cpu.get_mut(pyramid.id)?.as_mut_slice(pyramid.len)?);
    }
    Ok(())
}

/// One RSM texel and its importance (`rsm_importance` level 0, texel `i` of the face).
pub fn rsm_texel(
    p: &RsmParams,
    light: &GpuLight,
    g: &caustica_core::device::layout::GBufferTexel,
    i: u32,
) -> (RsmTexel, f32) {
    let none = (RsmTexel::default(), 0.0);
    if g.material == NO_MATERIAL {
        return none;
    }
    let (x, y) = (i % p.side, i / p.side);
    let falloff = if light.kind == light_kind::SPOT {
        light_spot_falloff(camera_ray(&p.face_camera, x, y), light)
    } else {
        1.0
    };
    let arriving = if light.kind == light_kind::DIRECTIONAL {
        ortho_texel_flux(
            Vec3::from_slice(&light.intensity[..3]),
            p.side,
            -p.face_camera.tan_half_fov_x,
        )
    } else {
        texel_arriving_flux(
            Vec3::from_slice(&light.intensity[..3]),
            falloff,
            x,
            y,
            p.side,
            p.face_camera.tan_half_fov_x,
        )
    };
    let albedo = Vec3::from(g.albedo);
    let importance = luminance(arriving * albedo);
    if !(importance > 0.0) || !importance.is_finite() {
        return none;
    }
    let diffuse = g.flags & gbuffer_flags::RECEIVER != 0;
    (
        RsmTexel {
            position: g.position,
            normal: pack_unit_vector(Vec3::from(g.normal)),
            flux: if diffuse { arriving * albedo } else { arriving }.to_array(),
            kind: if diffuse {
                rsm_texel_kind::DIFFUSE
            } else {
                rsm_texel_kind::SPECULAR
            },
        },
        caustica_core::math::rsm::pyramid_weight(p.sampling, importance),
    )
}

/// Level `p.level > 0` of `rsm_importance`: the 2x2 sums of level `p.level - 1` for
/// faces `0 ..= p.face`.
pub fn rsm_level(p: &RsmParams, pyramid: &mut [f32]) {
    let side = p.side;
    let plen = pyramid_len(side) as usize;
    let (below_off, off) = (
        level_offset(side, p.level - 1) as usize,
        level_offset(side, p.level) as usize,
    );
    let (s, sb) = ((side >> p.level) as usize, (side >> (p.level - 1)) as usize);
    for f in 0..=p.face as usize {
        let face = &mut pyramid[f * plen..(f + 1) * plen];
        let (below, rest) = face.split_at_mut(off);
        let below = &below[below_off..];
        for (i, v) in rest[..s * s].iter_mut().enumerate() {
            *v = pyramid_sum(
                |x, y| below[y as usize * sb + x as usize],
                (i % s) as u32,
                (i / s) as u32,
            );
        }
    }
}

//! `composite` (Kim 2019, section 30.3.3): the gathered caustic radiance is added to the
//! direct light, like one more light in a deferred renderer. Alpha 1.

use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::kernels::Composite;
use caustica_core::math::optics::saturate_radiance;
use rayon::prelude::*;

/// Runs `composite` on the host ([`super::run`]'s arm): its buffers read from `cpu`, its
/// results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &Composite) -> Result<(), BackendError> {
    let Composite {
        direct,
        caustics,
        out,
    } = k;
    let d = cpu.get(direct.id)?.as_slice(direct.len)?;
    let c = cpu.get(caustics.id)?.as_slice(caustics.len)?;
    reserve_temporary::<[f32; 4]>(out.len as u64, "the composite")?;
    let img = composite(d, c);
    cpu.put(out.id, &img)
}

/// `direct + caustics` per texel (radiance, W/(sr m^2)), alpha 1.
pub fn composite(direct: &[[f32; 4]], caustics: &[[f32; 4]]) -> Vec<[f32; 4]> {
    direct
        .par_iter()
        .zip(caustics.par_iter())
        .map(|(d, c)| {
            [
                saturate_radiance(d[0] + c[0]),
                saturate_radiance(d[1] + c[1]),
                saturate_radiance(d[2] + c[2]),
                1.0,
            ]
        })
        .collect()
}

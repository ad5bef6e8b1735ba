//! `composite` (seed 000 section 30.3.3): the gathered caustic radiance is added to the
//! direct light, like one more light in a deferred renderer. Alpha 1.

use caustica_core::math::optics::saturate_radiance;
use rayon::prelude::*;

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

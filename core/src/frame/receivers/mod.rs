//! Where photons land: the seams techniques deposit into.
//!
//! - [`screen`]: Kim 2019's screen-space photon map (one photon, one pixel, fixed-point
//!   sums), its resolve to radiance and its filters (density-adaptive or bilateral
//!   gather, then the opt-in temporal blend and A-Trous iterations);
//! - [`atlas`]: Vanderstichelen 2021's caustic map in the receivers' texture space (tiles of one
//!   atlas, irradiance per texel), its gather and the camera's lookup through mirrors and
//!   glass.

pub mod atlas;
pub mod screen;

/// The frame seed of the `k`-th frame a receiver accumulates (`k = 0`: `seed` itself, so
/// that the first frame is a frame without accumulation, bitwise).
pub fn accumulation_seed(seed: u32, k: u32) -> u32 {
    if k == 0 {
        seed
    } else {
        seed ^ crate::math::rng::pcg_hash(k.wrapping_add(0x4143_4355))
    }
}

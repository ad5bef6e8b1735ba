//! Where photons land: the seams techniques deposit into.
//!
//! - [`screen`]: seed 000's screen-space photon map (one photon, one pixel, fixed-point
//!   sums), its resolve to radiance and its filters (density-adaptive or bilateral
//!   gather, then the opt-in temporal blend and A-Trous iterations);
//! - [`atlas`]: seed 001's caustic map in the receivers' texture space (tiles of one
//!   atlas, irradiance per texel), its gather and the camera's lookup through mirrors and
//!   glass.

pub mod atlas;
pub mod screen;

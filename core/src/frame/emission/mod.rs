//! Photon emission: the seams from which techniques draw their photons.
//!
//! - [`projection_volume`]: Kim 2019's emission domains (a cone or sphere of directions
//!   around a point or spot light, the rectangle a directional light's projection volume
//!   casts), each photon of a light carrying the same flux;
//! - [`light_view_plane`] and [`view_planes`]: Vanderstichelen 2021's light view planes (one texel,
//!   one photon) and a frame's set of them with its fixed-point quanta;
//! - [`adaptive`]: Wyman 2009's coarse-to-fine traversal of light view planes, which traces
//!   clusters of photons and refines only those that still matter.

pub mod adaptive;
pub mod light_view_plane;
pub mod projection_volume;
pub mod view_planes;

pub use projection_volume::{
    emission_domain, unpruned_domain, EmissionDomain, NoEmission, PointEmission,
};

//! Photon emission: the seams from which techniques draw their photons.
//!
//! - [`projection_volume`]: Kim 2019's emission domains (a cone or sphere of directions
//!   around a point or spot light, the rectangle a directional light's projection volume
//!   casts), each photon of a light carrying the same flux;
//! - [`light_view_plane`] and [`view_planes`]: Vanderstichelen 2021's light view planes
//!   (one texel, one photon) and a frame's set of them with its fixed-point quanta
//!   (CausticMap's and AdaptiveCaustics').
//!
//! AdaptiveCaustics' coarse-to-fine traversal of the light view planes is its own
//! (`techniques/adaptive_caustics/traversal.rs`).

pub mod light_view_plane;
pub mod projection_volume;
pub mod view_planes;

pub use projection_volume::{
    emission_domain, unpruned_domain, EmissionDomain, NoEmission, PointEmission,
};

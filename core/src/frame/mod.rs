//! What every technique shares: the [`technique::Technique`] seam, the frame plan of
//! passes and buffers with reasons ([`plan`]), frame statistics ([`stats`]), planned
//! allocation with the device-limit check ([`allocation`]), temporal (ping-pong)
//! resources ([`temporal`]), photon emission domains ([`emission`]), light view planes
//! ([`light_view_plane`]), the caustic atlas ([`caustic_atlas`]), host images ([`image`]) and error metrics against a reference
//! ([`metrics`]), and the non-blocking frame ([`submitted`]). Knows no technique.

pub mod allocation;
pub mod caustic_atlas;
pub mod emission;
pub mod error;
pub mod image;
pub mod irradiance_passes;
pub mod light_view_plane;
pub mod material_update;
pub mod metrics;
pub mod plan;
pub mod stats;
pub mod submitted;
pub mod technique;
pub mod temporal;

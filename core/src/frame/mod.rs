//! What every technique shares, and knows no technique: the frame host that owns the
//! scene, camera and camera images and applies every update ([`host`], [`screen`]), the
//! seam a technique implements over it ([`pipeline`]) and the public
//! [`technique::Technique`] seam it gets from there, with the one output vocabulary of
//! every technique ([`output`]) and the settings every technique shares ([`settings`]);
//! photon emission ([`emission`]: projection volumes, light view planes) and the receivers
//! photons land in ([`receivers`]: the screen photon map, the caustic atlas); the frame
//! plan of passes and buffers with reasons ([`plan`]), frame statistics ([`stats`]),
//! planned allocation with the device-limit check ([`allocation`]), temporal (ping-pong)
//! resources ([`temporal`]) and the filters over them ([`irradiance_passes`]), host images
//! ([`image`]), error metrics against a reference ([`metrics`]) and the non-blocking frame
//! ([`submitted`]).

pub mod allocation;
pub mod emission;
pub mod error;
pub mod host;
pub mod image;
pub mod irradiance_passes;
pub mod material_update;
pub mod metrics;
pub mod output;
pub mod pipeline;
pub mod plan;
pub mod receivers;
pub mod screen;
pub mod settings;
pub mod stats;
pub mod submitted;
pub mod technique;
pub mod temporal;

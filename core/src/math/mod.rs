//! Scalar math every backend shares: each shader port (WGSL, OpenCL C, GLSL)
//! mirrors these functions by name. Depends on nothing else in the crate.

pub mod density_gather;
pub mod fixed_point;
pub mod footprint;
pub mod geometry;
pub mod gi_photon;
pub mod irradiance_filter;
pub mod map_gather;
pub mod optics;
pub mod packing;
pub mod path_sort;
pub mod photon_allocation;
pub mod photon_clusters;
pub mod photon_plan;
pub mod photon_splat;
pub mod rng;
pub mod rsm;
pub mod sampling;
pub mod spectrum;
pub mod wavelet_warp;

//! `#[repr(C)]` + `bytemuck::Pod` data shared with every backend's kernels (DESIGN 3).
//! Every struct is built from 4-byte scalars and 16-byte-aligned groups so that WGSL,
//! GLSL std430 and OpenCL C see the same layout; sizes are asserted below.
//!
//! Spaces: positions and directions are world space; `depth` is view depth (distance
//! along the camera's forward axis); pixel coordinates have (0, 0) at the top-left.

use crate::math::geometry::normalize_scaled;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;

/// Mesh vertex: world position and unit shading normal; uv split across the two `w`s.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuVertex {
    pub position: [f32; 3],
    pub u: f32,
    pub normal: [f32; 3],
    pub v: f32,
}

/// Triangle: three vertex indices and a material index.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriangle {
    pub indices: [u32; 3],
    pub material: u32,
}

/// `GpuMaterial::kind` values.
pub mod material_kind {
    pub const DIFFUSE: u32 = 0;
    pub const MIRROR: u32 = 1;
    pub const DIELECTRIC: u32 = 2;
}

/// Material: `color` is the diffuse albedo or the mirror reflectance; `ior`, `cauchy_b`
/// and `absorption` (1/scene unit) apply to dielectrics.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    pub kind: u32,
    pub ior: f32,
    pub cauchy_b: f32,
    pub _pad: u32,
    pub color: [f32; 4],
    pub absorption: [f32; 4],
}

/// `GpuLight::kind` values.
pub mod light_kind {
    pub const POINT: u32 = 0;
    pub const SPOT: u32 = 1;
    pub const DIRECTIONAL: u32 = 2;
}

/// Light: `position` (point, spot), unit `direction` the light travels (spot axis,
/// directional), `radiance_scale` = intensity in W/sr (point, spot) or irradiance in W/m^2
/// (directional); spot cone cosines.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    pub kind: u32,
    pub cos_inner: f32,
    pub cos_outer: f32,
    pub _pad: u32,
    pub position: [f32; 4],
    pub direction: [f32; 4],
    pub intensity: [f32; 4],
}

/// Pinhole camera in world space; `tan_half_fov_x/y` are the tangents of the half field of
/// view angles (seed 000 Eq. 4's `theta_x / 2`, `theta_y / 2`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCamera {
    pub position: [f32; 3],
    pub tan_half_fov_x: f32,
    pub forward: [f32; 3],
    pub tan_half_fov_y: f32,
    pub right: [f32; 3],
    pub width: u32,
    pub up: [f32; 3],
    pub height: u32,
}

/// One texel of the G-buffer (primary visibility). `depth` is the view depth of the first
/// hit (0 where the pixel sees nothing); `normal` is the unit shading normal turned
/// towards the camera; `albedo` is the diffuse albedo (or specular colour);
/// `material` indexes the material table (`u32::MAX` on a miss).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GBufferTexel {
    pub position: [f32; 3],
    pub depth: f32,
    pub normal: [f32; 3],
    pub roughness: f32,
    pub albedo: [f32; 3],
    pub material: u32,
    pub uv: [f32; 2],
    pub view_distance: f32,
    /// Bit flags, see [`gbuffer_flags`].
    pub flags: u32,
}

/// Sentinel material index for G-buffer texels that see no geometry.
pub const NO_MATERIAL: u32 = u32::MAX;

/// `GBufferTexel::flags` bits.
pub mod gbuffer_flags {
    /// The pixel sees a diffuse surface: it can receive photons.
    pub const RECEIVER: u32 = 1;
}

/// A stored photon (32 bytes): where it stopped on a diffuse surface, its flux (W per
/// channel), the length of its last traced segment (scene units, the "hit distance" of seed
/// 000 section 30.3.2) and its incoming direction packed octahedrally
/// (`packing::pack_unit_vector`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Photon {
    pub position: [f32; 3],
    pub hit_distance: f32,
    pub flux: [f32; 3],
    pub direction: u32,
}

/// Screen-space photon map texel: fixed-point sums, each a little-endian u64 stored as
/// (lo, hi) u32 words so that 32-bit-atomic devices (carry into `hi`) and 64-bit-atomic
/// devices write bitwise identical buffers. `flux` is in units of the frame's flux quantum,
/// `hit_distance` in units of the hit-distance quantum, `photons` counts photons.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DepositTexel {
    pub flux: [[u32; 2]; 3],
    pub hit_distance: [u32; 2],
    pub photons: [u32; 2],
}

/// `TraceParams::emission` values.
pub mod emission_kind {
    /// Directions uniformly in a cone (`axis`, `cos_max`); `cos_max = -1` is the sphere.
    pub const CONE: u32 = 0;
    /// Parallel rays from the rectangle `origin + s*rect_u + t*rect_v`, s, t in [0, 1).
    pub const RECTANGLE: u32 = 1;
}

/// Parameters of one `trace_photons` dispatch: photons `first .. first + count` of the
/// `grid_w x grid_h` emission grid of light `light`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TraceParams {
    pub light: u32,
    pub emission: u32,
    pub grid_w: u32,
    pub grid_h: u32,
    pub first: u32,
    pub count: u32,
    pub seed: u32,
    pub max_bounces: u32,
    /// Cone apex / rectangle corner (world); `w`: cosine of the cone half-angle.
    pub origin: [f32; 4],
    /// Cone axis / ray direction (unit, world); `w` unused.
    pub axis: [f32; 4],
    pub rect_u: [f32; 4],
    pub rect_v: [f32; 4],
    /// Flux of each photon at emission (W per channel; seed 000 Eqs. 1 and 3); `w`: the
    /// relative power below which a photon is dropped as negligible.
    pub photon_flux: [f32; 4],
    /// Flux quantum (W) of the fixed-point stored-flux counters.
    pub flux_quantum: f32,
    pub _pad: [u32; 3],
}

/// Parameters of `deposit_screen` and `resolve_caustics`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DepositParams {
    pub camera: GpuCamera,
    /// Flux per fixed-point unit (W).
    pub flux_quantum: f32,
    /// Hit distance per fixed-point unit (scene units).
    pub hit_distance_quantum: f32,
    /// A photon is stored only if its view depth is within `depth_tolerance * depth` of the
    /// G-buffer depth at its pixel.
    pub depth_tolerance: f32,
    pub photon_capacity: u32,
}

/// Parameters of the photon gather (`tile_hit_distance`, `bilateral_gather`), seed 000
/// section 30.3.2.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GatherParams {
    pub camera: GpuCamera,
    /// World-space blur radius per unit hit distance (the source's "roughness", 0.07).
    pub roughness: f32,
    pub hit_distance_min: f32,
    pub hit_distance_max: f32,
    pub max_radius_px: u32,
    /// Depth weight `exp(-|dz| / (sigma_depth * z))`.
    pub sigma_depth: f32,
    /// Normal weight `max(0, n . n')^normal_power`.
    pub normal_power: f32,
    /// 0: horizontal pass, 1: vertical pass.
    pub axis: u32,
    pub tile_size: u32,
    pub hit_distance_quantum: f32,
    pub _pad: [u32; 3],
}

/// Parameters of `direct_light`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DirectParams {
    pub camera: GpuCamera,
    pub light_count: u32,
    /// Longest specular chain followed from a mirror/glass pixel to a diffuse surface.
    pub max_specular_depth: u32,
    /// Chains whose weight falls below this are cut.
    pub min_weight: f32,
    pub _pad: u32,
}

/// Word offsets into the photon counter buffer (`u32` words; 64-bit sums as lo, hi).
pub mod counter {
    pub const STORED: usize = 0;
    pub const NO_SPECULAR: usize = 1;
    pub const ESCAPED: usize = 2;
    pub const NEGLIGIBLE: usize = 3;
    pub const BOUNCE_LIMIT: usize = 4;
    pub const OFF_SCREEN: usize = 5;
    pub const DEPTH_MISMATCH: usize = 6;
    pub const DEPOSITED: usize = 7;
    pub const UNDERFLOW: usize = 8;
    pub const SATURATED: usize = 9;
    /// u64: ray segments traced.
    pub const RAYS: usize = 10;
    /// 3 x u64: stored flux per channel, in flux quanta.
    pub const STORED_FLUX: usize = 12;
    /// Number of u32 words.
    pub const WORDS: usize = 20;
}

impl GpuCamera {
    /// Builds the camera frame from a scene camera.
    pub fn from_camera(c: &crate::scene::Camera) -> GpuCamera {
        let forward = (c.target - c.position).normalize();
        let right = forward.cross(c.up).normalize();
        let up = right.cross(forward);
        let tan_y = (c.fov_y_deg.to_radians() * 0.5).tan();
        GpuCamera {
            position: c.position.to_array(),
            tan_half_fov_x: tan_y * c.width as f32 / c.height as f32,
            forward: forward.to_array(),
            tan_half_fov_y: tan_y,
            right: right.to_array(),
            width: c.width,
            up: up.to_array(),
            height: c.height,
        }
    }
}

/// Unit ray direction through the centre of pixel (`px`, `py`) (world space).
#[inline]
pub fn camera_ray(cam: &GpuCamera, px: u32, py: u32) -> Vec3 {
    let sx = (2.0 * (px as f32 + 0.5) / cam.width as f32 - 1.0) * cam.tan_half_fov_x;
    let sy = (1.0 - 2.0 * (py as f32 + 0.5) / cam.height as f32) * cam.tan_half_fov_y;
    (Vec3::from(cam.forward) + sx * Vec3::from(cam.right) + sy * Vec3::from(cam.up)).normalize()
}

/// Projects world point `p` to the pixel that contains it; returns (px, py, view depth)
/// or `None` when it is behind the camera or off screen.
#[inline]
pub fn project_to_pixel(cam: &GpuCamera, p: Vec3) -> Option<(u32, u32, f32)> {
    let v = p - Vec3::from(cam.position);
    let z = v.dot(Vec3::from(cam.forward));
    if z.is_nan() || z <= 0.0 {
        return None;
    }
    let sx = v.dot(Vec3::from(cam.right)) / (z * cam.tan_half_fov_x);
    let sy = v.dot(Vec3::from(cam.up)) / (z * cam.tan_half_fov_y);
    let fx = (sx + 1.0) * 0.5 * cam.width as f32;
    let fy = (1.0 - sy) * 0.5 * cam.height as f32;
    if !(fx >= 0.0 && fy >= 0.0 && fx < cam.width as f32 && fy < cam.height as f32) {
        return None;
    }
    Some((fx as u32, fy as u32, z))
}

// ---- functions over the layouts (shader ports mirror them by name)

/// A point on a triangle, interpolated from its vertices (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    pub position: Vec3,
    /// Unit geometric normal, turned to the side of the interpolated vertex normals (for
    /// closed shapes: outward). Used to tell inside from outside and to offset rays.
    pub geometric_normal: Vec3,
    /// Unit interpolated shading normal (same side as `geometric_normal`).
    pub shading_normal: Vec3,
    pub uv: glam::Vec2,
}

/// Interpolates the surface at barycentrics (`u`, `v`) of the triangle (`a`, `b`, `c`).
#[inline]
pub fn surface_point(a: &GpuVertex, b: &GpuVertex, c: &GpuVertex, u: f32, v: f32) -> SurfacePoint {
    let w = 1.0 - u - v;
    let (pa, pb, pc) = (
        Vec3::from(a.position),
        Vec3::from(b.position),
        Vec3::from(c.position),
    );
    let (na, nb, nc) = (
        Vec3::from(a.normal),
        Vec3::from(b.normal),
        Vec3::from(c.normal),
    );
    let mut ng = normalize_scaled((pb - pa).cross(pc - pa), Vec3::Y);
    let n_sum = na + nb + nc;
    if ng.dot(n_sum) < 0.0 {
        ng = -ng;
    }
    let mut ns = (w * na + u * nb + v * nc).normalize_or(ng);
    if !ns.is_finite() {
        ns = ng;
    }
    SurfacePoint {
        position: w * pa + u * pb + v * pc,
        geometric_normal: ng,
        shading_normal: ns,
        uv: glam::Vec2::new(w * a.u + u * b.u + v * c.u, w * a.v + u * b.v + v * c.v),
    }
}

/// Surface area (scene units^2) that pixel `index` (row-major) of `cam` covers on the
/// surface its G-buffer texel `g` sees: the footprint at the texel's view depth (Eq. 4)
/// over the view and surface cosines ([`pixel_surface_area`]). Resolve divides a
/// pixel's flux by it.
pub fn gbuffer_pixel_area(cam: &GpuCamera, index: u32, g: &GBufferTexel) -> f32 {
    let ray = camera_ray(cam, index % cam.width, index / cam.width);
    let footprint = crate::math::footprint::pixel_footprint(
        g.depth,
        cam.width,
        cam.height,
        cam.tan_half_fov_x,
        cam.tan_half_fov_y,
    );
    crate::math::footprint::pixel_surface_area(
        footprint,
        ray.dot(glam::Vec3::from(cam.forward)),
        ray.dot(glam::Vec3::from(g.normal)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::size_of;

    #[test]
    fn sizes_are_multiples_of_16() {
        assert_eq!(size_of::<GpuVertex>(), 32);
        assert_eq!(size_of::<GpuTriangle>(), 16);
        assert_eq!(size_of::<GpuMaterial>(), 48);
        assert_eq!(size_of::<GpuLight>(), 64);
        assert_eq!(size_of::<GpuCamera>(), 64);
        assert_eq!(size_of::<GBufferTexel>(), 64);
        assert_eq!(size_of::<Photon>(), 32);
        assert_eq!(size_of::<DepositTexel>(), 40);
        assert_eq!(size_of::<TraceParams>() % 16, 0);
        assert_eq!(size_of::<DepositParams>() % 16, 0);
        assert_eq!(size_of::<GatherParams>() % 16, 0);
        assert_eq!(size_of::<DirectParams>() % 16, 0);
    }

    #[test]
    fn projection_inverts_camera_ray() {
        let cam = GpuCamera::from_camera(&crate::scene::builtin::sphere().camera);
        for &(px, py) in &[(0u32, 0u32), (480, 270), (959, 539), (13, 400)] {
            let d = camera_ray(&cam, px, py);
            let p = Vec3::from(cam.position) + 3.7 * d;
            let (qx, qy, z) = project_to_pixel(&cam, p).unwrap();
            assert_eq!((qx, qy), (px, py));
            assert!((z - 3.7 * d.dot(Vec3::from(cam.forward))).abs() < 1e-4);
        }
    }
}

//! `#[repr(C)]` + `bytemuck::Pod` data shared with every backend's kernels, defined once
//! here. Every struct is built from 4-byte scalars and 16-byte-aligned groups so that WGSL,
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
    /// World-space position (scene units).
    pub position: [f32; 3],
    /// Texture coordinate u.
    pub u: f32,
    /// Unit shading normal (world space); closed shapes point it outward.
    pub normal: [f32; 3],
    /// Texture coordinate v.
    pub v: f32,
}

/// Triangle: three vertex indices and a material index.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuTriangle {
    /// Indices of the three vertices in the vertex array.
    pub indices: [u32; 3],
    /// Index into the material table (the scene's materials in name order).
    pub material: u32,
}

/// `GpuMaterial::kind` values.
pub mod material_kind {
    /// Lambertian receiver: stores photons, shaded by `direct_light`.
    pub const DIFFUSE: u32 = 0;
    /// Perfect specular reflector (a caustic caster).
    pub const MIRROR: u32 = 1;
    /// Smooth refracting interface such as glass or water (a caustic caster).
    pub const DIELECTRIC: u32 = 2;
}

/// Material: `color` is the diffuse albedo or the mirror reflectance; `ior`,
/// `dispersion`, `ior_model` and `absorption` (1/scene unit) apply to dielectrics.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuMaterial {
    /// One of [`material_kind`].
    pub kind: u32,
    /// Index of refraction relative to the surrounding medium (dielectrics): at 550 nm
    /// under the Cauchy model, at the d line (587.56 nm) under the Abbe model.
    pub ior: f32,
    /// How the index varies with wavelength, by `ior_model`: Cauchy's `B` (um^2) of
    /// `n(lambda) = A + B / lambda^2`, or the Abbe number `V_d` (> 0). 0: no dispersion
    /// (the kernels test this alone).
    pub dispersion: f32,
    /// One of [`ior_model`](crate::math::optics::ior_model) (Cauchy is 0).
    pub ior_model: u32,
    /// rgb: diffuse albedo or mirror reflectance per channel in [0, 1] (1 for dielectrics); `w` unused.
    pub color: [f32; 4],
    /// rgb: Beer-Lambert absorption coefficient inside a dielectric (1/scene unit); `w` unused.
    pub absorption: [f32; 4],
}

/// `GpuLight::kind` values.
pub mod light_kind {
    /// Isotropic point light.
    pub const POINT: u32 = 0;
    /// Point light restricted to a cone with a smooth falloff.
    pub const SPOT: u32 = 1;
    /// Parallel light from infinitely far away.
    pub const DIRECTIONAL: u32 = 2;
}

/// Light: `position` (point, spot), unit `direction` the light travels (spot axis,
/// directional), `intensity` in W/sr (point, spot) or irradiance in W/m^2
/// (directional); spot cone cosines, and for a spot narrower than
/// [`NARROW_CONE`](crate::math::sampling::NARROW_CONE) their `1 - cos` computed without
/// cancellation ([`light_spot_falloff`](crate::device::device_scene::light_spot_falloff)).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuLight {
    /// One of [`light_kind`].
    pub kind: u32,
    /// Cosine of the spot's inner half-angle (full intensity inside); -1 for point lights.
    pub cos_inner: f32,
    /// Cosine of the spot's outer half-angle (zero intensity outside); -1 for point lights.
    pub cos_outer: f32,
    /// `1 - cos_outer` computed without cancellation (spot lights; 2 for the others).
    pub one_minus_cos_outer: f32,
    /// World-space position, `w = 1` (point and spot lights; unused for directional).
    pub position: [f32; 4],
    /// Unit world-space direction the light travels, `w = 0` (spot axis, directional).
    pub direction: [f32; 4],
    /// rgb: intensity in W/sr (point, spot) or irradiance in W/m^2 (directional); `w`:
    /// `1 - cos_inner` computed without cancellation (spot lights; 0 for the others).
    pub intensity: [f32; 4],
}

/// Pinhole camera in world space; `tan_half_fov_x/y` are the tangents of the half field of
/// view angles (Kim 2019 Eq. 4's `theta_x / 2`, `theta_y / 2`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GpuCamera {
    /// Eye position (world space).
    pub position: [f32; 3],
    /// Tangent of half the horizontal field of view.
    pub tan_half_fov_x: f32,
    /// Unit viewing direction (world space); view depth is measured along it.
    pub forward: [f32; 3],
    /// Tangent of half the vertical field of view.
    pub tan_half_fov_y: f32,
    /// Unit right vector (world space): screen x grows along it.
    pub right: [f32; 3],
    /// Image width (pixels).
    pub width: u32,
    /// Unit up vector (world space), orthogonal to `forward` and `right`: screen y grows against it.
    pub up: [f32; 3],
    /// Image height (pixels).
    pub height: u32,
}

/// One texel of the G-buffer (primary visibility). `depth` is the view depth of the first
/// hit (0 where the pixel sees nothing); `normal` is the unit shading normal turned
/// towards the camera; `albedo` is the diffuse albedo (or specular colour);
/// `material` indexes the material table (`u32::MAX` on a miss).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GBufferTexel {
    /// World-space position of the first hit.
    pub position: [f32; 3],
    /// View depth of the first hit (scene units); 0 on a miss.
    pub depth: f32,
    /// Unit shading normal (world space), turned towards the camera.
    pub normal: [f32; 3],
    /// Unit geometric normal of the hit triangle (world space), turned towards the camera
    /// on its own, packed octahedrally in two snorm16
    /// ([`crate::math::packing::pack_unit_vector`]): PhotonGi's shading-normal correction
    /// (Smal 2019, Eq. 20) compares the light direction with both normals.
    pub geometric_normal: u32,
    /// The material's `color`: diffuse albedo, mirror reflectance, 1 for dielectrics.
    pub albedo: [f32; 3],
    /// Index into the material table; [`NO_MATERIAL`] on a miss.
    pub material: u32,
    /// Interpolated texture coordinates.
    pub uv: [f32; 2],
    /// Distance from the eye to the first hit along the pixel's ray (scene units).
    pub view_distance: f32,
    /// Bit flags, see [`gbuffer_flags`].
    pub flags: u32,
}

/// The G-buffer is stored as [`GBUFFER_PLANES`] planes of 16 bytes per pixel, so that no
/// per-pixel buffer is larger than an RGBA f32 image (a device's storage-binding limit
/// then bounds the frame at 16 bytes per pixel, not 64): plane `k` of pixel `i` holds
/// bytes `16k .. 16k + 16` of its [`GBufferTexel`] as four u32 words (0: position, depth;
/// 1: normal, geometric normal; 2: albedo, material; 3: uv, view_distance, flags). The split is
/// a copy of bits, so the assembled texel is bitwise the texel.
pub const GBUFFER_PLANES: usize = 4;

/// One pixel of one G-buffer plane (16 bytes).
pub type GBufferPlaneTexel = [u32; 4];

impl GBufferTexel {
    /// The texel's [`GBUFFER_PLANES`] plane texels (its bytes in order, 16 a plane).
    pub fn to_planes(&self) -> [GBufferPlaneTexel; GBUFFER_PLANES] {
        bytemuck::cast(*self)
    }

    /// The texel whose plane texels are `p` (the inverse of [`GBufferTexel::to_planes`]).
    pub fn from_planes(p: [GBufferPlaneTexel; GBUFFER_PLANES]) -> GBufferTexel {
        bytemuck::cast(p)
    }
}

/// The G-buffer's planes as host slices: what the CPU kernels read texels from (the
/// shaders' `load_gbuffer`), without assembling a copy of the whole G-buffer.
#[derive(Clone, Copy, Debug)]
pub struct GBufferView<'a> {
    /// Plane `k` of every pixel.
    pub planes: [&'a [GBufferPlaneTexel]; GBUFFER_PLANES],
}

impl GBufferView<'_> {
    /// Texels (the shortest plane's length).
    pub fn len(&self) -> usize {
        self.planes.iter().map(|p| p.len()).min().unwrap_or(0)
    }

    /// Whether it holds no texel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The texel of pixel `i`, assembled from the planes.
    pub fn load_gbuffer(&self, i: usize) -> GBufferTexel {
        GBufferTexel::from_planes(self.planes.map(|p| p[i]))
    }
}

/// Assembles the G-buffer texels from its planes (each `pixels` texels long; the
/// shortest plane bounds the result).
pub fn gbuffer_from_planes(planes: [&[GBufferPlaneTexel]; GBUFFER_PLANES]) -> Vec<GBufferTexel> {
    let v = GBufferView { planes };
    (0..v.len()).map(|i| v.load_gbuffer(i)).collect()
}

/// Splits G-buffer texels into their planes (see [`GBUFFER_PLANES`]).
pub fn gbuffer_to_planes(texels: &[GBufferTexel]) -> [Vec<GBufferPlaneTexel>; GBUFFER_PLANES] {
    std::array::from_fn(|k| texels.iter().map(|t| t.to_planes()[k]).collect())
}

/// Sentinel material index for G-buffer texels that see no geometry.
pub const NO_MATERIAL: u32 = u32::MAX;

/// `GBufferTexel::flags` bits.
pub mod gbuffer_flags {
    /// The pixel sees a diffuse surface: it can receive photons.
    pub const RECEIVER: u32 = 1;
}

/// A stored photon (32 bytes): where it stopped on a diffuse surface, its flux (W per
/// channel), the length of its last traced segment (scene units, the "hit distance" of
/// Kim 2019, section 30.3.2) and its incoming direction packed octahedrally
/// (`packing::pack_unit_vector`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Photon {
    /// World-space point where the photon met the diffuse surface.
    pub position: [f32; 3],
    /// Length of the photon's last segment (scene units).
    pub hit_distance: f32,
    /// Flux carried by the photon (W per channel).
    pub flux: [f32; 3],
    /// Unit direction of travel as it arrived (world space), packed octahedrally.
    pub direction: u32,
}

/// Screen-space photon map texel: fixed-point sums, each a little-endian u64 stored as
/// (lo, hi) u32 words so that 32-bit-atomic devices (carry into `hi`) and 64-bit-atomic
/// devices write bitwise identical buffers. `flux` is in units of the frame's flux quantum,
/// `hit_distance` in units of the hit-distance quantum, `photons` counts photons.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DepositTexel {
    /// Summed flux per channel (r, g, b), in flux quanta.
    pub flux: [[u32; 2]; 3],
    /// Summed hit distance of the deposited photons, in hit-distance quanta.
    pub hit_distance: [u32; 2],
    /// Number of photons deposited in the pixel.
    pub photons: [u32; 2],
}

/// u32 words of a [`DepositTexel`].
pub const DEPOSIT_TEXEL_WORDS: usize = 10;

/// The screen photon map is stored as planes of at most 4 words (16 bytes) per pixel:
/// plane `k` of pixel `i` holds words `DEPOSIT_PLANE_FIRST[k] ..` `+ DEPOSIT_PLANE_WORDS[k]`
/// of its [`DepositTexel`] (flux r, g; flux b, hit distance; photons). No (lo, hi) pair
/// straddles two planes, so the atomic carry stays in one buffer.
pub const DEPOSIT_PLANES: usize = 3;
/// Words per pixel of each photon-map plane.
pub const DEPOSIT_PLANE_WORDS: [usize; DEPOSIT_PLANES] = [4, 4, 2];
/// First texel word of each photon-map plane.
pub const DEPOSIT_PLANE_FIRST: [usize; DEPOSIT_PLANES] = [0, 4, 8];

/// Photon-map plane and index in it of word `word` of pixel `pixel`: the one accessor
/// every kernel reaches the planes through.
pub fn deposit_word(pixel: u32, word: u32) -> (usize, usize) {
    let k = word as usize / 4;
    (
        k,
        pixel as usize * DEPOSIT_PLANE_WORDS[k] + (word as usize - DEPOSIT_PLANE_FIRST[k]),
    )
}

impl DepositTexel {
    /// The texel's words in order.
    pub fn words(&self) -> [u32; DEPOSIT_TEXEL_WORDS] {
        bytemuck::cast(*self)
    }
}

/// The photon map's planes as host slices (the CPU kernels read texels from them).
#[derive(Clone, Copy, Debug)]
pub struct PhotonMapView<'a> {
    /// Plane `k`: `DEPOSIT_PLANE_WORDS[k]` words per pixel.
    pub planes: [&'a [u32]; DEPOSIT_PLANES],
}

impl PhotonMapView<'_> {
    /// Texels (the shortest plane's, in pixels).
    pub fn len(&self) -> usize {
        (0..DEPOSIT_PLANES)
            .map(|k| self.planes[k].len() / DEPOSIT_PLANE_WORDS[k])
            .min()
            .unwrap_or(0)
    }

    /// Whether it holds no texel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Word `word` of pixel `pixel`'s texel.
    pub fn photon_map_word(&self, pixel: u32, word: u32) -> u32 {
        let (k, at) = deposit_word(pixel, word);
        self.planes[k][at]
    }

    /// The texel of pixel `i`, assembled from the planes.
    pub fn load(&self, i: usize) -> DepositTexel {
        let w: [u32; DEPOSIT_TEXEL_WORDS] =
            std::array::from_fn(|j| self.photon_map_word(i as u32, j as u32));
        bytemuck::cast(w)
    }
}

/// Assembles the photon-map texels from its planes (plane `k` holds
/// `DEPOSIT_PLANE_WORDS[k]` words per pixel).
pub fn deposit_from_planes(planes: [&[u32]; DEPOSIT_PLANES]) -> Vec<DepositTexel> {
    let v = PhotonMapView { planes };
    (0..v.len()).map(|i| v.load(i)).collect()
}

/// Splits photon-map texels into their planes (see [`DEPOSIT_PLANES`]).
pub fn deposit_to_planes(texels: &[DepositTexel]) -> [Vec<u32>; DEPOSIT_PLANES] {
    std::array::from_fn(|k| {
        let (first, n) = (DEPOSIT_PLANE_FIRST[k], DEPOSIT_PLANE_WORDS[k]);
        texels
            .iter()
            .flat_map(|t| t.words()[first..first + n].to_vec())
            .collect()
    })
}

/// `TraceParams::emission` values.
pub mod emission_kind {
    /// Directions uniformly in a cone (`axis`, `cos_max`); `cos_max = -1` is the sphere.
    pub const CONE: u32 = 0;
    /// Parallel rays from the rectangle `origin + s*rect_u + t*rect_v`, s, t in [0, 1).
    pub const RECTANGLE: u32 = 1;
    /// A perspective light view plane (Vanderstichelen 2021, section 3.1): rays from the pinhole
    /// `origin` through `axis + ndc.x * rect_u + ndc.y * rect_v` with `ndc = (2 s - 1,
    /// 1 - 2 t)`, s, t in [0, 1) (row 0 at the top); `rect_u.w`, `rect_v.w` hold the
    /// tangents of the half fields of view (`rect_u`, `rect_v` are the plane's unit right
    /// and up vectors scaled by them). Photon flux: `photon_flux` (the flux of a texel at
    /// the plane's centre, `I * dx * dy`) times the texel's
    /// [`view_plane_texel_weight`](crate::math::sampling::view_plane_texel_weight) and a
    /// spot light's falloff.
    pub const VIEW_PLANE: u32 = 2;
}

/// What `trace_photons` writes into a [`Photon`] (its `SURFACE_STORE` switch).
pub mod photon_store {
    /// World space (Sspm): `position` is the world-space hit point, `direction` the
    /// packed direction of travel.
    pub const WORLD: u32 = 0;
    /// Texture space (CausticMap): `position.x, .y` hold the hit's interpolated uv
    /// (`.z` = 0) and `direction` the index of the triangle it landed on; `flux` and
    /// `hit_distance` as in world space.
    pub const SURFACE: u32 = 1;
    // The `ADAPTIVE` variant of `trace_photons` stores texture space in one slot per
    // traced photon (slot = the photon's index in the batch): a stored photon as
    // `SURFACE` with `position.z` = 1; a photon that stored nothing with zero flux,
    // `direction` = `photon_clusters::NO_TRIANGLE` and `position.z` = 1 if it met a
    // caustic caster (`photon_clusters::photon_met_caster`), else 0.
}

/// Sentinel tile index: a triangle that is no receiver, an atlas texel outside every
/// tile.
pub const NO_TILE: u32 = u32::MAX;

/// One receiver's square tile of the caustic atlas as the kernels read it (texels):
/// `[x, y, side, receiver object index | flags]`, the flag
/// [`crate::math::map_gather::TILE_FULLY_COVERED`] set where every texel of the tile is
/// covered (`math::map_gather::tile_receiver` strips it).
pub type AtlasTileTexel = [u32; 4];

/// One atlas texel as the kernels read it: `[world area (f32 bits, scene units^2; 0 where
/// no UV triangle of the receiver covers the texel centre), tile index (`NO_TILE`
/// outside every tile)]`.
pub type AtlasTexel = [u32; 2];

/// Parameters of the atlas deposit (`trace_photons`' `fused_deposit`) and `gather_caustic_map` (the caustic atlas, Vanderstichelen 2021).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct AtlasParams {
    /// Atlas width (texels).
    pub width: u32,
    /// Atlas height (texels).
    pub height: u32,
    /// Flux per fixed-point unit (W).
    pub flux_quantum: f32,
    /// Hit distance per fixed-point unit (scene units).
    pub hit_distance_quantum: f32,
    /// Slots in the photon buffer.
    pub photon_capacity: u32,
    /// Width `N` of the gather window (odd; 1: no gather, the raw map).
    pub gather_width: u32,
    /// Padding to the 16-byte boundary.
    pub _pad: [u32; 2],
}

/// Parameters of `refine_clusters` (AdaptiveCaustics, Wyman 2009, section 3.2): one batch of
/// clusters of one level of one light view plane, traced by `trace_photons`' `ADAPTIVE`
/// variant into one slot per photon.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RefineParams {
    /// Atlas width (texels), for the texel under a photon's uv.
    pub atlas_width: u32,
    /// Flux per fixed-point unit (W).
    pub flux_quantum: f32,
    /// Hit distance per fixed-point unit (scene units).
    pub hit_distance_quantum: f32,
    /// The batch's level (0: the start grid).
    pub level: u32,
    /// The finest level: everything relevant left there is output.
    pub finest: u32,
    /// [`cluster_metric`](crate::math::photon_clusters::cluster_metric).
    pub metric: u32,
    /// First level at which the error metric is checked (coarser levels use the
    /// traversal-level metric, Wyman 2009, section 4.2).
    pub error_from_level: u32,
    /// Texels a side of the level's grid.
    pub grid_w: u32,
    /// First entry of the batch in the cluster list (`trace_photons` read the same).
    pub first: u32,
    /// Clusters in the batch (four photon slots each).
    pub count: u32,
    /// Entries the child list holds.
    pub children_capacity: u32,
    /// [`cluster_relevance`](crate::math::photon_clusters::cluster_relevance): what keeps
    /// a cluster from being discarded.
    pub relevance: u32,
    /// Rectangles in `caster_rects` (the buffer may hold more: a backend can round a
    /// binding up, so kernels never take its length from the buffer).
    pub rect_count: u32,
    /// Where output photons go
    /// ([`cluster_target`](crate::math::photon_clusters::cluster_target)): deposited into
    /// the atlas, or appended (world space) for Sspm's screen deposit.
    pub deposit_target: u32,
    /// The error metric's tolerance: a cluster converges when its four photons land in a
    /// square of at most this many texels a side (1: Wyman 2009's one texel), and its
    /// photons are then splatted over that footprint
    /// ([`footprint_window`](crate::math::photon_clusters::footprint_window)); at most
    /// [`MAX_ERROR_TEXELS`](crate::math::photon_clusters::MAX_ERROR_TEXELS).
    pub error_texels: u32,
    /// Padding to the 16-byte boundary.
    pub _pad: u32,
    /// The frame's camera: with the screen target a photon's "texel" is the pixel it
    /// projects to (`project_to_pixel`).
    pub camera: GpuCamera,
}

/// Words of `refine_clusters`' cluster counts buffer.
pub mod cluster_count {
    /// Entries written to the child cluster list (four per refined cluster).
    pub const CHILDREN: usize = 0;
    /// Clusters output (their photons deposited).
    pub const OUTPUT: usize = 1;
    /// Clusters discarded (every photon missed the casters).
    pub const DISCARDED: usize = 2;
    /// Photons deposited (stored photons of output clusters).
    pub const OUTPUT_PHOTONS: usize = 3;
    /// Clusters that converged before the finest level, appended to the converged list
    /// (to be output from fresh photons).
    pub const CONVERGED: usize = 4;
    /// Clusters to be refined whose children did not fit the next level's list: appended
    /// to the converged list instead (output at their level from fresh photons, so no
    /// photon is lost), and counted here.
    pub const OVERFLOW: usize = 5;
    /// Number of u32 words.
    pub const WORDS: usize = 8;
}

/// Parameters of `seed_clusters` (AdaptiveCaustics' bounds seed): the clusters of one
/// level's grid inside a window, tested against the casters' rectangles.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SeedParams {
    /// Texels a side of the level's grid (a power of two; clusters are 2x2 texels).
    pub grid_w: u32,
    /// The window's first cluster column and row (clusters of the level's grid).
    pub first_x: u32,
    /// See `first_x`.
    pub first_y: u32,
    /// The window's clusters a row (one thread each).
    pub window_w: u32,
    /// The window's rows of clusters.
    pub window_h: u32,
    /// Rectangles in `caster_rects` (as `RefineParams::rect_count`).
    pub rect_count: u32,
    /// Entries the list holds; appends past it are counted, not written.
    pub capacity: u32,
    /// Padding to the 16-byte boundary.
    pub _pad: u32,
}

/// Parameters of `temporal_blend` (Smal 2019, section 24.4.1, Eqs. 10-13): the frame's
/// camera and the history's, the blend's constants and whether a history exists.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TemporalParams {
    /// This frame's camera (its image size is the images').
    pub camera: GpuCamera,
    /// The camera the history was rendered with (reprojection target).
    pub previous: GpuCamera,
    /// Largest weight of the history (Eq. 13's 0.95).
    pub alpha_max: f32,
    /// Depth weight's `sigma_z` (Eq. 10).
    pub sigma_z: f32,
    /// Normal weight's exponent `sigma_n` (Eq. 11).
    pub sigma_n: f32,
    /// Eq. 10's guard, relative to the depth.
    pub epsilon: f32,
    /// Frames in the history (0: none yet, or reset: the history is not read).
    pub history_frames: u32,
    /// Padding to the 16-byte boundary.
    pub _pad: [u32; 3],
}

/// Parameters of one `atrous_filter` iteration (Smal 2019, section 24.4.2, Eqs. 14-18).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct AtrousParams {
    /// The frame's camera (its image size is the images').
    pub camera: GpuCamera,
    /// The iteration `i` (taps `2^i` pixels apart).
    pub iteration: u32,
    /// 1 on the last iteration: it writes `E_final` instead of `s_(i+1)`.
    pub last: u32,
    /// Depth weight's `sigma_z` (Eq. 10).
    pub sigma_z: f32,
    /// Normal weight's exponent `sigma_n` (Eq. 11).
    pub sigma_n: f32,
    /// Eq. 10's guard, relative to the depth.
    pub epsilon: f32,
    /// Standard deviations of the kernel's values a detail coefficient may keep (Eq. 18's
    /// bounds `b_i`).
    pub clip_sigmas: f32,
    /// Padding to the 16-byte boundary.
    pub _pad: [u32; 2],
}

/// One texel of a PhotonGi reflective shadow map (Smal 2019, section 24.2.1), 32 bytes: what
/// the light's face camera sees there and the flux that leaves it. Written by
/// `rsm_importance` (level 0) from the face's G-buffer, read by `sample_rsm`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RsmTexel {
    /// World-space point the light sees through the texel's centre.
    pub position: [f32; 3],
    /// Unit shading normal there, turned towards the light, packed octahedrally
    /// (`packing::pack_unit_vector`).
    pub normal: u32,
    /// Flux leaving the point (W per channel): the flux arriving through the texel
    /// (intensity x spot falloff x the texel's solid angle) times the diffuse albedo on a
    /// diffuse surface, unscaled on a mirror or dielectric (the trace applies those).
    pub flux: [f32; 3],
    /// One of [`crate::math::rsm::rsm_texel_kind`].
    pub kind: u32,
}

/// A photon leaving a reflective-shadow-map point (32 bytes): written by `sample_rsm`, the
/// start of a `trace_indirect` path.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RsmPhoton {
    /// Ray origin (world space): the RSM point lifted off its surface after a diffuse
    /// bounce, or the light's position for a photon on its way to a specular RSM point.
    pub origin: [f32; 3],
    /// Unit direction of travel, packed octahedrally (`packing::pack_unit_vector`).
    pub direction: u32,
    /// Flux (W per channel), the sampling probability divided out (zero: no photon).
    pub flux: [f32; 3],
    /// Diffuse bounces already made: 1 from a diffuse RSM point, 0 on the way to a
    /// specular one.
    pub bounces: u32,
}

/// Parameters of `rsm_importance` and `sample_rsm` (Smal 2019, section 24.2.1).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct RsmParams {
    /// The face camera (the light's position, the face's frame, `side x side` pixels)
    /// whose G-buffer `rsm_importance` level 0 reads.
    pub face_camera: GpuCamera,
    /// Index of the light in the light buffer.
    pub light: u32,
    /// `rsm_importance`: the face slot level 0 writes (of the stacked texel and pyramid
    /// arrays); `sample_rsm`: the light's first face slot.
    pub face: u32,
    /// Texels per face side (a power of two).
    pub side: u32,
    /// `rsm_importance`: the pyramid level this launch writes (0: texels and importance
    /// from the G-buffer; `k > 0`: 2x2 sums of level `k - 1` of every face up to `face`).
    pub level: u32,
    /// `sample_rsm`: the light's faces (slots `face .. face + face_count`).
    pub face_count: u32,
    /// `sample_rsm`: the light's first sample (slot in the output buffer).
    pub first_sample: u32,
    /// `sample_rsm`: the light's samples this frame (the Hammersley set's size).
    pub sample_count: u32,
    /// The frame seed hashed with the light (the set's Cranley-Patterson rotation).
    pub seed: u32,
    /// `rsm_importance` level 0: how texels are weighted in the pyramid
    /// (`math::rsm::rsm_sampling`).
    pub sampling: u32,
    /// Padding to a multiple of 16 bytes.
    pub _pad: [u32; 3],
}

/// PhotonGi's stored photon (Smal 2019, Table 24-2, derived in `docs/photon-gi.md`), 32
/// bytes: written by `trace_indirect`, splatted by `splat_photons`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GiPhoton {
    /// World-space hit point.
    pub position: [f32; 3],
    /// Power in units of the frame's power scale (W per channel / `power_scale`), rgb9e5
    /// (`packing::pack_rgb9e5`).
    pub power: u32,
    /// Unit geometric normal at the hit, turned towards the arriving photon, packed
    /// octahedrally.
    pub normal: u32,
    /// Unit direction of travel as it arrived, packed octahedrally.
    pub direction: u32,
    /// Length of the photon's last segment (scene units; Eq. 2's `l`).
    pub ray_length: f32,
    /// Row-major index of the screen tile the photon projects to (Eqs. 3-6's tile).
    pub tile: u32,
}

/// Parameters of `trace_indirect` (Smal 2019, section 24.2.2).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct IndirectTraceParams {
    /// The frame's camera: photons outside its frustum or on faces turned away from it
    /// are not stored, stored ones are counted in their screen tile.
    pub camera: GpuCamera,
    /// First `RsmPhoton` of the launch.
    pub first: u32,
    /// `RsmPhoton`s in the launch (one thread each).
    pub count: u32,
    /// Frame seed (random dimensions of the bounces and roulette).
    pub seed: u32,
    /// Diffuse bounces of a path (the RSM's included): photons are stored at the hits
    /// after bounces `1 ..= max_bounces`.
    pub max_bounces: u32,
    /// Most ray segments of a path (bounds specular chains).
    pub max_segments: u32,
    /// Screen tile edge (pixels) of the density counts.
    pub tile_size: u32,
    /// One of [`crate::math::gi_photon::gi_store`]: packed `GiPhoton`s, or float
    /// `Photon`s for the reference.
    pub store: u32,
    /// Reflectance of dielectric interfaces, one of
    /// [`fresnel_model`](crate::math::optics::fresnel_model).
    pub fresnel_model: u32,
    /// Unit of the packed power (W): stored power is `power / power_scale`.
    pub power_scale: f32,
    /// Flux quantum (W) of the fixed-point stored-flux counters.
    pub flux_quantum: f32,
    /// How a photon takes a colour at its first dispersive surface, one of
    /// [`dispersion_mode`](crate::math::spectrum::dispersion_mode) (0: spectral).
    pub dispersion_mode: u32,
    /// The launch's first path segment: 0 starts the paths at their RSM photons; `k > 0`
    /// (the `WAVES` variant's later waves) continues the `IndirectPath`s queued after
    /// segment `k - 1`.
    pub segment_first: u32,
    /// The launch's end segment (exclusive): `max_segments` traces each path to its end;
    /// less (a wave) queues the paths still going after segment `segment_end - 1`.
    pub segment_end: u32,
    /// The launch's chunk of the `count` photons (from their start): a launch from the
    /// RSM photons traces photons `chunk_first .. chunk_first + chunk_size` of them that
    /// are below `count` ([`crate::math::rsm::chunk_photons`]; `chunk_first` 0 with
    /// `chunk_size` `u32::MAX`: all of them).
    pub chunk_first: u32,
    /// See `chunk_first`.
    pub chunk_size: u32,
    /// 1 (the `sorted_waves` schedule, a wave that queues paths): each queued path's sort
    /// key ([`path_sort_key`](crate::math::path_sort::path_sort_key) of its next ray
    /// under `key_origin_min` and `key_origin_scale`) and its rank among the paths of
    /// that key are written beside it (`path_keys`), the key's count in `buckets` going
    /// up; 0: no keys.
    pub queue_keys: u32,
    /// The scene box's lower corner (world space) of the sort key's origin cells.
    pub key_origin_min: [f32; 3],
    /// 1 (a sorted wave after the first): thread `t` continues path `order[t]` of the
    /// queue (`sort_indirect_paths`' order of its keys); 0: path `t`.
    pub queue_order: u32,
    /// Origin cells per scene unit along each axis of the sort key.
    pub key_origin_scale: [f32; 3],
    /// Padding to the 16-byte boundary.
    pub _pad: u32,
}

/// A `trace_indirect` path between two waves (the `WAVES` variant): everything its next
/// segment needs, full precision, so that the waves trace exactly the single launch's
/// path (Smal 2019, section 24.2.2).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct IndirectPath {
    /// The next ray's origin (world space, already lifted off its surface).
    pub origin: [f32; 3],
    /// The photon's index among the RSM photons (the key of its random numbers).
    pub index: u32,
    /// The next ray's unit direction (world space).
    pub direction: [f32; 3],
    /// Diffuse bounces made so far (the RSM's included).
    pub bounces: u32,
    /// Flux (W per channel).
    pub flux: [f32; 3],
    /// Wavelength (micrometres) taken at the first dispersive surface; 0: none yet.
    pub wavelength: f32,
}

/// Parameters of `sort_indirect_paths` (the `sorted_waves` schedule's queues ordered by
/// the keys `trace_indirect` wrote beside them).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PathSortParams {
    /// Which launch, one of [`path_sort_phase`](crate::math::path_sort::path_sort_phase).
    pub phase: u32,
    /// The word of `path_counts` that holds the queue's length.
    pub count_word: u32,
    /// Padding to the 16-byte boundary.
    pub _pad: [u32; 2],
}

/// Parameters of `splat_photons` (Smal 2019, section 24.3, Eqs. 2-9): the camera, the
/// tiles and the kernel's constants
/// ([`SplatConstants`](crate::math::photon_splat::SplatConstants)).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct SplatParams {
    /// The frame's camera.
    pub camera: GpuCamera,
    /// Screen tile edge (pixels) of the density counts.
    pub tile_size: u32,
    /// Unit of the packed power (W).
    pub power_scale: f32,
    /// Flux quantum (W) of the photon map the splats add to.
    pub flux_quantum: f32,
    /// Most pixels from a splat's centre pixel to its edge, per axis: larger splats are
    /// clipped there and counted (`counter::SATURATED`'s word for splats).
    pub max_splat_px: u32,
    /// Eq. 2's `l_max` (scene units).
    pub max_ray_length: f32,
    /// Eq. 2's lower clamp.
    pub min_length_scale: f32,
    /// Eq. 6's `r_min` (scene units).
    pub density_radius_min: f32,
    /// Eq. 6's `r_max` (scene units).
    pub density_radius_max: f32,
    /// Eq. 6's `n_tile`.
    pub photons_per_pixel: f32,
    /// `s_n`.
    pub normal_compression: f32,
    /// `s_max` of Eq. 7.
    pub max_stretch: f32,
    /// Eqs. 3-4's `c_tile`.
    pub tile_constant: f32,
    /// Smallest uniform kernel scale, in pixel footprints at the photon's depth
    /// (`photon_splat::min_splat_scale`): a kernel smaller than a pixel would reach one
    /// pixel centre or none, an unbiased but fireflied estimate.
    pub min_splat_px: f32,
    /// 1: also add each splat's light direction to the direction map (Smal 2019, Eq. 20's
    /// `w_i`, [`crate::math::irradiance_filter::light_direction_deposit`]); 0: leave it.
    pub light_direction: u32,
    /// The scene's largest absolute coordinate (scene units): it bounds the vertices a
    /// G-buffer point is interpolated from, so [`splat_box_margin`] holds its rounding.
    pub scene_magnitude: f32,
    /// Padding to the 16-byte boundary.
    pub _pad: [u32; 1],
}

/// Parameters of `place_vertices`: one instance's placement (`world_from_object` and its
/// normal matrix as columns, [`crate::device::placement::placement_params`]) and the run
/// it maps: `count` object-space vertices from `object_first` to world vertices from
/// `world_first`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PlacementParams {
    /// `world_from_object`'s first column, the image of the object's x axis (w: 0,
    /// unused, in every column below).
    pub axis_x: [f32; 4],
    /// Its second column (the object's y axis).
    pub axis_y: [f32; 4],
    /// Its third column (the object's z axis).
    pub axis_z: [f32; 4],
    /// Its translation (scene units).
    pub translation: [f32; 4],
    /// The normal matrix's (the inverse transpose of the linear part) first column.
    pub normal_x: [f32; 4],
    /// Its second column.
    pub normal_y: [f32; 4],
    /// Its third column.
    pub normal_z: [f32; 4],
    /// First object-space vertex of the run (index into the object vertices).
    pub object_first: u32,
    /// First world vertex of the run (index into the scene's vertices).
    pub world_first: u32,
    /// Vertices in the run.
    pub count: u32,
    /// Padding.
    pub _pad: u32,
}

/// Parameters of `shading_normal_correction` (Smal 2019, Eq. 20).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct CorrectionParams {
    /// Image width (pixels).
    pub width: u32,
    /// Image height (pixels).
    pub height: u32,
    /// Largest factor, 24.3.1.2's `s_max` (the splat's light stretch).
    pub max_stretch: f32,
    /// Eq. 20's `epsilon` in the denominator.
    pub epsilon: f32,
}

/// Parameters of `select_photon_plan`: the light slot whose RSM the pyramid holds now, and
/// the plan table's row length ([`photon_plan_word`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct PlanParams {
    /// Texels per RSM face side (a power of two).
    pub side: u32,
    /// Faces of the light's RSM in the pyramid (slots `0 .. faces`, at most 6).
    pub faces: u32,
    /// The light's bit in the plan mask (its index among the lights with power), or
    /// [`NO_PLAN_BIT`]: no RSM is noted, the row is selected again.
    pub bit: u32,
    /// Words of a plan table row (`photon_plan_word::COUNTS - photon_plan_word::ROW` plus
    /// one per light).
    pub row_words: u32,
    /// Words of the plan table (a binding's length can be longer than its buffer's
    /// logical length: wgpu binds at least 64 bytes).
    pub table_words: u32,
    /// Padding to the 16-byte boundary.
    pub _pad: [u32; 3],
}

/// [`PlanParams::bit`] when no light's RSM is noted.
pub const NO_PLAN_BIT: u32 = u32::MAX;

/// Word indices of PhotonGi's photon plan on the device (`select_photon_plan`'s output;
/// its later launches read their photon counts and quanta from it through parameter
/// patches). Words `ROW ..` are a copy of the plan table's row for the mask.
pub mod photon_plan_word {
    /// Bit `k` set where the `k`-th light with power has an RSM that sees a texel that
    /// leaves flux.
    pub const MASK: usize = 0;
    /// First word of the selected row.
    pub const ROW: usize = 1;
    /// Unit of the packed photon power (W, `f32` bits).
    pub const POWER_SCALE: usize = 1;
    /// The photon map's flux quantum (W, `f32` bits).
    pub const FLUX_QUANTUM: usize = 2;
    /// The resolve's flux quantum (W, `f32` bits): the flux quantum over the frames an
    /// accumulation holds.
    pub const RESOLVE_QUANTUM: usize = 3;
    /// Light `k`'s initial photons this frame at `COUNTS + k`.
    pub const COUNTS: usize = 4;
}

/// Parameters of `caustic_map_lookup`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct MapLookupParams {
    /// The frame's camera.
    pub camera: GpuCamera,
    /// Atlas width (texels).
    pub atlas_width: u32,
    /// Longest specular chain followed from the camera to a diffuse surface.
    pub max_specular_depth: u32,
    /// Chains whose weight falls below this are cut.
    pub min_weight: f32,
    /// Reflectance of dielectric interfaces on the chain, one of
    /// [`fresnel_model`](crate::math::optics::fresnel_model).
    pub fresnel_model: u32,
}

/// Parameters of one `trace_photons` dispatch: photons `first .. first + count` of the
/// `grid_w x grid_h` emission grid of light `light`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct TraceParams {
    /// Index of the emitting light in the light buffer.
    pub light: u32,
    /// One of [`emission_kind`]: the shape of the emission domain.
    pub emission: u32,
    /// Width of the light's stratified emission grid (photons).
    pub grid_w: u32,
    /// Height of the light's stratified emission grid (photons).
    pub grid_h: u32,
    /// Grid index of the batch's first photon (row-major).
    pub first: u32,
    /// Photons in this batch (one thread each).
    pub count: u32,
    /// The light's RNG seed (the frame seed hashed with the light index).
    pub seed: u32,
    /// Longest photon path, in ray segments.
    pub max_bounces: u32,
    /// Cone apex / rectangle corner (world); `w`: cosine of the cone half-angle.
    pub origin: [f32; 4],
    /// Cone axis / ray direction (unit, world); for a cone `w` is `1 - cos_max` computed
    /// without cancellation (what a narrow cone is sampled from,
    /// [`uniform_cone`](crate::math::sampling::uniform_cone)), otherwise unused.
    pub axis: [f32; 4],
    /// Rectangle edge `u` (world, scene units; whole edge, not half); `w` unused; zero for cones.
    pub rect_u: [f32; 4],
    /// Rectangle edge `v` (world, scene units; whole edge, not half); `w` unused; zero for cones.
    pub rect_v: [f32; 4],
    /// Flux of each photon at emission (W per channel; Kim 2019 Eqs. 1 and 3); `w`: the
    /// relative power below which a photon is dropped as negligible.
    pub photon_flux: [f32; 4],
    /// Flux quantum (W) of the fixed-point stored-flux counters.
    pub flux_quantum: f32,
    /// With the variant's `FRESNEL_SPLIT`: the most branches (hence stored photons) one
    /// emitted photon may split into (1..=[`MAX_SPLIT_BRANCHES`]); unused otherwise.
    pub split_budget: u32,
    /// Reflectance of dielectric interfaces, one of
    /// [`fresnel_model`](crate::math::optics::fresnel_model).
    pub fresnel_model: u32,
    /// How many of `caster_spheres` a photon's first segment is tested against (0: no
    /// test, every photon is traversed).
    pub caster_sphere_count: u32,
    /// The seed of the photons' jitter inside their grid cells: `seed` for a frame on its
    /// own; with progressive accumulation the accumulation's first seed, so that every
    /// frame's photon in a cell is rotated alike ([`crate::math::rng::stratum_jitter`]).
    pub jitter_seed: u32,
    /// The frame's index in an accumulation (0 without): frame `k`'s jitter is the `k`-th
    /// point of a low-discrepancy sequence rotated per cell, so the frames' photons
    /// stratify each cell together.
    pub stratum: u32,
    /// How a photon takes a colour at its first dispersive surface, one of
    /// [`dispersion_mode`](crate::math::spectrum::dispersion_mode) (0: spectral).
    pub dispersion_mode: u32,
    /// Padding (the spheres start on 16 bytes).
    pub _pad: u32,
    /// Balls around the caustic casters (centre xyz, radius w; world space,
    /// [`crate::device::caster_spheres`]): a photon whose first segment meets none of them
    /// cannot meet a caster first, so it ends as `NO_SPECULAR` with no ray traced
    /// ([`crate::math::geometry::ray_meets_caster_spheres`]).
    pub caster_spheres: [[f32; 4]; MAX_CASTER_SPHERES],
}

/// Largest [`TraceParams::split_budget`]: the depth of the kernels' branch stacks.
pub const MAX_SPLIT_BRANCHES: u32 = 32;

/// Length of [`TraceParams::caster_spheres`].
pub const MAX_CASTER_SPHERES: usize = 8;

/// Largest `max_specular_depth` ([`DirectParams`], [`MapLookupParams`]): GPU kernels walk
/// the specular ray tree with a fixed stack of `MAX_SPECULAR_DEPTH + 1` entries (a
/// depth-first walk of a binary tree of depth `d` holds at most `d + 1` pending rays).
pub const MAX_SPECULAR_DEPTH: u32 = 30;

/// Parameters of `deposit_screen` and `resolve_caustics`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DepositParams {
    /// The frame's camera (projects photons to pixels, gives the pixel footprint).
    pub camera: GpuCamera,
    /// Flux per fixed-point unit (W).
    pub flux_quantum: f32,
    /// Hit distance per fixed-point unit (scene units).
    pub hit_distance_quantum: f32,
    /// A photon is stored only if its view depth is within `depth_tolerance * depth` of the
    /// G-buffer depth at its pixel; a negative value asks for the tangent-plane test
    /// instead ([`off_surface`]).
    pub depth_tolerance: f32,
    /// Slots in the photon buffer (photons per batch at most).
    pub photon_capacity: u32,
}

/// Parameters of the photon gather (`tile_hit_distance`, `bilateral_gather`), Kim 2019
/// section 30.3.2.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct GatherParams {
    /// The frame's camera (pixel size at a depth, image size).
    pub camera: GpuCamera,
    /// World-space blur radius per unit hit distance (the source's "roughness", 0.07).
    pub roughness: f32,
    /// Lower clamp of the tile's mean hit distance (scene units).
    pub hit_distance_min: f32,
    /// Upper clamp of the tile's mean hit distance (scene units).
    pub hit_distance_max: f32,
    /// Largest gather radius (pixels).
    pub max_radius_px: u32,
    /// Depth weight `exp(-|dz| / (sigma_depth * z))`.
    pub sigma_depth: f32,
    /// Normal weight `max(0, n . n')^normal_power`.
    pub normal_power: f32,
    /// 0: horizontal pass, 1: vertical pass.
    pub axis: u32,
    /// Edge of the square hit-distance tiles (pixels).
    pub tile_size: u32,
    /// Hit distance per fixed-point unit of the photon map (scene units).
    pub hit_distance_quantum: f32,
    /// Density gather: photons `k` whose nearest-neighbour window sets a pixel's radius
    /// (see [`crate::math::density_gather`]).
    pub knn_photons: u32,
    /// Flux per fixed-point unit of the photon map (W).
    pub flux_quantum: f32,
    /// Edge of the square blocks of the photon-count table (pixels, a power of two
    /// `>= 2 max_radius_px + 1`; see [`crate::math::density_gather::table_block`]).
    pub table_block: u32,
    /// The density gather's surface, one of [`gather_surface`]: the camera's screen (Sspm)
    /// or the caustic atlas (CausticMap); `camera.width x camera.height` is the grid's size
    /// either way.
    pub surface: u32,
    /// Padding to the 16-byte boundary.
    pub _pad: [u32; 3],
}

/// `GatherParams::surface` values: where the density gather (`photon_count_table`,
/// `gather_footprint`, `density_gather`) runs.
pub mod gather_surface {
    /// The camera's screen: edge texels from the G-buffer (written by
    /// `photon_count_table`'s axis 1), radiance `L = (albedo / pi) Phi / A_pixel` out of
    /// `density_gather`'s axis 1.
    pub const SCREEN: u32 = 0;
    /// The caustic atlas: the edge texels are the atlas's own
    /// ([`atlas_edge_texel`](crate::math::density_gather::atlas_edge_texel), uploaded with
    /// the layout, never written by a kernel; the G-buffer is bound but not read), and
    /// `density_gather`'s axis 1 writes irradiance `E = Phi / A_texel`.
    pub const ATLAS: u32 = 1;
}

/// Parameters of `direct_light`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct DirectParams {
    /// The frame's camera (one ray per pixel for mirror and glass pixels).
    pub camera: GpuCamera,
    /// Number of lights in the light buffer to shade with.
    pub light_count: u32,
    /// Longest specular chain followed from a mirror/glass pixel to a diffuse surface.
    pub max_specular_depth: u32,
    /// Chains whose weight falls below this are cut.
    pub min_weight: f32,
    /// Reflectance of dielectric interfaces on the chain, one of
    /// [`fresnel_model`](crate::math::optics::fresnel_model).
    pub fresnel_model: u32,
}

/// Word offsets into the photon counter buffer (`u32` words; 64-bit sums as lo, hi).
pub mod counter {
    /// Photons stored on a diffuse surface after at least one specular interaction.
    pub const STORED: usize = 0;
    /// Photons that reached a diffuse surface without a specular interaction (direct light).
    pub const NO_SPECULAR: usize = 1;
    /// Photons that left the scene.
    pub const ESCAPED: usize = 2;
    /// Photons dropped when their power fell below the negligible threshold.
    pub const NEGLIGIBLE: usize = 3;
    /// Photons still travelling after `max_bounces` segments.
    pub const BOUNCE_LIMIT: usize = 4;
    /// Stored photons that project outside the view or behind the camera.
    pub const OFF_SCREEN: usize = 5;
    /// Stored photons rejected at their pixel: not a receiver, depth mismatch, or arriving from behind.
    pub const DEPTH_MISMATCH: usize = 6;
    /// Stored photons added to the screen-space photon map.
    pub const DEPOSITED: usize = 7;
    /// Positive photon channel values that rounded to zero flux quanta.
    pub const UNDERFLOW: usize = 8;
    /// Photon channel values clamped to `u32::MAX` flux quanta.
    pub const SATURATED: usize = 9;
    /// u64: ray segments traced.
    pub const RAYS: usize = 10;
    /// 3 x u64: stored flux per channel, in flux quanta.
    pub const STORED_FLUX: usize = 12;
    /// Branches added by `trace_photons`' deterministic splits (`FRESNEL_SPLIT`): the path
    /// ends (stored, no specular, escaped, negligible, bounce limit) add up to the
    /// photons emitted plus these.
    pub const SPLITS: usize = 18;
    /// Number of u32 words.
    pub const WORDS: usize = 20;
}

impl GpuCamera {
    /// An orthographic camera (see [`primary_ray`]): the image plane centred on
    /// `position`, `half_x` by `half_y` scene units each side, looking along `forward`
    /// (unit; `right`, `up` unit and orthogonal to it).
    pub fn orthographic(
        position: Vec3,
        forward: Vec3,
        right: Vec3,
        up: Vec3,
        half: (f32, f32),
        size: (u32, u32),
    ) -> GpuCamera {
        GpuCamera {
            position: position.to_array(),
            tan_half_fov_x: -half.0,
            forward: forward.to_array(),
            tan_half_fov_y: -half.1,
            right: right.to_array(),
            width: size.0,
            up: up.to_array(),
            height: size.1,
        }
    }

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

/// The primary ray of pixel (`px`, `py`) as (origin, unit direction): from the eye
/// through the pixel, or, for an orthographic camera ([`GpuCamera::orthographic`]:
/// `tan_half_fov_x < 0`), along `forward` from the pixel's point of the image plane
/// (`position` at its centre, half-extents `-tan_half_fov_x`, `-tan_half_fov_y` in scene
/// units). PhotonGi's RSM of a directional light is the only orthographic camera.
#[inline]
pub fn primary_ray(cam: &GpuCamera, px: u32, py: u32) -> (Vec3, Vec3) {
    if cam.tan_half_fov_x < 0.0 {
        let sx = (2.0 * (px as f32 + 0.5) / cam.width as f32 - 1.0) * -cam.tan_half_fov_x;
        let sy = (1.0 - 2.0 * (py as f32 + 0.5) / cam.height as f32) * -cam.tan_half_fov_y;
        let origin =
            Vec3::from(cam.position) + sx * Vec3::from(cam.right) + sy * Vec3::from(cam.up);
        (origin, Vec3::from(cam.forward))
    } else {
        (Vec3::from(cam.position), camera_ray(cam, px, py))
    }
}

/// Whether a photon at world point `p` and view depth `z` lies off the surface of
/// G-buffer texel (`position`, `normal`, `depth`), `deposit_screen`'s test: with
/// `tolerance >= 0` (Kim 2019's condition 3) when `|z - depth| > tolerance x depth`; with
/// `tolerance < 0` (PhotonGi's indirect reference) when `p` is farther than `|tolerance| x
/// depth` from the texel's tangent plane, which keeps the photons of a surface seen at a
/// grazing angle, whose view depth varies across one pixel by more than any fixed
/// fraction (at 96x54 a 1% depth test dropped half the floor's photons in `cornell`).
#[inline]
pub fn off_surface(
    z: f32,
    p: Vec3,
    position: Vec3,
    normal: Vec3,
    depth: f32,
    tolerance: f32,
) -> bool {
    if tolerance < 0.0 {
        (p - position).dot(normal).abs() > -tolerance * depth
    } else {
        (z - depth).abs() > tolerance * depth
    }
}

/// `trace_indirect`'s visibility test's tolerance ([`off_surface`]'s negative form: within
/// 1% of the view depth of the pixel's tangent plane). Without it photons of a room hidden
/// behind a wall counted in the tiles they project to and shrank the visible photons'
/// kernels there (Eqs. 3-6: `rooms` showed 1500-6500 photons per 16 x 16 tile and
/// one-pixel speckles).
pub const VISIBLE_TOLERANCE: f32 = -0.01;

/// Projects world point `p` to continuous pixel coordinates (x right, y down; pixel `i`
/// spans `[i, i + 1)`) and view depth, on screen or not; `None` when it is not in front
/// of the camera.
#[inline]
pub fn project_to_screen(cam: &GpuCamera, p: Vec3) -> Option<(f32, f32, f32)> {
    let v = p - Vec3::from(cam.position);
    let z = v.dot(Vec3::from(cam.forward));
    if z.is_nan() || z <= 0.0 {
        return None;
    }
    let sx = v.dot(Vec3::from(cam.right)) / (z * cam.tan_half_fov_x);
    let sy = v.dot(Vec3::from(cam.up)) / (z * cam.tan_half_fov_y);
    let fx = (sx + 1.0) * 0.5 * cam.width as f32;
    let fy = (1.0 - sy) * 0.5 * cam.height as f32;
    Some((fx, fy, z))
}

/// Projects world point `p` to the pixel that contains it; returns (px, py, view depth)
/// or `None` when it is behind the camera or off screen.
#[inline]
pub fn project_to_pixel(cam: &GpuCamera, p: Vec3) -> Option<(u32, u32, f32)> {
    let (fx, fy, z) = project_to_screen(cam, p)?;
    if !(fx >= 0.0 && fy >= 0.0 && fx < cam.width as f32 && fy < cam.height as f32) {
        return None;
    }
    Some((fx as u32, fy as u32, z))
}

/// The pixels `splat_photons` tests for a splat: inclusive `[x0, x1, y0, y1]`, the square
/// of `r` pixels around the splat centre's pixel `(px, py)` inside the image, narrowed to
/// the screen bounds of kernel `k`'s box (half-axes `k.axes` along `k.n`, `k.u`, `k.t`
/// about `centre`, world space), so that a flat or stretched kernel seen at an angle no longer
/// scans its largest axis's square (Smal 2019's ellipsoid splat; 2x fewer pixel tests on
/// `rooms`).
///
/// Nothing the square held that the kernel contains is lost: a pixel passes the kernel
/// test only if its G-buffer point (on its centre ray) lies in the ellipsoid, so in the
/// box; with every corner in front of the camera the box's projection is the convex hull
/// of its corners' projections, and the point's pixel is within one of the hull's
/// bounds. The box is widened by [`splat_box_margin`] (`scene`: the scene's largest
/// absolute coordinate) and the bounds by a pixel on each side. A
/// corner at or behind the camera, or a non-finite bound, keeps the square.
pub fn splat_screen_rect(
    cam: &GpuCamera,
    centre: Vec3,
    k: &crate::math::photon_splat::SplatKernel,
    (px, py): (u32, u32),
    r: u32,
    scene: f32,
) -> [i32; 4] {
    let (n, u, t, axes) = (k.n, k.u, k.t, k.axes);
    let (w, h) = (cam.width as i32, cam.height as i32);
    let (px, py, r) = (px as i32, py as i32, r.min(1 << 24) as i32);
    let square = [
        (px - r).max(0),
        (px + r).min(w - 1),
        (py - r).max(0),
        (py + r).min(h - 1),
    ];
    let a = axes + Vec3::splat(splat_box_margin(cam, centre, axes, scene));
    let (mut lo_x, mut hi_x, mut lo_y, mut hi_y) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
    for corner in 0..8u32 {
        let sign = |bit: u32| if corner & bit != 0 { 1.0 } else { -1.0 };
        let c = centre + n * (sign(1) * a.x) + u * (sign(2) * a.y) + t * (sign(4) * a.z);
        let Some((fx, fy, _)) = project_to_screen(cam, c) else {
            return square;
        };
        if !(fx.is_finite() && fy.is_finite()) {
            return square;
        }
        lo_x = lo_x.min(fx);
        hi_x = hi_x.max(fx);
        lo_y = lo_y.min(fy);
        hi_y = hi_y.max(fy);
    }
    // clamped to the square in float first, so the conversions stay in range
    let bound = |v: f32, lo: i32, hi: i32| v.clamp(lo as f32, hi as f32) as i32;
    [
        bound(lo_x.floor() - 1.0, square[0], square[1]),
        bound(hi_x.floor() + 1.0, square[0], square[1]),
        bound(lo_y.floor() - 1.0, square[2], square[3]),
        bound(hi_y.floor() + 1.0, square[2], square[3]),
    ]
}

/// How far [`splat_screen_rect`] and [`splat_rays`] widen a kernel's box (scene units):
/// `1e-5` of the coordinate magnitudes about the splat (its centre's, the eye's, its
/// largest half-axis and the scene's largest coordinate `scene`), which holds the G-buffer
/// point's rounding (a point of a pixel's centre ray interpolated from its triangle's
/// vertices, a few ulp of their coordinates, which `scene` bounds) and the tests' own.
#[inline]
pub fn splat_box_margin(cam: &GpuCamera, centre: Vec3, axes: Vec3, scene: f32) -> f32 {
    1e-5 * (centre.abs().max_element()
        + Vec3::from(cam.position).abs().max_element()
        + axes.max_element()
        + scene)
}

/// What `splat_photons` needs to tell, before it loads a pixel's G-buffer, that the
/// pixel cannot pass its kernel test: the camera's eye and its forward, right and up
/// vectors in the kernel's frame (coordinates along `k.n`, `k.u`, `k.t` about the
/// splat's centre), and the half-extents of the kernel's box there, widened by
/// [`splat_box_margin`] twice (the G-buffer point's rounding, the test's own) and by
/// `1 + tan_x + tan_y` more (the test's image-plane point rounds differently from
/// `camera_ray`'s, by a few ulp of the field of view's tangents, which move the line by
/// as much times the depth). `half_axes.x < 0` turns the test off (every pixel may
/// pass).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SplatRays {
    /// The eye less the splat's centre, in the kernel's frame (scene units).
    pub eye: Vec3,
    /// The camera's unit forward vector in the kernel's frame.
    pub forward: Vec3,
    /// The camera's unit right vector in the kernel's frame.
    pub right: Vec3,
    /// The camera's unit up vector in the kernel's frame.
    pub up: Vec3,
    /// Half-axis lengths of the widened box (scene units); `x < 0`: no test.
    pub half_axes: Vec3,
}

/// [`SplatRays`] of kernel `k` about `centre` seen by `cam` (`scene`: the scene's largest
/// absolute coordinate); the test is off for an orthographic camera and where a
/// coordinate is not finite.
pub fn splat_rays(
    cam: &GpuCamera,
    centre: Vec3,
    k: &crate::math::photon_splat::SplatKernel,
    scene: f32,
) -> SplatRays {
    let r = SplatRays {
        eye: k.frame(Vec3::from(cam.position) - centre),
        forward: k.frame(Vec3::from(cam.forward)),
        right: k.frame(Vec3::from(cam.right)),
        up: k.frame(Vec3::from(cam.up)),
        half_axes: k.axes
            + Vec3::splat(
                2.0 * splat_box_margin(cam, centre, k.axes, scene)
                    * (1.0 + cam.tan_half_fov_x.abs() + cam.tan_half_fov_y.abs()),
            ),
    };
    let finite = [r.eye, r.forward, r.right, r.up, r.half_axes]
        .iter()
        .all(|v| v.is_finite());
    if cam.tan_half_fov_x < 0.0 || !finite {
        return SplatRays {
            half_axes: Vec3::splat(-1.0),
            ..r
        };
    }
    r
}

/// Whether pixel (`px`, `py`)'s centre ray may meet the kernel's box (`r`): false only
/// where the ray's line misses the widened box, so no point of the line within the
/// margin of the kernel, the pixel's G-buffer point included, lies in the kernel
/// (`splat_photons`' pixel test would fail). The separating-axis test of a line and a
/// box: a line misses a box exactly when one of the axes `e_i x d` (`e_i` the box's
/// axes, `d` the line's direction) separates them, and on it the line projects to the
/// point `|(eye x d)_i|` and the box to the interval of radius `half_j |d_k| + half_k
/// |d_j|`. `d` = forward + sx right + sy up, `camera_ray`'s direction before its
/// normalisation, need not be unit. The line, not the ray: a box partly behind the eye is
/// tested as well.
#[inline]
pub fn splat_ray_may_hit(r: &SplatRays, cam: &GpuCamera, px: u32, py: u32) -> bool {
    if r.half_axes.x < 0.0 {
        return true;
    }
    // camera_ray's image-plane point without its per-pixel division (the margin's
    // tangent factor holds the different rounding)
    let sx = (px as f32 + 0.5) * (2.0 * cam.tan_half_fov_x / cam.width as f32) - cam.tan_half_fov_x;
    let sy =
        cam.tan_half_fov_y - (py as f32 + 0.5) * (2.0 * cam.tan_half_fov_y / cam.height as f32);
    let d = r.forward + sx * r.right + sy * r.up;
    let c = r.eye.cross(d);
    let a = d.abs();
    let h = r.half_axes;
    // "not separated": a NaN from an overflow keeps the pixel
    !(c.x.abs() > h.y * a.z + h.z * a.y
        || c.y.abs() > h.x * a.z + h.z * a.x
        || c.z.abs() > h.x * a.y + h.y * a.x)
}

// ---- functions over the layouts (shader ports mirror them by name)

/// A point on a triangle, interpolated from its vertices (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfacePoint {
    /// World-space position (scene units).
    pub position: Vec3,
    /// Unit geometric normal, turned to the side of the interpolated vertex normals (for
    /// closed shapes: outward). Used to tell inside from outside and to offset rays.
    pub geometric_normal: Vec3,
    /// Unit interpolated shading normal (same side as `geometric_normal`).
    pub shading_normal: Vec3,
    /// Interpolated texture coordinates.
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
/// over the view and surface cosines ([`pixel_surface_area`](crate::math::footprint::pixel_surface_area)). Resolve divides a
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

    #[test]
    fn a_camera_from_host_matrices_is_the_look_at_camera() {
        let eye = Vec3::new(0.6, 3.0, 2.8);
        let target = Vec3::new(0.1, 0.7, -0.2);
        let (w, h) = (640u32, 360u32);
        let fov = 38.0f32;
        let view = glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y);
        let aspect = w as f32 / h as f32;
        for proj in [
            glam::camera::rh::proj::directx::perspective(fov.to_radians(), aspect, 0.01, 100.0),
            glam::camera::rh::proj::opengl::perspective(fov.to_radians(), aspect, 0.01, 100.0),
            // Vulkan's clip space flips y: the camera is the same
            glam::camera::rh::proj::vulkan::perspective(fov.to_radians(), aspect, 0.01, 100.0),
            glam::camera::rh::proj::vulkan::perspective_infinite_reverse(
                fov.to_radians(),
                aspect,
                0.01,
            ),
        ] {
            let c = crate::scene::Camera::from_view_projection(view, proj, w, h).unwrap();
            let want = GpuCamera::from_camera(&crate::scene::Camera {
                position: eye,
                target,
                up: Vec3::Y,
                fov_y_deg: fov,
                width: w,
                height: h,
            });
            let got = GpuCamera::from_camera(&c);
            let v = |a: [f32; 3]| Vec3::from(a);
            assert!((v(got.position) - v(want.position)).length() < 1e-5);
            assert!((v(got.forward) - v(want.forward)).length() < 1e-6);
            assert!((v(got.right) - v(want.right)).length() < 1e-6);
            assert!((v(got.up) - v(want.up)).length() < 1e-6);
            assert!((got.tan_half_fov_y / want.tan_half_fov_y - 1.0).abs() < 1e-6);
            assert!((got.tan_half_fov_x / want.tan_half_fov_x - 1.0).abs() < 1e-6);
        }
    }

    /// A random splat for the rectangle and ray tests: a camera (scene scale `1e-3`, 1 or
    /// `1e3` by `case`, a vertical field of view of 20 to `fov_max` degrees), a kernel centre that projects to pixel `(px, py)` and an
    /// orthonormal frame with half-axes from flat (normal compression) to long, `reach`
    /// times the scale; `None` when the centre is off screen.
    fn random_splat(
        rnd: &mut impl FnMut() -> f32,
        case: usize,
        reach: f32,
        fov_max: f32,
    ) -> Option<(
        GpuCamera,
        Vec3,
        (u32, u32),
        crate::math::photon_splat::SplatKernel,
    )> {
        let scale = [1e-3f32, 1.0, 1e3][case % 3];
        let eye = Vec3::new(rnd() - 0.5, rnd() + 0.5, rnd() + 2.0) * scale;
        let target = Vec3::new(rnd() - 0.5, rnd() * 0.5, rnd() - 0.5) * scale;
        let cam = GpuCamera::from_camera(&crate::scene::Camera {
            position: eye,
            target,
            up: Vec3::Y,
            fov_y_deg: 20.0 + (fov_max - 20.0) * rnd(),
            width: 64 + (rnd() * 400.0) as u32,
            height: 48 + (rnd() * 300.0) as u32,
        });
        let centre = target + (Vec3::new(rnd(), rnd(), rnd()) - 0.5) * scale;
        let (px, py, _) = project_to_pixel(&cam, centre)?;
        let n = (Vec3::new(rnd(), rnd(), rnd()) - 0.5).normalize_or(Vec3::Y);
        let (u, t) = n.any_orthonormal_pair();
        let axes = Vec3::new(0.02 + 0.2 * rnd(), 0.1 + rnd(), 0.1 + 0.5 * rnd()) * reach * scale;
        let kernel = crate::math::photon_splat::SplatKernel { n, u, t, axes };
        Some((cam, centre, (px, py), kernel))
    }

    #[test]
    fn a_splats_screen_rect_holds_every_pixel_its_kernel_contains() {
        use crate::math::rng::random_f32;
        let mut k = 0u32;
        let mut rnd = || {
            k += 1;
            random_f32(0x5b1a7, k, 0, 0)
        };
        let mut narrowed = 0;
        for case in 0..400 {
            let Some((cam, centre, (px, py), kernel)) = random_splat(&mut rnd, case, 0.3, 90.0)
            else {
                continue;
            };
            let crate::math::photon_splat::SplatKernel { n, u, t, axes } = kernel;
            let r = if case % 4 == 0 { 3 } else { 1 << 20 };
            let rect = splat_screen_rect(&cam, centre, &kernel, (px, py), r, 0.0);
            let (w, h) = (cam.width as i32, cam.height as i32);
            let square = [
                (px as i32 - r as i32).max(0),
                (px as i32 + r as i32).min(w - 1),
                (py as i32 - r as i32).max(0),
                (py as i32 + r as i32).min(h - 1),
            ];
            assert!(
                rect[0] >= square[0] && rect[1] <= square[1],
                "{case}: {rect:?} {square:?}"
            );
            assert!(
                rect[2] >= square[2] && rect[3] <= square[3],
                "{case}: {rect:?} {square:?}"
            );
            narrowed += ((rect[1] - rect[0] + 1) * (rect[3] - rect[2] + 1)
                < (square[1] - square[0] + 1) * (square[3] - square[2] + 1))
                as u32;
            for _ in 0..300 {
                // a point of the closed ellipsoid, its boundary included
                let d = Vec3::new(rnd(), rnd(), rnd()) * 2.0 - 1.0;
                let d = if d.length() > 1.0 { d / d.length() } else { d };
                let q = centre + n * (d.x * axes.x) + u * (d.y * axes.y) + t * (d.z * axes.z);
                if let Some((x, y, _)) = project_to_pixel(&cam, q) {
                    let (x, y) = (x as i32, y as i32);
                    if x < square[0] || x > square[1] || y < square[2] || y > square[3] {
                        continue;
                    }
                    assert!(
                        x >= rect[0] && x <= rect[1] && y >= rect[2] && y <= rect[3],
                        "{case}: pixel ({x}, {y}) of a kernel point outside {rect:?}"
                    );
                }
            }
        }
        assert!(
            narrowed > 100,
            "the rectangle narrowed only {narrowed} squares"
        );
    }

    /// `splat_ray_may_hit` never turns away a pixel whose kernel test could pass: for
    /// every pixel of a splat's rectangle whose centre ray meets the ellipsoid (in f64),
    /// points along the chord rounded to f32, where the kernel test (in f32) holds them,
    /// find the pixel let through; so do the G-buffer's own points, where the centre ray
    /// (f32) meets a triangle through the kernel's plane whose vertices lie up to 10^4
    /// kernel scales away (the watertight test's barycentrics, the vertices interpolated:
    /// the rounding the margin's scene term holds); and the test turns most other pixels
    /// away.
    #[test]
    fn a_splats_ray_test_keeps_every_pixel_its_kernel_may_contain() {
        use crate::math::rng::random_f32;
        use glam::DVec3;
        let mut k = 0u32;
        let mut rnd = || {
            k += 1;
            random_f32(0x5b1a8, k, 0, 0)
        };
        let (mut tested, mut turned_away, mut held) = (0u32, 0u32, 0u32);
        for case in 0..300 {
            // now and then a kernel around the eye
            let reach = if case % 17 == 0 { 4.0 } else { 0.3 };
            let Some((cam, centre, (px, py), kernel)) = random_splat(
                &mut rnd,
                case,
                reach,
                if case % 7 == 0 { 178.0 } else { 90.0 },
            ) else {
                continue;
            };
            let (eye, n, u, t, axes) = (
                Vec3::from(cam.position),
                kernel.n,
                kernel.u,
                kernel.t,
                kernel.axes,
            );
            // a triangle in the kernel's plane about its centre, its vertices near (every
            // third case) or far, and the scene's largest coordinate over them
            let far = [3.0f32, 300.0, 3e4][case % 3 / 2 + (case % 5 == 0) as usize] * axes.y;
            let corner = |a: f32| {
                let (s, c) = a.to_radians().sin_cos();
                GpuVertex {
                    position: (centre + (u * c + t * s) * far).to_array(),
                    normal: n.to_array(),
                    ..Default::default()
                }
            };
            let tri = [corner(10.0), corner(130.0), corner(250.0)];
            let scene = tri
                .iter()
                .map(|v| Vec3::from(v.position).abs().max_element())
                .fold(centre.abs().max_element(), f32::max);
            let rect = splat_screen_rect(&cam, centre, &kernel, (px, py), 40, scene);
            let rays = splat_rays(&cam, centre, &kernel, scene);
            let (c64, n64, u64_, t64) =
                (centre.as_dvec3(), n.as_dvec3(), u.as_dvec3(), t.as_dvec3());
            let a64 = axes.as_dvec3();
            for y in rect[2]..=rect[3] {
                for x in rect[0]..=rect[1] {
                    let (x, y) = (x as u32, y as u32);
                    let may = splat_ray_may_hit(&rays, &cam, x, y);
                    tested += 1;
                    turned_away += (!may) as u32;
                    // the G-buffer's point: the f32 centre ray on the triangle, interpolated
                    let ray = camera_ray(&cam, x, y);
                    let [ta, tb, tc] = tri.map(|v| Vec3::from(v.position));
                    if let Some(h) = crate::math::geometry::intersect_triangle(
                        eye,
                        ray,
                        ta,
                        tb,
                        tc,
                        0.0,
                        f32::MAX,
                    ) {
                        let p = surface_point(&tri[0], &tri[1], &tri[2], h.u, h.v).position;
                        if kernel.contains(centre, p) {
                            held += 1;
                            assert!(
                                may,
                                "{case}: pixel ({x}, {y}) turned away, G-buffer point {p} in the kernel"
                            );
                        }
                    }
                    // the centre ray and the ellipsoid in f64: |(o + s d - c) / axes|^2 = 1
                    let d = ray.as_dvec3();
                    let o = eye.as_dvec3() - c64;
                    let fr = |v: DVec3| DVec3::new(v.dot(n64), v.dot(u64_), v.dot(t64)) / a64;
                    let (ol, dl) = (fr(o), fr(d));
                    let (qa, qb, qc) = (dl.dot(dl), ol.dot(dl), ol.dot(ol) - 1.0);
                    let disc = qb * qb - qa * qc;
                    if disc < 0.0 {
                        continue;
                    }
                    let (s0, s1) = ((-qb - disc.sqrt()) / qa, (-qb + disc.sqrt()) / qa);
                    for f in [0.0, 1e-4, 0.5, 1.0 - 1e-4, 1.0] {
                        let s = s0 + f * (s1 - s0);
                        if s <= 0.0 {
                            continue;
                        }
                        let p = (eye.as_dvec3() + d * s).as_vec3();
                        if kernel.contains(centre, p) {
                            held += 1;
                            assert!(
                                may,
                                "{case}: pixel ({x}, {y}) turned away, point {p} in the kernel"
                            );
                        }
                    }
                }
            }
        }
        assert!(held > 10_000, "only {held} kernel points checked");
        assert!(
            turned_away * 4 > tested,
            "the test turned away {turned_away} of {tested} pixels"
        );
    }

    use std::mem::size_of;

    #[test]
    fn sizes_are_multiples_of_16() {
        assert_eq!(size_of::<GpuVertex>(), 32);
        assert_eq!(size_of::<GpuTriangle>(), 16);
        assert_eq!(size_of::<GpuMaterial>(), 48);
        assert_eq!(size_of::<GpuLight>(), 64);
        assert_eq!(size_of::<GpuCamera>(), 64);
        assert_eq!(size_of::<PlanParams>(), 32);
        assert_eq!(size_of::<GBufferTexel>(), 64);
        assert_eq!(size_of::<Photon>(), 32);
        assert_eq!(size_of::<DepositTexel>(), 40);
        assert_eq!(size_of::<TraceParams>() % 16, 0);
        assert_eq!(size_of::<DepositParams>() % 16, 0);
        assert_eq!(size_of::<GatherParams>() % 16, 0);
        assert_eq!(size_of::<DirectParams>() % 16, 0);
        assert_eq!(size_of::<AtlasParams>(), 32);
        assert_eq!(size_of::<MapLookupParams>(), 80);
    }

    #[test]
    fn planes_assemble_bitwise() {
        let g = GBufferTexel {
            position: [1.0, f32::from_bits(0x7fc0_0001), -0.0],
            depth: 2.5,
            normal: [0.0, 1.0, 0.0],
            geometric_normal: 7,
            albedo: [0.25, 0.5, 0.75],
            material: NO_MATERIAL,
            uv: [0.125, 0.875],
            view_distance: 3.0,
            flags: gbuffer_flags::RECEIVER,
        };
        let p = g.to_planes();
        assert_eq!(p[0][3], 2.5f32.to_bits());
        assert_eq!(p[2][3], NO_MATERIAL);
        assert_eq!(p[3][3], gbuffer_flags::RECEIVER);
        let planes = gbuffer_to_planes(&[g, g]);
        let back = gbuffer_from_planes([&planes[0], &planes[1], &planes[2], &planes[3]]);
        assert_eq!(
            bytemuck::cast_slice::<_, u8>(&back),
            bytemuck::cast_slice::<_, u8>(&[g, g])
        );
        let d: DepositTexel = bytemuck::cast(std::array::from_fn::<u32, 10, _>(|i| i as u32 + 1));
        let e: DepositTexel = bytemuck::cast(std::array::from_fn::<u32, 10, _>(|i| 100 + i as u32));
        let planes = deposit_to_planes(&[d, e]);
        assert_eq!(planes[0], vec![1, 2, 3, 4, 100, 101, 102, 103]);
        assert_eq!(planes[2], vec![9, 10, 108, 109]);
        assert_eq!(
            deposit_from_planes([&planes[0], &planes[1], &planes[2]]),
            vec![d, e]
        );
        assert_eq!(deposit_word(1, 9), (2, 3));
        assert_eq!(deposit_word(1, 6), (1, 6));
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

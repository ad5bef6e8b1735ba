// Mirror of core/src/sampling.rs and backend-opencl/kernels/sampling.cl: equal-area warps
// of the unit square.

// core::math::sampling::tiled_photon_index: the row-major grid index of the g-th photon
// in tile order (8 x 8 tiles, bands of tiles left to right; a warp's photons in one block).
fn tiled_photon_index(g: u32, grid_w: u32, grid_h: u32) -> u32 {
    return tiled_index(g, grid_w, grid_h, PHOTON_TILE);
}

// core::math::sampling::tiled_index.
fn tiled_index(g: u32, grid_w: u32, grid_h: u32, tile: u32) -> u32 {
    if (grid_w == 0u || grid_h == 0u || tile == 0u) {
        return g;
    }
    let band_y = g / grid_w / tile * tile;
    let band_h = min(tile, grid_h - band_y);
    let r = g - band_y * grid_w;
    let tile_x = r / (tile * band_h) * tile;
    let tile_w = min(tile, grid_w - tile_x);
    let q = r - tile_x * band_h;
    return (band_y + q / tile_w) * grid_w + tile_x + q % tile_w;
}

fn stratified_cell(ix: u32, iy: u32, grid_w: u32, grid_h: u32, jitter: vec2<f32>) -> vec2<f32> {
    return vec2<f32>((f32(ix) + jitter.x) / f32(grid_w), (f32(iy) + jitter.y) / f32(grid_h));
}

// sin and cos: WGSL bounds their error only absolutely (2^-11 on [-pi, pi]); drivers do
// much better, but not Rust's libm (see prelude.wgsl).
// core::math::sampling::uniform_cone: a narrow cone from 1 - cos_max computed without
// cancellation (TraceParams::axis.w).
fn uniform_cone(u: vec2<f32>, cos_max: f32, one_minus_cos: f32) -> vec3<f32> {
    var cos_t: f32;
    var sin_t: f32;
    if (one_minus_cos < NARROW_CONE) {
        let t = u.x * one_minus_cos;
        cos_t = 1.0 - t;
        sin_t = sqrt(max(t * (2.0 - t), 0.0));
    } else {
        cos_t = 1.0 - u.x * (1.0 - cos_max);
        sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    }
    let phi = TAU_F * u.y;
    return vec3<f32>(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// Duff et al. 2017 orthonormal basis; returns t, writes b.
fn orthonormal_basis(n: vec3<f32>, b_out: ptr<function, vec3<f32>>) -> vec3<f32> {
    let sgn = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sgn + n.z);
    let b = n.x * n.y * a;
    *b_out = vec3<f32>(b, sgn + n.y * n.y * a, -n.y);
    return vec3<f32>(1.0 + sgn * n.x * n.x * a, sgn * b, -sgn * n.x);
}

fn to_world(v: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    var b: vec3<f32>;
    let t = orthonormal_basis(n, &b);
    return t * v.x + b * v.y + n * v.z;
}

// core::math::sampling::view_plane_direction (Vanderstichelen 2021, section 3.1): the pinhole ray
// through point `u` of a perspective light view plane.
fn view_plane_direction(axis: vec3<f32>, right: vec3<f32>, up: vec3<f32>, u: vec2<f32>) -> vec3<f32> {
    let ndc = vec2<f32>(2.0 * u.x - 1.0, 1.0 - 2.0 * u.y);
    return normalize3(axis + ndc.x * right + ndc.y * up);
}

// core::math::sampling::view_plane_texel_weight: texel (ix, iy)'s solid angle over the
// centre texel's, 1 / q^(3/2).
fn view_plane_texel_weight(ix: u32, iy: u32, w: u32, h: u32, tan_x: f32, tan_y: f32) -> f32 {
    let a = (2.0 * (f32(ix) + 0.5) / f32(w) - 1.0) * tan_x;
    let b = (1.0 - 2.0 * (f32(iy) + 0.5) / f32(h)) * tan_y;
    let q = 1.0 + a * a + b * b;
    return 1.0 / (q * sqrt(q));
}

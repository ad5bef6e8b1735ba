// Mirror of core/src/sampling.rs and backend-opencl/kernels/sampling.cl: equal-area warps
// of the unit square.

// core::math::sampling::tiled_photon_index: the row-major grid index of the g-th photon
// in tile order (8 x 8 tiles, bands of tiles left to right; a warp's photons in one block).
uint tiled_photon_index(uint g, uint grid_w, uint grid_h) {
    if (grid_w == 0u || grid_h == 0u) return g;
    uint band_y = g / grid_w / PHOTON_TILE * PHOTON_TILE;
    uint band_h = min(PHOTON_TILE, grid_h - band_y);
    uint r = g - band_y * grid_w;
    uint tile_x = r / (PHOTON_TILE * band_h) * PHOTON_TILE;
    uint tile_w = min(PHOTON_TILE, grid_w - tile_x);
    uint q = r - tile_x * band_h;
    return (band_y + q / tile_w) * grid_w + tile_x + q % tile_w;
}

precise vec2 stratified_cell(uint ix, uint iy, uint grid_w, uint grid_h, vec2 jitter) {
    return vec2((float(ix) + jitter.x) / float(grid_w), (float(iy) + jitter.y) / float(grid_h));
}

// core::math::sampling::uniform_cone: a narrow cone from 1 - cos_max computed without
// cancellation (TraceParams::axis.w).
precise vec3 uniform_cone(vec2 u, float cos_max, float one_minus_cos) {
    float cos_t, sin_t;
    if (one_minus_cos < NARROW_CONE) {
        float t = u.x * one_minus_cos;
        cos_t = 1.0 - t;
        sin_t = sqrt(max(t * (2.0 - t), 0.0));
    } else {
        cos_t = 1.0 - u.x * (1.0 - cos_max);
        sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    }
    float phi = TAU_F * u.y;
    return vec3(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// Duff et al. 2017 orthonormal basis; returns t, writes b.
precise vec3 orthonormal_basis(vec3 n, precise out vec3 b_out) {
    float sign = n.z >= 0.0 ? 1.0 : -1.0;
    float a = -1.0 / (sign + n.z);
    float b = n.x * n.y * a;
    b_out = vec3(b, sign + n.y * n.y * a, -n.y);
    return vec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
}

precise vec3 to_world(vec3 v, vec3 n) {
    vec3 b;
    vec3 t = orthonormal_basis(n, b);
    return t * v.x + b * v.y + n * v.z;
}

// core::math::sampling::view_plane_direction (Vanderstichelen 2021, section 3.1): the pinhole ray
// through point `u` of a perspective light view plane.
precise vec3 view_plane_direction(vec3 axis, vec3 right, vec3 up, vec2 u) {
    vec2 ndc = vec2(2.0 * u.x - 1.0, 1.0 - 2.0 * u.y);
    return normalize3(axis + ndc.x * right + ndc.y * up);
}

// core::math::sampling::view_plane_texel_weight: texel (ix, iy)'s solid angle over the
// centre texel's, 1 / q^(3/2).
precise float view_plane_texel_weight(uint ix, uint iy, uint w, uint h, float tan_x, float tan_y) {
    float a = (2.0 * (float(ix) + 0.5) / float(w) - 1.0) * tan_x;
    float b = (1.0 - 2.0 * (float(iy) + 0.5) / float(h)) * tan_y;
    float q = 1.0 + a * a + b * b;
    return 1.0 / (q * sqrt(q));
}

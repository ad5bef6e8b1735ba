// Mirror of core/src/sampling.rs: equal-area warps of the unit square.

// core::math::sampling::tiled_index.
inline uint tiled_index(uint g, uint grid_w, uint grid_h, uint tile) {
    if (grid_w == 0u || grid_h == 0u || tile == 0u) return g;
    uint band_y = g / grid_w / tile * tile;
    uint band_h = min(tile, grid_h - band_y);
    uint r = g - band_y * grid_w;
    uint tile_x = r / (tile * band_h) * tile;
    uint tile_w = min(tile, grid_w - tile_x);
    uint q = r - tile_x * band_h;
    return (band_y + q / tile_w) * grid_w + tile_x + q % tile_w;
}

// core::math::sampling::tiled_photon_index: the row-major grid index of the g-th photon
// in tile order (8 x 8 tiles, bands of tiles left to right; a warp's photons in one block).
inline uint tiled_photon_index(uint g, uint grid_w, uint grid_h) {
    return tiled_index(g, grid_w, grid_h, PHOTON_TILE);
}

inline float2 stratified_cell(uint ix, uint iy, uint grid_w, uint grid_h, float2 jitter) {
    return (float2)(((float)ix + jitter.x) / (float)grid_w, ((float)iy + jitter.y) / (float)grid_h);
}

// core::math::sampling::uniform_cone: a narrow cone from 1 - cos_max computed without
// cancellation (TraceParams::axis.w).
inline float3 uniform_cone(float2 u, float cos_max, float one_minus_cos) {
    float cos_t, sin_t;
    if (one_minus_cos < NARROW_CONE) {
        float t = u.x * one_minus_cos;
        cos_t = 1.0f - t;
        sin_t = sqrt(fmax(t * (2.0f - t), 0.0f));
    } else {
        cos_t = 1.0f - u.x * (1.0f - cos_max);
        sin_t = sqrt(fmax(1.0f - cos_t * cos_t, 0.0f));
    }
    float phi = TAU_F * u.y;
    return (float3)(sin_t * cos(phi), sin_t * sin(phi), cos_t);
}

// Duff et al. 2017 orthonormal basis; returns t, writes b.
inline float3 orthonormal_basis(float3 n, float3* b_out) {
    float sign = n.z >= 0.0f ? 1.0f : -1.0f;
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    *b_out = (float3)(b, sign + n.y * n.y * a, -n.y);
    return (float3)(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
}

inline float3 to_world(float3 v, float3 n) {
    float3 b;
    float3 t = orthonormal_basis(n, &b);
    return t * v.x + b * v.y + n * v.z;
}

// core::math::sampling::view_plane_direction (Vanderstichelen 2021, section 3.1): the pinhole ray
// through point `u` of a perspective light view plane.
inline float3 view_plane_direction(float3 axis, float3 right, float3 up, float2 u) {
    float2 ndc = (float2)(2.0f * u.x - 1.0f, 1.0f - 2.0f * u.y);
    return normalize3(axis + ndc.x * right + ndc.y * up);
}

// core::math::sampling::view_plane_texel_weight: texel (ix, iy)'s solid angle over the
// centre texel's, 1 / q^(3/2).
inline float view_plane_texel_weight(uint ix, uint iy, uint w, uint h, float tan_x, float tan_y) {
    float a = (2.0f * ((float)ix + 0.5f) / (float)w - 1.0f) * tan_x;
    float b = (1.0f - 2.0f * ((float)iy + 0.5f) / (float)h) * tan_y;
    float q = 1.0f + a * a + b * b;
    return 1.0f / (q * sqrt(q));
}

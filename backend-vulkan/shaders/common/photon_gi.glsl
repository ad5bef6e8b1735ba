// Mirror of the parts of core::math::{rsm, gi_photon, path_sort} and packing's rgb9e5
// that trace_indirect.rgen needs (PhotonGi, Smal 2019), same names as the Rust, WGSL
// (shaders/wgsl/common/photon_gi.wgsl) and OpenCL C (kernels/common/photon_gi.cl,
// kernels/sort_indirect_paths.cl).

// rsm::cosine_hemisphere (Malley).
precise vec3 cosine_hemisphere(vec2 u, vec3 n) {
    float r = sqrt(u.x);
    float phi = TAU_F * u.y;
    float z = sqrt(max(1.0 - u.x, 0.0));
    return to_world(vec3(r * cos(phi), r * sin(phi), z), n);
}

// rsm::russian_roulette: w = 1 survives with flux xyz, 0 absorbed.
precise vec4 russian_roulette(vec3 flux, vec3 albedo, float xi) {
    vec3 reflected = flux * albedo;
    float m = max_element3(flux);
    if (!(m > 0.0)) return vec4(0.0);
    float q = clampf(max_element3(reflected) / m, 0.0, 1.0);
    if (xi < q) return vec4(reflected / q, 1.0);
    return vec4(0.0);
}

// rsm::chunk_photons: the photons of a launch's chunk below count.
uint chunk_photons(uint count, uint chunk_first, uint chunk_size) {
    return min(count - min(chunk_first, count), chunk_size);
}

// rsm::coherent_sample_order: the sample thread t of a launch over n samples traces.
uint coherent_sample_order(uint t, uint n) {
    if (n < 64u) return t;
    uint m = uint(findMSB(n));
    if (t >= (1u << m)) return t;
    uint k = (m - 5u) / 2u;
    uint hi = m - k;
    return ((t & ((1u << hi) - 1u)) << k) | (t >> hi);
}

// gi_photon::screen_tile.
uint screen_tile(uint x, uint y, uint width, uint tile_size) {
    uint t = max(tile_size, 1u);
    uint tiles_x = (width + t - 1u) / t;
    return (y / t) * tiles_x + x / t;
}

// packing::pow2: 2^k from its bits.
float pow2(int k) { return uintBitsToFloat(uint(k + 127) << 23); }

// packing::pack_rgb9e5 (exact arithmetic only).
uint pack_rgb9e5(vec3 rgb) {
    precise float r = is_nan(rgb.x) ? 0.0 : clampf(rgb.x, 0.0, 65408.0);
    precise float g = is_nan(rgb.y) ? 0.0 : clampf(rgb.y, 0.0, 65408.0);
    precise float b = is_nan(rgb.z) ? 0.0 : clampf(rgb.z, 0.0, 65408.0);
    precise float max_c = max(max(r, g), b);
    if (max_c == 0.0) return 0u;
    int e = int((floatBitsToUint(max_c) >> 23) & 0xffu) - 127;
    int exp_shared = max(e, -16) + 1 + 15;
    precise float scale = pow2(9 + 15 - exp_shared);
    precise float top = floor(max_c * scale + 0.5);
    if (uint(top) == 512u) {
        exp_shared += 1;
        scale = scale * 0.5;
    }
    precise float fr = floor(r * scale + 0.5);
    precise float fg = floor(g * scale + 0.5);
    precise float fb = floor(b * scale + 0.5);
    uint qr = min(uint(fr), 511u);
    uint qg = min(uint(fg), 511u);
    uint qb = min(uint(fb), 511u);
    return qr | (qg << 9) | (qb << 18) | (uint(exp_shared) << 27);
}

// path_sort::path_sort_key's cell along one axis: clamp((o - lo) * s, 0, top), truncated;
// one subtraction and one product (`precise`: not fused), NaN gives 0 as Rust's
// f32::max(NaN, 0.0) does (GLSL's max leaves NaN undefined, hence the comparisons).
uint path_sort_cell(float o, float lo, float s, float top) {
    precise float c = (o - lo) * s;
    c = c > 0.0 ? c : 0.0;
    return uint(c < top ? c : top);
}

// path_sort::path_sort_key: the octant of `direction` (bit 0 x, 1 y, 2 z set where that
// component is negative) above the Morton code (x in bit 3b, y 3b + 1, z 3b + 2) of
// `origin`'s cell, 2^PATH_SORT_BITS a side from origin_min at origin_scale cells per unit.
uint path_sort_key(vec3 origin, vec3 direction, vec3 origin_min, vec3 origin_scale) {
    float top = float((1u << PATH_SORT_BITS) - 1u);
    uint x = path_sort_cell(origin.x, origin_min.x, origin_scale.x, top);
    uint y = path_sort_cell(origin.y, origin_min.y, origin_scale.y, top);
    uint z = path_sort_cell(origin.z, origin_min.z, origin_scale.z, top);
    uint morton = 0u;
    for (uint b = 0u; b < PATH_SORT_BITS; b++)
        morton |= ((x >> b) & 1u) << (3u * b) | ((y >> b) & 1u) << (3u * b + 1u) |
                  ((z >> b) & 1u) << (3u * b + 2u);
    uint octant = (direction.x < 0.0 ? 1u : 0u) | (direction.y < 0.0 ? 2u : 0u) |
                  (direction.z < 0.0 ? 4u : 0u);
    return octant << (3u * PATH_SORT_BITS) | morton;
}

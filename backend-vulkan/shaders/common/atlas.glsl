// Mirror of core::math::map_gather's texel addressing (the caustic atlas, Vanderstichelen 2021) and of
// the photon map's word layout (core::device::layout::deposit_word), as
// shaders/wgsl/common/atlas.wgsl and prelude.wgsl and backend-opencl map_gather.cl and
// planes.cl have them.

uint atlas_texel_index(uvec4 tile, vec2 uv, uint atlas_width) {
    float s = float(tile.z);
    precise float fx = floor(uv.x * s);
    precise float fy = floor(uv.y * s);
    uint cx = min(uint(max(fx, 0.0)), tile.z - 1u);
    uint cy = min(uint(max(fy, 0.0)), tile.z - 1u);
    return (tile.y + cy) * atlas_width + tile.x + cx;
}

// math::map_gather::triangle_reach_bit: (word, bit) of scene triangle t in a reach mask
uvec2 triangle_reach_bit(uint t) { return uvec2(t >> 5u, 1u << (t & 31u)); }

// core's deposit_word: (plane, index in the plane) of word `word` of pixel `pixel`.
uvec2 deposit_word(uint pixel, uint word) {
    uint k = word / 4u;
    uint n = k == 2u ? 2u : 4u;
    return uvec2(k, pixel * n + (word - 4u * k));
}

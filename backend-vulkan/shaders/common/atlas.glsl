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

// math::map_gather::centroid_offset along one axis: a photon's offset inside its texel
// (the tile's `side` texels) in 1/CENTROID_SUBTEXELS of a texel, 0..=255; products by
// powers of two and a floor only, so that every backend computes the same integers.
uint centroid_offset_axis(float u, uint side) {
    float s = float(side);
    precise float f = floor(u * s);
    precise float g = floor(u * s * float(CENTROID_SUBTEXELS));
    uint c = min(uint(max(f, 0.0)), side - 1u);
    uint steps = uint(max(g, 0.0));
    uint base = c * CENTROID_SUBTEXELS;
    return min(steps >= base ? steps - base : 0u, CENTROID_SUBTEXELS - 1u);
}

// math::map_gather::centroid_offset: both axes, on tile `tile`.
uvec2 centroid_offset(uvec4 tile, vec2 uv) {
    return uvec2(centroid_offset_axis(uv.x, tile.z), centroid_offset_axis(uv.y, tile.z));
}

// math::map_gather::triangle_reach_bit: (word, bit) of scene triangle t in a reach mask
uvec2 triangle_reach_bit(uint t) { return uvec2(t >> 5u, 1u << (t & 31u)); }

// core's deposit_word: (plane, index in the plane) of word `word` of pixel `pixel`.
uvec2 deposit_word(uint pixel, uint word) {
    uint k = word / 4u;
    uint n = k == 2u ? 2u : 4u;
    return uvec2(k, pixel * n + (word - 4u * k));
}

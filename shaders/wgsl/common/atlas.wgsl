// Mirror of core::math::map_gather's texel addressing (the caustic atlas, Vanderstichelen 2021).

fn atlas_texel_index(tile: vec4<u32>, uv: vec2<f32>, atlas_width: u32) -> u32 {
    let s = f32(tile.z);
    let cx = min(u32(max(floor(uv.x * s), 0.0)), tile.z - 1u);
    let cy = min(u32(max(floor(uv.y * s), 0.0)), tile.z - 1u);
    return (tile.y + cy) * atlas_width + tile.x + cx;
}

// math::map_gather::centroid_offset along one axis: a photon's offset inside its texel
// (the tile's `side` texels) in 1/CENTROID_SUBTEXELS of a texel, 0..=255; products by
// powers of two and a floor only, so that every backend computes the same integers.
fn centroid_offset_axis(u: f32, side: u32) -> u32 {
    let s = f32(side);
    let c = min(u32(max(floor(u * s), 0.0)), side - 1u);
    let steps = u32(max(floor(u * s * f32(CENTROID_SUBTEXELS)), 0.0));
    let base = c * CENTROID_SUBTEXELS;
    return min(select(0u, steps - base, steps >= base), CENTROID_SUBTEXELS - 1u);
}

// math::map_gather::centroid_offset: both axes, on tile `tile`.
fn centroid_offset(tile: vec4<u32>, uv: vec2<f32>) -> vec2<u32> {
    return vec2<u32>(centroid_offset_axis(uv.x, tile.z), centroid_offset_axis(uv.y, tile.z));
}

// math::map_gather::triangle_reach_bit: (word, bit) of scene triangle t in a reach mask
fn triangle_reach_bit(t: u32) -> vec2<u32> {
    return vec2<u32>(t >> 5u, 1u << (t & 31u));
}

fn join_u64_f32(lo: u32, hi: u32) -> f32 {
    return f32(hi) * 4294967296.0f + f32(lo);
}

// (first column, last column, first row, last row), inclusive.
fn tile_window(tile: vec4<u32>, x: u32, y: u32, n: u32) -> vec4<u32> {
    let h = n / 2u;
    return vec4<u32>(max(select(0u, x - h, x >= h), tile.x), min(x + h, tile.x + tile.z - 1u),
                     max(select(0u, y - h, y >= h), tile.y), min(y + h, tile.y + tile.z - 1u));
}


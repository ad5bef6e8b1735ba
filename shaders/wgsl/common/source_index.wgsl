// Mirror of core/src/math/density_gather.rs (footprint_reach, reach_grid_index,
// reach_grid_entry, pass_reach, source_mask_word, source_bits, accumulate_source_index)
// and backend-opencl/kernels/common/density_gather.cl: the density gather's source index,
// which lets a pass visit only the sources that can have weight at a pixel. A kernel that
// needs this file binds `source_index` (array<atomic<u32>>, source_index_len entries: the
// row pass's reach grid, the column pass's, the row pass's source mask, the column
// pass's).

// The largest |offset| at which footprint_weight(offset, radius) can be nonzero, capped
// at `cap`; -1 where none.
fn footprint_reach(radius: f32, cap: i32) -> i32 {
    let s = radius + 0.5;
    if (!(s > 0.0)) {
        return -1;
    }
    return i32(min(ceil(s), f32(cap) + 1.0)) - 1;
}

// Entries of the two reach grids of a w x h image.
fn reach_grid_len(w: i32, h: i32) -> i32 {
    return 2 * ((w + REACH_TILE - 1) / REACH_TILE) * ((h + REACH_TILE - 1) / REACH_TILE);
}

// Index of the tile holding (x, y) in pass `axis`'s grid of a w x h image.
fn reach_grid_index(w: i32, h: i32, axis: u32, x: i32, y: i32) -> u32 {
    let tx = (w + REACH_TILE - 1) / REACH_TILE;
    let ty = (h + REACH_TILE - 1) / REACH_TILE;
    return u32(i32(axis) * tx * ty + (y / REACH_TILE) * tx + x / REACH_TILE);
}

// Index of word k of pass `axis`'s mask line through (x, y) (row y for axis 0, column x
// for axis 1).
fn source_mask_word(w: i32, h: i32, axis: u32, x: i32, y: i32, k: i32) -> u32 {
    let base = reach_grid_len(w, h);
    if (axis == 0u) {
        return u32(base + y * ((w + 31) / 32) + k);
    }
    return u32(base + h * ((w + 31) / 32) + x * ((h + 31) / 32) + k);
}

// Word k of the mask line through (x, y), its bits outside [lo, hi] cleared.
fn source_bits(w: i32, h: i32, axis: u32, x: i32, y: i32, k: i32, lo: i32, hi: i32) -> u32 {
    var bits = atomicLoad(&source_index[source_mask_word(w, h, axis, x, y, k)]);
    if (k == lo / 32) {
        bits &= 0xffffffffu << u32(lo % 32);
    }
    if (k == hi / 32) {
        bits &= 0xffffffffu >> u32(31 - hi % 32);
    }
    return bits;
}

// A source's entry: footprint_reach + 1, 0 for a pixel without flux.
fn reach_grid_entry(source: vec4<f32>, cap: i32) -> u32 {
    if (source.x == 0.0 && source.y == 0.0 && source.z == 0.0) {
        return 0u;
    }
    return u32(footprint_reach(source.w, cap) + 1);
}

// Enters a source pixel into pass `axis`'s part of the index: its reach into its tile
// (atomic maximum), its mask bit (atomic or).
fn put_source(w: i32, h: i32, axis: u32, x: i32, y: i32, source: vec4<f32>, cap: i32) {
    let e = reach_grid_entry(source, cap);
    if (e > 0u) {
        atomicMax(&source_index[reach_grid_index(w, h, axis, x, y)], e);
        let along = select(y, x, axis == 0u);
        atomicOr(&source_index[source_mask_word(w, h, axis, x, y, along / 32)],
                 1u << u32(along % 32));
    }
}

// Half-width of the taps destination (x, y) of pass `axis` visits: the largest reach
// among the tiles of its row (column) within `cap` whose entry covers the distance to the
// tile's nearest pixel; -1 where no source reaches it.
fn pass_reach(w: i32, h: i32, x: i32, y: i32, axis: u32, cap: i32) -> i32 {
    let along = select(y, x, axis == 0u);
    let len = select(h, w, axis == 0u);
    let t0 = max(along - cap, 0) / REACH_TILE;
    let t1 = min(along + cap, len - 1) / REACH_TILE;
    var r = -1;
    for (var k = t0; k <= t1; k++) {
        let tx = select(x / REACH_TILE, k, axis == 0u);
        let ty = select(k, y / REACH_TILE, axis == 0u);
        let g = i32(atomicLoad(&source_index[reach_grid_index(w, h, axis, tx * REACH_TILE,
                                                              ty * REACH_TILE)])) - 1;
        // distance from `along` to the tile's nearest pixel
        let dist = max(max(k * REACH_TILE - along, along - (k * REACH_TILE + REACH_TILE - 1)), 0);
        if (g >= dist) {
            r = max(r, g);
        }
    }
    return min(r, cap);
}

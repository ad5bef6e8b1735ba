//! Scalar functions of the density-adaptive caustic gather (Sspm's default filter; the
//! kernels are `photon_count_table`, `gather_footprint` and `density_gather`).
//!
//! **Method.** An adaptive ("variable") kernel density estimate in screen space: every
//! source pixel spreads its deposited flux over a kernel whose radius follows the local
//! photon density, and the kernel is normalised per *source*, so the image keeps the
//! deposit's flux by construction.
//!
//! - **Radius: k nearest photons.** A pixel's radius is set by the smallest centred square
//!   window (at least 3x3, [`MIN_WINDOW_HALF_WIDTH`]) that holds `k` photons, as photon
//!   mapping's k-nearest-neighbour estimate does (Jensen 1996, "Global illumination using
//!   photon maps", Rendering Techniques '96) and as progressive photon mapping shrinks its
//!   radius where photons accumulate (Hachisuka, Ogaki and Jensen 2008, "Progressive photon
//!   mapping", ACM TOG 27(5)). With `c` photons in a window of `a` pixels the density is
//!   `c / a` per pixel, and the kernel's support half-width is half the side of the square
//!   that holds `k` photons at that density, `r = sqrt(k a / c) / 2` pixels
//!   ([`knn_radius`]). Where the 3x3 window holds `k` photons per pixel, `r <= 1/2`: the
//!   support lies inside the pixel and the kernel is the identity, so a focused caustic is
//!   not blurred at all, and as the photon budget grows every pixel gets there and the
//!   output becomes the raw deposit, which converges. No radius is in scene units, so the
//!   scene's scale does not matter. Windows are counted with a summed-area table (Crow
//!   1984, "Summed-area tables for texture mapping", SIGGRAPH '84) of the per-pixel photon
//!   counts clamped at `9 k` ([`clamped_photon_count`]), summed per block
//!   ([`table_block`], [`window_photons`]): four reads per block a window overlaps.
//! - **Scatter normalisation: energy kept by construction.** The estimate is the
//!   sample-point adaptive kernel estimator, in which each *sample* carries its own
//!   bandwidth (Breiman, Meisel and Purcell 1977, "Variable kernel estimates of
//!   multivariate densities", Technometrics 19(2); Silverman 1986, "Density Estimation
//!   for Statistics and Data Analysis", section 5.3). Source pixel `i` with flux `F_i`
//!   gives destination `j` the share `F_i w_ij / W_i`, where `W_i = sum_j w_ij` runs over
//!   the destinations that exist: receivers inside the image and on the same surface (the
//!   edge weight). So `sum_j out_j = sum_i F_i` exactly in real arithmetic, also at the
//!   image border and at depth edges, where a gather-normalised filter (Kim 2019's
//!   bilateral one) gains or loses flux.
//! - **Separable.** Two 1-D passes (rows, then columns), each scatter-normalised on its
//!   own, so each keeps the flux; the column pass uses the radius of the pixel the row
//!   pass wrote into.
//! - **Weights.** Spatial: the 1-D Epanechnikov kernel integrated over each pixel
//!   ([`footprint_weight`]), compactly supported (zero for pixels outside `r + 1/2`, so
//!   `r <= 1/2` is the identity). Edges: [`edge_weight`], Kim 2019's depth and normal
//!   terms (Kim 2019, section 30.3.2), made symmetric so that a source's normaliser and its
//!   destinations' gathers use the very same number.
//!
//! - **Source index: only the taps with weight.** `gather_footprint` and the row pass
//!   enter every pixel they give flux into a bit mask (one bit per pixel, by rows for the
//!   row pass, by columns for the column pass) and into a per-tile grid of the farthest
//!   tap any source there has weight at ([`footprint_reach`], [`pass_reach`]); a pass
//!   visits only the set bits within that reach ([`for_each_pass_source`]). The visited
//!   taps are a superset of those with weight, in the loop's order, so the sums are
//!   bitwise those of the loop over every tap within `max_radius`; the GPU ports no
//!   longer pay, per warp, the weights of every tap that one lane needs.
//!
//! The filter works on flux (W per pixel), not radiance: flux is what is conserved, and
//! radiance `L = (albedo / pi) Phi / A` (Kim 2019, Eq. 5) is formed after the last pass with the
//! destination pixel's area.

/// Smallest window half-width: a pixel's density is never judged from the pixel alone.
/// If it were, a pixel that by chance holds more photons than its neighbours (and so
/// more flux) would keep them while its sparser neighbours spread theirs into it: the
/// radius would correlate with the flux it spreads, a bias that does not average out
/// (measured on `cornell`: with one-pixel windows the filtered error exceeded the raw
/// deposit's at 2048^2 photons). In a 3x3 window a pixel's own count is a ninth of the
/// evidence.
pub const MIN_WINDOW_HALF_WIDTH: i32 = 1;

/// Photons a pixel may contribute to the summed-area table, in units of `k`: a window
/// of `(2 MIN_WINDOW_HALF_WIDTH + 1)^2 = 9` pixels holds `9 k` photons exactly when its
/// radius is 1 (the identity), so a single pixel must be able to hold that many.
pub const COUNT_CLAMP_PER_K: u32 = 9;

/// Per-pixel photon count as the summed-area table holds it: `min(count, 9 k)`. Clamping
/// keeps every decision the gather makes exact (a window holding a pixel with `9 k`
/// photons has at least that many either way) and bounds a window's sum by
/// `9 k * 513^2 < 2^32` (`k <= 1024`, windows at most 513 pixels wide:
/// `9 * 2^10 * 513^2 < 2^32`), so the table's wrapping `u32` sums give every window's
/// count exactly.
#[inline]
pub fn clamped_photon_count(lo: u32, hi: u32, k: u32) -> u32 {
    let clamp = COUNT_CLAMP_PER_K * k;
    if hi != 0 {
        clamp
    } else {
        lo.min(clamp)
    }
}

/// Threads of a workgroup of the GPU ports' count-table scans (the launch's default
/// workgroup size); [`table_block`] is a multiple of it.
pub const SCAN_THREADS: u32 = 64;
/// Chunks a block's column is cut into by the GPU column scan (`table_block / 8` rows
/// each), so that eight threads share a column's latency chain.
pub const COLUMN_CHUNKS: u32 = 8;
/// Neighbouring columns a workgroup of the GPU column scan takes: `SCAN_THREADS /
/// COLUMN_CHUNKS`.
pub const SCAN_COLUMNS: u32 = SCAN_THREADS / COLUMN_CHUNKS;

/// Edge of the square blocks of the photon-count table (pixels): the smallest power of
/// two that is at least 64 and holds the widest window, `2 max_radius + 1`, so that a
/// window overlaps at most 2 x 2 blocks.
pub fn table_block(max_radius: u32) -> u32 {
    (2 * max_radius.max(MIN_WINDOW_HALF_WIDTH as u32) + 1)
        .next_power_of_two()
        .max(64)
}

/// The blocked summed-area table's entry at `(x, y)`: the sum over the rectangle from
/// the corner of `(x, y)`'s block to `(x, y)` (wrapping `u32`); 0 left of or above the
/// block whose corner is `(bx0, by0)`.
#[inline]
pub fn table_entry(table: &[u32], width: i32, bx0: i32, by0: i32, x: i32, y: i32) -> u32 {
    if x < bx0 || y < by0 {
        0
    } else {
        table[(y * width + x) as usize]
    }
}

/// Photons (clamped per pixel, see [`clamped_photon_count`]) in the rectangle
/// `[x0, x1] x [y0, y1]` (inside the image, `x0 <= x1`, `y0 <= y1`). The table is summed
/// per `block x block` block (one short scan per block row and column instead of one per
/// image row, which took 0.9 ms at 1920x1080 on an H200), so a rectangle adds the parts
/// it covers in each block it overlaps (at most 2 x 2 for the gather's windows), four
/// reads each. Wrapping sums: exact for any rectangle of fewer than 2^32 photons.
/// `block` is a power of two ([`table_block`]): block indices are shifts of the
/// (non-negative) coordinates, `log2 block = 31 - leading_zeros(block)`, not divisions.
#[inline]
pub fn rect_photons(table: &[u32], w: i32, block: i32, x0: i32, y0: i32, x1: i32, y1: i32) -> u32 {
    let shift = 31 - (block as u32).leading_zeros();
    let mut count = 0u32;
    for by in y0 >> shift..=y1 >> shift {
        for bx in x0 >> shift..=x1 >> shift {
            let (bx0, by0) = (bx * block, by * block);
            let (xa, xb) = (x0.max(bx0), x1.min(bx0 + block - 1));
            let (ya, yb) = (y0.max(by0), y1.min(by0 + block - 1));
            count = count
                .wrapping_add(table_entry(table, w, bx0, by0, xb, yb))
                .wrapping_sub(table_entry(table, w, bx0, by0, xa - 1, yb))
                .wrapping_sub(table_entry(table, w, bx0, by0, xb, ya - 1))
                .wrapping_add(table_entry(table, w, bx0, by0, xa - 1, ya - 1));
        }
    }
    count
}

/// Photons in the window of half-width `half_width` around `(x, y)`, clipped to the
/// image ([`rect_photons`]), and the window's pixel count.
#[inline]
pub fn window_photons(
    table: &[u32],
    w: i32,
    h: i32,
    block: i32,
    x: i32,
    y: i32,
    half_width: i32,
) -> (u32, u32) {
    let (x0, y0) = ((x - half_width).max(0), (y - half_width).max(0));
    let (x1, y1) = ((x + half_width).min(w - 1), (y + half_width).min(h - 1));
    let count = rect_photons(table, w, block, x0, y0, x1, y1);
    (count, ((x1 - x0 + 1) * (y1 - y0 + 1)) as u32)
}

/// Depth an edge texel holds for a pixel that is not a receiver (receivers' view depths
/// are positive).
pub const EDGE_TEXEL_NOT_RECEIVER: f32 = -1.0;

/// A pixel's edge texel: what [`edge_weight`] reads of it, `(depth, normal)` (view depth
/// in scene units, world-space unit normal), with depth [`EDGE_TEXEL_NOT_RECEIVER`] where
/// the pixel is not a receiver. `gather_footprint` writes one per pixel so that the gather
/// passes read one 16-byte texel a tap instead of three G-buffer planes; the values are
/// the G-buffer's own bits.
#[inline]
pub fn edge_texel(receiver: bool, depth: f32, normal: [f32; 3]) -> [f32; 4] {
    if receiver {
        [depth, normal[0], normal[1], normal[2]]
    } else {
        [EDGE_TEXEL_NOT_RECEIVER, 0.0, 0.0, 0.0]
    }
}

/// `sigma_depth` of the density gather on the caustic atlas: with
/// [`atlas_edge_texel`]'s "depths" (tile + 1 >= 1) the depth term of [`edge_weight`] is
/// `exp(-0 / (1e-30 z)) = 1` between texels of one tile and `exp(-|dt| / (1e-30 z)) <=
/// exp(-1e30 / 2^24) = 0` (it underflows to +0 in f32, exactly, on every backend) between
/// texels of two tiles: the gather never crosses a tile border, as Vanderstichelen 2021's N x N gather
/// does not. (1e-30 is a normal f32; with `normal_power` 0 the normal term is skipped.)
pub const ATLAS_SIGMA_DEPTH: f32 = 1e-30;

/// Most tiles an atlas may have for the density gather: tile + 1 must be exact in f32.
pub const ATLAS_MAX_TILES: u32 = 1 << 24;

/// An atlas texel's edge texel for the density gather: `(tile + 1, world area, 0, 0)` for
/// a texel some receiver's UV triangle covers (world area > 0, scene units^2), the
/// not-a-receiver mark elsewhere (texels outside every triangle, and outside every tile).
/// The "depth" keeps the gather inside a tile ([`ATLAS_SIGMA_DEPTH`]); `density_gather`'s
/// last pass divides by the area.
#[inline]
pub fn atlas_edge_texel(tile: u32, area: f32) -> [f32; 4] {
    if tile < ATLAS_MAX_TILES && area > 0.0 {
        [tile as f32 + 1.0, area, 0.0, 0.0]
    } else {
        [EDGE_TEXEL_NOT_RECEIVER, 0.0, 0.0, 0.0]
    }
}

/// The eight neighbours of an atlas texel in the order [`atlas_edge_texels`] looks for an
/// heir: the four sharing an edge first, then the four sharing a corner (texel offsets).
pub const HEIR_OFFSETS: [(i32, i32); 8] = [
    (-1, 0),
    (1, 0),
    (0, -1),
    (0, 1),
    (-1, -1),
    (1, -1),
    (-1, 1),
    (1, 1),
];

/// The edge texel of an uncovered atlas texel (inside a tile, its centre outside every
/// UV triangle) whose flux goes to its neighbour at `HEIR_OFFSETS[heir - 1]`, a covered
/// texel of the same tile; `heir` 0 for none. A photon within half a texel of a UV
/// island's border can land in such a texel: the raw map has no area to show it in, and
/// `gather_footprint` adds its flux to the heir's so that the density gather keeps it
/// (Vanderstichelen 2021's box gather keeps it by spreading its window over covered texels).
#[inline]
pub fn uncovered_edge_texel(heir: u32) -> [f32; 4] {
    [EDGE_TEXEL_NOT_RECEIVER, heir.min(8) as f32, 0.0, 0.0]
}

/// The heir of a texel that is not a receiver's (`1..=8`, an index into [`HEIR_OFFSETS`]
/// plus one), 0 for none (every non-receiver pixel of Sspm's screen).
#[inline]
pub fn edge_texel_heir(t: &[f32; 4]) -> u32 {
    if edge_texel_is_receiver(t) || !(t[1] >= 1.0 && t[1] <= 8.0) {
        0
    } else {
        t[1] as u32
    }
}

/// Every atlas texel's edge texel ([`atlas_edge_texel`]; for `(world area, tile)` texels
/// of a `size.0`-wide atlas, row-major): an uncovered texel inside a tile names as its
/// heir ([`uncovered_edge_texel`]) its first neighbour in [`HEIR_OFFSETS`] order that is
/// a covered texel of the same tile, if any.
pub fn atlas_edge_texels(texels: &[[u32; 2]], width: u32) -> Vec<[f32; 4]> {
    let w = width as i64;
    let h = if w > 0 { texels.len() as i64 / w } else { 0 };
    let at = |x: i64, y: i64| -> Option<[u32; 2]> {
        (x >= 0 && y >= 0 && x < w && y < h).then(|| texels[(y * w + x) as usize])
    };
    texels
        .iter()
        .enumerate()
        .map(|(i, t)| {
            let edge = atlas_edge_texel(t[1], f32::from_bits(t[0]));
            if edge_texel_is_receiver(&edge) || t[1] >= ATLAS_MAX_TILES || w == 0 {
                return edge;
            }
            let (x, y) = (i as i64 % w, i as i64 / w);
            let heir = HEIR_OFFSETS.iter().position(|&(dx, dy)| {
                at(x + dx as i64, y + dy as i64).is_some_and(|n| {
                    n[1] == t[1]
                        && edge_texel_is_receiver(&atlas_edge_texel(n[1], f32::from_bits(n[0])))
                })
            });
            uncovered_edge_texel(heir.map_or(0, |k| k as u32 + 1))
        })
        .collect()
}

/// The flux `gather_footprint` gives receiver pixel `(x, y)` of a `w x h` image: its own,
/// then that of each neighbour in [`HEIR_OFFSETS`] order whose heir it is, added in f32
/// in that order. `flux(i)` is pixel `i`'s deposited flux (W per channel).
pub fn inherited_flux(
    edge: &[[f32; 4]],
    w: i32,
    h: i32,
    x: i32,
    y: i32,
    flux: impl Fn(i32) -> [f32; 3],
) -> [f32; 3] {
    let mut f = flux(y * w + x);
    for &(dx, dy) in HEIR_OFFSETS.iter() {
        let (nx, ny) = (x + dx, y + dy);
        if nx < 0 || ny < 0 || nx >= w || ny >= h {
            continue;
        }
        let n = ny * w + nx;
        let heir = edge_texel_heir(&edge[n as usize]);
        // the neighbour's heir is this pixel: its offset is the opposite of offset k
        if heir != 0 && HEIR_OFFSETS[heir as usize - 1] == (-dx, -dy) {
            let g = flux(n);
            f = [f[0] + g[0], f[1] + g[1], f[2] + g[2]];
        }
    }
    f
}

/// Whether an edge texel is a receiver's ([`edge_texel`]).
#[inline]
pub fn edge_texel_is_receiver(t: &[f32; 4]) -> bool {
    t[0] >= 0.0
}

/// Edge of the square pixel tiles in which `density_gather`'s column pass hands pixels to
/// threads: 64 consecutive threads (a workgroup) take one 8 x 8 tile, so a workgroup reads
/// its columns' `8 + 2 reach` rows once instead of every thread of a 64-pixel row segment
/// reading its own column (measured on an H200, see the README).
pub const COLUMN_PASS_TILE: u32 = 8;

/// Threads the column pass launches for a `w x h` image: 64 per 8 x 8 tile, the edge tiles
/// padded.
pub fn column_pass_threads(w: u32, h: u32) -> u64 {
    let t = COLUMN_PASS_TILE;
    w.div_ceil(t) as u64 * h.div_ceil(t) as u64 * (t * t) as u64
}

/// The pixel `(x, y)` that thread `t` of the column pass takes (tile `t / 64` in row-major
/// tile order, pixel `t % 64` row-major inside it), `None` for the padding of edge tiles.
pub fn column_pass_pixel(t: u64, w: u32, h: u32) -> Option<(u32, u32)> {
    let e = COLUMN_PASS_TILE as u64;
    let (tile, l) = (t / (e * e), t % (e * e));
    let tiles_x = w.div_ceil(COLUMN_PASS_TILE) as u64;
    let x = (tile % tiles_x) * e + l % e;
    let y = (tile / tiles_x) * e + l / e;
    (x < w as u64 && y < h as u64).then_some((x as u32, y as u32))
}

/// Edge of the square tiles of the reach grid (pixels, or atlas texels on the caustic
/// atlas): one `u32` per tile and pass, see [`pass_reach`].
pub const REACH_TILE: u32 = 8;

/// The largest `|offset|` at which [`footprint_weight`]`(offset, radius)` can be nonzero,
/// capped at `cap`: the weight needs `|d| < radius + 1/2` (the very f32 sum
/// `footprint_weight` tests), and for `s = radius + 1/2 > 0` the integers with `|d| < s`
/// are those with `|d| <= ceil(s) - 1`. -1 where no offset has weight (a negative or NaN
/// radius).
#[inline]
pub fn footprint_reach(radius: f32, cap: i32) -> i32 {
    let s = radius + 0.5;
    if !(s > 0.0) {
        return -1;
    }
    s.ceil().min(cap as f32 + 1.0) as i32 - 1
}

/// Tiles `(across, down)` of one pass's reach grid over a `w x h` image.
pub fn reach_grid_tiles(w: u32, h: u32) -> (u32, u32) {
    (w.div_ceil(REACH_TILE), h.div_ceil(REACH_TILE))
}

/// Entries of the reach grid buffer: one grid per pass, the row pass's sources first
/// (written by `gather_footprint`), then the column pass's (written by the row pass).
pub fn reach_grid_len(w: u32, h: u32) -> u32 {
    let (tx, ty) = reach_grid_tiles(w, h);
    2 * tx * ty
}

/// Index into the reach grid buffer of the tile holding `(x, y)` in pass `axis`'s grid.
#[inline]
pub fn reach_grid_index(w: u32, h: u32, axis: u32, x: u32, y: u32) -> usize {
    let (tx, ty) = reach_grid_tiles(w, h);
    (axis * tx * ty + (y / REACH_TILE) * tx + x / REACH_TILE) as usize
}

/// The entry a source pixel puts into its tile (the grid keeps the maximum):
/// [`footprint_reach`]` + 1`, so 0 means "no source in this tile". A source is a pixel
/// whose flux is not all zero, the exact negation of the gather's "source without flux"
/// test.
#[inline]
pub fn reach_grid_entry(source: &[f32; 4], cap: i32) -> u32 {
    if source[0] == 0.0 && source[1] == 0.0 && source[2] == 0.0 {
        return 0;
    }
    (footprint_reach(source[3], cap) + 1) as u32
}

/// Half-width of the taps that destination `(x, y)` of pass `axis` must visit: the largest
/// reach among the tiles of its row (axis 0) or column (1) within `cap` whose entry covers
/// the distance from `(x, y)` to the tile's nearest pixel; -1 where no source reaches it.
/// Every source with a nonzero weight at `(x, y)` lies within it, so a loop over
/// `-reach..=reach` sums exactly the terms of a loop over `-cap..=cap` in the same order:
/// the same bits, with the dark and sparse parts of the image visiting few taps or none.
pub fn pass_reach(grid: &[u32], w: i32, h: i32, x: i32, y: i32, axis: u32, cap: i32) -> i32 {
    let t = REACH_TILE as i32;
    let (along, len) = if axis == 0 { (x, w) } else { (y, h) };
    let (t0, t1) = ((along - cap).max(0) / t, (along + cap).min(len - 1) / t);
    let mut reach = -1;
    for k in t0..=t1 {
        let (tx, ty) = if axis == 0 { (k, y / t) } else { (x / t, k) };
        let entry =
            grid[reach_grid_index(w as u32, h as u32, axis, (tx * t) as u32, (ty * t) as u32)];
        let g = entry as i32 - 1;
        // distance from `along` to the tile's nearest pixel
        let dist = (k * t - along).max(along - (k * t + t - 1)).max(0);
        if g >= dist {
            reach = reach.max(g);
        }
    }
    reach.min(cap)
}

/// Words of pass `axis`'s source mask over a `w x h` image: one bit per pixel,
/// `ceil(w / 32)` words per image row (axis 0) or `ceil(h / 32)` per column (axis 1), so
/// that the pixels a pass's loop visits lie in consecutive words.
pub fn source_mask_words(w: u32, h: u32, axis: u32) -> u32 {
    if axis == 0 {
        h * w.div_ceil(32)
    } else {
        w * h.div_ceil(32)
    }
}

/// Entries of the gather's source index, the buffer `gather_footprint` and the row pass
/// fill and the passes read: the reach grids ([`reach_grid_len`]), then the row pass's
/// source mask, then the column pass's ([`source_mask_words`]). Zeroed before each gather.
pub fn source_index_len(w: u32, h: u32) -> u32 {
    reach_grid_len(w, h) + source_mask_words(w, h, 0) + source_mask_words(w, h, 1)
}

/// Index in the source index of word `k` of the mask line (image row `y` for axis 0,
/// column `x` for axis 1) through `(x, y)`.
#[inline]
pub fn source_mask_word(w: u32, h: u32, axis: u32, x: u32, y: u32, k: u32) -> usize {
    let base = reach_grid_len(w, h);
    (if axis == 0 {
        base + y * w.div_ceil(32) + k
    } else {
        base + source_mask_words(w, h, 0) + x * h.div_ceil(32) + k
    }) as usize
}

/// Word `k` of the mask line through `(x, y)` (pass `axis`), its bits outside
/// `[lo, hi]` (positions along the line) cleared.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn source_bits(
    index: &[u32],
    w: u32,
    h: u32,
    axis: u32,
    x: u32,
    y: u32,
    k: u32,
    lo: u32,
    hi: u32,
) -> u32 {
    let mut bits = index[source_mask_word(w, h, axis, x, y, k)];
    if k == lo / 32 {
        bits &= !0u32 << (lo % 32);
    }
    if k == hi / 32 {
        bits &= !0u32 >> (31 - hi % 32);
    }
    bits
}

/// Pass `axis`'s part of the source index for `sources` (a `w x h` image of `(flux,
/// radius)`), merged into `index` as the GPU ports' atomic maxima and ors do: per tile the
/// maximum [`reach_grid_entry`], and a mask bit for every source.
pub fn accumulate_source_index(
    index: &mut [u32],
    sources: &[[f32; 4]],
    w: u32,
    h: u32,
    axis: u32,
    cap: i32,
) {
    for (i, s) in sources.iter().enumerate() {
        let e = reach_grid_entry(s, cap);
        if e > 0 {
            let (x, y) = (i as u32 % w, i as u32 / w);
            let k = reach_grid_index(w, h, axis, x, y);
            index[k] = index[k].max(e);
            let along = if axis == 0 { x } else { y };
            index[source_mask_word(w, h, axis, x, y, along / 32)] |= 1 << (along % 32);
        }
    }
}

/// The offsets `d` (increasing) of the sources destination `(x, y)` of pass `axis` visits:
/// the mask's set bits within [`pass_reach`] of it, clipped to the image. Every tap the
/// unbounded loop over `-cap..=cap` would have summed is among them, in the same order.
#[allow(clippy::too_many_arguments)]
pub fn for_each_pass_source(
    index: &[u32],
    w: i32,
    h: i32,
    x: i32,
    y: i32,
    axis: u32,
    cap: i32,
    mut f: impl FnMut(i32),
) {
    let taps = pass_reach(index, w, h, x, y, axis, cap);
    let (along, len) = if axis == 0 { (x, w) } else { (y, h) };
    let (lo, hi) = ((along - taps).max(0), (along + taps).min(len - 1));
    if lo > hi {
        return;
    }
    let (lo, hi) = (lo as u32, hi as u32);
    for k in lo / 32..=hi / 32 {
        let mut bits = source_bits(
            index, w as u32, h as u32, axis, x as u32, y as u32, k, lo, hi,
        );
        while bits != 0 {
            let b = bits.trailing_zeros();
            bits &= bits - 1;
            f((k * 32 + b) as i32 - along);
        }
    }
}

/// k-NN radius (pixels): half the side of the square that holds `k` photons at the
/// density `photons / pixels` of the smallest window holding `k` (Jensen 1996; see the
/// module doc), the support half-width of the kernel. `photons >= 1`.
#[inline]
pub fn knn_radius(k: u32, pixels: u32, photons: u32) -> f32 {
    0.5 * (k as f32 * pixels as f32 / photons as f32).sqrt()
}

/// The gather radius (pixels) at `(x, y)`: [`knn_radius`] of the smallest window (binary
/// search over half-widths `MIN_WINDOW_HALF_WIDTH..=max_radius`) holding `k` photons,
/// capped at `max_radius`; `max_radius` where even the largest window holds fewer.
#[allow(clippy::too_many_arguments)]
pub fn footprint_radius(
    table: &[u32],
    w: i32,
    h: i32,
    block: i32,
    x: i32,
    y: i32,
    k: u32,
    max_radius: u32,
) -> f32 {
    let max_radius = (max_radius as i32).max(MIN_WINDOW_HALF_WIDTH);
    // (count, pixels) of the window at `hi`, the smallest half-width known to hold k
    let mut at_hi = window_photons(table, w, h, block, x, y, max_radius);
    if at_hi.0 < k {
        return max_radius as f32;
    }
    let (mut lo, mut hi) = (MIN_WINDOW_HALF_WIDTH, max_radius);
    while lo < hi {
        let mid = (lo + hi) / 2;
        let c = window_photons(table, w, h, block, x, y, mid);
        if c.0 >= k {
            hi = mid;
            at_hi = c;
        } else {
            lo = mid + 1;
        }
    }
    knn_radius(k, at_hi.1, at_hi.0).min(max_radius as f32)
}

/// 1-D weight of the pixel `offset` pixels from a source whose kernel has support
/// half-width `radius` (pixels): the Epanechnikov kernel `(3 / 4r) max(0, 1 - (x / r)^2)`
/// (unit integral) integrated over the pixel, `x` in `[offset - 1/2, offset + 1/2]`; in
/// `u = x / r` that is `(3 / 4) (G(u_b) - G(u_a))` with `G(u) = u - u^3 / 3` and the
/// interval clipped to `[-1, 1]`. Weights lie in `[0, 1]` and sum to 1 over a row that
/// holds the whole support. Integrating over the pixel, rather than sampling the kernel
/// at its centre, makes a source's share of its own flux a smooth function of the
/// radius: it keeps all of it while the support lies inside the pixel (`r <= 1/2`), and
/// its neighbours' weights grow from 0 as the square of `r - 1/2`. A sampled
/// kernel's neighbour weight `1 - 1/r^2` grows with slope 2 at `r = 1`, so that pixels
/// just above the identity's threshold gave half their flux to neighbours just below it,
/// which gave none back: flux flowed towards denser pixels (measured on `ring` at 2048^2
/// photons, where the filtered error exceeded the raw deposit's). 0 where the pixel lies
/// outside the support (`|offset| >= r + 1/2`), also for radius 0.
#[inline]
pub fn footprint_weight(offset: i32, radius: f32) -> f32 {
    let d = offset as f32;
    if !(d.abs() < radius + 0.5) {
        return 0.0;
    }
    if !(radius > 0.0) {
        return 1.0; // offset 0 of a zero support: the pixel itself, with no division by 0
    }
    let ua = ((d - 0.5) / radius).max(-1.0);
    let ub = ((d + 0.5) / radius).min(1.0);
    0.75 * ((ub - ub * ub * ub / 3.0) - (ua - ua * ua * ua / 3.0))
}

/// Edge weight between two receiver pixels (view depths in scene units, unit normals):
/// `exp(-|z_a - z_b| / (sigma_depth * min(z_a, z_b))) * max(0, n_a . n_b)^normal_power`
/// (Kim 2019's bilateral terms, Kim 2019, section 30.3.2, symmetric in `a` and `b`).
#[inline]
pub fn edge_weight(
    depth_a: f32,
    normal_a: [f32; 3],
    depth_b: f32,
    normal_b: [f32; 3],
    sigma_depth: f32,
    normal_power: f32,
) -> f32 {
    let wd = (-(depth_a - depth_b).abs() / (sigma_depth * depth_a.min(depth_b))).exp();
    if normal_power > 0.0 {
        let c = normal_a[0] * normal_b[0] + normal_a[1] * normal_b[1] + normal_a[2] * normal_b[2];
        wd * c.max(0.0).powf(normal_power)
    } else {
        wd
    }
}

/// `hi * 2^32 + lo` in f32 from the exact split (the shaders' `join_u64_wide`): the
/// fixed-point sums the gather reads, the same roundings on every backend.
#[inline]
pub fn join_u64_wide(lo: u32, hi: u32) -> f32 {
    hi as f32 * 4294967296.0 + lo as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn footprint_reach_is_the_last_offset_with_weight() {
        for k in 0..4000 {
            let r = k as f32 * 0.01 - 1.0;
            for cap in [0, 1, 3, 16, 256] {
                let last = (0..=cap).rev().find(|&d| footprint_weight(d, r) > 0.0);
                let reach = footprint_reach(r, cap);
                // every offset with weight lies within the reach (a weight may still
                // round to 0 inside it)
                assert!(last.unwrap_or(-1) <= reach, "r {r} cap {cap}");
                assert!(reach <= cap);
                if reach >= 0 {
                    assert!((reach as f32) < r + 0.5, "r {r}: {reach} has no support");
                }
            }
        }
        assert_eq!(footprint_reach(f32::NAN, 16), -1);
        assert_eq!(footprint_reach(0.5, 16), 0);
        assert_eq!(footprint_reach(0.51, 16), 1);
    }

    #[test]
    fn the_pass_visits_every_source_with_weight_and_only_sources() {
        use crate::math::rng::random_f32;
        let (w, h, cap) = (37i32, 29i32, 11i32);
        for seed in 0..24u32 {
            // sparse sources with radii from the identity to beyond the cap
            let img: Vec<[f32; 4]> = (0..(w * h) as u32)
                .map(|i| {
                    let lit = random_f32(seed, i, 0, 0) < 0.04;
                    let r = random_f32(seed, i, 0, 1) * 14.0;
                    [if lit { 1.0 } else { 0.0 }, 0.0, 0.0, r]
                })
                .collect();
            for axis in 0..2u32 {
                let mut grid = vec![0; source_index_len(w as u32, h as u32) as usize];
                accumulate_source_index(&mut grid, &img, w as u32, h as u32, axis, cap);
                for y in 0..h {
                    for x in 0..w {
                        let reach = pass_reach(&grid, w, h, x, y, axis, cap);
                        let mut visited = Vec::new();
                        for_each_pass_source(&grid, w, h, x, y, axis, cap, |d| visited.push(d));
                        assert!(visited.windows(2).all(|p| p[0] < p[1]));
                        for d in -cap..=cap {
                            let (qx, qy) = if axis == 0 { (x + d, y) } else { (x, y + d) };
                            if qx < 0 || qy < 0 || qx >= w || qy >= h {
                                continue;
                            }
                            let s = img[(qy * w + qx) as usize];
                            if s[0] != 0.0 && footprint_weight(-d, s[3]) > 0.0 {
                                assert!(d.abs() <= reach, "({x}, {y}) axis {axis}: tap {d}");
                                assert!(visited.contains(&d), "({x}, {y}) axis {axis}: {d}");
                            }
                            if visited.contains(&d) {
                                assert!(s[0] != 0.0, "({x}, {y}) axis {axis}: dark {d}");
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn uncovered_texels_name_a_covered_heir_of_their_own_tile() {
        // a 4 x 3 atlas: tile 0 in columns 0-1, tile 1 in columns 2-3; covered (area 1)
        // texels marked C, uncovered ones u (tile 0) and v (tile 1), '-' outside tiles
        //   row 0:  C u v C
        //   row 1:  u u v v
        //   row 2:  - C v -
        let one = 1.0f32.to_bits();
        // outside every tile (the layout's NO_TILE, u32::MAX)
        let none = [0, u32::MAX];
        let texels = [
            [one, 0],
            [0, 0],
            [0, 1],
            [one, 1],
            [0, 0],
            [0, 0],
            [0, 1],
            [0, 1],
            none,
            [one, 0],
            [0, 1],
            none,
        ];
        let edge = atlas_edge_texels(&texels, 4);
        let heirs: Vec<u32> = edge.iter().map(edge_texel_heir).collect();
        // (1,0): left neighbour (0,0) is covered -> offset 0 -> heir 1. (0,1): up (0,0)
        // -> offset 2 -> heir 3. (1,1): left (0,1) uncovered, right (2,1) other tile, up
        // (1,0) uncovered, down (1,2) covered -> offset 3 -> heir 4. (2,0): right (3,0)
        // covered, same tile -> heir 2. (2,1): corner (3,0) -> offset 5 -> heir 6. (2,2)
        // and (3,1): only tile 0's or no covered texels of tile 1 at an edge or corner
        // but (3,0) for (3,1): up -> heir 3; (2,2): corner (3,1) uncovered, none -> 0.
        assert_eq!(heirs, vec![0, 1, 2, 0, 3, 4, 6, 3, 0, 0, 0, 0]);
        for (i, t) in edge.iter().enumerate() {
            assert_eq!(edge_texel_is_receiver(t), texels[i][0] == one, "texel {i}");
        }
        // the covered texel (0,0) inherits (1,0) and (0,1); (1,2) inherits (1,1)
        let flux = |i: i32| [i as f32 + 1.0, 0.0, 0.0];
        assert_eq!(inherited_flux(&edge, 4, 3, 0, 0, flux)[0], 1.0 + 2.0 + 5.0);
        assert_eq!(inherited_flux(&edge, 4, 3, 1, 2, flux)[0], 10.0 + 6.0);
        assert_eq!(
            inherited_flux(&edge, 4, 3, 3, 0, flux)[0],
            4.0 + 3.0 + 7.0 + 8.0
        );
        // Sspm's screen: no non-receiver pixel has an heir
        assert_eq!(edge_texel_heir(&edge_texel(false, 1.0, [0.0, 0.0, 1.0])), 0);
    }

    #[test]
    fn atlas_edge_texels_keep_the_gather_inside_a_tile() {
        let w = |a: [f32; 4], b: [f32; 4]| {
            edge_weight(
                a[0],
                [a[1], a[2], a[3]],
                b[0],
                [b[1], b[2], b[3]],
                ATLAS_SIGMA_DEPTH,
                0.0,
            )
        };
        let last = ATLAS_MAX_TILES - 1;
        for (t, u) in [(0, 1), (1, 0), (7, 8), (last - 1, last)] {
            let (a, b) = (atlas_edge_texel(t, 1e-6), atlas_edge_texel(u, 4.0));
            assert!(edge_texel_is_receiver(&a) && edge_texel_is_receiver(&b));
            assert_eq!(w(a, b), 0.0, "tiles {t} and {u}");
            assert_eq!(w(a, atlas_edge_texel(t, 3.0)), 1.0, "tile {t}");
        }
        // uncovered texels, texels outside every tile, too many tiles: not receivers
        for (t, area) in [(0, 0.0), (u32::MAX, 1.0), (ATLAS_MAX_TILES, 1.0)] {
            assert!(!edge_texel_is_receiver(&atlas_edge_texel(t, area)));
        }
    }

    #[test]
    fn the_column_pass_takes_every_pixel_once() {
        for (w, h) in [(1, 1), (8, 8), (9, 7), (33, 17), (64, 3)] {
            let mut seen = vec![0u32; (w * h) as usize];
            for t in 0..column_pass_threads(w, h) {
                if let Some((x, y)) = column_pass_pixel(t, w, h) {
                    seen[(y * w + x) as usize] += 1;
                }
            }
            assert!(seen.iter().all(|&n| n == 1), "{w}x{h}: {seen:?}");
        }
    }

    /// The blocked table of `counts` (`block x block` blocks).
    fn table_of(counts: &[u32], w: usize, block: usize) -> Vec<u32> {
        let h = counts.len() / w;
        let mut t = counts.to_vec();
        for y in 0..h {
            for x in 0..w {
                if x % block != 0 {
                    t[y * w + x] = t[y * w + x].wrapping_add(t[y * w + x - 1]);
                }
            }
        }
        for y in 0..h {
            for x in 0..w {
                if y % block != 0 {
                    t[y * w + x] = t[y * w + x].wrapping_add(t[(y - 1) * w + x]);
                }
            }
        }
        t
    }

    #[test]
    fn windows_count_exactly_and_clip_at_the_border() {
        let (w, h) = (13usize, 11usize);
        let counts: Vec<u32> = (0..w * h).map(|i| (i as u32 * 7) % 5).collect();
        // blocks of 4 (windows up to 2 blocks wide) and one block over the whole image
        for block in [4usize, 64] {
            let t = table_of(&counts, w, block);
            for y in 0..h as i32 {
                for x in 0..w as i32 {
                    for half in 0..=1 + (block as i32 > 4) as i32 * 3 {
                        let mut want = (0, 0);
                        for yy in (y - half).max(0)..=(y + half).min(h as i32 - 1) {
                            for xx in (x - half).max(0)..=(x + half).min(w as i32 - 1) {
                                want.0 += counts[yy as usize * w + xx as usize];
                                want.1 += 1;
                            }
                        }
                        let got = window_photons(&t, w as i32, h as i32, block as i32, x, y, half);
                        assert_eq!(got, want, "block {block} ({x}, {y}) half {half}");
                    }
                }
            }
        }
    }

    #[test]
    fn blocks_hold_the_widest_window() {
        for r in [0u32, 1, 16, 31, 32, 256] {
            let b = table_block(r);
            assert!(b.is_power_of_two() && b >= 64 && b > 2 * r, "{r}: {b}");
        }
    }

    #[test]
    fn a_focused_pixel_is_not_blurred_a_sparse_one_is() {
        let k = 16;
        let mut counts = vec![0u32; 25];
        // 9 k photons in one pixel fill its 3x3 window at the identity's density
        counts[12] = clamped_photon_count(1000, 0, k);
        let t = table_of(&counts, 5, 64);
        let r = footprint_radius(&t, 5, 5, 64, 2, 2, k, 16);
        assert_eq!(r, 0.5);
        assert_eq!(footprint_weight(1, r), 0.0);
        assert!((footprint_weight(0, r) - 1.0).abs() < 1e-6);
        // k photons alone in a pixel: 16 photons over 9 pixels, support half-width 1.5
        counts[12] = clamped_photon_count(16, 0, k);
        let t = table_of(&counts, 5, 64);
        assert_eq!(footprint_radius(&t, 5, 5, 64, 2, 2, k, 16), 1.5);
        // at the corner the window is clipped to 2x2: 4 k photons suffice
        let mut counts = vec![0u32; 25];
        counts[0] = clamped_photon_count(64, 0, k);
        let t = table_of(&counts, 5, 64);
        assert_eq!(footprint_radius(&t, 5, 5, 64, 0, 0, k, 16), 0.5);
    }

    #[test]
    fn radius_grows_as_photons_thin_out() {
        // one photon per pixel everywhere: k = 16 photons fill a 4x4 square, half-width 2
        let (w, h) = (64usize, 64usize);
        let t = table_of(&vec![1u32; w * h], w, 64);
        let r = footprint_radius(&t, w as i32, h as i32, 64, 32, 32, 16, 16);
        // smallest window with >= 16 photons: half-width 2 (25 pixels, 25 photons)
        assert!((r - 2.0).abs() < 1e-6, "{r}");
        // a quarter of the density doubles the radius
        let sparse: Vec<u32> = (0..w * h)
            .map(|i| u32::from((i % w) % 2 == 0 && (i / w) % 2 == 0))
            .collect();
        let t = table_of(&sparse, w, 64);
        let r2 = footprint_radius(&t, w as i32, h as i32, 64, 32, 32, 16, 16);
        assert!(r2 > 3.5 && r2 < 4.5, "{r2}");
        // nothing near: the cap
        let t = table_of(&vec![0u32; w * h], w, 64);
        assert_eq!(
            footprint_radius(&t, w as i32, h as i32, 64, 3, 3, 16, 12),
            12.0
        );
    }

    #[test]
    fn pixel_weights_sum_to_one_and_grow_smoothly() {
        for r in [0.3f32, 0.5, 0.75, 1.0, 2.5, 7.9, 16.0] {
            let sum: f32 = (-17..=17).map(|d| footprint_weight(d, r)).sum();
            assert!((sum - 1.0).abs() < 1e-5, "r {r}: {sum}");
            assert!((-17..=17).all(|d| (0.0..=1.0 + 1e-6).contains(&footprint_weight(d, r))));
        }
        // the neighbours' share starts at 0 and grows as (r - 1/2)^2
        assert_eq!(footprint_weight(1, 0.5), 0.0);
        let (a, b) = (footprint_weight(1, 0.51), footprint_weight(1, 0.52));
        assert!(a > 0.0 && b / a > 3.0 && b / a < 5.0, "{a} {b}");
        assert_eq!(footprint_weight(0, 0.0), 1.0);
        assert_eq!(footprint_weight(1, 0.0), 0.0);
    }

    #[test]
    fn edge_weight_is_symmetric_and_one_on_a_plane() {
        let n = [0.0, 1.0, 0.0];
        assert_eq!(edge_weight(2.0, n, 2.0, n, 0.02, 8.0), 1.0);
        let m = [0.6, 0.8, 0.0];
        assert_eq!(
            edge_weight(2.0, n, 2.1, m, 0.02, 8.0),
            edge_weight(2.1, m, 2.0, n, 0.02, 8.0)
        );
        assert_eq!(edge_weight(2.0, n, 2.0, [0.0, -1.0, 0.0], 0.02, 8.0), 0.0);
    }

    #[test]
    fn clamped_counts_saturate_at_9k() {
        assert_eq!(clamped_photon_count(3, 0, 16), 3);
        assert_eq!(clamped_photon_count(300, 0, 16), 144);
        assert_eq!(clamped_photon_count(0, 1, 16), 144);
    }
}

// Mirror of core/src/math/density_gather.rs (method and sources there): the scalar
// functions of the density-adaptive, scatter-normalised caustic gather.

// Per-pixel photon count as the summed-area table holds it: min(count, 9 k).
inline uint clamped_photon_count(uint lo, uint hi, uint k) {
    uint clamp = COUNT_CLAMP_PER_K * k;
    return hi != 0u ? clamp : min(lo, clamp);
}

// The blocked summed-area table's entry at (x, y), 0 left of or above the block whose
// corner is (bx0, by0).
inline uint table_entry(__global const uint* table, int width, int bx0, int by0, int x,
                        int y) {
    return (x < bx0 || y < by0) ? 0u : table[y * width + x];
}

// Photons in the rectangle [x0, x1] x [y0, y1] inside the image: the parts it covers in
// each block it overlaps, four reads each. Wrapping uint sums, exact (see the CPU doc).
// `block` is a power of two: block indices are shifts of the (non-negative) coordinates.
inline uint rect_photons(__global const uint* table, int w, int block, int x0, int y0,
                         int x1, int y1) {
    int shift = 31 - (int)clz((uint)block);
    uint count = 0u;
    for (int by = y0 >> shift; by <= y1 >> shift; by++) {
        for (int bx = x0 >> shift; bx <= x1 >> shift; bx++) {
            int bx0 = bx * block, by0 = by * block;
            int xa = max(x0, bx0), xb = min(x1, bx0 + block - 1);
            int ya = max(y0, by0), yb = min(y1, by0 + block - 1);
            count = count + table_entry(table, w, bx0, by0, xb, yb) -
                    table_entry(table, w, bx0, by0, xa - 1, yb) -
                    table_entry(table, w, bx0, by0, xb, ya - 1) +
                    table_entry(table, w, bx0, by0, xa - 1, ya - 1);
        }
    }
    return count;
}

// Photons in the window of half-width `half_width` around (x, y), clipped to the image
// (.x), and the window's pixel count (.y).
inline uint2 window_photons(__global const uint* table, int w, int h, int block, int x,
                            int y, int half_width) {
    int x0 = max(x - half_width, 0), y0 = max(y - half_width, 0);
    int x1 = min(x + half_width, w - 1), y1 = min(y + half_width, h - 1);
    return (uint2)(rect_photons(table, w, block, x0, y0, x1, y1),
                   (uint)((x1 - x0 + 1) * (y1 - y0 + 1)));
}

// k-NN radius (pixels): the support half-width 0.5 sqrt(k a / c).
inline float knn_radius(uint k, uint pixels, uint photons) {
    return 0.5f * sqrt((float)k * (float)pixels / (float)photons);
}

// The gather radius (pixels) at (x, y): smallest window holding k photons, capped.
inline float footprint_radius(__global const uint* table, int w, int h, int block, int x,
                              int y, uint k, uint max_radius_px) {
    int max_radius = max((int)max_radius_px, MIN_WINDOW_HALF_WIDTH);
    // (count, pixels) of the window at hi, the smallest half-width known to hold k
    uint2 at_hi = window_photons(table, w, h, block, x, y, max_radius);
    if (at_hi.x < k) return (float)max_radius;
    int lo = MIN_WINDOW_HALF_WIDTH, hi = max_radius;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        uint2 c = window_photons(table, w, h, block, x, y, mid);
        if (c.x >= k) {
            hi = mid;
            at_hi = c;
        } else {
            lo = mid + 1;
        }
    }
    return fmin(knn_radius(k, at_hi.y, at_hi.x), (float)max_radius);
}

// Pixel-integrated 1-D Epanechnikov weight (unit integral): (3/4) (G(u_b) - G(u_a)),
// G(u) = u - u^3 / 3 over the pixel [offset - 1/2, offset + 1/2] / radius clipped to
// [-1, 1]; 0 outside the support, 1 for offset 0 of a zero support.
inline float footprint_weight(int offset, float radius) {
    float d = (float)offset;
    if (!(fabs(d) < radius + 0.5f)) return 0.0f;
    if (!(radius > 0.0f)) return 1.0f;
    float ua = fmax((d - 0.5f) / radius, -1.0f);
    float ub = fmin((d + 0.5f) / radius, 1.0f);
    return 0.75f * ((ub - ub * ub * ub / 3.0f) - (ua - ua * ua * ua / 3.0f));
}

// Edge weight between two receiver pixels (symmetric): depth and normal terms.
inline float edge_weight(float depth_a, float3 normal_a, float depth_b, float3 normal_b,
                         float sigma_depth, float normal_power) {
    float wd = exp(-fabs(depth_a - depth_b) / (sigma_depth * fmin(depth_a, depth_b)));
    if (normal_power > 0.0f) {
        float c = normal_a.x * normal_b.x + normal_a.y * normal_b.y + normal_a.z * normal_b.z;
        // powr: pow for a non-negative base (same 16-ulp bound, no negative-base paths)
        return wd * powr(fmax(c, 0.0f), normal_power);
    }
    return wd;
}

// hi * 2^32 + lo in f32 from the exact split (core's join_u64_wide).
inline float join_u64_wide_f32(uint lo, uint hi) {
    return (float)hi * 4294967296.0f + (float)lo;
}

// The G-buffer planes a gather reads of its neighbours: 0 (depth), 1 (normal), 3 (flags).
#define GATHER_GBUFFER_PARAMS(q) q uint4* gbuffer0, q uint4* gbuffer1, q uint4* gbuffer3
#define GATHER_GBUFFER_ARGS gbuffer0, gbuffer1, gbuffer3

// What the gather needs of a G-buffer texel: receiver flag, view depth, normal (planes
// 0, 1 and 3 only: the gather reads many neighbours).
typedef struct {
    uint receiver;
    float depth;
    float3 normal;
} GatherTexel;

inline GatherTexel load_gather_texel(GATHER_GBUFFER_PARAMS(__global const), uint i) {
    GatherTexel t;
    t.receiver = gbuffer3[i].w & GBUFFER_RECEIVER;
    t.depth = as_float(gbuffer0[i].w);
    uint4 n = gbuffer1[i];
    t.normal = (float3)(as_float(n.x), as_float(n.y), as_float(n.z));
    return t;
}

// A pixel's edge texel: (view depth, normal) of a receiver, the G-buffer's bits; depth
// EDGE_TEXEL_NOT_RECEIVER elsewhere.
inline float4 edge_texel(GatherTexel t) {
    return t.receiver != 0u ? (float4)(t.depth, t.normal)
                            : (float4)(EDGE_TEXEL_NOT_RECEIVER, 0.0f, 0.0f, 0.0f);
}

inline bool edge_texel_is_receiver(float4 t) { return t.x >= 0.0f; }

// core::math::density_gather::HEIR_OFFSETS: an uncovered atlas texel's neighbours in the
// order its heir was chosen.
__constant int2 HEIR_OFFSETS[8] = {(int2)(-1, 0),  (int2)(1, 0),  (int2)(0, -1), (int2)(0, 1),
                                   (int2)(-1, -1), (int2)(1, -1), (int2)(-1, 1), (int2)(1, 1)};

// core's edge_texel_heir: 1..8 for an uncovered texel whose flux goes to its neighbour at
// HEIR_OFFSETS[heir - 1], 0 for none.
inline uint edge_texel_heir(float4 t) {
    if (edge_texel_is_receiver(t) || !(t.y >= 1.0f && t.y <= 8.0f)) return 0u;
    return (uint)t.y;
}

// Edge weight between two edge texels.
inline float edge_weight_of(__global const GatherParams* p, float4 a, float4 b) {
    return edge_weight(a.x, a.yzw, b.x, b.yzw, p->sigma_depth, p->normal_power);
}

// Normaliser of a source at pixel (x, y) with radius r: the sum of its weights over the
// receivers of its row (axis 0) or column (1) inside the image.
inline float gather_normaliser(__global const GatherParams* p, __global const float4* edge,
                               int x, int y, float r, uint axis) {
    int w = (int)p->camera.width, h = (int)p->camera.height;
    float4 ei = edge[y * w + x];
    // taps beyond the radius weigh 0: the loop stops there
    int reach = min((int)ceil(r + 0.5f), (int)p->max_radius_px);
    float sum = 0.0f;
    for (int d = -reach; d <= reach; d++) {
        int qx = axis == 0u ? x + d : x;
        int qy = axis == 0u ? y : y + d;
        if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
        float4 eq = edge[qy * w + qx];
        if (!edge_texel_is_receiver(eq)) continue;
        sum += footprint_weight(d, r) * edge_weight_of(p, ei, eq);
    }
    return sum;
}

// The pixel thread t of density_gather's column pass takes: 8 x 8 tiles, 64 threads
// each (core's column_pass_pixel); false for the padding of edge tiles.
inline bool column_pass_pixel(uint t, uint w, uint h, int* x, int* y) {
    uint tile = t / (COLUMN_PASS_TILE * COLUMN_PASS_TILE);
    uint l = t % (COLUMN_PASS_TILE * COLUMN_PASS_TILE);
    uint tiles_x = (w + COLUMN_PASS_TILE - 1u) / COLUMN_PASS_TILE;
    uint px = (tile % tiles_x) * COLUMN_PASS_TILE + l % COLUMN_PASS_TILE;
    uint py = (tile / tiles_x) * COLUMN_PASS_TILE + l / COLUMN_PASS_TILE;
    *x = (int)px;
    *y = (int)py;
    return px < w && py < h;
}

// The density gather's source index (core's footprint_reach, reach_grid_index,
// reach_grid_entry, pass_reach, source_mask_word, source_bits, accumulate_source_index):
// per REACH_TILE x REACH_TILE tile and pass the maximum footprint_reach + 1 of its
// sources (the row pass's grid, then the column pass's), then per pass a bit per pixel
// (the row pass's mask by image rows, the column pass's by columns).

// The largest |offset| at which footprint_weight(offset, radius) can be nonzero, capped
// at `cap`; -1 where none.
inline int footprint_reach(float radius, int cap) {
    float s = radius + 0.5f;
    if (!(s > 0.0f)) return -1;
    return (int)fmin(ceil(s), (float)cap + 1.0f) - 1;
}

// Entries of the two reach grids of a w x h image.
inline int reach_grid_len(int w, int h) {
    return 2 * ((w + REACH_TILE - 1) / REACH_TILE) * ((h + REACH_TILE - 1) / REACH_TILE);
}

// Index of the tile holding (x, y) in pass `axis`'s grid of a w x h image.
inline uint reach_grid_index(int w, int h, uint axis, int x, int y) {
    int tx = (w + REACH_TILE - 1) / REACH_TILE;
    int ty = (h + REACH_TILE - 1) / REACH_TILE;
    return (uint)((int)axis * tx * ty + (y / REACH_TILE) * tx + x / REACH_TILE);
}

// Index of word k of pass `axis`'s mask line through (x, y) (row y for axis 0, column x
// for axis 1).
inline uint source_mask_word(int w, int h, uint axis, int x, int y, int k) {
    int base = reach_grid_len(w, h);
    if (axis == 0u) return (uint)(base + y * ((w + 31) / 32) + k);
    return (uint)(base + h * ((w + 31) / 32) + x * ((h + 31) / 32) + k);
}

// Word k of the mask line through (x, y), its bits outside [lo, hi] cleared.
inline uint source_bits(__global const uint* index, int w, int h, uint axis, int x, int y,
                        int k, int lo, int hi) {
    uint bits = index[source_mask_word(w, h, axis, x, y, k)];
    if (k == lo / 32) bits &= 0xffffffffu << (uint)(lo % 32);
    if (k == hi / 32) bits &= 0xffffffffu >> (uint)(31 - hi % 32);
    return bits;
}

// Index of the lowest set bit of a nonzero word (OpenCL C 1.2 has clz, not ctz).
inline int lowest_bit(uint bits) { return 31 - (int)clz(bits & (0u - bits)); }

// A source's entry: footprint_reach + 1, 0 for a pixel without flux.
inline uint reach_grid_entry(float4 source, int cap) {
    if (source.x == 0.0f && source.y == 0.0f && source.z == 0.0f) return 0u;
    return (uint)(footprint_reach(source.w, cap) + 1);
}

// Enters a source pixel into pass `axis`'s part of the index: its reach into its tile
// (atomic maximum), its mask bit (atomic or).
inline void put_source(__global uint* index, int w, int h, uint axis, int x, int y,
                       float4 source, int cap) {
    uint e = reach_grid_entry(source, cap);
    if (e > 0u) {
        atomic_max(&index[reach_grid_index(w, h, axis, x, y)], e);
        int along = axis == 0u ? x : y;
        atomic_or(&index[source_mask_word(w, h, axis, x, y, along / 32)],
                  1u << (uint)(along % 32));
    }
}

// Half-width of the taps destination (x, y) of pass `axis` visits: the largest reach
// among the tiles of its row (column) within `cap` whose entry covers the distance to the
// tile's nearest pixel; -1 where no source reaches it.
inline int pass_reach(__global const uint* index, int w, int h, int x, int y, uint axis,
                      int cap) {
    int along = axis == 0u ? x : y;
    int len = axis == 0u ? w : h;
    int t0 = max(along - cap, 0) / REACH_TILE;
    int t1 = min(along + cap, len - 1) / REACH_TILE;
    int r = -1;
    for (int k = t0; k <= t1; k++) {
        int tx = axis == 0u ? k : x / REACH_TILE;
        int ty = axis == 0u ? y / REACH_TILE : k;
        int g = (int)index[reach_grid_index(w, h, axis, tx * REACH_TILE, ty * REACH_TILE)] - 1;
        // distance from `along` to the tile's nearest pixel
        int dist = max(max(k * REACH_TILE - along, along - (k * REACH_TILE + REACH_TILE - 1)), 0);
        if (g >= dist) r = max(r, g);
    }
    return min(r, cap);
}

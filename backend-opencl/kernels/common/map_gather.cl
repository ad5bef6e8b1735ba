// Mirror of core::math::map_gather (the caustic atlas, Vanderstichelen 2021): texel addressing, the
// flux-keeping N x N gather and the lookup over a pixel's footprint.

inline uint atlas_texel_index(uint4 tile, float2 uv, uint atlas_width) {
    float s = (float)tile.z;
    uint cx = min((uint)fmax(floor(uv.x * s), 0.0f), tile.z - 1u);
    uint cy = min((uint)fmax(floor(uv.y * s), 0.0f), tile.z - 1u);
    return (tile.y + cy) * atlas_width + tile.x + cx;
}

// math::map_gather::centroid_offset along one axis: a photon's offset inside its texel
// (the tile's `side` texels) in 1/CENTROID_SUBTEXELS of a texel, 0..=255; products by
// powers of two and a floor only, so that every backend computes the same integers.
inline uint centroid_offset_axis(float u, uint side) {
    float s = (float)side;
    uint c = min((uint)fmax(floor(u * s), 0.0f), side - 1u);
    uint steps = (uint)fmax(floor(u * s * (float)CENTROID_SUBTEXELS), 0.0f);
    uint base = c * CENTROID_SUBTEXELS;
    return min(steps >= base ? steps - base : 0u, CENTROID_SUBTEXELS - 1u);
}

// math::map_gather::centroid_offset: both axes, on tile `tile`.
inline uint2 centroid_offset(uint4 tile, float2 uv) {
    return (uint2)(centroid_offset_axis(uv.x, tile.z), centroid_offset_axis(uv.y, tile.z));
}

// backend-cpu atlas_deposit.rs::add_centroid: a photon at `offsets` inside atlas texel
// `texel` added to its centroid sums (x offsets, y offsets, photons); the add that takes
// the texel to CENTROID_MAX_PHOTONS photons counted saturated in `lc`.
inline void add_centroid(volatile __global uint* centroids, __local uint* lc, uint texel,
                         uint2 offsets) {
    uint i = texel * CENTROID_WORDS;
    atomic_add(&centroids[i], offsets.x);
    atomic_add(&centroids[i + 1u], offsets.y);
    if (atomic_inc(&centroids[i + 2u]) == CENTROID_MAX_PHOTONS - 1u)
        atomic_inc(&lc[COUNTER_SATURATED]);
}

// core::math::map_gather::texel_centroid: the mean position (texel-local) of a texel's
// photons from its centroid sums; the texel's middle without photons or past
// CENTROID_MAX_PHOTONS.
inline float2 texel_centroid(uint sx, uint sy, uint n) {
    if (n == 0u || n >= CENTROID_MAX_PHOTONS) return (float2)(0.5f);
    float nf = (float)n;
    float d = (float)(n * CENTROID_SUBTEXELS);
    return (float2)(((float)sx + 0.5f * nf) / d, ((float)sy + 0.5f * nf) / d);
}

// core::math::map_gather::centroid_share: the share of a texel's flux inside [lo, hi)
// (texel-local) when it lies uniformly on [c - a, c + a], a = min(c, 1 - c).
inline float centroid_share(float c, float lo, float hi) {
    float a = fmax(fmin(c, 1.0f - c), 0.5f / (float)CENTROID_SUBTEXELS);
    return fmin(fmax(fmin(hi, c + a) - fmax(lo, c - a), 0.0f) / (2.0f * a), 1.0f);
}

// math::map_gather::triangle_reach_bit: (word, bit) of scene triangle t in a reach mask
inline uint2 triangle_reach_bit(uint t) { return (uint2)(t >> 5, 1u << (t & 31u)); }

// The caustic atlas a texture-space photon is deposited into (the FUSED_DEPOSIT variant
// of trace_photons).
#define ATLAS_DEPOSIT_PARAMS                                                                  \
    __global const AtlasParams *ap, __global const uint *triangle_tiles,                    \
        __global const uint4 *tiles, volatile __global uint *triangle_reach,                \
        PHOTON_MAP_PARAMS(volatile __global)
#define ATLAS_DEPOSIT_ARGS ap, triangle_tiles, tiles, triangle_reach, PHOTON_MAP_ARGS

// One texture-space photon (uv, triangle) into the atlas (backend-cpu caustic_map.rs
// deposit_atlas and mark_triangle_reach): its triangle's reach bit, then its flux, hit
// distance and a count in fixed point on the texel under its uv on its triangle's tile and
// its offset inside the texel on the texel's centroid sums, or OFF_SCREEN counted in the
// work-group's `lc` when the triangle has no tile.
inline void deposit_atlas_photon(ATLAS_DEPOSIT_PARAMS, volatile __global uint* centroids,
                                 __local uint* lc, const Photon* ph) {
    uint2 reach = triangle_reach_bit(ph->direction);
    // most photons land on a few triangles: a load first, so that a bit already set costs
    // no atomic on the hot word
    if ((triangle_reach[reach.x] & reach.y) == 0u) atomic_or(&triangle_reach[reach.x], reach.y);
    uint tile = triangle_tiles[ph->direction];
    if (tile == NO_TILE) {
        atomic_inc(&lc[COUNTER_OFF_SCREEN]);
    } else {
        uint texel = atlas_texel_index(tiles[tile], (float2)(ph->position[0], ph->position[1]),
                                       ap->width);
        deposit_photon_texel(PHOTON_MAP_ARGS, lc, texel, ph, ap->flux_quantum,
                             ap->hit_distance_quantum);
        add_centroid(centroids, lc, texel,
                     centroid_offset(tiles[tile], (float2)(ph->position[0], ph->position[1])));
    }
}

inline float join_u64_f32(uint lo, uint hi) { return (float)hi * 4294967296.0f + (float)lo; }

// (first column, last column, first row, last row), inclusive.
inline uint4 tile_window(uint4 tile, uint x, uint y, uint n) {
    uint h = n / 2u;
    return (uint4)(max(x >= h ? x - h : 0u, tile.x), min(x + h, tile.x + tile.z - 1u),
                   max(y >= h ? y - h : 0u, tile.y), min(y + h, tile.y + tile.z - 1u));
}

inline float atlas_area(__global const uint2* texels, uint i) { return as_float(texels[i].x); }

// Texel i's flux (words 0-5 of its DepositTexel: planes.cl's deposit_word puts words 0-3
// at plane 0's uint4 i and words 4-5 at plane 1's uint2 2i), read as one 16- and one
// 8-byte load: the gather's nine taps a texel made six 4-byte loads each (0.158 against
// 0.134 ms at Vanderstichelen 2021's setting 0 on the H200).
inline float3 atlas_flux(PHOTON_MAP_PARAMS(__global const), uint i, float q) {
    uint4 rg = ((__global const uint4*)photon_map0)[i];
    uint2 b = ((__global const uint2*)photon_map1)[2u * i];
    return (float3)(join_u64_f32(rg.x, rg.y) * q, join_u64_f32(rg.z, rg.w) * q,
                    join_u64_f32(b.x, b.y) * q);
}

// core::math::map_gather::window_coverage: the covered texels of source (qx, qy)'s window.
inline uint window_coverage(__global const uint2* texels, uint4 tile, uint qx, uint qy, uint n,
                            uint atlas_width) {
    uint4 cw = tile_window(tile, qx, qy, n);
    if ((tile.w & TILE_FULLY_COVERED) != 0u) return (cw.y - cw.x + 1u) * (cw.w - cw.z + 1u);
    uint c = 0u;
    for (uint sy = cw.z; sy <= cw.w; sy++)
        for (uint sx = cw.x; sx <= cw.y; sx++)
            c += atlas_area(texels, sy * atlas_width + sx) > 0.0f ? 1u : 0u;
    return c;
}

inline float3 gather_caustic_texel(__global const uint2* texels, PHOTON_MAP_PARAMS(__global const),
                                   float quantum, uint4 tile, uint x, uint y, uint n,
                                   uint atlas_width) {
    uint t = y * atlas_width + x;
    float area_t = atlas_area(texels, t);
    if (!(area_t > 0.0f)) return (float3)(0.0f);
    uint4 win = tile_window(tile, x, y, n);
    float3 sum = (float3)(0.0f);
    for (uint qy = win.z; qy <= win.w; qy++) {
        for (uint qx = win.x; qx <= win.y; qx++) {
            uint q = qy * atlas_width + qx;
            float3 f = atlas_flux(PHOTON_MAP_ARGS, q, quantum);
            if (f.x == 0.0f && f.y == 0.0f && f.z == 0.0f) continue;
            uint c = window_coverage(texels, tile, qx, qy, n, atlas_width);
            if (c == 0u) {
                if (q == t) sum += f;
            } else {
                sum += f / (float)c;
            }
        }
    }
    return sum / area_t;
}

inline float footprint_texels(float pixel_angle, float distance, float cos_in, float texel_area) {
    float w = pixel_angle * distance;
    float area = w * w / fmax(fabs(cos_in), 1e-3f);
    return texel_area > 0.0f ? sqrt(area / texel_area) : 0.0f;
}

// A world vector in the triangle's plane in the tile's texels (footprint_extent's map).
inline float2 footprint_to_texels(float3 v, float3 e1, float3 e2, float g11, float g12, float g22,
                                  float det, float2 d1, float2 d2, uint side) {
    float x1 = dot3(e1, v);
    float x2 = dot3(e2, v);
    float alpha = (g22 * x1 - g12 * x2) / det;
    float beta = (g11 * x2 - g12 * x1) / det;
    return (d1 * alpha + d2 * beta) * (float)side;
}

// core::math::map_gather::footprint_extent: half-extents (texels) of the rectangle that
// bounds a pixel's footprint on a triangle (world corners p0..p2, UV corners t0..t2) of a
// tile `side` texels wide; (-1, -1) without a UV Jacobian.
inline float2 footprint_extent(float3 dir, float3 right, float width, float3 p0, float3 p1,
                               float3 p2, float2 t0, float2 t1, float2 t2, uint side) {
    float3 e1 = p1 - p0;
    float3 e2 = p2 - p0;
    float g11 = dot3(e1, e1);
    float g12 = dot3(e1, e2);
    float g22 = dot3(e2, e2);
    float det = g11 * g22 - g12 * g12;
    float2 d1 = t1 - t0;
    float2 d2 = t2 - t0;
    float3 nc = cross3(e1, e2);
    float n_len = length3(nc);
    if (!(det > 0.0f && n_len > 0.0f) || d1.x * d2.y - d1.y * d2.x == 0.0f)
        return (float2)(-1.0f);
    float3 n = nc / n_len;
    float3 a = right - dir * dot3(right, dir);
    if (!(dot3(a, a) > 1e-12f)) {
        a = (float3)(1.0f, 0.0f, 0.0f) - dir * dir.x;
        if (!(dot3(a, a) > 1e-12f)) a = (float3)(0.0f, 1.0f, 0.0f) - dir * dir.y;
    }
    a = a * (1.0f / sqrt(dot3(a, a)));
    float3 b = cross3(dir, a);
    float c = dot3(dir, n);
    if (fabs(c) < 1e-3f) c = copysign(1e-3f, c);
    float3 va = width * (a - dir * (dot3(n, a) / c));
    float3 vb = width * (b - dir * (dot3(n, b) / c));
    float2 ta = footprint_to_texels(va, e1, e2, g11, g12, g22, det, d1, d2, side);
    float2 tb = footprint_to_texels(vb, e1, e2, g11, g12, g22, det, d1, d2, side);
    return 0.5f * (fabs(ta) + fabs(tb));
}

// One texel's share [i, i + 1) ∩ [lo, hi) of an interval (texels).
inline float texel_overlap(uint i, float lo, float hi) {
    return fmax(fmin((float)i + 1.0f, hi) - fmax((float)i, lo), 0.0f);
}

inline float3 sample_caustic_map(__global const uint2* texels, __global const float4* map,
                                 __global const uint* centroids, uint4 tile, float2 uv,
                                 float2 extent, uint atlas_width) {
    float s = (float)tile.z;
    if (extent.x > 0.5f || extent.y > 0.5f) {
        float hx = clampf(extent.x, 0.5f, 0.5f * MAX_FOOTPRINT_TEXELS);
        float hy = clampf(extent.y, 0.5f, 0.5f * MAX_FOOTPRINT_TEXELS);
        float cx = clampf(uv.x * s, 0.0f, s);
        float cy = clampf(uv.y * s, 0.0f, s);
        float lx = fmax(cx - hx, 0.0f), ux = fmin(cx + hx, s);
        float ly = fmax(cy - hy, 0.0f), uy = fmin(cy + hy, s);
        uint bx0 = (uint)floor(lx);
        uint bx1 = clamp((uint)ceil(ux), 1u, tile.z) - 1u;
        uint by0 = (uint)floor(ly);
        uint by1 = clamp((uint)ceil(uy), 1u, tile.z) - 1u;
        float3 bsum = (float3)(0.0f);
        float bw = 0.0f;
        for (uint y = by0; y <= by1; y++) {
            float wy = texel_overlap(y, ly, uy);
            for (uint x = bx0; x <= bx1; x++) {
                uint i = (tile.y + y) * atlas_width + tile.x + x;
                float w = texel_overlap(x, lx, ux) * wy;
                if (atlas_area(texels, i) > 0.0f && w > 0.0f) {
                    uint k = i * CENTROID_WORDS;
                    float2 c = texel_centroid(centroids[k], centroids[k + 1u], centroids[k + 2u]);
                    float share = centroid_share(c.x, lx - (float)x, ux - (float)x) *
                                  centroid_share(c.y, ly - (float)y, uy - (float)y);
                    bsum += share * map[i].xyz;
                    bw += w;
                }
            }
        }
        if (bw > 0.0f) return bsum / bw;
    }
    float fx = clamp(uv.x * s - 0.5f, 0.0f, s - 1.0f);
    float fy = clamp(uv.y * s - 0.5f, 0.0f, s - 1.0f);
    float x0 = floor(fx);
    float y0 = floor(fy);
    float wx = fx - x0;
    float wy = fy - y0;
    uint ix0 = (uint)x0;
    uint iy0 = (uint)y0;
    uint ix1 = min(ix0 + 1u, tile.z - 1u);
    uint iy1 = min(iy0 + 1u, tile.z - 1u);
    uint xs[4] = {ix0, ix1, ix0, ix1};
    uint ys[4] = {iy0, iy0, iy1, iy1};
    float ws[4] = {(1.0f - wx) * (1.0f - wy), wx * (1.0f - wy), (1.0f - wx) * wy, wx * wy};
    float3 sum = (float3)(0.0f);
    float wsum = 0.0f;
    for (uint k = 0u; k < 4u; k++) {
        uint i = (tile.y + ys[k]) * atlas_width + tile.x + xs[k];
        if (atlas_area(texels, i) > 0.0f && ws[k] > 0.0f) {
            sum += ws[k] * map[i].xyz;
            wsum += ws[k];
        }
    }
    return wsum > 0.0f ? sum / wsum : (float3)(0.0f);
}

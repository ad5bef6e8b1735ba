// Mirror of core::math::map_gather (the caustic atlas, seed 001): texel addressing, the
// flux-keeping N x N gather and the covered-bilinear lookup.

inline uint atlas_texel_index(uint4 tile, float2 uv, uint atlas_width) {
    float s = (float)tile.z;
    uint cx = min((uint)fmax(floor(uv.x * s), 0.0f), tile.z - 1u);
    uint cy = min((uint)fmax(floor(uv.y * s), 0.0f), tile.z - 1u);
    return (tile.y + cy) * atlas_width + tile.x + cx;
}

inline float join_u64_f32(uint lo, uint hi) { return (float)hi * 4294967296.0f + (float)lo; }

// (first column, last column, first row, last row), inclusive.
inline uint4 tile_window(uint4 tile, uint x, uint y, uint n) {
    uint h = n / 2u;
    return (uint4)(max(x >= h ? x - h : 0u, tile.x), min(x + h, tile.x + tile.z - 1u),
                   max(y >= h ? y - h : 0u, tile.y), min(y + h, tile.y + tile.z - 1u));
}

inline float atlas_area(__global const uint2* texels, uint i) { return as_float(texels[i].x); }

inline float3 atlas_flux(PHOTON_MAP_PARAMS(__global const), uint i, float q) {
    return (float3)(join_u64_f32(photon_map_word(PHOTON_MAP_ARGS, i, 0u),
                                 photon_map_word(PHOTON_MAP_ARGS, i, 1u)) * q,
                    join_u64_f32(photon_map_word(PHOTON_MAP_ARGS, i, 2u),
                                 photon_map_word(PHOTON_MAP_ARGS, i, 3u)) * q,
                    join_u64_f32(photon_map_word(PHOTON_MAP_ARGS, i, 4u),
                                 photon_map_word(PHOTON_MAP_ARGS, i, 5u)) * q);
}

inline float3 gather_caustic_texel(__global const uint2* texels, PHOTON_MAP_PARAMS(__global const),
                                   float quantum, uint4 tile, uint x, uint y, uint n,
                                   uint atlas_width) {
    uint t = y * atlas_width + x;
    float area_t = atlas_area(texels, t);
    uint4 win = tile_window(tile, x, y, n);
    float3 sum = (float3)(0.0f);
    for (uint qy = win.z; qy <= win.w; qy++) {
        for (uint qx = win.x; qx <= win.y; qx++) {
            uint q = qy * atlas_width + qx;
            float3 f = atlas_flux(PHOTON_MAP_ARGS, q, quantum);
            if (f.x == 0.0f && f.y == 0.0f && f.z == 0.0f) continue;
            uint4 cw = tile_window(tile, qx, qy, n);
            uint c = 0u;
            for (uint sy = cw.z; sy <= cw.w; sy++)
                for (uint sx = cw.x; sx <= cw.y; sx++)
                    c += atlas_area(texels, sy * atlas_width + sx) > 0.0f ? 1u : 0u;
            if (c == 0u) {
                if (q == t) sum += f;
            } else if (area_t > 0.0f) {
                sum += f / (float)c;
            }
        }
    }
    return area_t > 0.0f ? sum / area_t : (float3)(0.0f);
}

#define MAX_FOOTPRINT_TEXELS 32.0f

inline float footprint_texels(float pixel_angle, float distance, float cos_in, float texel_area) {
    float w = pixel_angle * distance;
    float area = w * w / fmax(fabs(cos_in), 1e-3f);
    return texel_area > 0.0f ? sqrt(area / texel_area) : 0.0f;
}

inline float3 sample_caustic_map(__global const uint2* texels, __global const float4* map,
                                 uint4 tile, float2 uv, float footprint, uint atlas_width) {
    float s = (float)tile.z;
    float fx = clamp(uv.x * s - 0.5f, 0.0f, s - 1.0f);
    float fy = clamp(uv.y * s - 0.5f, 0.0f, s - 1.0f);
    if (footprint > 1.0f) {
        float h = 0.5f * fmin(footprint, MAX_FOOTPRINT_TEXELS);
        uint bx0 = (uint)fmax(ceil(fx - h), 0.0f);
        uint bx1 = (uint)fmin(ceil(fx + h) - 1.0f, s - 1.0f);
        uint by0 = (uint)fmax(ceil(fy - h), 0.0f);
        uint by1 = (uint)fmin(ceil(fy + h) - 1.0f, s - 1.0f);
        float3 bsum = (float3)(0.0f);
        uint n = 0u;
        for (uint y = by0; y <= by1; y++) {
            for (uint x = bx0; x <= bx1; x++) {
                uint i = (tile.y + y) * atlas_width + tile.x + x;
                if (atlas_area(texels, i) > 0.0f) {
                    bsum += map[i].xyz;
                    n++;
                }
            }
        }
        if (n > 0u) return bsum / (float)n;
    }
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

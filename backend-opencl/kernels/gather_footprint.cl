// gather_footprint: per receiver pixel its k-NN gather radius and its flux over its row
// normaliser (core/src/math/density_gather.rs). Mirror of
// backend-cpu/src/kernels/gather_footprint.rs.

// A pixel's deposited flux (W per channel) from the photon map's fixed-point sums.
inline float3 pixel_flux(PHOTON_MAP_PARAMS(__global const), uint i, float quantum) {
    float3 f;
    f.x = join_u64_wide_f32(photon_map_word(PHOTON_MAP_ARGS, i, 0u),
                            photon_map_word(PHOTON_MAP_ARGS, i, 1u)) * quantum;
    f.y = join_u64_wide_f32(photon_map_word(PHOTON_MAP_ARGS, i, 2u),
                            photon_map_word(PHOTON_MAP_ARGS, i, 3u)) * quantum;
    f.z = join_u64_wide_f32(photon_map_word(PHOTON_MAP_ARGS, i, 4u),
                            photon_map_word(PHOTON_MAP_ARGS, i, 5u)) * quantum;
    return f;
}

__kernel void gather_footprint(__global const GatherParams* p,
                               PHOTON_MAP_PARAMS(__global const), __global const uint* table,
                               __global const float4* edge, __global float4* out,
                               __global uint* source_index) {
    int w = (int)p->camera.width, h = (int)p->camera.height;
    int i = (int)get_global_id(0);
    if (i >= w * h) return;
    if (!edge_texel_is_receiver(edge[i])) {
        out[i] = (float4)(0.0f);
        return;
    }
    int x = i % w, y = i / w;
    float r = footprint_radius(table, w, h, (int)p->table_block, x, y, p->knn_photons,
                               p->max_radius_px);
    float3 f = pixel_flux(PHOTON_MAP_ARGS, (uint)i, p->flux_quantum);
    if (p->surface == GATHER_SURFACE_ATLAS) {
        // core's inherited_flux: the flux of uncovered neighbours whose heir this texel is
        for (int k = 0; k < 8; k++) {
            int2 d = HEIR_OFFSETS[k];
            int nx = x + d.x, ny = y + d.y;
            if (nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
            int n = ny * w + nx;
            uint heir = edge_texel_heir(edge[n]);
            // the neighbour's heir is this texel: its offset is the opposite of d
            if (heir != 0u && all(HEIR_OFFSETS[heir - 1u] == -d))
                f += pixel_flux(PHOTON_MAP_ARGS, (uint)n, p->flux_quantum);
        }
    }
    if (f.x == 0.0f && f.y == 0.0f && f.z == 0.0f) {
        // no flux to spread: no normaliser to compute
        out[i] = (float4)(0.0f, 0.0f, 0.0f, r);
        return;
    }
    float inv = 1.0f / gather_normaliser(p, edge, x, y, r, 0u);
    float4 o = (float4)(f.x * inv, f.y * inv, f.z * inv, r);
    out[i] = o;
    // the row pass's sources: its loops visit only them
    put_source(source_index, w, h, 0u, x, y, o, (int)p->max_radius_px);
}

// gather_footprint: per receiver pixel its k-NN gather radius and its flux over its row
// normaliser (core/src/math/density_gather.rs). Mirror of
// backend-cpu/src/kernels/density_gather.rs.

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
    float3 f;
    f.x = join_u64_wide_f32(photon_map_word(PHOTON_MAP_ARGS, (uint)i, 0u),
                            photon_map_word(PHOTON_MAP_ARGS, (uint)i, 1u)) * p->flux_quantum;
    f.y = join_u64_wide_f32(photon_map_word(PHOTON_MAP_ARGS, (uint)i, 2u),
                            photon_map_word(PHOTON_MAP_ARGS, (uint)i, 3u)) * p->flux_quantum;
    f.z = join_u64_wide_f32(photon_map_word(PHOTON_MAP_ARGS, (uint)i, 4u),
                            photon_map_word(PHOTON_MAP_ARGS, (uint)i, 5u)) * p->flux_quantum;
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

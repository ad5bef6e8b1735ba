// photon_count_table: one direction of the blocked summed-area table of the photon
// counts clamped at 9 k (core/src/math/density_gather.rs). Mirror of
// backend-cpu/src/kernels/density_gather.rs. Axis 0: a thread per row and block; 1: a
// thread per column and block, in place. Wrapping uint sums: exact, the same bits on
// every backend. Axis 1 also writes every pixel's edge texel (on the screen; the atlas's
// come with its layout).

__kernel void photon_count_table(__global const GatherParams* p,
                                 PHOTON_MAP_PARAMS(__global const), __global uint* table,
                                 GATHER_GBUFFER_PARAMS(__global const), __global float4* edge) {
    uint w = p->camera.width, h = p->camera.height, b = p->table_block;
    uint t = get_global_id(0);
    if (p->axis == 0u) {
        // a thread per row and block: y = t / blocks, block = t % blocks
        uint blocks = (w + b - 1u) / b;
        if (t >= h * blocks) return;
        uint y = t / blocks, x0 = (t % blocks) * b;
        uint sum = 0u;
        for (uint x = x0; x < min(x0 + b, w); x++) {
            uint i = y * w + x;
            sum += clamped_photon_count(photon_map_word(PHOTON_MAP_ARGS, i, 8u),
                                        photon_map_word(PHOTON_MAP_ARGS, i, 9u),
                                        p->knn_photons);
            table[i] = sum;
        }
    } else {
        // a thread per pixel writes its edge texel; the first w x blocks also scan, a
        // thread per column and block: x = t % w (neighbouring threads, neighbouring
        // columns), block = t / w
        // (the atlas's edge texels come with its layout)
        if (t < w * h && p->surface != GATHER_SURFACE_ATLAS)
            edge[t] = edge_texel(load_gather_texel(GATHER_GBUFFER_ARGS, t));
        uint blocks = (h + b - 1u) / b;
        if (t >= w * blocks) return;
        uint x = t % w, y0 = (t / w) * b;
        uint sum = 0u;
        for (uint y = y0; y < min(y0 + b, h); y++) {
            sum += table[y * w + x];
            table[y * w + x] = sum;
        }
    }
}

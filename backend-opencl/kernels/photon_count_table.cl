// photon_count_table: one direction of the summed-area table of the photon counts
// clamped at 9 k (core/src/math/density_gather.rs). Mirror of
// backend-cpu/src/kernels/density_gather.rs. Axis 0: a thread per row; 1: a thread per
// column, in place. Wrapping uint sums: exact, the same bits on every backend.

__kernel void photon_count_table(__global const GatherParams* p,
                                 PHOTON_MAP_PARAMS(__global const), __global uint* table) {
    uint w = p->camera.width, h = p->camera.height;
    uint t = get_global_id(0);
    if (p->axis == 0u) {
        if (t >= h) return;
        uint sum = 0u;
        for (uint x = 0u; x < w; x++) {
            uint i = t * w + x;
            sum += clamped_photon_count(photon_map_word(PHOTON_MAP_ARGS, i, 8u),
                                        photon_map_word(PHOTON_MAP_ARGS, i, 9u),
                                        p->knn_photons);
            table[i] = sum;
        }
    } else {
        if (t >= w) return;
        uint sum = 0u;
        for (uint y = 0u; y < h; y++) {
            sum += table[y * w + t];
            table[y * w + t] = sum;
        }
    }
}

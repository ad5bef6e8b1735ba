// tile_hit_distance (Kim 2019, section 30.3.2): photon-weighted mean hit distance per
// tile_size^2 tile, 0 for empty tiles. Mirror of backend-cpu/src/kernels/tile_hit_distance.rs.

__kernel void tile_hit_distance(__global const GatherParams* p,
                                PHOTON_MAP_PARAMS(__global const), __global float* tiles) {
    uint w = p->camera.width, h = p->camera.height, ts = p->tile_size;
    uint tw = (w + ts - 1u) / ts, th = (h + ts - 1u) / ts;
    uint t = get_global_id(0);
    if (t >= tw * th) return;
    uint tx = t % tw, ty = t / tw;
    ulong sum = 0ul, n = 0ul;
    for (uint y = ty * ts; y < min((ty + 1u) * ts, h); y++) {
        for (uint x = tx * ts; x < min((tx + 1u) * ts, w); x++) {
            uint m = y * w + x;
            sum += (ulong)photon_map_word(PHOTON_MAP_ARGS, m, 6u) |
                   ((ulong)photon_map_word(PHOTON_MAP_ARGS, m, 7u) << 32);
            n += (ulong)photon_map_word(PHOTON_MAP_ARGS, m, 8u) |
                 ((ulong)photon_map_word(PHOTON_MAP_ARGS, m, 9u) << 32);
        }
    }
    if (n == 0ul) {
        tiles[t] = 0.0f;
        return;
    }
#ifdef cl_khr_fp64
    tiles[t] = (float)((double)sum * (double)p->hit_distance_quantum / (double)n);
#else
    tiles[t] = (float)sum * p->hit_distance_quantum / (float)n;
#endif
}

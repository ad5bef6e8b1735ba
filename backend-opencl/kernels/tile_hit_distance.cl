// tile_hit_distance (seed 000 section 30.3.2): photon-weighted mean hit distance per
// tile_size^2 tile, 0 for empty tiles. Mirror of backend-cpu/src/kernels/gather.rs.

__kernel void tile_hit_distance(__global const GatherParams* p, __global const uint* photon_map,
                                __global float* tiles) {
    uint w = p->camera.width, h = p->camera.height, ts = p->tile_size;
    uint tw = (w + ts - 1u) / ts, th = (h + ts - 1u) / ts;
    uint t = get_global_id(0);
    if (t >= tw * th) return;
    uint tx = t % tw, ty = t / tw;
    ulong sum = 0ul, n = 0ul;
    for (uint y = ty * ts; y < min((ty + 1u) * ts, h); y++) {
        for (uint x = tx * ts; x < min((tx + 1u) * ts, w); x++) {
            __global const uint* m = &photon_map[(y * w + x) * 10u];
            sum += (ulong)m[6] | ((ulong)m[7] << 32);
            n += (ulong)m[8] | ((ulong)m[9] << 32);
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

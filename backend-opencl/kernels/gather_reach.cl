// gather_reach: per tile_size^2 tile, the largest radius among its pixels whose input
// flux is non-zero, 0 if none (core/src/kernels/gather_reach.rs). Mirror of
// backend-cpu/src/kernels/density_gather.rs.

__kernel void gather_reach(__global const GatherParams* p, __global const float* radius,
                           __global const float4* input, __global float* tiles) {
    uint w = p->camera.width, h = p->camera.height, ts = p->tile_size;
    uint tw = (w + ts - 1u) / ts, th = (h + ts - 1u) / ts;
    uint t = get_global_id(0);
    if (t >= tw * th) return;
    uint tx = t % tw, ty = t / tw;
    float r = 0.0f;
    for (uint y = ty * ts; y < min((ty + 1u) * ts, h); y++) {
        for (uint x = tx * ts; x < min((tx + 1u) * ts, w); x++) {
            uint i = y * w + x;
            float4 s = input[i];
            if (s.x != 0.0f || s.y != 0.0f || s.z != 0.0f) r = fmax(r, radius[i]);
        }
    }
    tiles[t] = r;
}

// deposit_atlas (seed 001 section 3.2): each texture-space photon (uv, triangle) is added
// in fixed point to the atlas texel under its uv on its triangle's receiver tile. Mirror
// of backend-cpu/src/kernels/caustic_map.rs; the sums are bitwise the CPU's.

__kernel void deposit_atlas(__global const AtlasParams* p, __global const uint* triangle_tiles,
                            __global const uint4* tiles, __global const Photon* photons,
                            uint photon_capacity, __global const uint* photon_count,
                            volatile __global uint* counters,
                            PHOTON_MAP_PARAMS(volatile __global)) {
    __local uint lc[COUNTER_WORDS];
    counters_clear_local(lc);
    uint i = get_global_id(0);
    if (i < min(photon_count[0], photon_capacity)) {
        Photon ph = photons[i];
        uint tile = triangle_tiles[ph.direction];
        if (tile == NO_TILE) {
            atomic_inc(&lc[COUNTER_OFF_SCREEN]);
        } else {
            uint texel = atlas_texel_index(tiles[tile], (float2)(ph.position[0], ph.position[1]),
                                           p->width);
            for (uint ch = 0u; ch < 3u; ch++) {
                Quantized q = quantize(ph.flux[ch], p->flux_quantum);
                if (q.underflow) atomic_inc(&lc[COUNTER_UNDERFLOW]);
                if (q.saturated) atomic_inc(&lc[COUNTER_SATURATED]);
                if (q.units != 0u)
                    atomic_add_u64_photon_map(PHOTON_MAP_ARGS, texel, 2u * ch, q.units, 0u);
            }
            atomic_add_u64_photon_map(PHOTON_MAP_ARGS, texel, 6u,
                                      quantize(ph.hit_distance, p->hit_distance_quantum).units, 0u);
            atomic_add_u64_photon_map(PHOTON_MAP_ARGS, texel, 8u, 1u, 0u);
            atomic_inc(&lc[COUNTER_DEPOSITED]);
        }
    }
    counters_flush_local(lc, counters);
}

// deposit_atlas (seed 001 section 3.2): each texture-space photon (uv, triangle) is added
// in fixed point to the atlas texel under its uv on its triangle's receiver tile. Mirror
// of backend-cpu/src/kernels/caustic_map.rs; the sums are bitwise the CPU's.

__kernel void deposit_atlas(__global const AtlasParams* p, __global const uint* triangle_tiles,
                            __global const uint4* tiles, __global const Photon* photons,
                            uint photon_capacity, __global const uint* photon_count,
                            volatile __global uint* counters,
                            volatile __global uint* triangle_reach,
                            PHOTON_MAP_PARAMS(volatile __global)) {
    __local uint lc[COUNTER_WORDS];
    counters_clear_local(lc);
    uint i = get_global_id(0);
    if (i < min(photon_count[0], photon_capacity)) {
        Photon ph = photons[i];
        uint2 reach = triangle_reach_bit(ph.direction);
        // most photons land on a few triangles: a load first, so that a bit already set
        // costs no atomic on the hot word
        if ((triangle_reach[reach.x] & reach.y) == 0u) atomic_or(&triangle_reach[reach.x], reach.y);
        uint tile = triangle_tiles[ph.direction];
        if (tile == NO_TILE) {
            atomic_inc(&lc[COUNTER_OFF_SCREEN]);
        } else {
            uint texel = atlas_texel_index(tiles[tile], (float2)(ph.position[0], ph.position[1]),
                                           p->width);
            deposit_photon_texel(PHOTON_MAP_ARGS, lc, texel, &ph, p->flux_quantum,
                                 p->hit_distance_quantum);
        }
    }
    counters_flush_local(lc, counters);
}

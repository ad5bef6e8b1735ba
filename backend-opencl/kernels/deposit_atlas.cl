// deposit_atlas (seed 001 section 3.2): each texture-space photon (uv, triangle) is added
// in fixed point to the atlas texel under its uv on its triangle's receiver tile. Mirror
// of backend-cpu/src/kernels/caustic_map.rs; the sums are bitwise the CPU's.

__kernel void deposit_atlas(__global const AtlasParams* ap, __global const uint* triangle_tiles,
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
        deposit_atlas_photon(ATLAS_DEPOSIT_ARGS, lc, &ph);
    }
    counters_flush_local(lc, counters);
}

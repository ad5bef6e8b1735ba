// deposit_screen (Kim 2019, section 30.3.1.3): each stored photon is projected to its pixel
// and added in fixed point if the pixel sees a diffuse surface at a consistent depth and
// the photon arrives on the side the camera sees. Mirror of
// backend-cpu/src/kernels/deposit_screen.rs; 64-bit sums are (lo, hi) u32 atomics with
// carry, so the map is bitwise identical to the CPU's for the same photons.

__kernel void deposit_screen(__global const DepositParams* dp,
                             GBUFFER_PARAMS(__global const),
                             __global const Photon* photons, uint photon_capacity,
                             __global const uint* photon_count,
                             volatile __global uint* counters,
                             PHOTON_MAP_PARAMS(volatile __global)) {
    __local uint lc[COUNTER_WORDS];
    counters_clear_local(lc);
    uint i = get_global_id(0);
    if (i < min(photon_count[0], photon_capacity)) {
        Photon ph = photons[i];
        deposit_screen_photon(SCREEN_DEPOSIT_ARGS, lc, &ph);
    }
    counters_flush_local(lc, counters);
}

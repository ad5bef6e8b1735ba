// deposit_screen (seed 000 section 30.3.1.3): each stored photon is projected to its pixel
// and added in fixed point if the pixel sees a diffuse surface at a consistent depth and
// the photon arrives on the side the camera sees. Mirror of
// backend-cpu/src/kernels/deposit_screen.rs; 64-bit sums are (lo, hi) u32 atomics with
// carry, so the map is bitwise identical to the CPU's for the same photons.

__kernel void deposit_screen(__global const DepositParams* p,
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
        uint px, py;
        float z;
        if (!project_to_pixel(&p->camera, load3(ph.position), &px, &py, &z)) {
            atomic_inc(&lc[COUNTER_OFF_SCREEN]);
        } else {
            uint pix = py * p->camera.width + px;
            GBufferTexel gt = load_gbuffer(GBUFFER_ARGS, pix);
            const GBufferTexel* g = &gt;
            bool arrives_in_front = dot3(unpack_unit_vector(ph.direction), load3(g->normal)) < 0.0f;
            if ((g->flags & GBUFFER_RECEIVER) == 0u ||
                off_surface(z, load3(ph.position), load3(g->position), load3(g->normal), g->depth,
                            p->depth_tolerance) ||
                !arrives_in_front) {
                atomic_inc(&lc[COUNTER_DEPTH_MISMATCH]);
            } else {
                deposit_photon_texel(PHOTON_MAP_ARGS, lc, pix, &ph, p->flux_quantum,
                                     p->hit_distance_quantum);
            }
        }
    }
    counters_flush_local(lc, counters);
}

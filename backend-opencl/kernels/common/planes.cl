// The G-buffer and the screen photon map in planes (core::device::layout::GBUFFER_PLANES,
// DEPOSIT_PLANES), so that no per-pixel buffer is over 16 bytes a pixel. G-buffer plane k
// of pixel i holds bytes 16k .. 16k + 16 of its GBufferTexel as a uint4 (the texel's bits:
// as_float / as_uint, so the assembled texel is bitwise the texel). The photon map's
// planes hold words 0-3, 4-7 (4 a pixel) and 8-9 (2 a pixel) of its DepositTexel; no
// (lo, hi) pair straddles two planes.

#define GBUFFER_PARAMS(q) q uint4* gbuffer0, q uint4* gbuffer1, q uint4* gbuffer2, q uint4* gbuffer3
#define GBUFFER_ARGS gbuffer0, gbuffer1, gbuffer2, gbuffer3
#define PHOTON_MAP_PARAMS(q) q uint* photon_map0, q uint* photon_map1, q uint* photon_map2
#define PHOTON_MAP_ARGS photon_map0, photon_map1, photon_map2

// core's GBufferTexel::from_planes.
inline GBufferTexel gbuffer_from_planes(uint4 p0, uint4 p1, uint4 p2, uint4 p3) {
    GBufferTexel g;
    g.position[0] = as_float(p0.x);
    g.position[1] = as_float(p0.y);
    g.position[2] = as_float(p0.z);
    g.depth = as_float(p0.w);
    g.normal[0] = as_float(p1.x);
    g.normal[1] = as_float(p1.y);
    g.normal[2] = as_float(p1.z);
    g.geometric_normal = p1.w;
    g.albedo[0] = as_float(p2.x);
    g.albedo[1] = as_float(p2.y);
    g.albedo[2] = as_float(p2.z);
    g.material = p2.w;
    g.uv[0] = as_float(p3.x);
    g.uv[1] = as_float(p3.y);
    g.view_distance = as_float(p3.z);
    g.flags = p3.w;
    return g;
}

// The texel of pixel `i`, assembled from the planes.
inline GBufferTexel load_gbuffer(GBUFFER_PARAMS(__global const), uint i) {
    return gbuffer_from_planes(gbuffer0[i], gbuffer1[i], gbuffer2[i], gbuffer3[i]);
}

// Writes the texel of pixel `i` into the planes (core's GBufferTexel::to_planes).
inline void store_gbuffer(GBUFFER_PARAMS(__global), uint i, const GBufferTexel* g) {
    gbuffer0[i] = (uint4)(as_uint(g->position[0]), as_uint(g->position[1]),
                          as_uint(g->position[2]), as_uint(g->depth));
    gbuffer1[i] = (uint4)(as_uint(g->normal[0]), as_uint(g->normal[1]), as_uint(g->normal[2]),
                          g->geometric_normal);
    gbuffer2[i] = (uint4)(as_uint(g->albedo[0]), as_uint(g->albedo[1]), as_uint(g->albedo[2]),
                          g->material);
    gbuffer3[i] = (uint4)(as_uint(g->uv[0]), as_uint(g->uv[1]), as_uint(g->view_distance),
                          g->flags);
}

// core's deposit_word: (plane, index in the plane) of word `word` of pixel `pixel`.
inline uint2 deposit_word(uint pixel, uint word) {
    uint k = word / 4u;
    uint n = k == 2u ? 2u : 4u;
    return (uint2)(k, pixel * n + (word - 4u * k));
}

// Word `word` of pixel `pixel`'s DepositTexel.
inline uint photon_map_word(PHOTON_MAP_PARAMS(__global const), uint pixel, uint word) {
    uint2 at = deposit_word(pixel, word);
    return at.x == 0u ? photon_map0[at.y] : at.x == 1u ? photon_map1[at.y] : photon_map2[at.y];
}

// Words (word, word + 1) of pixel `pixel`'s texel += (lo, hi), with carry.
inline void atomic_add_u64_photon_map(PHOTON_MAP_PARAMS(volatile __global), uint pixel,
                                      uint word, uint lo, uint hi) {
    uint2 at = deposit_word(pixel, word);
    volatile __global uint* plane = at.x == 0u ? photon_map0 : at.x == 1u ? photon_map1
                                                                         : photon_map2;
    atomic_add_u64_global(&plane[at.y], lo, hi);
}

// backend-cpu deposit_screen.rs::photon_flux_units: the photon's flux per channel in
// flux quanta (into `units`), underflow and saturation counted in the work-group's `lc`.
inline void photon_flux_units(const Photon* ph, float flux_quantum, __local uint* lc,
                              uint* units) {
    for (uint ch = 0u; ch < 3u; ch++) {
        Quantized q = quantize(ph->flux[ch], flux_quantum);
        if (q.underflow) atomic_inc(&lc[COUNTER_UNDERFLOW]);
        if (q.saturated) atomic_inc(&lc[COUNTER_SATURATED]);
        units[ch] = q.units;
    }
}

// backend-cpu deposit_screen.rs::deposit_photon_texel: photon `ph` added to texel `texel`
// (a screen pixel or an atlas texel): flux per channel, hit distance and a count in fixed
// point; underflow, saturation and the deposit counted in the work-group's `lc`.
// Every low word's add goes out before any carry is looked at, so that their round trips
// overlap (a carry waits for its low word's old value): splat_photons at Smal 2019's high
// setting on the H200 took 1.72 ms against 2.14 with an add and its carry in turn, and
// 3.6 against 5.0 in WGSL on Vulkan and wgpu (docs/performance.md, "PhotonGi").
// Adding zero changes no word and carries nothing, so the flux adds need no test; a zero
// hit distance (a splat's) is left out.
inline void deposit_photon_texel(PHOTON_MAP_PARAMS(volatile __global), __local uint* lc,
                                 uint texel, const Photon* ph, float flux_quantum,
                                 float hit_distance_quantum) {
    uint units[3];
    photon_flux_units(ph, flux_quantum, lc, units);
    uint hit = quantize(ph->hit_distance, hit_distance_quantum).units;
    // deposit_word: words 0-3 in plane 0, 4-7 in plane 1, 8-9 in plane 2
    volatile __global uint* rg = &photon_map0[4u * texel];
    volatile __global uint* bh = &photon_map1[4u * texel];
    volatile __global uint* count = &photon_map2[2u * texel];
    uint old_r = atomic_add(&rg[0], units[0]);
    uint old_g = atomic_add(&rg[2], units[1]);
    uint old_b = atomic_add(&bh[0], units[2]);
    uint old_h = hit != 0u ? atomic_add(&bh[2], hit) : 0u;
    uint old_n = atomic_inc(&count[0]);
    if (old_r > 0xFFFFFFFFu - units[0]) atomic_inc(&rg[1]);
    if (old_g > 0xFFFFFFFFu - units[1]) atomic_inc(&rg[3]);
    if (old_b > 0xFFFFFFFFu - units[2]) atomic_inc(&bh[1]);
    if (old_h > 0xFFFFFFFFu - hit) atomic_inc(&bh[3]);
    if (old_n == 0xFFFFFFFFu) atomic_inc(&count[1]);
    atomic_inc(&lc[COUNTER_DEPOSITED]);
}

// The screen photon map and G-buffer a world-space photon is deposited into
// (deposit_screen, and the FUSED_DEPOSIT variant of trace_photons in world space).
#define SCREEN_DEPOSIT_PARAMS                                                                 \
    __global const DepositParams *dp, GBUFFER_PARAMS(__global const),                        \
        PHOTON_MAP_PARAMS(volatile __global)
#define SCREEN_DEPOSIT_ARGS dp, GBUFFER_ARGS, PHOTON_MAP_ARGS

// One world-space photon into the screen photon map (backend-cpu deposit_screen.rs): projected
// to its pixel and added in fixed point if the pixel sees a diffuse surface at a consistent
// depth and the photon arrives on the side the camera sees; OFF_SCREEN or DEPTH_MISMATCH
// counted in the work-group's `lc` otherwise.
inline void deposit_screen_photon(SCREEN_DEPOSIT_PARAMS, __local uint* lc, const Photon* ph) {
    uint px, py;
    float z;
    if (!project_to_pixel(&dp->camera, load3(ph->position), &px, &py, &z)) {
        atomic_inc(&lc[COUNTER_OFF_SCREEN]);
        return;
    }
    uint pix = py * dp->camera.width + px;
    GBufferTexel gt = load_gbuffer(GBUFFER_ARGS, pix);
    const GBufferTexel* g = &gt;
    bool arrives_in_front = dot3(unpack_unit_vector(ph->direction), load3(g->normal)) < 0.0f;
    if ((g->flags & GBUFFER_RECEIVER) == 0u ||
        off_surface(z, load3(ph->position), load3(g->position), load3(g->normal), g->depth,
                    dp->depth_tolerance) ||
        !arrives_in_front) {
        atomic_inc(&lc[COUNTER_DEPTH_MISMATCH]);
    } else {
        deposit_photon_texel(PHOTON_MAP_ARGS, lc, pix, ph, dp->flux_quantum,
                             dp->hit_distance_quantum);
    }
}

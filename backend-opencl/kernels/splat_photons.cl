// splat_photons (seed 003 section 24.3, Eqs. 2-9): a thread per stored photon adds its
// ellipsoid splat's irradiance times each covered receiver pixel's area to the photon map
// in fixed point. Mirror of backend-cpu/src/kernels/photon_gi.rs (splat_photon) and
// shaders/wgsl/splat_photons.wgsl.

inline void splat_photon(__global const SplatParams* p, GBUFFER_PARAMS(__global const),
                         GiPhoton ph, __global const uint* tile_counts,
                         PHOTON_MAP_PARAMS(volatile __global), volatile __global uint* direction_map0,
                         volatile __global uint* direction_map1,
                         volatile __global uint* direction_map2, __local uint* lc,
                         __local uint* uncounted) {
    float3 power = unpack_rgb9e5(ph.power) * p->power_scale;
    if (!(max_element3(power) > 0.0f)) return;
    float3 pos = load3(ph.position);
    uint px, py;
    float z;
    if (!project_to_pixel(&p->camera, pos, &px, &py, &z)) return;
    float3 n = unpack_unit_vector(ph.normal);
    float3 to_light = -unpack_unit_vector(ph.direction);
    float s = max(ray_length_scale(ph.ray_length, p) *
                      density_scale(z, p->tile_constant, tile_counts[ph.tile], p),
                  min_splat_scale(z, p->camera.tan_half_fov_y, p->camera.height, p->min_splat_px));
    SplatKernel k = splat_kernel(n, to_light, s, p);
    float3 e = splat_irradiance(power, &k);
    uint reach = splat_reach_px(p, max_element3(k.axes), z);
    if (reach > p->max_splat_px) atomic_inc(&lc[COUNTER_SATURATED]);
    int4 rect = splat_screen_rect(&p->camera, pos, &k, px, py, min(reach, p->max_splat_px));
    int w = (int)p->camera.width;
    for (int qy = rect.z; qy <= rect.w; qy++) {
        for (int qx = rect.x; qx <= rect.y; qx++) {
            uint q = (uint)(qy * w + qx);
            // each test loads the G-buffer plane it reads, in the tests' order (flags,
            // position, normal): most pixels of the square fail the first two (1-2 ms of
            // 16 at the chapter's high setting on the H200)
            uint4 p3 = gbuffer3[q];
            if ((p3.w & GBUFFER_RECEIVER) == 0u) continue;
            uint4 p0 = gbuffer0[q];
            if (!kernel_contains(&k, pos, (float3)(as_float(p0.x), as_float(p0.y), as_float(p0.z))))
                continue;
            uint4 p1 = gbuffer1[q];
            if (dot3((float3)(as_float(p1.x), as_float(p1.y), as_float(p1.z)), n) <= 0.0f) continue;
            GBufferTexel t = gbuffer_from_planes(p0, p1, gbuffer2[q], p3);
            float area = gbuffer_pixel_area(&p->camera, q, &t);
            float3 f = e * area;
            Photon splat = {{0.0f, 0.0f, 0.0f}, 0.0f, {f.x, f.y, f.z}, 0u};
            deposit_photon_texel(PHOTON_MAP_ARGS, lc, q, &splat, p->flux_quantum, 1.0f);
            if (p->light_direction != 0u &&
                shading_normal_departs(load3(t.normal), unpack_unit_vector(t.geometric_normal))) {
                // Eq. 20's power-weighted light direction, in the flux's quanta; its
                // rounding is not counted (the flux's own deposit counts it)
                float4 d = light_direction_deposit(f, to_light);
                Photon dir = {{0.0f, 0.0f, 0.0f}, d.w, {d.x, d.y, d.z}, 0u};
                deposit_photon_texel(direction_map0, direction_map1, direction_map2, uncounted,
                                     q, &dir, p->flux_quantum, p->flux_quantum);
            }
        }
    }
}

__kernel void splat_photons(__global const SplatParams* p, GBUFFER_PARAMS(__global const),
                            __global const GiPhoton* photons, uint photon_capacity,
                            __global const uint* photon_count,
                            __global const uint* tile_counts, volatile __global uint* counters,
                            PHOTON_MAP_PARAMS(volatile __global),
                            volatile __global uint* direction_map0,
                            volatile __global uint* direction_map1,
                            volatile __global uint* direction_map2) {
    __local uint lc[COUNTER_WORDS];
    __local uint uncounted[COUNTER_WORDS];
    counters_clear_local(lc);
    uint i = get_global_id(0);
    if (i < min(photon_count[0], photon_capacity))
        splat_photon(p, GBUFFER_ARGS, photons[i], tile_counts, PHOTON_MAP_ARGS, direction_map0,
                     direction_map1, direction_map2, lc, uncounted);
    counters_flush_local(lc, counters);
}

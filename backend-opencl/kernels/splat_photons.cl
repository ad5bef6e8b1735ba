// splat_photons (Smal 2019, section 24.3, Eqs. 2-9): each stored photon's ellipsoid splat adds
// its irradiance times each covered receiver pixel's area to the photon map in fixed point.
// A workgroup splats its photons together: each thread sets up its own photon's splat
// (splat_setup), then the group walks the run of all its splats' pixels, a pixel per
// thread (splat_pixel), so that neighbouring threads test neighbouring pixels of one splat
// (their G-buffer loads coalesce) and every thread gets the same share (a large splat does
// not hold up the rest of its warp). The sums are exact integers, so the order is free.
// Mirror of backend-cpu/src/kernels/splat_photons.rs (splat_setup, splat_pixel) and
// shaders/wgsl/splat_photons.wgsl.

// threads per workgroup (core::kernels::DEFAULT_WORKGROUP_SIZE, the launch's local size)
#define SPLAT_GROUP 64

// backend-cpu splat_photons::SplatSetup: what every pixel test of one splat reads.
typedef struct {
    SplatKernel ellipsoid;
    float3 centre;
    float3 normal;
    float3 to_light;
    float3 irradiance;
    int4 rect; // x0, x1, y0, y1 inclusive; empty when x1 < x0
    SplatRays rays; // the pixels' centre rays, tested before a pixel's G-buffer is read
} SplatSetup;

inline SplatSetup splat_setup(__global const SplatParams* p, GiPhoton ph,
                              __global const uint* tile_counts, __local uint* lc) {
    SplatSetup s;
    s.rect = (int4)(0, -1, 0, -1);
    float3 power = unpack_rgb9e5(ph.power) * p->power_scale;
    if (!(max_element3(power) > 0.0f)) return s;
    float3 pos = load3(ph.position);
    uint px, py;
    float z;
    if (!project_to_pixel(&p->camera, pos, &px, &py, &z)) return s;
    float3 n = unpack_unit_vector(ph.normal);
    float3 to_light = -unpack_unit_vector(ph.direction);
    float sc = max(ray_length_scale(ph.ray_length, p) *
                       density_scale(z, p->tile_constant, tile_counts[ph.tile], p),
                   min_splat_scale(z, p->camera.tan_half_fov_y, p->camera.height, p->min_splat_px));
    SplatKernel k = splat_kernel(n, to_light, sc, p);
    uint reach = splat_reach_px(p, max_element3(k.axes), z);
    if (reach > p->max_splat_px) atomic_inc(&lc[COUNTER_SATURATED]);
    s.ellipsoid = k;
    s.centre = pos;
    s.normal = n;
    s.to_light = to_light;
    s.irradiance = splat_irradiance(power, &k);
    s.rect = splat_screen_rect(&p->camera, pos, &k, px, py, min(reach, p->max_splat_px),
                               p->scene_magnitude);
    s.rays = splat_rays(&p->camera, pos, &k, p->scene_magnitude);
    return s;
}

// Pixels in a splat's screen rectangle (0 when empty).
inline uint splat_rect_pixels(int4 rect) {
    return rect.y < rect.x || rect.w < rect.z ? 0u
                                              : (uint)(rect.y - rect.x + 1) * (uint)(rect.w - rect.z + 1);
}

inline void splat_pixel(__global const SplatParams* p, GBUFFER_PARAMS(__global const),
                        const SplatSetup* s, uint q, PHOTON_MAP_PARAMS(volatile __global),
                        volatile __global uint* direction_map0,
                        volatile __global uint* direction_map1,
                        volatile __global uint* direction_map2, __local uint* lc,
                        __local uint* uncounted) {
    // each test loads the G-buffer plane it reads, in the tests' order (flags, position,
    // normal): most pixels of the rectangle fail the first two
    uint4 p3 = gbuffer3[q];
    if ((p3.w & GBUFFER_RECEIVER) == 0u) return;
    uint4 p0 = gbuffer0[q];
    if (!kernel_contains(&s->ellipsoid, s->centre,
                         (float3)(as_float(p0.x), as_float(p0.y), as_float(p0.z))))
        return;
    uint4 p1 = gbuffer1[q];
    if (dot3((float3)(as_float(p1.x), as_float(p1.y), as_float(p1.z)), s->normal) <= 0.0f) return;
    GBufferTexel t = gbuffer_from_planes(p0, p1, gbuffer2[q], p3);
    float area = gbuffer_pixel_area(&p->camera, q, &t);
    float3 f = s->irradiance * area;
    Photon splat = {{0.0f, 0.0f, 0.0f}, 0.0f, {f.x, f.y, f.z}, 0u};
    deposit_photon_texel(PHOTON_MAP_ARGS, lc, q, &splat, p->flux_quantum, 1.0f);
    if (p->light_direction != 0u &&
        shading_normal_departs(load3(t.normal), unpack_unit_vector(t.geometric_normal))) {
        // Eq. 20's power-weighted light direction, in the flux's quanta; its rounding is
        // not counted (the flux's own deposit counts it)
        float4 d = light_direction_deposit(f, s->to_light);
        Photon dir = {{0.0f, 0.0f, 0.0f}, d.w, {d.x, d.y, d.z}, 0u};
        deposit_photon_texel(direction_map0, direction_map1, direction_map2, uncounted, q, &dir,
                             p->flux_quantum, p->flux_quantum);
    }
}

// The photon thread `l` of group `group` splats: every G-th photon from `group` on,
// G = ceil(stored / SPLAT_GROUP) the groups that hold the `stored` photons. Photons stored
// one after another come from neighbouring paths and splat onto the same pixels: a group
// of such neighbours would add to the same words over and over, and atomics on one word
// are served one at a time.
inline uint splat_group_photon(uint group, uint l, uint stored) {
    return group + l * ((stored + SPLAT_GROUP - 1u) / SPLAT_GROUP);
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
    __local SplatSetup setups[SPLAT_GROUP];
    // first pixel of each splat in the group's run of pixels; [SPLAT_GROUP]: their total
    __local uint starts[SPLAT_GROUP + 1];
    // the launch covers the photon buffer's capacity; a group past the stored photons
    // (most of them at 3 bounces) leaves at once, all its threads alike, before any barrier
    uint stored = min(photon_count[0], photon_capacity);
    if (get_group_id(0) * SPLAT_GROUP >= stored) return;
    counters_clear_local(lc);
    uint l = get_local_id(0), i = splat_group_photon(get_group_id(0), l, stored);
    SplatSetup mine;
    mine.rect = (int4)(0, -1, 0, -1);
    if (i < stored)
        mine = splat_setup(p, photons[i], tile_counts, lc);
    setups[l] = mine;
    starts[l + 1u] = splat_rect_pixels(mine.rect);
    barrier(CLK_LOCAL_MEM_FENCE);
    if (l == 0u) {
        starts[0] = 0u;
        for (uint j = 1u; j <= SPLAT_GROUP; j++) starts[j] += starts[j - 1u];
    }
    barrier(CLK_LOCAL_MEM_FENCE);
    // the group's pixels in order, a thread each: neighbouring threads test neighbouring
    // pixels of the same splat, and every thread gets the same share
    int w = (int)p->camera.width;
    uint j = 0u, loaded = SPLAT_GROUP;
    SplatSetup s;
    for (uint k = l; k < starts[SPLAT_GROUP]; k += SPLAT_GROUP) {
        while (starts[j + 1u] <= k) j++;
        if (j != loaded) {
            s = setups[j];
            loaded = j;
        }
        uint at = k - starts[j];
        uint rw = (uint)(s.rect.y - s.rect.x + 1);
        int qx = s.rect.x + (int)(at % rw), qy = s.rect.z + (int)(at / rw);
        // a pixel whose centre ray misses the kernel's box is turned away before its
        // G-buffer is read (most of a rectangle's pixels)
        if (splat_ray_may_hit(&s.rays, &p->camera, (uint)qx, (uint)qy))
            splat_pixel(p, GBUFFER_ARGS, &s, (uint)(qy * w + qx), PHOTON_MAP_ARGS,
                        direction_map0, direction_map1, direction_map2, lc, uncounted);
    }
    counters_flush_local(lc, counters);
}

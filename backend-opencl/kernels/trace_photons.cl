// trace_photons (seed 000 sections 30.3.1.1-2): photon `first + i` of the light's
// stratified grid is emitted, traced through mirrors and dielectrics and stored where it
// first meets a diffuse surface after at least one specular interaction. Mirror of
// backend-cpu/src/kernels/trace_photons.rs (same random dimensions, same decisions).
// Stored photons are appended in arrival order (an atomic slot counter): the set of
// photons equals the CPU's, their order does not, and every later sum is order-free.

// Compiled variants (not branches): the host builds this file with `-D DIELECTRIC=0/1
// -D DISPERSION=0/1 -D ABSORPTION=0/1` (core's TraceVariant); a switch at 0 compiles its
// material feature out. Without defines every feature is in.
#ifndef DIELECTRIC
#define DIELECTRIC 1
#endif
#ifndef DISPERSION
#define DISPERSION 1
#endif
#ifndef ABSORPTION
#define ABSORPTION 1
#endif
// Store policy (core's photon_store): 0 stores world space (Sspm), 1 the hit's uv and
// triangle (CausticMap's atlas).
#ifndef SURFACE_STORE
#define SURFACE_STORE 0
#endif

#define PATH_STORED 0
#define PATH_NO_SPECULAR 1
#define PATH_ESCAPED 2
#define PATH_NEGLIGIBLE 3
#define PATH_BOUNCE_LIMIT 4

// The emitted ray and flux of photon `index` (global index in the light's grid).
inline void emit_photon(__global const GpuLight* lights, __global const TraceParams* p,
                        uint index, float3* origin, float3* dir, float3* flux) {
    uint ix = index % p->grid_w;
    uint iy = index / p->grid_w;
    float2 jitter = (float2)(random_f32(p->seed, index, 0u, 0u), random_f32(p->seed, index, 0u, 1u));
    float2 u = stratified_cell(ix, iy, p->grid_w, p->grid_h, jitter);
    *flux = load3g(p->photon_flux);
    float3 axis = load3g(p->axis);
    if (p->emission == EMISSION_RECTANGLE) {
        *origin = load3g(p->origin) + u.x * load3g(p->rect_u) + u.y * load3g(p->rect_v);
        *dir = axis;
        return;
    }
    if (p->emission == EMISSION_VIEW_PLANE) {
        *dir = view_plane_direction(axis, load3g(p->rect_u), load3g(p->rect_v), u);
        *flux = *flux * view_plane_texel_weight(ix, iy, p->grid_w, p->grid_h, p->rect_u[3],
                                                p->rect_v[3]);
    } else {
        *dir = to_world(uniform_cone(u, p->origin[3]), axis);
    }
    __global const GpuLight* light = &lights[p->light];
    float falloff = light->kind == LIGHT_SPOT
                        ? spot_falloff(dot3(*dir, load3g(light->direction)), light->cos_inner,
                                       light->cos_outer)
                        : 1.0f;
    *origin = load3g(p->origin);
    *flux = *flux * falloff;
}

// Traces one photon: returns how the path ended, writes the stored photon and the number
// of ray segments traced.
inline int trace_photon(SCENE_PARAMS, __global const TraceParams* p, uint index, Photon* ph,
                        uint* rays) {
    float3 origin, dir, flux;
    emit_photon(lights, p, index, &origin, &dir, &flux);
    float emitted_max = max_element3(load3g(p->photon_flux));
    float min_power = p->photon_flux[3] * emitted_max;
    *rays = 0u;
    if (max_element3(flux) <= 0.0f || max_element3(flux) < min_power) return PATH_NEGLIGIBLE;
    int channel = -1;
    for (uint bounce = 0u; bounce < p->max_bounces; bounce++) {
        *rays = bounce + 1u;
        Hit hit;
        if (!closest_hit(nodes, node_count, vertices, triangles, origin, dir, INFINITY, &hit))
            return PATH_ESCAPED;
        SurfacePoint s = hit_surface(vertices, triangles, &hit);
        __global const GpuMaterial* m = &materials[triangles[hit.triangle].material];
        bool entering = dot3(dir, s.geometric_normal) < 0.0f;
        if (ABSORPTION && m->kind == MATERIAL_DIELECTRIC && !entering)
            flux *= beer_lambert(load3g(m->absorption), hit.t);
        if (m->kind == MATERIAL_DIFFUSE) {
            // every earlier segment ended at a mirror or dielectric
            if (bounce == 0u) return PATH_NO_SPECULAR;
            ph->hit_distance = hit.t;
            store3(ph->flux, flux);
            if (SURFACE_STORE) {
                store3(ph->position, (float3)(s.uv.x, s.uv.y, 0.0f));
                ph->direction = hit.triangle;
            } else {
                store3(ph->position, s.position);
                ph->direction = pack_unit_vector(dir);
            }
            return PATH_STORED;
        } else if (m->kind == MATERIAL_MIRROR) {
            flux *= load3g(m->color);
            float3 n = facing_normal(s.shading_normal, dir);
            dir = normalize3(reflect(dir, n));
        } else if (DIELECTRIC) {
            float ior = m->ior;
            if (DISPERSION && m->cauchy_b != 0.0f) {
                if (channel < 0) {
                    // First dispersive surface: keep one channel, x3 so that the expected
                    // flux per channel is unchanged.
                    channel = min((int)(random_f32(p->seed, index, bounce, 3u) * 3.0f), 2);
                    float one[3] = {0.0f, 0.0f, 0.0f};
                    one[channel] = (channel == 0 ? flux.x : channel == 1 ? flux.y : flux.z) * 3.0f;
                    flux = load3(one);
                }
                ior = cauchy_ior(m->ior, m->cauchy_b, CHANNEL_WAVELENGTH_UM[channel]);
            }
            dir = dielectric_scatter(dir, s.shading_normal, entering, ior,
                                     random_f32(p->seed, index, bounce, 2u));
        }
        // (a variant without DIELECTRIC is never run on a dielectric: the frame plan)
        if (max_element3(flux) < min_power || max_element3(flux) <= 0.0f) return PATH_NEGLIGIBLE;
        float3 side = dot3(dir, s.geometric_normal) > 0.0f ? s.geometric_normal : -s.geometric_normal;
        origin = offset_ray_origin(s.position, side);
    }
    *rays = p->max_bounces;
    return PATH_BOUNCE_LIMIT;
}

__kernel void trace_photons(SCENE_PARAMS, __global const TraceParams* p,
                            __global Photon* photons, uint photon_capacity,
                            volatile __global uint* photon_count,
                            volatile __global uint* counters) {
    __local uint lc[COUNTER_WORDS];
    counters_clear_local(lc);
    uint i = get_global_id(0);
    if (i < p->count) {
        Photon ph;
        uint rays;
        int end = trace_photon(SCENE_ARGS, p, p->first + i, &ph, &rays);
        atomic_add_u64_local(&lc[COUNTER_RAYS], rays);
        if (end == PATH_STORED) {
            uint slot = atomic_inc(photon_count);
            // The host never dispatches more photons than the buffer holds.
            if (slot < photon_capacity) photons[slot] = ph;
            atomic_inc(&lc[COUNTER_STORED]);
            for (uint ch = 0u; ch < 3u; ch++) {
                uint units = quantize(ph.flux[ch], p->flux_quantum).units;
                if (units != 0u) atomic_add_u64_local(&lc[COUNTER_STORED_FLUX + 2u * ch], units);
            }
        } else {
            atomic_inc(&lc[end == PATH_NO_SPECULAR  ? COUNTER_NO_SPECULAR
                          : end == PATH_ESCAPED     ? COUNTER_ESCAPED
                          : end == PATH_NEGLIGIBLE  ? COUNTER_NEGLIGIBLE
                                                    : COUNTER_BOUNCE_LIMIT]);
        }
    }
    counters_flush_local(lc, counters);
}

// trace_photons (Kim 2019, sections 30.3.1.1-2): photon tiled_photon_index(first + i) of
// the light's stratified grid (tile order, sampling.cl) is emitted, traced through
// mirrors and dielectrics and stored where it first meets a diffuse surface after at
// least one specular interaction. Mirror of backend-cpu/src/kernels/trace_photons.rs
// (same random dimensions, same decisions).
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
// Vanderstichelen 2021's deterministic splits (core's TraceVariant::fresnel_split).
#ifndef FRESNEL_SPLIT
#define FRESNEL_SPLIT 0
#endif
// Wyman 2009's adaptive emission (core's TraceVariant::adaptive): photon i is photon i % 4
// of cluster clusters[p->first + i / 4] of the p->grid_w grid and is written to slot i,
// stored or not (core's photon_store says how), or with FUSED_DEPOSIT deposited (a level
// whose every cluster is output); photon_count is left untouched.
#ifndef ADAPTIVE
#define ADAPTIVE 0
#endif
// The fused pass (core's TraceVariant::fused_deposit): a stored photon is deposited where
// its path ends instead of into the photon buffer: with SURFACE_STORE into the caustic
// atlas (CausticMap; map_gather.cl's deposit_atlas_photon), without into the screen photon
// map (Sspm; planes.cl's deposit_screen_photon, as deposit_screen adds it).
#ifndef FUSED_DEPOSIT
#define FUSED_DEPOSIT 0
#endif

// The fused deposit's arguments, after `clusters`: the atlas with the photon map's planes
// (map_gather.cl), then the screen's parameters and G-buffer (planes.cl), then the atlas's
// centroid sums.
#define FUSED_DEPOSIT_PARAMS                                                                  \
    ATLAS_DEPOSIT_PARAMS, __global const DepositParams *dp, GBUFFER_PARAMS(__global const),  \
        volatile __global uint *centroids
#define FUSED_DEPOSIT_ARGS ATLAS_DEPOSIT_ARGS, dp, GBUFFER_ARGS, centroids

#define PATH_STORED 0
#define PATH_NO_SPECULAR 1
#define PATH_ESCAPED 2
#define PATH_NEGLIGIBLE 3
#define PATH_BOUNCE_LIMIT 4

// core::math::geometry::ray_meets_caster_spheres over the batch's caster balls (core's
// device::caster_spheres): a first segment that meets none cannot meet a caster first.
inline bool ray_meets_caster_spheres(__global const TraceParams* p, float3 origin, float3 dir) {
    uint count = p->caster_sphere_count;
    if (count == 0u) return true;
    for (uint k = 0u; k < min(count, (uint)MAX_CASTER_SPHERES); k++)
        if (ray_meets_sphere(origin, dir, p->caster_spheres[k])) return true;
    return false;
}

// The emitted ray and flux of photon `index` (global index in the light's grid).
inline void emit_photon(__global const GpuLight* lights, __global const TraceParams* p,
                        uint index, float3* origin, float3* dir, float3* flux) {
    uint ix = index % p->grid_w;
    uint iy = index / p->grid_w;
    float2 jitter = (float2)(stratum_jitter(p->jitter_seed, index, 0u, p->stratum),
                             stratum_jitter(p->jitter_seed, index, 1u, p->stratum));
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
        *dir = to_world(uniform_cone(u, p->origin[3], p->axis[3]), axis);
    }
    __global const GpuLight* light = &lights[p->light];
    float falloff = light->kind == LIGHT_SPOT
                        ? light_spot_falloff(*dir, light)
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
    // no caster ball on the first segment, so no caster first: no ray traced
    if (!ray_meets_caster_spheres(p, origin, dir)) return PATH_NO_SPECULAR;
    // the photon's wavelength (micrometres) from its first dispersive surface on
    float wavelength = 0.0f;
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
            if (DISPERSION && m->dispersion != 0.0f) {
                // First dispersive surface: a wavelength and its colour; the expected flux
                // per channel is unchanged.
                if (wavelength == 0.0f)
                    wavelength = disperse(&flux, p->dispersion_mode, p->seed, index,
                                          random_f32(p->seed, index, bounce, 3u));
                ior = dispersive_ior(m->ior, m->dispersion, m->ior_model, wavelength);
            }
            dir = dielectric_scatter(dir, s.shading_normal, entering, ior,
                                     random_f32(p->seed, index, bounce, 2u), p->fresnel_model);
        }
        // (a variant without DIELECTRIC is never run on a dielectric: the frame plan)
        if (max_element3(flux) < min_power || max_element3(flux) <= 0.0f) return PATH_NEGLIGIBLE;
        float3 side = dot3(dir, s.geometric_normal) > 0.0f ? s.geometric_normal : -s.geometric_normal;
        origin = offset_ray_origin(s.position, side);
    }
    *rays = p->max_bounces;
    return PATH_BOUNCE_LIMIT;
}

inline void count_end(int end, const Photon* ph, float flux_quantum, __local uint* lc);

// Adds one path end to the photon buffer (or the atlas) and the work-group's counters.
inline void record_end(int end, const Photon* ph, float flux_quantum, __global Photon* photons,
                       uint photon_capacity, volatile __global uint* photon_count,
                       FUSED_DEPOSIT_PARAMS, __local uint* lc) {
    if (end == PATH_STORED) {
        if (FUSED_DEPOSIT && SURFACE_STORE) {
            deposit_atlas_photon(ATLAS_DEPOSIT_ARGS, centroids, lc, ph);
        } else if (FUSED_DEPOSIT) {
            deposit_screen_photon(SCREEN_DEPOSIT_ARGS, lc, ph);
        } else {
            uint slot = atomic_inc(photon_count);
            // The host never dispatches more photons than the buffer holds.
            if (slot < photon_capacity) photons[slot] = *ph;
        }
    }
    count_end(end, ph, flux_quantum, lc);
}

// The slot an adaptive photon leaves (backend-cpu trace_photons.rs::cluster_slot).
inline Photon cluster_slot(int end, uint rays, const Photon* ph) {
    Photon s = *ph;
    if (end == PATH_STORED) {
        // texture space marks the stored slot; world space keeps its point
        if (SURFACE_STORE) s.position[2] = 1.0f;
        return s;
    }
    store3(s.position, (float3)(0.0f, 0.0f, photon_met_caster((uint)end, rays) ? 1.0f : 0.0f));
    s.hit_distance = 0.0f;
    store3(s.flux, (float3)(0.0f, 0.0f, 0.0f));
    s.direction = NO_TRIANGLE;
    return s;
}

// Adds one path end to the work-group's counters.
inline void count_end(int end, const Photon* ph, float flux_quantum, __local uint* lc) {
    if (end == PATH_STORED) {
        count_stored(ph, flux_quantum, lc);
    } else {
        atomic_inc(&lc[end == PATH_NO_SPECULAR  ? COUNTER_NO_SPECULAR
                      : end == PATH_ESCAPED     ? COUNTER_ESCAPED
                      : end == PATH_NEGLIGIBLE  ? COUNTER_NEGLIGIBLE
                                                : COUNTER_BOUNCE_LIMIT]);
    }
}

// The photon a path stores at surface `s` of `hit` (world or texture space).
inline Photon stored_photon(const SurfacePoint* s, const Hit* hit, float3 flux, float3 dir) {
    Photon ph;
    ph.hit_distance = hit->t;
    store3(ph.flux, flux);
    if (SURFACE_STORE) {
        store3(ph.position, (float3)(s->uv.x, s->uv.y, 0.0f));
        ph.direction = hit->triangle;
    } else {
        store3(ph.position, s->position);
        ph.direction = pack_unit_vector(dir);
    }
    return ph;
}

typedef struct {
    float3 origin;
    float3 dir;
    float3 flux;
    uint bounce;
    float wavelength; // micrometres; 0 until the first dispersive surface
} Branch;

inline Branch branch(float3 origin, float3 dir, float3 flux, uint bounce, float wavelength) {
    Branch b;
    b.origin = origin;
    b.dir = dir;
    b.flux = flux;
    b.bounce = bounce;
    b.wavelength = wavelength;
    return b;
}

#define RECORD(end, ph)                                                                    \
    record_end(end, ph, p->flux_quantum, photons, photon_capacity, photon_count,            \
               FUSED_DEPOSIT_ARGS, lc)

// One emitted photon with Vanderstichelen 2021's deterministic splits (backend-cpu
// trace_photons.rs::trace_photon_split, same order and decisions): records every branch's
// end; returns the ray segments traced, writes the branches added.
inline uint trace_photon_split(SCENE_PARAMS, __global const TraceParams* p, uint index,
                               __global Photon* photons, uint photon_capacity,
                               volatile __global uint* photon_count, FUSED_DEPOSIT_PARAMS,
                               __local uint* lc, uint* splits) {
    float3 origin, dir, flux;
    emit_photon(lights, p, index, &origin, &dir, &flux);
    float emitted_max = max_element3(load3g(p->photon_flux));
    float min_power = p->photon_flux[3] * emitted_max;
    Photon none;
    *splits = 0u;
    if (max_element3(flux) <= 0.0f || max_element3(flux) < min_power) {
        RECORD(PATH_NEGLIGIBLE, &none);
        return 0u;
    }
    if (!ray_meets_caster_spheres(p, origin, dir)) {
        RECORD(PATH_NO_SPECULAR, &none);
        return 0u;
    }
    uint budget = clamp(p->split_budget, 1u, (uint)MAX_SPLIT_BRANCHES);
    Branch stack[MAX_SPLIT_BRANCHES];
    uint sp = 0u;
    stack[sp++] = branch(origin, dir, flux, 0u, 0.0f);
    uint rays = 0u, branches = 1u;
    while (sp > 0u) {
        Branch b = stack[--sp];
        for (;;) {
            if (b.bounce >= p->max_bounces) {
                RECORD(PATH_BOUNCE_LIMIT, &none);
                break;
            }
            rays++;
            Hit hit;
            if (!closest_hit(nodes, node_count, vertices, triangles, b.origin, b.dir, INFINITY, &hit)) {
                RECORD(PATH_ESCAPED, &none);
                break;
            }
            SurfacePoint s = hit_surface(vertices, triangles, &hit);
            __global const GpuMaterial* m = &materials[triangles[hit.triangle].material];
            bool entering = dot3(b.dir, s.geometric_normal) < 0.0f;
            if (ABSORPTION && m->kind == MATERIAL_DIELECTRIC && !entering)
                b.flux *= beer_lambert(load3g(m->absorption), hit.t);
            uint bounce = b.bounce;
            b.bounce += 1u;
            float3 facing = facing_normal(s.shading_normal, b.dir);
            if (m->kind == MATERIAL_DIFFUSE) {
                if (bounce == 0u) {
                    RECORD(PATH_NO_SPECULAR, &none);
                } else {
                    Photon ph = stored_photon(&s, &hit, b.flux, b.dir);
                    RECORD(PATH_STORED, &ph);
                }
                break;
            }
            if (m->kind == MATERIAL_MIRROR) {
                b.flux *= load3g(m->color);
                b.dir = normalize3(reflect(b.dir, facing));
                if (max_element3(b.flux) < min_power || max_element3(b.flux) <= 0.0f) {
                    RECORD(PATH_NEGLIGIBLE, &none);
                    break;
                }
                float3 side = dot3(b.dir, s.geometric_normal) > 0.0f ? s.geometric_normal
                                                                     : -s.geometric_normal;
                b.origin = offset_ray_origin(s.position, side);
                continue;
            }
            // a dielectric: the lanes this surface continues, each split by its Fresnel
            Branch lanes[3] = {b, b, b};
            uint n_lanes = 1u;
            if (DISPERSION && m->dispersion != 0.0f && b.wavelength == 0.0f) {
                if (branches + 2u <= budget) {
                    branches += 2u;
                    n_lanes = 3u;
                    for (uint k = 0u; k < 3u; k++)
                        lanes[k].wavelength =
                            split_lane(&lanes[k].flux, p->dispersion_mode, p->seed, index, k);
                } else {
                    lanes[0].wavelength = disperse(&lanes[0].flux, p->dispersion_mode, p->seed,
                                                   index, random_f32(p->seed, index, bounce, 3u));
                }
            }
            for (uint k = 0u; k < n_lanes; k++) {
                Branch lane = lanes[k];
                float ior = m->ior;
                if (DISPERSION && m->dispersion != 0.0f && lane.wavelength != 0.0f)
                    ior = dispersive_ior(m->ior, m->dispersion, m->ior_model, lane.wavelength);
                float eta = entering ? 1.0f / ior : ior;
                float f = fresnel_reflectance(-dot3(b.dir, facing), eta, p->fresnel_model);
                float3 reflected = reflect(b.dir, facing);
                float3 cdir[2] = {reflected, reflected};
                float3 cflux[2] = {lane.flux, lane.flux};
                uint n_children = 1u;
                float3 t;
                if (refract(b.dir, facing, eta, &t)) {
                    if (branches < budget) {
                        branches += 1u;
                        cflux[0] = lane.flux * f;
                        cdir[1] = normalize3(t);
                        cflux[1] = lane.flux * (1.0f - f);
                        n_children = 2u;
                    } else if (random_f32(p->seed, index, bounce, 2u) >= f) {
                        cdir[0] = normalize3(t);
                    }
                }
                for (uint j = 0u; j < n_children; j++) {
                    float3 cf = cflux[j];
                    if (max_element3(cf) < min_power || max_element3(cf) <= 0.0f) {
                        RECORD(PATH_NEGLIGIBLE, &none);
                        continue;
                    }
                    float3 side = dot3(cdir[j], s.geometric_normal) > 0.0f ? s.geometric_normal
                                                                          : -s.geometric_normal;
                    if (sp < MAX_SPLIT_BRANCHES)
                        stack[sp++] = branch(offset_ray_origin(s.position, side), cdir[j], cf,
                                             b.bounce, lane.wavelength);
                }
            }
            break;
        }
    }
    *splits = branches - 1u;
    return rays;
}

__kernel void trace_photons(SCENE_PARAMS, __global const TraceParams* p,
                            __global Photon* photons, uint photon_capacity,
                            volatile __global uint* photon_count,
                            volatile __global uint* counters, __global const uint* clusters,
                            FUSED_DEPOSIT_PARAMS) {
    __local uint lc[COUNTER_WORDS];
    counters_clear_local(lc);
    uint i = get_global_id(0);
    if (i < p->count) {
        // the adaptive batch's live clusters: photon_count[0] is its list's length
        if (ADAPTIVE && i < 4u * live_clusters(photon_count[0], p->first, p->count / 4u)) {
            uint index = cluster_photon_index(entry_cluster(clusters[p->first + i / 4u]), i % 4u,
                                              p->grid_w);
            Photon ph;
            uint rays;
            int end = trace_photon(SCENE_ARGS, p, index, &ph, &rays);
            atomic_add_u64_local(&lc[COUNTER_RAYS], rays);
            if (FUSED_DEPOSIT) {
                // a level whose every cluster is output: deposited, no slot
                RECORD(end, &ph);
            } else {
                if (i < photon_capacity) photons[i] = cluster_slot(end, rays, &ph);
                count_end(end, &ph, p->flux_quantum, lc);
            }
        } else if (ADAPTIVE) {
            // past the list's live clusters: nothing to trace
        } else if (FRESNEL_SPLIT) {
            uint splits;
            // grid photon in tile order (sampling.cl)
            uint index = tiled_photon_index(p->first + i, p->grid_w, p->grid_h);
            uint rays = trace_photon_split(SCENE_ARGS, p, index, photons, photon_capacity,
                                           photon_count, FUSED_DEPOSIT_ARGS, lc,
                                           &splits);
            atomic_add_u64_local(&lc[COUNTER_RAYS], rays);
            atomic_add(&lc[COUNTER_SPLITS], splits);
        } else {
            Photon ph;
            uint rays;
            uint index = tiled_photon_index(p->first + i, p->grid_w, p->grid_h);
            int end = trace_photon(SCENE_ARGS, p, index, &ph, &rays);
            atomic_add_u64_local(&lc[COUNTER_RAYS], rays);
            RECORD(end, &ph);
        }
    }
    counters_flush_local(lc, counters);
}

// trace_indirect (Smal 2019, section 24.2.2): photon p->first + coherent_sample_order(i) of
// the RSM photons is traced with Russian roulette at diffuse bounces and stored (culled to
// the camera's view and facing side, counted per screen tile) at every diffuse hit after
// its first bounce.
// Mirror of backend-cpu/src/kernels/trace_indirect.rs (trace_indirect_path, store_indirect) and
// shaders/wgsl/trace_indirect.wgsl: same random dimensions (per segment: 0, 1 bounce
// direction, 2 roulette, 3 Fresnel, 4 channel of three bands), same decisions. Photons are 32-byte slots,
// two uint4 each: GiPhoton (p->store 0) or Photon (1), appended in arrival order.
// Compiled variant (not a branch): `-D WAVES=0/1` (core's TRACE_INDIRECT_SWITCHES); 1 traces
// one wave of segments p->segment_first .. p->segment_end, from the RSM photons or the
// queued paths (sorted: in sort_indirect_paths' order, p->queue_order), and queues the
// paths still going (sorted: each with its sort key and rank, p->queue_keys).
#ifndef WAVES
#define WAVES 0
#endif

inline void store_indirect(__global const IndirectTraceParams* p, float3 position,
                           float3 geometric_normal, float3 dir, float ray_length, float3 flux,
                           __global uint4* photons, uint photon_capacity,
                           volatile __global uint* photon_count,
                           volatile __global uint* tile_counts,
                           GATHER_GBUFFER_PARAMS(__global const), __local uint* lc) {
    float3 n = dot3(geometric_normal, dir) > 0.0f ? -geometric_normal : geometric_normal;
    if (dot3(load3g(p->camera.position) - position, n) <= 0.0f) {
        atomic_inc(&lc[COUNTER_DEPTH_MISMATCH]);
        return;
    }
    uint px, py;
    float z;
    if (!project_to_pixel(&p->camera, position, &px, &py, &z)) {
        atomic_inc(&lc[COUNTER_OFF_SCREEN]);
        return;
    }
    // the camera must see the photon's surface there (core's VISIBLE_TOLERANCE)
    uint pix = py * p->camera.width + px;
    uint4 g0 = gbuffer0[pix], g1 = gbuffer1[pix];
    if ((gbuffer3[pix].w & GBUFFER_RECEIVER) == 0u ||
        off_surface(z, position, (float3)(as_float(g0.x), as_float(g0.y), as_float(g0.z)),
                    (float3)(as_float(g1.x), as_float(g1.y), as_float(g1.z)), as_float(g0.w),
                    VISIBLE_TOLERANCE)) {
        atomic_inc(&lc[COUNTER_DEPTH_MISMATCH]);
        return;
    }
    uint tile = screen_tile(px, py, p->camera.width, p->tile_size);
    uint4 a, b;
    if (p->store == GI_STORE_FLOAT) {
        a = (uint4)(as_uint(position.x), as_uint(position.y), as_uint(position.z),
                    as_uint(ray_length));
        b = (uint4)(as_uint(flux.x), as_uint(flux.y), as_uint(flux.z), pack_unit_vector(dir));
    } else {
        uint power = pack_rgb9e5(flux / p->power_scale);
        if ((power & 0x07ffffffu) == 0u) atomic_inc(&lc[COUNTER_UNDERFLOW]);
        a = (uint4)(as_uint(position.x), as_uint(position.y), as_uint(position.z), power);
        b = (uint4)(pack_unit_vector(n), pack_unit_vector(dir), as_uint(ray_length), tile);
    }
    Photon stored = {{0.0f, 0.0f, 0.0f}, 0.0f, {flux.x, flux.y, flux.z}, 0u};
    count_stored(&stored, p->flux_quantum, lc);
    uint slot = atomic_inc(&photon_count[0]);
    // the host sizes the buffer for every photon a launch can store
    if (slot < photon_capacity) {
        photons[2u * slot] = a;
        photons[2u * slot + 1u] = b;
    }
    atomic_inc(&tile_counts[tile]);
}

// The path of RSM photon `index` before its first segment (backend-cpu
// trace_indirect.rs::indirect_path_from_rsm); false (counted negligible) without flux.
inline bool indirect_path_from_rsm(RsmPhoton r, uint index, IndirectPath* path,
                                   __local uint* lc) {
    if (!(max_element3(load3(r.flux)) > 0.0f)) {
        atomic_inc(&lc[COUNTER_NEGLIGIBLE]);
        return false;
    }
    store3(path->origin, load3(r.origin));
    path->index = index;
    store3(path->direction, unpack_unit_vector(r.direction));
    path->bounces = r.bounces;
    store3(path->flux, load3(r.flux));
    path->wavelength = 0.0f;
    return true;
}

// Segments p->segment_first .. p->segment_end of `path` (backend-cpu
// trace_indirect.rs::trace_indirect_segments); adds the rays traced to *rays and returns
// whether the path goes on after the last of them (`path` then holds its next segment's
// state; its end is counted otherwise).
inline bool trace_indirect_segments(SCENE_PARAMS, __global const IndirectTraceParams* p,
                                    IndirectPath* path, __global uint4* photons,
                                    uint photon_capacity, volatile __global uint* photon_count,
                                    volatile __global uint* tile_counts,
                                    GATHER_GBUFFER_PARAMS(__global const), __local uint* lc,
                                    uint* rays) {
    uint index = path->index;
    float3 flux = load3(path->flux);
    float3 origin = load3(path->origin);
    float3 dir = load3(path->direction);
    uint bounces = path->bounces;
    // the photon's wavelength (micrometres) from its first dispersive surface on (0: none
    // yet)
    float wavelength = path->wavelength;
    for (uint segment = p->segment_first; segment < p->segment_end; segment++) {
        *rays += 1u;
        Hit hit;
        if (!closest_hit(nodes, node_count, vertices, triangles, origin, dir, INFINITY, &hit)) {
            atomic_inc(&lc[COUNTER_ESCAPED]);
            return false;
        }
        SurfacePoint s = hit_surface(vertices, triangles, &hit);
        __global const GpuMaterial* m = &materials[triangles[hit.triangle].material];
        bool entering = dot3(dir, s.geometric_normal) < 0.0f;
        if (m->kind == MATERIAL_DIELECTRIC && !entering)
            flux *= beer_lambert(load3g(m->absorption), hit.t);
        float3 facing = facing_normal(s.shading_normal, dir);
        if (m->kind == MATERIAL_DIFFUSE) {
            if (bounces >= 1u)
                store_indirect(p, s.position, s.geometric_normal, dir, hit.t, flux, photons,
                               photon_capacity, photon_count, tile_counts, GATHER_GBUFFER_ARGS, lc);
            if (bounces >= p->max_bounces) {
                atomic_inc(&lc[COUNTER_BOUNCE_LIMIT]);
                return false;
            }
            float4 rr = russian_roulette(flux, load3g(m->color),
                                         random_f32(p->seed, index, segment, 2u));
            if (rr.w == 0.0f) {
                atomic_inc(&lc[COUNTER_NEGLIGIBLE]);
                return false;
            }
            flux = rr.xyz;
            float2 u = (float2)(random_f32(p->seed, index, segment, 0u),
                                random_f32(p->seed, index, segment, 1u));
            dir = cosine_hemisphere(u, facing);
            bounces += 1u;
        } else if (m->kind == MATERIAL_MIRROR) {
            flux *= load3g(m->color);
            dir = normalize3(reflect(dir, facing));
        } else {
            float ior = m->ior;
            if (m->dispersion != 0.0f) {
                // first dispersive surface: a wavelength and its colour
                if (wavelength == 0.0f)
                    wavelength = disperse(&flux, p->dispersion_mode, p->seed, index,
                                          random_f32(p->seed, index, segment, 4u));
                ior = dispersive_ior(m->ior, m->dispersion, m->ior_model, wavelength);
            }
            dir = dielectric_scatter(dir, s.shading_normal, entering, ior,
                                     random_f32(p->seed, index, segment, 3u), p->fresnel_model);
        }
        if (!(max_element3(flux) > 0.0f)) {
            atomic_inc(&lc[COUNTER_NEGLIGIBLE]);
            return false;
        }
        float3 side = dot3(dir, s.geometric_normal) > 0.0f ? s.geometric_normal : -s.geometric_normal;
        origin = offset_ray_origin(s.position, side);
    }
    store3(path->origin, origin);
    store3(path->direction, dir);
    path->bounces = bounces;
    store3(path->flux, flux);
    path->wavelength = wavelength;
    return true;
}

__kernel void trace_indirect(SCENE_PARAMS, __global const IndirectTraceParams* p,
                             __global const RsmPhoton* rsm_photons, __global uint4* photons,
                             uint photon_capacity, volatile __global uint* photon_count,
                             volatile __global uint* tile_counts,
                             volatile __global uint* counters,
                             GATHER_GBUFFER_PARAMS(__global const),
                             __global const IndirectPath* paths_in,
                             __global IndirectPath* paths_out, uint path_capacity,
                             volatile __global uint* path_counts, __global uint2* path_keys,
                             volatile __global uint* buckets, __global const uint* order) {
    __local uint lc[COUNTER_WORDS];
    counters_clear_local(lc);
    uint i = get_global_id(0);
    IndirectPath path;
    bool live;
    if (!WAVES || p->segment_first == 0u) {
        // a warp's samples in one small box of the Hammersley square (its RSM photons
        // near each other), not a column across it
        // (the launch's chunk of the light's photons)
        uint n = chunk_photons(p->count, p->chunk_first, p->chunk_size);
        live = i < n;
        if (live) {
            uint index = p->first + p->chunk_first + coherent_sample_order(i, n);
            live = indirect_path_from_rsm(rsm_photons[index], index, &path, lc);
        }
    } else {
        // a later wave: the paths the one before queued
        live = i < min(path_counts[p->segment_first], path_capacity);
        // sorted: the queue in its keys' order (sort_indirect_paths; an entry past the
        // queue, which no sort writes, is no path)
        uint q = live && p->queue_order != 0u ? order[i] : i;
        live = live && q < path_capacity;
        if (live) path = paths_in[q];
    }
    if (live) {
        uint rays = 0u;
        bool going = trace_indirect_segments(SCENE_ARGS, p, &path, photons, photon_capacity,
                                             photon_count, tile_counts, GATHER_GBUFFER_ARGS,
                                             lc, &rays);
        atomic_add_u64_local(&lc[COUNTER_RAYS], rays);
        if (going) {
            if (!WAVES || p->segment_end >= p->max_segments) {
                atomic_inc(&lc[COUNTER_BOUNCE_LIMIT]);
            } else {
                // the queue holds every path of the launch; a slot past it is not written
                uint slot = atomic_inc(&path_counts[p->segment_end]);
                if (slot < path_capacity) {
                    paths_out[slot] = path;
                    if (p->queue_keys != 0u) {
                        // its key and rank among the queue's paths of that key, for the
                        // sort before the next wave
                        uint key = path_sort_key(load3(path.origin), load3(path.direction),
                                                 load3g(p->key_origin_min),
                                                 load3g(p->key_origin_scale));
                        path_keys[slot] = (uint2)(key, atomic_inc(&buckets[key]));
                    }
                }
            }
        }
    }
    counters_flush_local(lc, counters);
}

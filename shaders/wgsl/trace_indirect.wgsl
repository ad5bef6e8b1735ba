// needs: layout prelude vector rng sampling optics spectrum packing geometry footprint fixed_point traversal scene photon_gi
// trace_indirect (Smal 2019, section 24.2.2): photon params.first + coherent_sample_order(i)
// of the RSM photons is traced with Russian roulette at diffuse bounces and stored (culled
// to the camera's view and facing side, counted per screen tile) at every diffuse hit
// after its first bounce.
// Mirror of backend-cpu/src/kernels/trace_indirect.rs (trace_indirect_path, store_indirect)
// and backend-opencl/kernels/trace_indirect.cl: same random dimensions (per segment: 0, 1
// bounce direction, 2 roulette, 3 Fresnel, 4 channel of three bands), same decisions. Stored photons are
// appended in arrival order (an atomic slot counter): the set equals the CPU's.
// Photons are 32-byte slots, two vec4<u32> each: GiPhoton (params.store 0) or Photon (1).
// WAVES (the sorted_waves schedule): with params.queue_keys each queued path's sort key
// (path_sort_key of its next ray under key_origin_min and key_origin_scale, photon_gi.wgsl)
// and its rank among the queue's paths of that key (an atomic count in `buckets`) are
// written beside it (path_keys[slot] = (key, rank)), for sort_indirect_paths; with
// params.queue_order thread i of a later wave continues path order[i] of paths_in
// (sort_indirect_paths' order), else path i.

@group(0) @binding(0) var<storage, read> vertices: array<GpuVertex>;
@group(0) @binding(1) var<storage, read> triangles: array<GpuTriangle>;
@group(0) @binding(2) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(3) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(4) var<storage, read> nodes: array<vec4<u32>>;
@group(0) @binding(5) var<uniform> params: IndirectTraceParams;
@group(0) @binding(6) var<storage, read> rsm_photons: array<RsmPhoton>;
@group(0) @binding(7) var<storage, read_write> photons: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read_write> photon_count: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> tile_counts: array<atomic<u32>>;
@group(0) @binding(10) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(11) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(12) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(13) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(14) var<storage, read> paths_in: array<IndirectPath>;
@group(0) @binding(15) var<storage, read_write> paths_out: array<IndirectPath>;
@group(0) @binding(16) var<storage, read_write> path_counts: array<atomic<u32>>;
@group(0) @binding(17) var<storage, read_write> path_keys: array<vec2<u32>>;
@group(0) @binding(18) var<storage, read_write> buckets: array<atomic<u32>>;
@group(0) @binding(19) var<storage, read> order: array<u32>;

// Compiled variant (not a branch; core's TRACE_INDIRECT_SWITCHES): true traces one wave of
// segments params.segment_first .. segment_end, from the RSM photons or the queued paths,
// and queues the paths still going.
override WAVES: bool = false;

// The work-group's counters (fixed_point.wgsl).
var<workgroup> lc: array<atomic<u32>, COUNTER_WORDS>;

// Stores a photon at a diffuse hit if the camera sees its side and it projects into the
// view (backend-cpu trace_indirect.rs::store_indirect).
fn store_indirect(p: IndirectTraceParams, position: vec3<f32>, geometric_normal: vec3<f32>,
                  dir: vec3<f32>, ray_length: f32, flux: vec3<f32>) {
    let n = select(geometric_normal, -geometric_normal, dot3(geometric_normal, dir) > 0.0);
    if (dot3(p.camera.position - position, n) <= 0.0) {
        atomicAdd(&lc[COUNTER_DEPTH_MISMATCH], 1u);
        return;
    }
    var px: u32;
    var py: u32;
    var z: f32;
    if (!project_to_pixel(p.camera, position, &px, &py, &z)) {
        atomicAdd(&lc[COUNTER_OFF_SCREEN], 1u);
        return;
    }
    // the camera must see the photon's surface there (core's VISIBLE_TOLERANCE)
    let pix = py * p.camera.width + px;
    let g0 = gbuffer0[pix];
    if ((gbuffer3[pix].w & GBUFFER_RECEIVER) == 0u ||
        off_surface(z, position, bitcast<vec3<f32>>(g0.xyz), bitcast<vec3<f32>>(gbuffer1[pix].xyz),
                    bitcast<f32>(g0.w), VISIBLE_TOLERANCE)) {
        atomicAdd(&lc[COUNTER_DEPTH_MISMATCH], 1u);
        return;
    }
    let tile = screen_tile(px, py, p.camera.width, p.tile_size);
    var a: vec4<u32>;
    var b: vec4<u32>;
    if (p.store == GI_STORE_FLOAT) {
        a = vec4<u32>(bitcast<vec3<u32>>(position), bitcast<u32>(ray_length));
        b = vec4<u32>(bitcast<vec3<u32>>(flux), pack_unit_vector(dir));
    } else {
        let power = pack_rgb9e5(flux / p.power_scale);
        if ((power & 0x07ffffffu) == 0u) {
            atomicAdd(&lc[COUNTER_UNDERFLOW], 1u);
        }
        a = vec4<u32>(bitcast<vec3<u32>>(position), power);
        b = vec4<u32>(pack_unit_vector(n), pack_unit_vector(dir), bitcast<u32>(ray_length), tile);
    }
    var stored: Photon;
    stored.position = vec3<f32>(0.0);
    stored.hit_distance = 0.0;
    stored.flux = flux;
    stored.direction = 0u;
    count_stored(stored, p.flux_quantum);
    let slot = atomicAdd(&photon_count[0], 1u);
    // The host sizes the buffer for every photon a launch can store.
    if (2u * slot + 1u < arrayLength(&photons)) {
        photons[2u * slot] = a;
        photons[2u * slot + 1u] = b;
    }
    atomicAdd(&tile_counts[tile], 1u);
}

// The path of RSM photon `index` before its first segment (backend-cpu
// trace_indirect.rs::indirect_path_from_rsm); false (counted negligible) without flux.
fn indirect_path_from_rsm(r: RsmPhoton, index: u32, path: ptr<function, IndirectPath>) -> bool {
    if (!(max_element3(r.flux) > 0.0)) {
        atomicAdd(&lc[COUNTER_NEGLIGIBLE], 1u);
        return false;
    }
    (*path).origin = r.origin;
    (*path).index = index;
    (*path).direction = unpack_unit_vector(r.direction);
    (*path).bounces = r.bounces;
    (*path).flux = r.flux;
    (*path).wavelength = 0.0;
    return true;
}

// Segments p.segment_first .. p.segment_end of `path` (backend-cpu
// trace_indirect.rs::trace_indirect_segments); adds the rays traced to *rays and returns
// whether the path goes on after the last of them (`path` then holds its next segment's
// state; its end is counted otherwise).
fn trace_indirect_segments(p: IndirectTraceParams, path: ptr<function, IndirectPath>,
                           rays: ptr<function, u32>) -> bool {
    let index = (*path).index;
    var flux = (*path).flux;
    var origin = (*path).origin;
    var dir = (*path).direction;
    var bounces = (*path).bounces;
    // the photon's wavelength (micrometres) from its first dispersive surface on (0: none
    // yet)
    var wavelength = (*path).wavelength;
    for (var segment = p.segment_first; segment < p.segment_end; segment++) {
        *rays += 1u;
        var hit: Hit;
        if (!closest_hit(origin, dir, NO_T_MAX, &hit)) {
            atomicAdd(&lc[COUNTER_ESCAPED], 1u);
            return false;
        }
        let s = hit_surface(hit);
        let m = materials[triangles[hit.triangle].material];
        let entering = dot3(dir, s.geometric_normal) < 0.0;
        if (m.kind == MATERIAL_DIELECTRIC && !entering) {
            flux *= beer_lambert(m.absorption.xyz, hit.t);
        }
        let facing = facing_normal(s.shading_normal, dir);
        if (m.kind == MATERIAL_DIFFUSE) {
            if (bounces >= 1u) {
                store_indirect(p, s.position, s.geometric_normal, dir, hit.t, flux);
            }
            if (bounces >= p.max_bounces) {
                atomicAdd(&lc[COUNTER_BOUNCE_LIMIT], 1u);
                return false;
            }
            let rr = russian_roulette(flux, m.color.xyz, random_f32(p.seed, index, segment, 2u));
            if (rr.w == 0.0) {
                atomicAdd(&lc[COUNTER_NEGLIGIBLE], 1u);
                return false;
            }
            flux = rr.xyz;
            let u = vec2<f32>(random_f32(p.seed, index, segment, 0u),
                              random_f32(p.seed, index, segment, 1u));
            dir = cosine_hemisphere(u, facing);
            bounces += 1u;
        } else if (m.kind == MATERIAL_MIRROR) {
            flux *= m.color.xyz;
            dir = normalize3(reflect(dir, facing));
        } else {
            var ior = m.ior;
            if (m.dispersion != 0.0) {
                if (wavelength == 0.0) {
                    // first dispersive surface: a wavelength and its colour
                    let d = disperse(flux, p.dispersion_mode, p.seed, index,
                                     random_f32(p.seed, index, segment, 4u));
                    wavelength = d.wavelength;
                    flux = d.flux;
                }
                ior = dispersive_ior(m.ior, m.dispersion, m.ior_model, wavelength);
            }
            dir = dielectric_scatter(dir, s.shading_normal, entering, ior,
                                     random_f32(p.seed, index, segment, 3u), p.fresnel_model);
        }
        if (!(max_element3(flux) > 0.0)) {
            atomicAdd(&lc[COUNTER_NEGLIGIBLE], 1u);
            return false;
        }
        let side = select(-s.geometric_normal, s.geometric_normal,
                          dot3(dir, s.geometric_normal) > 0.0);
        origin = offset_ray_origin(s.position, side);
    }
    (*path).origin = origin;
    (*path).direction = dir;
    (*path).bounces = bounces;
    (*path).flux = flux;
    (*path).wavelength = wavelength;
    return true;
}

// `li`: local invocation index. Every invocation reaches the counter helpers' barriers.
fn trace_indirect(i: u32, li: u32) {
    counters_clear_local(li);
    let p = params;
    var path: IndirectPath;
    var live: bool;
    if (!WAVES || p.segment_first == 0u) {
        // a warp's samples in one small box of the Hammersley square (its RSM photons
        // near each other), not a column across it
        // (the launch's chunk of the light's photons)
        let n = chunk_photons(p.count, p.chunk_first, p.chunk_size);
        live = i < n;
        if (live) {
            let index = p.first + p.chunk_first + coherent_sample_order(i, n);
            live = indirect_path_from_rsm(rsm_photons[index], index, &path);
        }
    } else {
        // a later wave: the paths the one before queued (in sort_indirect_paths' order
        // under queue_order)
        live = i < min(atomicLoad(&path_counts[p.segment_first]), arrayLength(&paths_out));
        if (live) {
            var q = i;
            if (p.queue_order != 0u) {
                q = order[i];
            }
            // an entry past the queue, which no sort writes, is no path
            live = q < arrayLength(&paths_out);
            if (live) {
                path = paths_in[q];
            }
        }
    }
    if (live) {
        var rays = 0u;
        let going = trace_indirect_segments(p, &path, &rays);
        atomic_add_u64_local(COUNTER_RAYS, rays);
        if (going) {
            if (!WAVES || p.segment_end >= p.max_segments) {
                atomicAdd(&lc[COUNTER_BOUNCE_LIMIT], 1u);
            } else {
                // the queue holds every path of the launch; a slot past it is not written
                let slot = atomicAdd(&path_counts[p.segment_end], 1u);
                if (slot < arrayLength(&paths_out)) {
                    paths_out[slot] = path;
                    // its next ray's sort key and its rank among the queue's paths of it
                    if (p.queue_keys != 0u) {
                        let key = path_sort_key(path.origin, path.direction,
                                                p.key_origin_min, p.key_origin_scale);
                        let rank = atomicAdd(&buckets[key], 1u);
                        path_keys[slot] = vec2<u32>(key, rank);
                    }
                }
            }
        }
    }
    counters_flush_local(li);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    // `lights` is part of the scene bindings but unused here (the RSM photons carry
    // their light); wgpu derives the bind group layout from the bindings main uses.
    _ = arrayLength(&lights);
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    trace_indirect(i, li);
}

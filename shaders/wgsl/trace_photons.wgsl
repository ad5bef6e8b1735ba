// needs: layout prelude vector rng sampling optics spectrum packing geometry fixed_point traversal scene photon_clusters atlas gbuffer photon_map_add centroid_add atlas_deposit screen_deposit
// trace_photons (Kim 2019, sections 30.3.1.1-2): photon tiled_photon_index(first + i) of
// the light's stratified grid (tile order, sampling.wgsl) is emitted, traced through
// mirrors and dielectrics and stored where it first meets a diffuse surface after at least
// one specular interaction. Mirror of
// backend-opencl/kernels/trace_photons.cl and backend-cpu/src/kernels/trace_photons.rs
// (same random dimensions, same decisions). Stored photons are appended in arrival order
// (an atomic slot counter): the set of photons equals the CPU's, their order does not,
// and every later sum is order-free.
//
// Compiled variants (not branches): pipeline-overridable constants named as core's
// TraceVariant switches; false compiles a material feature out. The backend builds one
// pipeline per variant a frame plan asks for.
override DIELECTRIC: bool = true;
override DISPERSION: bool = true;
override ABSORPTION: bool = true;
// Store policy (core's photon_store): false stores world space (Sspm), true the hit's uv
// and triangle (CausticMap's atlas).
override SURFACE_STORE: bool = false;
// Vanderstichelen 2021's deterministic splits (core's TraceVariant::fresnel_split): both Fresnel
// branches and three lanes (core's spectrum::split_lane) at the first dispersive surface, up to
// params.split_budget branches per photon.
override FRESNEL_SPLIT: bool = false;
// Wyman 2009's adaptive emission (core's TraceVariant::adaptive): photon i is photon i % 4
// of cluster clusters[params.first + i / 4] of the params.grid_w grid and is written to
// slot i, stored or not (core's photon_store says how), or with FUSED_DEPOSIT deposited
// (a level whose every cluster is output); photon_count is left untouched.
override ADAPTIVE: bool = false;
// The fused pass (core's TraceVariant::fused_deposit): a stored photon is deposited where
// its path ends instead of into the photon buffer: with SURFACE_STORE into the caustic
// atlas (CausticMap; atlas_deposit.wgsl), without into the screen photon map (Sspm;
// screen_deposit.wgsl, as deposit_screen adds it).
override FUSED_DEPOSIT: bool = false;

@group(0) @binding(0) var<storage, read> vertices: array<GpuVertex>;
@group(0) @binding(1) var<storage, read> triangles: array<GpuTriangle>;
@group(0) @binding(2) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(3) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(4) var<storage, read> nodes: array<vec4<u32>>;
@group(0) @binding(5) var<uniform> params: TraceParams;
@group(0) @binding(6) var<storage, read_write> photons: array<Photon>;
@group(0) @binding(7) var<storage, read_write> photon_count: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read> clusters: array<u32>;
// the atlas of FUSED_DEPOSIT (otherwise aliases that nobody touches)
@group(0) @binding(10) var<uniform> atlas_params: AtlasParams;
@group(0) @binding(11) var<storage, read> triangle_tiles: array<u32>;
@group(0) @binding(12) var<storage, read> tiles: array<vec4<u32>>;
@group(0) @binding(13) var<storage, read_write> triangle_reach: array<atomic<u32>>;
@group(0) @binding(14) var<storage, read_write> photon_map0: array<atomic<u32>>;
@group(0) @binding(15) var<storage, read_write> photon_map1: array<atomic<u32>>;
@group(0) @binding(16) var<storage, read_write> photon_map2: array<atomic<u32>>;
// the screen of FUSED_DEPOSIT in world space (otherwise aliases that nobody touches)
@group(0) @binding(17) var<uniform> deposit_params: DepositParams;
@group(0) @binding(18) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(19) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(20) var<storage, read> gbuffer2: array<vec4<u32>>;
@group(0) @binding(21) var<storage, read> gbuffer3: array<vec4<u32>>;
// the atlas's centroid sums of FUSED_DEPOSIT (otherwise an alias that nobody touches)
@group(0) @binding(22) var<storage, read_write> centroids: array<atomic<u32>>;

// The work-group's counters (fixed_point.wgsl), OpenCL's `__local uint lc[COUNTER_WORDS]`.
var<workgroup> lc: array<atomic<u32>, COUNTER_WORDS>;

const PATH_STORED: i32 = 0;
const PATH_NO_SPECULAR: i32 = 1;
const PATH_ESCAPED: i32 = 2;
const PATH_NEGLIGIBLE: i32 = 3;
const PATH_BOUNCE_LIMIT: i32 = 4;

// core::math::geometry::ray_meets_caster_spheres over the batch's caster balls (core's
// device::caster_spheres): a first segment that meets none cannot meet a caster first.
fn ray_meets_caster_spheres(origin: vec3<f32>, dir: vec3<f32>) -> bool {
    let count = params.caster_sphere_count;
    if (count == 0u) {
        return true;
    }
    for (var k = 0u; k < min(count, MAX_CASTER_SPHERES); k++) {
        if (ray_meets_sphere(origin, dir, params.caster_spheres[k])) {
            return true;
        }
    }
    return false;
}

// The emitted ray and flux of photon `index` (global index in the light's grid).
fn emit_photon(p: TraceParams, index: u32, origin: ptr<function, vec3<f32>>,
               dir: ptr<function, vec3<f32>>, flux: ptr<function, vec3<f32>>) {
    let ix = index % p.grid_w;
    let iy = index / p.grid_w;
    let jitter = vec2<f32>(stratum_jitter(p.jitter_seed, index, 0u, p.stratum),
                           stratum_jitter(p.jitter_seed, index, 1u, p.stratum));
    let u = stratified_cell(ix, iy, p.grid_w, p.grid_h, jitter);
    *flux = p.photon_flux.xyz;
    let axis = p.axis.xyz;
    if (p.emission == EMISSION_RECTANGLE) {
        *origin = p.origin.xyz + u.x * p.rect_u.xyz + u.y * p.rect_v.xyz;
        *dir = axis;
        return;
    }
    if (p.emission == EMISSION_VIEW_PLANE) {
        *dir = view_plane_direction(axis, p.rect_u.xyz, p.rect_v.xyz, u);
        *flux = *flux * view_plane_texel_weight(ix, iy, p.grid_w, p.grid_h, p.rect_u.w, p.rect_v.w);
    } else {
        *dir = to_world(uniform_cone(u, p.origin.w, p.axis.w), axis);
    }
    let light = lights[p.light];
    var falloff = 1.0;
    if (light.kind == LIGHT_SPOT) {
        falloff = light_spot_falloff(*dir, light);
    }
    *origin = p.origin.xyz;
    *flux = *flux * falloff;
}

// Traces one photon: returns how the path ended, writes the stored photon and the number
// of ray segments traced.
fn trace_photon(p: TraceParams, index: u32, ph: ptr<function, Photon>,
                rays: ptr<function, u32>) -> i32 {
    var origin: vec3<f32>;
    var dir: vec3<f32>;
    var flux: vec3<f32>;
    emit_photon(p, index, &origin, &dir, &flux);
    let emitted_max = max_element3(p.photon_flux.xyz);
    let min_power = p.photon_flux.w * emitted_max;
    *rays = 0u;
    if (max_element3(flux) <= 0.0 || max_element3(flux) < min_power) {
        return PATH_NEGLIGIBLE;
    }
    if (!ray_meets_caster_spheres(origin, dir)) {
        // no caster ball on the first segment, so no caster first: no ray traced
        return PATH_NO_SPECULAR;
    }
    // the photon's wavelength (micrometres) from its first dispersive surface on
    var wavelength = 0.0;
    for (var bounce = 0u; bounce < p.max_bounces; bounce++) {
        *rays = bounce + 1u;
        var hit: Hit;
        if (!closest_hit(origin, dir, NO_T_MAX, &hit)) {
            return PATH_ESCAPED;
        }
        let s = hit_surface(hit);
        let m = materials[triangles[hit.triangle].material];
        let entering = dot3(dir, s.geometric_normal) < 0.0;
        if (ABSORPTION && m.kind == MATERIAL_DIELECTRIC && !entering) {
            flux *= beer_lambert(m.absorption.xyz, hit.t);
        }
        if (m.kind == MATERIAL_DIFFUSE) {
            // every earlier segment ended at a mirror or dielectric
            if (bounce == 0u) {
                return PATH_NO_SPECULAR;
            }
            (*ph).hit_distance = hit.t;
            (*ph).flux = flux;
            if (SURFACE_STORE) {
                (*ph).position = vec3<f32>(s.uv.x, s.uv.y, 0.0);
                (*ph).direction = hit.triangle;
            } else {
                (*ph).position = s.position;
                (*ph).direction = pack_unit_vector(dir);
            }
            return PATH_STORED;
        } else if (m.kind == MATERIAL_MIRROR) {
            flux *= m.color.xyz;
            let n = facing_normal(s.shading_normal, dir);
            dir = normalize3(reflect(dir, n));
        } else if (DIELECTRIC) {
            var ior = m.ior;
            if (DISPERSION && m.dispersion != 0.0) {
                if (wavelength == 0.0) {
                    // First dispersive surface: a wavelength and its colour; the expected
                    // flux per channel is unchanged.
                    let d = disperse(flux, p.dispersion_mode, p.seed, index,
                                     random_f32(p.seed, index, bounce, 3u));
                    wavelength = d.wavelength;
                    flux = d.flux;
                }
                ior = dispersive_ior(m.ior, m.dispersion, m.ior_model, wavelength);
            }
            dir = dielectric_scatter(dir, s.shading_normal, entering, ior,
                                     random_f32(p.seed, index, bounce, 2u), p.fresnel_model);
        }
        if (max_element3(flux) < min_power || max_element3(flux) <= 0.0) {
            return PATH_NEGLIGIBLE;
        }
        let side = select(-s.geometric_normal, s.geometric_normal,
                          dot3(dir, s.geometric_normal) > 0.0);
        origin = offset_ray_origin(s.position, side);
    }
    *rays = p.max_bounces;
    return PATH_BOUNCE_LIMIT;
}

// The photon a path stores at surface `s` of `hit` (world or texture space).
fn stored_photon(s: SurfacePoint, hit: Hit, flux: vec3<f32>, dir: vec3<f32>) -> Photon {
    var ph: Photon;
    ph.hit_distance = hit.t;
    ph.flux = flux;
    if (SURFACE_STORE) {
        ph.position = vec3<f32>(s.uv.x, s.uv.y, 0.0);
        ph.direction = hit.triangle;
    } else {
        ph.position = s.position;
        ph.direction = pack_unit_vector(dir);
    }
    return ph;
}

// Adds one path end to the photon buffer (or the atlas) and the work-group's counters.
fn record_end(end: i32, ph: Photon, flux_quantum: f32) {
    if (end == PATH_STORED) {
        if (FUSED_DEPOSIT && SURFACE_STORE) {
            let a = atlas_params;
            deposit_atlas_photon(ph, a.width, a.flux_quantum, a.hit_distance_quantum);
        } else if (FUSED_DEPOSIT) {
            deposit_screen_photon(ph, deposit_params);
        } else {
            let slot = atomicAdd(&photon_count[0], 1u);
            // The host never dispatches more photons than the buffer holds.
            if (slot < arrayLength(&photons)) {
                photons[slot] = ph;
            }
        }
    }
    count_end(end, ph, flux_quantum);
}

// The slot an adaptive photon leaves (backend-cpu trace_photons.rs::cluster_slot).
fn cluster_slot(end: i32, rays: u32, ph: Photon) -> Photon {
    var s = ph;
    if (end == PATH_STORED) {
        // texture space marks the stored slot; world space keeps its point
        if (SURFACE_STORE) {
            s.position.z = 1.0f;
        }
        return s;
    }
    s.position = vec3<f32>(0.0f, 0.0f, select(0.0f, 1.0f, photon_met_caster(u32(end), rays)));
    s.hit_distance = 0.0f;
    s.flux = vec3<f32>(0.0f, 0.0f, 0.0f);
    s.direction = NO_TRIANGLE;
    return s;
}

// Adds one path end to the work-group's counters.
fn count_end(end: i32, ph: Photon, flux_quantum: f32) {
    if (end == PATH_STORED) {
        count_stored(ph, flux_quantum);
    } else {
        var word = COUNTER_BOUNCE_LIMIT;
        if (end == PATH_NO_SPECULAR) {
            word = COUNTER_NO_SPECULAR;
        } else if (end == PATH_ESCAPED) {
            word = COUNTER_ESCAPED;
        } else if (end == PATH_NEGLIGIBLE) {
            word = COUNTER_NEGLIGIBLE;
        }
        atomicAdd(&lc[word], 1u);
    }
}

struct Branch {
    origin: vec3<f32>,
    dir: vec3<f32>,
    flux: vec3<f32>,
    bounce: u32,
    // micrometres; 0 until the first dispersive surface
    wavelength: f32,
}

// One emitted photon with Vanderstichelen 2021's deterministic splits (backend-cpu
// trace_photons.rs::trace_photon_split, same order and decisions): records every branch's
// end; returns the ray segments traced, writes the branches added.
fn trace_photon_split(p: TraceParams, index: u32, splits: ptr<function, u32>) -> u32 {
    var origin: vec3<f32>;
    var dir: vec3<f32>;
    var flux: vec3<f32>;
    emit_photon(p, index, &origin, &dir, &flux);
    let emitted_max = max_element3(p.photon_flux.xyz);
    let min_power = p.photon_flux.w * emitted_max;
    var none: Photon;
    *splits = 0u;
    if (max_element3(flux) <= 0.0 || max_element3(flux) < min_power) {
        record_end(PATH_NEGLIGIBLE, none, p.flux_quantum);
        return 0u;
    }
    if (!ray_meets_caster_spheres(origin, dir)) {
        record_end(PATH_NO_SPECULAR, none, p.flux_quantum);
        return 0u;
    }
    let budget = clamp(p.split_budget, 1u, MAX_SPLIT_BRANCHES);
    var stack: array<Branch, MAX_SPLIT_BRANCHES>;
    var sp = 0u;
    stack[sp] = Branch(origin, dir, flux, 0u, 0.0);
    sp += 1u;
    var rays = 0u;
    var branches = 1u;
    while (sp > 0u) {
        sp -= 1u;
        var b = stack[sp];
        loop {
            if (b.bounce >= p.max_bounces) {
                record_end(PATH_BOUNCE_LIMIT, none, p.flux_quantum);
                break;
            }
            rays += 1u;
            var hit: Hit;
            if (!closest_hit(b.origin, b.dir, NO_T_MAX, &hit)) {
                record_end(PATH_ESCAPED, none, p.flux_quantum);
                break;
            }
            let s = hit_surface(hit);
            let m = materials[triangles[hit.triangle].material];
            let entering = dot3(b.dir, s.geometric_normal) < 0.0;
            if (ABSORPTION && m.kind == MATERIAL_DIELECTRIC && !entering) {
                b.flux *= beer_lambert(m.absorption.xyz, hit.t);
            }
            let bounce = b.bounce;
            b.bounce += 1u;
            let facing = facing_normal(s.shading_normal, b.dir);
            if (m.kind == MATERIAL_DIFFUSE) {
                if (bounce == 0u) {
                    record_end(PATH_NO_SPECULAR, none, p.flux_quantum);
                } else {
                    record_end(PATH_STORED, stored_photon(s, hit, b.flux, b.dir), p.flux_quantum);
                }
                break;
            }
            if (m.kind == MATERIAL_MIRROR) {
                b.flux *= m.color.xyz;
                b.dir = normalize3(reflect(b.dir, facing));
                if (max_element3(b.flux) < min_power || max_element3(b.flux) <= 0.0) {
                    record_end(PATH_NEGLIGIBLE, none, p.flux_quantum);
                    break;
                }
                let side = select(-s.geometric_normal, s.geometric_normal,
                                  dot3(b.dir, s.geometric_normal) > 0.0);
                b.origin = offset_ray_origin(s.position, side);
                continue;
            }
            // a dielectric: the lanes this surface continues (three at the first dispersive
            // surface while the budget allows), each split by its own Fresnel
            var lanes = array<Branch, 3>(b, b, b);
            var n_lanes = 1u;
            if (DISPERSION && m.dispersion != 0.0 && b.wavelength == 0.0) {
                if (branches + 2u <= budget) {
                    branches += 2u;
                    n_lanes = 3u;
                    for (var k = 0u; k < 3u; k++) {
                        let d = split_lane(b.flux, p.dispersion_mode, p.seed, index, k);
                        lanes[k].wavelength = d.wavelength;
                        lanes[k].flux = d.flux;
                    }
                } else {
                    let d = disperse(b.flux, p.dispersion_mode, p.seed, index,
                                     random_f32(p.seed, index, bounce, 3u));
                    lanes[0].wavelength = d.wavelength;
                    lanes[0].flux = d.flux;
                }
            }
            for (var k = 0u; k < n_lanes; k++) {
                let lane = lanes[k];
                var ior = m.ior;
                if (DISPERSION && m.dispersion != 0.0 && lane.wavelength != 0.0) {
                    ior = dispersive_ior(m.ior, m.dispersion, m.ior_model, lane.wavelength);
                }
                let eta = select(ior, 1.0 / ior, entering);
                let f = fresnel_reflectance(-dot3(b.dir, facing), eta, p.fresnel_model);
                let reflected = reflect(b.dir, facing);
                var cdir = array<vec3<f32>, 2>(reflected, reflected);
                var cflux = array<vec3<f32>, 2>(lane.flux, lane.flux);
                var n_children = 1u;
                var t: vec3<f32>;
                if (refract(b.dir, facing, eta, &t)) {
                    if (branches < budget) {
                        branches += 1u;
                        cflux[0] = lane.flux * f;
                        cdir[1] = normalize3(t);
                        cflux[1] = lane.flux * (1.0 - f);
                        n_children = 2u;
                    } else if (random_f32(p.seed, index, bounce, 2u) >= f) {
                        cdir[0] = normalize3(t);
                    }
                }
                for (var j = 0u; j < n_children; j++) {
                    let cf = cflux[j];
                    if (max_element3(cf) < min_power || max_element3(cf) <= 0.0) {
                        record_end(PATH_NEGLIGIBLE, none, p.flux_quantum);
                        continue;
                    }
                    let side = select(-s.geometric_normal, s.geometric_normal,
                                      dot3(cdir[j], s.geometric_normal) > 0.0);
                    if (sp < MAX_SPLIT_BRANCHES) {
                        stack[sp] = Branch(offset_ray_origin(s.position, side), cdir[j], cf,
                                           b.bounce, lane.wavelength);
                        sp += 1u;
                    }
                }
            }
            break;
        }
    }
    *splits = branches - 1u;
    return rays;
}

// `li`: local invocation index. Called by every invocation of the group (the counter
// helpers hold barriers); invocations past the batch only take part in them.
fn trace_photons(i: u32, li: u32) {
    counters_clear_local(li);
    let p = params;
    if (i < p.count) {
        // the adaptive batch's live clusters: photon_count[0] is its list's length
        if (ADAPTIVE && i < 4u * live_clusters(atomicLoad(&photon_count[0]), p.first, p.count / 4u)) {
            let index = cluster_photon_index(entry_cluster(clusters[p.first + i / 4u]), i % 4u, p.grid_w);
            var ph: Photon;
            var rays: u32;
            let end = trace_photon(p, index, &ph, &rays);
            atomic_add_u64_local(COUNTER_RAYS, rays);
            if (FUSED_DEPOSIT) {
                // a level whose every cluster is output: deposited, no slot
                record_end(end, ph, p.flux_quantum);
            } else {
                if (i < arrayLength(&photons)) {
                    photons[i] = cluster_slot(end, rays, ph);
                }
                count_end(end, ph, p.flux_quantum);
            }
        } else if (ADAPTIVE) {
            // past the list's live clusters: nothing to trace
        } else if (FRESNEL_SPLIT) {
            var splits: u32;
            // grid photon in tile order (sampling.wgsl)
            let index = tiled_photon_index(p.first + i, p.grid_w, p.grid_h);
            let rays = trace_photon_split(p, index, &splits);
            atomic_add_u64_local(COUNTER_RAYS, rays);
            atomicAdd(&lc[COUNTER_SPLITS], splits);
        } else {
            var ph: Photon;
            var rays: u32;
            let index = tiled_photon_index(p.first + i, p.grid_w, p.grid_h);
            let end = trace_photon(p, index, &ph, &rays);
            atomic_add_u64_local(COUNTER_RAYS, rays);
            record_end(end, ph, p.flux_quantum);
        }
    }
    counters_flush_local(li);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    // No early return: every invocation reaches the barriers in trace_photons.
    trace_photons(i, li);
}

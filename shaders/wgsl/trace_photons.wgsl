// needs: types vector rng sampling optics packing geometry fixed_point traversal scene
// trace_photons (seed 000 sections 30.3.1.1-2): photon `first + i` of the light's
// stratified grid is emitted, traced through mirrors and dielectrics and stored where it
// first meets a diffuse surface after at least one specular interaction. Mirror of
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

@group(0) @binding(0) var<storage, read> vertices: array<GpuVertex>;
@group(0) @binding(1) var<storage, read> triangles: array<GpuTriangle>;
@group(0) @binding(2) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(3) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(4) var<storage, read> nodes: array<vec4<u32>>;
@group(0) @binding(5) var<uniform> params: TraceParams;
@group(0) @binding(6) var<storage, read_write> photons: array<Photon>;
@group(0) @binding(7) var<storage, read_write> photon_count: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>>;

// The work-group's counters (fixed_point.wgsl), OpenCL's `__local uint lc[COUNTER_WORDS]`.
var<workgroup> lc: array<atomic<u32>, COUNTER_WORDS>;

const PATH_STORED: i32 = 0;
const PATH_NO_SPECULAR: i32 = 1;
const PATH_ESCAPED: i32 = 2;
const PATH_NEGLIGIBLE: i32 = 3;
const PATH_BOUNCE_LIMIT: i32 = 4;

// The emitted ray and flux of photon `index` (global index in the light's grid).
fn emit_photon(p: TraceParams, index: u32, origin: ptr<function, vec3<f32>>,
               dir: ptr<function, vec3<f32>>, flux: ptr<function, vec3<f32>>) {
    let ix = index % p.grid_w;
    let iy = index / p.grid_w;
    let jitter = vec2<f32>(random_f32(p.seed, index, 0u, 0u), random_f32(p.seed, index, 0u, 1u));
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
        *dir = to_world(uniform_cone(u, p.origin.w), axis);
    }
    let light = lights[p.light];
    var falloff = 1.0;
    if (light.kind == LIGHT_SPOT) {
        falloff = spot_falloff(dot3(*dir, light.direction.xyz), light.cos_inner, light.cos_outer);
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
    var channel = -1;
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
            if (DISPERSION && m.cauchy_b != 0.0) {
                if (channel < 0) {
                    // First dispersive surface: keep one channel, x3 so that the expected
                    // flux per channel is unchanged.
                    channel = min(i32(random_f32(p.seed, index, bounce, 3u) * 3.0), 2);
                    var one = vec3<f32>(0.0, 0.0, 0.0);
                    one[channel] = select(select(flux.z, flux.y, channel == 1), flux.x,
                                          channel == 0) * 3.0;
                    flux = one;
                }
                ior = cauchy_ior(m.ior, m.cauchy_b, CHANNEL_WAVELENGTH_UM[channel]);
            }
            dir = dielectric_scatter(dir, s.shading_normal, entering, ior,
                                     random_f32(p.seed, index, bounce, 2u));
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

// `li`: local invocation index. Called by every invocation of the group (the counter
// helpers hold barriers); invocations past the batch only take part in them.
fn trace_photons(i: u32, li: u32) {
    counters_clear_local(li);
    let p = params;
    let photon_capacity = arrayLength(&photons);
    if (i < p.count) {
        var ph: Photon;
        var rays: u32;
        let end = trace_photon(p, p.first + i, &ph, &rays);
        atomic_add_u64_local(COUNTER_RAYS, rays);
        if (end == PATH_STORED) {
            let slot = atomicAdd(&photon_count[0], 1u);
            // The host never dispatches more photons than the buffer holds.
            if (slot < photon_capacity) {
                photons[slot] = ph;
            }
            atomicAdd(&lc[COUNTER_STORED], 1u);
            for (var ch = 0u; ch < 3u; ch++) {
                let units = quantize(ph.flux[ch], p.flux_quantum).units;
                if (units != 0u) {
                    atomic_add_u64_local(COUNTER_STORED_FLUX + 2u * ch, units);
                }
            }
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
    counters_flush_local(li);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    // No early return: every invocation reaches the barriers in trace_photons.
    trace_photons(i, li);
}

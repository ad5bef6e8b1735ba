// needs: types vector packing fixed_point footprint scene gbuffer photon_map_add sampling photon_gi irradiance_filter
// splat_photons (seed 003 section 24.3, Eqs. 2-9): a thread per stored photon adds its
// ellipsoid splat's irradiance times each covered receiver pixel's area to the photon map
// in fixed point. Mirror of backend-cpu/src/kernels/photon_gi.rs (splat_photon) and
// backend-opencl/kernels/splat_photons.cl.

@group(0) @binding(0) var<uniform> params: SplatParams;
@group(0) @binding(1) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> gbuffer2: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read> photons: array<GiPhoton>;
@group(0) @binding(6) var<storage, read> photon_count: array<u32>;
@group(0) @binding(7) var<storage, read> tile_counts: array<u32>;
@group(0) @binding(8) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> photon_map0: array<atomic<u32>>;
@group(0) @binding(10) var<storage, read_write> photon_map1: array<atomic<u32>>;
@group(0) @binding(11) var<storage, read_write> photon_map2: array<atomic<u32>>;
@group(0) @binding(12) var<storage, read_write> direction_map0: array<atomic<u32>>;
@group(0) @binding(13) var<storage, read_write> direction_map1: array<atomic<u32>>;
@group(0) @binding(14) var<storage, read_write> direction_map2: array<atomic<u32>>;

var<workgroup> lc: array<atomic<u32>, COUNTER_WORDS>;

// atomic_add_photon_map on the direction map's plane `at.x`, index `at.y`.
fn atomic_add_direction_map(at: vec2<u32>, v: u32) -> u32 {
    if (at.x == 0u) {
        return atomicAdd(&direction_map0[at.y], v);
    }
    if (at.x == 1u) {
        return atomicAdd(&direction_map1[at.y], v);
    }
    return atomicAdd(&direction_map2[at.y], v);
}

// atomic_add_u64_photon_map on the direction map.
fn atomic_add_u64_direction_map(pixel: u32, word: u32, lo: u32, hi: u32) {
    let at = deposit_word(pixel, word);
    let old = atomic_add_direction_map(at, lo);
    let carry = u64_carry(old, lo);
    if (hi + carry != 0u) {
        atomic_add_direction_map(vec2<u32>(at.x, at.y + 1u), hi + carry);
    }
}

// backend-cpu photon_gi.rs splat_photon's direction deposit: deposit_photon_texel of
// (flux d.xyz, hit distance d.w) into the direction map, in the flux's quanta, uncounted.
fn deposit_light_direction(texel: u32, d: vec4<f32>, quantum: f32) {
    for (var ch = 0u; ch < 3u; ch++) {
        let units = quantize(d[ch], quantum).units;
        if (units != 0u) {
            atomic_add_u64_direction_map(texel, DEPOSIT_FLUX + 2u * ch, units, 0u);
        }
    }
    atomic_add_u64_direction_map(texel, DEPOSIT_HIT_DISTANCE, quantize(d.w, quantum).units, 0u);
    atomic_add_u64_direction_map(texel, DEPOSIT_PHOTONS, 1u, 0u);
}

fn splat_photon(p: SplatParams, ph: GiPhoton) {
    let power = unpack_rgb9e5(ph.power) * p.power_scale;
    if (!(max_element3(power) > 0.0)) {
        return;
    }
    var px: u32;
    var py: u32;
    var z: f32;
    if (!project_to_pixel(p.camera, ph.position, &px, &py, &z)) {
        return;
    }
    let n = unpack_unit_vector(ph.normal);
    let to_light = -unpack_unit_vector(ph.direction);
    let s = max(ray_length_scale(ph.ray_length, p) *
                density_scale(z, p.tile_constant, tile_counts[ph.tile], p),
                min_splat_scale(z, p.camera.tan_half_fov_y, p.camera.height, p.min_splat_px));
    let kernel = splat_kernel(n, to_light, s, p);
    let e = splat_irradiance(power, kernel);
    let reach = splat_reach_px(p, max_element3(kernel.axes), z);
    if (reach > p.max_splat_px) {
        atomicAdd(&lc[COUNTER_SATURATED], 1u);
    }
    let rect = splat_screen_rect(p.camera, ph.position, kernel, px, py,
                                 min(reach, p.max_splat_px));
    let w = i32(p.camera.width);
    for (var qy = rect.z; qy <= rect.w; qy++) {
        for (var qx = rect.x; qx <= rect.y; qx++) {
            let q = u32(qy * w + qx);
            // each test loads the G-buffer plane it reads, in the tests' order (flags,
            // position, normal): most pixels of the square fail the first two
            let p3 = gbuffer3[q];
            if ((p3.w & GBUFFER_RECEIVER) == 0u) {
                continue;
            }
            let p0 = gbuffer0[q];
            if (!kernel_contains(kernel, ph.position, bitcast<vec3<f32>>(p0.xyz))) {
                continue;
            }
            let p1 = gbuffer1[q];
            if (dot3(bitcast<vec3<f32>>(p1.xyz), n) <= 0.0) {
                continue;
            }
            let t = gbuffer_from_planes(p0, p1, gbuffer2[q], p3);
            let area = gbuffer_pixel_area(p.camera, q, t);
            var splat: Photon;
            splat.position = vec3<f32>(0.0);
            splat.hit_distance = 0.0;
            splat.flux = e * area;
            splat.direction = 0u;
            deposit_photon_texel(q, splat, p.flux_quantum, 1.0);
            if (p.light_direction != 0u &&
                shading_normal_departs(t.normal, unpack_unit_vector(t.geometric_normal))) {
                deposit_light_direction(q, light_direction_deposit(e * area, to_light),
                                        p.flux_quantum);
            }
        }
    }
}

// `li`: local invocation index; every invocation reaches the counter helpers' barriers.
fn splat_photons(i: u32, li: u32) {
    counters_clear_local(li);
    let p = params;
    if (i < min(photon_count[0], arrayLength(&photons))) {
        splat_photon(p, photons[i]);
    }
    counters_flush_local(li);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    splat_photons(i, li);
}

// needs: layout prelude vector packing fixed_point footprint scene gbuffer photon_map_add sampling photon_gi irradiance_filter
// splat_photons (Smal 2019, section 24.3, Eqs. 2-9): each stored photon's ellipsoid splat
// adds its irradiance times each covered receiver pixel's area to the photon map in fixed
// point. Mirror of backend-cpu/src/kernels/splat_photons.rs (splat_setup, splat_pixel) and
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

// This invocation's deposits, underflows and saturations, added to `lc` once at its end:
// a workgroup atomic a covered pixel cost the splat 3-4% (Smal 2019's high setting on the
// H200: 3.65 -> 3.51 ms on Vulkan, 3.64 -> 3.54 on wgpu).
var<private> n_deposited: u32;
var<private> n_underflow: u32;
var<private> n_saturated: u32;

// deposit_photon_texel for a splat (no hit distance), counted in the private counters.
fn deposit_splat_texel(texel: u32, flux: vec3<f32>, flux_quantum: f32) {
    var units: vec3<u32>;
    for (var ch = 0u; ch < 3u; ch++) {
        let q = quantize(flux[ch], flux_quantum);
        n_underflow += u32(q.underflow);
        n_saturated += u32(q.saturated);
        units[ch] = q.units;
    }
    add_photon_texel(texel, units, 0u);
    n_deposited += 1u;
}

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

// backend-cpu splat_photons.rs splat_photon's direction deposit: deposit_photon_texel of
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

// backend-cpu splat_photons::SplatSetup: what every pixel test of one splat reads.
struct SplatSetup {
    ellipsoid: SplatKernel,
    centre: vec3<f32>,
    normal: vec3<f32>,
    to_light: vec3<f32>,
    irradiance: vec3<f32>,
    // x0, x1, y0, y1 inclusive; empty when x1 < x0
    rect: vec4<i32>,
    // the pixels' centre rays, tested before a pixel's G-buffer is read
    rays: SplatRays,
}

var<workgroup> setups: array<SplatSetup, WORKGROUP_SIZE>;
// first pixel of each splat in the group's run of pixels; [WORKGROUP_SIZE]: their total
var<workgroup> starts: array<u32, WORKGROUP_SIZE + 1u>;

fn no_splat() -> SplatSetup {
    var s: SplatSetup;
    s.rect = vec4<i32>(0, -1, 0, -1);
    return s;
}

// backend-cpu splat_photons::splat_setup: the photon's kernel, irradiance and screen rectangle
// (empty when it packs to zero power or projects off screen).
fn splat_setup(p: SplatParams, ph: GiPhoton) -> SplatSetup {
    var s = no_splat();
    let power = unpack_rgb9e5(ph.power) * p.power_scale;
    if (!(max_element3(power) > 0.0)) {
        return s;
    }
    var px: u32;
    var py: u32;
    var z: f32;
    if (!project_to_pixel(p.camera, ph.position, &px, &py, &z)) {
        return s;
    }
    let n = unpack_unit_vector(ph.normal);
    let to_light = -unpack_unit_vector(ph.direction);
    let sc = max(ray_length_scale(ph.ray_length, p) *
                 density_scale(z, p.tile_constant, tile_counts[ph.tile], p),
                 min_splat_scale(z, p.camera.tan_half_fov_y, p.camera.height, p.min_splat_px));
    let kernel = splat_kernel(n, to_light, sc, p);
    let reach = splat_reach_px(p, max_element3(kernel.axes), z);
    if (reach > p.max_splat_px) {
        atomicAdd(&lc[COUNTER_SATURATED], 1u);
    }
    s.ellipsoid = kernel;
    s.centre = ph.position;
    s.normal = n;
    s.to_light = to_light;
    s.irradiance = splat_irradiance(power, kernel);
    s.rect = splat_screen_rect(p.camera, ph.position, kernel, px, py, min(reach, p.max_splat_px),
                               p.scene_magnitude);
    s.rays = splat_rays(p.camera, ph.position, kernel, p.scene_magnitude);
    return s;
}

// Pixels in a splat's screen rectangle (splat_photons.cl's splat_rect_pixels; the CPU
// walks its rectangles directly).
fn splat_rect_pixels(rect: vec4<i32>) -> u32 {
    if (rect.y < rect.x || rect.w < rect.z) {
        return 0u;
    }
    return u32(rect.y - rect.x + 1) * u32(rect.w - rect.z + 1);
}

// backend-cpu splat_photons::splat_pixel: one pixel's test and deposit for the group's splat
// `j` (read from workgroup memory where used: most pixels fail the first test).
fn splat_pixel(p: SplatParams, j: u32, q: u32) {
    // each test loads the G-buffer plane it reads, in the tests' order (flags, position,
    // normal): most pixels of the rectangle fail the first two
    let p3 = gbuffer3[q];
    if ((p3.w & GBUFFER_RECEIVER) == 0u) {
        return;
    }
    let p0 = gbuffer0[q];
    if (!kernel_contains(setups[j].ellipsoid, setups[j].centre, bitcast<vec3<f32>>(p0.xyz))) {
        return;
    }
    let p1 = gbuffer1[q];
    if (dot3(bitcast<vec3<f32>>(p1.xyz), setups[j].normal) <= 0.0) {
        return;
    }
    let t = gbuffer_from_planes(p0, p1, gbuffer2[q], p3);
    let area = gbuffer_pixel_area(p.camera, q, t);
    let irradiance = setups[j].irradiance;
    deposit_splat_texel(q, irradiance * area, p.flux_quantum);
    if (p.light_direction != 0u &&
        shading_normal_departs(t.normal, unpack_unit_vector(t.geometric_normal))) {
        deposit_light_direction(q, light_direction_deposit(irradiance * area, setups[j].to_light),
                                p.flux_quantum);
    }
}

// The photon invocation `li` of workgroup `group` splats: every G-th photon from `group` on,
// G = ceil(stored / 64) the groups that hold the `stored` photons. Photons stored one after
// another come from neighbouring paths and splat onto the same pixels: a group of 64 such
// neighbours would add to the same words over and over, and atomics on one word are
// served one at a time.
fn splat_group_photon(group: u32, li: u32, stored: u32) -> u32 {
    return group + li * ((stored + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE);
}

// A workgroup splats its photons together: each invocation sets up its own photon's splat,
// then the group walks the run of all its splats' pixels, a pixel per invocation, so that
// neighbouring invocations test neighbouring pixels of one splat and every invocation
// gets the same share (a large splat does not hold up the rest of its group). The sums
// are exact integers, so the order is free. `group`: the workgroup's index; `li`: local
// invocation index. Every invocation reaches the barriers.
fn splat_photons(group: u32, li: u32) {
    let stored = min(photon_count[0], arrayLength(&photons));
    counters_clear_local(li);
    let p = params;
    let i = splat_group_photon(group, li, stored);
    var mine = no_splat();
    if (i < stored) {
        mine = splat_setup(p, photons[i]);
    }
    setups[li] = mine;
    starts[li + 1u] = splat_rect_pixels(mine.rect);
    workgroupBarrier();
    if (li == 0u) {
        starts[0] = 0u;
        for (var j = 1u; j <= WORKGROUP_SIZE; j++) {
            starts[j] += starts[j - 1u];
        }
    }
    workgroupBarrier();
    let w = i32(p.camera.width);
    let total = starts[WORKGROUP_SIZE];
    var j = 0u;
    for (var k = li; k < total; k += WORKGROUP_SIZE) {
        while (starts[j + 1u] <= k) {
            j++;
        }
        let at = k - starts[j];
        let rect = setups[j].rect;
        let rw = u32(rect.y - rect.x + 1);
        let qx = rect.x + i32(at % rw);
        let qy = rect.z + i32(at / rw);
        // a pixel whose centre ray misses the kernel's box is turned away before its
        // G-buffer is read (most of a rectangle's pixels)
        if (splat_ray_may_hit(setups[j].rays, p.camera, u32(qx), u32(qy))) {
            splat_pixel(p, j, u32(qy * w + qx));
        }
    }
    if (n_deposited != 0u) {
        atomicAdd(&lc[COUNTER_DEPOSITED], n_deposited);
    }
    if (n_underflow != 0u) {
        atomicAdd(&lc[COUNTER_UNDERFLOW], n_underflow);
    }
    if (n_saturated != 0u) {
        atomicAdd(&lc[COUNTER_SATURATED], n_saturated);
    }
    counters_flush_local(li);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let group = wg.y * nwg.x + wg.x;
    // the launch covers the photon buffer's capacity; a group past the stored photons
    // (most of them at 3 bounces) leaves at once, all its invocations alike, before any
    // barrier: the condition reads only workgroup builtins and read-only storage, which
    // WGSL's uniformity analysis holds uniform (wgsl_validate's
    // barriers_in_uniform_control_flow checks that form)
    if (group * 64u >= min(photon_count[0], arrayLength(&photons))) {
        return;
    }
    splat_photons(group, li);
}

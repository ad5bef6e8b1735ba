// needs: layout prelude vector packing fixed_point scene gbuffer photon_map_add screen_deposit
// deposit_screen (Kim 2019, section 30.3.1.3): each stored photon is projected to its pixel
// and added in fixed point if the pixel sees a diffuse surface at a consistent depth and
// the photon arrives on the side the camera sees. Mirror of
// backend-opencl/kernels/deposit_screen.cl and backend-cpu/src/kernels/deposit_screen.rs;
// 64-bit sums are (lo, hi) u32 atomics with carry, so the map is bitwise identical to the
// CPU's for the same photons.

@group(0) @binding(0) var<uniform> params: DepositParams;
@group(0) @binding(1) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> gbuffer2: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read> photons: array<Photon>;
@group(0) @binding(6) var<storage, read> photon_count: array<u32>;
@group(0) @binding(7) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> photon_map0: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> photon_map1: array<atomic<u32>>;
@group(0) @binding(10) var<storage, read_write> photon_map2: array<atomic<u32>>;

// The work-group's counters (fixed_point.wgsl), OpenCL's `__local uint lc[COUNTER_WORDS]`.
var<workgroup> lc: array<atomic<u32>, COUNTER_WORDS>;

// `li`: local invocation index. Called by every invocation of the group (the counter
// helpers hold barriers).
fn deposit_screen(i: u32, li: u32) {
    counters_clear_local(li);
    let p = params;
    // The OpenCL kernel's `photon_capacity` argument is the photon buffer's length.
    let photon_capacity = arrayLength(&photons);
    if (i < min(photon_count[0], photon_capacity)) {
        deposit_screen_photon(photons[i], p);
    }
    counters_flush_local(li);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    // No early return: every invocation reaches the barriers in deposit_screen.
    deposit_screen(i, li);
}

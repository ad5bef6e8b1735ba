// needs: layout prelude vector optics footprint scene gbuffer photon_map
// resolve_caustics (Kim 2019 Eq. 5): radiance L = (albedo / pi) * Phi / A from the pixel's
// fixed-point flux sum; alpha = mean hit distance. Mirror of
// backend-opencl/kernels/resolve_caustics.cl without cl_khr_fp64 (WGSL has no f64): the
// 64-bit sums are split exactly into hi * 2^32 and lo and scaled in f32. The CPU
// (backend-cpu/src/kernels/resolve_caustics.rs::resolve_caustics) scales in f64; this is a
// few f32 roundings (<= ~4 ulp, plus WGSL's division accuracy) away from it.

@group(0) @binding(0) var<uniform> params: DepositParams;
@group(0) @binding(1) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> gbuffer2: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read> photon_map0: array<u32>;
@group(0) @binding(6) var<storage, read> photon_map1: array<u32>;
@group(0) @binding(7) var<storage, read> photon_map2: array<u32>;
@group(0) @binding(8) var<storage, read_write> out: array<vec4<f32>>;

// hi * 2^32 (exact when f32(hi) is) + lo, in f32.
fn join_u64_wide(lo: u32, hi: u32) -> f32 {
    return f32(hi) * 4294967296.0f + f32(lo);
}

const WIDE_PI: f32 = PI_F;

fn resolve_caustics(i: u32) {
    let p = params;
    let cam = p.camera;
    if (i >= cam.width * cam.height) {
        return;
    }
    let g = load_gbuffer(i);
    if ((photon_map_word(i, 8u) == 0u && photon_map_word(i, 9u) == 0u) ||
        (g.flags & GBUFFER_RECEIVER) == 0u) {
        out[i] = vec4<f32>(0.0);
        return;
    }
    let ray = camera_ray(cam, i % cam.width, i / cam.width);
    let footprint = pixel_footprint(g.depth, cam.width, cam.height, cam.tan_half_fov_x,
                                    cam.tan_half_fov_y);
    let area = pixel_surface_area(footprint, dot3(ray, cam.forward), dot3(ray, g.normal));
    let scale = saturate_radiance(p.flux_quantum / (WIDE_PI * area));
    let n = join_u64_wide(photon_map_word(i, 8u), photon_map_word(i, 9u));
    var l: vec4<f32>;
    l.x = saturate_radiance(join_u64_wide(photon_map_word(i, 0u), photon_map_word(i, 1u)) * scale) * g.albedo.x;
    l.y = saturate_radiance(join_u64_wide(photon_map_word(i, 2u), photon_map_word(i, 3u)) * scale) * g.albedo.y;
    l.z = saturate_radiance(join_u64_wide(photon_map_word(i, 4u), photon_map_word(i, 5u)) * scale) * g.albedo.z;
    l.w = join_u64_wide(photon_map_word(i, 6u), photon_map_word(i, 7u)) * p.hit_distance_quantum / n;
    out[i] = l;
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    resolve_caustics(i);
}

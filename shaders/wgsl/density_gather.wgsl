// needs: layout prelude vector optics footprint scene gbuffer density_gather source_index
// density_gather: one direction of the scatter-normalised, density-adaptive caustic
// gather (core/src/math/density_gather.rs; the contract in core/src/kernels/
// density_gather.rs). Mirror of backend-opencl/kernels/density_gather.cl and
// backend-cpu/src/kernels/density_gather.rs.

@group(0) @binding(0) var<uniform> params: GatherParams;
@group(0) @binding(1) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> gbuffer2: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read> edge: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> input: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> out: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> source_index: array<atomic<u32>>;

fn density_gather(index: u32) {
    let p = params;
    let w = i32(p.camera.width);
    let h = i32(p.camera.height);
    var x: i32;
    var y: i32;
    if (p.axis == 0u) {
        let i = i32(index);
        if (i >= w * h) {
            return;
        }
        x = i % w;
        y = i / w;
    } else {
        let c = column_pass_pixel(index, p.camera.width);
        if (c.x >= p.camera.width || c.y >= p.camera.height) {
            return;
        }
        x = i32(c.x);
        y = i32(c.y);
    }
    let j = y * w + x;
    let ej = edge[j];
    if (!edge_texel_is_receiver(ej)) {
        out[j] = vec4<f32>(0.0);
        return;
    }
    let r = input[j].w;
    let dark = vec4<f32>(0.0, 0.0, 0.0, select(0.0, r, p.axis == 0u));
    var sum = vec3<f32>(0.0);
    // the sources that can have weight here, in increasing offset (the taps left out
    // have no flux or no weight): the mask's set bits within the reach grid's bound
    let taps = pass_reach(w, h, x, y, p.axis, i32(p.max_radius_px));
    let along = select(y, x, p.axis == 0u);
    let lo = max(along - taps, 0);
    let hi = min(along + taps, select(h, w, p.axis == 0u) - 1);
    for (var k = lo / 32; k <= hi / 32 && lo <= hi; k++) {
        var bits = source_bits(w, h, p.axis, x, y, k, lo, hi);
        while (bits != 0u) {
            let d = k * 32 + i32(countTrailingZeros(bits)) - along;
            bits &= bits - 1u;
            let q = select(y + d, y, p.axis == 0u) * w + select(x, x + d, p.axis == 0u);
            // source q, destination j: a source without flux adds nothing; then the
            // source's radius at offset j - q (non-receivers hold no flux)
            let s = input[q];
            if (s.x == 0.0 && s.y == 0.0 && s.z == 0.0) {
                continue;
            }
            let ws = footprint_weight(-d, s.w);
            if (ws == 0.0) {
                continue;
            }
            let eq = edge[q];
            if (!edge_texel_is_receiver(eq)) {
                continue;
            }
            let wgt = ws * edge_weight_of(p, eq, ej);
            sum += wgt * s.xyz;
        }
    }
    // (flux and weights are >= 0: a sum without a positive channel is 0)
    if (!(sum.x > 0.0 || sum.y > 0.0 || sum.z > 0.0)) {
        out[j] = dark;
        return;
    }
    if (p.axis == 0u) {
        let o = vec4<f32>(sum / gather_normaliser(p, x, y, r, 1u), r);
        out[j] = o;
        // the column pass's sources
        put_source(w, h, 1u, x, y, o, i32(p.max_radius_px));
    } else if (p.surface == GATHER_SURFACE_ATLAS) {
        // irradiance E = Phi / A over the texel's world area (its edge texel's y)
        let e = saturate_radiance3(sum * saturate_radiance(1.0 / ej.y));
        out[j] = vec4<f32>(e, r);
    } else {
        // Kim 2019, Eq. 5: L = (albedo / pi) Phi / A (the scale saturates first: no 0 / 0)
        let g = load_gbuffer(u32(j));
        let cam = p.camera;
        let ray = camera_ray(cam, u32(x), u32(y));
        let footprint = pixel_footprint(g.depth, cam.width, cam.height, cam.tan_half_fov_x,
                                        cam.tan_half_fov_y);
        let area = pixel_surface_area(footprint, dot3(ray, cam.forward), dot3(ray, g.normal));
        let scale = saturate_radiance(1.0 / (PI_F * area));
        let l = saturate_radiance3(sum * scale) * g.albedo;
        // alpha: the radius where the filter gave light
        out[j] = vec4<f32>(l, r);
    }
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    density_gather(i);
}

// needs: layout prelude vector optics footprint gbuffer
// bilateral_gather (Kim 2019, section 30.3.2): one direction of the separable edge-aware
// photon gather. Mirror of backend-opencl/kernels/bilateral_gather.cl and
// backend-cpu/src/kernels/bilateral_gather.rs.

@group(0) @binding(0) var<uniform> params: GatherParams;
@group(0) @binding(1) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> gbuffer2: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read> tiles: array<f32>;
@group(0) @binding(6) var<storage, read> input: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> out: array<vec4<f32>>;

// Gather radius in pixels at a receiver pixel.
fn gather_radius_px(p: GatherParams, g: GBufferTexel, tile_hit_distance: f32) -> f32 {
    var d = select(p.hit_distance_min, tile_hit_distance, tile_hit_distance > 0.0);
    d = clampf(d, p.hit_distance_min, p.hit_distance_max);
    let world = p.roughness * d;
    let c = p.camera;
    let pixel = sqrt(pixel_footprint(g.depth, c.width, c.height, c.tan_half_fov_x,
                                     c.tan_half_fov_y));
    if (!(pixel > 0.0)) {
        return 0.0;
    }
    return min(world / pixel, f32(p.max_radius_px));
}

fn bilateral_gather(index: u32) {
    let p = params;
    let w = i32(p.camera.width);
    let h = i32(p.camera.height);
    let ts = i32(p.tile_size);
    let tw = (w + ts - 1) / ts;
    let i = i32(index);
    if (i >= w * h) {
        return;
    }
    let x = i % w;
    let y = i / w;
    let g = load_gbuffer(u32(i));
    if ((g.flags & GBUFFER_RECEIVER) == 0u) {
        out[i] = vec4<f32>(0.0, 0.0, 0.0, input[i].w);
        return;
    }
    let r = gather_radius_px(p, g, tiles[(y / ts) * tw + x / ts]);
    let radius = i32(ceil(r));
    let s = max(0.5 * r, 0.5);
    let inv_2s2 = 1.0 / (2.0 * (s * s));
    let n = g.normal;
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var k = -radius; k <= radius; k++) {
        let qx = select(x, x + k, p.axis == 0u);
        let qy = select(y + k, y, p.axis == 0u);
        if (qx < 0 || qy < 0 || qx >= w || qy >= h) {
            continue;
        }
        let q = qy * w + qx;
        let gq = load_gbuffer(u32(q));
        if ((gq.flags & GBUFFER_RECEIVER) == 0u) {
            continue;
        }
        let ws = exp(-f32(k * k) * inv_2s2);
        let wd = exp(-abs(gq.depth - g.depth) / (p.sigma_depth * g.depth));
        var wn = 1.0;
        if (p.normal_power > 0.0) {
            // WGSL's pow is exp2(y * log2(x)) in accuracy, looser than Rust's powf.
            wn = pow(max(dot3(n, gq.normal), 0.0), p.normal_power);
        }
        let wgt = ws * wd * wn;
        sum += wgt * input[q].xyz;
        wsum += wgt;
    }
    var o = vec3<f32>(0.0);
    if (wsum > 0.0) {
        o = saturate_radiance3(sum / wsum);
    }
    out[i] = vec4<f32>(o, input[i].w);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    bilateral_gather(i);
}

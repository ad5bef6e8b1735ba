// needs: layout prelude vector scene gbuffer irradiance_filter
// temporal_blend (Smal 2019, section 24.4.1, Eqs. 10-13): a pixel's estimate blended with
// its reprojected history (the contract in core/src/kernels/temporal_blend.rs). Mirror of
// backend-opencl/kernels/temporal_blend.cl and backend-cpu/src/kernels/temporal_blend.rs.

@group(0) @binding(0) var<uniform> params: TemporalParams;
@group(0) @binding(1) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> gbuffer2: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read> input: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read> history: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read> history_edge: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> out: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> next_history: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> next_edge: array<vec4<f32>>;

// View depth of receiver (x, y), 0 off the image or where the pixel is no receiver.
fn receiver_depth_at(x: i32, y: i32, w: i32, h: i32) -> f32 {
    if (x < 0 || y < 0 || x >= w || y >= h) {
        return 0.0f;
    }
    let i = u32(y * w + x);
    if ((gbuffer3[i].w & GBUFFER_RECEIVER) == 0u) {
        return 0.0f;
    }
    return bitcast<f32>(gbuffer0[i].w);
}

fn temporal_blend_pixel(j: u32) {
    let p = params;
    let w = i32(p.camera.width);
    let h = i32(p.camera.height);
    if (j >= u32(w * h)) {
        return;
    }
    let g = load_gbuffer(j);
    let cur = input[j];
    if ((g.flags & GBUFFER_RECEIVER) == 0u) {
        out[j] = cur;
        next_history[j] = cur;
        next_edge[j] = vec4<f32>(EDGE_TEXEL_NOT_RECEIVER, 0.0f, 0.0f, 0.0f);
        return;
    }
    let x = i32(j) % w;
    let y = i32(j) / w;
    var alpha = 0.0f;
    var hist = vec3<f32>(0.0f);
    if (p.history_frames > 0u) {
        var qx: u32;
        var qy: u32;
        var zq: f32;
        if (project_to_pixel(p.previous, g.position, &qx, &qy, &zq)) {
            let q = qy * p.camera.width + qx;
            let e = history_edge[q];
            if (e.x > 0.0f) {
                let n = vec4<f32>(receiver_depth_at(x - 1, y, w, h), receiver_depth_at(x + 1, y, w, h),
                                  receiver_depth_at(x, y - 1, w, h), receiver_depth_at(x, y + 1, w, h));
                let step = reprojection_depth_step(g.depth, n);
                let wz = depth_weight(zq, e.x, step, p.sigma_z, p.epsilon);
                let wn = normal_weight(g.normal, e.yzw, p.sigma_n);
                alpha = temporal_alpha(wz, wn, p.alpha_max);
                hist = history[q].xyz;
            }
        }
    }
    let rgb = blend_with_history(cur.xyz, hist, alpha);
    let o = vec4<f32>(rgb, cur.w);
    out[j] = o;
    next_history[j] = o;
    next_edge[j] = vec4<f32>(g.depth, g.normal);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    temporal_blend_pixel(i);
}

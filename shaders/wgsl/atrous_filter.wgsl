// needs: layout prelude vector irradiance_filter density_gather gather_texel
// atrous_filter (Smal 2019, section 24.4.2, Eqs. 14-18): one edge-avoiding A-Trous
// iteration with variance clipping of its detail coefficient (the contract in
// core/src/kernels/atrous_filter.rs). Mirror of backend-opencl/kernels/atrous_filter.cl
// and backend-cpu/src/kernels/atrous_filter.rs.

@group(0) @binding(0) var<uniform> params: AtrousParams;
@group(0) @binding(1) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> input: array<vec4<f32>>;
@group(0) @binding(5) var<storage, read_write> details: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> out: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> edge: array<vec4<f32>>;

// Pixel i's edge texel: from the G-buffer on iteration 0 (which writes them all), from
// the edge texels on the later iterations (one 16-byte texel for three planes).
fn atrous_edge(first: bool, i: u32) -> vec4<f32> {
    if (first) {
        return edge_texel(load_gather_texel(i));
    }
    return edge[i];
}

// View depth of receiver (x, y); 0 off the image or on a non-receiver.
fn atrous_depth(first: bool, x: i32, y: i32, w: i32, h: i32) -> f32 {
    if (x < 0 || y < 0 || x >= w || y >= h) {
        return 0.0f;
    }
    let t = atrous_edge(first, u32(y * w + x));
    if (!edge_texel_is_receiver(t)) {
        return 0.0f;
    }
    return t.x;
}

fn atrous_pixel(j: u32) {
    let p = params;
    let w = i32(p.camera.width);
    let h = i32(p.camera.height);
    if (j >= u32(w * h)) {
        return;
    }
    let first = p.iteration == 0u;
    let e = atrous_edge(first, j);
    if (first) {
        edge[j] = e;
    }
    let s_i = input[j];
    if (!edge_texel_is_receiver(e)) {
        out[j] = s_i;
        details[j] = vec4<f32>(0.0f);
        return;
    }
    let x = i32(j) % w;
    let y = i32(j) / w;
    let z = e.x;
    let n = e.yzw;
    let g = depth_gradient(z, vec4<f32>(atrous_depth(first, x - 1, y, w, h), atrous_depth(first, x + 1, y, w, h),
                                        atrous_depth(first, x, y - 1, w, h), atrous_depth(first, x, y + 1, w, h)));
    var sum_w = 0.0f;
    var sum = vec3<f32>(0.0f);
    var sum_sq = vec3<f32>(0.0f);
    for (var ky = 0u; ky < 5u; ky++) {
        for (var kx = 0u; kx < 5u; kx++) {
            let dx = atrous_offset(kx, p.iteration);
            let dy = atrous_offset(ky, p.iteration);
            let qx = x + dx;
            let qy = y + dy;
            if (qx < 0 || qy < 0 || qx >= w || qy >= h) {
                continue;
            }
            let q = u32(qy * w + qx);
            let eq = atrous_edge(first, q);
            if (!edge_texel_is_receiver(eq)) {
                continue;
            }
            let step = g.x * f32(dx) + g.y * f32(dy);
            let wgt = ATROUS_TAPS[kx] * ATROUS_TAPS[ky] * depth_weight(z, eq.x, step, p.sigma_z, p.epsilon)
                * normal_weight(n, eq.yzw, p.sigma_n);
            let v = input[q].xyz;
            sum_w += wgt;
            sum += wgt * v;
            sum_sq += wgt * v * v;
        }
    }
    let mean = sum / sum_w;
    let mean_sq = sum_sq / sum_w;
    let clipped = clipped_detail(s_i.xyz, mean, detail_bound(mean, mean_sq, p.clip_sigmas));
    var before = vec3<f32>(0.0f);
    if (p.iteration > 0u) {
        before = details[j].xyz;
    }
    let d = before + clipped;
    var o = mean;
    if (p.last != 0u) {
        o = atrous_final(mean, d);
    }
    details[j] = vec4<f32>(d, 0.0f);
    out[j] = vec4<f32>(o, s_i.w);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    atrous_pixel(i);
}

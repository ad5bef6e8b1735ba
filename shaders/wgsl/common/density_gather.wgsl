// Mirror of core/src/math/density_gather.rs (method and sources there) and
// backend-opencl/kernels/common/density_gather.cl: the weights of the density-adaptive,
// scatter-normalised caustic gather. A kernel that needs this file binds the G-buffer's
// planes 0, 1 and 3 (`gbuffer0`, `gbuffer1`, `gbuffer3`, see gbuffer.wgsl). The summed-area table's functions are in photon_table.wgsl,
// footprint_radius in gather_footprint.wgsl, and clamped_photon_count in
// photon_count_table.wgsl, which binds no G-buffer.

const MIN_WINDOW_HALF_WIDTH: i32 = 1;

// k-NN radius (pixels): the support half-width 0.5 sqrt(k a / c).
fn knn_radius(k: u32, pixels: u32, photons: u32) -> f32 {
    return 0.5 * sqrt(f32(k) * f32(pixels) / f32(photons));
}

// Pixel-integrated 1-D Epanechnikov weight (unit integral): (3/4) (G(u_b) - G(u_a)),
// G(u) = u - u^3 / 3 over the pixel [offset - 1/2, offset + 1/2] / radius clipped to
// [-1, 1]; 0 outside the support, 1 for offset 0 of a zero support.
fn footprint_weight(offset: i32, radius: f32) -> f32 {
    let d = f32(offset);
    if (!(abs(d) < radius + 0.5)) {
        return 0.0;
    }
    if (!(radius > 0.0)) {
        return 1.0;
    }
    let ua = max((d - 0.5) / radius, -1.0);
    let ub = min((d + 0.5) / radius, 1.0);
    return 0.75 * ((ub - ub * ub * ub / 3.0) - (ua - ua * ua * ua / 3.0));
}

// Edge weight between two receiver pixels (symmetric): depth and normal terms. WGSL's
// pow is exp2(y * log2(x)) in accuracy, looser than Rust's powf.
fn edge_weight(depth_a: f32, normal_a: vec3<f32>, depth_b: f32, normal_b: vec3<f32>,
               sigma_depth: f32, normal_power: f32) -> f32 {
    let wd = exp(-abs(depth_a - depth_b) / (sigma_depth * min(depth_a, depth_b)));
    if (normal_power > 0.0) {
        let c = normal_a.x * normal_b.x + normal_a.y * normal_b.y + normal_a.z * normal_b.z;
        return wd * pow(max(c, 0.0), normal_power);
    }
    return wd;
}

// hi * 2^32 + lo in f32 from the exact split (core's join_u64_wide).
fn join_u64_wide(lo: u32, hi: u32) -> f32 {
    return f32(hi) * 4294967296.0f + f32(lo);
}

// What the gather needs of a G-buffer texel (planes 0, 1 and 3 only).
struct GatherTexel {
    receiver: u32,
    depth: f32,
    normal: vec3<f32>,
}

fn load_gather_texel(i: u32) -> GatherTexel {
    var t: GatherTexel;
    t.receiver = gbuffer3[i].w & GBUFFER_RECEIVER;
    t.depth = bitcast<f32>(gbuffer0[i].w);
    t.normal = bitcast<vec3<f32>>(gbuffer1[i].xyz);
    return t;
}

// Depth of a non-receiver's edge texel (receivers' view depths are positive).
const EDGE_TEXEL_NOT_RECEIVER: f32 = -1.0;

// A pixel's edge texel: (view depth, normal) of a receiver, the G-buffer's bits; depth
// EDGE_TEXEL_NOT_RECEIVER elsewhere.
fn edge_texel(t: GatherTexel) -> vec4<f32> {
    if (t.receiver != 0u) {
        return vec4<f32>(t.depth, t.normal);
    }
    return vec4<f32>(EDGE_TEXEL_NOT_RECEIVER, 0.0, 0.0, 0.0);
}

fn edge_texel_is_receiver(t: vec4<f32>) -> bool {
    return t.x >= 0.0;
}

// Normaliser of a source at pixel (x, y) with radius r: the sum of its weights over the
// receivers of its row (axis 0) or column (1) inside the image.
fn gather_normaliser(p: GatherParams, x: i32, y: i32, r: f32, axis: u32) -> f32 {
    let w = i32(p.camera.width);
    let h = i32(p.camera.height);
    let gi = load_gather_texel(u32(y * w + x));
    // taps beyond the radius weigh 0: the loop stops there
    let reach = min(i32(ceil(r + 0.5)), i32(p.max_radius_px));
    var sum = 0.0;
    for (var d = -reach; d <= reach; d++) {
        let qx = select(x, x + d, axis == 0u);
        let qy = select(y + d, y, axis == 0u);
        if (qx < 0 || qy < 0 || qx >= w || qy >= h) {
            continue;
        }
        let gq = load_gather_texel(u32(qy * w + qx));
        if (gq.receiver == 0u) {
            continue;
        }
        sum += footprint_weight(d, r) *
               edge_weight(gi.depth, gi.normal, gq.depth, gq.normal, p.sigma_depth,
                           p.normal_power);
    }
    return sum;
}

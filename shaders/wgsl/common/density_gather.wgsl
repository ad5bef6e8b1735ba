// Mirror of core/src/math/density_gather.rs (method and sources there) and
// backend-opencl/kernels/common/density_gather.cl: the weights of the density-adaptive,
// scatter-normalised caustic gather. A kernel that needs this file binds the edge
// texels (`edge`, array<vec4<f32>>). The summed-area table's functions are in
// photon_table.wgsl, footprint_radius in gather_footprint.wgsl; clamped_photon_count in
// photon_count_table.wgsl, the one kernel that reads the photon counts and writes the
// edge texels (edge_texel: gather_texel.wgsl).

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

// Whether an edge texel is a receiver's (a non-receiver's depth is -1, receivers' view
// depths are positive; photon_count_table.wgsl writes them).
fn edge_texel_is_receiver(t: vec4<f32>) -> bool {
    return t.x >= 0.0;
}

// core::math::density_gather::HEIR_OFFSETS[k]: an uncovered atlas texel's neighbours in
// the order its heir was chosen (edge neighbours, then corner neighbours).
fn heir_offset(k: u32) -> vec2<i32> {
    var offsets = array<vec2<i32>, 8>(vec2<i32>(-1, 0), vec2<i32>(1, 0), vec2<i32>(0, -1),
                                      vec2<i32>(0, 1), vec2<i32>(-1, -1), vec2<i32>(1, -1),
                                      vec2<i32>(-1, 1), vec2<i32>(1, 1));
    return offsets[min(k, 7u)];
}

// core's edge_texel_heir: 1..8 for an uncovered texel whose flux goes to its neighbour at
// heir_offset(heir - 1), 0 for none.
fn edge_texel_heir(t: vec4<f32>) -> u32 {
    if (edge_texel_is_receiver(t) || !(t.y >= 1.0 && t.y <= 8.0)) {
        return 0u;
    }
    return u32(t.y);
}

// Edge weight between two edge texels.
fn edge_weight_of(p: GatherParams, a: vec4<f32>, b: vec4<f32>) -> f32 {
    return edge_weight(a.x, a.yzw, b.x, b.yzw, p.sigma_depth, p.normal_power);
}

// Normaliser of a source at pixel (x, y) with radius r: the sum of its weights over the
// receivers of its row (axis 0) or column (1) inside the image. Reads `edge`.
fn gather_normaliser(p: GatherParams, x: i32, y: i32, r: f32, axis: u32) -> f32 {
    let w = i32(p.camera.width);
    let h = i32(p.camera.height);
    let ei = edge[y * w + x];
    // taps beyond the radius weigh 0: the loop stops there
    let reach = min(i32(ceil(r + 0.5)), i32(p.max_radius_px));
    var sum = 0.0;
    for (var d = -reach; d <= reach; d++) {
        let qx = select(x, x + d, axis == 0u);
        let qy = select(y + d, y, axis == 0u);
        if (qx < 0 || qy < 0 || qx >= w || qy >= h) {
            continue;
        }
        let eq = edge[qy * w + qx];
        if (!edge_texel_is_receiver(eq)) {
            continue;
        }
        sum += footprint_weight(d, r) * edge_weight_of(p, ei, eq);
    }
    return sum;
}

// The pixel thread t of density_gather's column pass takes: 8 x 8 tiles, 64 threads each
// (core's column_pass_pixel); x >= w or y >= h for the padding of edge tiles.
fn column_pass_pixel(t: u32, w: u32) -> vec2<u32> {
    let tile = t / (COLUMN_PASS_TILE * COLUMN_PASS_TILE);
    let l = t % (COLUMN_PASS_TILE * COLUMN_PASS_TILE);
    let tiles_x = (w + COLUMN_PASS_TILE - 1u) / COLUMN_PASS_TILE;
    return vec2<u32>((tile % tiles_x) * COLUMN_PASS_TILE + l % COLUMN_PASS_TILE,
                     (tile / tiles_x) * COLUMN_PASS_TILE + l / COLUMN_PASS_TILE);
}

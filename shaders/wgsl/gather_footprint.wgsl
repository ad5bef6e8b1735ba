// needs: types vector photon_map density_gather
// gather_footprint: per receiver pixel its k-NN gather radius and its flux over its row
// normaliser (core/src/math/density_gather.rs). Mirror of
// backend-opencl/kernels/gather_footprint.cl and backend-cpu/src/kernels/
// density_gather.rs.

@group(0) @binding(0) var<uniform> params: GatherParams;
@group(0) @binding(1) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> photon_map0: array<u32>;
@group(0) @binding(5) var<storage, read> photon_map1: array<u32>;
@group(0) @binding(6) var<storage, read> photon_map2: array<u32>;
@group(0) @binding(7) var<storage, read> table: array<u32>;
@group(0) @binding(8) var<storage, read_write> out: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> radius: array<f32>;

// The blocked summed-area table's entry at (x, y), 0 left of or above the block whose
// corner is (bx0, by0).
fn table_entry(width: i32, bx0: i32, by0: i32, x: i32, y: i32) -> u32 {
    if (x < bx0 || y < by0) {
        return 0u;
    }
    return table[y * width + x];
}

// Photons in the window of half-width `half_width` around (x, y), clipped to the image
// (.x), and the window's pixel count (.y): the rectangles it covers in each of the (at
// most 2 x 2) blocks it overlaps. Wrapping u32 sums, exact.
fn window_photons(w: i32, h: i32, block: i32, x: i32, y: i32, half_width: i32) -> vec2<u32> {
    let x0 = max(x - half_width, 0);
    let y0 = max(y - half_width, 0);
    let x1 = min(x + half_width, w - 1);
    let y1 = min(y + half_width, h - 1);
    var count = 0u;
    for (var by = y0 / block; by <= y1 / block; by++) {
        for (var bx = x0 / block; bx <= x1 / block; bx++) {
            let bx0 = bx * block;
            let by0 = by * block;
            let xa = max(x0, bx0);
            let xb = min(x1, bx0 + block - 1);
            let ya = max(y0, by0);
            let yb = min(y1, by0 + block - 1);
            count = count + table_entry(w, bx0, by0, xb, yb) - table_entry(w, bx0, by0, xa - 1, yb) -
                    table_entry(w, bx0, by0, xb, ya - 1) + table_entry(w, bx0, by0, xa - 1, ya - 1);
        }
    }
    return vec2<u32>(count, u32((x1 - x0 + 1) * (y1 - y0 + 1)));
}

// The gather radius (pixels) at (x, y): smallest window holding k photons, capped.
fn footprint_radius(w: i32, h: i32, block: i32, x: i32, y: i32, k: u32,
                    max_radius_px: u32) -> f32 {
    let max_radius = max(i32(max_radius_px), MIN_WINDOW_HALF_WIDTH);
    if (window_photons(w, h, block, x, y, max_radius).x < k) {
        return f32(max_radius);
    }
    var lo = MIN_WINDOW_HALF_WIDTH;
    var hi = max_radius;
    while (lo < hi) {
        let mid = (lo + hi) / 2;
        if (window_photons(w, h, block, x, y, mid).x >= k) {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    let c = window_photons(w, h, block, x, y, lo);
    return min(knn_radius(k, c.y, c.x), f32(max_radius));
}

fn gather_footprint(index: u32) {
    let p = params;
    let w = i32(p.camera.width);
    let h = i32(p.camera.height);
    let i = i32(index);
    if (i >= w * h) {
        return;
    }
    if ((gbuffer3[i].w & GBUFFER_RECEIVER) == 0u) {
        out[i] = vec4<f32>(0.0);
        radius[i] = 0.0;
        return;
    }
    let x = i % w;
    let y = i / w;
    let r = footprint_radius(w, h, i32(p.table_block), x, y, p.knn_photons, p.max_radius_px);
    let inv = 1.0 / gather_normaliser(p, x, y, r, 0u);
    let u = u32(i);
    var o: vec4<f32>;
    o.x = join_u64_wide(photon_map_word(u, 0u), photon_map_word(u, 1u)) * p.flux_quantum * inv;
    o.y = join_u64_wide(photon_map_word(u, 2u), photon_map_word(u, 3u)) * p.flux_quantum * inv;
    o.z = join_u64_wide(photon_map_word(u, 4u), photon_map_word(u, 5u)) * p.flux_quantum * inv;
    o.w = r;
    out[i] = o;
    radius[i] = r;
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    gather_footprint(i);
}

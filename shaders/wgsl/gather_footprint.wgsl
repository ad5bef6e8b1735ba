// needs: layout prelude vector photon_map photon_table density_gather source_index
// gather_footprint: per receiver pixel its k-NN gather radius and its flux over its row
// normaliser (core/src/math/density_gather.rs). Mirror of
// backend-opencl/kernels/gather_footprint.cl and backend-cpu/src/kernels/
// density_gather.rs.

@group(0) @binding(0) var<uniform> params: GatherParams;
@group(0) @binding(1) var<storage, read> photon_map0: array<u32>;
@group(0) @binding(2) var<storage, read> photon_map1: array<u32>;
@group(0) @binding(3) var<storage, read> photon_map2: array<u32>;
@group(0) @binding(4) var<storage, read> table: array<u32>;
@group(0) @binding(5) var<storage, read> edge: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> out: array<vec4<f32>>;
@group(0) @binding(7) var<storage, read_write> source_index: array<atomic<u32>>;

// The gather radius (pixels) at (x, y): smallest window holding k photons, capped.
fn footprint_radius(w: i32, h: i32, block: i32, x: i32, y: i32, k: u32,
                    max_radius_px: u32) -> f32 {
    let max_radius = max(i32(max_radius_px), MIN_WINDOW_HALF_WIDTH);
    // (count, pixels) of the window at hi, the smallest half-width known to hold k
    var at_hi = window_photons(w, h, block, x, y, max_radius);
    if (at_hi.x < k) {
        return f32(max_radius);
    }
    var lo = MIN_WINDOW_HALF_WIDTH;
    var hi = max_radius;
    while (lo < hi) {
        let mid = (lo + hi) / 2;
        let c = window_photons(w, h, block, x, y, mid);
        if (c.x >= k) {
            hi = mid;
            at_hi = c;
        } else {
            lo = mid + 1;
        }
    }
    return min(knn_radius(k, at_hi.y, at_hi.x), f32(max_radius));
}

// A pixel's deposited flux (W per channel) from the photon map's fixed-point sums.
fn pixel_flux(u: u32, quantum: f32) -> vec3<f32> {
    return vec3<f32>(join_u64_wide(photon_map_word(u, 0u), photon_map_word(u, 1u)),
                     join_u64_wide(photon_map_word(u, 2u), photon_map_word(u, 3u)),
                     join_u64_wide(photon_map_word(u, 4u), photon_map_word(u, 5u))) * quantum;
}

fn gather_footprint(index: u32) {
    let p = params;
    let w = i32(p.camera.width);
    let h = i32(p.camera.height);
    let i = i32(index);
    if (i >= w * h) {
        return;
    }
    if (!edge_texel_is_receiver(edge[i])) {
        out[i] = vec4<f32>(0.0);
        return;
    }
    let x = i % w;
    let y = i / w;
    let r = footprint_radius(w, h, i32(p.table_block), x, y, p.knn_photons, p.max_radius_px);
    var f = pixel_flux(u32(i), p.flux_quantum);
    if (p.surface == GATHER_SURFACE_ATLAS) {
        // core's inherited_flux: the flux of uncovered neighbours whose heir this texel is
        for (var k = 0u; k < 8u; k++) {
            let d = heir_offset(k);
            let nx = x + d.x;
            let ny = y + d.y;
            if (nx < 0 || ny < 0 || nx >= w || ny >= h) {
                continue;
            }
            let n = ny * w + nx;
            let heir = edge_texel_heir(edge[n]);
            if (heir != 0u && all(heir_offset(heir - 1u) == -d)) {
                f += pixel_flux(u32(n), p.flux_quantum);
            }
        }
    }
    if (f.x == 0.0 && f.y == 0.0 && f.z == 0.0) {
        // no flux to spread: no normaliser to compute
        out[i] = vec4<f32>(0.0, 0.0, 0.0, r);
        return;
    }
    let inv = 1.0 / gather_normaliser(p, x, y, r, 0u);
    let o = vec4<f32>(f.x * inv, f.y * inv, f.z * inv, r);
    out[i] = o;
    // the row pass's sources: its loops visit only them
    put_source(w, h, 0u, x, y, o, i32(p.max_radius_px));
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    gather_footprint(i);
}

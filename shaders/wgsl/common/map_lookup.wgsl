// Mirror of core::math::map_gather::sample_caustic_map: the covered texels of a tile
// over a pixel's footprint rectangle (footprint_extent), or bilinear where it is smaller
// than a texel. Reads the atlas through functions the kernel module defines: `atlas_area(i)`,
// `map_irradiance(i)` (W/m^2) and `atlas_centroid(i)` (texel_centroid).

// core::math::map_gather::texel_centroid: the mean position (texel-local) of a texel's
// photons from its centroid sums; the texel's middle without photons or past
// CENTROID_MAX_PHOTONS.
fn texel_centroid(sx: u32, sy: u32, n: u32) -> vec2<f32> {
    if (n == 0u || n >= CENTROID_MAX_PHOTONS) {
        return vec2<f32>(0.5);
    }
    let nf = f32(n);
    let d = f32(n * CENTROID_SUBTEXELS);
    return vec2<f32>((f32(sx) + 0.5 * nf) / d, (f32(sy) + 0.5 * nf) / d);
}

// core::math::map_gather::centroid_share: the share of a texel's flux inside [lo, hi)
// (texel-local) when it lies uniformly on [c - a, c + a], a = min(c, 1 - c).
fn centroid_share(c: f32, lo: f32, hi: f32) -> f32 {
    let a = max(min(c, 1.0 - c), 0.5 / f32(CENTROID_SUBTEXELS));
    return min(max(min(hi, c + a) - max(lo, c - a), 0.0) / (2.0 * a), 1.0);
}

fn footprint_texels(pixel_angle: f32, distance: f32, cos_in: f32, texel_area: f32) -> f32 {
    let w = pixel_angle * distance;
    let area = w * w / max(abs(cos_in), 1e-3);
    if (texel_area > 0.0) {
        return sqrt(area / texel_area);
    }
    return 0.0;
}

// core::math::map_gather::footprint_extent: half-extents (texels) of the rectangle that
// bounds a pixel's footprint on a triangle (world corners p0..p2, UV corners t0..t2) of a
// tile `side` texels wide; (-1, -1) without a UV Jacobian.
fn footprint_extent(dir: vec3<f32>, right: vec3<f32>, width: f32, p0: vec3<f32>,
                    p1: vec3<f32>, p2: vec3<f32>, t0: vec2<f32>, t1: vec2<f32>,
                    t2: vec2<f32>, side: u32) -> vec2<f32> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let g11 = dot3(e1, e1);
    let g12 = dot3(e1, e2);
    let g22 = dot3(e2, e2);
    let det = g11 * g22 - g12 * g12;
    let d1 = t1 - t0;
    let d2 = t2 - t0;
    let nc = cross3(e1, e2);
    let n_len = length3(nc);
    if (!(det > 0.0 && n_len > 0.0) || d1.x * d2.y - d1.y * d2.x == 0.0) {
        return vec2<f32>(-1.0);
    }
    let n = nc / n_len;
    var a = right - dir * dot3(right, dir);
    if (!(dot3(a, a) > 1e-12)) {
        a = vec3<f32>(1.0, 0.0, 0.0) - dir * dir.x;
        if (!(dot3(a, a) > 1e-12)) {
            a = vec3<f32>(0.0, 1.0, 0.0) - dir * dir.y;
        }
    }
    a = a * (1.0 / sqrt(dot3(a, a)));
    let b = cross3(dir, a);
    var c = dot3(dir, n);
    if (abs(c) < 1e-3) {
        c = copysign_f32(1e-3, c);
    }
    let va = width * (a - dir * (dot3(n, a) / c));
    let vb = width * (b - dir * (dot3(n, b) / c));
    let ta = footprint_to_texels(va, e1, e2, g11, g12, g22, det, d1, d2, side);
    let tb = footprint_to_texels(vb, e1, e2, g11, g12, g22, det, d1, d2, side);
    return 0.5 * (abs(ta) + abs(tb));
}

// A world vector in the triangle's plane in the tile's texels (footprint_extent's map).
fn footprint_to_texels(v: vec3<f32>, e1: vec3<f32>, e2: vec3<f32>, g11: f32, g12: f32,
                       g22: f32, det: f32, d1: vec2<f32>, d2: vec2<f32>, side: u32) -> vec2<f32> {
    let x1 = dot3(e1, v);
    let x2 = dot3(e2, v);
    let alpha = (g22 * x1 - g12 * x2) / det;
    let beta = (g11 * x2 - g12 * x1) / det;
    return (d1 * alpha + d2 * beta) * f32(side);
}

// One texel's share [i, i + 1) ∩ [lo, hi) of an interval (texels).
fn texel_overlap(i: u32, lo: f32, hi: f32) -> f32 {
    return max(min(f32(i) + 1.0, hi) - max(f32(i), lo), 0.0);
}

fn sample_caustic_map(tile: vec4<u32>, uv: vec2<f32>, extent: vec2<f32>, atlas_width: u32) -> vec3<f32> {
    let s = f32(tile.z);
    if (extent.x > 0.5 || extent.y > 0.5) {
        let hx = clampf(extent.x, 0.5, 0.5 * MAX_FOOTPRINT_TEXELS);
        let hy = clampf(extent.y, 0.5, 0.5 * MAX_FOOTPRINT_TEXELS);
        let cx = clampf(uv.x * s, 0.0, s);
        let cy = clampf(uv.y * s, 0.0, s);
        let lx = max(cx - hx, 0.0);
        let ux = min(cx + hx, s);
        let ly = max(cy - hy, 0.0);
        let uy = min(cy + hy, s);
        let bx0 = u32(floor(lx));
        let bx1 = clamp(u32(ceil(ux)), 1u, tile.z) - 1u;
        let by0 = u32(floor(ly));
        let by1 = clamp(u32(ceil(uy)), 1u, tile.z) - 1u;
        var bsum = vec3<f32>(0.0);
        var bw = 0.0;
        for (var y = by0; y <= by1; y++) {
            let wy = texel_overlap(y, ly, uy);
            for (var x = bx0; x <= bx1; x++) {
                let i = (tile.y + y) * atlas_width + tile.x + x;
                let w = texel_overlap(x, lx, ux) * wy;
                if (atlas_area(i) > 0.0 && w > 0.0) {
                    let c = atlas_centroid(i);
                    let share = centroid_share(c.x, lx - f32(x), ux - f32(x))
                        * centroid_share(c.y, ly - f32(y), uy - f32(y));
                    bsum += share * map_irradiance(i);
                    bw += w;
                }
            }
        }
        if (bw > 0.0) {
            return bsum / bw;
        }
    }
    let fx = clamp(uv.x * s - 0.5, 0.0, s - 1.0);
    let fy = clamp(uv.y * s - 0.5, 0.0, s - 1.0);
    let x0 = floor(fx);
    let y0 = floor(fy);
    let wx = fx - x0;
    let wy = fy - y0;
    let ix0 = u32(x0);
    let iy0 = u32(y0);
    let ix1 = min(ix0 + 1u, tile.z - 1u);
    let iy1 = min(iy0 + 1u, tile.z - 1u);
    let xs = array<u32, 4>(ix0, ix1, ix0, ix1);
    let ys = array<u32, 4>(iy0, iy0, iy1, iy1);
    let ws = array<f32, 4>((1.0 - wx) * (1.0 - wy), wx * (1.0 - wy), (1.0 - wx) * wy, wx * wy);
    var sum = vec3<f32>(0.0);
    var wsum = 0.0;
    for (var k = 0u; k < 4u; k++) {
        let i = (tile.y + ys[k]) * atlas_width + tile.x + xs[k];
        if (atlas_area(i) > 0.0 && ws[k] > 0.0) {
            sum += ws[k] * map_irradiance(i);
            wsum += ws[k];
        }
    }
    if (wsum > 0.0) {
        return sum / wsum;
    }
    return vec3<f32>(0.0);
}

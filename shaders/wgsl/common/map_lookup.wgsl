// Mirror of core::math::map_gather::sample_caustic_map: bilinear over the covered texels
// of a tile. Reads the atlas through functions the kernel module defines: `atlas_area(i)`
// and `map_irradiance(i)` (W/m^2).

const MAX_FOOTPRINT_TEXELS: f32 = 32.0;

fn footprint_texels(pixel_angle: f32, distance: f32, cos_in: f32, texel_area: f32) -> f32 {
    let w = pixel_angle * distance;
    let area = w * w / max(abs(cos_in), 1e-3);
    if (texel_area > 0.0) {
        return sqrt(area / texel_area);
    }
    return 0.0;
}

fn sample_caustic_map(tile: vec4<u32>, uv: vec2<f32>, footprint: f32, atlas_width: u32) -> vec3<f32> {
    let s = f32(tile.z);
    let fx = clamp(uv.x * s - 0.5, 0.0, s - 1.0);
    let fy = clamp(uv.y * s - 0.5, 0.0, s - 1.0);
    if (footprint > 1.0) {
        let h = 0.5 * min(footprint, MAX_FOOTPRINT_TEXELS);
        let bx0 = u32(max(ceil(fx - h), 0.0));
        let bx1 = u32(min(ceil(fx + h) - 1.0, s - 1.0));
        let by0 = u32(max(ceil(fy - h), 0.0));
        let by1 = u32(min(ceil(fy + h) - 1.0, s - 1.0));
        var bsum = vec3<f32>(0.0);
        var n = 0u;
        for (var y = by0; y <= by1; y++) {
            for (var x = bx0; x <= bx1; x++) {
                let i = (tile.y + y) * atlas_width + tile.x + x;
                if (atlas_area(i) > 0.0) {
                    bsum += map_irradiance(i);
                    n += 1u;
                }
            }
        }
        if (n > 0u) {
            return bsum / f32(n);
        }
    }
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

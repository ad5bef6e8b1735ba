// Mirror of core::math::map_gather::gather_caustic_texel (Vanderstichelen 2021's N x N gather, fixed to
// keep flux). Reads the atlas through functions the kernel module defines:
// `atlas_area(i)` (texel i's world area, 0 where uncovered) and `atlas_flux(i)` (its
// flux, W).

// core::math::map_gather::window_coverage: the covered texels of source (qx, qy)'s window.
fn window_coverage(tile: vec4<u32>, qx: u32, qy: u32, n: u32, atlas_width: u32) -> u32 {
    let cw = tile_window(tile, qx, qy, n);
    if ((tile.w & TILE_FULLY_COVERED) != 0u) {
        return (cw.y - cw.x + 1u) * (cw.w - cw.z + 1u);
    }
    var c = 0u;
    for (var sy = cw.z; sy <= cw.w; sy++) {
        for (var sx = cw.x; sx <= cw.y; sx++) {
            c += select(0u, 1u, atlas_area(sy * atlas_width + sx) > 0.0);
        }
    }
    return c;
}

fn gather_caustic_texel(tile: vec4<u32>, x: u32, y: u32, n: u32, atlas_width: u32) -> vec3<f32> {
    let t = y * atlas_width + x;
    let area_t = atlas_area(t);
    if (!(area_t > 0.0)) {
        return vec3<f32>(0.0);
    }
    let win = tile_window(tile, x, y, n);
    var sum = vec3<f32>(0.0);
    for (var qy = win.z; qy <= win.w; qy++) {
        for (var qx = win.x; qx <= win.y; qx++) {
            let q = qy * atlas_width + qx;
            let f = atlas_flux(q);
            if (all(f == vec3<f32>(0.0))) {
                continue;
            }
            let c = window_coverage(tile, qx, qy, n, atlas_width);
            if (c == 0u) {
                if (q == t) {
                    sum += f;
                }
            } else {
                sum += f / f32(c);
            }
        }
    }
    return sum / area_t;
}


// Mirror of core/src/math/density_gather.rs (rect_photons, window_photons) and backend-opencl/kernels/common/density_gather.cl: counting photons
// in the blocked summed-area table of the photon counts. A kernel that needs this file
// binds `table` (array<u32>, from photon_count_table).

// The blocked summed-area table's entry at (x, y), 0 left of or above the block whose
// corner is (bx0, by0).
fn table_entry(width: i32, bx0: i32, by0: i32, x: i32, y: i32) -> u32 {
    if (x < bx0 || y < by0) {
        return 0u;
    }
    return table[y * width + x];
}

// Photons in the rectangle [x0, x1] x [y0, y1] inside the image: the parts it covers in
// each block it overlaps, four reads each. Wrapping u32 sums, exact. `block` is a power
// of two: block indices are shifts of the (non-negative) coordinates.
fn rect_photons(w: i32, block: i32, x0: i32, y0: i32, x1: i32, y1: i32) -> u32 {
    let shift = 31u - countLeadingZeros(u32(block));
    var count = 0u;
    for (var by = y0 >> shift; by <= y1 >> shift; by++) {
        for (var bx = x0 >> shift; bx <= x1 >> shift; bx++) {
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
    return count;
}

// Photons in the window of half-width `half_width` around (x, y), clipped to the image
// (.x), and the window's pixel count (.y).
fn window_photons(w: i32, h: i32, block: i32, x: i32, y: i32, half_width: i32) -> vec2<u32> {
    let x0 = max(x - half_width, 0);
    let y0 = max(y - half_width, 0);
    let x1 = min(x + half_width, w - 1);
    let y1 = min(y + half_width, h - 1);
    return vec2<u32>(rect_photons(w, block, x0, y0, x1, y1), u32((x1 - x0 + 1) * (y1 - y0 + 1)));
}

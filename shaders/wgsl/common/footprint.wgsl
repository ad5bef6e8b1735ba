// Mirror of core/src/footprint.rs and backend-opencl/kernels/footprint.cl: Kim 2019, Eq. 4 pixel
// footprint and its obliquity correction.

// Kim 2019, Eq. 4: world-space area of one pixel at view depth `depth` (scene units^2).
fn pixel_footprint(depth: f32, width: u32, height: u32, tan_half_fov_x: f32,
                   tan_half_fov_y: f32) -> f32 {
    let sx = 2.0 * depth * tan_half_fov_x / f32(width);
    let sy = 2.0 * depth * tan_half_fov_y / f32(height);
    return sx * sy;
}

fn pixel_surface_area(footprint: f32, cos_axis: f32, cos_normal: f32) -> f32 {
    return footprint * abs(cos_axis) / max(abs(cos_normal), MIN_COSINE);
}

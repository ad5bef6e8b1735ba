// Mirror of core/src/footprint.rs: Kim 2019, Eq. 4 pixel footprint and its obliquity correction.

// Kim 2019, Eq. 4: world-space area of one pixel at view depth `depth` (scene units^2).
inline float pixel_footprint(float depth, uint width, uint height, float tan_half_fov_x,
                             float tan_half_fov_y) {
    float sx = 2.0f * depth * tan_half_fov_x / (float)width;
    float sy = 2.0f * depth * tan_half_fov_y / (float)height;
    return sx * sy;
}

inline float pixel_surface_area(float footprint, float cos_axis, float cos_normal) {
    return footprint * fabs(cos_axis) / fmax(fabs(cos_normal), MIN_COSINE);
}

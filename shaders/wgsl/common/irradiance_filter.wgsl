// Mirror of core::math::irradiance_filter (seed 003 section 24.4: edge-stopping weights,
// the temporal blend).

fn depth_weight(z_p: f32, z_q: f32, depth_step: f32, sigma_z: f32, epsilon: f32) -> f32 {
    return exp(-abs(z_p - z_q) / (sigma_z * abs(depth_step) + epsilon * abs(z_p)));
}

fn reprojection_depth_step(z: f32, neighbours: vec4<f32>) -> f32 {
    var step = 0.0f;
    for (var k = 0u; k < 4u; k++) {
        if (neighbours[k] > 0.0f) {
            step = max(step, abs(neighbours[k] - z));
        }
    }
    return 0.5f * step;
}

fn normal_weight(n_p: vec3<f32>, n_q: vec3<f32>, sigma_n: f32) -> f32 {
    return pow(max(dot3(n_p, n_q), 0.0f), sigma_n);
}

fn temporal_alpha(w_z: f32, w_n: f32, alpha_max: f32) -> f32 {
    return clamp(alpha_max * w_z * w_n, 0.0f, alpha_max);
}

fn blend_with_history(current: vec3<f32>, history: vec3<f32>, alpha: f32) -> vec3<f32> {
    return current * (1.0f - alpha) + history * alpha;
}

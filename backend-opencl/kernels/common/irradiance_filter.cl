// Mirror of core::math::irradiance_filter (seed 003 section 24.4: edge-stopping weights,
// the temporal blend).

inline float depth_weight(float z_p, float z_q, float depth_step, float sigma_z, float epsilon) {
    return exp(-fabs(z_p - z_q) / (sigma_z * fabs(depth_step) + epsilon * fabs(z_p)));
}

inline float reprojection_depth_step(float z, float4 neighbours) {
    float n[4] = {neighbours.x, neighbours.y, neighbours.z, neighbours.w};
    float step = 0.0f;
    for (uint k = 0u; k < 4u; k++)
        if (n[k] > 0.0f) step = fmax(step, fabs(n[k] - z));
    return 0.5f * step;
}

inline float normal_weight(float3 n_p, float3 n_q, float sigma_n) {
    return pow(fmax(dot3(n_p, n_q), 0.0f), sigma_n);
}

inline float temporal_alpha(float w_z, float w_n, float alpha_max) {
    return clamp(alpha_max * w_z * w_n, 0.0f, alpha_max);
}

inline float3 blend_with_history(float3 current, float3 history, float alpha) {
    return current * (1.0f - alpha) + history * alpha;
}

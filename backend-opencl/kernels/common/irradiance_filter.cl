// Mirror of core::math::irradiance_filter (Smal 2019, section 24.4: edge-stopping weights,
// the temporal blend).

// The weights use the native (hardware) exp2, log2 and division, as WGSL's exp and pow
// do on the GPUs: an A-Trous iteration at Smal 2019's high setting on the H200 took 0.90 ms
// against 1.54 with OpenCL's full-precision exp, pow and division (docs/performance.md,
// "PhotonGi"). Their error (NVIDIA: ex2.approx and lg2.approx,
// ~2^-22 relative and absolute; exp's argument rounded before it: ~1e-7 x |argument|)
// keeps a weight within ~1e-5 relative of the CPU's where it matters (an argument under
// ~50, a normal weight's log2 x sigma_n of 32), the bound the conformance tolerances of
// atrous_filter and temporal_blend are argued from.
inline float depth_weight(float z_p, float z_q, float depth_step, float sigma_z, float epsilon) {
    return native_exp(native_divide(-fabs(z_p - z_q),
                                    sigma_z * fabs(depth_step) + epsilon * fabs(z_p)));
}

inline float reprojection_depth_step(float z, float4 neighbours) {
    float n[4] = {neighbours.x, neighbours.y, neighbours.z, neighbours.w};
    float step = 0.0f;
    for (uint k = 0u; k < 4u; k++)
        if (n[k] > 0.0f) step = fmax(step, fabs(n[k] - z));
    return 0.5f * step;
}

// pow(c, sigma_n) as exp2(sigma_n log2 c), with pow's values at c = 0 (0, or 1 when
// sigma_n is 0)
inline float normal_weight(float3 n_p, float3 n_q, float sigma_n) {
    float c = fmax(dot3(n_p, n_q), 0.0f);
    return c > 0.0f ? native_exp2(sigma_n * native_log2(c)) : (sigma_n == 0.0f ? 1.0f : 0.0f);
}

inline float temporal_alpha(float w_z, float w_n, float alpha_max) {
    return clamp(alpha_max * w_z * w_n, 0.0f, alpha_max);
}

inline float3 blend_with_history(float3 current, float3 history, float alpha) {
    return current * (1.0f - alpha) + history * alpha;
}

// 1D taps of one 5x5 A-Trous iteration (Eq. 14's h).
__constant float ATROUS_TAPS[5] = {0.125f, 0.25f, 0.5f, 0.25f, 0.125f};

inline int atrous_offset(uint k, uint iteration) { return ((int)k - 2) << iteration; }

inline float depth_gradient_axis(float z, float lo, float hi) {
    if (lo > 0.0f && hi > 0.0f) return 0.5f * (hi - lo);
    if (hi > 0.0f) return hi - z;
    if (lo > 0.0f) return z - lo;
    return 0.0f;
}

inline float2 depth_gradient(float z, float4 n) {
    return (float2)(depth_gradient_axis(z, n.x, n.y), depth_gradient_axis(z, n.z, n.w));
}

inline float3 detail_bound(float3 mean, float3 mean_sq, float gamma) {
    return sqrt(fmax(mean_sq - mean * mean, (float3)(0.0f))) * gamma;
}

inline float3 clipped_detail(float3 s_i, float3 s_next, float3 bound) {
    return clamp(s_next - s_i, -bound, bound);
}

inline float3 atrous_final(float3 s_n, float3 clipped_details) {
    return fmax(s_n - clipped_details, (float3)(0.0f));
}

// irradiance_filter::shading_normal_departs (SHADING_DEPARTURE = 1e-3).
inline bool shading_normal_departs(float3 n_s, float3 n_g) {
    float3 d = fabs(n_s - n_g);
    return fmax(d.x, fmax(d.y, d.z)) > 1e-3f;
}

// irradiance_filter::mean_light_direction: normalize(2 d - w), zero where it has no length.
inline float3 mean_light_direction(float3 d, float w) {
    float3 v = 2.0f * d - (float3)(w);
    float l = length(v);
    if (!(l > 0.0f) || !(l < 3.4e38f)) return (float3)(0.0f);
    return v * (1.0f / l);
}

// irradiance_filter::shading_normal_factor (Smal 2019, Eq. 20).
inline float shading_normal_factor(float3 w_i, float3 n_s, float3 n_g, float s_max, float eps) {
    float num = fmax(dot3(w_i, n_s), 0.0f);
    float den = fmax(dot3(w_i, n_g), 0.0f) + eps;
    return fmin(num / den, s_max);
}

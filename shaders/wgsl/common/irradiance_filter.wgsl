// Mirror of core::math::irradiance_filter (Smal 2019, section 24.4: edge-stopping weights,
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

// 1D taps of one 5x5 A-Trous iteration (Eq. 14's h).
const ATROUS_TAPS = array<f32, 5>(0.125f, 0.25f, 0.5f, 0.25f, 0.125f);

fn atrous_offset(k: u32, iteration: u32) -> i32 {
    return (i32(k) - 2) << iteration;
}

fn depth_gradient(z: f32, n: vec4<f32>) -> vec2<f32> {
    var g: vec2<f32>;
    for (var a = 0u; a < 2u; a++) {
        let lo = n[2u * a];
        let hi = n[2u * a + 1u];
        var v = 0.0f;
        if (lo > 0.0f && hi > 0.0f) {
            v = 0.5f * (hi - lo);
        } else if (hi > 0.0f) {
            v = hi - z;
        } else if (lo > 0.0f) {
            v = z - lo;
        }
        g[a] = v;
    }
    return g;
}

fn detail_bound(mean: vec3<f32>, mean_sq: vec3<f32>, gamma: f32) -> vec3<f32> {
    return sqrt(max(mean_sq - mean * mean, vec3<f32>(0.0f))) * gamma;
}

fn clipped_detail(s_i: vec3<f32>, s_next: vec3<f32>, bound: vec3<f32>) -> vec3<f32> {
    return clamp(s_next - s_i, -bound, bound);
}

fn atrous_final(s_n: vec3<f32>, clipped_details: vec3<f32>) -> vec3<f32> {
    return max(s_n - clipped_details, vec3<f32>(0.0f));
}

// irradiance_filter::shading_normal_departs (SHADING_DEPARTURE = 1e-3).
fn shading_normal_departs(n_s: vec3<f32>, n_g: vec3<f32>) -> bool {
    let d = abs(n_s - n_g);
    return max(d.x, max(d.y, d.z)) > 1e-3f;
}

// irradiance_filter::mean_light_direction: normalize(2 d - w), zero where it has no length.
fn mean_light_direction(d: vec3<f32>, w: f32) -> vec3<f32> {
    let v = 2.0f * d - vec3<f32>(w);
    let l = length(v);
    if (!(l > 0.0f) || !(l < 3.4e38f)) {
        return vec3<f32>(0.0f);
    }
    return v * (1.0f / l);
}

// irradiance_filter::shading_normal_factor (Smal 2019, Eq. 20).
fn shading_normal_factor(w_i: vec3<f32>, n_s: vec3<f32>, n_g: vec3<f32>, s_max: f32,
                         eps: f32) -> f32 {
    let num = max(dot3(w_i, n_s), 0.0f);
    let den = max(dot3(w_i, n_g), 0.0f) + eps;
    return min(num / den, s_max);
}

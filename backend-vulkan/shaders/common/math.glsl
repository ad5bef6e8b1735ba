// Mirrors of core's scalar functions (vector helpers with glam's operation order, rng,
// sampling, optics, packing, geometry, footprint, spot falloff), as in the OpenCL and WGSL
// ports. `precise` keeps the driver from fusing multiply-adds, so products and sums round
// as in the Rust reference.

float dot3(vec3 a, vec3 b) { precise float r = a.x * b.x + a.y * b.y + a.z * b.z; return r; }
vec3 cross3(vec3 a, vec3 b) {
    precise vec3 r = vec3(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
    return r;
}
float length3(vec3 a) { return sqrt(dot3(a, a)); }
vec3 normalize3(vec3 a) { precise vec3 r = a * (1.0 / length3(a)); return r; }
bool is_finite(float x) { return !isnan(x) && !isinf(x); }
vec3 normalize_or(vec3 a, vec3 fallback) {
    float rcp = 1.0 / length3(a);
    return (is_finite(rcp) && rcp > 0.0) ? a * rcp : fallback;
}
float gt_max(float a, float b) { return a > b ? a : b; }
float max_element3(vec3 a) { return gt_max(a.x, gt_max(a.y, a.z)); }
bool all_finite3(vec3 a) { return is_finite(a.x) && is_finite(a.y) && is_finite(a.z); }
float clampf(float x, float lo, float hi) { return x < lo ? lo : (x > hi ? hi : x); }

// core/src/rng.rs
uint pcg_hash(uint x) {
    uint state = x * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}
uint random_u32(uint seed, uint index, uint bounce, uint dimension) {
    uint h = pcg_hash(seed ^ pcg_hash(index));
    h = pcg_hash(h ^ (bounce * 0x9E3779B9u));
    return pcg_hash(h ^ (dimension * 0x85EBCA6Bu));
}
float u32_to_unit_f32(uint x) { return float(x >> 8u) * (1.0 / 16777216.0); }
float random_f32(uint seed, uint index, uint bounce, uint dimension) {
    return u32_to_unit_f32(random_u32(seed, index, bounce, dimension));
}

// core/src/sampling.rs
vec2 stratified_cell(uint ix, uint iy, uint grid_w, uint grid_h, vec2 jitter) {
    precise vec2 r = vec2((float(ix) + jitter.x) / float(grid_w), (float(iy) + jitter.y) / float(grid_h));
    return r;
}
vec3 uniform_cone(vec2 u, float cos_max) {
    precise float cos_t = 1.0 - u.x * (1.0 - cos_max);
    precise float sin_t = sqrt(max(1.0 - cos_t * cos_t, 0.0));
    float phi = TAU_F * u.y;
    precise vec3 r = vec3(sin_t * cos(phi), sin_t * sin(phi), cos_t);
    return r;
}
vec3 to_world(vec3 v, vec3 n) {
    float sign = n.z >= 0.0 ? 1.0 : -1.0;
    precise float a = -1.0 / (sign + n.z);
    precise float b = n.x * n.y * a;
    precise vec3 t = vec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
    precise vec3 bb = vec3(b, sign + n.y * n.y * a, -n.y);
    precise vec3 r = t * v.x + bb * v.y + n * v.z;
    return r;
}

// core/src/optics.rs
vec3 reflect3(vec3 incident, vec3 normal) {
    precise vec3 r = incident - 2.0 * dot3(incident, normal) * normal;
    return r;
}
bool refract3(vec3 incident, vec3 normal, float eta, out vec3 result) {
    float cos_i = -dot3(incident, normal);
    precise float cos2_t = (1.0 - eta * eta) + eta * eta * cos_i * cos_i;
    if (cos2_t < 0.0) return false;
    float cos_t = sqrt(cos2_t);
    precise vec3 r = eta * incident + (eta * cos_i - cos_t) * normal;
    result = r;
    return true;
}
float fresnel_dielectric(float cos_i, float eta) {
    cos_i = clampf(cos_i, 0.0, 1.0);
    precise float cos2_t = (1.0 - eta * eta) + eta * eta * cos_i * cos_i;
    if (cos2_t <= 0.0) return 1.0;
    float cos_t = sqrt(cos2_t);
    precise float r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    precise float r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    precise float f = 0.5 * (r_s * r_s + r_p * r_p);
    return clampf(f, 0.0, 1.0);
}
vec3 beer_lambert(vec3 sigma_a, float distance) {
    return vec3(exp(-sigma_a.x * distance), exp(-sigma_a.y * distance), exp(-sigma_a.z * distance));
}
const float CHANNEL_WAVELENGTH_UM[3] = float[3](0.65, 0.55, 0.45);
const float REFERENCE_WAVELENGTH_UM = 0.55;
float cauchy_ior(float ior, float cauchy_b, float wavelength_um) {
    precise float a = ior - cauchy_b / (REFERENCE_WAVELENGTH_UM * REFERENCE_WAVELENGTH_UM);
    precise float r = a + cauchy_b / (wavelength_um * wavelength_um);
    return r;
}
vec3 dielectric_scatter(vec3 incident, vec3 shading_normal, bool entering, float ior, float xi) {
    vec3 facing = dot3(incident, shading_normal) < 0.0 ? shading_normal : -shading_normal;
    float eta = entering ? 1.0 / ior : ior;
    float cos_i = -dot3(incident, facing);
    float f = fresnel_dielectric(cos_i, eta);
    if (xi < f) return reflect3(incident, facing);
    vec3 t;
    if (refract3(incident, facing, eta, t)) return normalize3(t);
    return reflect3(incident, facing);
}

// core/src/packing.rs
float sign_not_zero(float v) { return v >= 0.0 ? 1.0 : -1.0; }
vec2 oct_encode(vec3 n) {
    precise float l1 = abs(n.x) + abs(n.y) + abs(n.z);
    if (l1 <= 0.0 || !is_finite(l1)) return vec2(0.0);
    vec2 p = vec2(n.x, n.y) / l1;
    if (n.z >= 0.0) return p;
    return vec2((1.0 - abs(p.y)) * sign_not_zero(p.x), (1.0 - abs(p.x)) * sign_not_zero(p.y));
}
// Rust's f32::round: half away from zero (GLSL's round may pick either).
float round_half_away(float x) { return sign(x) * floor(abs(x) + 0.5); }
uint snorm16(float x) { return uint(int(round_half_away(clampf(x, -1.0, 1.0) * 32767.0))) & 0xFFFFu; }
uint pack_unit_vector(vec3 n) {
    vec2 e = oct_encode(n);
    return snorm16(e.x) | (snorm16(e.y) << 16u);
}

// core/src/geometry.rs
float offset_component(float pc, float nc) {
    const float ORIGIN = 1.0 / 32.0;
    const float FLOAT_SCALE = 1.0 / 65536.0;
    const float INT_SCALE = 256.0;
    int of_i = int(INT_SCALE * nc);
    int bits = floatBitsToInt(pc);
    float moved = intBitsToFloat(bits + (pc < 0.0 ? -of_i : of_i)); // wraps as Rust's
    precise float near = pc + FLOAT_SCALE * nc;
    return abs(pc) < ORIGIN ? near : moved;
}
vec3 offset_ray_origin(vec3 p, vec3 n) {
    return vec3(offset_component(p.x, n.x), offset_component(p.y, n.y), offset_component(p.z, n.z));
}

struct SurfacePoint { vec3 position; vec3 geometric_normal; vec3 shading_normal; vec2 uv; };

SurfacePoint surface_point(GpuVertex a, GpuVertex b, GpuVertex c, float u, float v) {
    precise float w = 1.0 - u - v;
    vec3 ng = normalize_or(cross3(b.position - a.position, c.position - a.position), vec3(0.0, 1.0, 0.0));
    precise vec3 n_sum = a.normal + b.normal + c.normal;
    if (dot3(ng, n_sum) < 0.0) ng = -ng;
    precise vec3 ns_raw = w * a.normal + u * b.normal + v * c.normal;
    vec3 ns = normalize_or(ns_raw, ng);
    if (!all_finite3(ns)) ns = ng;
    SurfacePoint s;
    precise vec3 pos = w * a.position + u * b.position + v * c.position;
    precise vec2 uv = vec2(w * a.u + u * b.u + v * c.u, w * a.v + u * b.v + v * c.v);
    s.position = pos;
    s.geometric_normal = ng;
    s.shading_normal = ns;
    s.uv = uv;
    return s;
}

// core::gpu::camera_ray
vec3 camera_ray(GpuCamera cam, uint px, uint py) {
    precise float sx = (2.0 * (float(px) + 0.5) / float(cam.width) - 1.0) * cam.tan_half_fov_x;
    precise float sy = (1.0 - 2.0 * (float(py) + 0.5) / float(cam.height)) * cam.tan_half_fov_y;
    precise vec3 d = cam.forward + sx * cam.right + sy * cam.up;
    return normalize3(d);
}

// core::device_scene::spot_falloff
float spot_falloff(float cos_theta, float cos_inner, float cos_outer) {
    if (cos_theta >= cos_inner) return 1.0;
    if (cos_theta <= cos_outer) return 0.0;
    float t = clampf((cos_theta - cos_outer) / (cos_inner - cos_outer), 0.0, 1.0);
    precise float r = t * t * (3.0 - 2.0 * t);
    return r;
}

vec3 facing_normal(vec3 n, vec3 dir) { return dot3(n, dir) > 0.0 ? -n : n; }

// core::fixed_point::quantize
uint quantize_units(float value, float quantum, out bool underflow, out bool saturated) {
    underflow = false;
    saturated = false;
    float x = value / quantum;
    if (!(x > 0.0)) return 0u;
    float r = floor(x + 0.5);
    if (r >= 4294967295.0) { saturated = true; return 0xFFFFFFFFu; }
    uint units = uint(r);
    underflow = units == 0u;
    return units;
}

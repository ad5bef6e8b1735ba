// The scene as kernels see it (core::recording::SceneArgs), and the camera helpers of
// core/src/gpu.rs (camera_ray, project_to_pixel).

#define SCENE_PARAMS                                                                       \
    __global const GpuVertex *vertices, __global const GpuTriangle *triangles,            \
        __global const GpuMaterial *materials, __global const GpuLight *lights,            \
        __global const uint4 *nodes, uint node_count
#define SCENE_ARGS vertices, triangles, materials, lights, nodes, node_count

inline float3 camera_ray(__global const GpuCamera* cam, uint px, uint py) {
    float sx = (2.0f * ((float)px + 0.5f) / (float)cam->width - 1.0f) * cam->tan_half_fov_x;
    float sy = (1.0f - 2.0f * ((float)py + 0.5f) / (float)cam->height) * cam->tan_half_fov_y;
    return normalize3(load3g(cam->forward) + sx * load3g(cam->right) + sy * load3g(cam->up));
}

// core::device::layout::primary_ray: the pixel's ray origin and direction; an
// orthographic camera (tan_half_fov_x < 0) shoots along forward from the pixel's point of
// the image plane.
inline float3 primary_ray(__global const GpuCamera* cam, uint px, uint py, float3* origin) {
    if (cam->tan_half_fov_x < 0.0f) {
        float sx = (2.0f * ((float)px + 0.5f) / (float)cam->width - 1.0f) * -cam->tan_half_fov_x;
        float sy = (1.0f - 2.0f * ((float)py + 0.5f) / (float)cam->height) * -cam->tan_half_fov_y;
        *origin = load3g(cam->position) + sx * load3g(cam->right) + sy * load3g(cam->up);
        return load3g(cam->forward);
    }
    *origin = load3g(cam->position);
    return camera_ray(cam, px, py);
}

// core's project_to_screen: continuous pixel coordinates and view depth, on screen or not;
// false when p is not in front of the camera.
inline bool project_to_screen(__global const GpuCamera* cam, float3 p, float* fx, float* fy,
                              float* depth) {
    float3 v = p - load3g(cam->position);
    float z = dot3(v, load3g(cam->forward));
    if (isnan(z) || z <= 0.0f) return false;
    float sx = dot3(v, load3g(cam->right)) / (z * cam->tan_half_fov_x);
    float sy = dot3(v, load3g(cam->up)) / (z * cam->tan_half_fov_y);
    *fx = (sx + 1.0f) * 0.5f * (float)cam->width;
    *fy = (1.0f - sy) * 0.5f * (float)cam->height;
    *depth = z;
    return true;
}

// Pixel containing world point `p` and its view depth; false behind the camera or off
// screen.
inline bool project_to_pixel(__global const GpuCamera* cam, float3 p, uint* px, uint* py,
                             float* depth) {
    float fx, fy, z;
    if (!project_to_screen(cam, p, &fx, &fy, &z)) return false;
    if (!(fx >= 0.0f && fy >= 0.0f && fx < (float)cam->width && fy < (float)cam->height))
        return false;
    *px = (uint)fx;
    *py = (uint)fy;
    *depth = z;
    return true;
}

inline SurfacePoint hit_surface(__global const GpuVertex* vertices,
                                __global const GpuTriangle* triangles, const Hit* hit) {
    __global const GpuTriangle* t = &triangles[hit->triangle];
    return surface_point(&vertices[t->indices[0]], &vertices[t->indices[1]],
                         &vertices[t->indices[2]], hit->u, hit->v);
}

// core::device_scene::spot_falloff: smoothstep between the outer and inner cone.
inline float spot_falloff(float cos_theta, float cos_inner, float cos_outer) {
    if (cos_theta >= cos_inner) return 1.0f;
    if (cos_theta <= cos_outer) return 0.0f;
    float t = clampf((cos_theta - cos_outer) / (cos_inner - cos_outer), 0.0f, 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

// core::device_scene::spot_falloff_narrow: the smoothstep in h = 1 - cos.
inline float spot_falloff_narrow(float h, float h_inner, float h_outer) {
    if (h <= h_inner) return 1.0f;
    if (h >= h_outer) return 0.0f;
    float t = clampf((h_outer - h) / (h_outer - h_inner), 0.0f, 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

// core::device_scene::light_spot_falloff: a narrow spot's falloff from
// h = |dir - axis|^2 / 2, a wider one's from the cosine.
inline float light_spot_falloff(float3 dir, __global const GpuLight* l) {
    float3 axis = load3g(l->direction);
    if (l->one_minus_cos_outer < NARROW_CONE) {
        float3 d = dir - axis;
        return spot_falloff_narrow(0.5f * dot3(d, d), l->intensity[3], l->one_minus_cos_outer);
    }
    return spot_falloff(dot3(dir, axis), l->cos_inner, l->cos_outer);
}

inline float3 facing_normal(float3 n, float3 dir) { return dot3(n, dir) > 0.0f ? -n : n; }

// core::device::layout::off_surface: the deposit's surface test (a depth test, or with a
// negative tolerance a tangent-plane test).
inline bool off_surface(float z, float3 p, float3 position, float3 normal, float depth,
                        float tolerance) {
    if (tolerance < 0.0f) return fabs(dot3(p - position, normal)) > -tolerance * depth;
    return fabs(z - depth) > tolerance * depth;
}

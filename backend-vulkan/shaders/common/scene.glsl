// The scene as kernels see it (core::recording::SceneArgs) and the camera helpers of
// core/src/gpu.rs (camera_ray, project_to_pixel). Mirror of backend-opencl/kernels/
// scene.cl: its SCENE_PARAMS become the bindings below (the same numbers in every ray
// generation stage: 0 the TLAS (trace.glsl), 1 vertices, 2 triangles, 3 materials; 4 the
// lights, declared by the kernels that read them), and the BVH nodes give way to the TLAS.

layout(set = 0, binding = 1, scalar) readonly buffer Vertices { GpuVertex vertices[]; };
layout(set = 0, binding = 2, scalar) readonly buffer Triangles { GpuTriangle triangles[]; };
layout(set = 0, binding = 3, scalar) readonly buffer Materials { GpuMaterial materials[]; };

precise vec3 camera_ray(GpuCamera cam, uint px, uint py) {
    float sx = (2.0 * (float(px) + 0.5) / float(cam.width) - 1.0) * cam.tan_half_fov_x;
    float sy = (1.0 - 2.0 * (float(py) + 0.5) / float(cam.height)) * cam.tan_half_fov_y;
    vec3 d = cam.forward + sx * cam.right + sy * cam.up;
    return normalize3(d);
}

// core::device::layout::primary_ray: the pixel's ray origin and direction; an
// orthographic camera (tan_half_fov_x < 0) shoots along forward from the pixel's point of
// the image plane.
precise vec3 primary_ray(GpuCamera cam, uint px, uint py, precise out vec3 origin) {
    if (cam.tan_half_fov_x < 0.0) {
        precise float hx = -cam.tan_half_fov_x;
        precise float hy = -cam.tan_half_fov_y;
        precise float sx = (2.0 * (float(px) + 0.5) / float(cam.width) - 1.0) * hx;
        precise float sy = (1.0 - 2.0 * (float(py) + 0.5) / float(cam.height)) * hy;
        origin = cam.position + sx * cam.right + sy * cam.up;
        return cam.forward;
    }
    origin = cam.position;
    return camera_ray(cam, px, py);
}

// Pixel containing world point `p` and its view depth; false behind the camera or off
// screen.
bool project_to_pixel(GpuCamera cam, vec3 p, out uint px, out uint py, precise out float depth) {
    precise vec3 v = p - cam.position;
    precise float z = dot3(v, cam.forward);
    if (is_nan(z) || z <= 0.0) return false;
    precise float sx = dot3(v, cam.right) / (z * cam.tan_half_fov_x);
    precise float sy = dot3(v, cam.up) / (z * cam.tan_half_fov_y);
    precise float fx = (sx + 1.0) * 0.5 * float(cam.width);
    precise float fy = (1.0 - sy) * 0.5 * float(cam.height);
    if (!(fx >= 0.0 && fy >= 0.0 && fx < float(cam.width) && fy < float(cam.height)))
        return false;
    px = uint(fx);
    py = uint(fy);
    depth = z;
    return true;
}

SurfacePoint hit_surface(Hit hit) {
    GpuTriangle t = triangles[hit.triangle];
    return surface_point(vertices[t.indices.x], vertices[t.indices.y], vertices[t.indices.z],
                         hit.u, hit.v);
}

// core::device_scene::spot_falloff: smoothstep between the outer and inner cone.
precise float spot_falloff(float cos_theta, float cos_inner, float cos_outer) {
    if (cos_theta >= cos_inner) return 1.0;
    if (cos_theta <= cos_outer) return 0.0;
    float t = clampf((cos_theta - cos_outer) / (cos_inner - cos_outer), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// core::device_scene::spot_falloff_narrow: the smoothstep in h = 1 - cos.
precise float spot_falloff_narrow(float h, float h_inner, float h_outer) {
    if (h <= h_inner) return 1.0;
    if (h >= h_outer) return 0.0;
    float t = clampf((h_outer - h) / (h_outer - h_inner), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// core::device_scene::light_spot_falloff: a narrow spot's falloff from
// h = |dir - axis|^2 / 2, a wider one's from the cosine.
precise float light_spot_falloff(vec3 dir, GpuLight l) {
    vec3 axis = l.direction.xyz;
    if (l.one_minus_cos_outer < NARROW_CONE) {
        precise vec3 d = dir - axis;
        return spot_falloff_narrow(0.5 * dot3(d, d), l.intensity.w, l.one_minus_cos_outer);
    }
    return spot_falloff(dot3(dir, axis), l.cos_inner, l.cos_outer);
}

vec3 facing_normal(vec3 n, vec3 dir) { return dot3(n, dir) > 0.0 ? -n : n; }

// core::device::layout::off_surface: the deposit's surface test (a depth test, or with a
// negative tolerance a tangent-plane test).
bool off_surface(float z, vec3 p, vec3 position, vec3 normal, float depth, float tolerance) {
    if (tolerance < 0.0) {
        precise vec3 d = p - position;
        precise float dist = abs(dot3(d, normal));
        precise float bound = -tolerance * depth;
        return dist > bound;
    }
    precise float dz = abs(z - depth);
    precise float bound = tolerance * depth;
    return dz > bound;
}

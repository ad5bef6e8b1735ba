// The camera helpers of core/src/gpu.rs (camera_ray, project_to_pixel) and the small
// scene helpers of backend-opencl/kernels/scene.cl. scene.cl's SCENE_PARAMS/SCENE_ARGS
// macros have no WGSL counterpart: the scene is the kernel's module-scope bindings
// `vertices`, `triangles`, `materials`, `lights`, `nodes`. scene.cl's hit_surface is in
// traversal.wgsl, so that this file reads no binding and kernels without a scene can use it.

fn camera_ray(cam: GpuCamera, px: u32, py: u32) -> vec3<f32> {
    let sx = (2.0 * (f32(px) + 0.5) / f32(cam.width) - 1.0) * cam.tan_half_fov_x;
    let sy = (1.0 - 2.0 * (f32(py) + 0.5) / f32(cam.height)) * cam.tan_half_fov_y;
    return normalize3(cam.forward + sx * cam.right + sy * cam.up);
}

// core::device::layout::primary_ray: the pixel's ray origin (written to `origin`) and
// direction; an orthographic camera (tan_half_fov_x < 0) shoots along forward from the
// pixel's point of the image plane.
fn primary_ray(cam: GpuCamera, px: u32, py: u32, origin: ptr<function, vec3<f32>>) -> vec3<f32> {
    if (cam.tan_half_fov_x < 0.0) {
        let sx = (2.0 * (f32(px) + 0.5) / f32(cam.width) - 1.0) * -cam.tan_half_fov_x;
        let sy = (1.0 - 2.0 * (f32(py) + 0.5) / f32(cam.height)) * -cam.tan_half_fov_y;
        *origin = cam.position + sx * cam.right + sy * cam.up;
        return cam.forward;
    }
    *origin = cam.position;
    return camera_ray(cam, px, py);
}

// core's project_to_screen: continuous pixel coordinates and view depth, on screen or not;
// false when p is not in front of the camera.
fn project_to_screen(cam: GpuCamera, p: vec3<f32>, fx: ptr<function, f32>,
                     fy: ptr<function, f32>, depth: ptr<function, f32>) -> bool {
    let v = p - cam.position;
    let z = dot3(v, cam.forward);
    if (is_nan_f32(z) || z <= 0.0) {
        return false;
    }
    let sx = dot3(v, cam.right) / (z * cam.tan_half_fov_x);
    let sy = dot3(v, cam.up) / (z * cam.tan_half_fov_y);
    *fx = (sx + 1.0) * 0.5 * f32(cam.width);
    *fy = (1.0 - sy) * 0.5 * f32(cam.height);
    *depth = z;
    return true;
}

// Pixel containing world point `p` and its view depth; false behind the camera or off
// screen.
fn project_to_pixel(cam: GpuCamera, p: vec3<f32>, px: ptr<function, u32>,
                    py: ptr<function, u32>, depth: ptr<function, f32>) -> bool {
    var fx: f32;
    var fy: f32;
    var z: f32;
    if (!project_to_screen(cam, p, &fx, &fy, &z)) {
        return false;
    }
    if (!(fx >= 0.0 && fy >= 0.0 && fx < f32(cam.width) && fy < f32(cam.height))) {
        return false;
    }
    *px = u32(fx);
    *py = u32(fy);
    *depth = z;
    return true;
}

// core::device_scene::spot_falloff: smoothstep between the outer and inner cone.
fn spot_falloff(cos_theta: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if (cos_theta >= cos_inner) {
        return 1.0;
    }
    if (cos_theta <= cos_outer) {
        return 0.0;
    }
    let t = clampf((cos_theta - cos_outer) / (cos_inner - cos_outer), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// core::device_scene::spot_falloff_narrow: the smoothstep in h = 1 - cos.
fn spot_falloff_narrow(h: f32, h_inner: f32, h_outer: f32) -> f32 {
    if (h <= h_inner) {
        return 1.0;
    }
    if (h >= h_outer) {
        return 0.0;
    }
    let t = clampf((h_outer - h) / (h_outer - h_inner), 0.0, 1.0);
    return t * t * (3.0 - 2.0 * t);
}

// core::device_scene::light_spot_falloff: a narrow spot's falloff from
// h = |dir - axis|^2 / 2, a wider one's from the cosine.
fn light_spot_falloff(dir: vec3<f32>, l: GpuLight) -> f32 {
    let axis = l.direction.xyz;
    if (l.one_minus_cos_outer < NARROW_CONE) {
        let d = dir - axis;
        return spot_falloff_narrow(0.5 * dot3(d, d), l.intensity.w, l.one_minus_cos_outer);
    }
    return spot_falloff(dot3(dir, axis), l.cos_inner, l.cos_outer);
}

fn facing_normal(n: vec3<f32>, dir: vec3<f32>) -> vec3<f32> {
    return select(n, -n, dot3(n, dir) > 0.0);
}

// core::device::layout::off_surface: the deposit's surface test (a depth test, or with a
// negative tolerance a tangent-plane test).
fn off_surface(z: f32, p: vec3<f32>, position: vec3<f32>, normal: vec3<f32>, depth: f32,
               tolerance: f32) -> bool {
    if (tolerance < 0.0) {
        return abs(dot3(p - position, normal)) > -tolerance * depth;
    }
    return abs(z - depth) > tolerance * depth;
}

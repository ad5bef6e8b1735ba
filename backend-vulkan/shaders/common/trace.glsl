// Hardware replacement of backend-opencl/kernels/traversal.cl (the software CWBVH
// traversal): closest_hit and occluded trace against the driver-built TLAS with
// traceRayEXT. Included by ray generation stages only (GL_EXT_ray_tracing). One BLAS per
// level of core's two-level layout, instanced in the TLAS with the level's transform; the
// closest-hit stage reports the triangle index the other backends use (accel.rs).
//
// Differences from the software traversal (0 < t < t_max, Moller-Trumbore):
// - hardware reports hits with t_min <= t <= t_max; t_min is 0.0, so a hit exactly at
//   t = 0 counts here and not on the CPU (kernels offset ray origins off surfaces, so it
//   does not arise), and so does one exactly at t_max;
// - the driver's watertight triangle test rounds t, u and v its own way (and may decide
//   hits on an edge or vertex differently); like the software traversal (which no
//   longer has obvhs's 1e-4 box-cull epsilon), it culls no box in front of the origin;
// - "no t_max" (OpenCL's INFINITY) is NO_T_MAX = f32::MAX: traceRayEXT needs finite values.

layout(set = 0, binding = 0) uniform accelerationStructureEXT tlas;

struct Hit {
    float t;
    uint triangle;
    float u;
    float v;
};

layout(location = 0) rayPayloadEXT HitPayload hit_payload;
layout(location = 1) rayPayloadEXT uint shadow_visible;

// Closest hit with 0 <= t <= t_max; `hit` is meaningful only when it returns true.
bool closest_hit(vec3 origin, vec3 dir, float t_max, out Hit hit) {
    hit_payload.triangle = NO_HIT;
    traceRayEXT(tlas, gl_RayFlagsOpaqueEXT, 0xff, 0, 0, 0, origin, 0.0, dir, t_max, 0);
    hit.t = hit_payload.t;
    hit.triangle = hit_payload.triangle;
    hit.u = hit_payload.bary.x;
    hit.v = hit_payload.bary.y;
    return hit_payload.triangle != NO_HIT;
}

// True when something lies on the ray with 0 <= t <= t_max: the first hit ends the
// search, no closest-hit shader runs, and only shadow_miss.rmiss (miss index 1) marks the
// ray visible.
bool occluded(vec3 origin, vec3 dir, float t_max) {
    shadow_visible = 0u;
    traceRayEXT(tlas,
                gl_RayFlagsOpaqueEXT | gl_RayFlagsTerminateOnFirstHitEXT |
                    gl_RayFlagsSkipClosestHitShaderEXT,
                0xff, 0, 0, 1, origin, 0.0, dir, t_max, 1);
    return shadow_visible == 0u;
}

// OpenCL's get_global_id(0): the host launches traceRaysKHR(min(n, 8192), ceil(n / 8192),
// 1) for n threads, so the last row may run past n (each kernel returns there).
uint launch_index() { return gl_LaunchIDEXT.y * gl_LaunchSizeEXT.x + gl_LaunchIDEXT.x; }

// The scene bindings of every ray-tracing kernel and the hardware replacements of the
// software traversal's closest_hit / occluded: traceRayEXT against the driver-built TLAS.
// BLAS primitive order is the triangle buffer's order, so gl_PrimitiveID is the triangle.

layout(set = 0, binding = 0) uniform accelerationStructureEXT tlas;
layout(set = 0, binding = 1, scalar) readonly buffer Vertices { GpuVertex vertices[]; };
layout(set = 0, binding = 2, scalar) readonly buffer Triangles { GpuTriangle triangles[]; };
layout(set = 0, binding = 3, scalar) readonly buffer Materials { GpuMaterial materials[]; };
layout(set = 0, binding = 4, scalar) readonly buffer Lights { GpuLight lights[]; };

struct HitPayload { float t; uint triangle; vec2 bary; };
layout(location = 0) rayPayloadEXT HitPayload hit_payload;
layout(location = 1) rayPayloadEXT uint shadow_visible;

struct Hit { float t; uint triangle; float u; float v; };

// Closest hit with 0 <= t <= t_max (the software traversal takes 0 < t < t_max: a hit at
// exactly t = 0 or t_max is the one difference; ray origins are offset off surfaces).
bool closest_hit(vec3 origin, vec3 dir, float t_max, out Hit hit) {
    hit_payload.triangle = 0xffffffffu;
    traceRayEXT(tlas, gl_RayFlagsOpaqueEXT, 0xff, 0, 0, 0, origin, 0.0, dir, t_max, 0);
    hit.t = hit_payload.t;
    hit.triangle = hit_payload.triangle;
    hit.u = hit_payload.bary.x;
    hit.v = hit_payload.bary.y;
    return hit_payload.triangle != 0xffffffffu;
}

bool occluded(vec3 origin, vec3 dir, float t_max) {
    shadow_visible = 0u;
    traceRayEXT(tlas,
                gl_RayFlagsOpaqueEXT | gl_RayFlagsTerminateOnFirstHitEXT | gl_RayFlagsSkipClosestHitShaderEXT,
                0xff, 0, 0, 1, origin, 0.0, dir, t_max, 1);
    return shadow_visible == 0u;
}

SurfacePoint hit_surface(Hit hit) {
    GpuTriangle t = triangles[hit.triangle];
    return surface_point(vertices[t.indices.x], vertices[t.indices.y], vertices[t.indices.z], hit.u, hit.v);
}

// Launch index: the host launches (min(n, 8192), ceil(n / 8192), 1).
uint launch_index() { return gl_LaunchIDEXT.y * gl_LaunchSizeEXT.x + gl_LaunchIDEXT.x; }

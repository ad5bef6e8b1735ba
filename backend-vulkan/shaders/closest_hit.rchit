#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// The closest-hit stage of every ray-tracing kernel (hit group 0): the hit distance, the
// triangle (the instance's custom index is its level's first triangle, and each level's
// BLAS holds its triangles in the triangle buffer's order: accel.rs) and the barycentrics (u, v), weights 1 - u - v, u, v of vertices 0, 1, 2, core's
// convention (geometry.rs, Moller-Trumbore's u and v).

#include "common/layout.glsl"
#include "common/prelude.glsl"

layout(location = 0) rayPayloadInEXT HitPayload hit_payload;
hitAttributeEXT vec2 bary;

void main() {
    hit_payload.t = gl_HitTEXT;
    hit_payload.triangle = uint(gl_InstanceCustomIndexEXT) + uint(gl_PrimitiveID);
    hit_payload.bary = bary;
}

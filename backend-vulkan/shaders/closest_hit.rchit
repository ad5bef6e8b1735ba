#version 460
#extension GL_EXT_ray_tracing : require
// Closest hit of every ray-tracing kernel: distance, triangle (= gl_PrimitiveID, the
// triangle buffer's order) and barycentrics (weights 1-u-v, u, v of vertices 0, 1, 2,
// core's convention).

struct HitPayload { float t; uint triangle; vec2 bary; };
layout(location = 0) rayPayloadInEXT HitPayload hit_payload;
hitAttributeEXT vec2 bary;

void main() {
    hit_payload.t = gl_HitTEXT;
    hit_payload.triangle = gl_PrimitiveID;
    hit_payload.bary = bary;
}

#version 460
#extension GL_EXT_ray_tracing : require
// Miss of closest-hit rays: no triangle.

struct HitPayload { float t; uint triangle; vec2 bary; };
layout(location = 0) rayPayloadInEXT HitPayload hit_payload;

void main() { hit_payload.triangle = 0xffffffffu; }

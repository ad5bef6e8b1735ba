#version 460
#extension GL_EXT_ray_tracing : require
#extension GL_GOOGLE_include_directive : require
// Miss stage 0, closest-hit rays (trace.glsl's closest_hit): no triangle.

#include "common/layout.glsl"
#include "common/prelude.glsl"

layout(location = 0) rayPayloadInEXT HitPayload hit_payload;

void main() { hit_payload.triangle = NO_HIT; }

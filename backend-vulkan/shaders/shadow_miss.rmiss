#version 460
#extension GL_EXT_ray_tracing : require
// Miss stage 1, shadow rays (trace.glsl's occluded): nothing in the way, the light is
// visible.

layout(location = 1) rayPayloadInEXT uint shadow_visible;

void main() { shadow_visible = 1u; }

// The G-buffer's planes (core::device::layout::GBUFFER_PLANES): plane k of pixel i holds
// bytes 16k .. 16k + 16 of its GBufferTexel as four u32 words, so that no per-pixel buffer
// is over 16 bytes a pixel. A kernel that needs this file declares the four planes as
// `gbuffer0` .. `gbuffer3: array<vec4<u32>>` (read or read_write); the words are the
// texel's bits (bitcast), so the assembled texel is bitwise the texel.

// core's GBufferTexel::from_planes.
fn gbuffer_from_planes(p0: vec4<u32>, p1: vec4<u32>, p2: vec4<u32>, p3: vec4<u32>) -> GBufferTexel {
    var g: GBufferTexel;
    g.position = bitcast<vec3<f32>>(p0.xyz);
    g.depth = bitcast<f32>(p0.w);
    g.normal = bitcast<vec3<f32>>(p1.xyz);
    g.geometric_normal = p1.w;
    g.albedo = bitcast<vec3<f32>>(p2.xyz);
    g.material = p2.w;
    g.uv = bitcast<vec2<f32>>(p3.xy);
    g.view_distance = bitcast<f32>(p3.z);
    g.flags = p3.w;
    return g;
}

// The texel of pixel `i`, assembled from the planes.
fn load_gbuffer(i: u32) -> GBufferTexel {
    return gbuffer_from_planes(gbuffer0[i], gbuffer1[i], gbuffer2[i], gbuffer3[i]);
}

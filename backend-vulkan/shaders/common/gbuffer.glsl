// The G-buffer's planes (core::device::layout::GBUFFER_PLANES): plane k of pixel i holds
// bytes 16k .. 16k + 16 of its GBufferTexel as a uvec4 (the texel's bits: uintBitsToFloat
// and floatBitsToUint, so the assembled texel is bitwise the texel), so that no per-pixel
// buffer is over 16 bytes a pixel. A stage that reads the G-buffer declares the planes as
// `gbuffer0` .. `gbuffer3` (`uvec4 gbufferK[]`), then includes this file.

// core's GBufferTexel::from_planes.
GBufferTexel gbuffer_from_planes(uvec4 p0, uvec4 p1, uvec4 p2, uvec4 p3) {
    return GBufferTexel(uintBitsToFloat(p0.xyz), uintBitsToFloat(p0.w),
                        uintBitsToFloat(p1.xyz), p1.w,
                        uintBitsToFloat(p2.xyz), p2.w,
                        uintBitsToFloat(p3.xy), uintBitsToFloat(p3.z), p3.w);
}

#ifndef GBUFFER_WRITE_ONLY
// The texel of pixel `i`, assembled from the planes.
GBufferTexel load_gbuffer(uint i) {
    return gbuffer_from_planes(gbuffer0[i], gbuffer1[i], gbuffer2[i], gbuffer3[i]);
}
#else
// Writes the texel of pixel `i` into the planes (core's GBufferTexel::to_planes).
void store_gbuffer(uint i, GBufferTexel g) {
    gbuffer0[i] = uvec4(floatBitsToUint(g.position), floatBitsToUint(g.depth));
    gbuffer1[i] = uvec4(floatBitsToUint(g.normal), g.geometric_normal);
    gbuffer2[i] = uvec4(floatBitsToUint(g.albedo), g.material);
    gbuffer3[i] = uvec4(floatBitsToUint(g.uv), floatBitsToUint(g.view_distance), g.flags);
}
#endif

// Mirror of backend-opencl/kernels/common/density_gather.cl's GatherTexel and
// core::math::density_gather::edge_texel: what a gather reads of a G-buffer texel and the
// edge texel made of it. A kernel that needs this file declares the G-buffer planes
// `gbuffer0`, `gbuffer1` and `gbuffer3: array<vec4<u32>>`.

// What the gather needs of a G-buffer texel (planes 0, 1 and 3 only).
struct GatherTexel {
    receiver: u32,
    depth: f32,
    normal: vec3<f32>,
}

fn load_gather_texel(i: u32) -> GatherTexel {
    var t: GatherTexel;
    t.receiver = gbuffer3[i].w & GBUFFER_RECEIVER;
    t.depth = bitcast<f32>(gbuffer0[i].w);
    t.normal = bitcast<vec3<f32>>(gbuffer1[i].xyz);
    return t;
}

// A pixel's edge texel: (view depth, normal) of a receiver, the G-buffer's bits; depth
// EDGE_TEXEL_NOT_RECEIVER elsewhere.
fn edge_texel(t: GatherTexel) -> vec4<f32> {
    if (t.receiver != 0u) {
        return vec4<f32>(t.depth, t.normal);
    }
    return vec4<f32>(EDGE_TEXEL_NOT_RECEIVER, 0.0, 0.0, 0.0);
}

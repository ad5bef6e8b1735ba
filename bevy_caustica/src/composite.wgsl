// bevy_caustica: caustica's light (linear radiance, in the view's size) added to the
// view's HDR target, times the camera's exposure (as Bevy's PBR shader scales its own
// light). Non-finite texels add nothing.

@group(0) @binding(0) var caustics: texture_2d<f32>;
// x: exposure times the Caustics' strength; y, z: the viewport's origin in the target
@group(0) @binding(1) var<uniform> params: vec4<f32>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let xy = vec2<i32>(floor(p.xy)) - vec2<i32>(params.yz);
    let c = textureLoad(caustics, xy, 0).rgb * params.x;
    let finite = all(c == c) && all(abs(c) < vec3<f32>(6.0e4));
    return vec4<f32>(select(vec3<f32>(0.0), max(c, vec3<f32>(0.0)), finite), 0.0);
}

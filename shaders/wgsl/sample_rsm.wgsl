// needs: layout prelude vector rng sampling footprint scene packing geometry photon_gi
// sample_rsm (Smal 2019, section 24.2.1, Figure 24-3): sample i of the light's rotated
// Hammersley set warped through its faces' importance pyramids (rsm::warp_rsm) to an RSM
// texel, and the photon leaving it. Mirror of backend-cpu/src/kernels/sample_rsm.rs
// (rsm_photon) and backend-opencl/kernels/sample_rsm.cl.

@group(0) @binding(0) var<uniform> params: RsmParams;
@group(0) @binding(1) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(2) var<storage, read> texels: array<RsmTexel>;
@group(0) @binding(3) var<storage, read> pyramid: array<f32>;
@group(0) @binding(4) var<storage, read_write> photons: array<RsmPhoton>;

// rsm::warp_rsm over faces params.face .. + face_count: (face, texel x, texel y) and the
// probability and leftover sample; false when no face has weight.
fn warp_rsm(u0: vec2<f32>, face_out: ptr<function, u32>, texel: ptr<function, vec2<u32>>,
            probability: ptr<function, f32>, within: ptr<function, vec2<f32>>) -> bool {
    let p = params;
    let plen = pyramid_len(p.side);
    let levels = level_count(p.side);
    let top = level_offset(p.side, levels - 1u);
    let faces = min(p.face_count, 6u);
    var rests: array<f32, 7>;
    rests[faces] = 0.0;
    for (var f = i32(faces) - 1; f >= 0; f--) {
        rests[f] = pyramid[(p.face + u32(f)) * plen + top] + rests[f + 1];
    }
    if (!(rests[0] > 0.0)) {
        return false;
    }
    var u = u0;
    var prob = 1.0;
    var face = faces - 1u;
    for (var f = 0u; f + 1u < faces; f++) {
        let w = warp_split(u.x, warp_ratio(pyramid[(p.face + f) * plen + top], rests[f]));
        u.x = w.y;
        prob *= w.z;
        if (w.x > 0.5) {
            face = f;
            break;
        }
    }
    let base = (p.face + face) * plen;
    var x = 0u;
    var y = 0u;
    for (var k = i32(levels) - 2; k >= 0; k--) {
        let s = p.side >> u32(k);
        let off = base + level_offset(p.side, u32(k));
        let a = pyramid[off + (2u * y) * s + 2u * x];
        let b = pyramid[off + (2u * y) * s + 2u * x + 1u];
        let c = pyramid[off + (2u * y + 1u) * s + 2u * x];
        let d = pyramid[off + (2u * y + 1u) * s + 2u * x + 1u];
        let h = warp_split(u.x, warp_ratio(a + c, (a + c) + (b + d)));
        let left = h.x > 0.5;
        let top_row = select(b, a, left);
        let bottom = select(d, c, left);
        let v = warp_split(u.y, warp_ratio(top_row, top_row + bottom));
        u = vec2<f32>(h.y, v.y);
        prob *= h.z * v.z;
        x = 2u * x + select(1u, 0u, left);
        y = 2u * y + select(1u, 0u, v.x > 0.5);
    }
    *face_out = face;
    *texel = vec2<u32>(x, y);
    *probability = prob;
    *within = u;
    return prob > 0.0;
}

fn sample_rsm(i: u32) {
    let p = params;
    if (i >= p.sample_count) {
        return;
    }
    let shift = vec2<f32>(random_f32(p.seed, p.light, 0u, 0u), random_f32(p.seed, p.light, 0u, 1u));
    let u = hammersley(i, p.sample_count, shift);
    var out: RsmPhoton;
    out.origin = vec3<f32>(0.0);
    out.direction = 0u;
    out.flux = vec3<f32>(0.0);
    out.bounces = 0u;
    var face: u32;
    var texel: vec2<u32>;
    var probability: f32;
    var within: vec2<f32>;
    if (warp_rsm(u, &face, &texel, &probability, &within)) {
        let t = texels[(p.face + face) * p.side * p.side + texel.y * p.side + texel.x];
        let scale = 1.0 / (probability * f32(p.sample_count));
        let flux = t.flux * scale;
        if (t.kind == RSM_TEXEL_DIFFUSE) {
            let n = unpack_unit_vector(t.normal);
            out.origin = offset_ray_origin(t.position, n);
            out.direction = pack_unit_vector(cosine_hemisphere(within, n));
            out.flux = flux;
            out.bounces = 1u;
        } else if (t.kind == RSM_TEXEL_SPECULAR) {
            let light = lights[p.light];
            var origin = light.position.xyz;
            if (light.kind == LIGHT_DIRECTIONAL) {
                origin = ortho_origin(t.position, p.face_camera.position, p.face_camera.forward);
            }
            out.origin = origin;
            out.direction = pack_unit_vector(normalize3(t.position - origin));
            out.flux = flux;
        }
    }
    photons[p.first_sample + i] = out;
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    sample_rsm(i);
}

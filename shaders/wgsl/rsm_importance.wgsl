// needs: layout prelude vector sampling footprint scene gbuffer packing photon_gi
// rsm_importance (Smal 2019, section 24.2.1): level 0 writes a face's RSM texels and
// importance from the G-buffer its face camera rendered; level k > 0 the 2x2 sums of level
// k - 1 of faces 0 ..= params.face. Mirror of backend-cpu/src/kernels/rsm_importance.rs
// (rsm_texel, rsm_level) and backend-opencl/kernels/rsm_importance.cl.

@group(0) @binding(0) var<uniform> params: RsmParams;
@group(0) @binding(1) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(2) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> gbuffer2: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(6) var<storage, read_write> texels: array<RsmTexel>;
@group(0) @binding(7) var<storage, read_write> pyramid: array<f32>;

// Level 0, texel i of the face.
fn rsm_texel(i: u32) {
    let p = params;
    let n = p.side * p.side;
    let at = p.face * n + i;
    let level0 = p.face * pyramid_len(p.side) + i;
    var t: RsmTexel;
    t.kind = RSM_TEXEL_NONE;
    var importance = 0.0;
    let g = load_gbuffer(i);
    if (g.material != NO_MATERIAL) {
        let light = lights[p.light];
        let x = i % p.side;
        let y = i / p.side;
        var falloff = 1.0;
        if (light.kind == LIGHT_SPOT) {
            let dir = camera_ray(p.face_camera, x, y);
            falloff = light_spot_falloff(dir, light);
        }
        var arriving: vec3<f32>;
        if (light.kind == LIGHT_DIRECTIONAL) {
            arriving = ortho_texel_flux(light.intensity.xyz, p.side, -p.face_camera.tan_half_fov_x);
        } else {
            arriving = texel_arriving_flux(light.intensity.xyz, falloff, x, y, p.side,
                                           p.face_camera.tan_half_fov_x);
        }
        let imp = luminance(arriving * g.albedo);
        if (imp > 0.0 && is_finite_f32(imp)) {
            let diffuse = (g.flags & GBUFFER_RECEIVER) != 0u;
            t.position = g.position;
            t.normal = pack_unit_vector(g.normal);
            t.flux = select(arriving, arriving * g.albedo, diffuse);
            t.kind = select(RSM_TEXEL_SPECULAR, RSM_TEXEL_DIFFUSE, diffuse);
            importance = pyramid_weight(p.sampling, imp);
        }
    }
    texels[at] = t;
    pyramid[level0] = importance;
}

// Level k > 0: thread i is face i / s^2, texel i % s^2 of the level.
fn rsm_level(i: u32) {
    let p = params;
    let s = p.side >> p.level;
    let sb = s * 2u;
    let face = i / (s * s);
    let j = i % (s * s);
    let base = face * pyramid_len(p.side);
    let below = base + level_offset(p.side, p.level - 1u);
    let x = 2u * (j % s);
    let y = 2u * (j / s);
    // rsm::pyramid_sum: (a + c) + (b + d), columns first
    let a = pyramid[below + y * sb + x];
    let c = pyramid[below + (y + 1u) * sb + x];
    let b = pyramid[below + y * sb + x + 1u];
    let d = pyramid[below + (y + 1u) * sb + x + 1u];
    pyramid[base + level_offset(p.side, p.level) + j] = (a + c) + (b + d);
}

fn rsm_importance(i: u32) {
    let p = params;
    if (p.level == 0u) {
        if (i < p.side * p.side) {
            rsm_texel(i);
        }
    } else {
        let s = p.side >> p.level;
        if (i < (p.face + 1u) * s * s) {
            rsm_level(i);
        }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    rsm_importance(i);
}

// needs: layout prelude vector optics geometry traversal scene gbuffer specular_tree
// direct_light: radiance from the lights with shadow rays; mirror and glass pixels follow
// their specular ray tree. Mirror of backend-opencl/kernels/direct_light.cl and
// backend-cpu/src/kernels/direct_light.rs.

@group(0) @binding(0) var<storage, read> vertices: array<GpuVertex>;
@group(0) @binding(1) var<storage, read> triangles: array<GpuTriangle>;
@group(0) @binding(2) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(3) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(4) var<storage, read> nodes: array<vec4<u32>>;
@group(0) @binding(5) var<uniform> params: DirectParams;
@group(0) @binding(6) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(7) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read> gbuffer2: array<vec4<u32>>;
@group(0) @binding(9) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(10) var<storage, read_write> out: array<vec4<f32>>;

// Reflected radiance of a Lambertian surface at `pos` (shading normal `n`, geometric
// normal `ng`, both on the viewer's side), lit by every light with shadow rays.
fn shade_diffuse(light_count: u32, pos: vec3<f32>, n: vec3<f32>, ng: vec3<f32>,
                 albedo: vec3<f32>) -> vec3<f32> {
    var e = vec3<f32>(0.0); // irradiance, W/m^2
    for (var k = 0u; k < light_count; k++) {
        let light = lights[k];
        var wi: vec3<f32>;
        var dist: f32;
        var scale: f32;
        let lpos = light.position.xyz;
        if (light.kind == LIGHT_DIRECTIONAL) {
            wi = -light.direction.xyz;
            dist = NO_T_MAX; // OpenCL: INFINITY
            scale = 1.0;
        } else {
            let to = lpos - pos;
            let d2 = dot3(to, to);
            if (d2 <= 0.0) {
                continue;
            }
            let d = sqrt(d2);
            wi = to / d;
            var falloff = 1.0;
            if (light.kind == LIGHT_SPOT) {
                falloff = light_spot_falloff(-wi, light);
            }
            dist = d;
            scale = saturate_radiance(falloff / d2);
        }
        let cos_t = dot3(n, wi);
        if (cos_t <= 0.0 || scale <= 0.0 || dot3(ng, wi) <= 0.0) {
            continue;
        }
        let origin = offset_ray_origin(pos, ng);
        // OpenCL's isfinite(dist): false exactly for the directional sentinel (and for an
        // infinite or NaN distance, as there).
        var t_max = NO_T_MAX;
        if (dist < NO_T_MAX) {
            t_max = length3(origin - lpos) * (1.0f - 1e-5f);
        }
        if (occluded(origin, wi, t_max)) {
            continue;
        }
        e = saturate_radiance3(e + light.intensity.xyz * (scale * cos_t));
    }
    return albedo / PI_F * e;
}

// The specular tree's diffuse end (common/specular_tree.wgsl): the lights' shading.
fn diffuse_end(hit: Hit, s: SurfacePoint, m: GpuMaterial, n: vec3<f32>,
               ng_view: vec3<f32>, distance: f32, cos_in: f32, dir: vec3<f32>) -> vec3<f32> {
    return shade_diffuse(params.light_count, s.position, n, ng_view, m.color.xyz);
}

fn direct_light(i: u32) {
    let p = params;
    let w = p.camera.width;
    if (i >= w * p.camera.height) {
        return;
    }
    let g = load_gbuffer(i);
    if (g.depth <= 0.0) {
        out[i] = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return;
    }
    var l: vec3<f32>;
    if ((g.flags & GBUFFER_RECEIVER) != 0u) {
        let n = g.normal;
        l = shade_diffuse(p.light_count, g.position, n, n, g.albedo);
    } else {
        l = specular_tree(p.max_specular_depth, p.min_weight, p.fresnel_model, p.camera.position,
                          camera_ray(p.camera, i % w, i / w));
    }
    out[i] = vec4<f32>(saturate_radiance3(l), 1.0);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    direct_light(i);
}

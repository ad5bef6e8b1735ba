// needs: layout prelude vector packing geometry traversal scene
// primary_gbuffer: one camera ray per pixel; mirror of backend-opencl/kernels/
// primary_gbuffer.cl and backend-cpu/src/kernels/primary_gbuffer.rs.

@group(0) @binding(0) var<storage, read> vertices: array<GpuVertex>;
@group(0) @binding(1) var<storage, read> triangles: array<GpuTriangle>;
@group(0) @binding(2) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(3) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(4) var<storage, read> nodes: array<vec4<u32>>;
@group(0) @binding(5) var<uniform> camera: GpuCamera;
@group(0) @binding(6) var<storage, read_write> gbuffer0: array<vec4<u32>>;
@group(0) @binding(7) var<storage, read_write> gbuffer1: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read_write> gbuffer2: array<vec4<u32>>;
@group(0) @binding(9) var<storage, read_write> gbuffer3: array<vec4<u32>>;

// Writes the texel of pixel `i` into the G-buffer's planes (core's
// GBufferTexel::to_planes; load_gbuffer in common/gbuffer.wgsl reads them back).
fn store_gbuffer(i: u32, g: GBufferTexel) {
    gbuffer0[i] = vec4<u32>(bitcast<vec3<u32>>(g.position), bitcast<u32>(g.depth));
    gbuffer1[i] = vec4<u32>(bitcast<vec3<u32>>(g.normal), g.geometric_normal);
    gbuffer2[i] = vec4<u32>(bitcast<vec3<u32>>(g.albedo), g.material);
    gbuffer3[i] = vec4<u32>(bitcast<vec2<u32>>(g.uv), bitcast<u32>(g.view_distance), g.flags);
}

fn primary_gbuffer(i: u32) {
    let cam = camera;
    if (i >= cam.width * cam.height) {
        return;
    }
    let px = i % cam.width;
    let py = i / cam.width;
    var origin: vec3<f32>;
    let dir = primary_ray(cam, px, py, &origin);
    var g: GBufferTexel; // zero-initialised, as the OpenCL loop clears it
    var hit: Hit;
    if (!closest_hit(origin, dir, NO_T_MAX, &hit)) {
        g.material = NO_MATERIAL;
        store_gbuffer(i, g);
        return;
    }
    let s = hit_surface(hit);
    let mat = triangles[hit.triangle].material;
    let m = materials[mat];
    let n = facing_normal(s.shading_normal, dir);
    let diffuse = m.kind == MATERIAL_DIFFUSE;
    g.position = s.position;
    g.depth = hit.t * dot3(dir, cam.forward);
    g.normal = n;
    g.geometric_normal = pack_unit_vector(facing_normal(s.geometric_normal, dir));
    g.albedo = m.color.xyz;
    g.material = mat;
    g.uv = s.uv;
    g.view_distance = hit.t;
    g.flags = select(0u, GBUFFER_RECEIVER, diffuse);
    store_gbuffer(i, g);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    // `lights` is part of the scene bindings but unused here; wgpu derives the bind group
    // layout from the bindings the entry point uses, so it is referenced (a length query,
    // no memory access) to keep binding 3 in the layout the host binds.
    _ = arrayLength(&lights);
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    primary_gbuffer(i);
}

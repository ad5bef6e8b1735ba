// needs: types vector geometry traversal scene
// primary_gbuffer: one camera ray per pixel; mirror of backend-opencl/kernels/
// primary_gbuffer.cl and backend-cpu/src/kernels/gbuffer.rs.

@group(0) @binding(0) var<storage, read> vertices: array<GpuVertex>;
@group(0) @binding(1) var<storage, read> triangles: array<GpuTriangle>;
@group(0) @binding(2) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(3) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(4) var<storage, read> nodes: array<vec4<u32>>;
@group(0) @binding(5) var<uniform> camera: GpuCamera;
@group(0) @binding(6) var<storage, read_write> gbuffer: array<GBufferTexel>;

fn primary_gbuffer(i: u32) {
    let cam = camera;
    if (i >= cam.width * cam.height) {
        return;
    }
    let px = i % cam.width;
    let py = i / cam.width;
    let dir = camera_ray(cam, px, py);
    let origin = cam.position;
    var g: GBufferTexel; // zero-initialised, as the OpenCL loop clears it
    var hit: Hit;
    if (!closest_hit(origin, dir, NO_T_MAX, &hit)) {
        g.material = NO_MATERIAL;
        gbuffer[i] = g;
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
    g.roughness = select(0.0, 1.0, diffuse);
    g.albedo = m.color.xyz;
    g.material = mat;
    g.uv = s.uv;
    g.view_distance = hit.t;
    g.flags = select(0u, GBUFFER_RECEIVER, diffuse);
    gbuffer[i] = g;
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

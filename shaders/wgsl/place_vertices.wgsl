// needs: layout prelude vector
// place_vertices: an instance's world vertices placed from its object-space vertices (the
// contract in core/src/kernels/place_vertices.rs). Mirror of core's
// device::placement::place_vertices (the CPU backend's kernel) and
// backend-opencl/kernels/place_vertices.cl: the same products and sums in the same order.
// WGSL's division and sqrt are accurate to a few ulp and a driver may fuse a * b + c
// (prelude.wgsl), so a vertex may differ from the host's placement in its last bits; a
// build places through this kernel as a move does, so a moved scene stays a fresh one.

@group(0) @binding(0) var<uniform> params: PlacementParams;
@group(0) @binding(1) var<storage, read> object_vertices: array<GpuVertex>;
@group(0) @binding(2) var<storage, read_write> vertices: array<GpuVertex>;

fn place_vertices(i: u32) {
    let p = params;
    if (i >= p.count) {
        return;
    }
    let v = object_vertices[p.object_first + i];
    var w: GpuVertex;
    // world_from_object: x_axis x + y_axis y + z_axis z, then the translation
    w.position = p.axis_x.xyz * v.position.x + p.axis_y.xyz * v.position.y +
                 p.axis_z.xyz * v.position.z + p.translation.xyz;
    w.u = v.u;
    // the normal matrix's columns likewise, renormalised (+Y for a normal of no length)
    w.normal = normalize_or(p.normal_x.xyz * v.normal.x + p.normal_y.xyz * v.normal.y +
                            p.normal_z.xyz * v.normal.z, vec3<f32>(0.0, 1.0, 0.0));
    w.v = v.v;
    vertices[p.world_first + i] = w;
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    place_vertices(i);
}

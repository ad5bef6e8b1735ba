// place_vertices: an instance's world vertices placed from its object-space vertices (the
// contract in core/src/kernels/place_vertices.rs). Mirror of core's
// device::placement::place_vertices (the CPU backend's kernel): the same products and sums
// in the same order with FP_CONTRACT off, so the bits are the host's on a device that
// divides and takes square roots correctly rounded (the program asks for it where the
// device offers it) and keeps subnormals.

__kernel void place_vertices(__global const PlacementParams* p,
                             __global const GpuVertex* object_vertices,
                             __global GpuVertex* vertices) {
    uint i = get_global_id(0);
    if (i >= p->count) return;
    __global const GpuVertex* v = &object_vertices[p->object_first + i];
    float3 x = load3g(v->position), n = load3g(v->normal);
    // world_from_object: x_axis x + y_axis y + z_axis z, then the translation
    float3 position = load3g(p->axis_x) * x.x + load3g(p->axis_y) * x.y +
                      load3g(p->axis_z) * x.z + load3g(p->translation);
    // the normal matrix's columns likewise, renormalised (+Y for a normal of no length)
    float3 normal = normalize_or(load3g(p->normal_x) * n.x + load3g(p->normal_y) * n.y +
                                     load3g(p->normal_z) * n.z,
                                 (float3)(0.0f, 1.0f, 0.0f));
    __global GpuVertex* w = &vertices[p->world_first + i];
    store3g(w->position, position);
    w->u = v->u;
    store3g(w->normal, normal);
    w->v = v->v;
}

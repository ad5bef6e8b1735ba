// primary_gbuffer: one camera ray per pixel; mirror of backend-cpu/src/kernels/primary_gbuffer.rs.

__kernel void primary_gbuffer(SCENE_PARAMS, __global const GpuCamera* cam,
                              GBUFFER_PARAMS(__global)) {
    uint i = get_global_id(0);
    if (i >= cam->width * cam->height) return;
    uint px = i % cam->width, py = i / cam->width;
    float3 origin;
    float3 dir = primary_ray(cam, px, py, &origin);
    GBufferTexel g;
    for (int k = 0; k < 16; k++) ((float*)&g)[k] = 0.0f;
    Hit hit;
    if (!closest_hit(nodes, node_count, vertices, triangles, origin, dir, INFINITY, &hit)) {
        g.material = NO_MATERIAL;
        store_gbuffer(GBUFFER_ARGS, i, &g);
        return;
    }
    SurfacePoint s = hit_surface(vertices, triangles, &hit);
    uint mat = triangles[hit.triangle].material;
    __global const GpuMaterial* m = &materials[mat];
    float3 n = facing_normal(s.shading_normal, dir);
    bool diffuse = m->kind == MATERIAL_DIFFUSE;
    store3(g.position, s.position);
    g.depth = hit.t * dot3(dir, load3g(cam->forward));
    store3(g.normal, n);
    g.geometric_normal = pack_unit_vector(facing_normal(s.geometric_normal, dir));
    g.albedo[0] = m->color[0];
    g.albedo[1] = m->color[1];
    g.albedo[2] = m->color[2];
    g.material = mat;
    g.uv[0] = s.uv.x;
    g.uv[1] = s.uv.y;
    g.view_distance = hit.t;
    g.flags = diffuse ? GBUFFER_RECEIVER : 0u;
    store_gbuffer(GBUFFER_ARGS, i, &g);
}

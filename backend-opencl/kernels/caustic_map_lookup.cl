// caustic_map_lookup (Vanderstichelen 2021, section 3.3): the camera ray's specular tree
// (common/specular_tree.cl) reads the caustic map of each diffuse surface it ends on.
// Mirror of backend-cpu/src/kernels/caustic_map_lookup.rs.

__kernel void caustic_map_lookup(SCENE_PARAMS, __global const MapLookupParams* p,
                                 __global const uint* triangle_tiles, __global const uint4* tiles,
                                 __global const uint2* texels, __global const float4* map,
                                 __global float4* out, __global const uint* centroids) {
    uint i = get_global_id(0);
    uint w = p->camera.width;
    if (i >= w * p->camera.height) return;
    DiffuseEnd end;
    end.light_count = 0u;
    end.triangle_tiles = triangle_tiles;
    end.tiles = tiles;
    end.texels = texels;
    end.map = map;
    end.centroids = centroids;
    end.atlas_width = p->atlas_width;
    end.pixel_angle = 2.0f * p->camera.tan_half_fov_y / (float)p->camera.height;
    end.right = load3g(p->camera.right);
    float3 l = specular_tree(SCENE_ARGS, &end, p->max_specular_depth, p->min_weight,
                          p->fresnel_model,
                             load3g(p->camera.position), camera_ray(&p->camera, i % w, i / w));
    out[i] = (float4)(saturate_radiance3(l), 1.0f);
}

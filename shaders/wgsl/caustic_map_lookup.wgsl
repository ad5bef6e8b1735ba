// needs: layout prelude vector optics geometry traversal scene atlas specular_tree map_lookup
// caustic_map_lookup (Vanderstichelen 2021, section 3.3): the camera ray's specular tree reads the
// caustic map of each diffuse surface it ends on. Mirror of
// backend-opencl/kernels/caustic_map_lookup.cl, backend-vulkan/shaders/caustic_map_lookup.rgen
// and backend-cpu/src/kernels/caustic_map_lookup.rs.

@group(0) @binding(0) var<storage, read> vertices: array<GpuVertex>;
@group(0) @binding(1) var<storage, read> triangles: array<GpuTriangle>;
@group(0) @binding(2) var<storage, read> materials: array<GpuMaterial>;
@group(0) @binding(3) var<storage, read> lights: array<GpuLight>;
@group(0) @binding(4) var<storage, read> nodes: array<vec4<u32>>;
@group(0) @binding(5) var<uniform> params: MapLookupParams;
@group(0) @binding(6) var<storage, read> triangle_tiles: array<u32>;
@group(0) @binding(7) var<storage, read> tiles: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read> texels: array<vec2<u32>>;
@group(0) @binding(9) var<storage, read> map: array<vec4<f32>>;
@group(0) @binding(10) var<storage, read_write> out: array<vec4<f32>>;
@group(0) @binding(11) var<storage, read> centroids: array<u32>;

fn atlas_area(i: u32) -> f32 {
    return bitcast<f32>(texels[i].x);
}

fn map_irradiance(i: u32) -> vec3<f32> {
    return map[i].xyz;
}

fn atlas_centroid(i: u32) -> vec2<f32> {
    let k = i * CENTROID_WORDS;
    return texel_centroid(centroids[k], centroids[k + 1u], centroids[k + 2u]);
}

// The specular tree's diffuse end (common/specular_tree.wgsl): the caustic map.
fn diffuse_end(hit: Hit, s: SurfacePoint, m: GpuMaterial, n: vec3<f32>,
               ng_view: vec3<f32>, distance: f32, cos_in: f32, dir: vec3<f32>) -> vec3<f32> {
    let tile = triangle_tiles[hit.triangle];
    if (tile == NO_TILE) {
        return vec3<f32>(0.0);
    }
    let t = tiles[tile];
    let pixel_angle = 2.0 * params.camera.tan_half_fov_y / f32(params.camera.height);
    let tri = triangles[hit.triangle].indices;
    let v0 = vertices[tri.x];
    let v1 = vertices[tri.y];
    let v2 = vertices[tri.z];
    var extent = footprint_extent(dir, params.camera.right, pixel_angle * distance,
                                  v0.position, v1.position, v2.position, vec2<f32>(v0.u, v0.v),
                                  vec2<f32>(v1.u, v1.v), vec2<f32>(v2.u, v2.v), t.z);
    if (extent.x < 0.0) {
        // no UV Jacobian: the isotropic footprint
        let texel = atlas_texel_index(t, s.uv, params.atlas_width);
        extent = vec2<f32>(0.5 * footprint_texels(pixel_angle, distance, cos_in,
                                                  atlas_area(texel)));
    }
    let e = sample_caustic_map(t, s.uv, extent, params.atlas_width);
    return m.color.xyz / PI_F * e;
}

fn caustic_map_lookup(i: u32) {
    let p = params;
    let w = p.camera.width;
    if (i >= w * p.camera.height) {
        return;
    }
    // `lights` is part of every traced kernel's scene bindings; the lookup needs none.
    let unused = arrayLength(&lights);
    let l = specular_tree(p.max_specular_depth, p.min_weight, p.fresnel_model, p.camera.position,
                          camera_ray(p.camera, i % w, i / w));
    out[i] = vec4<f32>(saturate_radiance3(l), 1.0);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    caustic_map_lookup(i);
}

// gather_caustic_map (Vanderstichelen 2021, section 3.1, "Denoising"): per atlas texel, the
// flux-keeping N x N gather inside its tile, as irradiance. Mirror of
// backend-cpu/src/kernels/gather_caustic_map.rs.

__kernel void gather_caustic_map(__global const AtlasParams* p, __global const uint2* texels,
                                 __global const uint4* tiles,
                                 PHOTON_MAP_PARAMS(__global const), __global float4* out) {
    uint t = get_global_id(0);
    if (t >= p->width * p->height) return;
    uint tile = texels[t].y;
    if (tile == NO_TILE) {
        out[t] = (float4)(0.0f, 0.0f, 0.0f, 1.0f);
        return;
    }
    float3 e = gather_caustic_texel(texels, PHOTON_MAP_ARGS, p->flux_quantum, tiles[tile],
                                    t % p->width, t / p->width, p->gather_width, p->width);
    out[t] = (float4)(e, 1.0f);
}

// composite (Kim 2019, section 30.3.3): direct light + gathered caustics, alpha 1. Mirror
// of backend-cpu/src/kernels/composite.rs.

__kernel void composite(uint texels, __global const float4* direct,
                        __global const float4* caustics, __global float4* out) {
    uint i = get_global_id(0);
    if (i >= texels) return;
    out[i] = (float4)(saturate_radiance3(direct[i].xyz + caustics[i].xyz), 1.0f);
}

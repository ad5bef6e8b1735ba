// needs: layout prelude vector optics
// composite (Kim 2019, section 30.3.3): direct light + gathered caustics, alpha 1. Mirror
// of backend-opencl/kernels/composite.cl and backend-cpu/src/kernels/composite.rs. The
// texel count (the OpenCL `texels` argument) is the output's length.

@group(0) @binding(0) var<storage, read> direct: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> caustics: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> out: array<vec4<f32>>;

fn composite(i: u32) {
    let texels = arrayLength(&out);
    if (i >= texels) {
        return;
    }
    out[i] = vec4<f32>(saturate_radiance3(direct[i].xyz + caustics[i].xyz), 1.0);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    composite(i);
}

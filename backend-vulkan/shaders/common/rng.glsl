// Mirror of core/src/rng.rs and backend-opencl/kernels/rng.cl: counter-based random
// numbers (PCG hash). u32 arithmetic wraps in GLSL as in OpenCL and Rust's wrapping ops.

uint pcg_hash(uint input_) {
    uint state = input_ * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28) + 4u)) ^ state) * 277803737u;
    return (word >> 22) ^ word;
}

uint random_u32(uint seed, uint index, uint bounce, uint dimension) {
    uint h = pcg_hash(seed ^ pcg_hash(index));
    h = pcg_hash(h ^ (bounce * 0x9E3779B9u));
    return pcg_hash(h ^ (dimension * 0x85EBCA6Bu));
}

// float(x >> 8) is exact (24 bits); the product by 2^-24 is exact.
precise float u32_to_unit_f32(uint x) { return float(x >> 8) * (1.0 / 16777216.0); }

// core::math::rng::stratum_jitter: the cell's rotation plus the k-th R2 point, mod 1 in
// 0.32 fixed point.
float stratum_jitter(uint jitter_seed, uint index, uint dim, uint k) {
    uint step = (dim & 1u) == 1u ? R2_STEP_Y : R2_STEP_X;
    return u32_to_unit_f32(random_u32(jitter_seed, index, 0u, dim) + k * step);
}

float random_f32(uint seed, uint index, uint bounce, uint dimension) {
    return u32_to_unit_f32(random_u32(seed, index, bounce, dimension));
}

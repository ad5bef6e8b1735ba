// Mirror of core/src/rng.rs and backend-opencl/kernels/rng.cl: counter-based random
// numbers (PCG hash). u32 arithmetic wraps in WGSL as Rust's wrapping_mul/wrapping_add,
// so every backend draws bitwise the same numbers.

fn pcg_hash(input: u32) -> u32 {
    let state = input * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn random_u32(seed: u32, index: u32, bounce: u32, dimension: u32) -> u32 {
    var h = pcg_hash(seed ^ pcg_hash(index));
    h = pcg_hash(h ^ (bounce * 0x9E3779B9u));
    return pcg_hash(h ^ (dimension * 0x85EBCA6Bu));
}

// x >> 8 < 2^24 converts to f32 exactly; the product by 2^-24 is exact.
fn u32_to_unit_f32(x: u32) -> f32 {
    return f32(x >> 8u) * (1.0f / 16777216.0f);
}

// core::math::rng::stratum_jitter: the cell's rotation plus the k-th R2 point, mod 1 in
// 0.32 fixed point.
fn stratum_jitter(jitter_seed: u32, index: u32, dim: u32, k: u32) -> f32 {
    let step = select(R2_STEP_X, R2_STEP_Y, (dim & 1u) == 1u);
    return u32_to_unit_f32(random_u32(jitter_seed, index, 0u, dim) + k * step);
}

fn random_f32(seed: u32, index: u32, bounce: u32, dimension: u32) -> f32 {
    return u32_to_unit_f32(random_u32(seed, index, bounce, dimension));
}

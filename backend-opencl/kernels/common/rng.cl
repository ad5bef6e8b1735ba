// Mirror of core/src/rng.rs: counter-based random numbers (PCG hash).

inline uint pcg_hash(uint input) {
    uint state = input * 747796405u + 2891336453u;
    uint word = ((state >> ((state >> 28) + 4u)) ^ state) * 277803737u;
    return (word >> 22) ^ word;
}

inline uint random_u32(uint seed, uint index, uint bounce, uint dimension) {
    uint h = pcg_hash(seed ^ pcg_hash(index));
    h = pcg_hash(h ^ (bounce * 0x9E3779B9u));
    return pcg_hash(h ^ (dimension * 0x85EBCA6Bu));
}

inline float u32_to_unit_f32(uint x) { return (float)(x >> 8) * (1.0f / 16777216.0f); }

// core::math::rng::stratum_jitter: the cell's rotation plus the k-th R2 point, mod 1 in
// 0.32 fixed point.
inline float stratum_jitter(uint jitter_seed, uint index, uint dim, uint k) {
    uint step = (dim & 1u) ? R2_STEP_Y : R2_STEP_X;
    return u32_to_unit_f32(random_u32(jitter_seed, index, 0u, dim) + k * step);
}

inline float random_f32(uint seed, uint index, uint bounce, uint dimension) {
    return u32_to_unit_f32(random_u32(seed, index, bounce, dimension));
}

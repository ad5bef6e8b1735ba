// Mirror of core/src/math/fixed_point.rs and backend-opencl/kernels/common/fixed_point.cl, and 64-bit
// sums from 32-bit atomics: a u64 is a (lo, hi) pair of u32 words; adding to lo and
// carrying into hi gives the same final sum, in any order, as a 64-bit atomic add
// (exact and order-independent).
//
// GLSL functions cannot take a pointer to buffer memory, so the atomic helpers of
// fixed_point.cl live beside the buffer they add into: trace_photons.rgen's
// `atomic_add_u64_bank` (OpenCL's atomic_add_u64_local: ray generation shaders have no
// shared memory, so a photon adds into one of 64 counter banks in global memory), and
// reduce_counters.comp folds the banks into the counters (OpenCL's counters_flush_local).

struct Quantized {
    uint units;
    bool underflow;
    bool saturated;
};

Quantized quantize(float value, float quantum) {
    Quantized q = Quantized(0u, false, false);
    precise float x = value / quantum;
    if (!(x > 0.0)) return q;
    precise float r = floor(x + 0.5);
    // 4294967295.0 is 2^32 in f32, as in Rust and OpenCL.
    if (r >= 4294967295.0) {
        q.units = 0xFFFFFFFFu;
        q.saturated = true;
        return q;
    }
    q.units = uint(r);
    q.underflow = q.units == 0u;
    return q;
}

// The carry out of `old + v` (u32): 1 when the sum wraps.
uint u64_carry(uint old, uint v) { return old > 0xFFFFFFFFu - v ? 1u : 0u; }

bool counter_is_u64(uint k) {
    return k == COUNTER_RAYS || k == COUNTER_STORED_FLUX || k == COUNTER_STORED_FLUX + 2u ||
           k == COUNTER_STORED_FLUX + 4u;
}

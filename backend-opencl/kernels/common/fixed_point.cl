// Mirror of core/src/math/fixed_point.rs, and 64-bit sums from 32-bit atomics: a u64 is a
// (lo, hi) pair of u32 words; adding to lo and carrying into hi gives the same final sum,
// in any order, as a 64-bit atomic add: the deposit stays exact and order-independent.

typedef struct {
    uint units;
    bool underflow;
    bool saturated;
} Quantized;

inline Quantized quantize(float value, float quantum) {
    Quantized q = {0u, false, false};
    float x = value / quantum;
    if (!(x > 0.0f)) return q;
    float r = floor(x + 0.5f);
    if (r >= 4294967295.0f) {
        q.units = 0xFFFFFFFFu;
        q.saturated = true;
        return q;
    }
    q.units = (uint)r;
    q.underflow = q.units == 0u;
    return q;
}

inline void atomic_add_u64_global(volatile __global uint* w, uint lo, uint hi) {
    uint old = atomic_add(&w[0], lo);
    uint carry = old > 0xFFFFFFFFu - lo ? 1u : 0u;
    if (hi + carry != 0u) atomic_add(&w[1], hi + carry);
}

inline void atomic_add_u64_local(volatile __local uint* w, uint v) {
    uint old = atomic_add(&w[0], v);
    if (old > 0xFFFFFFFFu - v) atomic_inc(&w[1]);
}

// One stored photon into the work-group's counters `lc`: STORED and its flux in quanta
// (backend-cpu trace_photons.rs::count_stored).
inline void count_stored(const Photon* ph, float flux_quantum, volatile __local uint* lc) {
    atomic_inc(&lc[COUNTER_STORED]);
    for (uint ch = 0u; ch < 3u; ch++) {
        uint units = quantize(ph->flux[ch], flux_quantum).units;
        if (units != 0u) atomic_add_u64_local(&lc[COUNTER_STORED_FLUX + 2u * ch], units);
    }
}

// The photon counters of a work-group, summed in local memory (same word layout as
// core::gpu::counter) and added to the global counters once per group.
inline void counters_clear_local(volatile __local uint* lc) {
    for (uint k = get_local_id(0); k < COUNTER_WORDS; k += get_local_size(0)) lc[k] = 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
}

inline bool counter_is_u64(uint k) {
    return k == COUNTER_RAYS || k == COUNTER_STORED_FLUX || k == COUNTER_STORED_FLUX + 2 ||
           k == COUNTER_STORED_FLUX + 4;
}

inline void counters_flush_local(volatile __local uint* lc, volatile __global uint* counters) {
    barrier(CLK_LOCAL_MEM_FENCE);
    for (uint k = get_local_id(0); k < COUNTER_WORDS; k += get_local_size(0)) {
        if (counter_is_u64(k)) {
            if (lc[k] != 0u || lc[k + 1u] != 0u) atomic_add_u64_global(&counters[k], lc[k], lc[k + 1u]);
        } else if (k == 0u || !counter_is_u64(k - 1u)) {
            if (lc[k] != 0u) atomic_add(&counters[k], lc[k]);
        }
    }
}

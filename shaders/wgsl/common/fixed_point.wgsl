// Mirror of core/src/math/fixed_point.rs and backend-opencl/kernels/common/fixed_point.cl, and 64-bit
// sums from 32-bit atomics: a u64 is a (lo, hi) pair of u32 words; adding to lo and
// carrying into hi gives the same final sum, in any order, as a 64-bit atomic add
// (exact and order-independent). WGSL has no 64-bit integers at all, so every u64 here is such a pair.
//
// WGSL functions cannot take pointers to workgroup or storage memory, so the atomic helpers
// name their memory: a kernel that needs this file declares
//   var<workgroup> lc: array<atomic<u32>, COUNTER_WORDS>;   (OpenCL's __local uint lc[])
//   @group(0) @binding(N) var<storage, read_write> counters: array<atomic<u32>>;
// (trace_photons and deposit_screen do). The OpenCL `atomic_add_u64_global` on any global
// pointer becomes `atomic_add_u64_counters` here and a twin on `photon_map` in
// deposit_screen.wgsl, both built on `u64_carry`.

struct Quantized {
    units: u32,
    underflow: bool,
    saturated: bool,
}

fn quantize(value: f32, quantum: f32) -> Quantized {
    var q = Quantized(0u, false, false);
    let x = value / quantum;
    if (!(x > 0.0)) {
        return q;
    }
    let r = floor(x + 0.5);
    // 4294967295.0f is 2^32 in f32, as in Rust and OpenCL.
    if (r >= 4294967295.0f) {
        q.units = 0xFFFFFFFFu;
        q.saturated = true;
        return q;
    }
    q.units = u32(r);
    q.underflow = q.units == 0u;
    return q;
}

// The carry out of `old + v` (u32): 1 when the sum wraps.
fn u64_carry(old: u32, v: u32) -> u32 {
    return select(0u, 1u, old > 0xFFFFFFFFu - v);
}

// counters[k, k + 1] += (lo, hi)
fn atomic_add_u64_counters(k: u32, lo: u32, hi: u32) {
    let old = atomicAdd(&counters[k], lo);
    let carry = u64_carry(old, lo);
    if (hi + carry != 0u) {
        atomicAdd(&counters[k + 1u], hi + carry);
    }
}

// lc[k, k + 1] += v
fn atomic_add_u64_local(k: u32, v: u32) {
    let old = atomicAdd(&lc[k], v);
    if (old > 0xFFFFFFFFu - v) {
        atomicAdd(&lc[k + 1u], 1u);
    }
}

// One stored photon into the work-group's counters: STORED and its flux in quanta
// (backend-cpu trace_photons.rs::count_stored).
fn count_stored(ph: Photon, flux_quantum: f32) {
    atomicAdd(&lc[COUNTER_STORED], 1u);
    for (var ch = 0u; ch < 3u; ch++) {
        let units = quantize(ph.flux[ch], flux_quantum).units;
        if (units != 0u) {
            atomic_add_u64_local(COUNTER_STORED_FLUX + 2u * ch, units);
        }
    }
}

// The photon counters of a work-group, summed in workgroup memory (same word layout as
// core::gpu::counter) and added to the global counters once per group. `li` is the
// local invocation index. Both functions contain a workgroupBarrier: call them from
// uniform control flow (before any early return).
fn counters_clear_local(li: u32) {
    for (var k = li; k < COUNTER_WORDS; k += WORKGROUP_SIZE) {
        atomicStore(&lc[k], 0u);
    }
    workgroupBarrier();
}

fn counter_is_u64(k: u32) -> bool {
    return k == COUNTER_RAYS || k == COUNTER_STORED_FLUX || k == COUNTER_STORED_FLUX + 2u ||
           k == COUNTER_STORED_FLUX + 4u;
}

fn counters_flush_local(li: u32) {
    workgroupBarrier();
    for (var k = li; k < COUNTER_WORDS; k += WORKGROUP_SIZE) {
        if (counter_is_u64(k)) {
            let lo = atomicLoad(&lc[k]);
            let hi = atomicLoad(&lc[k + 1u]);
            if (lo != 0u || hi != 0u) {
                atomic_add_u64_counters(k, lo, hi);
            }
        } else if (k == 0u || !counter_is_u64(k - 1u)) {
            let v = atomicLoad(&lc[k]);
            if (v != 0u) {
                atomicAdd(&counters[k], v);
            }
        }
    }
}

#version 460
#extension GL_GOOGLE_include_directive : require
// reduce_counters: folds the 64 counter banks that trace_photons.rgen adds into (one
// bank per photon index mod 64, core::gpu::counter's word layout) into the frame's photon
// counters, and zeroes the banks for the next launch: OpenCL's counters_flush_local
// (fixed_point.cl), once for all banks. One invocation per word (dispatch 1 group):
// the (lo, hi) u64 words are summed with a carry (the lo word's invocation does the pair),
// the other u32 words wrap. Nothing else writes the counters or the banks meanwhile, so
// plain loads and stores suffice.
// Bindings (set 0): 0 the counter banks (64 x COUNTER_WORDS words), 1 the counters
// (COUNTER_WORDS words).

#include "common/layout.glsl"
#include "common/prelude.glsl"
#include "common/fixed_point.glsl"

layout(local_size_x = 64) in;
layout(set = 0, binding = 0, std430) buffer CounterBanks { uint counter_banks[]; };
layout(set = 0, binding = 1, std430) buffer Counters { uint counters[]; };

const uint COUNTER_BANKS = 64u;

void main() {
    uint k = gl_LocalInvocationIndex;
    if (k >= COUNTER_WORDS) return;
    if (k > 0u && counter_is_u64(k - 1u)) return; // a hi word: done with its lo word
    if (counter_is_u64(k)) {
        uint lo = 0u, hi = 0u;
        for (uint b = 0u; b < COUNTER_BANKS; b++) {
            uint w = b * COUNTER_WORDS + k;
            uint blo = counter_banks[w], bhi = counter_banks[w + 1u];
            hi += bhi + u64_carry(lo, blo);
            lo += blo;
            counter_banks[w] = 0u;
            counter_banks[w + 1u] = 0u;
        }
        uint old = counters[k];
        counters[k + 1u] += hi + u64_carry(old, lo);
        counters[k] = old + lo;
    } else {
        uint sum = 0u;
        for (uint b = 0u; b < COUNTER_BANKS; b++) {
            uint w = b * COUNTER_WORDS + k;
            sum += counter_banks[w];
            counter_banks[w] = 0u;
        }
        counters[k] += sum;
    }
}

#version 460
// Folds the 64 counter banks that trace_photons' ray generation shader adds into (to
// spread its atomics) into the frame's photon counters (core::gpu::counter layout: RAYS
// and STORED_FLUX are (lo, hi) u64 pairs, the rest u32 words that wrap), then zeroes the
// banks. One invocation per word; nothing else writes the counters meanwhile.

layout(local_size_x = 64) in;
layout(set = 0, binding = 0) buffer CounterBanks { uint banks[]; };
layout(set = 0, binding = 1) buffer Counters { uint counters[]; };

const uint WORDS = 20u;
const uint BANKS = 64u;

bool is_u64_lo(uint k) { return k == 10u || k == 12u || k == 14u || k == 16u; }
bool is_u64_hi(uint k) { return k == 11u || k == 13u || k == 15u || k == 17u; }

void main() {
    uint k = gl_LocalInvocationIndex;
    if (k >= WORDS || is_u64_hi(k)) return;
    if (is_u64_lo(k)) {
        uint lo = 0u, hi = 0u;
        for (uint b = 0u; b < BANKS; b++) {
            uint blo = banks[b * WORDS + k], bhi = banks[b * WORDS + k + 1u];
            uint s = lo + blo;
            hi += bhi + (s < lo ? 1u : 0u);
            lo = s;
            banks[b * WORDS + k] = 0u;
            banks[b * WORDS + k + 1u] = 0u;
        }
        uint s = counters[k] + lo;
        counters[k + 1u] += hi + (s < lo ? 1u : 0u);
        counters[k] = s;
    } else {
        uint sum = 0u;
        for (uint b = 0u; b < BANKS; b++) {
            sum += banks[b * WORDS + k];
            banks[b * WORDS + k] = 0u;
        }
        counters[k] += sum;
    }
}

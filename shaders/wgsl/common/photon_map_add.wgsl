// Fixed-point adds into the photon map's planes (core::device::layout::DEPOSIT_PLANES), for
// the kernels that deposit (deposit_screen, deposit_atlas): the kernel declares
// `photon_map0`, `photon_map1`, `photon_map2` as `array<atomic<u32>>`.

// atomicAdd on the photon-map plane `at.x`, index `at.y` (deposit_word's result).
fn atomic_add_photon_map(at: vec2<u32>, v: u32) -> u32 {
    if (at.x == 0u) {
        return atomicAdd(&photon_map0[at.y], v);
    }
    if (at.x == 1u) {
        return atomicAdd(&photon_map1[at.y], v);
    }
    return atomicAdd(&photon_map2[at.y], v);
}

// Words (word, word + 1) of pixel `pixel`'s texel += (lo, hi): fixed_point.cl's
// atomic_add_u64_global on the map. A pair never straddles two planes.
fn atomic_add_u64_photon_map(pixel: u32, word: u32, lo: u32, hi: u32) {
    let at = deposit_word(pixel, word);
    let old = atomic_add_photon_map(at, lo);
    let carry = u64_carry(old, lo);
    if (hi + carry != 0u) {
        atomic_add_photon_map(vec2<u32>(at.x, at.y + 1u), hi + carry);
    }
}

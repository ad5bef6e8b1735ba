// The screen photon map's planes (core::device::layout::DEPOSIT_PLANES): a kernel that
// needs this file declares `photon_map0`, `photon_map1` (4 words a pixel) and
// `photon_map2` (2 words a pixel) as `array<u32>`; `deposit_word` (prelude.wgsl) finds a
// texel word in them.

// Word `word` of pixel `pixel`'s DepositTexel.
fn photon_map_word(pixel: u32, word: u32) -> u32 {
    let at = deposit_word(pixel, word);
    if (at.x == 0u) {
        return photon_map0[at.y];
    }
    if (at.x == 1u) {
        return photon_map1[at.y];
    }
    return photon_map2[at.y];
}

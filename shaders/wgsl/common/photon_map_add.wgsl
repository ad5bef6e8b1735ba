// Fixed-point adds into the photon map's planes (core::device::layout::DEPOSIT_PLANES), for
// the kernels that deposit (deposit_screen, trace_photons' atlas deposit): the kernel declares
// `photon_map0`, `photon_map1`, `photon_map2` as `array<atomic<u32>>` and the work-group
// counters `lc`.

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

// backend-cpu deposit_screen.rs::photon_flux_units: the photon's flux per channel in
// flux quanta, underflow and saturation counted in `lc`.
fn photon_flux_units(ph: Photon, flux_quantum: f32) -> vec3<u32> {
    var units: vec3<u32>;
    for (var ch = 0u; ch < 3u; ch++) {
        let q = quantize(ph.flux[ch], flux_quantum);
        if (q.underflow) {
            atomicAdd(&lc[COUNTER_UNDERFLOW], 1u);
        }
        if (q.saturated) {
            atomicAdd(&lc[COUNTER_SATURATED], 1u);
        }
        units[ch] = q.units;
    }
    return units;
}

// backend-cpu deposit_screen.rs::deposit_photon_texel: photon `ph` added to texel `texel`
// (a screen pixel or an atlas texel): flux per channel, hit distance and a count in fixed
// point; underflow, saturation and the deposit counted in `lc`.
fn deposit_photon_texel(texel: u32, ph: Photon, flux_quantum: f32, hit_distance_quantum: f32) {
    let units = photon_flux_units(ph, flux_quantum);
    add_photon_texel(texel, units, quantize(ph.hit_distance, hit_distance_quantum).units);
    atomicAdd(&lc[COUNTER_DEPOSITED], 1u);
}

// Texel `texel` += flux `units` per channel, hit distance `hit` and one photon, in fixed
// point, uncounted. Every low word's add goes out before any carry is looked at, so that
// their round trips overlap (planes.cl's deposit_photon_texel says what it bought); adding
// zero changes nothing, a zero hit distance (a splat's) is left out.
fn add_photon_texel(texel: u32, units: vec3<u32>, hit: u32) {
    let r = deposit_word(texel, DEPOSIT_FLUX);
    let g = deposit_word(texel, DEPOSIT_FLUX + 2u);
    let b = deposit_word(texel, DEPOSIT_FLUX + 4u);
    let h = deposit_word(texel, DEPOSIT_HIT_DISTANCE);
    let n = deposit_word(texel, DEPOSIT_PHOTONS);
    let old_r = atomic_add_photon_map(r, units.x);
    let old_g = atomic_add_photon_map(g, units.y);
    let old_b = atomic_add_photon_map(b, units.z);
    var old_h = 0u;
    if (hit != 0u) {
        old_h = atomic_add_photon_map(h, hit);
    }
    let old_n = atomic_add_photon_map(n, 1u);
    add_carry_photon_map(r, u64_carry(old_r, units.x));
    add_carry_photon_map(g, u64_carry(old_g, units.y));
    add_carry_photon_map(b, u64_carry(old_b, units.z));
    add_carry_photon_map(h, u64_carry(old_h, hit));
    add_carry_photon_map(n, u64_carry(old_n, 1u));
}

// The high word after low word `at` += `carry` (0 or 1).
fn add_carry_photon_map(at: vec2<u32>, carry: u32) {
    if (carry != 0u) {
        atomic_add_photon_map(vec2<u32>(at.x, at.y + 1u), 1u);
    }
}

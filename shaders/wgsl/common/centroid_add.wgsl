// backend-cpu atlas_deposit.rs::add_centroid: a photon at `offsets` (centroid_offset)
// inside atlas texel `texel` added to the texel's centroid sums (sum of x offsets, of y
// offsets, photons); the add that takes the texel to CENTROID_MAX_PHOTONS photons is
// counted saturated. The kernel declares `centroids: array<atomic<u32>>` and the
// work-group counters `lc`.
fn add_centroid(texel: u32, offsets: vec2<u32>) {
    let i = texel * CENTROID_WORDS;
    atomicAdd(&centroids[i], offsets.x);
    atomicAdd(&centroids[i + 1u], offsets.y);
    if (atomicAdd(&centroids[i + 2u], 1u) == CENTROID_MAX_PHOTONS - 1u) {
        atomicAdd(&lc[COUNTER_SATURATED], 1u);
    }
}

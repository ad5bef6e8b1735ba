// One texture-space photon into the caustic atlas, for the FUSED_DEPOSIT variant of
// trace_photons: the kernel declares
// `triangle_tiles: array<u32>`, `tiles: array<vec4<u32>>`,
// `triangle_reach: array<atomic<u32>>`, the photon map's planes (photon_map_add.wgsl), the
// centroid sums (centroid_add.wgsl) and the work-group counters `lc`. Mirror of backend-opencl map_gather.cl's
// deposit_atlas_photon.

// backend-cpu caustic_map.rs deposit_atlas and mark_triangle_reach: the reach bit of the
// photon's triangle, then its flux, hit distance and a count in fixed point on the texel
// under its uv on its triangle's tile and its offset inside the texel on the texel's
// centroid sums, or OFF_SCREEN counted when the triangle has none.
fn deposit_atlas_photon(ph: Photon, width: u32, flux_quantum: f32, hit_distance_quantum: f32) {
    let reach = triangle_reach_bit(ph.direction);
    // most photons land on a few triangles: a load first, so that a bit already set
    // costs no atomic on the hot word
    if (reach.x < arrayLength(&triangle_reach) &&
        (atomicLoad(&triangle_reach[reach.x]) & reach.y) == 0u) {
        atomicOr(&triangle_reach[reach.x], reach.y);
    }
    var tile = NO_TILE;
    if (ph.direction < arrayLength(&triangle_tiles)) {
        tile = triangle_tiles[ph.direction];
    }
    if (tile == NO_TILE || tile >= arrayLength(&tiles)) {
        atomicAdd(&lc[COUNTER_OFF_SCREEN], 1u);
    } else {
        let texel = atlas_texel_index(tiles[tile], ph.position.xy, width);
        deposit_photon_texel(texel, ph, flux_quantum, hit_distance_quantum);
        add_centroid(texel, centroid_offset(tiles[tile], ph.position.xy));
    }
}

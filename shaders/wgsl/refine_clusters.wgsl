// needs: layout prelude vector fixed_point atlas photon_map_add centroid_add photon_clusters scene
// refine_clusters (Wyman 2009, section 3.2, AdaptiveCaustics): one thread per traced
// cluster of the batch. Its four photon slots (trace_photons' ADAPTIVE variant) decide
// its fate (core::math::photon_clusters::cluster_fate): discarded, output (its stored
// photons deposited into the atlas exactly as the fused trace does) or refined (four
// children appended to the next level's list). With the screen target (world-space
// slots) a photon's texel is its pixel and an output cluster's stored photons are
// appended to output_photons for deposit_screen. Mirror of
// backend-opencl/kernels/refine_clusters.cl and backend-cpu/src/kernels/refine_clusters.rs;
// the atlas sums and counts are bitwise the CPU's, the child list's order is not (every
// later result is independent of it).

@group(0) @binding(0) var<uniform> params: RefineParams;
@group(0) @binding(1) var<storage, read> clusters: array<u32>;
@group(0) @binding(2) var<storage, read> list_length: array<u32>;
@group(0) @binding(3) var<storage, read> caster_rects: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> photons: array<Photon>;
@group(0) @binding(5) var<storage, read> triangle_tiles: array<u32>;
@group(0) @binding(6) var<storage, read> tiles: array<vec4<u32>>;
@group(0) @binding(7) var<storage, read_write> children: array<u32>;
@group(0) @binding(8) var<storage, read_write> converged: array<u32>;
@group(0) @binding(9) var<storage, read_write> converged_count: array<atomic<u32>>;
@group(0) @binding(10) var<storage, read_write> cluster_counts: array<atomic<u32>>;
@group(0) @binding(11) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(12) var<storage, read_write> photon_map0: array<atomic<u32>>;
@group(0) @binding(13) var<storage, read_write> photon_map1: array<atomic<u32>>;
@group(0) @binding(14) var<storage, read_write> photon_map2: array<atomic<u32>>;
@group(0) @binding(15) var<storage, read_write> output_photons: array<Photon>;
@group(0) @binding(16) var<storage, read_write> output_count: array<atomic<u32>>;
// the atlas's centroid sums (the atlas target; otherwise an alias that nobody touches)
@group(0) @binding(17) var<storage, read_write> centroids: array<atomic<u32>>;

var<workgroup> lc: array<atomic<u32>, COUNTER_WORDS>;

// The atlas texel under texture-space photon `ph`, NO_TILE when its triangle has no tile
// (backend-cpu caustic_map.rs::atlas_photon_texel).
fn atlas_photon_texel(ph: Photon, atlas_width: u32) -> u32 {
    var tile = NO_TILE;
    if (ph.direction < arrayLength(&triangle_tiles)) {
        tile = triangle_tiles[ph.direction];
    }
    if (tile == NO_TILE || tile >= arrayLength(&tiles)) {
        return NO_TILE;
    }
    return atlas_texel_index(tiles[tile], ph.position.xy, atlas_width);
}

// The texel the error metric compares: the pixel a world-space photon projects to (the
// screen target) or the atlas texel under a texture-space photon's uv; NO_TILE off both.
fn target_texel(ph: Photon, p: RefineParams) -> u32 {
    if (p.deposit_target == CLUSTER_TARGET_SCREEN) {
        var px: u32;
        var py: u32;
        var depth: f32;
        if (!project_to_pixel(p.camera, ph.position, &px, &py, &depth)) {
            return NO_TILE;
        }
        return py * p.camera.width + px;
    }
    return atlas_photon_texel(ph, p.atlas_width);
}

// backend-cpu caustic_map.rs::deposit_atlas_footprint: photon `ph` spread over the window
// `w` = (x0, x1, y0, y1) of a `width`-wide map, its flux units split exactly
// (footprint_share), the hit distance and a count on every texel, and every texel's
// middle to its centroid sums; one deposit counted.
fn deposit_photon_footprint(w: vec4<u32>, width: u32, ph: Photon, flux_quantum: f32,
                            hit_distance_quantum: f32) {
    let n = (w.y - w.x + 1u) * (w.w - w.z + 1u);
    let units = photon_flux_units(ph, flux_quantum);
    for (var ch = 0u; ch < 3u; ch++) {
        if (units[ch] == 0u) {
            continue;
        }
        var k = 0u;
        for (var y = w.z; y <= w.w; y++) {
            for (var x = w.x; x <= w.y; x++) {
                let share = footprint_share(units[ch], n, k);
                if (share != 0u) {
                    atomic_add_u64_photon_map(y * width + x, DEPOSIT_FLUX + 2u * ch, share, 0u);
                }
                k += 1u;
            }
        }
    }
    let hd = quantize(ph.hit_distance, hit_distance_quantum).units;
    for (var y = w.z; y <= w.w; y++) {
        for (var x = w.x; x <= w.y; x++) {
            atomic_add_u64_photon_map(y * width + x, DEPOSIT_HIT_DISTANCE, hd, 0u);
            atomic_add_u64_photon_map(y * width + x, DEPOSIT_PHOTONS, 1u, 0u);
            add_centroid(y * width + x, vec2<u32>(CENTROID_SUBTEXELS / 2u));
        }
    }
    atomicAdd(&lc[COUNTER_DEPOSITED], 1u);
}

// The tile of the receiver under texture-space photon `ph`; false without one
// (backend-cpu caustic_map.rs::atlas_photon_tile).
fn atlas_photon_tile(ph: Photon, tile: ptr<function, vec4<u32>>) -> bool {
    if (ph.direction >= arrayLength(&triangle_tiles)) {
        return false;
    }
    let i = triangle_tiles[ph.direction];
    if (i >= arrayLength(&tiles)) {
        return false;
    }
    *tile = tiles[i];
    return true;
}

fn refine_clusters(t: u32, li: u32) {
    counters_clear_local(li);
    let p = params;
    // the pass's live clusters: list_length[0] is its list's length
    if (t < live_clusters(list_length[0], p.first, p.count)) {
        let entry = clusters[p.first + t];
        let cluster = entry_cluster(entry);
        var slots: array<Photon, 4>;
        var texels: array<u32, 4>;
        var relevant = false;
        var stored = 0u;
        for (var k = 0u; k < 4u; k++) {
            slots[k] = photons[4u * t + k];
            relevant = relevant || slot_met_caster(slots[k].flux, slots[k].position.z);
            texels[k] = NO_TILE;
            if (slot_stored(slots[k].flux)) {
                texels[k] = target_texel(slots[k], p);
                stored += 1u;
            }
        }
        if (p.relevance == CLUSTER_RELEVANCE_BOUNDS) {
            for (var r = 0u; r < p.rect_count; r++) {
                relevant = relevant || cluster_overlaps_rect(cluster, p.grid_w, caster_rects[r]);
            }
        }
        // converged: all four in one square of at most error_texels a side, on one
        // receiver's tile (atlas) or on screen (backend-cpu refine_clusters.rs)
        let screen = p.deposit_target == CLUSTER_TARGET_SCREEN;
        let width = select(p.atlas_width, p.camera.width, screen);
        var tile: vec4<u32>;
        var all_in = stored == 4u && (screen || atlas_photon_tile(slots[0], &tile));
        var xs: array<u32, 4>;
        var ys: array<u32, 4>;
        for (var k = 0u; k < 4u; k++) {
            xs[k] = texels[k] % width;
            ys[k] = texels[k] / width;
            all_in = all_in && texels[k] != NO_TILE
                && (screen || (xs[k] >= tile.x && xs[k] < tile.x + tile.z
                               && ys[k] >= tile.y && ys[k] < tile.y + tile.z));
        }
        var spread = 0xffffffffu;
        if (all_in) {
            spread = cluster_spread(xs, ys);
        }
        // with error_texels 1 on the atlas, the four also in one convergence cell of their
        // texel
        var one_cell = true;
        if (!screen && p.error_texels <= 1u && all_in) {
            let c0 = convergence_cell(centroid_offset(tile, slots[0].position.xy));
            for (var k = 1u; k < 4u; k++) {
                let ck = convergence_cell(centroid_offset(tile, slots[k].position.xy));
                one_cell = one_cell && all(ck == c0);
            }
        }
        let converged_here = spread <= max(p.error_texels, 1u) && one_cell;
        let fate = cluster_fate(relevant, converged_here, p.level, p.finest, p.metric,
                                p.error_from_level);
        if (fate == CLUSTER_OUTPUT && p.level < p.finest) {
            // converged early: output later from fresh photons
            atomicAdd(&cluster_counts[CLUSTER_COUNT_CONVERGED], 1u);
            let slot = atomicAdd(&converged_count[0], 1u);
            if (slot < arrayLength(&converged)) {
                converged[slot] = cluster_entry(cluster, spread);
            }
        } else if (fate == CLUSTER_OUTPUT) {
            for (var k = 0u; k < 4u; k++) {
                if (!slot_stored(slots[k].flux)) {
                    continue;
                }
                count_stored(slots[k], p.flux_quantum);
                if (p.deposit_target == CLUSTER_TARGET_SCREEN) {
                    // deposit_screen deposits (and accounts for) the listed photons
                    let at = atomicAdd(&output_count[0], 1u);
                    // the host sizes the list to four photons per cluster of a batch
                    if (at < arrayLength(&output_photons)) {
                        output_photons[at] = slots[k];
                    }
                } else if (texels[k] == NO_TILE) {
                    atomicAdd(&lc[COUNTER_OFF_SCREEN], 1u);
                } else if (entry_spread(entry) > 1u && atlas_photon_tile(slots[k], &tile)) {
                    // a converged cluster's photon covers the cluster's footprint
                    deposit_photon_footprint(footprint_window(texels[k] % p.atlas_width,
                                                              texels[k] / p.atlas_width,
                                                              entry_spread(entry), tile),
                                             p.atlas_width, slots[k], p.flux_quantum,
                                             p.hit_distance_quantum);
                } else {
                    deposit_photon_texel(texels[k], slots[k], p.flux_quantum, p.hit_distance_quantum);
                    if (atlas_photon_tile(slots[k], &tile)) {
                        add_centroid(texels[k], centroid_offset(tile, slots[k].position.xy));
                    }
                }
            }
            atomicAdd(&cluster_counts[CLUSTER_COUNT_OUTPUT], 1u);
            atomicAdd(&cluster_counts[CLUSTER_COUNT_OUTPUT_PHOTONS], stored);
        } else if (fate == CLUSTER_DISCARDED) {
            atomicAdd(&cluster_counts[CLUSTER_COUNT_DISCARDED], 1u);
        } else {
            let base = atomicAdd(&cluster_counts[CLUSTER_COUNT_CHILDREN], 4u);
            if (base + 4u <= min(p.children_capacity, arrayLength(&children))) {
                for (var k = 0u; k < 4u; k++) {
                    children[base + k] = cluster_photon_index(cluster, k, p.grid_w);
                }
            } else {
                // the next level's list is full: output at this level from fresh photons
                atomicAdd(&cluster_counts[CLUSTER_COUNT_OVERFLOW], 1u);
                let slot = atomicAdd(&converged_count[0], 1u);
                if (slot < arrayLength(&converged)) {
                    converged[slot] = cluster_entry(cluster, 1u);
                }
            }
        }
    }
    counters_flush_local(li);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let t = (wg.y * nwg.x + wg.x) * 64u + li;
    // No early return: every invocation reaches the barriers in refine_clusters.
    refine_clusters(t, li);
}

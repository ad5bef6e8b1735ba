// refine_clusters (Wyman 2009, section 3.2, AdaptiveCaustics): one work-item per traced
// cluster of the batch decides its fate from its four photon slots (discarded, output
// into the atlas as the fused trace deposits, or refined into four children appended to
// the next level's list). With the screen target (world-space slots) a photon's texel is
// its pixel and an output cluster's stored photons are appended to output_photons for
// deposit_screen. Mirror of backend-cpu/src/kernels/refine_clusters.rs; the atlas
// sums and counts are bitwise the CPU's, the child list's order is not.

// The atlas texel under texture-space photon `ph`, NO_TILE when its triangle has no tile
// (backend-cpu caustic_map.rs::atlas_photon_texel).
inline uint atlas_photon_texel(__global const uint* triangle_tiles, __global const uint4* tiles,
                               const Photon* ph, uint atlas_width) {
    uint tile = triangle_tiles[ph->direction];
    if (tile == NO_TILE) return NO_TILE;
    return atlas_texel_index(tiles[tile], (float2)(ph->position[0], ph->position[1]),
                             atlas_width);
}

// backend-cpu caustic_map.rs::deposit_atlas_footprint: photon `ph` spread over the window
// `w` = (x0, x1, y0, y1) of a `width`-wide map, its flux units split exactly
// (footprint_share), the hit distance and a count on every texel, and every texel's
// middle to its centroid sums; one deposit counted.
inline void deposit_photon_footprint(PHOTON_MAP_PARAMS(volatile __global),
                                     volatile __global uint* centroids, __local uint* lc,
                                     uint4 w, uint width, const Photon* ph, float flux_quantum,
                                     float hit_distance_quantum) {
    uint n = (w.y - w.x + 1u) * (w.w - w.z + 1u);
    uint units[3];
    photon_flux_units(ph, flux_quantum, lc, units);
    for (uint ch = 0u; ch < 3u; ch++) {
        if (units[ch] == 0u) continue;
        uint k = 0u;
        for (uint y = w.z; y <= w.w; y++)
            for (uint x = w.x; x <= w.y; x++) {
                uint share = footprint_share(units[ch], n, k++);
                if (share != 0u)
                    atomic_add_u64_photon_map(PHOTON_MAP_ARGS, y * width + x, 2u * ch, share, 0u);
            }
    }
    uint hd = quantize(ph->hit_distance, hit_distance_quantum).units;
    for (uint y = w.z; y <= w.w; y++)
        for (uint x = w.x; x <= w.y; x++) {
            atomic_add_u64_photon_map(PHOTON_MAP_ARGS, y * width + x, 6u, hd, 0u);
            atomic_add_u64_photon_map(PHOTON_MAP_ARGS, y * width + x, 8u, 1u, 0u);
            add_centroid(centroids, lc, y * width + x, (uint2)(CENTROID_SUBTEXELS / 2u));
        }
    atomic_inc(&lc[COUNTER_DEPOSITED]);
}

// The tile of the receiver under texture-space photon `ph`; false without one
// (backend-cpu caustic_map.rs::atlas_photon_tile).
inline bool atlas_photon_tile(__global const uint* triangle_tiles, __global const uint4* tiles,
                              const Photon* ph, uint4* tile) {
    uint i = triangle_tiles[ph->direction];
    if (i == NO_TILE) return false;
    *tile = tiles[i];
    return true;
}

// The texel the error metric compares: the pixel a world-space photon projects to (the
// screen target) or the atlas texel under a texture-space photon's uv; NO_TILE off both.
inline uint target_texel(__global const RefineParams* p, __global const uint* triangle_tiles,
                         __global const uint4* tiles, const Photon* ph) {
    if (p->deposit_target == CLUSTER_TARGET_SCREEN) {
        uint px, py;
        float depth;
        if (!project_to_pixel(&p->camera, load3(ph->position), &px, &py, &depth)) return NO_TILE;
        return py * p->camera.width + px;
    }
    return atlas_photon_texel(triangle_tiles, tiles, ph, p->atlas_width);
}

__kernel void refine_clusters(__global const RefineParams* p, __global const uint* clusters,
                              __global const uint* list_length,
                              __global const float4* caster_rects,
                              __global const Photon* photons,
                              __global const uint* triangle_tiles, __global const uint4* tiles,
                              __global uint* children, __global uint* converged,
                              uint converged_capacity, volatile __global uint* converged_count,
                              volatile __global uint* cluster_counts,
                              volatile __global uint* counters,
                              PHOTON_MAP_PARAMS(volatile __global),
                              __global Photon* output_photons, uint output_capacity,
                              volatile __global uint* output_count,
                              volatile __global uint* centroids) {
    __local uint lc[COUNTER_WORDS];
    counters_clear_local(lc);
    uint t = get_global_id(0);
    // the pass's live clusters: list_length[0] is its list's length
    if (t < live_clusters(list_length[0], p->first, p->count)) {
        uint entry = clusters[p->first + t];
        uint cluster = entry_cluster(entry);
        Photon slots[4];
        uint texels[4];
        bool relevant = false;
        uint stored = 0u;
        for (uint k = 0u; k < 4u; k++) {
            slots[k] = photons[4u * t + k];
            relevant = relevant || slot_met_caster(slots[k].flux, slots[k].position[2]);
            texels[k] = NO_TILE;
            if (slot_stored(slots[k].flux)) {
                texels[k] = target_texel(p, triangle_tiles, tiles, &slots[k]);
                stored++;
            }
        }
        if (p->relevance == CLUSTER_RELEVANCE_BOUNDS)
            for (uint r = 0u; r < p->rect_count; r++)
                relevant = relevant || cluster_overlaps_rect(cluster, p->grid_w, caster_rects[r]);
        // converged: all four in one square of at most error_texels a side, on one
        // receiver's tile (atlas) or on screen (backend-cpu refine_clusters.rs)
        bool screen = p->deposit_target == CLUSTER_TARGET_SCREEN;
        uint width = screen ? p->camera.width : p->atlas_width;
        uint4 tile = (uint4)(0u);
        bool all_in = stored == 4u && (screen || atlas_photon_tile(triangle_tiles, tiles,
                                                                   &slots[0], &tile));
        uint xs[4], ys[4];
        for (uint k = 0u; k < 4u; k++) {
            xs[k] = texels[k] % width;
            ys[k] = texels[k] / width;
            all_in = all_in && texels[k] != NO_TILE &&
                     (screen || (xs[k] >= tile.x && xs[k] < tile.x + tile.z && ys[k] >= tile.y &&
                                 ys[k] < tile.y + tile.z));
        }
        uint spread = all_in ? cluster_spread(xs, ys) : 0xffffffffu;
        // with error_texels 1 on the atlas, the four also in one convergence cell of their
        // texel
        bool one_cell = true;
        if (!screen && p->error_texels <= 1u && all_in) {
            uint2 c0 = convergence_cell(
                centroid_offset(tile, (float2)(slots[0].position[0], slots[0].position[1])));
            for (uint k = 1u; k < 4u; k++) {
                uint2 ck = convergence_cell(
                    centroid_offset(tile, (float2)(slots[k].position[0], slots[k].position[1])));
                one_cell = one_cell && ck.x == c0.x && ck.y == c0.y;
            }
        }
        uint fate = cluster_fate(relevant, spread <= max(p->error_texels, 1u) && one_cell,
                                 p->level, p->finest, p->metric, p->error_from_level);
        if (fate == CLUSTER_OUTPUT && p->level < p->finest) {
            // converged early: output later from fresh photons
            atomic_inc(&cluster_counts[CLUSTER_COUNT_CONVERGED]);
            uint slot = atomic_inc(converged_count);
            if (slot < converged_capacity) converged[slot] = cluster_entry(cluster, spread);
        } else if (fate == CLUSTER_OUTPUT) {
            for (uint k = 0u; k < 4u; k++) {
                if (!slot_stored(slots[k].flux)) continue;
                count_stored(&slots[k], p->flux_quantum, lc);
                if (p->deposit_target == CLUSTER_TARGET_SCREEN) {
                    // deposit_screen deposits (and accounts for) the listed photons
                    uint at = atomic_inc(output_count);
                    if (at < output_capacity) output_photons[at] = slots[k];
                } else if (texels[k] == NO_TILE) {
                    atomic_inc(&lc[COUNTER_OFF_SCREEN]);
                } else if (entry_spread(entry) > 1u &&
                           atlas_photon_tile(triangle_tiles, tiles, &slots[k], &tile)) {
                    // a converged cluster's photon covers the cluster's footprint
                    uint4 w = footprint_window(texels[k] % p->atlas_width,
                                               texels[k] / p->atlas_width, entry_spread(entry),
                                               tile);
                    deposit_photon_footprint(PHOTON_MAP_ARGS, centroids, lc, w, p->atlas_width,
                                             &slots[k], p->flux_quantum, p->hit_distance_quantum);
                } else {
                    deposit_photon_texel(PHOTON_MAP_ARGS, lc, texels[k], &slots[k],
                                         p->flux_quantum, p->hit_distance_quantum);
                    if (atlas_photon_tile(triangle_tiles, tiles, &slots[k], &tile))
                        add_centroid(centroids, lc, texels[k],
                                     centroid_offset(tile, (float2)(slots[k].position[0],
                                                                    slots[k].position[1])));
                }
            }
            atomic_inc(&cluster_counts[CLUSTER_COUNT_OUTPUT]);
            atomic_add(&cluster_counts[CLUSTER_COUNT_OUTPUT_PHOTONS], stored);
        } else if (fate == CLUSTER_DISCARDED) {
            atomic_inc(&cluster_counts[CLUSTER_COUNT_DISCARDED]);
        } else {
            uint base = atomic_add(&cluster_counts[CLUSTER_COUNT_CHILDREN], 4u);
            if (base + 4u <= p->children_capacity) {
                for (uint k = 0u; k < 4u; k++)
                    children[base + k] = cluster_photon_index(cluster, k, p->grid_w);
            } else {
                // the next level's list is full: output at this level from fresh photons
                atomic_inc(&cluster_counts[CLUSTER_COUNT_OVERFLOW]);
                uint slot = atomic_inc(converged_count);
                if (slot < converged_capacity) converged[slot] = cluster_entry(cluster, 1u);
            }
        }
    }
    counters_flush_local(lc, counters);
}

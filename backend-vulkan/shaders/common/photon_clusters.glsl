// Mirror of core::math::photon_clusters (Wyman 2009's photon clusters, AdaptiveCaustics):
// what trace_photons' ADAPTIVE variant needs (refine_clusters runs from WGSL).

uint entry_cluster(uint entry) { return entry & CLUSTER_ID_MASK; }

// core::math::photon_clusters::live_clusters: entries `first ..` of a list of
// `list_length`, at most `bound`.
uint live_clusters(uint list_length, uint first, uint bound) {
    return list_length <= first ? 0u : min(list_length - first, bound);
}

uint cluster_photon_index(uint cluster, uint sub, uint grid_w) {
    uint clusters_w = grid_w / 2u;
    uint cx = cluster % clusters_w;
    uint cy = cluster / clusters_w;
    return (2u * cy + (sub >> 1u)) * grid_w + 2u * cx + (sub & 1u);
}

bool photon_met_caster(uint end, uint rays) {
    return !(end == 1u || (end == 2u && rays <= 1u) || (end == 3u && rays == 0u));
}

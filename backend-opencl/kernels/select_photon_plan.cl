// select_photon_plan (Smal 2019, section 24.2.1: photons allocated to the lights by
// power, among those whose RSM sees something): one thread notes whether the light whose
// RSM the pyramid holds sees a texel that leaves flux (photon_plan::rsm_sees,
// note_light) and copies the plan table's row of the mask into the plan
// (photon_plan::plan_row). Mirror of backend-cpu/src/kernels/select_photon_plan.rs and
// shaders/wgsl/select_photon_plan.wgsl. The plan holds at least PLAN_ROW + row_words
// words (core checks it).

// photon_plan::note_light.
inline uint note_light(uint mask, uint bit, bool sees) {
    return (sees && bit < 32u) ? (mask | (1u << bit)) : mask;
}

// photon_plan::rsm_sees over the tops of faces 0 .. faces of the pyramid.
inline bool rsm_sees(__global const float* pyramid, uint side, uint faces) {
    uint len = pyramid_len(side);
    uint top = level_offset(side, level_count(side) - 1u);
    bool sees = false;
    for (uint f = 0u; f < min(faces, 6u); f++) {
        if (pyramid[f * len + top] >= RSM_SEEN_MIN_TOP) sees = true;
    }
    return sees;
}

__kernel void select_photon_plan(__global const PlanParams* p, __global const float* pyramid,
                                 __global const uint* table, __global uint* plan) {
    if (get_global_id(0) != 0) return;
    uint mask = plan[PLAN_MASK];
    if (p->bit != NO_PLAN_BIT) mask = note_light(mask, p->bit, rsm_sees(pyramid, p->side, p->faces));
    plan[PLAN_MASK] = mask;
    // photon_plan::plan_row: row `mask` exists where mask < table_words / row_words; a
    // row past the table leaves the plan's row as it was
    if (p->row_words > 0u && mask < p->table_words / p->row_words) {
        uint start = mask * p->row_words;
        for (uint w = 0u; w < p->row_words; w++) plan[PLAN_ROW + w] = table[start + w];
    }
}

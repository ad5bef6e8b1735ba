// needs: layout prelude vector sampling footprint scene packing photon_gi
// select_photon_plan (Smal 2019, section 24.2.1: photons allocated to the lights by
// power, among those whose RSM sees something): one thread notes whether the light whose
// RSM the pyramid holds sees a texel that leaves flux (photon_plan::rsm_sees,
// note_light) and copies the plan table's row of the mask into the plan
// (photon_plan::plan_row). Mirror of backend-cpu/src/kernels/select_photon_plan.rs and
// backend-opencl/kernels/select_photon_plan.cl. The table's length is
// `params.table_words`, never its binding's (wgpu binds at least 64 bytes).

@group(0) @binding(0) var<uniform> params: PlanParams;
@group(0) @binding(1) var<storage, read> pyramid: array<f32>;
@group(0) @binding(2) var<storage, read> table: array<u32>;
@group(0) @binding(3) var<storage, read_write> plan: array<u32>;

// photon_plan::note_light.
fn note_light(mask: u32, bit: u32, sees: bool) -> u32 {
    if (sees && bit < 32u) {
        return mask | (1u << bit);
    }
    return mask;
}

// photon_plan::rsm_sees over the tops of faces 0 .. faces of the pyramid.
fn rsm_sees(side: u32, faces: u32) -> bool {
    let len = pyramid_len(side);
    let top = level_offset(side, level_count(side) - 1u);
    var sees = false;
    for (var f = 0u; f < min(faces, 6u); f++) {
        let at = f * len + top;
        if (at < arrayLength(&pyramid) && pyramid[at] >= RSM_SEEN_MIN_TOP) {
            sees = true;
        }
    }
    return sees;
}

fn select_photon_plan() {
    let p = params;
    if (PLAN_MASK >= arrayLength(&plan)) {
        return;
    }
    var mask = plan[PLAN_MASK];
    if (p.bit != NO_PLAN_BIT) {
        mask = note_light(mask, p.bit, rsm_sees(p.side, p.faces));
    }
    plan[PLAN_MASK] = mask;
    // photon_plan::plan_row: row `mask` exists where (mask + 1) row_words <= the
    // table's length, i.e. mask < length / row_words; a row past the table leaves the
    // plan's row as it was
    let table_words = min(p.table_words, arrayLength(&table));
    if (p.row_words > 0u && mask < table_words / p.row_words) {
        let start = mask * p.row_words;
        for (var w = 0u; w < p.row_words; w++) {
            if (PLAN_ROW + w < arrayLength(&plan)) {
                plan[PLAN_ROW + w] = table[start + w];
            }
        }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    if ((wg.y * nwg.x + wg.x) * 64u + li == 0u) {
        select_photon_plan();
    }
}

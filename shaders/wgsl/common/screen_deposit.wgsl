// One world-space photon into the screen photon map, for deposit_screen and the
// FUSED_DEPOSIT variant of trace_photons in world space: the kernel declares the G-buffer
// planes (gbuffer.wgsl), the photon map's planes (photon_map_add.wgsl) and the work-group
// counters `lc`. Mirror of backend-opencl planes.cl's deposit_screen_photon.

// backend-cpu deposit_screen.rs: the photon projected to its pixel and added in fixed
// point if the pixel sees a diffuse surface at a consistent depth and the photon arrives
// on the side the camera sees; OFF_SCREEN or DEPTH_MISMATCH counted otherwise.
fn deposit_screen_photon(ph: Photon, p: DepositParams) {
    var px: u32;
    var py: u32;
    var z: f32;
    if (!project_to_pixel(p.camera, ph.position, &px, &py, &z)) {
        atomicAdd(&lc[COUNTER_OFF_SCREEN], 1u);
        return;
    }
    let pix = py * p.camera.width + px;
    let g = load_gbuffer(pix);
    let arrives_in_front = dot3(unpack_unit_vector(ph.direction), g.normal) < 0.0;
    if ((g.flags & GBUFFER_RECEIVER) == 0u ||
        off_surface(z, ph.position, g.position, g.normal, g.depth, p.depth_tolerance) ||
        !arrives_in_front) {
        atomicAdd(&lc[COUNTER_DEPTH_MISMATCH], 1u);
    } else {
        deposit_photon_texel(pix, ph, p.flux_quantum, p.hit_distance_quantum);
    }
}

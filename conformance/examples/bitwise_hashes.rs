//! Prints a 64-bit FNV-1a hash of every output image, the G-buffer, the last photon batch
//! (as a sorted multiset) and the photon counters of every built-in scene on every backend
//! found, one line each: `backend<TAB>device<TAB>scene<TAB>item<TAB>hash`; then the same
//! for every other technique created by name (CausticMap, AdaptiveCaustics with either
//! target, PhotonGi with its temporal blend), over two frames with the camera moved
//! between them (`<technique>/<frame>/<output>` items). Refactors that must not change a
//! bit compare this output before and after (`conformance/baselines/`).
//!
//! `cargo run --release -p caustica-conformance --example bitwise_hashes > hashes.tsv`

use caustica_conformance::{backends, small_settings};
use caustica_core::backend::{read_buf, read_gbuffer};
use caustica_core::scene::builtin::{builtin, BUILTIN_SCENES};
use caustica_core::Sspm;
use caustica_core::TraceSettings;

/// FNV-1a, 64-bit: stable across Rust versions (std's hasher is not promised to be).
fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= *b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

fn main() {
    let mut all = backends();
    for name in BUILTIN_SCENES {
        let mut scene = builtin(name).expect("built-in scene");
        scene.camera.width = 320;
        scene.camera.height = 180;
        for (bname, backend) in all.iter_mut() {
            let device = backend.capabilities().device;
            let settings = caustica_core::SspmSettings {
                trace: TraceSettings {
                    // several batches per light: batching must not change a bit either
                    max_photons_per_batch: 20_000,
                    ..small_settings(256).trace
                },
                // the photons stored, so that their multiset is hashed too (the fused
                // deposit, the default, stores none and gives the same images)
                fused_deposit: false,
                ..small_settings(256)
            };
            let mut s = Sspm::new(backend.as_mut(), &scene, settings).expect("valid scene");
            let stats = s.frame(backend.as_mut(), &mut |_| {}).expect("frame");
            let line = |item: &str, bytes: &[u8]| {
                println!("{bname}\t{device}\t{name}\t{item}\t{:016x}", fnv1a(bytes));
            };
            for o in s.outputs().into_iter().map(|o| o.output) {
                let img = s.read_output(backend.as_mut(), o).expect("read");
                line(o.stem(), bytemuck::cast_slice(&img.pixels));
            }
            // the texels assembled from the planes: the same bytes as before the split
            let g = read_gbuffer(backend.as_mut(), &s.gbuffer()).expect("gbuffer");
            line("gbuffer", bytemuck::cast_slice(&g));
            if let Some((p, n)) = s.photon_buffers() {
                let n = read_buf(backend.as_mut(), n).expect("count")[0] as usize;
                let p = read_buf(backend.as_mut(), p).expect("photons");
                // GPU backends append photons in atomic order, which varies run to run:
                // hash the (deterministic) multiset, sorted by bytes.
                let mut rows: Vec<&[u8]> =
                    p[..n.min(p.len())].iter().map(bytemuck::bytes_of).collect();
                rows.sort_unstable();
                line("last_batch_photons", &rows.concat());
            }
            let counters = format!(
                "{} {} {} {:?} {:?} {:?} {} {} {}",
                stats.photons_emitted,
                stats.photons_stored,
                stats.photons_deposited,
                stats.discarded,
                stats.stored_flux,
                stats.emitted_flux,
                stats.fixed_point_saturated,
                stats.fixed_point_underflow,
                stats.photon_rays_traced,
            );
            line("counters", counters.as_bytes());
            println!("{bname}\t{device}\t{name}\tcounters_text\t{counters}");
            s.free(backend.as_mut()).expect("free");
        }
    }
    others(&mut all);
}

/// The other techniques by name, their settings small enough for lavapipe and PoCL.
fn technique_settings() -> Vec<(&'static str, &'static str, serde_json::Value)> {
    vec![
        (
            "caustic-map",
            "caustic-map",
            serde_json::json!({ "photons_w": 128, "photons_h": 128, "atlas_size": 256 }),
        ),
        (
            "caustic-map:box",
            "caustic-map",
            serde_json::json!({
                "photons_w": 128, "photons_h": 128, "atlas_size": 256, "gather": "box"
            }),
        ),
        (
            "adaptive-caustics",
            "adaptive-caustics",
            serde_json::json!({
                "photons_w": 256, "photons_h": 256, "atlas_size": 256, "error_from_grid": 128
            }),
        ),
        (
            "adaptive-caustics:screen",
            "adaptive-caustics",
            serde_json::json!({
                "photons_w": 256, "photons_h": 256, "error_from_grid": 128, "deposit": "screen"
            }),
        ),
        (
            "photon-gi",
            "photon-gi",
            serde_json::json!({
                "photons_w": 96, "photons_h": 96, "rsm_size": 32, "temporal": true,
                "atrous_iterations": 2
            }),
        ),
    ]
}

/// Every technique but Sspm on every built-in scene: two frames, the camera moved between
/// them (the second frame reuses CausticMap's atlas and blends PhotonGi's history).
fn others(all: &mut [(&'static str, Box<dyn caustica_core::backend::Backend>)]) {
    for name in BUILTIN_SCENES {
        let mut scene = builtin(name).expect("built-in scene");
        scene.camera.width = 160;
        scene.camera.height = 90;
        for (bname, backend) in all.iter_mut() {
            let device = backend.capabilities().device;
            for (label, technique, settings) in technique_settings() {
                let mut t = caustica_core::techniques::create(
                    technique,
                    backend.as_mut(),
                    &scene,
                    &settings,
                )
                .expect("valid scene and settings");
                for frame in 0..2 {
                    if frame == 1 {
                        let mut camera = scene.camera.clone();
                        camera.position += glam::Vec3::new(0.05, 0.02, -0.03);
                        t.set_camera(backend.as_mut(), &camera).expect("camera");
                    }
                    let stats = t.frame(backend.as_mut(), &mut |_| {}).expect("frame");
                    let line = |item: &str, bytes: &[u8]| {
                        println!(
                            "{bname}\t{device}\t{name}\t{label}/{frame}/{item}\t{:016x}",
                            fnv1a(bytes)
                        );
                    };
                    for o in t.outputs().into_iter().filter(|o| o.requested) {
                        let img = t.read_output(backend.as_mut(), o.output).expect("read");
                        line(o.name, bytemuck::cast_slice(&img.pixels));
                    }
                    let counters = format!(
                        "{} {} {} {:?} {:?} {:?} {} {} {}",
                        stats.photons_emitted,
                        stats.photons_stored,
                        stats.photons_deposited,
                        stats.discarded,
                        stats.stored_flux,
                        stats.emitted_flux,
                        stats.fixed_point_saturated,
                        stats.fixed_point_underflow,
                        stats.photon_rays_traced,
                    );
                    line("counters", counters.as_bytes());
                }
                t.free(backend.as_mut()).expect("free");
            }
        }
    }
}

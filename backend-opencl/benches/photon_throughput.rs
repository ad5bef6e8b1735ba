//! OpenCL photon paths per second on `sphere` and `cornell`: one `trace_photons` dispatch
//! of `n x n` photon paths through the `Backend` API (upload once, trace many times),
//! wall clock including the wait for the device, next to the device's own kernel
//! timestamp. Run: `cargo bench -p caustica-opencl --bench photon_throughput`
//! (`CAUSTICA_BENCH_GRID=1024` for a bigger grid on a GPU; default 256).
//! Criterion's "elements" are photon paths.

use caustica_core::backend::Backend;
use caustica_core::device::device_scene::DeviceScene;
use caustica_core::device::layout::{counter, Photon};
use caustica_core::frame::emission::{emission_domain, PointEmission};
use caustica_core::kernels::Kernel;
use caustica_core::kernels::TracePhotons;
use caustica_core::recording::Recording;
use caustica_core::scene::builtin::builtin;
use caustica_opencl::OpenClBackend;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};

fn bench(c: &mut Criterion) {
    let n: u32 = std::env::var("CAUSTICA_BENCH_GRID")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(256);
    let mut backend = match OpenClBackend::new() {
        Ok(b) => b,
        Err(e) => {
            eprintln!("OpenCL unavailable, benchmark skipped: {e}");
            return;
        }
    };
    eprintln!("device: {}", backend.capabilities().device);
    for name in ["sphere", "cornell"] {
        let scene = builtin(name).unwrap();
        let ds = DeviceScene::build(&scene, Default::default()).expect("built-in scene builds");
        let d = emission_domain(
            &scene.lights[0],
            ds.caster_bounds,
            ds.bounds,
            PointEmission::CasterCone,
        )
        .unwrap();
        let mut setup = Recording::new();
        let scene_args = setup.upload_scene(&ds);
        let photons = setup.create::<Photon>(n * n, "photons");
        let photon_count = setup.create::<u32>(1, "photon count");
        let counters = setup.create::<u32>(counter::WORDS as u32, "counters");
        backend.execute(&setup).unwrap();
        let mut trace = Recording::new();
        trace.clear(photon_count);
        trace.kernel(Kernel::TracePhotons(TracePhotons {
            scene: scene_args,
            variant: caustica_core::frame::plan::SceneFeatures::of(&scene).trace_variant(),
            params: d.trace_params(0, (n, n), (0, n * n), 1, 12, 1e-4, 1e-9),
            photons,
            photon_count,
            counters,
            clusters: None,
            deposit: None,
        }));
        // warm-up (first launch compiles on some drivers), then the device timestamp
        backend.execute(&trace).unwrap();
        let device_s: f64 = (0..5)
            .map(|_| backend.execute(&trace).unwrap()[0].seconds)
            .fold(f64::INFINITY, f64::min);
        eprintln!(
            "{name}: {n}x{n} paths, best device time {:.3} ms = {:.2} M paths/s",
            device_s * 1e3,
            (n * n) as f64 / device_s * 1e-6
        );
        let mut g = c.benchmark_group(format!("opencl/{name}"));
        g.throughput(Throughput::Elements((n * n) as u64));
        g.sample_size(10);
        g.bench_function("trace_photons (paths)", |b| {
            b.iter(|| backend.execute(&trace).unwrap())
        });
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);

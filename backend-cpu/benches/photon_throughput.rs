//! CPU photon paths per second on `sphere` and `cornell`, next to raw obvhs traversal of
//! the same rays in the same run. Run: `cargo bench -p caustica-cpu --bench photon_throughput`.
//!
//! Three measurements per scene, each over the same `n x n` photon paths, so criterion's
//! "elements" are photon paths in all three:
//! - `trace_photons`: the kernel (emission, traversal, Fresnel, Beer, storing, counters);
//! - `raw obvhs, every segment`: obvhs closest-hit traversal (obvhs's own triangle test)
//!   of exactly the ray segments those paths trace, recorded once beforehand. This is the
//!   comparison the CPU backend's target is set in (photon paths per second within 2x of
//!   raw obvhs traversal): the kernel's time over the raw traversal time of its own rays;
//! - `raw obvhs, first segments`: only each path's emitted ray (coherent, cheaper), for
//!   reference.

use caustica_core::device::device_scene::DeviceScene;
use caustica_core::frame::emission::{emission_domain, PointEmission};
use caustica_core::scene::builtin::builtin;
use caustica_cpu::kernels::trace_photons::{emit_photon, trace_photon_observed, trace_photons};
use caustica_cpu::traversal::SceneView;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3A;
use obvhs::ray::{Ray, RayHit};
use obvhs::triangle::Triangle;
use rayon::prelude::*;

fn bench(c: &mut Criterion) {
    let n = 256u32;
    for name in ["sphere", "cornell"] {
        let scene = builtin(name).unwrap();
        let ds = DeviceScene::build(&scene, Default::default()).expect("built-in scene builds");
        let view = SceneView {
            vertices: &ds.vertices,
            triangles: &ds.triangles,
            materials: &ds.materials,
            lights: &ds.lights,
            nodes: &ds.bvh_nodes,
        };
        let d = emission_domain(
            &scene.lights[0],
            ds.caster_bounds,
            ds.bounds,
            PointEmission::CasterCone,
        )
        .unwrap();
        let params = d.trace_params(0, (n, n), (0, n * n), 1, 12, 1e-4, 1e-9);
        // the variant a frame of this scene runs (the frame plan's)
        let variant = caustica_core::frame::plan::SceneFeatures::of(&scene).trace_variant();
        let tris: Vec<Triangle> = ds
            .triangles
            .iter()
            .map(|t| {
                let p = |k: usize| Vec3A::from(ds.vertices[t.indices[k] as usize].position);
                Triangle {
                    v0: p(0),
                    v1: p(1),
                    v2: p(2),
                }
            })
            .collect();
        // the raw obvhs baseline: its own one-level BVH over the world triangles (built
        // as caustica builds a static level), leaf order (its callback's ids)
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            &tris,
            caustica_core::device::device_scene::STATIC_LEVEL_BUILD,
            &mut std::time::Duration::default(),
        );
        let tris: Vec<Triangle> = bvh
            .primitive_indices
            .iter()
            .map(|&i| tris[i as usize])
            .collect();
        let rays: Vec<Ray> = (0..n * n)
            .map(|i| {
                let (o, dir, _) = emit_photon(&view, &params, i);
                Ray::new_inf(Vec3A::from(o), Vec3A::from(dir))
            })
            .collect();
        let segments: Vec<Ray> = (0..n * n)
            .flat_map(|i| {
                let mut rays = Vec::new();
                trace_photon_observed(&view, &params, i, &mut |o, d| {
                    rays.push(Ray::new_inf(Vec3A::from(o), Vec3A::from(d)))
                });
                rays
            })
            .collect();
        let raw = |rays: &[Ray]| {
            rays.par_iter()
                .map(|r| {
                    let mut hit = RayHit::none();
                    bvh.ray_traverse(*r, &mut hit, |ray, id| tris[id].intersect(ray)) as u32
                })
                .sum::<u32>()
        };
        eprintln!(
            "{name}: {:.2} ray segments per photon path",
            segments.len() as f64 / (n * n) as f64
        );
        let mut g = c.benchmark_group(name);
        g.throughput(Throughput::Elements((n * n) as u64));
        g.sample_size(10);
        g.bench_function("trace_photons (paths)", |b| {
            b.iter(|| trace_photons(&view, &params, variant).photons.len())
        });
        g.bench_function("raw obvhs, every segment (paths)", |b| {
            b.iter(|| raw(&segments))
        });
        g.bench_function("raw obvhs, first segments (paths)", |b| {
            b.iter(|| raw(&rays))
        });
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);

//! Hostile scenes: what a careless or malicious scene file does must end in a
//! clean error naming the field, or in a frame whose every output texel is finite; never
//! a panic, an abort, a hang or Inf/NaN.
//!
//! Two tests:
//! - `hostile_catalogue_on_every_backend`: the inputs that broke caustica before (huge
//!   and tiny geometry, intensities of 3.4e38, a light touching a surface, coincident and
//!   degenerate triangles, triangle and light budgets, ...), each with its expected
//!   outcome, on every backend.
//! - `fuzzed_scene_files_end_cleanly`: proptest mutates the built-in scenes' JSON
//!   (numeric fields set to hostile values, values of the wrong type, fields deleted,
//!   unknown fields added, array elements duplicated) and renders every file that loads
//!   on the CPU backend. A bounded number of cases, each under a stated time bound; the
//!   outcome counts are printed (`--nocapture`).

use caustica_conformance::backends;
use caustica_core::scene::builtin::{builtin, BUILTIN_SCENES};
use caustica_core::scene::format::parse_scene;
use caustica_core::scene::{Light, Material, Object, Scene, Shape};
use caustica_core::techniques::create;
use caustica_core::{Backend, Error};
use glam::{Vec2, Vec3};
use proptest::prelude::*;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Image and photon grid of every render here: small, the point is the path, not the
/// picture.
const SIZE: (u32, u32) = (32, 18);

fn settings(max_triangles: u64) -> serde_json::Value {
    serde_json::json!({ "photons_w": 32, "photons_h": 32, "max_triangles": max_triangles })
}

fn small(name: &str) -> Scene {
    let mut s = builtin(name).expect("built-in scene");
    s.camera.width = SIZE.0;
    s.camera.height = SIZE.1;
    s
}

/// How one scene ended.
#[derive(Debug)]
enum Outcome {
    /// Refused with this message (validation, build or creation).
    Refused(String),
    /// Rendered; every output finite. Carries the frame's dropped degenerate triangles.
    Rendered { degenerate: u64 },
}

/// Validates, creates Sspm, renders one frame and reads every requested output; an
/// output texel that is not finite fails the test (with `what`).
fn render(b: &mut dyn Backend, scene: &Scene, max_triangles: u64, what: &str) -> Outcome {
    if let Err(p) = scene.validate() {
        return Outcome::Refused(format!("{}: {}", p[0].path, p[0].reason));
    }
    let mut t = match create("sspm", b, scene, &settings(max_triangles)) {
        Ok(t) => t,
        Err(e) => return Outcome::Refused(e.to_string()),
    };
    let stats = match t.frame(b, &mut |_| {}) {
        Ok(s) => s,
        Err(e) => {
            let _ = t.free(b);
            return Outcome::Refused(e.to_string());
        }
    };
    for o in t.outputs().into_iter().filter(|o| o.requested) {
        let img = t.read_output(b, o.output).expect("read output");
        if let Some((i, px)) = img
            .pixels
            .iter()
            .enumerate()
            .find(|(_, p)| !p.iter().all(|v| v.is_finite()))
        {
            panic!("{what}: output {} texel {i} is {px:?}", o.name);
        }
    }
    for c in 0..3 {
        assert!(
            stats.emitted_flux[c].is_finite() && stats.stored_flux[c].is_finite(),
            "{what}: flux not finite in the stats"
        );
    }
    t.free(b).expect("free");
    Outcome::Rendered {
        degenerate: stats.degenerate_triangles,
    }
}

/// What a catalogue case must end in.
enum Expect {
    /// Refused, the message containing this text (the field or the bound).
    Refused(&'static str),
    /// Rendered with finite outputs.
    Finite,
    /// Rendered with finite outputs and at least this many degenerate triangles dropped.
    FiniteDropping(u64),
}

fn set_light_intensity(s: &mut Scene, v: f32) {
    match &mut s.lights[0] {
        Light::Point { intensity, .. } | Light::Spot { intensity, .. } => {
            *intensity = Vec3::splat(v)
        }
        Light::Directional { irradiance, .. } => *irradiance = Vec3::splat(v),
    }
}

fn object(s: &mut Scene, shape: Shape) {
    let material = s.materials.keys().next().expect("a material").clone();
    s.objects.push(Object {
        name: "hostile".into(),
        material,
        shape,
        transform: None,
    });
}

fn sphere(center: Vec3, radius: f32, segments: u32) -> Shape {
    Shape::Sphere {
        center,
        radius,
        segments,
    }
}

/// A mesh of `n` copies of one triangle (`tri`), or of one point when `tri` collapses.
fn repeated_triangle(n: u32, tri: [Vec3; 3]) -> Shape {
    Shape::Mesh {
        positions: tri.to_vec().into(),
        normals: vec![].into(),
        uvs: vec![].into(),
        indices: vec![[0, 1, 2]; n as usize].into(),
    }
}

type Case = (&'static str, fn() -> Scene, Expect);

fn catalogue() -> Vec<Case> {
    vec![
        (
            "intensity 3.4e38",
            || {
                let mut s = small("sphere");
                set_light_intensity(&mut s, 3.4e38);
                s
            },
            Expect::Refused("intensity"),
        ),
        (
            "intensity at the 2^60 bound",
            || {
                let mut s = small("sphere");
                set_light_intensity(&mut s, 1.152_921_5e18);
                s
            },
            Expect::Finite,
        ),
        (
            "point light touching the floor at 2^60 W/sr",
            || {
                let mut s = small("cornell");
                s.lights = vec![Light::Point {
                    position: Vec3::new(0.0, 1e-7, 0.0),
                    intensity: Vec3::new(1.152_921_5e18, 0.0, 1.0),
                }];
                s
            },
            Expect::Finite,
        ),
        (
            "sun irradiance 2^60 over a 2^40 projection volume",
            || {
                let mut s = small("sphere-sun");
                if let Light::Directional {
                    irradiance,
                    projection_volume,
                    ..
                } = &mut s.lights[0]
                {
                    *irradiance = Vec3::splat(1.152_921_5e18);
                    *projection_volume = Some(caustica_core::scene::Aabb {
                        min: Vec3::splat(-1.0e12),
                        max: Vec3::splat(1.0e12),
                    });
                }
                s
            },
            Expect::Refused("emits"),
        ),
        (
            "sphere radius 1e30",
            || {
                let mut s = small("sphere");
                object(&mut s, sphere(Vec3::ZERO, 1e30, 32));
                s
            },
            Expect::Refused("radius"),
        ),
        (
            "sphere radius 3.4e38",
            || {
                let mut s = small("sphere");
                object(&mut s, sphere(Vec3::ZERO, 3.4e38, 32));
                s
            },
            Expect::Refused("radius"),
        ),
        (
            "sphere radius 1e-30",
            || {
                let mut s = small("sphere");
                object(&mut s, sphere(Vec3::Y, 1e-30, 32));
                s
            },
            Expect::Refused("radius"),
        ),
        (
            "sphere radius 1e-45",
            || {
                let mut s = small("sphere");
                object(&mut s, sphere(Vec3::Y, 1e-45, 32));
                s
            },
            Expect::Refused("radius"),
        ),
        (
            "sphere below f32 resolution at 1e3",
            || {
                let mut s = small("sphere");
                object(&mut s, sphere(Vec3::splat(1e3), 1e-6, 32));
                s
            },
            Expect::Refused("f32 resolution"),
        ),
        (
            "sphere moved below f32 resolution by its transform",
            || {
                let mut s = small("sphere");
                object(&mut s, sphere(Vec3::Y, 0.5, 32));
                let o = s.objects.last_mut().expect("the sphere");
                o.transform = Some(caustica_core::scene::Transform {
                    translation: Vec3::new(1e12, 0.0, 0.0),
                    ..Default::default()
                });
                s
            },
            Expect::Refused("f32 resolution"),
        ),
        (
            "sphere scaled below f32 resolution by its transform",
            || {
                let mut s = small("sphere");
                object(&mut s, sphere(Vec3::ZERO, 1.0, 32));
                let o = s.objects.last_mut().expect("the sphere");
                o.transform = Some(caustica_core::scene::Transform {
                    translation: Vec3::splat(1e3),
                    scale: Vec3::splat(2f32.powi(-20)),
                    ..Default::default()
                });
                s
            },
            Expect::Refused("f32 resolution"),
        ),
        (
            "a terminal escape in the scene's name",
            || {
                let mut s = small("sphere");
                s.name = "a\nb\u{1b}[31mRED".into();
                s
            },
            Expect::Refused("control character"),
        ),
        (
            "camera at 1e30",
            || {
                let mut s = small("sphere");
                s.camera.position = Vec3::new(0.0, 1e30, 1e30);
                s
            },
            Expect::Refused("camera.position"),
        ),
        (
            "cuboid side 3.4e38",
            || {
                let mut s = small("sphere");
                object(
                    &mut s,
                    Shape::Cuboid {
                        min: Vec3::ZERO,
                        max: Vec3::splat(3.4e38),
                    },
                );
                s
            },
            Expect::Refused("coordinate"),
        ),
        (
            "height field amplitude 1e30",
            || {
                let mut s = small("pool");
                for o in &mut s.objects {
                    if let Shape::HeightField { waves, .. } = &mut o.shape {
                        waves[0].amplitude = 1e30;
                    }
                }
                s
            },
            Expect::Refused("reaches 1e30"),
        ),
        (
            "IOR 1e30",
            || {
                let mut s = small("sphere");
                for m in s.materials.values_mut() {
                    if let Material::Dielectric { ior, .. } = m {
                        *ior = 1e30;
                    }
                }
                s
            },
            Expect::Refused("ior"),
        ),
        (
            "IOR 2^20 and absorption 2^60",
            || {
                let mut s = small("sphere");
                for m in s.materials.values_mut() {
                    if let Material::Dielectric {
                        ior, absorption, ..
                    } = m
                    {
                        *ior = 1_048_576.0;
                        *absorption = Vec3::splat(1.152_921_5e18);
                    }
                }
                s
            },
            Expect::Finite,
        ),
        (
            "10^5 triangles at one point",
            || {
                let mut s = small("sphere");
                object(&mut s, repeated_triangle(100_000, [Vec3::ONE; 3]));
                s
            },
            Expect::Refused("zero area"),
        ),
        (
            "10^4 coincident triangles",
            || {
                let mut s = small("sphere");
                object(
                    &mut s,
                    repeated_triangle(10_000, [Vec3::ZERO, Vec3::X, Vec3::Y]),
                );
                s
            },
            Expect::Refused("bounding box"),
        ),
        (
            "a mesh half degenerate",
            || {
                let mut s = small("sphere");
                object(
                    &mut s,
                    Shape::Mesh {
                        positions: vec![
                            Vec3::new(2.0, 0.0, 0.0),
                            Vec3::new(2.5, 0.0, 0.0),
                            Vec3::new(2.0, 0.5, 0.0),
                            Vec3::new(3.0, 0.0, 0.0),
                        ]
                        .into(),
                        normals: vec![].into(),
                        uvs: vec![].into(),
                        // the second triangle's vertices are collinear
                        indices: vec![[0, 1, 2], [0, 1, 3]].into(),
                    },
                );
                s
            },
            Expect::FiniteDropping(1),
        ),
        (
            "eight spheres of 4096 segments",
            || {
                let mut s = small("sphere");
                for k in 0..8 {
                    object(&mut s, sphere(Vec3::new(k as f32, 0.0, 0.0), 0.4, 4096));
                }
                s
            },
            Expect::Refused("triangles"),
        ),
        (
            "height field of resolution 4096",
            || {
                let mut s = small("pool");
                for o in &mut s.objects {
                    if let Shape::HeightField { resolution, .. } = &mut o.shape {
                        *resolution = 4096;
                    }
                }
                s
            },
            Expect::Refused("budget"),
        ),
        (
            "65 lights",
            || {
                let mut s = small("sphere");
                let l = s.lights[0].clone();
                s.lights = vec![l; 65];
                s
            },
            Expect::Refused("lights"),
        ),
        (
            "64 lights",
            || {
                let mut s = small("sphere");
                let l = s.lights[0].clone();
                s.lights = vec![l; 64];
                s
            },
            Expect::Finite,
        ),
        (
            "quad of 1e-10 half-edges at the origin",
            || {
                let mut s = small("sphere");
                object(
                    &mut s,
                    Shape::Quad {
                        center: Vec3::ZERO,
                        u: Vec3::X * 1e-10,
                        v: Vec3::Z * 1e-10,
                    },
                );
                s
            },
            Expect::Finite,
        ),
        (
            "height field of 1e-12 x 1e-12",
            || {
                let mut s = small("sphere");
                object(
                    &mut s,
                    Shape::HeightField {
                        center: Vec3::ZERO,
                        size: Vec2::splat(1e-12),
                        resolution: 4,
                        waves: vec![],
                    },
                );
                s
            },
            Expect::Finite,
        ),
    ]
}

/// The default triangle budget; the catalogue's budget cases exceed it.
const DEFAULT_BUDGET: u64 = caustica_core::scene::limits::DEFAULT_MAX_TRIANGLES;

#[test]
fn hostile_catalogue_on_every_backend() {
    let mut failures = Vec::new();
    let mut counts = (0, 0);
    for (bname, mut b) in backends() {
        for (name, make, expect) in catalogue() {
            let t0 = Instant::now();
            let what = format!("{bname}/{name}");
            let outcome = render(b.as_mut(), &make(), DEFAULT_BUDGET, &what);
            let secs = t0.elapsed().as_secs_f64();
            let ok = match (&expect, &outcome) {
                (Expect::Refused(needle), Outcome::Refused(m)) => m.contains(needle),
                (Expect::Finite, Outcome::Rendered { .. }) => true,
                (Expect::FiniteDropping(n), Outcome::Rendered { degenerate }) => degenerate >= n,
                _ => false,
            };
            match &outcome {
                Outcome::Refused(_) => counts.0 += 1,
                Outcome::Rendered { .. } => counts.1 += 1,
            }
            eprintln!("{what}: {outcome:?} ({secs:.2} s)");
            // Time bound: a refusal is decided before any allocation, so well under a
            // second even for 10^5-triangle inputs; a small frame renders in seconds.
            if !ok || secs > 30.0 {
                failures.push(format!("{what}: {outcome:?} in {secs:.1} s"));
            }
        }
    }
    eprintln!(
        "hostile catalogue: {} refused cleanly, {} rendered finite",
        counts.0, counts.1
    );
    assert!(failures.is_empty(), "{failures:#?}");
}

// ---- the fuzzer ----

/// Values a numeric field is set to.
const HOSTILE_NUMBERS: &[f64] = &[
    0.0,
    -0.0,
    -1.0,
    1e-45,
    1e-30,
    1e-13,
    1e-6,
    0.5,
    3.0,
    4096.0,
    1e6,
    1e12,
    1.2e12,
    1e18,
    1e30,
    3.4e38,
    -3.4e38,
    4294967295.0,
    4294967296.0,
    1e308,
];

/// One mutation of a scene's JSON tree; `pick` chooses the node (see `nth_node`).
#[derive(Clone, Debug)]
enum Mutation {
    /// Sets a number to one of [`HOSTILE_NUMBERS`].
    Number(usize, usize),
    /// Replaces any value by a string, null, an empty array or an empty object.
    Type(usize, u8),
    /// Deletes a member of an object.
    Delete(usize),
    /// Adds an unknown member to an object.
    Extra(usize),
    /// Duplicates an element of an array (more objects, lights, triangles).
    Duplicate(usize, u8),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        6 => (any::<usize>(), 0..HOSTILE_NUMBERS.len()).prop_map(|(p, v)| Mutation::Number(p, v)),
        1 => (any::<usize>(), 0u8..4).prop_map(|(p, t)| Mutation::Type(p, t)),
        1 => any::<usize>().prop_map(Mutation::Delete),
        1 => any::<usize>().prop_map(Mutation::Extra),
        1 => (any::<usize>(), 1u8..8).prop_map(|(p, n)| Mutation::Duplicate(p, n)),
    ]
}

/// Every node of the tree in pre-order, as a path of keys and indices.
fn nodes(
    v: &serde_json::Value,
    path: &mut Vec<serde_json::Value>,
    out: &mut Vec<Vec<serde_json::Value>>,
) {
    out.push(path.clone());
    match v {
        serde_json::Value::Object(m) => {
            for (k, c) in m {
                path.push(k.clone().into());
                nodes(c, path, out);
                path.pop();
            }
        }
        serde_json::Value::Array(a) => {
            for (i, c) in a.iter().enumerate() {
                path.push(i.into());
                nodes(c, path, out);
                path.pop();
            }
        }
        _ => {}
    }
}

fn at<'a>(v: &'a mut serde_json::Value, path: &[serde_json::Value]) -> &'a mut serde_json::Value {
    path.iter().fold(v, |v, k| match k {
        serde_json::Value::String(s) => &mut v[s.as_str()],
        serde_json::Value::Number(n) => &mut v[n.as_u64().unwrap() as usize],
        _ => unreachable!(),
    })
}

/// Applies `m` to the `pick % n`-th node of the right kind (numbers for `Number`, objects
/// for `Delete`/`Extra`, arrays for `Duplicate`, any for `Type`); no-op when none.
fn apply(root: &mut serde_json::Value, m: &Mutation) {
    let mut all = Vec::new();
    nodes(root, &mut Vec::new(), &mut all);
    let kind = |v: &serde_json::Value| match m {
        Mutation::Number(..) => v.is_number(),
        Mutation::Type(..) => true,
        Mutation::Delete(_) | Mutation::Extra(_) => v.is_object(),
        Mutation::Duplicate(..) => v.as_array().is_some_and(|a| !a.is_empty()),
    };
    let candidates: Vec<_> = all
        .into_iter()
        .filter(|p| kind(at(&mut root.clone(), p)))
        .collect();
    if candidates.is_empty() {
        return;
    }
    let pick = match m {
        Mutation::Number(p, _) | Mutation::Type(p, _) | Mutation::Duplicate(p, _) => *p,
        Mutation::Delete(p) | Mutation::Extra(p) => *p,
    };
    let node = at(root, &candidates[pick % candidates.len()]);
    match m {
        Mutation::Number(_, v) => {
            *node = serde_json::Number::from_f64(HOSTILE_NUMBERS[*v])
                .map(serde_json::Value::Number)
                .unwrap_or(serde_json::Value::Null)
        }
        Mutation::Type(_, t) => {
            *node = match t {
                0 => "text".into(),
                1 => serde_json::Value::Null,
                2 => serde_json::json!([]),
                _ => serde_json::json!({}),
            }
        }
        Mutation::Delete(p) => {
            let m = node.as_object_mut().unwrap();
            if let Some(k) = m.keys().nth(p / 7 % m.len().max(1)).cloned() {
                m.remove(&k);
            }
        }
        Mutation::Extra(_) => {
            node.as_object_mut()
                .unwrap()
                .insert("unknown_field".into(), 1.into());
        }
        Mutation::Duplicate(p, n) => {
            let a = node.as_array_mut().unwrap();
            let e = a[p / 7 % a.len()].clone();
            for _ in 0..*n {
                a.push(e.clone());
            }
        }
    }
}

/// Per-case bound (this 2-core machine, CPU backend, 32x18 pixels, 32x32 photons per
/// light, at most 2^18 triangles): the slowest accepted case is a 2^18-triangle BVH build
/// and up to 64 lights' photon passes, a few seconds.
const CASE_BOUND: Duration = Duration::from_secs(20);
/// Triangle budget of the fuzzer: the budget is what bounds a case's time and memory.
const FUZZ_BUDGET: u64 = 1 << 18;

static NOT_A_SCENE: AtomicUsize = AtomicUsize::new(0);
static INVALID: AtomicUsize = AtomicUsize::new(0);
static REFUSED: AtomicUsize = AtomicUsize::new(0);
static RENDERED: AtomicUsize = AtomicUsize::new(0);
static SLOWEST_MS: AtomicUsize = AtomicUsize::new(0);

proptest! {
    #![proptest_config(ProptestConfig {
        cases: 1024,
        failure_persistence: None,
        ..ProptestConfig::default()
    })]

    #[test]
    fn fuzzed_scene_files_end_cleanly(
        scene in 0..BUILTIN_SCENES.len(),
        mutations in prop::collection::vec(mutation(), 1..4),
    ) {
        let mut json = serde_json::to_value(small(BUILTIN_SCENES[scene])).unwrap();
        for m in &mutations {
            apply(&mut json, m);
        }
        let text = serde_json::to_string(&json).unwrap();
        let t0 = Instant::now();
        if let Err(e) = serde_json::from_str::<Scene>(&text) {
            // not a scene at all: parse_scene must say where
            let e2 = parse_scene(&text, "<fuzz>").expect_err("serde refused it");
            prop_assert!(e2.line > 0, "{e} reported without a line: {e2}");
            NOT_A_SCENE.fetch_add(1, Ordering::Relaxed);
        } else {
            match parse_scene(&text, "<fuzz>") {
                Err(e) => {
                    prop_assert!(e.reason.contains(": "), "{e}");
                    INVALID.fetch_add(1, Ordering::Relaxed);
                }
                Ok(mut s) => {
                    // the fuzzer may have grown the image: keep the render small
                    s.camera.width = s.camera.width.min(64);
                    s.camera.height = s.camera.height.min(64);
                    let mut b = caustica_cpu::CpuBackend::new().expect("cpu backend");
                    match render(&mut b, &s, FUZZ_BUDGET, &format!("{mutations:?}")) {
                        Outcome::Refused(_) => REFUSED.fetch_add(1, Ordering::Relaxed),
                        Outcome::Rendered { .. } => RENDERED.fetch_add(1, Ordering::Relaxed),
                    };
                }
            }
        }
        let secs = t0.elapsed();
        SLOWEST_MS.fetch_max(secs.as_millis() as usize, Ordering::Relaxed);
        prop_assert!(secs < CASE_BOUND, "{mutations:?} took {secs:?}");
        let counts = [&NOT_A_SCENE, &INVALID, &REFUSED, &RENDERED]
            .map(|c| c.load(Ordering::Relaxed));
        let total: usize = counts.iter().sum();
        if total.is_multiple_of(256) {
            eprintln!(
                "fuzz: {total} files: {} not a scene (syntax, type, missing or unknown \
                 field; located), {} refused by validation, {} refused by the build or \
                 creation, {} rendered finite; slowest case {} ms",
                counts[0],
                counts[1],
                counts[2],
                counts[3],
                SLOWEST_MS.load(Ordering::Relaxed)
            );
        }
    }
}

#[test]
fn reading_dev_zero_is_refused_without_filling_memory() {
    let path = std::path::Path::new("/dev/zero");
    if !path.exists() {
        eprintln!("SKIPPING: no /dev/zero on this system");
        return;
    }
    let t0 = Instant::now();
    let e = caustica_core::scene::format::load_scene_file(path).expect_err("not a scene");
    assert!(e.reason.contains("MiB"), "{e}");
    assert!(t0.elapsed() < Duration::from_secs(30));
}

#[test]
fn budget_and_counts_are_checked_before_tessellating() {
    // 8 spheres of 4096 segments would be 134 M triangles (about 6 GB): the error must
    // come from the count, at once.
    let mut s = small("sphere");
    for k in 0..8 {
        object(&mut s, sphere(Vec3::new(k as f32, 0.0, 0.0), 0.4, 4096));
    }
    let t0 = Instant::now();
    let mut b = caustica_cpu::CpuBackend::new().expect("cpu backend");
    match create("sspm", &mut b, &s, &settings(DEFAULT_BUDGET)) {
        Err(Error::InvalidScene(m)) => assert!(m.contains("134"), "{m}"),
        Err(e) => panic!("expected the triangle budget, got {e}"),
        Ok(_) => panic!("134 M triangles accepted"),
    }
    assert!(t0.elapsed() < Duration::from_secs(1));
}

//! `pool`'s waves moved over frames through the vertex update API, on every backend: the
//! water is an instance whose height field `Shape::advanced` carries forward in time
//! (deep-water waves), handed to the technique with `set_object_vertices` (only the
//! water's bottom-level BVH is rebuilt). The frame after the update equals, bitwise, the
//! first frame of a technique created for the pool at that time; and the caustic network
//! on the floor moves: two frames a quarter second apart are far less alike than two
//! renders of one instant with different seeds.

use caustica_conformance::backends;
use caustica_conformance::techniques::frame_outputs;
use caustica_core::scene::builtin::{builtin, POOL_WATER};
use caustica_core::scene::shapes::tessellate;
use caustica_core::scene::{Scene, Shape};
use caustica_core::techniques::create;
use caustica_core::{Backend, Output, Technique};

/// Seconds between the two frames: the waves (0.36-1.1 long, phase speeds
/// `sqrt(g wavelength / 2 pi)` = 0.75-1.31 m/s) travel 0.19-0.33, a third to a half of
/// their wavelengths, so the network's cells (about a wavelength across) move by about
/// their own size.
const STEP_S: f32 = 0.25;

fn pool(width: u32, height: u32) -> Scene {
    let mut s = builtin("pool").expect("built-in scene");
    s.camera.width = width;
    s.camera.height = height;
    s
}

/// The pool with its water `seconds` later.
fn pool_at(scene: &Scene, seconds: f32) -> Scene {
    let mut s = scene.clone();
    s.objects[POOL_WATER].shape = s.objects[POOL_WATER].shape.advanced(seconds);
    s
}

/// Moves the technique's water to `seconds` (from the scene's time 0).
fn move_waves(t: &mut dyn Technique, b: &mut dyn Backend, scene: &Scene, seconds: f32) {
    let m = tessellate(&scene.objects[POOL_WATER].shape.advanced(seconds));
    t.set_object_vertices(b, POOL_WATER, &m.positions, &m.normals)
        .expect("set_object_vertices");
}

#[test]
fn pool_water_is_an_instance_whose_waves_advance() {
    let scene = builtin("pool").expect("built-in scene");
    let water = &scene.objects[POOL_WATER];
    assert!(water.transform.is_some(), "the water is an instance");
    let Shape::HeightField { waves, size, .. } = &water.shape else {
        panic!("the pool's water is a height field");
    };
    // the water fills the basin (the floor's extent) and no more
    let Shape::Quad { u, v, .. } = scene.objects[0].shape else {
        panic!("the pool's first object is its floor");
    };
    assert_eq!((size.x, size.y), (2.0 * u.x.abs(), 2.0 * v.z.abs()));
    // a moved surface keeps the vertex count and triangles, and moves
    let later = water.shape.advanced(STEP_S);
    let (m0, m1) = (tessellate(&water.shape), tessellate(&later));
    assert_eq!(m0.positions.len(), m1.positions.len());
    assert_eq!(m0.indices, m1.indices);
    assert_ne!(m0.positions, m1.positions);
    // deep-water dispersion: omega = sqrt(g k)
    for w in waves {
        let k = std::f32::consts::TAU / w.wavelength;
        assert!((w.angular_frequency() - (9.81 * k).sqrt()).abs() < 1e-5);
    }
}

/// For CausticMap (which sees the floor through the water) and Sspm: the frame after the
/// waves move equals, bitwise, a fresh technique's frame of the pool at that time, on every
/// backend; moving back to time 0 gives the first frame again.
#[test]
fn animated_pool_frames_equal_fresh_techniques_bitwise() {
    let scene = pool(64, 36);
    let later = pool_at(&scene, STEP_S);
    for (bname, mut b) in backends() {
        for (name, settings) in [
            (
                "caustic-map",
                serde_json::json!({
                    "frame": { "photons_w": 64, "photons_h": 64 },
                    "atlas": { "atlas_size": 128 }
                }),
            ),
            (
                "sspm",
                serde_json::json!({ "frame": { "photons_w": 64, "photons_h": 64 } }),
            ),
        ] {
            let mut fresh = create(name, b.as_mut(), &later, &settings).expect("create");
            let want = frame_outputs(fresh.as_mut(), b.as_mut());
            fresh.free(b.as_mut()).expect("free");

            let mut t = create(name, b.as_mut(), &scene, &settings).expect("create");
            let first = frame_outputs(t.as_mut(), b.as_mut());
            move_waves(t.as_mut(), b.as_mut(), &scene, STEP_S);
            let got = frame_outputs(t.as_mut(), b.as_mut());
            assert!(
                got == want,
                "{bname}/{name}: the animated frame differs from a fresh technique's"
            );
            assert!(
                got != first,
                "{bname}/{name}: moving the waves changed nothing"
            );
            move_waves(t.as_mut(), b.as_mut(), &scene, 0.0);
            let back = frame_outputs(t.as_mut(), b.as_mut());
            assert!(
                back == first,
                "{bname}/{name}: the waves moved back, the frame differs from the first"
            );
            t.free(b.as_mut()).expect("free");
            eprintln!("{bname}/{name}: the animated pool equals fresh techniques, bitwise");
        }
    }
}

/// Pearson correlation of two images' channel sums over the pixels where either is lit.
fn correlation(a: &[[f32; 4]], b: &[[f32; 4]]) -> f64 {
    let v = |p: &[f32; 4]| (p[0] + p[1] + p[2]) as f64;
    let pairs: Vec<(f64, f64)> = a
        .iter()
        .zip(b)
        .map(|(p, q)| (v(p), v(q)))
        .filter(|(x, y)| *x > 0.0 || *y > 0.0)
        .collect();
    let n = pairs.len() as f64;
    let (mx, my) = pairs
        .iter()
        .fold((0.0, 0.0), |(sx, sy), (x, y)| (sx + x / n, sy + y / n));
    let (mut sxy, mut sxx, mut syy) = (0.0, 0.0, 0.0);
    for (x, y) in &pairs {
        sxy += (x - mx) * (y - my);
        sxx += (x - mx) * (x - mx);
        syy += (y - my) * (y - my);
    }
    sxy / (sxx * syy).sqrt()
}

/// The caustic network moves: CausticMap's filtered caustics (the floor seen through the
/// water) a quarter second apart correlate below 0.5, while two renders of the same
/// instant with different seeds (photon noise only) correlate above 0.9, so the
/// measurement resolves the change, which is the waves' and not the noise's. Both bounds
/// leave room: a pattern moved by about its cell size is close to uncorrelated with itself
/// (near 0), and at 512^2 photons the noise is a small part of the network's contrast.
#[test]
fn floor_caustics_move_between_frames() {
    let scene = pool(160, 90);
    let mut b = caustica_cpu::CpuBackend::new().expect("cpu backend");
    let settings = |seed: u32| {
        serde_json::json!({
            "frame": { "photons_w": 512, "photons_h": 512, "seed": seed },
            "atlas": { "atlas_size": 1024 }
        })
    };
    let caustics = |t: &mut dyn Technique, b: &mut dyn Backend| {
        t.frame(b, &mut |_| {}).expect("frame");
        t.read_output(b, Output::FilteredCaustics)
            .expect("read")
            .pixels
    };
    let mut t = create("caustic-map", &mut b, &scene, &settings(1)).expect("create");
    let first = caustics(t.as_mut(), &mut b);
    move_waves(t.as_mut(), &mut b, &scene, STEP_S);
    let moved = caustics(t.as_mut(), &mut b);
    t.free(&mut b).expect("free");
    let mut other = create("caustic-map", &mut b, &scene, &settings(2)).expect("create");
    let reseeded = caustics(other.as_mut(), &mut b);
    other.free(&mut b).expect("free");

    let (waves, noise) = (correlation(&first, &moved), correlation(&first, &reseeded));
    eprintln!("correlation a quarter second apart {waves:.3}, between seeds {noise:.3}");
    assert!(
        noise > 0.9,
        "two seeds of one instant correlate {noise:.3}: too noisy to tell"
    );
    assert!(
        waves < 0.5,
        "frames a quarter second apart correlate {waves:.3}: the caustics barely moved"
    );
}

//! PhotonGi's stiff cases on every backend (`backends()`: all four,
//! required in CI), each against the CPU's frame of the same scene and seed:
//!
//! - **A light whose RSM sees nothing** (a spot aimed into empty space beside the room):
//!   its RSM, rendered in the first frame before the device selects the photon plan, has
//!   no texel that leaves flux, so it gets no photon (none could carry any) and the plan
//!   read back says so; the room's light gets the whole budget and the frame stays
//!   finite.
//! - **Albedo-1 walls** (a closed white box of albedo exactly 1): Jensen's roulette never
//!   ends a path there (survival `max(flux x 1) / max(flux) = 1`), so every path must end
//!   by the bounce limit, none by roulette, and the image stays finite.
//! - **A room one pixel wide** on screen (a corridor 0.2 wide seen from 20 away, 54 rows
//!   over 30 degrees): splats of pixel size on a sliver; some photons are seen and
//!   stored, the image is finite, and the stored photons agree.
//! - **A light of zero power beside one of 1e9 W/sr**: the allocation gives the dark light
//!   no photon, the bright one all of them; its photons' fixed-point flux neither
//!   overflows silently nor turns into Inf or NaN.
//!
//! Agreement with the CPU: stored photons within the path-divergence allowance
//! (`divergence_allowance` of the stored count, times the bounces), path-end counters
//! within the allowance of the emitted count, and the raw indirect image's total within
//! 1% plus the diverged photons' share.

use caustica_conformance::backends;
use caustica_conformance::harness::tolerance::divergence_allowance;
use caustica_core::frame::output::Output;
use caustica_core::frame::stats::FrameStats;
use caustica_core::scene::{Camera, Light, Material, Object, Scene, Shape};
use caustica_core::techniques::create;
use caustica_core::Backend;
use glam::Vec3;
use std::collections::BTreeMap;

const BOUNCES: u32 = 3;

fn quad(name: &str, material: &str, c: Vec3, u: Vec3, v: Vec3) -> Object {
    Object {
        name: name.into(),
        material: material.into(),
        shape: Shape::Quad { center: c, u, v },
        transform: None,
    }
}

/// A closed box `[-h, h]^3` of material `m`, the camera inside looking at a wall.
fn closed_box(m: Material, h: f32, lights: Vec<Light>) -> Scene {
    Scene {
        name: "box".into(),
        description: String::new(),
        camera: Camera {
            position: Vec3::new(0.0, 0.0, 0.8 * h),
            target: Vec3::new(0.0, 0.0, -h),
            up: Vec3::Y,
            fov_y_deg: 60.0,
            width: 64,
            height: 36,
        },
        materials: BTreeMap::from([("wall".into(), m)]),
        objects: vec![
            quad(
                "floor",
                "wall",
                Vec3::new(0.0, -h, 0.0),
                Vec3::X * h,
                -Vec3::Z * h,
            ),
            quad(
                "ceiling",
                "wall",
                Vec3::new(0.0, h, 0.0),
                Vec3::X * h,
                Vec3::Z * h,
            ),
            quad(
                "back",
                "wall",
                Vec3::new(0.0, 0.0, -h),
                Vec3::X * h,
                Vec3::Y * h,
            ),
            quad(
                "front",
                "wall",
                Vec3::new(0.0, 0.0, h),
                Vec3::X * h,
                -Vec3::Y * h,
            ),
            quad(
                "left",
                "wall",
                Vec3::new(-h, 0.0, 0.0),
                Vec3::Y * h,
                Vec3::Z * h,
            ),
            quad(
                "right",
                "wall",
                Vec3::new(h, 0.0, 0.0),
                Vec3::Y * h,
                -Vec3::Z * h,
            ),
        ],
        lights,
    }
}

fn point(p: Vec3, i: f32) -> Light {
    Light::Point {
        position: p,
        intensity: Vec3::splat(i),
    }
}

/// The cases: (name, scene).
fn cases() -> Vec<(&'static str, Scene)> {
    let white = Material::Diffuse {
        albedo: Vec3::splat(0.7),
    };
    let mut blind = closed_box(
        white.clone(),
        1.0,
        vec![point(Vec3::new(0.0, 0.5, 0.0), 2.0)],
    );
    // open the box's front so that a spot outside it can aim into nothing
    blind.objects.retain(|o| o.name != "front");
    blind.lights.push(Light::Spot {
        position: Vec3::new(0.0, 0.0, 3.0),
        direction: Vec3::Z,
        intensity: Vec3::splat(5.0),
        inner_angle_deg: 10.0,
        outer_angle_deg: 20.0,
    });
    let albedo_one = closed_box(
        Material::Diffuse { albedo: Vec3::ONE },
        1.0,
        vec![point(Vec3::new(0.2, 0.6, -0.1), 1.0)],
    );
    let mut sliver = closed_box(
        white.clone(),
        1.0,
        vec![point(Vec3::new(0.0, 0.5, 0.0), 2.0)],
    );
    // a corridor 0.2 wide (one pixel footprint, 2 x 20 x tan 15 deg / 54 = 0.2, at the
    // camera's distance): the box squeezed along x, seen from 20 away
    for o in &mut sliver.objects {
        if let Shape::Quad { center, u, v } = &mut o.shape {
            *center *= Vec3::new(0.1, 1.0, 1.0);
            *u *= Vec3::new(0.1, 1.0, 1.0);
            *v *= Vec3::new(0.1, 1.0, 1.0);
        }
    }
    sliver.objects.retain(|o| o.name != "front");
    sliver.lights = vec![point(Vec3::new(0.0, 0.5, 0.0), 2.0)];
    sliver.camera = Camera {
        position: Vec3::new(0.0, 0.0, 20.0),
        target: Vec3::new(0.0, 0.0, -1.0),
        up: Vec3::Y,
        fov_y_deg: 30.0,
        width: 96,
        height: 54,
    };
    let extremes = closed_box(
        white,
        1.0,
        vec![
            point(Vec3::new(-0.5, 0.5, 0.0), 0.0),
            point(Vec3::new(0.5, 0.5, 0.0), 1e9),
        ],
    );
    vec![
        ("a light whose RSM sees nothing", blind),
        ("albedo-1 walls", albedo_one),
        ("a room one pixel wide", sliver),
        ("a light of zero power beside one of 1e9", extremes),
    ]
}

const FOUR_PI: f64 = 4.0 * std::f64::consts::PI;

/// Flux is kept along albedo-1 paths: roulette survives with probability 1 and scales
/// nothing, so each stored photon carries its initial photon's flux, which importance
/// sampling makes the same for all (a grey light on grey walls: a texel's probability is
/// its share of the flux), the RSM's arriving flux over the photon count. The RSM's
/// texels receive the light's `I x 4 pi` (the frame's `emitted_flux`) up to their solid
/// angles' centre rule, which this computes (`texel_arriving_flux` over the six faces);
/// the rest is the f32 rounding of a photon's flux (the pyramid's sums and ratios, a few
/// dozen roundings of 2^-24: 1e-5 covers them) and half a fixed-point quantum a stored
/// photon.
fn flux_kept_along_albedo_one_paths(st: &FrameStats, what: &str) {
    use caustica_core::math::rsm::texel_arriving_flux;
    let side = RSM_SIZE;
    let face: f64 = (0..side * side)
        .map(|k| texel_arriving_flux(Vec3::ONE, 1.0, k % side, k / side, side, 1.0).y as f64)
        .sum();
    let rule = (6.0 * face - FOUR_PI).abs() / FOUR_PI;
    assert_eq!(st.emitted_flux, [FOUR_PI; 3], "{what}");
    assert!(st.photons_stored > 0, "{what}: nothing stored");
    let per_photon = st.emitted_flux[1] / st.photons_emitted as f64;
    for c in 0..3 {
        let per_stored = st.stored_flux[c] / st.photons_stored as f64;
        let allow = per_photon * (rule + 1e-5) + 0.5 * st.flux_quantum;
        assert!(
            (per_stored - per_photon).abs() <= allow,
            "{what}: channel {c}: a stored photon carries {per_stored:e} W, an emitted one \
             {per_photon:e} (allowed {allow:e}: the RSM's solid angles off by {rule:e})"
        );
    }
}

/// RSM side (texels) of the cases' frames.
const RSM_SIZE: u32 = 32;

fn run(b: &mut dyn Backend, scene: &Scene) -> (FrameStats, Vec<[f32; 4]>) {
    let settings = serde_json::json!({
        "photons_w": 96, "photons_h": 96, "rsm_size": RSM_SIZE, "bounces": BOUNCES,
        "temporal": false, "atrous_iterations": 0
    });
    let mut t = create("photon-gi", b, scene, &settings).expect("create");
    let st = t.frame(b, &mut |_| {}).expect("frame");
    let img = t.read_output(b, Output::RawIndirect).expect("read").pixels;
    t.free(b).expect("free");
    (st, img)
}

#[test]
fn photon_gi_stiff_cases_on_every_backend() {
    let mut reference: Vec<(FrameStats, Vec<[f32; 4]>)> = Vec::new();
    for (name, mut b) in backends() {
        for (k, (case, scene)) in cases().into_iter().enumerate() {
            let (st, img) = run(b.as_mut(), &scene);
            let what = format!("{name} / {case}");
            assert!(
                img.iter().flatten().all(|x| x.is_finite()),
                "{what}: a pixel is not finite"
            );
            let total: f64 = img.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum();
            eprintln!(
                "{what}: photons per light {:?}, stored {}, flux emitted {:?} stored {:?}, ends: escaped {} roulette {} limit {}, saturated {}, total {total:.4e}",
                st.photons_per_light,
                st.photons_stored,
                st.emitted_flux,
                st.stored_flux,
                st.discarded.escaped,
                st.discarded.negligible_power,
                st.discarded.bounce_limit,
                st.fixed_point_saturated
            );
            match case {
                "a light whose RSM sees nothing" => {
                    assert!(
                        st.photons_stored > 0,
                        "{what}: the box's light stored nothing"
                    );
                    // the blind spot's RSM is rendered and proven empty: no photon, the
                    // box's light gets the whole budget, the plan says why
                    // only the lights given photons emit: the box's, 2 W/sr all round
                    assert_eq!(st.emitted_flux, [2.0 * FOUR_PI; 3], "{what}");
                    assert_eq!(
                        st.photons_per_light,
                        vec![st.photons_emitted, 0],
                        "{what}: the blind light got photons"
                    );
                    let plan = st.plan.as_ref().expect("plan");
                    assert!(
                        !plan.lights[1].emits && plan.lights[1].reason.contains("sees no texel"),
                        "{what}: {:?}",
                        plan.lights[1]
                    );
                }
                "a room one pixel wide" => assert!(
                    st.photons_stored > 0,
                    "{what}: the camera sees no photon in the corridor"
                ),
                "albedo-1 walls" => {
                    // paths that start with flux end by the bounce limit (or escape
                    // nowhere: the box is closed); roulette may only end the RSM's
                    // zero-flux samples
                    assert_eq!(
                        st.discarded.escaped, 0,
                        "{what}: a photon left a closed box"
                    );
                    assert!(
                        st.discarded.bounce_limit >= st.photons_emitted * 9 / 10,
                        "{what}: only {} of {} paths reached the bounce limit",
                        st.discarded.bounce_limit,
                        st.photons_emitted
                    );
                    flux_kept_along_albedo_one_paths(&st, &what);
                }
                "a light of zero power beside one of 1e9" => {
                    assert_eq!(
                        st.photons_per_light[0], 0,
                        "{what}: the dark light got photons"
                    );
                    assert_eq!(st.photons_per_light[1], st.photons_emitted, "{what}");
                    assert_eq!(st.emitted_flux, [1e9 * FOUR_PI; 3], "{what}");
                    assert!(total > 0.0, "{what}: no light");
                }
                _ => {}
            }
            if name == "cpu" {
                reference.push((st, img));
                continue;
            }
            let (rs, rimg) = &reference[k];
            let stored = rs.photons_stored.max(st.photons_stored);
            let allow = divergence_allowance(stored) * BOUNCES as u64;
            assert!(
                rs.photons_stored.abs_diff(st.photons_stored) <= allow,
                "{what}: stored {} vs cpu {} (allowance {allow})",
                st.photons_stored,
                rs.photons_stored
            );
            let paths = divergence_allowance(rs.photons_emitted);
            assert!(
                rs.discarded
                    .bounce_limit
                    .abs_diff(st.discarded.bounce_limit)
                    <= paths,
                "{what}: bounce-limit ends {} vs cpu {}",
                st.discarded.bounce_limit,
                rs.discarded.bounce_limit
            );
            let rtotal: f64 = rimg.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum();
            let share = allow as f64 / stored.max(1) as f64;
            assert!(
                (total - rtotal).abs() <= (0.01 + 2.0 * share) * rtotal.max(f64::MIN_POSITIVE),
                "{what}: image total {total} vs cpu {rtotal}"
            );
        }
    }
}

/// The raw indirect image, the photons per light and the flux quantum of a frame, and
/// whether the plan says the spot (light `spot`) sees nothing.
type GiFrame = (Vec<[f32; 4]>, Vec<u64>, f64, bool);

fn gi_frame(t: &mut dyn caustica_core::Technique, b: &mut dyn Backend, spot: usize) -> GiFrame {
    let st = t.frame(b, &mut |_| {}).expect("frame");
    let img = t.read_output(b, Output::RawIndirect).expect("read").pixels;
    let blind = st
        .plan
        .as_ref()
        .and_then(|p| p.lights.get(spot))
        .is_some_and(|l| !l.emits && l.reason.contains("sees no texel"));
    (img, st.photons_per_light, st.flux_quantum, blind)
}

/// A spot turned from the room into empty space and back (`set_lights`): the frame after
/// each update, and the one after it (which traces with the plan read back), equal a
/// fresh technique's frame of that scene bitwise, photons per light and flux quantum
/// included, on every backend; the blind spot's photons go to the room's light. With a
/// light of its own per corner besides (ten lights with power, more than the device's
/// plan table covers) the host probes on updates, and the same holds.
#[test]
fn a_spot_turned_blind_and_back_equals_a_fresh_technique_bitwise() {
    let white = Material::Diffuse {
        albedo: Vec3::splat(0.7),
    };
    let mut aimed = closed_box(white, 1.0, vec![point(Vec3::new(0.0, 0.5, 0.0), 2.0)]);
    aimed.objects.retain(|o| o.name != "front");
    let spot = |direction: Vec3| Light::Spot {
        position: Vec3::new(0.0, 0.0, 3.0),
        direction,
        intensity: Vec3::splat(5.0),
        inner_angle_deg: 10.0,
        outer_angle_deg: 20.0,
    };
    let mut many = aimed.clone();
    for k in 0..8 {
        let c = |bit: usize| if k & (1 << bit) != 0 { 0.6 } else { -0.6 };
        many.lights
            .push(point(Vec3::new(c(0), c(1), c(2) * 0.5), 0.2));
    }
    let settings = serde_json::json!({
        "photons_w": 96, "photons_h": 96, "rsm_size": RSM_SIZE, "bounces": BOUNCES,
        "temporal": false, "atrous_iterations": 0
    });
    for (name, mut b) in backends() {
        for (what, base) in [("two lights", &aimed), ("ten lights", &many)] {
            let with_spot = |d: Vec3| {
                let mut s = base.clone();
                s.lights.insert(1, spot(d));
                s
            };
            let (room, blind) = (with_spot(-Vec3::Z), with_spot(Vec3::Z));
            let fresh = |b: &mut dyn Backend, s: &Scene| {
                let mut t = create("photon-gi", b, s, &settings).expect("create");
                let f = gi_frame(t.as_mut(), b, 1);
                t.free(b).expect("free");
                f
            };
            let want_room = fresh(b.as_mut(), &room);
            let want_blind = fresh(b.as_mut(), &blind);
            assert!(
                want_blind.3,
                "{name} / {what}: a fresh technique's spot sees something"
            );
            assert_eq!(
                want_blind.1[1], 0,
                "{name} / {what}: the blind spot got photons"
            );
            assert!(
                !want_room.3 && want_room.1[1] > 0,
                "{name} / {what}: the spot sees nothing"
            );
            let mut t = create("photon-gi", b.as_mut(), &room, &settings).expect("create");
            gi_frame(t.as_mut(), b.as_mut(), 1);
            for (to, want) in [(&blind, &want_blind), (&room, &want_room)] {
                t.set_lights(b.as_mut(), &to.lights).expect("set_lights");
                for k in 0..2 {
                    let got = gi_frame(t.as_mut(), b.as_mut(), 1);
                    assert!(
                        got.0 == want.0,
                        "{name} / {what}: frame {k} after the update differs from a fresh technique's"
                    );
                    assert_eq!(
                        (&got.1, got.2, got.3),
                        (&want.1, want.2, want.3),
                        "{name} / {what}: frame {k}"
                    );
                }
            }
            t.free(b.as_mut()).expect("free");
        }
        eprintln!("*** {name}: a spot turned blind and back equals a fresh technique ***");
    }
}

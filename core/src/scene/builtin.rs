//! Built-in procedural scenes. Each function's doc comment states its geometry; every
//! scene round-trips through the file format (`caustica scenes --export NAME`).
//! Units: metres; light intensity W/sr; irradiance W/m^2.

use super::{Aabb, Camera, Light, Material, Object, Scene, Shape, Wave};
use glam::{Vec2, Vec3};
use std::collections::BTreeMap;

/// Names of the built-in scenes, in the order `caustica scenes` lists them.
pub const BUILTIN_SCENES: [&str; 10] = [
    "sphere",
    "sphere-sun",
    "ring",
    "cornell",
    "pool",
    "prism",
    "jelly",
    "spot-glass",
    "plain",
    "rooms",
];

/// The built-in scene called `name`, or `None`.
pub fn builtin(name: &str) -> Option<Scene> {
    Some(match name {
        "sphere" => sphere(),
        "sphere-sun" => sphere_sun(),
        "ring" => ring(),
        "cornell" => cornell(),
        "pool" => pool(),
        "prism" => prism(),
        "jelly" => jelly(),
        "spot-glass" => spot_glass(),
        "plain" => plain(),
        "rooms" => rooms(),
        _ => return None,
    })
}

/// Default image size of the built-in cameras (pixels).
pub const DEFAULT_WIDTH: u32 = 960;
/// Default image height (pixels).
pub const DEFAULT_HEIGHT: u32 = 540;

fn camera(position: Vec3, target: Vec3, fov_y_deg: f32) -> Camera {
    Camera {
        position,
        target,
        up: Vec3::Y,
        fov_y_deg,
        width: DEFAULT_WIDTH,
        height: DEFAULT_HEIGHT,
    }
}

fn obj(name: &str, material: &str, shape: Shape) -> Object {
    Object {
        name: name.into(),
        material: material.into(),
        shape,
        transform: None,
    }
}

fn diffuse(a: f32) -> Material {
    Material::Diffuse {
        albedo: Vec3::splat(a),
    }
}

fn glass(ior: f32) -> Material {
    Material::Dielectric {
        ior,
        cauchy_b: 0.0,
        absorption: Vec3::ZERO,
        ior_model: Default::default(),
    }
}

/// Floor quad of half-size `h` in the plane y = `y`, normal +y.
fn floor(h: f32, y: f32) -> Shape {
    Shape::Quad {
        center: Vec3::new(0.0, y, 0.0),
        u: Vec3::new(h, 0.0, 0.0),
        v: Vec3::new(0.0, 0.0, -h),
    }
}

/// `sphere`: white diffuse plane 4 x 4 centred at the origin in y = 0 (albedo 0.8); glass
/// sphere IOR 1.5, radius 0.5, centre (0, 1, 0); point light at (0, 3, 0) with intensity
/// 10 W/sr per channel; camera at (0, 4, 3) looking at the origin, vertical fov 45 deg.
/// The ball is tessellated with 384 segments (147k triangles): with 192 its facets moved
/// the caustic 0.3% (relative L2 at 960x540) from the exact sphere's, a floor Sspm's
/// estimate reached at 4096^2 photons; with 384 the difference is below a frame's noise at
/// 8192^2 (docs/sspm.md, "Against the exact sphere").
pub fn sphere() -> Scene {
    Scene {
        name: "sphere".into(),
        description: "Glass ball (IOR 1.5, r 0.5, centre (0,1,0)) over a 4x4 white plane at y=0, point light 10 W/sr at (0,3,0)".into(),
        camera: camera(Vec3::new(0.0, 4.0, 3.0), Vec3::ZERO, 45.0),
        materials: BTreeMap::from([("white".into(), diffuse(0.8)), ("glass".into(), glass(1.5))]),
        objects: vec![
            obj("plane", "white", floor(2.0, 0.0)),
            obj("ball", "glass", Shape::Sphere { center: Vec3::Y, radius: 0.5, segments: 384 }),
        ],
        lights: vec![Light::Point { position: Vec3::new(0.0, 3.0, 0.0), intensity: Vec3::splat(10.0) }],
    }
}

/// `sphere-sun`: the `sphere` scene lit by a directional light straight down (irradiance
/// 1 W/m^2) with a projection volume [-0.55, 0.45, -0.55] .. [0.55, 1.55, 0.55] around the
/// ball. The ball lens focuses at `f = n R / (2 (n - 1)) = 0.75` below its centre (y = 0.25).
pub fn sphere_sun() -> Scene {
    let mut s = sphere();
    s.name = "sphere-sun".into();
    s.description =
        "The sphere scene under a directional light straight down, irradiance 1 W/m^2".into();
    s.lights = vec![Light::Directional {
        direction: -Vec3::Y,
        irradiance: Vec3::ONE,
        projection_volume: Some(Aabb {
            min: Vec3::new(-0.55, 0.45, -0.55),
            max: Vec3::new(0.55, 1.55, 0.55),
        }),
    }];
    s
}

/// `ring`: a mirror ring (inner radius 1, wall 0.04, height 0.25, reflectance 0.95 gold
/// tint) standing on a 4 x 4 white plane at y = 0, lit from the side by a directional light
/// travelling along (1, -0.45, 0) (irradiance 3): the inner wall focuses a cardioid onto the
/// plane. Camera at (0, 3.6, 2.2) looking at the origin, fov 45 deg.
pub fn ring() -> Scene {
    Scene {
        name: "ring".into(),
        description: "Mirror ring on a plane lit from the side: a cardioid caustic".into(),
        camera: camera(Vec3::new(0.0, 3.6, 2.2), Vec3::ZERO, 45.0),
        materials: BTreeMap::from([
            ("white".into(), diffuse(0.8)),
            (
                "gold".into(),
                Material::Mirror {
                    reflectance: Vec3::new(0.95, 0.8, 0.45),
                },
            ),
        ]),
        objects: vec![
            obj("plane", "white", floor(2.0, 0.0)),
            obj(
                "ring",
                "gold",
                Shape::Ring {
                    center: Vec3::ZERO,
                    radius: 1.0,
                    thickness: 0.04,
                    height: 0.25,
                    segments: 256,
                },
            ),
        ],
        lights: vec![Light::Directional {
            direction: Vec3::new(1.0, -0.45, 0.0),
            irradiance: Vec3::splat(3.0),
            projection_volume: None,
        }],
    }
}

/// `cornell`: box [-1, 1] x [0, 2] x [-1, 1] open towards +z: white floor, ceiling and back
/// wall (albedo 0.75), red left wall (x = -1), green right wall (x = 1); a glass sphere
/// (IOR 1.5, r 0.35) at (-0.45, 0.35, -0.25) and a mirror sphere (r 0.35) at
/// (0.45, 0.35, 0.3); point light 3 W/sr at (0, 1.9, 0); camera at (0, 1, 3.6) looking at
/// (0, 1, 0), fov 40 deg.
pub fn cornell() -> Scene {
    let q = |c: Vec3, u: Vec3, v: Vec3| Shape::Quad { center: c, u, v };
    Scene {
        name: "cornell".into(),
        description: "Cornell box with a glass and a mirror sphere, point light near the ceiling"
            .into(),
        camera: camera(Vec3::new(0.0, 1.0, 3.6), Vec3::new(0.0, 1.0, 0.0), 40.0),
        materials: BTreeMap::from([
            ("white".into(), diffuse(0.75)),
            (
                "red".into(),
                Material::Diffuse {
                    albedo: Vec3::new(0.75, 0.12, 0.1),
                },
            ),
            (
                "green".into(),
                Material::Diffuse {
                    albedo: Vec3::new(0.12, 0.6, 0.15),
                },
            ),
            ("glass".into(), glass(1.5)),
            (
                "mirror".into(),
                Material::Mirror {
                    reflectance: Vec3::splat(0.95),
                },
            ),
        ]),
        objects: vec![
            obj("floor", "white", q(Vec3::ZERO, Vec3::X, -Vec3::Z)),
            obj(
                "ceiling",
                "white",
                q(Vec3::new(0.0, 2.0, 0.0), Vec3::X, Vec3::Z),
            ),
            obj(
                "back",
                "white",
                q(Vec3::new(0.0, 1.0, -1.0), Vec3::X, Vec3::Y),
            ),
            obj(
                "left",
                "red",
                q(Vec3::new(-1.0, 1.0, 0.0), Vec3::Y, Vec3::Z),
            ),
            obj(
                "right",
                "green",
                q(Vec3::new(1.0, 1.0, 0.0), Vec3::Y, -Vec3::Z),
            ),
            obj(
                "glass ball",
                "glass",
                Shape::Sphere {
                    center: Vec3::new(-0.45, 0.35, -0.25),
                    radius: 0.35,
                    segments: 128,
                },
            ),
            obj(
                "mirror ball",
                "mirror",
                Shape::Sphere {
                    center: Vec3::new(0.45, 0.35, 0.3),
                    radius: 0.35,
                    segments: 128,
                },
            ),
        ],
        lights: vec![Light::Point {
            position: Vec3::new(0.0, 1.9, 0.0),
            intensity: Vec3::splat(3.0),
        }],
    }
}

/// Object `name` of `material`: the parallelogram `center + s u + t v`, `s, t` in
/// [-1, 1], facing `u x v`.
fn rect(name: &str, material: &str, center: Vec3, u: Vec3, v: Vec3) -> Object {
    obj(name, material, Shape::Quad { center, u, v })
}

/// Curvature (1/m) of each of the pool's wave crests: `a k^2` with `k = 2 pi / wavelength`.
const POOL_CREST_CURVATURE: f32 = 1.2;

/// The pool's water at time 0: seven sine waves summed, wavelengths 0.36-1.1 in seven
/// directions, each of amplitude `1.2 wavelength^2 / (4 pi^2)` (0.004-0.037), so that every
/// crest has the curvature `kappa = a k^2 = 1.2` per metre. A crest focuses refracted
/// sunlight about `n / ((n - 1) kappa)` below it: 3.4 m for one wave alone, 1 m or less
/// where three or more crests add, so the floor 1 below catches the sharp network of their
/// focal lines.
fn pool_waves() -> Vec<Wave> {
    // (wavelength, direction in degrees from +x towards +z, phase)
    [
        (1.1f32, 10.0f32, 0.0f32),
        (0.83, 75.0, 1.3),
        (0.67, 140.0, 2.1),
        (0.57, 200.0, 4.0),
        (0.49, 260.0, 0.7),
        (0.41, 320.0, 3.3),
        (0.36, 35.0, 5.1),
    ]
    .into_iter()
    .map(|(wavelength, deg, phase)| {
        let k = std::f32::consts::TAU / wavelength;
        let (s, c) = deg.to_radians().sin_cos();
        Wave {
            amplitude: POOL_CREST_CURVATURE / (k * k),
            wavelength,
            direction: Vec2::new(c, s),
            phase,
        }
    })
    .collect()
}

/// Index of the water in [`pool`]'s objects (an instance: its transform is the identity,
/// so its waves can be moved with `Technique::set_object_vertices`).
pub const POOL_WATER: usize = 5;

/// `pool`: a basin 4 x 4 and 1 deep: a tiled floor (light blue-grey) at y = -1 inside
/// four tiled walls rising to a stone deck at y = 0.15 that runs 2 wide around it; the
/// water (IOR 1.33) is a height field filling the basin exactly (x, z in [-2, 2], 256
/// quads a side, mean level y = 0) of the seven waves of [`pool_waves`], an instance with
/// the identity transform ([`POOL_WATER`]) so that a frame loop can move its waves
/// ([`Wave::advanced`], `Technique::set_object_vertices`). Sun: a directional light
/// travelling along (0.15, -1, -0.25) (away from the camera, so that the far wall catches
/// light too), irradiance 2. Camera above the water's edge at (-0.5, 1.8, 2.8) looking
/// down at (0.35, -1, -0.8), fov 50 deg. The water casts every shadow under it, so the
/// floor shows only the light the waves focus: the caustic network (the wall at -x, which
/// the sun does not reach, stays dark). The camera sees the floor only through the water,
/// where CausticMap's and AdaptiveCaustics' atlases show caustics; Sspm's screen-space
/// photons land only on surfaces in direct view, here the deck.
pub fn pool() -> Scene {
    let (h, depth, deck) = (2.0, 1.0, 0.15);
    let wall_y = (deck - depth) / 2.0;
    let wall_h = (deck + depth) / 2.0;
    let mut water = obj(
        "water",
        "water",
        Shape::HeightField {
            center: Vec3::ZERO,
            size: Vec2::splat(2.0 * h),
            resolution: 256,
            waves: pool_waves(),
        },
    );
    water.transform = Some(super::Transform::IDENTITY);
    // the deck's outer edge and the middle of its slabs
    let (outer, stone) = (h + 2.0, h + 1.0);
    Scene {
        name: "pool".into(),
        description: "Swimming pool seen from its edge: waves (IOR 1.33) focus the sun into a caustic network on the floor 1 below, seen through the water (--technique caustic-map; --animate SECONDS moves the waves)".into(),
        camera: camera(Vec3::new(-0.5, 1.8, 2.8), Vec3::new(0.35, -1.0, -0.8), 50.0),
        materials: BTreeMap::from([
            (
                "tiles".into(),
                Material::Diffuse {
                    albedo: Vec3::new(0.6, 0.75, 0.8),
                },
            ),
            (
                "stone".into(),
                Material::Diffuse {
                    albedo: Vec3::new(0.7, 0.66, 0.6),
                },
            ),
            ("water".into(), glass(1.33)),
        ]),
        objects: vec![
            obj("floor", "tiles", floor(h, -depth)),
            // the walls face the water
            rect("wall -x", "tiles", Vec3::new(-h, wall_y, 0.0), Vec3::Y * wall_h, Vec3::Z * h),
            rect("wall +x", "tiles", Vec3::new(h, wall_y, 0.0), Vec3::Z * h, Vec3::Y * wall_h),
            rect("wall -z", "tiles", Vec3::new(0.0, wall_y, -h), Vec3::X * h, Vec3::Y * wall_h),
            rect("wall +z", "tiles", Vec3::new(0.0, wall_y, h), Vec3::Y * wall_h, Vec3::X * h),
            water,
            // the deck: four slabs around the basin, facing up
            rect("deck -z", "stone", Vec3::new(0.0, deck, -stone), Vec3::X * outer, -Vec3::Z * (outer - h) * 0.5),
            rect("deck +z", "stone", Vec3::new(0.0, deck, stone), Vec3::X * outer, -Vec3::Z * (outer - h) * 0.5),
            rect("deck -x", "stone", Vec3::new(-stone, deck, 0.0), Vec3::X * (outer - h) * 0.5, -Vec3::Z * h),
            rect("deck +x", "stone", Vec3::new(stone, deck, 0.0), Vec3::X * (outer - h) * 0.5, -Vec3::Z * h),
        ],
        lights: vec![Light::Directional {
            direction: Vec3::new(0.15, -1.0, -0.25),
            irradiance: Vec3::splat(2.0),
            projection_volume: None,
        }],
    }
}

/// The prism's wall with the slit: the plane x = `PRISM_SLIT_X`.
pub const PRISM_SLIT_X: f32 = -0.4;
/// Centre height of the prism's slit (y).
pub const PRISM_SLIT_Y: f32 = 0.7;
/// Half-height of the prism's slit (scene units).
pub const PRISM_SLIT_HALF_HEIGHT: f32 = 0.02;
/// Half-length of the prism's slit along z (scene units).
pub const PRISM_SLIT_HALF_LENGTH: f32 = 0.35;
/// The prism's screen: the plane x = `PRISM_SCREEN_X`, facing -x.
pub const PRISM_SCREEN_X: f32 = 1.5;

/// The direction of the prism's beam: in the xy plane, rising at
/// `asin(1.5 sin 30 deg) - 30 deg = 18.59 deg`, the angle at which light of index 1.5 (the
/// flint's at 550 nm, the green channel's) passes the prism at minimum deviation, parallel
/// to its base inside.
pub fn prism_beam_direction() -> Vec3 {
    let rise = (1.5f32 * 0.5).asin() - 30f32.to_radians();
    Vec3::new(rise.cos(), rise.sin(), 0.0)
}

/// `prism`: Newton's experiment in a dark room 1.9 x 1.8 x 1.4, open at the front.
/// A collimated beam ([`prism_beam_direction`], irradiance 4) passes a slit 0.04 x 0.7
/// (centre y = 0.7, along z) in the left wall (x = -0.4) and meets a dispersive flint
/// prism (IOR 1.5 at 550 nm, Cauchy B = 0.04 um^2, so 1.645, 1.565, 1.5, 1.462 and 1.434
/// at 380, 450, 550, 650 and 780 nm; equilateral, side 0.6, length 1, axis along z,
/// centred at (0, 0.7, 0), apex up). Each wavelength leaves at its own angle (24.6, 18.6
/// and 15.4 deg below the horizontal at 450, 550 and 650 nm) and lands on the white screen
/// that is the right wall (x = 1.5): a continuous spectrum 0.7 long, red highest (650 nm
/// at height 0.42, 550 nm at 0.33, 450 nm at 0.17), whose deepest violet (below about
/// 400 nm) passes under the screen onto the floor. With `frame.dispersion` three bands it
/// is three separated bands 0.04 tall at those three heights. The beam's photons start over a box around the slit (the light's
/// projection volume); the wall shades the room from the rest of the light. A dim room
/// light under the ceiling (y = 1.4; point, 1 W/sr at (0.8, 1.3, -0.6), behind the prism
/// so that its shadow falls away from the view) lights the floor, the walls and the
/// backdrop (the back wall, z = -0.9) that the glass shows, and casts the prism's faint
/// caustic of its own. Camera at (0.3, 1.05, 2) looking at (0.7, 0.55, -0.1), fov 50 deg.
pub fn prism() -> Scene {
    let (xw, xs, zb) = (PRISM_SLIT_X, PRISM_SCREEN_X, -0.9);
    let (ys, hs, ls) = (PRISM_SLIT_Y, PRISM_SLIT_HALF_HEIGHT, PRISM_SLIT_HALF_LENGTH);
    let top = 1.4;
    let (zf, zmid) = (0.9, 0.0);
    let below = ys - hs;
    let above = ys + hs;
    // the left wall around the slit, facing the room (+x)
    let wall = |name: &str, y0: f32, y1: f32, z0: f32, z1: f32| {
        rect(
            name,
            "grey",
            Vec3::new(xw, 0.5 * (y0 + y1), 0.5 * (z0 + z1)),
            Vec3::Y * (0.5 * (y1 - y0)),
            Vec3::Z * (0.5 * (z1 - z0)),
        )
    };
    Scene {
        name: "prism".into(),
        description: "Dispersive prism (Cauchy B 0.04) in a dark room: a beam through a slit lands on the screen as a continuous spectrum, red highest (three separated bands at 650, 550 and 450 nm with the three-band split)".into(),
        camera: camera(Vec3::new(0.3, 1.05, 2.0), Vec3::new(0.7, 0.55, -0.1), 50.0),
        materials: BTreeMap::from([
            ("white".into(), diffuse(0.8)),
            ("grey".into(), diffuse(0.5)),
            (
                "flint".into(),
                Material::Dielectric {
                    ior: 1.5,
                    cauchy_b: 0.04,
                    absorption: Vec3::ZERO,
                    ior_model: Default::default(),
                },
            ),
        ]),
        objects: vec![
            rect("floor", "grey", Vec3::new(0.5, 0.0, 0.2), Vec3::X * 1.5, -Vec3::Z * 1.4),
            obj(
                "prism",
                "flint",
                Shape::Prism {
                    center: Vec3::new(0.0, 0.7, 0.0),
                    side: 0.6,
                    length: 1.0,
                },
            ),
            rect(
                "screen",
                "white",
                Vec3::new(xs, 0.5 * top, zmid),
                Vec3::Z * zf,
                Vec3::Y * (0.5 * top),
            ),
            rect(
                "backdrop",
                "grey",
                Vec3::new(0.5 * (xw + xs), 0.5 * top, zb),
                Vec3::X * (0.5 * (xs - xw)),
                Vec3::Y * (0.5 * top),
            ),
            rect(
                "ceiling",
                "grey",
                Vec3::new(0.5 * (xw + xs), top, zmid),
                Vec3::X * (0.5 * (xs - xw)),
                Vec3::Z * zf,
            ),
            wall("wall below the slit", 0.0, below, -zf, zf),
            wall("wall above the slit", above, top, -zf, zf),
            wall("wall behind the slit", below, above, -zf, -ls),
            wall("wall before the slit", below, above, ls, zf),
        ],
        lights: vec![
            Light::Directional {
                direction: prism_beam_direction(),
                irradiance: Vec3::splat(4.0),
                projection_volume: Some(Aabb {
                    min: Vec3::new(xw - 0.01, below, -ls),
                    max: Vec3::new(-0.25, above, ls),
                }),
            },
            Light::Point {
                position: Vec3::new(0.8, 1.3, -0.6),
                intensity: Vec3::splat(1.0),
            },
        ],
    }
}

/// `spot-glass` (Wyman 2009's setting: a wide light and a small, finely tessellated
/// refractor): a spot light 30 W/sr at (0, 4, 0) shining down with a 50-degree outer
/// (40-degree inner) half-angle over an 8 x 8 white floor (albedo 0.8) at y = 0, and a
/// glass ball (IOR 1.5) of radius 0.4 at (0.9, 1.1, 0.3) tessellated into 50,176
/// triangles (224 segments), which covers under 3% of the spot's cone (its solid angle
/// `2 pi (1 - cos asin(0.4 / 3.06)) = 0.054 sr` of the cone's 2.24 sr); camera from
/// (0, 5.5, 5.5) towards (0.4, 0, 0).
pub fn spot_glass() -> Scene {
    Scene {
        name: "spot-glass".into(),
        description: "Wide spot light (50 deg) over an 8x8 white floor, small glass ball (r 0.4, 50k triangles) off axis".into(),
        camera: camera(Vec3::new(0.0, 5.5, 5.5), Vec3::new(0.4, 0.0, 0.0), 45.0),
        materials: BTreeMap::from([("white".into(), diffuse(0.8)), ("glass".into(), glass(1.5))]),
        objects: vec![
            obj("floor", "white", floor(4.0, 0.0)),
            obj("ball", "glass", Shape::Sphere { center: Vec3::new(0.9, 1.1, 0.3), radius: 0.4, segments: 224 }),
        ],
        lights: vec![Light::Spot {
            position: Vec3::new(0.0, 4.0, 0.0),
            direction: -Vec3::Y,
            intensity: Vec3::splat(30.0),
            inner_angle_deg: 40.0,
            outer_angle_deg: 50.0,
        }],
    }
}

/// `jelly`: an absorbing red jelly ball (IOR 1.35, Beer-Lambert absorption (0.2, 2.5, 3.5)
/// per metre, r 0.5, centre (0, 0.9, 0)) on the `sphere` plane, point light 10 W/sr at
/// (0.4, 3, 0.2); camera as in `sphere`.
pub fn jelly() -> Scene {
    Scene {
        name: "jelly".into(),
        description: "Absorbing coloured jelly ball: a tinted caustic".into(),
        camera: camera(Vec3::new(0.0, 4.0, 3.0), Vec3::ZERO, 45.0),
        materials: BTreeMap::from([
            ("white".into(), diffuse(0.8)),
            (
                "jelly".into(),
                Material::Dielectric {
                    ior: 1.35,
                    cauchy_b: 0.0,
                    absorption: Vec3::new(0.2, 2.5, 3.5),
                    ior_model: Default::default(),
                },
            ),
        ]),
        objects: vec![
            obj("plane", "white", floor(2.0, 0.0)),
            obj(
                "jelly",
                "jelly",
                Shape::Sphere {
                    center: Vec3::new(0.0, 0.9, 0.0),
                    radius: 0.5,
                    segments: 128,
                },
            ),
        ],
        lights: vec![Light::Point {
            position: Vec3::new(0.4, 3.0, 0.2),
            intensity: Vec3::splat(10.0),
        }],
    }
}

/// `plain`: diffuse objects only (a white plane, an orange box [-0.9,0,-0.4]..[-0.3,0.6,0.2]
/// and a blue ball r 0.4 at (0.6, 0.4, 0)), point light 10 W/sr at (0, 3, 1): no specular
/// surface, so no caustics at all.
pub fn plain() -> Scene {
    Scene {
        name: "plain".into(),
        description: "Diffuse objects only: no caustic casters".into(),
        camera: camera(Vec3::new(0.0, 4.0, 3.0), Vec3::ZERO, 45.0),
        materials: BTreeMap::from([
            ("white".into(), diffuse(0.8)),
            (
                "orange".into(),
                Material::Diffuse {
                    albedo: Vec3::new(0.8, 0.4, 0.1),
                },
            ),
            (
                "blue".into(),
                Material::Diffuse {
                    albedo: Vec3::new(0.1, 0.2, 0.8),
                },
            ),
        ]),
        objects: vec![
            obj("plane", "white", floor(2.0, 0.0)),
            obj(
                "box",
                "orange",
                Shape::Cuboid {
                    min: Vec3::new(-0.9, 0.0, -0.4),
                    max: Vec3::new(-0.3, 0.6, 0.2),
                },
            ),
            obj(
                "ball",
                "blue",
                Shape::Sphere {
                    center: Vec3::new(0.6, 0.4, 0.0),
                    radius: 0.4,
                    segments: 64,
                },
            ),
        ],
        lights: vec![Light::Point {
            position: Vec3::new(0.0, 3.0, 1.0),
            intensity: Vec3::splat(10.0),
        }],
    }
}

/// `rooms` (PhotonGi, Smal 2019's multi-room test scenes): two rooms 3 x 2.5 x 4 side by
/// side (x in [-3, 0] and [0, 3], z in [-2, 2], floor y = 0, ceiling y = 2.5), joined by a
/// doorway 1 wide and 2 high in the dividing wall at x = 0. Room A (x < 0) holds both
/// lights, of unequal power: a point light 12 W/sr at (-1.5, 2.2, 0) and a spot light
/// 3 W/sr at (-2.4, 2.4, 1.4) aimed straight down (outer cone 35 degrees), and a glass
/// ball (IOR 1.5, r 0.5 at (-1.2, 0.5, -0.9), 256 segments: 65k triangles) casting a
/// caustic. Room B (x > 0) has no light: it is lit only through the doorway, by light
/// that bounced at least once; its far wall is red, its front wall green, and a grey
/// ball (r 0.45 at (1.6, 0.45, -0.8)) stands in it. The camera stands in room B's corner
/// at (2.7, 1.5, 1.8) looking at (-0.8, 0.9, -0.6), through the doorway into room A.
/// The walls are single quads (two-sided).
pub fn rooms() -> Scene {
    let q = |c: Vec3, u: Vec3, v: Vec3| Shape::Quad { center: c, u, v };
    let colour = |r, g, b| Material::Diffuse {
        albedo: Vec3::new(r, g, b),
    };
    Scene {
        name: "rooms".into(),
        description: "Two rooms joined by a doorway: two lights of unequal power and a glass \
                      ball in one, the other lit only indirectly"
            .into(),
        camera: camera(Vec3::new(2.7, 1.5, 1.8), Vec3::new(-0.8, 0.9, -0.6), 60.0),
        materials: BTreeMap::from([
            ("white".into(), diffuse(0.75)),
            ("red".into(), colour(0.75, 0.15, 0.12)),
            ("green".into(), colour(0.15, 0.6, 0.2)),
            ("blue".into(), colour(0.2, 0.3, 0.7)),
            ("grey".into(), diffuse(0.5)),
            ("glass".into(), glass(1.5)),
        ]),
        objects: vec![
            obj(
                "floor",
                "white",
                q(
                    Vec3::new(0.0, 0.0, 0.0),
                    Vec3::new(3.0, 0.0, 0.0),
                    Vec3::new(0.0, 0.0, -2.0),
                ),
            ),
            obj(
                "ceiling",
                "white",
                q(
                    Vec3::new(0.0, 2.5, 0.0),
                    Vec3::new(3.0, 0.0, 0.0),
                    Vec3::new(0.0, 0.0, 2.0),
                ),
            ),
            obj(
                "room A back",
                "white",
                q(
                    Vec3::new(-1.5, 1.25, -2.0),
                    Vec3::new(1.5, 0.0, 0.0),
                    Vec3::new(0.0, 1.25, 0.0),
                ),
            ),
            obj(
                "room A front",
                "white",
                q(
                    Vec3::new(-1.5, 1.25, 2.0),
                    Vec3::new(1.5, 0.0, 0.0),
                    Vec3::new(0.0, -1.25, 0.0),
                ),
            ),
            obj(
                "room A side",
                "blue",
                q(
                    Vec3::new(-3.0, 1.25, 0.0),
                    Vec3::new(0.0, 1.25, 0.0),
                    Vec3::new(0.0, 0.0, 2.0),
                ),
            ),
            obj(
                "room B back",
                "red",
                q(
                    Vec3::new(1.5, 1.25, -2.0),
                    Vec3::new(1.5, 0.0, 0.0),
                    Vec3::new(0.0, 1.25, 0.0),
                ),
            ),
            obj(
                "room B front",
                "green",
                q(
                    Vec3::new(1.5, 1.25, 2.0),
                    Vec3::new(1.5, 0.0, 0.0),
                    Vec3::new(0.0, -1.25, 0.0),
                ),
            ),
            obj(
                "room B side",
                "white",
                q(
                    Vec3::new(3.0, 1.25, 0.0),
                    Vec3::new(0.0, 1.25, 0.0),
                    Vec3::new(0.0, 0.0, -2.0),
                ),
            ),
            // the dividing wall at x = 0: two panels beside the doorway and a lintel over it
            obj(
                "wall, back panel",
                "white",
                q(
                    Vec3::new(0.0, 1.25, -1.25),
                    Vec3::new(0.0, 1.25, 0.0),
                    Vec3::new(0.0, 0.0, 0.75),
                ),
            ),
            obj(
                "wall, front panel",
                "white",
                q(
                    Vec3::new(0.0, 1.25, 1.25),
                    Vec3::new(0.0, 1.25, 0.0),
                    Vec3::new(0.0, 0.0, 0.75),
                ),
            ),
            obj(
                "wall, lintel",
                "white",
                q(
                    Vec3::new(0.0, 2.25, 0.0),
                    Vec3::new(0.0, 0.25, 0.0),
                    Vec3::new(0.0, 0.0, 0.5),
                ),
            ),
            obj(
                "glass ball",
                "glass",
                Shape::Sphere {
                    center: Vec3::new(-1.2, 0.5, -0.9),
                    radius: 0.5,
                    segments: 256,
                },
            ),
            obj(
                "grey ball",
                "grey",
                Shape::Sphere {
                    center: Vec3::new(1.6, 0.45, -0.8),
                    radius: 0.45,
                    segments: 96,
                },
            ),
        ],
        lights: vec![
            Light::Point {
                position: Vec3::new(-1.5, 2.2, 0.0),
                intensity: Vec3::splat(12.0),
            },
            Light::Spot {
                position: Vec3::new(-2.4, 2.4, 1.4),
                direction: Vec3::new(0.0, -1.0, 0.0),
                intensity: Vec3::splat(3.0),
                inner_angle_deg: 25.0,
                outer_angle_deg: 35.0,
            },
        ],
    }
}

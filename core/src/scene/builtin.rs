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
pub fn sphere() -> Scene {
    Scene {
        name: "sphere".into(),
        description: "Glass ball (IOR 1.5, r 0.5, centre (0,1,0)) over a 4x4 white plane at y=0, point light 10 W/sr at (0,3,0)".into(),
        camera: camera(Vec3::new(0.0, 4.0, 3.0), Vec3::ZERO, 45.0),
        materials: BTreeMap::from([("white".into(), diffuse(0.8)), ("glass".into(), glass(1.5))]),
        objects: vec![
            obj("plane", "white", floor(2.0, 0.0)),
            obj("ball", "glass", Shape::Sphere { center: Vec3::Y, radius: 0.5, segments: 192 }),
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

/// `pool`: a 4 x 4 water surface (IOR 1.33) at y = 0 with three sine waves (amplitudes
/// 0.02-0.03, wavelengths 0.6-1.3) over a light blue-grey pool floor at y = -1, under a
/// directional light travelling along (0.15, -1, 0.1), irradiance 2. Camera at (0, 2.6, 3.2)
/// looking at (0, -0.8, 0), fov 45 deg. The water is a single surface: photons refract
/// into it and land on the floor.
pub fn pool() -> Scene {
    Scene {
        name: "pool".into(),
        description: "Wavy water surface (IOR 1.33) over a pool floor, sun from above".into(),
        camera: camera(Vec3::new(0.0, 2.6, 3.2), Vec3::new(0.0, -0.8, 0.0), 45.0),
        materials: BTreeMap::from([
            (
                "tiles".into(),
                Material::Diffuse {
                    albedo: Vec3::new(0.6, 0.75, 0.8),
                },
            ),
            ("water".into(), glass(1.33)),
        ]),
        objects: vec![
            obj("floor", "tiles", floor(2.5, -1.0)),
            obj(
                "water",
                "water",
                Shape::HeightField {
                    center: Vec3::ZERO,
                    size: Vec2::splat(4.0),
                    resolution: 160,
                    waves: vec![
                        Wave {
                            amplitude: 0.03,
                            wavelength: 1.3,
                            direction: Vec2::new(1.0, 0.3),
                            phase: 0.0,
                        },
                        Wave {
                            amplitude: 0.02,
                            wavelength: 0.8,
                            direction: Vec2::new(-0.4, 1.0),
                            phase: 1.0,
                        },
                        Wave {
                            amplitude: 0.02,
                            wavelength: 0.6,
                            direction: Vec2::new(0.7, -0.7),
                            phase: 2.0,
                        },
                    ],
                },
            ),
        ],
        lights: vec![Light::Directional {
            direction: Vec3::new(0.15, -1.0, 0.1),
            irradiance: Vec3::splat(2.0),
            projection_volume: None,
        }],
    }
}

/// `prism`: a dispersive glass prism (IOR 1.5 at 550 nm, Cauchy B = 0.04 um^2, side 0.6,
/// length 1, axis along z, centred at (0, 0.7, 0)) over a 4 x 4 white plane, lit by a
/// directional light travelling along (1, -0.3, 0) (irradiance 4): the refracted beam
/// lands on the plane as a spectrum. Camera at (0.6, 3.0, 2.8) looking at (0.6, 0, 0).
pub fn prism() -> Scene {
    Scene {
        name: "prism".into(),
        description: "Dispersive glass prism casting a spectrum".into(),
        camera: camera(Vec3::new(0.6, 3.0, 2.8), Vec3::new(0.6, 0.0, 0.0), 45.0),
        materials: BTreeMap::from([
            ("white".into(), diffuse(0.8)),
            (
                "flint".into(),
                Material::Dielectric {
                    ior: 1.5,
                    cauchy_b: 0.04,
                    absorption: Vec3::ZERO,
                },
            ),
        ]),
        objects: vec![
            obj("plane", "white", floor(2.0, 0.0)),
            obj(
                "prism",
                "flint",
                Shape::Prism {
                    center: Vec3::new(0.0, 0.7, 0.0),
                    side: 0.6,
                    length: 1.0,
                },
            ),
        ],
        lights: vec![Light::Directional {
            direction: Vec3::new(1.0, -0.3, 0.0),
            irradiance: Vec3::splat(4.0),
            projection_volume: None,
        }],
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

//! Physical and structural validation of a [`Scene`]: every problem is reported with the
//! path of the offending field, so the file loader can point at its line.

use super::{Light, Material, Scene, Shape};
use glam::{Vec2, Vec3};

/// One thing wrong with a scene: `path` names the field (`objects[2].shape.radius`),
/// `reason` says what is wrong with it.
#[derive(Clone, Debug, PartialEq)]
pub struct Problem {
    /// Path of the offending field, e.g. `objects[2].shape.radius`.
    pub path: String,
    /// What is wrong with it.
    pub reason: String,
}

struct Check {
    problems: Vec<Problem>,
}

impl Check {
    fn fail(&mut self, path: impl Into<String>, reason: impl Into<String>) {
        self.problems.push(Problem {
            path: path.into(),
            reason: reason.into(),
        });
    }
    fn finite(&mut self, path: &str, v: f32) -> bool {
        if !v.is_finite() {
            self.fail(path, format!("must be a finite number, got {v}"));
            return false;
        }
        true
    }
    fn finite3(&mut self, path: &str, v: Vec3) -> bool {
        if !v.is_finite() {
            self.fail(
                path,
                format!("must be finite, got [{}, {}, {}]", v.x, v.y, v.z),
            );
            return false;
        }
        true
    }
    fn positive(&mut self, path: &str, v: f32) {
        if self.finite(path, v) && v <= 0.0 {
            self.fail(path, format!("must be > 0, got {v}"));
        }
    }
    fn nonneg3(&mut self, path: &str, v: Vec3) {
        if self.finite3(path, v) && v.min_element() < 0.0 {
            self.fail(path, "must not be negative");
        }
    }
    fn unit_range3(&mut self, path: &str, v: Vec3) {
        if self.finite3(path, v) && (v.min_element() < 0.0 || v.max_element() > 1.0) {
            self.fail(
                path,
                "every channel must be in [0, 1] (energy conservation)",
            );
        }
    }
    fn direction(&mut self, path: &str, v: Vec3) {
        if self.finite3(path, v) && v.length_squared() < 1e-20 {
            self.fail(path, "zero-length direction");
        }
    }
}

pub(super) fn validate(s: &Scene) -> Result<(), Vec<Problem>> {
    let mut c = Check {
        problems: Vec::new(),
    };
    // camera
    let cam = &s.camera;
    c.finite3("camera.position", cam.position);
    c.finite3("camera.target", cam.target);
    c.direction("camera.up", cam.up);
    if (cam.target - cam.position).length_squared() < 1e-20 {
        c.fail("camera.target", "camera target equals its position");
    } else if cam.up.is_finite()
        && (cam.target - cam.position)
            .normalize()
            .cross(cam.up.normalize_or_zero())
            .length()
            < 1e-6
    {
        c.fail("camera.up", "up is parallel to the view direction");
    }
    if c.finite("camera.fov_y_deg", cam.fov_y_deg)
        && !(cam.fov_y_deg > 0.0 && cam.fov_y_deg < 179.0)
    {
        c.fail("camera.fov_y_deg", "must be in (0, 179) degrees");
    }
    for (name, v) in [("width", cam.width), ("height", cam.height)] {
        if v == 0 || v > 16384 {
            c.fail(format!("camera.{name}"), "must be in 1..=16384 pixels");
        }
    }
    // materials
    for (name, m) in &s.materials {
        let p = format!("materials.{name}");
        match m {
            Material::Diffuse { albedo } => c.unit_range3(&format!("{p}.albedo"), *albedo),
            Material::Mirror { reflectance } => {
                c.unit_range3(&format!("{p}.reflectance"), *reflectance)
            }
            Material::Dielectric {
                ior,
                cauchy_b,
                absorption,
            } => {
                if c.finite(&format!("{p}.ior"), *ior) && *ior <= 0.0 {
                    c.fail(
                        format!("{p}.ior"),
                        format!("index of refraction must be > 0, got {ior}"),
                    );
                }
                if c.finite(&format!("{p}.cauchy_b"), *cauchy_b) {
                    // n must stay positive over the visible channels
                    for wl in crate::math::optics::CHANNEL_WAVELENGTH_UM {
                        if crate::math::optics::cauchy_ior(*ior, *cauchy_b, wl) <= 0.0 {
                            c.fail(
                                format!("{p}.cauchy_b"),
                                format!("makes the index <= 0 at {wl} um"),
                            );
                            break;
                        }
                    }
                }
                c.nonneg3(&format!("{p}.absorption"), *absorption);
            }
        }
    }
    // objects
    if s.objects.is_empty() {
        c.fail("objects", "the scene has no objects");
    }
    for (i, o) in s.objects.iter().enumerate() {
        let p = format!("objects[{i}]");
        if !s.materials.contains_key(&o.material) {
            c.fail(
                format!("{p}.material"),
                format!("unknown material '{}'", o.material),
            );
        }
        let sp = format!("{p}.shape");
        match &o.shape {
            Shape::Mesh {
                positions,
                normals,
                uvs,
                indices,
            } => {
                if positions.is_empty() || indices.is_empty() {
                    c.fail(&sp, "empty mesh (no positions or no triangles)");
                }
                for (k, v) in positions.iter().enumerate() {
                    c.finite3(&format!("{sp}.positions[{k}]"), *v);
                }
                if !normals.is_empty() && normals.len() != positions.len() {
                    c.fail(
                        format!("{sp}.normals"),
                        format!(
                            "{} normals for {} positions",
                            normals.len(),
                            positions.len()
                        ),
                    );
                }
                for (k, n) in normals.iter().enumerate() {
                    c.direction(&format!("{sp}.normals[{k}]"), *n);
                }
                if !uvs.is_empty() && uvs.len() != positions.len() {
                    c.fail(
                        format!("{sp}.uvs"),
                        format!("{} uvs for {} positions", uvs.len(), positions.len()),
                    );
                }
                for (k, t) in indices.iter().enumerate() {
                    if t.iter().any(|&i| i as usize >= positions.len()) {
                        c.fail(
                            format!("{sp}.indices[{k}]"),
                            format!(
                                "index out of range (mesh has {} positions)",
                                positions.len()
                            ),
                        );
                    }
                }
            }
            Shape::Sphere {
                center,
                radius,
                segments,
            } => {
                c.finite3(&format!("{sp}.center"), *center);
                c.positive(&format!("{sp}.radius"), *radius);
                if !(3..=4096).contains(segments) {
                    c.fail(format!("{sp}.segments"), "must be in 3..=4096");
                }
            }
            Shape::Quad { center, u, v } => {
                c.finite3(&format!("{sp}.center"), *center);
                if c.finite3(&format!("{sp}.u"), *u)
                    && c.finite3(&format!("{sp}.v"), *v)
                    // unit vectors first: at 1e-10 units |u x v|^2 underflows to 0
                    && u.normalize_or_zero()
                        .cross(v.normalize_or_zero())
                        .length_squared()
                        == 0.0
                {
                    c.fail(&sp, "u and v span no area");
                }
            }
            Shape::Cuboid { min, max } => {
                if c.finite3(&format!("{sp}.min"), *min)
                    && c.finite3(&format!("{sp}.max"), *max)
                    && !(max.cmpgt(*min).all())
                {
                    c.fail(format!("{sp}.max"), "max must exceed min on every axis");
                }
            }
            Shape::Ring {
                center,
                radius,
                thickness,
                height,
                segments,
            } => {
                c.finite3(&format!("{sp}.center"), *center);
                c.positive(&format!("{sp}.radius"), *radius);
                c.positive(&format!("{sp}.thickness"), *thickness);
                c.positive(&format!("{sp}.height"), *height);
                if !(3..=8192).contains(segments) {
                    c.fail(format!("{sp}.segments"), "must be in 3..=8192");
                }
            }
            Shape::Prism {
                center,
                side,
                length,
            } => {
                c.finite3(&format!("{sp}.center"), *center);
                c.positive(&format!("{sp}.side"), *side);
                c.positive(&format!("{sp}.length"), *length);
            }
            Shape::HeightField {
                center,
                size,
                resolution,
                waves,
            } => {
                c.finite3(&format!("{sp}.center"), *center);
                if !(size.is_finite() && size.cmpgt(Vec2::ZERO).all()) {
                    c.fail(format!("{sp}.size"), "must be positive and finite");
                }
                if !(1..=4096).contains(resolution) {
                    c.fail(format!("{sp}.resolution"), "must be in 1..=4096");
                }
                for (k, w) in waves.iter().enumerate() {
                    c.finite(&format!("{sp}.waves[{k}].amplitude"), w.amplitude);
                    c.positive(&format!("{sp}.waves[{k}].wavelength"), w.wavelength);
                    c.finite(&format!("{sp}.waves[{k}].phase"), w.phase);
                    if !(w.direction.is_finite() && w.direction.length_squared() > 0.0) {
                        c.fail(
                            format!("{sp}.waves[{k}].direction"),
                            "zero-length or non-finite direction",
                        );
                    }
                }
            }
        }
    }
    // lights
    if s.lights.is_empty() {
        c.fail("lights", "the scene has no lights");
    }
    for (i, l) in s.lights.iter().enumerate() {
        let p = format!("lights[{i}]");
        match l {
            Light::Point {
                position,
                intensity,
            } => {
                c.finite3(&format!("{p}.position"), *position);
                c.nonneg3(&format!("{p}.intensity"), *intensity);
            }
            Light::Spot {
                position,
                direction,
                intensity,
                inner_angle_deg,
                outer_angle_deg,
            } => {
                c.finite3(&format!("{p}.position"), *position);
                c.direction(&format!("{p}.direction"), *direction);
                c.nonneg3(&format!("{p}.intensity"), *intensity);
                if c.finite(&format!("{p}.outer_angle_deg"), *outer_angle_deg)
                    && !(*outer_angle_deg > 0.0 && *outer_angle_deg <= 180.0)
                {
                    c.fail(
                        format!("{p}.outer_angle_deg"),
                        "must be in (0, 180] degrees",
                    );
                }
                if c.finite(&format!("{p}.inner_angle_deg"), *inner_angle_deg)
                    && !(*inner_angle_deg >= 0.0 && inner_angle_deg <= outer_angle_deg)
                {
                    c.fail(
                        format!("{p}.inner_angle_deg"),
                        "must be in [0, outer_angle_deg]",
                    );
                }
            }
            Light::Directional {
                direction,
                irradiance,
                projection_volume,
            } => {
                c.direction(&format!("{p}.direction"), *direction);
                c.nonneg3(&format!("{p}.irradiance"), *irradiance);
                if let Some(b) = projection_volume {
                    let pv = format!("{p}.projection_volume");
                    if c.finite3(&format!("{pv}.min"), b.min)
                        && c.finite3(&format!("{pv}.max"), b.max)
                        && !b.max.cmpge(b.min).all()
                    {
                        c.fail(format!("{pv}.max"), "max must not be below min");
                    }
                }
            }
        }
    }
    if c.problems.is_empty() {
        Ok(())
    } else {
        Err(c.problems)
    }
}

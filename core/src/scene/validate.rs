//! Physical and structural validation of a [`Scene`]: every problem is reported with the
//! path of the offending field, so the file loader can point at its line.

use super::limits::{
    MAX_COORDINATE, MAX_INTENSITY, MAX_IOR, MAX_LENGTH, MAX_LIGHTS, MIN_EXTENT_PER_POSITION,
    MIN_INTENSITY, MIN_IOR, MIN_LENGTH,
};
use super::{IorModel, Light, Material, Scene, Shape, Transform};
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

/// The tail of a one-line error that names the first of several problems: `""` for none
/// more, else ` (and 1 more problem: objects[2].shape)` or ` (and 5 more problems:
/// a, b, c, d, ...)`, naming at most four of the rest by path.
pub fn more_problems<S: std::fmt::Display>(rest: &[S]) -> String {
    const NAMED: usize = 4;
    if rest.is_empty() {
        return String::new();
    }
    let mut names: Vec<String> = rest.iter().take(NAMED).map(|p| p.to_string()).collect();
    if rest.len() > NAMED {
        names.push("...".into());
    }
    let noun = if rest.len() == 1 {
        "problem"
    } else {
        "problems"
    };
    format!(" (and {} more {noun}: {})", rest.len(), names.join(", "))
}

struct Check {
    problems: Vec<Problem>,
    /// The transform of the object whose shape is checked (its world placement), if any.
    transform: Option<Transform>,
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
        if self.coord3(path, v) && v.length_squared() < 1e-20 {
            self.fail(path, "zero-length direction");
        }
    }
    /// A point (or a vector of point size): finite, every coordinate within
    /// `MAX_COORDINATE` (2^40, see `limits`); [`is_coord3`] without the report.
    fn coord3(&mut self, path: &str, v: Vec3) -> bool {
        if !self.finite3(path, v) {
            return false;
        }
        if v.abs().max_element() > MAX_COORDINATE {
            self.fail(
                path,
                format!(
                    "coordinate {:e} is beyond the bound +-{MAX_COORDINATE:e} (2^40) that keeps \
                     f32 products of three lengths finite",
                    v.abs().max_element()
                ),
            );
            return false;
        }
        true
    }
    /// A length (radius, side, ...): finite, in [MIN_LENGTH, MAX_LENGTH] (2^-40, 2^41).
    fn length(&mut self, path: &str, v: f32) -> bool {
        if !self.finite(path, v) {
            return false;
        }
        if !(MIN_LENGTH..=MAX_LENGTH).contains(&v) {
            self.fail(
                path,
                format!(
                    "must be in [{MIN_LENGTH:e}, {MAX_LENGTH:e}] (2^-40 to 2^41 scene units), \
                     got {v:e}"
                ),
            );
            return false;
        }
        true
    }
    /// A shape around `center` reaching `reach` from it (both valid) with smallest feature
    /// `extent`: it must stay inside the coordinate bound and span at least 2^-16 of its
    /// centre's largest coordinate (128 f32 ulps there), or its vertices collapse.
    /// Given in object space, the shape is judged where its object's transform puts it:
    /// its centre placed, its reach (a largest coordinate, which a rotation can lengthen by
    /// up to sqrt 3) and its feature (which may lie across the smallest scale's axis or
    /// not: the largest scale is taken, so a valid shape is never refused) scaled.
    fn placed(&mut self, path: &str, center: Vec3, reach: f32, extent: f32) {
        let (center, reach, extent) = match &self.transform {
            Some(t) => {
                let scale = t.scale.abs().max_element();
                let turn = if t.rotation == glam::Quat::IDENTITY {
                    1.0
                } else {
                    3f32.sqrt()
                };
                (
                    t.world_from_object().transform_point3(center),
                    reach * scale * turn,
                    extent * scale,
                )
            }
            None => (center, reach, extent),
        };
        let c = center.abs().max_element();
        if c + reach > MAX_COORDINATE {
            self.fail(
                path,
                format!(
                    "reaches {:e} from the origin, beyond the coordinate bound {MAX_COORDINATE:e}",
                    c + reach
                ),
            );
        } else if extent < c * MIN_EXTENT_PER_POSITION {
            self.fail(
                path,
                format!(
                    "is {extent:e} across at {c:e} from the origin: below f32 resolution there \
                     (at least 2^-16 of the distance, {:e}, is needed or its vertices collapse)",
                    c * MIN_EXTENT_PER_POSITION
                ),
            );
        }
    }
    /// A name without control characters (a line break or a terminal escape in a name
    /// would reach whoever prints it).
    fn printable(&mut self, path: &str, name: &str) {
        if let Some(ch) = name.chars().find(|ch| ch.is_control()) {
            self.fail(
                path,
                format!(
                    "'{}' holds the control character {:?}; names are printed, so they \
                     hold printable characters only",
                    name.escape_debug(),
                    ch
                ),
            );
        }
    }
    /// A non-negative per-channel quantity at most `bound`.
    fn bounded3(&mut self, path: &str, v: Vec3, bound: f32, what: &str) {
        self.nonneg3(path, v);
        if v.is_finite() && v.max_element() > bound {
            self.fail(
                path,
                format!("{what} {:e} exceeds the bound {bound:e}", v.max_element()),
            );
        }
    }
}

pub(super) fn validate(s: &Scene) -> Result<(), Vec<Problem>> {
    validate_parts(s, true)
}

/// [`validate`], with the meshes' own checks (every vertex) left out when `shapes` is
/// false: what an update that changes no shape needs (a technique's scene was validated
/// whole when it was made). The other shapes' checks, a few numbers each, still run: a
/// moved shape is judged where its new transform puts it, as a new scene would be.
pub(super) fn validate_parts(s: &Scene, shapes: bool) -> Result<(), Vec<Problem>> {
    let mut c = Check {
        problems: Vec::new(),
        transform: None,
    };
    // names are printed on terminals and in messages
    c.printable("name", &s.name);
    for (i, o) in s.objects.iter().enumerate() {
        c.printable(&format!("objects[{i}].name"), &o.name);
    }
    for name in s.materials.keys() {
        c.printable(&format!("materials['{}']", name.escape_debug()), name);
    }
    // camera
    let cam = &s.camera;
    c.coord3("camera.position", cam.position);
    c.coord3("camera.target", cam.target);
    c.direction("camera.up", cam.up);
    if (cam.target - cam.position).length_squared() < 1e-20 {
        c.fail("camera.target", "camera target equals its position");
    } else if cam.up.is_finite()
        && cam.target.is_finite()
        && cam.position.is_finite()
        && unit(cam.target - cam.position).cross(unit(cam.up)).length() < 1e-6
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
                ior_model,
            } => {
                if c.finite(&format!("{p}.ior"), *ior) && !(MIN_IOR..=MAX_IOR).contains(ior) {
                    c.fail(
                        format!("{p}.ior"),
                        format!(
                            "index of refraction must be in [{MIN_IOR:e}, {MAX_IOR:e}] \
                             (2^-20 to 2^20, so eta^2 stays finite), got {ior:e}"
                        ),
                    );
                }
                // n must stay in range over the sampled spectrum (n is monotonic in the
                // wavelength under both models, so its ends bound it)
                let ends = [
                    crate::math::spectrum::SPECTRUM_MIN_UM,
                    crate::math::spectrum::SPECTRUM_MAX_UM,
                ];
                match ior_model {
                    IorModel::Cauchy => {
                        if c.finite(&format!("{p}.cauchy_b"), *cauchy_b) && ior.is_finite() {
                            for wl in ends {
                                let n = crate::math::optics::cauchy_ior(*ior, *cauchy_b, wl);
                                if !(MIN_IOR..=MAX_IOR).contains(&n) {
                                    c.fail(
                                        format!("{p}.cauchy_b"),
                                        format!(
                                            "makes the index {n:e} at {wl} um, outside \
                                             [{MIN_IOR:e}, {MAX_IOR:e}]"
                                        ),
                                    );
                                    break;
                                }
                            }
                        }
                    }
                    IorModel::Abbe { abbe_number } => {
                        let at = format!("{p}.ior_model.abbe_number");
                        if *cauchy_b != 0.0 {
                            c.fail(
                                format!("{p}.cauchy_b"),
                                "must be 0 under the Abbe model (the Abbe number sets the \
                                 dispersion)",
                            );
                        }
                        if ior.is_finite() && *ior < 1.0 {
                            c.fail(
                                format!("{p}.ior"),
                                format!(
                                    "the Abbe model needs n_d >= 1 (KHR_materials_dispersion), \
                                     got {ior:e}"
                                ),
                            );
                        }
                        if c.finite(&at, *abbe_number) {
                            if *abbe_number <= 0.0 {
                                c.fail(
                                    at,
                                    format!("must be > 0 (glTF dispersion 20 / V_d), got {abbe_number:e}"),
                                );
                            } else if ior.is_finite() {
                                for wl in ends {
                                    let n = crate::math::optics::abbe_ior(*ior, *abbe_number, wl);
                                    if !(MIN_IOR..=MAX_IOR).contains(&n) {
                                        c.fail(
                                            at,
                                            format!(
                                                "makes the index {n:e} at {wl} um, outside \
                                                 [{MIN_IOR:e}, {MAX_IOR:e}]"
                                            ),
                                        );
                                        break;
                                    }
                                }
                            }
                        }
                    }
                }
                c.bounded3(
                    &format!("{p}.absorption"),
                    *absorption,
                    MAX_INTENSITY,
                    "absorption",
                );
            }
        }
    }
    // objects
    if s.objects.is_empty() {
        c.fail("objects", "the scene has no objects");
    }
    for (i, o) in s.objects.iter().enumerate() {
        let p = format!("objects[{i}]");
        c.transform = None;
        if let Some(reason) = o.transform.as_ref().and_then(|t| t.problem()) {
            c.fail(format!("{p}.transform"), reason);
        } else if let Some(t) = &o.transform {
            if c.coord3(&format!("{p}.transform.translation"), t.translation) {
                c.transform = Some(*t);
            }
        }
        if !s.materials.contains_key(&o.material) {
            c.fail(
                format!("{p}.material"),
                format!("unknown material '{}'", o.material),
            );
        }
        if !shapes && matches!(o.shape, Shape::Mesh { .. } | Shape::ObjFile { .. }) {
            continue;
        }
        let sp = format!("{p}.shape");
        match &o.shape {
            Shape::ObjFile { path } => c.fail(
                format!("{sp}.path"),
                format!(
                    "OBJ file '{path}' not loaded (load the scene with caustica's scene \
                     loader, built with the `obj` feature)"
                ),
            ),
            Shape::Mesh {
                positions,
                normals,
                uvs,
                indices,
            } => {
                if positions.is_empty() || indices.is_empty() {
                    c.fail(&sp, "empty mesh (no positions or no triangles)");
                }
                // (paths are formatted only for a bad value: a mesh of a million vertices
                // is validated on every update of a technique's scene)
                for (k, v) in positions.iter().enumerate() {
                    if !is_coord3(*v) {
                        c.coord3(&format!("{sp}.positions[{k}]"), *v);
                    }
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
                    if !(is_coord3(*n) && n.length_squared() >= 1e-20) {
                        c.direction(&format!("{sp}.normals[{k}]"), *n);
                    }
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
                if c.coord3(&format!("{sp}.center"), *center)
                    & c.length(&format!("{sp}.radius"), *radius)
                {
                    c.placed(&sp, *center, *radius, *radius);
                }
                if !(3..=4096).contains(segments) {
                    c.fail(format!("{sp}.segments"), "must be in 3..=4096");
                }
            }
            Shape::Quad { center, u, v } => {
                let placed = c.coord3(&format!("{sp}.center"), *center);
                let (u_ok, v_ok) = (
                    c.coord3(&format!("{sp}.u"), *u),
                    c.coord3(&format!("{sp}.v"), *v),
                );
                if placed && u_ok && v_ok {
                    let (ua, va) = (u.abs().max_element(), v.abs().max_element());
                    c.placed(&sp, *center, ua + va, ua.min(va));
                }
                if u_ok
                    && v_ok
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
                if c.coord3(&format!("{sp}.min"), *min) & c.coord3(&format!("{sp}.max"), *max) {
                    if !(max.cmpgt(*min).all()) {
                        c.fail(format!("{sp}.max"), "max must exceed min on every axis");
                    } else {
                        let center = (*min + *max) * 0.5;
                        // (its corners are checked coordinates where it is not moved)
                        let half = match c.transform {
                            Some(_) => ((*max - *min) * 0.5).max_element(),
                            None => 0.0,
                        };
                        c.placed(&sp, center, half, (*max - *min).min_element());
                    }
                }
            }
            Shape::Ring {
                center,
                radius,
                thickness,
                height,
                segments,
            } => {
                let ok = c.coord3(&format!("{sp}.center"), *center)
                    & c.length(&format!("{sp}.radius"), *radius)
                    & c.length(&format!("{sp}.thickness"), *thickness)
                    & c.length(&format!("{sp}.height"), *height);
                if ok {
                    c.placed(
                        &sp,
                        *center,
                        radius + thickness + height,
                        radius.min(*thickness).min(*height),
                    );
                }
                if !(3..=8192).contains(segments) {
                    c.fail(format!("{sp}.segments"), "must be in 3..=8192");
                }
            }
            Shape::Prism {
                center,
                side,
                length,
            } => {
                let ok = c.coord3(&format!("{sp}.center"), *center)
                    & c.length(&format!("{sp}.side"), *side)
                    & c.length(&format!("{sp}.length"), *length);
                if ok {
                    c.placed(&sp, *center, side + length, side.min(*length));
                }
            }
            Shape::HeightField {
                center,
                size,
                resolution,
                waves,
            } => {
                let mut ok = c.coord3(&format!("{sp}.center"), *center);
                if !(size.is_finite() && size.cmpgt(Vec2::ZERO).all()) {
                    c.fail(format!("{sp}.size"), "must be positive and finite");
                    ok = false;
                } else {
                    ok &= c.length(&format!("{sp}.size"), size.max_element())
                        & c.length(&format!("{sp}.size"), size.min_element());
                }
                let amplitude: f32 = waves.iter().map(|w| w.amplitude.abs()).sum();
                if ok && amplitude.is_finite() {
                    c.placed(
                        &sp,
                        *center,
                        size.max_element() + amplitude,
                        size.min_element(),
                    );
                }
                if !(1..=4096).contains(resolution) {
                    c.fail(format!("{sp}.resolution"), "must be in 1..=4096");
                }
                for (k, w) in waves.iter().enumerate() {
                    if c.finite(&format!("{sp}.waves[{k}].amplitude"), w.amplitude)
                        && w.amplitude.abs() > MAX_LENGTH
                    {
                        c.fail(
                            format!("{sp}.waves[{k}].amplitude"),
                            format!("must be within +-{MAX_LENGTH:e} (2^41)"),
                        );
                    }
                    c.length(&format!("{sp}.waves[{k}].wavelength"), w.wavelength);
                    c.finite(&format!("{sp}.waves[{k}].phase"), w.phase);
                    let d = w.direction;
                    if !(d.is_finite()
                        && d.abs().max_element() <= MAX_COORDINATE
                        && d.length_squared() > 1e-20)
                    {
                        c.fail(
                            format!("{sp}.waves[{k}].direction"),
                            "zero-length, non-finite or out-of-bound direction",
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
    if s.lights.len() > MAX_LIGHTS {
        c.fail(
            "lights",
            format!(
                "{} lights; at most {MAX_LIGHTS} (each costs a photon pass and a shadow ray \
                 per pixel)",
                s.lights.len()
            ),
        );
    }
    /// A light's intensity or irradiance `v` in `[0, MAX_INTENSITY]`, and, unless zero,
    /// at least `MIN_INTENSITY` in its brightest channel (the flux quantum stays normal).
    fn light_power(c: &mut Check, path: &str, v: Vec3, what: &str) {
        c.bounded3(path, v, MAX_INTENSITY, what);
        let m = v.max_element();
        if v.is_finite() && v.min_element() >= 0.0 && m > 0.0 && m < MIN_INTENSITY {
            c.fail(
                path,
                format!(
                    "{what} {m:e} is below the bound {MIN_INTENSITY:e} (2^-60) that keeps the \
                     photons' fixed-point flux quantum a normal f32; use 0 for a light that is off"
                ),
            );
        }
    }
    for (i, l) in s.lights.iter().enumerate() {
        let p = format!("lights[{i}]");
        match l {
            Light::Point {
                position,
                intensity,
            } => {
                c.coord3(&format!("{p}.position"), *position);
                light_power(&mut c, &format!("{p}.intensity"), *intensity, "intensity");
            }
            Light::Spot {
                position,
                direction,
                intensity,
                inner_angle_deg,
                outer_angle_deg,
            } => {
                c.coord3(&format!("{p}.position"), *position);
                c.direction(&format!("{p}.direction"), *direction);
                light_power(&mut c, &format!("{p}.intensity"), *intensity, "intensity");
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
                light_power(
                    &mut c,
                    &format!("{p}.irradiance"),
                    *irradiance,
                    "irradiance",
                );
                if let Some(b) = projection_volume {
                    let pv = format!("{p}.projection_volume");
                    if c.coord3(&format!("{pv}.min"), b.min) & c.coord3(&format!("{pv}.max"), b.max)
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

/// `v` scaled to unit length without overflow (largest component first).
fn unit(v: Vec3) -> Vec3 {
    let m = v.abs().max_element();
    if m > 0.0 {
        (v / m).normalize_or_zero()
    } else {
        Vec3::ZERO
    }
}

/// Whether `v` passes [`Check::coord3`]: finite, every coordinate within
/// `MAX_COORDINATE`.
fn is_coord3(v: Vec3) -> bool {
    v.is_finite() && v.abs().max_element() <= MAX_COORDINATE
}

#[cfg(test)]
mod tests {
    use super::more_problems;

    #[test]
    fn further_problems_are_named_by_path() {
        assert_eq!(more_problems::<&str>(&[]), "");
        assert_eq!(
            more_problems(&["objects[2].shape"]),
            " (and 1 more problem: objects[2].shape)"
        );
        assert_eq!(
            more_problems(&["a", "b", "c", "d", "e"]),
            " (and 5 more problems: a, b, c, d, ...)"
        );
    }
}

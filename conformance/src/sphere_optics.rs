//! The `sphere` scene's exact optics in f64, the anchor for every technique
//! (`tests/sphere_closed_form.rs`) and the traced reference of CausticMap's view through
//! the ball (`tests/caustic_map_frames.rs`): a point light of I = 10 W/sr per channel at
//! (0, 3, 0), a glass ball (n = 1.5, R = 0.5) centred at (0, 1, 0), a 4 x 4 diffuse plane
//! at y = 0.
//!
//! Derivation. The scene is rotationally symmetric about the y axis, so every ray from
//! the light stays in its meridional plane: a ray leaving at angle theta from -y meets
//! the ball when sin(theta) <= R / d (d = 2), carries flux I dOmega with
//! dOmega = 2 pi d(cos theta), and splits at each interface into a reflected part
//! (unpolarised Fresnel, the mean of the s and p reflectances) and a refracted part (Snell).
//! Inside a sphere every internal incidence angle equals the entry refraction angle, so
//! there is no total internal reflection and the internal chain is a geometric series;
//! it is followed until the weight is below 1e-15 (at most 10^5 orders). Each part leaving the ball downwards
//! lands on y = 0 at distance rho from the axis; on the square plane [-2, 2]^2 a ring of
//! radius rho keeps the fraction of its azimuths inside the square (1 for rho <= 2;
//! (asin(2/rho) - acos(2/rho)) / (pi/2) up to 2 sqrt 2). The integral over cos(theta) is
//! a midpoint sum of 2^21 rays (the integrand has jumps where rho crosses a radius, so the
//! error is O(1/N): below 1e-6 relative).
//!
//! Numbers (per channel): total caustic flux on the plane ~1.749 W (all internal orders),
//! 1.665 W straight through (two refractions), 0.079 W reflected off the outside; 0.737 W
//! within rho < 0.02 and 1.097 W within rho < 0.1 of the axis.
//!
//! The caustic irradiance on the plane, `E(rho)` (W/m^2 per channel, [`IrradianceProfile`]),
//! is the same integral binned by landing radius: the flux landing in the ring
//! `[rho_k, rho_k+1)` over the ring's area. A camera ray's caustic radiance
//! ([`CameraReference`]) follows the ray's specular tree through the exact sphere (both
//! Fresnel branches, no absorption: the scene's glass is clear) to the plane, where a
//! diffuse end adds `weight * albedo / pi * E(rho)`.

use std::f64::consts::PI;

/// Index of the glass.
pub const N_GLASS: f64 = 1.5;
/// Radius of the ball.
pub const RADIUS: f64 = 0.5;
/// Height of the ball's centre.
pub const CENTRE_Y: f64 = 1.0;
/// Height of the point light.
pub const LIGHT_Y: f64 = 3.0;
/// Intensity of the point light (W/sr per channel).
pub const INTENSITY: f64 = 10.0;
/// Half the side of the square plane.
pub const PLANE_HALF: f64 = 2.0;

/// Which reflectance the interfaces have.
#[derive(Clone, Copy, PartialEq, Debug)]
pub enum Fresnel {
    /// The exact unpolarised reflectance (caustica's default, the published figures).
    Exact,
    /// Schlick's approximation as Vanderstichelen 2021 uses it (CausticMap's `fresnel: schlick`).
    Schlick,
}

/// Reflectance, light going from index `n1` into `n2` at incidence cosine `cos_i`, 1
/// beyond the critical angle. Exact: the mean of R_s and R_p. Schlick: `R0 + (1 - R0)
/// (1 - cos)^5` with `R0 = ((n1 - n2) / (n1 + n2))^2` and the cosine on the side of the
/// lower index (the transmitted one when `n1 > n2`).
pub fn fresnel(model: Fresnel, cos_i: f64, n1: f64, n2: f64) -> f64 {
    let sin_t = n1 / n2 * (1.0 - cos_i * cos_i).max(0.0).sqrt();
    if sin_t >= 1.0 {
        return 1.0;
    }
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    if model == Fresnel::Schlick {
        let r0 = ((n1 - n2) / (n1 + n2)).powi(2);
        let c = if n1 > n2 { cos_t } else { cos_i };
        return r0 + (1.0 - r0) * (1.0 - c).powi(5);
    }
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n1 * cos_t - n2 * cos_i) / (n1 * cos_t + n2 * cos_i);
    0.5 * (rs * rs + rp * rp)
}

/// Snell: the refracted unit direction of unit `d` through unit normal `n` (facing
/// against `d`), `eta = n1 / n2`.
/// In the plane of the ray (N = 2) or in space (N = 3); the caller makes sure that there
/// is no total internal reflection.
pub fn refract<const N: usize>(d: [f64; N], n: [f64; N], eta: f64) -> [f64; N] {
    let cos_i = -dot(d, n);
    let k = 1.0 - eta * eta * (1.0 - cos_i * cos_i);
    let c = eta * cos_i - k.sqrt();
    std::array::from_fn(|i| eta * d[i] + c * n[i])
}

/// Mirror reflection of `d` about unit `n`.
pub fn reflect<const N: usize>(d: [f64; N], n: [f64; N]) -> [f64; N] {
    let dn = dot(d, n);
    std::array::from_fn(|i| d[i] - 2.0 * dn * n[i])
}

fn dot<const N: usize>(a: [f64; N], b: [f64; N]) -> f64 {
    (0..N).map(|i| a[i] * b[i]).sum()
}

/// How a path reached the plane.
#[derive(Clone, Copy, PartialEq)]
pub enum Path {
    /// Off the outside of the ball.
    ReflectedOutside,
    /// In and out, two refractions.
    StraightThrough,
    /// In, one or more internal reflections, out.
    InternalReflections,
}

/// Every part of the ray leaving the light downwards at `sin_theta` that lands on y = 0:
/// (distance from the axis, fraction of the ray's flux, path).
pub fn landings(model: Fresnel, sin_theta: f64) -> Vec<(f64, f64, Path)> {
    let cos_theta = (1.0 - sin_theta * sin_theta).sqrt();
    let d = [sin_theta, -cos_theta];
    let o = [0.0, LIGHT_Y];
    // first hit: |o + t d - c|^2 = R^2
    let oc = [o[0], o[1] - CENTRE_Y];
    let b = oc[0] * d[0] + oc[1] * d[1];
    let disc = b * b - (oc[0] * oc[0] + oc[1] * oc[1] - RADIUS * RADIUS);
    if disc < 0.0 {
        return vec![];
    }
    let t = -b - disc.sqrt();
    let mut p = [o[0] + t * d[0], o[1] + t * d[1]];
    let mut n = [p[0] / RADIUS, (p[1] - CENTRE_Y) / RADIUS];
    let mut out = Vec::new();
    let land = |p: [f64; 2], d: [f64; 2]| -> Option<f64> {
        (d[1] < 0.0).then(|| (p[0] + (0.0 - p[1]) / d[1] * d[0]).abs())
    };
    let cos_i = -(d[0] * n[0] + d[1] * n[1]);
    let r0 = fresnel(model, cos_i, 1.0, N_GLASS);
    if let Some(rho) = land(p, reflect(d, n)) {
        out.push((rho, r0, Path::ReflectedOutside));
    }
    let mut w = 1.0 - r0;
    let mut dir = refract(d, n, 1.0 / N_GLASS);
    let mut k = 0;
    // Near the silhouette the internal reflectance tends to 1 and the chain to an
    // infinite one; 10^5 orders (or a reflectance rounded to 1) end it: what is left
    // there is a measure-zero set of rays.
    while w > 1e-15 && k < 100_000 {
        // next hit from inside: the chord through p along dir
        let pc = [p[0], p[1] - CENTRE_Y];
        let t = -2.0 * (pc[0] * dir[0] + pc[1] * dir[1]);
        p = [p[0] + t * dir[0], p[1] + t * dir[1]];
        n = [p[0] / RADIUS, (p[1] - CENTRE_Y) / RADIUS];
        let cos_i = dir[0] * n[0] + dir[1] * n[1];
        let r = fresnel(model, cos_i, N_GLASS, 1.0);
        let exit = refract(dir, [-n[0], -n[1]], N_GLASS);
        if let Some(rho) = land(p, exit) {
            let kind = if k == 0 {
                Path::StraightThrough
            } else {
                Path::InternalReflections
            };
            out.push((rho, w * (1.0 - r), kind));
        }
        if r >= 1.0 {
            break;
        }
        w *= r;
        dir = reflect(dir, [-n[0], -n[1]]);
        k += 1;
    }
    out
}

/// Fraction of a ring of radius `rho` (centred on the axis) inside the square plane.
pub fn on_square(rho: f64) -> f64 {
    if rho <= PLANE_HALF {
        1.0
    } else if rho < PLANE_HALF * 2f64.sqrt() {
        ((PLANE_HALF / rho).asin() - (PLANE_HALF / rho).acos()) / (PI / 2.0)
    } else {
        0.0
    }
}

/// The anchor numbers (W per channel).
pub struct Anchor {
    /// Flux on the plane over every path.
    pub total: f64,
    /// Flux on the plane after two refractions.
    pub straight: f64,
    /// Flux on the plane reflected off the outside of the ball.
    pub reflected: f64,
    /// Flux within rho < r, for each radius of `RADII`.
    pub within: Vec<f64>,
}

/// The radii of [`Anchor::within`].
pub const RADII: [f64; 2] = [0.02, 0.1];

/// The anchor numbers by a midpoint sum of `samples` rays over the cone of rays that meet
/// the ball.
pub fn anchor(model: Fresnel, samples: usize) -> Anchor {
    let sin_max = RADIUS / (LIGHT_Y - CENTRE_Y);
    let cos_min = (1.0 - sin_max * sin_max).sqrt();
    let d_cos = (1.0 - cos_min) / samples as f64;
    let mut a = Anchor {
        total: 0.0,
        straight: 0.0,
        reflected: 0.0,
        within: vec![0.0; RADII.len()],
    };
    for i in 0..samples {
        let cos_theta = cos_min + (i as f64 + 0.5) * d_cos;
        let sin_theta = (1.0 - cos_theta * cos_theta).sqrt();
        let flux = INTENSITY * 2.0 * PI * d_cos;
        for (rho, w, path) in landings(model, sin_theta) {
            let f = flux * w * on_square(rho);
            a.total += f;
            match path {
                Path::StraightThrough => a.straight += f,
                Path::ReflectedOutside => a.reflected += f,
                Path::InternalReflections => {}
            }
            for (k, r) in RADII.iter().enumerate() {
                if rho < *r {
                    a.within[k] += flux * w;
                }
            }
        }
    }
    a
}

/// The caustic irradiance on the plane as a function of the distance from the axis,
/// binned: `e[k]` is the flux landing in the ring `[k bin, (k + 1) bin)` over the ring's
/// area (W/m^2 per channel), by the midpoint sum of [`anchor`].
pub struct IrradianceProfile {
    /// Width of a ring (scene units).
    pub bin: f64,
    /// Irradiance of each ring.
    pub e: Vec<f64>,
}

impl IrradianceProfile {
    /// The profile under `model` from `samples` rays, in rings of width `bin`.
    pub fn new(model: Fresnel, samples: usize, bin: f64) -> IrradianceProfile {
        let rings = (PLANE_HALF * 2f64.sqrt() / bin).ceil() as usize + 1;
        let mut flux = vec![0.0; rings];
        let sin_max = RADIUS / (LIGHT_Y - CENTRE_Y);
        let cos_min = (1.0 - sin_max * sin_max).sqrt();
        let d_cos = (1.0 - cos_min) / samples as f64;
        for i in 0..samples {
            let cos_theta = cos_min + (i as f64 + 0.5) * d_cos;
            let sin_theta = (1.0 - cos_theta * cos_theta).sqrt();
            for (rho, w, _) in landings(model, sin_theta) {
                if let Some(f) = flux.get_mut((rho / bin) as usize) {
                    *f += INTENSITY * 2.0 * PI * d_cos * w;
                }
            }
        }
        let e = flux
            .iter()
            .enumerate()
            .map(|(k, f)| f / (PI * bin * bin * ((k + 1).pow(2) - k.pow(2)) as f64))
            .collect();
        IrradianceProfile { bin, e }
    }

    /// `E` at distance `rho` from the axis (0 off the profile).
    pub fn at(&self, rho: f64) -> f64 {
        self.e
            .get((rho / self.bin) as usize)
            .copied()
            .unwrap_or(0.0)
    }
}

/// What a camera ray meets first.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum FirstHit {
    /// The glass ball.
    Ball,
    /// The plane.
    Plane,
    /// Nothing.
    Nothing,
}

/// The caustic radiance a camera sees in `sphere` (see the module doc): the specular tree
/// of each ray, cut as caustica's camera chains are (`max_depth` specular surfaces,
/// weights below `min_weight`), ending on the plane in `weight * albedo / pi * E(rho)`.
pub struct CameraReference<'a> {
    /// `E(rho)` on the plane.
    pub profile: &'a IrradianceProfile,
    /// The plane's albedo.
    pub albedo: f64,
    /// Longest specular chain.
    pub max_depth: u32,
    /// Branches below this weight are cut.
    pub min_weight: f64,
    /// The interfaces' reflectance.
    pub model: Fresnel,
}

/// Distance along unit `d` from `o` to the ball, beyond `t_min`.
fn ball_hit(o: [f64; 3], d: [f64; 3], t_min: f64) -> Option<f64> {
    let oc = [o[0], o[1] - CENTRE_Y, o[2]];
    let b = dot(oc, d);
    let disc = b * b - (dot(oc, oc) - RADIUS * RADIUS);
    if disc < 0.0 {
        return None;
    }
    let s = disc.sqrt();
    [-b - s, -b + s].into_iter().find(|t| *t > t_min)
}

/// Distance along `d` from `o` to the square plane, beyond `t_min`.
fn plane_hit(o: [f64; 3], d: [f64; 3], t_min: f64) -> Option<f64> {
    let t = -o[1] / d[1];
    let on =
        |t: f64| (o[0] + t * d[0]).abs() <= PLANE_HALF && (o[2] + t * d[2]).abs() <= PLANE_HALF;
    (t > t_min && on(t)).then_some(t)
}

/// `camera_ray`'s direction through the point `(x, y)` of the image (pixels, not
/// rounded), in f64.
fn camera_dir(cam: &caustica_core::device::layout::GpuCamera, x: f64, y: f64) -> [f64; 3] {
    let sx = (2.0 * x / cam.width as f64 - 1.0) * cam.tan_half_fov_x as f64;
    let sy = (1.0 - 2.0 * y / cam.height as f64) * cam.tan_half_fov_y as f64;
    let d: [f64; 3] = std::array::from_fn(|i| {
        cam.forward[i] as f64 + sx * cam.right[i] as f64 + sy * cam.up[i] as f64
    });
    let l = dot(d, d).sqrt();
    d.map(|c| c / l)
}

impl CameraReference<'_> {
    /// What the ray through the centre of pixel (`px`, `py`) meets first.
    pub fn first_hit(cam: &caustica_core::device::layout::GpuCamera, px: u32, py: u32) -> FirstHit {
        let o = cam.position.map(|c| c as f64);
        let d = camera_dir(cam, px as f64 + 0.5, py as f64 + 0.5);
        match (ball_hit(o, d, 0.0), plane_hit(o, d, 0.0)) {
            (Some(b), Some(p)) if b < p => FirstHit::Ball,
            (Some(_), None) => FirstHit::Ball,
            (_, Some(_)) => FirstHit::Plane,
            _ => FirstHit::Nothing,
        }
    }

    /// The pixel's caustic radiance (W/(sr m^2) per channel): the mean over `sub x sub`
    /// rays through the centres of a regular grid of sub-pixels.
    pub fn pixel(
        &self,
        cam: &caustica_core::device::layout::GpuCamera,
        px: u32,
        py: u32,
        sub: u32,
    ) -> f64 {
        let o = cam.position.map(|c| c as f64);
        let mut sum = 0.0;
        for j in 0..sub {
            for i in 0..sub {
                let x = px as f64 + (i as f64 + 0.5) / sub as f64;
                let y = py as f64 + (j as f64 + 0.5) / sub as f64;
                sum += self.tree(o, camera_dir(cam, x, y));
            }
        }
        sum / (sub * sub) as f64
    }

    /// The specular tree of one ray.
    fn tree(&self, origin: [f64; 3], dir: [f64; 3]) -> f64 {
        const T_MIN: f64 = 1e-9;
        let mut l = 0.0;
        let mut stack = vec![(origin, dir, 1.0f64, 0u32)];
        while let Some((o, d, w, depth)) = stack.pop() {
            let ball = ball_hit(o, d, T_MIN);
            let plane = plane_hit(o, d, T_MIN);
            let t = match (ball, plane) {
                (Some(b), Some(p)) if p < b => {
                    let p = [o[0] + p * d[0], o[2] + p * d[2]];
                    l += w * self.albedo / PI * self.profile.at(p[0].hypot(p[1]));
                    continue;
                }
                (None, Some(p)) => {
                    let p = [o[0] + p * d[0], o[2] + p * d[2]];
                    l += w * self.albedo / PI * self.profile.at(p[0].hypot(p[1]));
                    continue;
                }
                (Some(b), _) => b,
                (None, None) => continue,
            };
            if depth >= self.max_depth {
                continue;
            }
            let p: [f64; 3] = std::array::from_fn(|i| o[i] + t * d[i]);
            let n_out = [p[0] / RADIUS, (p[1] - CENTRE_Y) / RADIUS, p[2] / RADIUS];
            let entering = dot(d, n_out) < 0.0;
            let facing = if entering { n_out } else { n_out.map(|c| -c) };
            let (n1, n2) = if entering {
                (1.0, N_GLASS)
            } else {
                (N_GLASS, 1.0)
            };
            let cos_i = -dot(d, facing);
            let f = fresnel(self.model, cos_i, n1, n2);
            if w * f >= self.min_weight {
                stack.push((p, reflect(d, facing), w * f, depth + 1));
            }
            if f < 1.0 && w * (1.0 - f) >= self.min_weight {
                stack.push((p, refract(d, facing, n1 / n2), w * (1.0 - f), depth + 1));
            }
        }
        l
    }
}

//! An independent caustic reference: a brute-force light tracer in f64, written from the
//! physics and sharing no code with the techniques' kernels, optics or sampling (only the
//! scene model and its tessellation).
//!
//! Photons leave every light uniformly over an emission domain that contains every
//! caustic caster (a cone from a point or spot light around the casters' bounding
//! spheres, a square of parallel rays across their bounding sphere for a directional
//! light, kept only where the ray crosses its `projection_volume` when it has one), each
//! with flux `emitted power over the domain / N`. They are traced through mirrors
//! (power x reflectance) and dielectrics (exact unpolarised Fresnel: reflect with
//! probability `R`, refract otherwise, total internal reflection always reflects;
//! Beer-Lambert over segments inside). In a scene with a dispersive dielectric (a Cauchy
//! `B`, or KHR_materials_dispersion's Abbe model, each index written out here in f64)
//! every photon is traced three times: with `spec.dispersion` spectral at three
//! wavelengths stratified over 380-780 nm (one uniform offset per photon), each carrying a
//! third of the flux times its colour, the CIE 1931 functions (the same published fit and
//! sRGB matrix the library defines colour by, evaluated and normalised here in f64:
//! clipped at 0, each channel's mean over the range 1); with three bands once per colour
//! channel at that channel's wavelength. Spheres are analytic or, selectably, the
//! tessellated mesh with interpolated normals the kernels trace.
//!
//! Estimator (the quantity Sspm's raw deposit, Kim 2019 Eq. 5, converges to): a photon
//! whose path met at least one specular surface and first meets a diffuse surface at `x`
//! is connected to the pinhole camera. It counts for the pixel `P` that `x` projects into
//! when (a) the surface `P`'s centre ray sees is diffuse and is the object `x` lies on,
//! (b) with [`SilhouetteDefinition::EyeVisible`] only, nothing lies between `x` and the
//! eye, and (c) the photon arrives on the side of the surface the eye is on. Then
//!
//! `L_P = (albedo / pi) x sum_i Phi_i / A_P`,
//!
//! `A_P = (2 tan(fov_x/2) / w) (2 tan(fov_y/2) / h) z^2 (omega . f) / |omega . n|`: the
//! surface area the pixel's pencil cuts at its centre ray (view depth `z`, unit ray
//! `omega`, camera axis `f`, surface normal `n`), which is the pixel's solid angle
//! `(sx sy (omega . f)^3)` times `t^2 / |omega . n|` with `t = z / (omega . f)`.
//!
//! Error bar: `batches` independent batches of `photons` photons per light, each with
//! its own seed stream; the image is their mean, the error the standard error of the
//! mean (RMS over the caustic pixels relative to the RMS of the mean, as the technique
//! references report). Each photon's random numbers come from SplitMix64 seeded by
//! (seed, batch, light, photon, pass), and contributions are summed in photon order,
//! so the result is the same for any thread count.

use super::{cached_sidecar, file_name, paths, read_exr};
use caustica_core::frame::image::Image;
use caustica_core::frame::settings::Dispersion;
use caustica_core::scene::shapes::tessellate;
use caustica_core::scene::{IorModel, Light, Material, Scene, Shape};
use glam::DVec3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;
use std::fmt;
use std::path::Path;
use std::str::FromStr;

/// Why a light-tracer reference could not be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum LightTracerError {
    /// The settings cannot give an estimate with an error bar.
    #[error("light tracer settings: {0}")]
    Settings(String),
    /// The scene has something the tracer cannot trace.
    #[error("light tracer scene: {0}")]
    Scene(String),
    /// The cache folder or one of its files could not be made, read or written (the
    /// message names the path).
    #[error("reference cache {0}")]
    Cache(String),
}

impl From<LightTracerError> for String {
    fn from(e: LightTracerError) -> String {
        e.to_string()
    }
}

/// How spheres are represented.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SphereModel {
    /// The exact sphere (analytic intersection, radial normal).
    Analytic,
    /// The scene's tessellated UV sphere with interpolated normals, as the kernels see it.
    Mesh,
}

impl SphereModel {
    /// The command line's name: `analytic` or `mesh`.
    pub fn name(self) -> &'static str {
        match self {
            SphereModel::Analytic => "analytic",
            SphereModel::Mesh => "mesh",
        }
    }
}

/// What a pixel whose footprint straddles a silhouette measures: the two definitions
/// agree on every other pixel (both count only photons on the diffuse surface the
/// pixel's centre ray sees, over that surface's area at the centre ray), and both leave
/// a pixel whose centre sees no diffuse surface (the glass ball, the sky) empty.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SilhouetteDefinition {
    /// The radiance of the surface the pixel's centre sees: every photon on that surface
    /// that projects into the pixel counts, whether the eye sees it or an object in front
    /// hides it. Sspm's tangent-plane store test counts exactly these (it has no
    /// visibility test), and CausticMap's and AdaptiveCaustics' atlas lookup at the
    /// centre ray's hit reads that surface's irradiance: the default, the quantity the
    /// caustic techniques estimate.
    #[default]
    CentreSurface,
    /// The flux the eye sees through the pixel's footprint: of those photons only the
    /// ones with nothing between them and the eye, so a silhouette pixel over a caustic
    /// gets the surface's radiance times the fraction of its footprint the eye sees.
    EyeVisible,
}

impl SilhouetteDefinition {
    /// Both definitions, default first.
    pub const ALL: [SilhouetteDefinition; 2] = [
        SilhouetteDefinition::CentreSurface,
        SilhouetteDefinition::EyeVisible,
    ];

    /// The command line's name: `centre-surface` or `eye-visible`.
    pub fn name(self) -> &'static str {
        match self {
            SilhouetteDefinition::CentreSurface => "centre-surface",
            SilhouetteDefinition::EyeVisible => "eye-visible",
        }
    }

    /// One line saying what a silhouette pixel measures (for tables and help).
    pub fn describe(self) -> &'static str {
        match self {
            SilhouetteDefinition::CentreSurface => {
                "the radiance of the surface the pixel's centre sees, hidden photons counted \
                 as the caustic techniques' store test counts them"
            }
            SilhouetteDefinition::EyeVisible => {
                "the flux the eye sees through the pixel's footprint (hidden photons dropped)"
            }
        }
    }
}

impl fmt::Display for SilhouetteDefinition {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for SilhouetteDefinition {
    type Err = LightTracerError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        SilhouetteDefinition::ALL
            .into_iter()
            .find(|d| d.name() == s)
            .ok_or_else(|| {
                LightTracerError::Settings(format!(
                    "unknown silhouette definition '{s}': centre-surface or eye-visible"
                ))
            })
    }
}

/// How a light-tracer reference is computed.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LightTracerSpec {
    /// Image width (pixels).
    pub width: u32,
    /// Image height (pixels).
    pub height: u32,
    /// Photons per light and batch (over the emission domain).
    pub photons: u64,
    /// Independent batches (at least 2: the error bar comes from their spread).
    pub batches: u32,
    /// Seed of the first batch's stream.
    pub seed: u64,
    /// Spheres analytic or tessellated.
    pub spheres: SphereModel,
    /// Specular interactions after which a path is dropped (counted in the info).
    pub max_specular: u32,
    /// How photons through dispersive glass take a colour (as the techniques'
    /// `frame.dispersion`; default spectral).
    #[serde(default)]
    pub dispersion: Dispersion,
    /// What a silhouette pixel measures: with [`SilhouetteDefinition::EyeVisible`] test
    /// (b), the eye's view of the photon, applies; the default counts every photon on the
    /// surface the pixel's centre sees, as the caustic techniques do. The two differ only
    /// in pixels that straddle a silhouette.
    #[serde(default)]
    pub silhouette: SilhouetteDefinition,
}

impl Default for LightTracerSpec {
    fn default() -> Self {
        LightTracerSpec {
            width: 480,
            height: 270,
            photons: 1 << 22,
            batches: 16,
            seed: 1,
            spheres: SphereModel::Analytic,
            max_specular: 64,
            dispersion: Dispersion::Spectral,
            silhouette: SilhouetteDefinition::CentreSurface,
        }
    }
}

/// How a light-tracer reference was made.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LightTracerInfo {
    /// Scene name.
    pub scene: String,
    /// Cache key ([`light_tracer_hash`]).
    pub scene_hash: String,
    /// How it was computed.
    pub spec: LightTracerSpec,
    /// Photons emitted over all batches and lights (per channel pass for dispersion).
    pub photons: u64,
    /// Photons that reached a diffuse surface after a specular one and counted.
    pub connected: u64,
    /// Paths dropped at `max_specular`.
    pub truncated: u64,
    /// Relative standard error of the mean over the caustic pixels.
    pub noise: f64,
}

/// A light-tracer reference: the mean caustic radiance, its per-pixel standard error, and
/// how it was made.
pub struct LightTracerReference {
    /// Mean caustic radiance (W/(sr m^2) per channel).
    pub image: Image,
    /// Standard error of the mean per pixel and channel.
    pub std_error: Image,
    /// Per pixel: 1 where the pixel's corners see another object than its centre (or
    /// nothing): a silhouette pixel, where counting photons visible from the eye and
    /// counting photons on the centre's surface differ.
    pub silhouette: Vec<bool>,
    /// How it was made.
    pub info: LightTracerInfo,
}

// ---------------------------------------------------------------- random numbers

fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

struct Rng(u64);

impl Rng {
    fn new(keys: [u64; 5]) -> Rng {
        let mut s = 0x5851_f42d_4c95_7f2d;
        for k in keys {
            s ^= k;
            s = splitmix(&mut s);
        }
        Rng(s)
    }
    /// Uniform in [0, 1).
    fn next(&mut self) -> f64 {
        (splitmix(&mut self.0) >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }
}

// ---------------------------------------------------------------- geometry

#[derive(Clone, Copy)]
enum Mat {
    Diffuse([f64; 3]),
    Mirror([f64; 3]),
    Dielectric { ior: Index, absorption: [f64; 3] },
}

/// A dielectric's index against wavelength (micrometres).
#[derive(Clone, Copy, PartialEq)]
enum Index {
    /// Cauchy: `a + b / l^2`.
    Cauchy { a: f64, b: f64 },
    /// KHR_materials_dispersion: `max(n_d + (n_d - 1) / v (0.523655 / l^2 - 1.5168), 1)`.
    Abbe { n_d: f64, v: f64 },
}

impl Index {
    /// The index at `l` micrometres; `None`: the nominal index (`ior`).
    fn at(&self, l: Option<f64>) -> f64 {
        match (*self, l) {
            (Index::Cauchy { a, b }, None) => a + b / (NOMINAL_UM * NOMINAL_UM),
            (Index::Cauchy { a, b }, Some(l)) => a + b / (l * l),
            (Index::Abbe { n_d, .. }, None) => n_d,
            (Index::Abbe { n_d, v }, Some(l)) => {
                (n_d + (n_d - 1.0) / v * (0.523655 / (l * l) - 1.5168)).max(1.0)
            }
        }
    }

    fn dispersive(&self) -> bool {
        !matches!(self, Index::Cauchy { b, .. } if *b == 0.0)
    }
}

struct Tri {
    p0: DVec3,
    e1: DVec3,
    e2: DVec3,
    n: [DVec3; 3],
    ng: DVec3,
    obj: u32,
}

struct Ball {
    c: DVec3,
    r: f64,
    obj: u32,
}

#[derive(Clone, Copy)]
struct Node {
    min: DVec3,
    max: DVec3,
    /// Leaf: first triangle; inner: index of the second child (the first follows).
    index: u32,
    /// Triangles in a leaf, 0 for an inner node.
    count: u32,
}

struct Hit {
    t: f64,
    p: DVec3,
    /// Unit geometric normal (outward for closed shapes).
    ng: DVec3,
    /// Unit shading normal.
    ns: DVec3,
    obj: u32,
}

struct Geometry {
    tris: Vec<Tri>,
    nodes: Vec<Node>,
    balls: Vec<Ball>,
    mats: Vec<Mat>,
    /// Bounding sphere per object.
    bounds: Vec<(DVec3, f64)>,
    /// Scene bounding sphere.
    scene_bound: (DVec3, f64),
    eps: f64,
}

fn d3(v: glam::Vec3) -> DVec3 {
    DVec3::new(v.x as f64, v.y as f64, v.z as f64)
}

/// Wavelengths (um) of the red, green and blue channels, and the one `ior` is given at.
const CHANNEL_UM: [f64; 3] = [0.65, 0.55, 0.45];
const NOMINAL_UM: f64 = 0.55;

/// The linear sRGB weight of a wavelength, in f64: the CIE 1931 2-degree functions in
/// Wyman 2013's multi-lobe fit (its published coefficients, the data core's
/// `math::spectrum` holds), the IEC 61966-2-1 matrix, each channel clipped at 0 and scaled
/// to mean 1 over 380-780 nm (the scale integrated here by the midpoint rule).
struct SpectralColour {
    scale: [f64; 3],
}

impl SpectralColour {
    fn new() -> SpectralColour {
        let mut c = SpectralColour { scale: [1.0; 3] };
        let n = 40_000;
        let mut mean = [0.0f64; 3];
        for i in 0..n {
            let w = c.weight(0.38 + 0.4 * (i as f64 + 0.5) / n as f64);
            for k in 0..3 {
                mean[k] += w[k] / n as f64;
            }
        }
        c.scale = mean.map(|m| 1.0 / m);
        c
    }

    /// The weight at `l` micrometres.
    fn weight(&self, l: f64) -> [f64; 3] {
        use caustica_core::math::spectrum::{
            CieLobe, CIE_X_LOBES, CIE_Y_LOBES, CIE_Z_LOBES, XYZ_TO_LINEAR_SRGB,
        };
        let nm = l * 1000.0;
        let f = |lobes: &[CieLobe]| -> f64 {
            lobes
                .iter()
                .map(|g| {
                    let mu = g.mean_nm as f64;
                    let s = if nm < mu {
                        g.inv_sigma_below
                    } else {
                        g.inv_sigma_above
                    } as f64;
                    g.weight as f64 * (-0.5 * ((nm - mu) * s).powi(2)).exp()
                })
                .sum()
        };
        let xyz = [f(&CIE_X_LOBES), f(&CIE_Y_LOBES), f(&CIE_Z_LOBES)];
        std::array::from_fn(|r| {
            let m = XYZ_TO_LINEAR_SRGB[r];
            let v = m[0] as f64 * xyz[0] + m[1] as f64 * xyz[1] + m[2] as f64 * xyz[2];
            v.max(0.0) * self.scale[r]
        })
    }
}

fn material(m: &Material) -> Mat {
    let v = |x: glam::Vec3| [x.x as f64, x.y as f64, x.z as f64];
    match m {
        Material::Diffuse { albedo } => Mat::Diffuse(v(*albedo)),
        Material::Mirror { reflectance } => Mat::Mirror(v(*reflectance)),
        Material::Dielectric {
            ior,
            cauchy_b,
            absorption,
            ior_model,
        } => {
            let (n, b) = (*ior as f64, *cauchy_b as f64);
            let ior = match ior_model {
                IorModel::Cauchy => Index::Cauchy {
                    a: n - b / (NOMINAL_UM * NOMINAL_UM),
                    b,
                },
                IorModel::Abbe { abbe_number } => Index::Abbe {
                    n_d: n,
                    v: *abbe_number as f64,
                },
            };
            Mat::Dielectric {
                ior,
                absorption: v(*absorption),
            }
        }
    }
}

impl Geometry {
    fn build(scene: &Scene, spheres: SphereModel) -> Result<Geometry, LightTracerError> {
        let mut g = Geometry {
            tris: Vec::new(),
            nodes: Vec::new(),
            balls: Vec::new(),
            mats: Vec::new(),
            bounds: Vec::new(),
            scene_bound: (DVec3::ZERO, 0.0),
            eps: 0.0,
        };
        let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        for (i, o) in scene.objects.iter().enumerate() {
            let m = scene.materials.get(&o.material).ok_or_else(|| {
                LightTracerError::Scene(format!("object {}: no material {}", o.name, o.material))
            })?;
            g.mats.push(material(m));
            let obj = i as u32;
            if let (Shape::Sphere { center, radius, .. }, SphereModel::Analytic, None) =
                (&o.shape, spheres, &o.transform)
            {
                let (c, r) = (d3(*center), *radius as f64);
                g.balls.push(Ball { c, r, obj });
                g.bounds.push((c, r));
                lo = lo.min(c - r);
                hi = hi.max(c + r);
                continue;
            }
            if matches!(o.shape, Shape::ObjFile { .. }) {
                return Err(LightTracerError::Scene(format!(
                    "object {}: an unloaded obj_file shape",
                    o.name
                )));
            }
            let mut mesh = tessellate(&o.shape);
            if let Some(t) = &o.transform {
                let (w, nm) = (t.world_from_object(), t.normal_matrix());
                for p in &mut mesh.positions {
                    *p = w.transform_point3(*p);
                }
                for n in &mut mesh.normals {
                    *n = glam::Vec3::from(nm * glam::Vec3A::from(*n));
                }
            }
            let (mut olo, mut ohi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
            for p in &mesh.positions {
                olo = olo.min(d3(*p));
                ohi = ohi.max(d3(*p));
            }
            let c = 0.5 * (olo + ohi);
            g.bounds.push((c, 0.5 * (ohi - olo).length()));
            lo = lo.min(olo);
            hi = hi.max(ohi);
            for t in &mesh.indices {
                let p = t.map(|k| d3(mesh.positions[k as usize]));
                let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
                let ng = e1.cross(e2);
                if ng.length_squared() == 0.0 {
                    continue;
                }
                let ng = ng.normalize();
                let n = t.map(|k| {
                    mesh.normals
                        .get(k as usize)
                        .map(|n| d3(*n).normalize_or_zero())
                        .filter(|n| *n != DVec3::ZERO)
                        .unwrap_or(ng)
                });
                g.tris.push(Tri {
                    p0: p[0],
                    e1,
                    e2,
                    n,
                    ng,
                    obj,
                });
            }
        }
        if g.mats.is_empty() {
            return Err(LightTracerError::Scene("the scene has no object".into()));
        }
        g.scene_bound = (0.5 * (lo + hi), 0.5 * (hi - lo).length());
        g.eps = 1e-9 * g.scene_bound.1.max(1.0);
        let n = g.tris.len();
        if n > 0 {
            let mut order: Vec<usize> = (0..n).collect();
            g.build_node(&mut order, 0, n);
            let tris = std::mem::take(&mut g.tris);
            let mut slots: Vec<Option<Tri>> = tris.into_iter().map(Some).collect();
            g.tris = order.iter().map(|&i| slots[i].take().unwrap()).collect();
        }
        Ok(g)
    }

    fn tri_bounds(&self, i: usize) -> (DVec3, DVec3) {
        let t = &self.tris[i];
        let (a, b, c) = (t.p0, t.p0 + t.e1, t.p0 + t.e2);
        (a.min(b).min(c), a.max(b).max(c))
    }

    /// Median split on the longest centroid axis; leaves of at most 4 triangles.
    fn build_node(&mut self, order: &mut [usize], first: usize, count: usize) -> usize {
        let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        let (mut clo, mut chi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        for &i in &order[first..first + count] {
            let (a, b) = self.tri_bounds(i);
            lo = lo.min(a);
            hi = hi.max(b);
            let c = 0.5 * (a + b);
            clo = clo.min(c);
            chi = chi.max(c);
        }
        let me = self.nodes.len();
        self.nodes.push(Node {
            min: lo,
            max: hi,
            index: first as u32,
            count: count as u32,
        });
        if count <= 4 {
            return me;
        }
        let ext = chi - clo;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let half = count / 2;
        let key = |g: &Geometry, i: usize| {
            let (a, b) = g.tri_bounds(i);
            (a + b)[axis]
        };
        {
            let slice = &mut order[first..first + count];
            let keys: Vec<f64> = slice.iter().map(|&i| key(self, i)).collect();
            let mut idx: Vec<usize> = (0..count).collect();
            idx.select_nth_unstable_by(half, |&a, &b| keys[a].total_cmp(&keys[b]));
            let copy: Vec<usize> = idx.iter().map(|&k| slice[k]).collect();
            slice.copy_from_slice(&copy);
        }
        self.build_node(order, first, half);
        let second = self.build_node(order, first + half, count - half);
        self.nodes[me].index = second as u32;
        self.nodes[me].count = 0;
        me
    }

    /// Nearest hit with `eps < t < t_max`.
    fn intersect(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<Hit> {
        let mut best: Option<(f64, usize, f64, f64)> = None; // t, tri, u, v
        let mut t_best = t_max;
        if !self.nodes.is_empty() {
            let inv = DVec3::ONE / d;
            let mut stack = [0usize; 64];
            let mut sp = 1;
            while sp > 0 {
                sp -= 1;
                let ni = stack[sp];
                let node = self.nodes[ni];
                let t0 = (node.min - o) * inv;
                let t1 = (node.max - o) * inv;
                let tn = t0.min(t1).max_element().max(0.0);
                let tf = t0.max(t1).min_element().min(t_best);
                if tn > tf || tf.is_nan() {
                    continue;
                }
                if node.count == 0 {
                    // the first child follows its parent
                    stack[sp] = ni + 1;
                    stack[sp + 1] = node.index as usize;
                    sp += 2;
                    continue;
                }
                for i in node.index as usize..(node.index + node.count) as usize {
                    let t = &self.tris[i];
                    // Moller-Trumbore
                    let pv = d.cross(t.e2);
                    let det = t.e1.dot(pv);
                    if det.abs() < 1e-300 {
                        continue;
                    }
                    let inv_det = 1.0 / det;
                    let tv = o - t.p0;
                    let u = tv.dot(pv) * inv_det;
                    if !(0.0..=1.0).contains(&u) {
                        continue;
                    }
                    let qv = tv.cross(t.e1);
                    let v = d.dot(qv) * inv_det;
                    if v < 0.0 || u + v > 1.0 {
                        continue;
                    }
                    let th = t.e2.dot(qv) * inv_det;
                    if th > self.eps && th < t_best {
                        t_best = th;
                        best = Some((th, i, u, v));
                    }
                }
            }
        }
        let mut ball_hit: Option<(f64, usize)> = None;
        for (k, b) in self.balls.iter().enumerate() {
            let oc = o - b.c;
            let hb = oc.dot(d);
            let c = oc.length_squared() - b.r * b.r;
            let disc = hb * hb - c;
            if disc < 0.0 {
                continue;
            }
            let s = disc.sqrt();
            for th in [-hb - s, -hb + s] {
                if th > self.eps && th < t_best {
                    t_best = th;
                    ball_hit = Some((th, k));
                    break;
                }
            }
        }
        if let Some((t, k)) = ball_hit {
            let b = &self.balls[k];
            let p = o + t * d;
            let n = (p - b.c) / b.r;
            return Some(Hit {
                t,
                p,
                ng: n,
                ns: n,
                obj: b.obj,
            });
        }
        best.map(|(t, i, u, v)| {
            let tri = &self.tris[i];
            let ns = ((1.0 - u - v) * tri.n[0] + u * tri.n[1] + v * tri.n[2]).normalize_or_zero();
            Hit {
                t,
                p: o + t * d,
                ng: tri.ng,
                ns: if ns == DVec3::ZERO { tri.ng } else { ns },
                obj: tri.obj,
            }
        })
    }

    /// An origin just off the surface of `h` on the side `dir` leaves to.
    fn offset(&self, h: &Hit, dir: DVec3) -> DVec3 {
        let s = if dir.dot(h.ng) >= 0.0 { 1.0 } else { -1.0 };
        h.p + h.ng * (s * 1e-7 * self.scene_bound.1.max(1.0) * (1.0 + h.p.abs().max_element()))
    }
}

// ---------------------------------------------------------------- optics (from the physics)

fn reflect(d: DVec3, n: DVec3) -> DVec3 {
    d - 2.0 * d.dot(n) * n
}

/// Unpolarised Fresnel reflectance and the refracted direction (None: total internal
/// reflection) for unit `d` arriving at unit `n` (facing `d`: `d . n < 0`), relative index
/// `eta = n_incident / n_transmitted`.
fn fresnel(d: DVec3, n: DVec3, eta: f64) -> (f64, Option<DVec3>) {
    let ci = (-d.dot(n)).clamp(0.0, 1.0);
    let s2t = eta * eta * (1.0 - ci * ci);
    if s2t >= 1.0 {
        return (1.0, None);
    }
    let ct = (1.0 - s2t).sqrt();
    // n1 = eta, n2 = 1 (only the ratio matters)
    let rs = (eta * ci - ct) / (eta * ci + ct);
    let rp = (ci - eta * ct) / (ci + eta * ct);
    let r = 0.5 * (rs * rs + rp * rp);
    let t = (eta * d + (eta * ci - ct) * n).normalize();
    (r, Some(t))
}

// ---------------------------------------------------------------- camera

struct Cam {
    pos: DVec3,
    f: DVec3,
    r: DVec3,
    u: DVec3,
    tx: f64,
    ty: f64,
    w: u32,
    h: u32,
}

impl Cam {
    fn new(c: &caustica_core::scene::Camera, w: u32, h: u32) -> Cam {
        let pos = d3(c.position);
        let f = (d3(c.target) - pos).normalize();
        let r = f.cross(d3(c.up)).normalize();
        let u = r.cross(f);
        let ty = (c.fov_y_deg as f64 * PI / 360.0).tan();
        Cam {
            pos,
            f,
            r,
            u,
            tx: ty * w as f64 / h as f64,
            ty,
            w,
            h,
        }
    }
    /// Unit ray through image point (`x`, `y`) in pixels (x right, y down).
    fn ray(&self, x: f64, y: f64) -> DVec3 {
        let sx = (2.0 * x / self.w as f64 - 1.0) * self.tx;
        let sy = (1.0 - 2.0 * y / self.h as f64) * self.ty;
        (self.f + sx * self.r + sy * self.u).normalize()
    }
    fn pixel(&self, p: DVec3) -> Option<usize> {
        let v = p - self.pos;
        let z = v.dot(self.f);
        if z <= 0.0 {
            return None;
        }
        let fx = (v.dot(self.r) / (z * self.tx) + 1.0) * 0.5 * self.w as f64;
        let fy = (1.0 - v.dot(self.u) / (z * self.ty)) * 0.5 * self.h as f64;
        if !(fx >= 0.0 && fy >= 0.0 && fx < self.w as f64 && fy < self.h as f64) {
            return None;
        }
        Some(fy as usize * self.w as usize + fx as usize)
    }
}

/// What a pixel's centre ray sees: a diffuse object, its `albedo / (pi A_P)`.
#[derive(Clone, Copy)]
struct PixelSee {
    obj: u32,
    scale: [f64; 3],
}

/// Smallest |omega . n| in the footprint (a surface seen edge-on gets a large area).
const MIN_COS: f64 = 1e-4;

fn pixel_table(g: &Geometry, cam: &Cam) -> (Vec<Option<PixelSee>>, Vec<bool>) {
    let n = (cam.w * cam.h) as usize;
    let sxsy = (2.0 * cam.tx / cam.w as f64) * (2.0 * cam.ty / cam.h as f64);
    (0..n)
        .into_par_iter()
        .map(|i| {
            let (px, py) = ((i % cam.w as usize) as f64, (i / cam.w as usize) as f64);
            let see = |x: f64, y: f64| g.intersect(cam.pos, cam.ray(x, y), f64::INFINITY);
            let centre = see(px + 0.5, py + 0.5);
            let obj = centre.as_ref().map(|h| h.obj);
            let silhouette = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
                .iter()
                .any(|(a, b)| see(px + a, py + b).map(|h| h.obj) != obj);
            let entry = centre.and_then(|h| {
                let Mat::Diffuse(albedo) = g.mats[h.obj as usize] else {
                    return None;
                };
                let omega = cam.ray(px + 0.5, py + 0.5);
                let cos_axis = omega.dot(cam.f);
                let z = h.t * cos_axis;
                let area = sxsy * z * z * cos_axis / omega.dot(h.ng).abs().max(MIN_COS);
                Some(PixelSee {
                    obj: h.obj,
                    scale: albedo.map(|a| a / (PI * area)),
                })
            });
            (entry, silhouette)
        })
        .unzip()
}

// ---------------------------------------------------------------- emission

/// A cone from `apex` containing every specular object's bounding sphere: (axis, cos of
/// the half-angle); the whole sphere of directions when the apex is inside one.
fn caster_cone(g: &Geometry, apex: DVec3) -> (DVec3, f64) {
    let casters: Vec<(DVec3, f64)> = g
        .bounds
        .iter()
        .zip(&g.mats)
        .filter(|(_, m)| !matches!(m, Mat::Diffuse(_)))
        .map(|(b, _)| *b)
        .collect();
    let mut axis = DVec3::ZERO;
    for (c, r) in &casters {
        let v = *c - apex;
        if v.length() <= *r * 1.000001 {
            return (DVec3::Y, -1.0);
        }
        axis += v.normalize();
    }
    let axis = axis.normalize_or_zero();
    if axis == DVec3::ZERO {
        return (DVec3::Y, -1.0);
    }
    let mut half: f64 = 0.0;
    for (c, r) in &casters {
        let v = *c - apex;
        let a = axis.dot(v.normalize()).clamp(-1.0, 1.0).acos() + (*r / v.length()).asin();
        half = half.max(a);
    }
    (
        axis,
        if half >= PI {
            -1.0
        } else {
            half.cos() * (1.0 - 1e-12)
        },
    )
}

fn basis(n: DVec3) -> (DVec3, DVec3) {
    let a = if n.x.abs() < 0.9 { DVec3::X } else { DVec3::Y };
    let u = n.cross(a).normalize();
    (u, n.cross(u))
}

/// Uniform direction in the cone (axis, cos half-angle).
fn sample_cone(axis: DVec3, cos_max: f64, rng: &mut Rng) -> DVec3 {
    let cos = 1.0 - rng.next() * (1.0 - cos_max);
    let sin = (1.0 - cos * cos).max(0.0).sqrt();
    let phi = 2.0 * PI * rng.next();
    let (u, v) = basis(axis);
    (cos * axis + sin * (phi.cos() * u + phi.sin() * v)).normalize()
}

fn ray_box(o: DVec3, d: DVec3, lo: DVec3, hi: DVec3) -> bool {
    let inv = DVec3::ONE / d;
    let (t0, t1) = ((lo - o) * inv, (hi - o) * inv);
    let tn = t0.min(t1).max_element();
    let tf = t0.max(t1).min_element();
    tn <= tf && tf >= 0.0
}

enum Emitter {
    Cone {
        apex: DVec3,
        axis: DVec3,
        cos_max: f64,
        /// Intensity (W/sr) and the cone's solid angle.
        power: [f64; 3],
        /// Spot: (axis, cos inner, cos outer).
        spot: Option<(DVec3, f64, f64)>,
    },
    Parallel {
        dir: DVec3,
        centre: DVec3,
        half: f64,
        back: f64,
        power: [f64; 3],
        volume: Option<(DVec3, DVec3)>,
    },
}

fn emitters(scene: &Scene, g: &Geometry) -> Vec<Emitter> {
    let v = |x: glam::Vec3| [x.x as f64, x.y as f64, x.z as f64];
    scene
        .lights
        .iter()
        .map(|l| match l {
            Light::Point {
                position,
                intensity,
            } => {
                let apex = d3(*position);
                let (axis, cos_max) = caster_cone(g, apex);
                let omega = 2.0 * PI * (1.0 - cos_max);
                Emitter::Cone {
                    apex,
                    axis,
                    cos_max,
                    power: v(*intensity).map(|i| i * omega),
                    spot: None,
                }
            }
            Light::Spot {
                position,
                direction,
                intensity,
                inner_angle_deg,
                outer_angle_deg,
            } => {
                let apex = d3(*position);
                let sd = d3(*direction).normalize();
                let (ci, co) = (
                    (*inner_angle_deg as f64).to_radians().cos(),
                    (*outer_angle_deg as f64).to_radians().cos(),
                );
                let (axis, cos_max) = caster_cone(g, apex);
                // the narrower of the casters' cone and the spot's support
                let (axis, cos_max) = if co > cos_max {
                    (sd, co)
                } else {
                    (axis, cos_max)
                };
                let omega = 2.0 * PI * (1.0 - cos_max);
                Emitter::Cone {
                    apex,
                    axis,
                    cos_max,
                    power: v(*intensity).map(|i| i * omega),
                    spot: Some((sd, ci, co)),
                }
            }
            Light::Directional {
                direction,
                irradiance,
                projection_volume,
            } => {
                let dir = d3(*direction).normalize();
                let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
                for (b, m) in g.bounds.iter().zip(&g.mats) {
                    if !matches!(m, Mat::Diffuse(_)) {
                        lo = lo.min(b.0 - b.1);
                        hi = hi.max(b.0 + b.1);
                    }
                }
                let volume = projection_volume.map(|b| (d3(b.min), d3(b.max)));
                // no caster and no volume: no caustic photon (an empty square)
                let empty = volume.is_none() && lo.x > hi.x;
                if empty {
                    lo = DVec3::ZERO;
                    hi = DVec3::ZERO;
                }
                if let Some((a, b)) = volume {
                    lo = a;
                    hi = b;
                }
                let centre = 0.5 * (lo + hi);
                let half = 0.5 * (hi - lo).length();
                let side = 2.0 * half;
                Emitter::Parallel {
                    dir,
                    centre,
                    half,
                    back: (g.scene_bound.0 - centre).length() + g.scene_bound.1 + half,
                    power: v(*irradiance).map(|e| if empty { 0.0 } else { e * side * side }),
                    volume,
                }
            }
        })
        .collect()
}

impl Emitter {
    /// Origin, direction and flux of one photon (of `n` over the domain).
    fn emit(&self, n: u64, rng: &mut Rng) -> Option<(DVec3, DVec3, [f64; 3])> {
        let k = 1.0 / n as f64;
        match self {
            Emitter::Cone {
                apex,
                axis,
                cos_max,
                power,
                spot,
            } => {
                let d = sample_cone(*axis, *cos_max, rng);
                let w = match spot {
                    None => 1.0,
                    Some((sd, ci, co)) => {
                        let c = d.dot(*sd);
                        if c >= *ci {
                            1.0
                        } else if c <= *co {
                            0.0
                        } else {
                            let t = (c - co) / (ci - co);
                            t * t * (3.0 - 2.0 * t)
                        }
                    }
                };
                (w > 0.0).then(|| (*apex, d, power.map(|p| p * w * k)))
            }
            Emitter::Parallel {
                dir,
                centre,
                half,
                back,
                power,
                volume,
            } => {
                let (u, v) = basis(*dir);
                let (a, b) = (2.0 * rng.next() - 1.0, 2.0 * rng.next() - 1.0);
                let o = *centre + half * (a * u + b * v) - *back * *dir;
                if let Some((lo, hi)) = volume {
                    if !ray_box(o, *dir, *lo, *hi) {
                        return None;
                    }
                }
                Some((o, *dir, power.map(|p| p * k)))
            }
        }
    }
}

// ---------------------------------------------------------------- tracing

enum PathEnd {
    Stored {
        hit: Hit,
        dir: DVec3,
        flux: [f64; 3],
    },
    Lost,
    Truncated,
}

/// Traces a photon; `wavelength` (micrometres) sets dispersive dielectrics' index (None:
/// every dielectric's nominal `ior`).
fn trace(
    g: &Geometry,
    mut o: DVec3,
    mut d: DVec3,
    mut flux: [f64; 3],
    wavelength: Option<f64>,
    max_specular: u32,
    rng: &mut Rng,
) -> PathEnd {
    let mut specular = 0u32;
    let mut inside: Option<[f64; 3]> = None;
    loop {
        let Some(h) = g.intersect(o, d, f64::INFINITY) else {
            return PathEnd::Lost;
        };
        if let Some(a) = inside {
            for c in 0..3 {
                flux[c] *= (-a[c] * h.t).exp();
            }
        }
        match g.mats[h.obj as usize] {
            Mat::Diffuse(_) => {
                if specular == 0 {
                    return PathEnd::Lost;
                }
                return PathEnd::Stored {
                    hit: h,
                    dir: d,
                    flux,
                };
            }
            _ if specular >= max_specular => return PathEnd::Truncated,
            Mat::Mirror(r) => {
                for c in 0..3 {
                    flux[c] *= r[c];
                }
                let n = if d.dot(h.ns) < 0.0 { h.ns } else { -h.ns };
                d = reflect(d, n).normalize();
            }
            Mat::Dielectric { ior, absorption } => {
                let entering = d.dot(h.ng) < 0.0;
                let mut n = if entering { h.ns } else { -h.ns };
                if d.dot(n) >= 0.0 {
                    n = if entering { h.ng } else { -h.ng };
                }
                let ior = ior.at(wavelength);
                let eta = if entering { 1.0 / ior } else { ior };
                let (r, t) = fresnel(d, n, eta);
                match t {
                    Some(t) if rng.next() >= r => {
                        d = t;
                        inside = entering.then_some(absorption);
                    }
                    _ => d = reflect(d, n).normalize(),
                }
            }
        }
        specular += 1;
        o = g.offset(&h, d);
    }
}

// ---------------------------------------------------------------- the reference

/// Per pixel of `scene` seen at `spec`'s size: whether its corner rays see another object
/// than its centre ray (or nothing), as [`LightTracerReference::silhouette`].
pub fn silhouette_pixels(
    scene: &Scene,
    spec: &LightTracerSpec,
) -> Result<Vec<bool>, LightTracerError> {
    validate(spec)?;
    let n = (spec.width * spec.height) as usize;
    check_image_memory(n)?;
    let g = Geometry::build(scene, spec.spheres)?;
    let cam = Cam::new(&scene.camera, spec.width, spec.height);
    Ok(pixel_table(&g, &cam).1)
}

/// FNV-1a (64 bit) of the scene file text and the light tracer's settings. With
/// [`SphereModel::Analytic`] the spheres the tracer intersects exactly (those without a
/// transform) are hashed without their tessellation's `segments`, which it never reads:
/// a finer ball mesh keeps the exact sphere's cached reference.
pub fn light_tracer_hash(scene: &Scene, spec: &LightTracerSpec) -> String {
    let mut hashed = scene.clone();
    if spec.spheres == SphereModel::Analytic {
        for o in &mut hashed.objects {
            if let (Shape::Sphere { segments, .. }, None) = (&mut o.shape, &o.transform) {
                *segments = 0;
            }
        }
    }
    let text = format!(
        "light-tracer|{}|{}",
        caustica_core::scene::format::to_json(&hashed),
        serde_json::to_string(spec).unwrap_or_default()
    );
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in text.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

/// Largest image side (pixels), as the scene format's camera.
const MAX_SIDE: u32 = 16384;

/// Rejects settings that cannot give an estimate with an error bar.
pub fn validate(spec: &LightTracerSpec) -> Result<(), LightTracerError> {
    let bad = |what: &str| Err(LightTracerError::Settings(what.into()));
    if spec.batches < 2 {
        return bad("at least 2 batches (the error bar is their spread)");
    }
    if spec.photons == 0 {
        return bad("photons per batch must be positive");
    }
    if spec.photons > MAX_PHOTONS {
        return bad("photons per batch must be at most 2^40 (1.1e12)");
    }
    if !(1..=MAX_SIDE).contains(&spec.width) || !(1..=MAX_SIDE).contains(&spec.height) {
        return bad("the image sides must be 1..=16384 pixels");
    }
    Ok(())
}

/// Most photons per batch: 2^40, days of tracing on any host; the memory a batch holds
/// does not grow with them ([`CHUNK_GROUP`]).
const MAX_PHOTONS: u64 = 1 << 40;

/// Host bytes the tracer holds per pixel: its pixel table and silhouette flag, the batch's
/// image and the two sums over batches (f64 RGB each), and the mean and error images.
const BYTES_PER_PIXEL: usize = std::mem::size_of::<Option<PixelSee>>()
    + std::mem::size_of::<bool>()
    + 3 * std::mem::size_of::<[f64; 3]>()
    + 2 * std::mem::size_of::<[f32; 4]>();

/// Checks that the host can hold the images of `n` pixels before any is made: one
/// reservation of their total, refused where the allocator cannot give it.
fn check_image_memory(n: usize) -> Result<(), LightTracerError> {
    let bytes = n.saturating_mul(BYTES_PER_PIXEL);
    let mut probe: Vec<u8> = Vec::new();
    probe.try_reserve_exact(bytes).map_err(|_| {
        LightTracerError::Settings(format!(
            "out of memory: the image's {n} pixels need {bytes} bytes of host memory"
        ))
    })
}

/// `n` zeroed f64 RGB pixels, or an out-of-memory error naming `what`.
fn zeroed_image(n: usize, what: &str) -> Result<Vec<[f64; 3]>, LightTracerError> {
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| {
        LightTracerError::Settings(format!("out of memory allocating the {what} ({n} pixels)"))
    })?;
    v.resize(n, [0.0; 3]);
    Ok(v)
}

/// A work item's (pixel, radiance) contributions in photon order.
type Contributions = Vec<(u32, [f64; 3])>;

/// Photons per parallel work item.
const CHUNK: u64 = 8192;

/// Work items traced in parallel per rayon thread before their contributions are added
/// to the image (in photon order): what a batch holds at once is at most this many items'
/// contributions a thread, whatever its photon count.
const CHUNK_GROUP: u64 = 16;

/// Computes the light-tracer reference of `scene` (its camera at `spec`'s size);
/// `progress(batches_done, batches, noise)` after each batch.
pub fn compute(
    scene: &Scene,
    spec: &LightTracerSpec,
    progress: &mut dyn FnMut(u32, u32, f64),
) -> Result<LightTracerReference, LightTracerError> {
    validate(spec)?;
    let n = (spec.width * spec.height) as usize;
    check_image_memory(n)?;
    let g = Geometry::build(scene, spec.spheres)?;
    let cam = Cam::new(&scene.camera, spec.width, spec.height);
    let (table, silhouette) = pixel_table(&g, &cam);
    let lights = emitters(scene, &g);
    let dispersive = g
        .mats
        .iter()
        .any(|m| matches!(m, Mat::Dielectric { ior, .. } if ior.dispersive()));
    let colour = SpectralColour::new();
    let mut sum = zeroed_image(n, "sum over batches")?;
    let mut sum2 = zeroed_image(n, "sum of squares over batches")?;
    let mut img = zeroed_image(n, "batch image")?;
    let (mut photons, mut connected, mut truncated) = (0u64, 0u64, 0u64);
    let mut noise = f64::INFINITY;
    let chunks = spec.photons.div_ceil(CHUNK);
    let group = CHUNK_GROUP * rayon::current_num_threads().max(1) as u64;
    let groups = (0..chunks).step_by(group as usize);
    for batch in 0..spec.batches {
        img.fill([0.0; 3]);
        for (li, light) in lights.iter().enumerate() {
            for first in groups.clone() {
                let parts: Vec<(Contributions, u64)> = (first..(first + group).min(chunks))
                    .into_par_iter()
                    .map(|ci| {
                        let mut out = Vec::new();
                        let mut trunc = 0u64;
                        let end = ((ci + 1) * CHUNK).min(spec.photons);
                        for i in ci * CHUNK..end {
                            let key = [spec.seed, batch as u64, li as u64, i, 0];
                            let mut rng = Rng::new(key);
                            let Some((o, d, flux)) = light.emit(spec.photons, &mut rng) else {
                                continue;
                            };
                            // (wavelength, flux) of each pass: one without dispersion, else
                            // three (stratified wavelengths, or the three bands)
                            let offset = rng.next();
                            let passes: Vec<(Option<f64>, [f64; 3])> = if !dispersive {
                                vec![(None, flux)]
                            } else {
                                (0..3)
                                    .map(|k| match spec.dispersion {
                                        Dispersion::ThreeBands => {
                                            let mut f = [0.0; 3];
                                            f[k] = flux[k];
                                            (Some(CHANNEL_UM[k]), f)
                                        }
                                        Dispersion::Spectral => {
                                            let l = 0.38 + 0.4 * (k as f64 + offset) / 3.0;
                                            let w = colour.weight(l);
                                            (Some(l), std::array::from_fn(|c| flux[c] * w[c] / 3.0))
                                        }
                                    })
                                    .collect()
                            };
                            for (pi, &(wl, flux)) in passes.iter().enumerate() {
                                let mut rng =
                                    Rng::new([key[0], key[1], key[2], key[3], 1 + pi as u64]);
                                match trace(&g, o, d, flux, wl, spec.max_specular, &mut rng) {
                                    PathEnd::Truncated => trunc += 1,
                                    PathEnd::Lost => {}
                                    PathEnd::Stored { hit, dir, flux } => {
                                        let c = connect(
                                            &g,
                                            &cam,
                                            &table,
                                            &hit,
                                            dir,
                                            flux,
                                            spec.silhouette,
                                        );
                                        if let Some(c) = c {
                                            out.push(c);
                                        }
                                    }
                                }
                            }
                        }
                        (out, trunc)
                    })
                    .collect();
                for (out, trunc) in parts {
                    truncated += trunc;
                    connected += out.len() as u64;
                    for (p, c) in out {
                        for k in 0..3 {
                            img[p as usize][k] += c[k];
                        }
                    }
                }
            }
            photons += spec.photons * if dispersive { 3 } else { 1 };
        }
        for i in 0..n {
            for c in 0..3 {
                sum[i][c] += img[i][c];
                sum2[i][c] += img[i][c] * img[i][c];
            }
        }
        noise = super::relative_standard_error(&sum, &sum2, batch + 1);
        progress(batch + 1, spec.batches, noise);
    }
    let k = spec.batches as f64;
    let mean: Vec<[f32; 4]> = sum
        .iter()
        .map(|s| [(s[0] / k) as f32, (s[1] / k) as f32, (s[2] / k) as f32, 1.0])
        .collect();
    let err: Vec<[f32; 4]> = sum
        .iter()
        .zip(&sum2)
        .map(|(s, s2)| {
            let e = |c: usize| {
                let m = s[c] / k;
                (((s2[c] / k - m * m) * k / (k - 1.0)).max(0.0) / k).sqrt() as f32
            };
            [e(0), e(1), e(2), 1.0]
        })
        .collect();
    Ok(LightTracerReference {
        image: Image::new(spec.width, spec.height, mean),
        std_error: Image::new(spec.width, spec.height, err),
        silhouette,
        info: LightTracerInfo {
            scene: scene.name.clone(),
            scene_hash: light_tracer_hash(scene, spec),
            spec: spec.clone(),
            photons,
            connected,
            truncated,
            noise,
        },
    })
}

/// The pixel and radiance contribution of a photon stored at `hit`, arriving along
/// `dir`, or None when the eye does not see it on the surface its pixel sees.
fn connect(
    g: &Geometry,
    cam: &Cam,
    table: &[Option<PixelSee>],
    hit: &Hit,
    dir: DVec3,
    flux: [f64; 3],
    silhouette: SilhouetteDefinition,
) -> Option<(u32, [f64; 3])> {
    let p = cam.pixel(hit.p)?;
    let see = table[p]?;
    if see.obj != hit.obj {
        return None;
    }
    let to_eye = cam.pos - hit.p;
    // lit side and seen side the same
    if dir.dot(hit.ng) * to_eye.dot(hit.ng) >= 0.0 {
        return None;
    }
    let dist = to_eye.length();
    let w = to_eye / dist;
    let o = g.offset(hit, w);
    if silhouette == SilhouetteDefinition::EyeVisible
        && g.intersect(o, w, (cam.pos - o).length()).is_some()
    {
        return None;
    }
    Some((p as u32, std::array::from_fn(|c| flux[c] * see.scale[c])))
}

/// The file name of the light-tracer reference of `scene` under `spec` where `dir` lacks
/// it; `None` where [`load_or_compute`] would load it.
pub fn missing_from_cache(dir: &Path, scene: &Scene, spec: &LightTracerSpec) -> Option<String> {
    let hash = light_tracer_hash(scene, spec);
    let (exr, json) = paths(dir, &scene.name, &format!("light-tracer-{hash}"));
    match cached_sidecar::<LightTracerInfo>(&exr, &json, &hash, |i| &i.scene_hash) {
        Some(_) => None,
        None => Some(file_name(&exr)),
    }
}

/// Loads the cached light-tracer reference of `scene` from `dir`, or computes and caches
/// it (EXR of the mean, EXR of the per-pixel standard error, JSON sidecar).
pub fn load_or_compute(
    dir: &Path,
    scene: &Scene,
    spec: &LightTracerSpec,
    progress: &mut dyn FnMut(u32, u32, f64),
) -> Result<(Image, LightTracerInfo), LightTracerError> {
    let hash = light_tracer_hash(scene, spec);
    let (exr_path, json_path) = paths(dir, &scene.name, &format!("light-tracer-{hash}"));
    let err_path = exr_path.with_extension("stderr.exr");
    if let Some(info) =
        cached_sidecar::<LightTracerInfo>(&exr_path, &json_path, &hash, |i| &i.scene_hash)
    {
        return Ok((read_exr(&exr_path).map_err(LightTracerError::Cache)?, info));
    }
    validate(spec)?;
    // the cache must take the result before the work begins
    crate::output::prepare_folder(dir).map_err(LightTracerError::Cache)?;
    let r = compute(scene, spec, progress)?;
    crate::output::write_exr(&exr_path, &r.image).map_err(LightTracerError::Cache)?;
    crate::output::write_exr(&err_path, &r.std_error).map_err(LightTracerError::Cache)?;
    let text = serde_json::to_string_pretty(&r.info)
        .map_err(|e| LightTracerError::Cache(format!("{}: {e}", json_path.display())))?;
    crate::output::write_file(&json_path, text.as_bytes()).map_err(LightTracerError::Cache)?;
    Ok((r.image, r.info))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An image no host can hold is refused before anything is made, with its size.
    #[test]
    fn images_past_the_hosts_memory_are_an_error() {
        let e = check_image_memory(usize::MAX / 4).expect_err("refused");
        assert!(e.to_string().contains("out of memory"), "{e}");
        assert!(check_image_memory(480 * 270).is_ok());
        assert!(zeroed_image(usize::MAX / 4, "test").is_err());
    }

    #[test]
    fn same_result_for_any_thread_count() {
        let scene = caustica_core::scene::builtin::sphere();
        let spec = LightTracerSpec {
            width: 16,
            height: 9,
            photons: 20_000,
            batches: 2,
            spheres: SphereModel::Mesh,
            ..LightTracerSpec::default()
        };
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| compute(&scene, &spec, &mut |_, _, _| {}).unwrap())
        };
        let (a, b) = (run(1), run(3));
        assert!(a.info.connected > 0);
        assert_eq!(a.image.pixels, b.image.pixels);
        assert_eq!(a.info, b.info);
    }

    #[test]
    fn fresnel_normal_incidence_and_tir() {
        // (n - 1)^2 / (n + 1)^2 = 0.04 for n = 1.5, either way through the interface
        let (r, t) = fresnel(-DVec3::Y, DVec3::Y, 1.0 / 1.5);
        assert!((r - 0.04).abs() < 1e-12 && (t.unwrap() + DVec3::Y).length() < 1e-12);
        let (r, _) = fresnel(-DVec3::Y, DVec3::Y, 1.5);
        assert!((r - 0.04).abs() < 1e-12);
        // past the critical angle asin(1/1.5) = 41.8 deg: total reflection
        let d = DVec3::new(0.8, -0.6, 0.0);
        assert_eq!(fresnel(d, DVec3::Y, 1.5), (1.0, None));
        // Snell: eta sin_i = sin_t
        let (_, t) = fresnel(d, DVec3::Y, 1.0 / 1.5);
        assert!((t.unwrap().x - 0.8 / 1.5).abs() < 1e-12);
    }
}

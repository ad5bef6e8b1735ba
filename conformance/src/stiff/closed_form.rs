//! Bounds the stiff cases compute independently of the ray tracer: the stratified photon
//! grid's boundary bound, solid angles, tessellation shortfall, Fresnel averages.

use caustica_core::math::optics::fresnel_dielectric;

/// Photons of a `pw x ph` stratified grid (one per cell) that can fall on either side of
/// `curves` boundary curves, each made of at most two pieces monotone in both grid
/// coordinates: such a piece crosses at most `pw + ph` cells, and only a crossed cell's
/// photon can land on the "wrong" side of the expectation.
pub(super) fn grid_bound(pw: u32, ph: u32, curves: u32) -> f64 {
    (2 * curves * (pw + ph)) as f64
}

/// Solid angle (sr) of a ball of radius `r` seen from distance `d` to its centre:
/// `2 pi (1 - cos)` with `1 - cos = x / (1 + sqrt(1 - x))`, `x = (r / d)^2` (no
/// cancellation for a far ball).
pub(super) fn ball_solid_angle(r: f64, d: f64) -> f64 {
    let x = (r / d).powi(2);
    std::f64::consts::TAU * x / (1.0 + (1.0 - x).sqrt())
}

/// Relative shortfall of a UV sphere of `segments` from its true silhouette: vertices lie
/// on the sphere, edges inside it, by at most `1 - cos(pi / segments)` of the radius on
/// the equator; twice that in area.
pub(super) fn tessellation_rel(segments: u32) -> f64 {
    2.0 * (1.0 - (std::f64::consts::PI / segments as f64).cos())
}

/// The segments of `scene`'s first sphere shape (3, the coarsest tessellation, when it has
/// none: the largest [`tessellation_rel`]).
pub(super) fn sphere_segments(scene: &caustica_core::scene::Scene) -> u32 {
    scene
        .objects
        .iter()
        .find_map(|o| match o.shape {
            caustica_core::scene::Shape::Sphere { segments, .. } => Some(segments.max(3)),
            _ => None,
        })
        .unwrap_or(3)
}

/// Mean of `g(F(theta))` over a disk of parallel rays hitting a ball (impact parameter
/// `b = sin(theta)`, uniform in area: weight `2 sin cos dtheta`), in f64.
pub(super) fn disk_mean(ior: f32, g: impl Fn(f64) -> f64) -> f64 {
    let n = 20_000;
    let mut sum = 0.0;
    for i in 0..n {
        let b = (i as f64 + 0.5) / n as f64; // sin(theta), uniform b^2 in area
        let w = 2.0 * b / n as f64;
        let cos_i = (1.0 - b * b).sqrt();
        sum += w * g(fresnel_dielectric(cos_i as f32, 1.0 / ior) as f64);
    }
    sum
}

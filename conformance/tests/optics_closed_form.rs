//! Whole-technique checks against closed forms computed independently of the ray tracer.

use caustica_conformance::render;
use caustica_core::backend::read_buf;
use caustica_core::math::packing::unpack_unit_vector;
use caustica_core::scene::{builtin, Aabb, Light};
use caustica_core::{FrameSettings, TechniqueSettings};
use caustica_core::{Sspm, SspmSettings};
use caustica_cpu::CpuBackend;
use glam::Vec3;

/// sphere-sun with a projection volume of half-width 0.05 around the axis: paraxial rays
/// (height h <= 0.07 R). Each stored photon's last segment crosses the axis (rays stay in
/// meridional planes); the mean crossing height must be the ball-lens back focus
/// f = n R / (2 (n - 1)) = 0.75 below the centre, y = 0.25.
/// Tolerance 0.01 (1.3% of f): spherical aberration at h = 0.07 R shifts the focus by
/// ~ (h/R)^2 * f * 0.5 ≈ 0.002 towards the lens; the 192-segment tessellation perturbs
/// interpolated normals by < 1e-3 rad, moving crossings by < 0.75 * 2e-3; octahedral
/// direction packing adds < 1e-4 rad.
#[test]
fn ball_lens_focus_matches_paraxial_optics() {
    let mut scene = builtin::sphere_sun();
    if let Light::Directional {
        projection_volume, ..
    } = &mut scene.lights[0]
    {
        *projection_volume = Some(Aabb {
            min: Vec3::new(-0.05, 0.45, -0.05),
            max: Vec3::new(0.05, 1.55, 0.05),
        });
    }
    let mut b = CpuBackend::new().unwrap();
    let settings = SspmSettings {
        frame: FrameSettings {
            photons_w: 64,
            photons_h: 64,
            ..SspmSettings::default().frame
        },
        // the stored photons are what this test reads
        fused_deposit: false,
        ..SspmSettings::default()
    };
    let mut s = Sspm::new(&mut b, &scene, settings).unwrap();
    s.frame(&mut b, &mut |_| {}).unwrap();
    let (photons, count) = s.photon_buffers().unwrap();
    let n = read_buf(&mut b, count).unwrap()[0] as usize;
    let photons = read_buf(&mut b, photons).unwrap();
    let mut sum = 0.0f64;
    let mut k = 0;
    for ph in &photons[..n] {
        let p = Vec3::from(ph.position);
        let d = unpack_unit_vector(ph.direction);
        let rho = (p.x * p.x + p.z * p.z).sqrt();
        let drho = (p.x * d.x + p.z * d.z) / rho.max(1e-9); // radial component of d
        if drho < -1e-4 || rho < 1e-6 {
            continue; // not diverging from the axis after the focus (e.g. internal reflections)
        }
        let s_back = rho / drho.max(1e-9); // distance back along the ray to the axis
        sum += (p.y - s_back * d.y) as f64;
        k += 1;
    }
    assert!(k > 1000, "only {k} usable photons");
    let focus = sum / k as f64;
    assert!(
        (focus - 0.25).abs() < 0.01,
        "focus at y = {focus}, paraxial optics says 0.25"
    );
}

/// The flux the `sphere` caustic stores equals what an independent integration over the
/// analytic sphere predicts. The light is on the axis above the centre, so every photon
/// path stays in its meridional plane: an f64 2-D tracer written here (its own Snell and
/// Fresnel) follows the external reflection (weight F) and up to 6 internal chords (exit k
/// leaves with (1 - F)^2 F^(k-1), Stokes), each outgoing ray to the plane y = 0, counted
/// when it lands inside the 4 x 4 square (azimuth integrated numerically).
/// Tolerance 2%: Monte Carlo noise of the ~10k photons reaching the sphere through the
/// stratified 512^2 cone (stratification keeps it well below 1%), tessellation of the
/// sphere (area and normals, ~0.1%), paths beyond 6 internal chords (F^6 < 1e-6).
#[test]
fn sphere_caustic_flux_matches_numerical_integration() {
    let scene = builtin::sphere();
    let mut b = CpuBackend::new().unwrap();
    let settings = SspmSettings::default().with_photons(512, 512);
    let (stats, _) = render(&mut b, &scene, settings, 64, 36);
    let measured = stats.stored_flux[0];

    let (n, r0, c, lpos, intensity) = (
        1.5f64,
        0.5f64,
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, 3.0, 0.0),
        10.0f64,
    );
    let d_lc = (lpos - c).length() as f64; // 2
    let theta_max = (r0 / d_lc).asin();
    let (nt, nphi) = (4000, 256);
    let mut expected = 0.0f64;
    for it in 0..nt {
        let theta = (it as f64 + 0.5) / nt as f64 * theta_max;
        let d_omega = 2.0 * std::f64::consts::PI * theta.sin() * (theta_max / nt as f64);
        // 2D meridional plane: light at (0, 2) relative to the centre, ray direction
        // (sin theta, -cos theta) in (x, y).
        let o = [0.0, d_lc];
        let dir = [theta.sin(), -theta.cos()];
        let bq = o[0] * dir[0] + o[1] * dir[1];
        let disc = bq * bq - (d_lc * d_lc - r0 * r0);
        if disc < 0.0 {
            continue;
        }
        let t = -bq - disc.sqrt();
        let p = [o[0] + t * dir[0], o[1] + t * dir[1]];
        let nrm = [p[0] / r0, p[1] / r0];
        // Independent f64 2-D tracer: external reflection, then internal chords, each exit
        // transmitting (1 - F) and reflecting F (Stokes: the same F inside and outside).
        let refl = |d: [f64; 2], m: [f64; 2]| {
            let k = d[0] * m[0] + d[1] * m[1];
            [d[0] - 2.0 * k * m[0], d[1] - 2.0 * k * m[1]]
        };
        // Snell with m facing the incoming ray and eta = n_i / n_t.
        let refr = |d: [f64; 2], m: [f64; 2], eta: f64| -> Option<[f64; 2]> {
            let ci = -(d[0] * m[0] + d[1] * m[1]);
            let ct2 = 1.0 - eta * eta * (1.0 - ci * ci);
            (ct2 >= 0.0).then(|| {
                let ct = ct2.sqrt();
                [
                    eta * d[0] + (eta * ci - ct) * m[0],
                    eta * d[1] + (eta * ci - ct) * m[1],
                ]
            })
        };
        let fres = |ci: f64, eta: f64| -> f64 {
            let ct2 = 1.0 - eta * eta * (1.0 - ci * ci);
            if ct2 <= 0.0 {
                return 1.0;
            }
            let ct = ct2.sqrt();
            let rs = (eta * ci - ct) / (eta * ci + ct);
            let rp = (ci - eta * ct) / (ci + eta * ct);
            0.5 * (rs * rs + rp * rp)
        };
        let cos_i = -(dir[0] * nrm[0] + dir[1] * nrm[1]);
        let f = fres(cos_i, 1.0 / n);
        let mut outs = vec![(p, refl(dir, nrm), f)];
        let mut d_in = refr(dir, nrm, 1.0 / n).unwrap();
        let mut at = p;
        let mut w = 1.0 - f;
        for _ in 0..6 {
            let tq = -2.0 * (at[0] * d_in[0] + at[1] * d_in[1]);
            let q = [at[0] + tq * d_in[0], at[1] + tq * d_in[1]];
            let inward = [-q[0] / r0, -q[1] / r0];
            let ci = -(d_in[0] * inward[0] + d_in[1] * inward[1]);
            let fi = fres(ci, n);
            if let Some(d_out) = refr(d_in, inward, n) {
                outs.push((q, d_out, w * (1.0 - fi)));
            }
            w *= fi;
            d_in = refl(d_in, inward);
            at = q;
        }
        for (q, d, w) in outs {
            if d[1] >= 0.0 {
                continue; // goes up: never reaches the plane
            }
            // to the plane y = -1 relative to the centre
            let s = (-1.0 - q[1]) / d[1];
            let rad = q[0] + s * d[0]; // signed radial coordinate in the meridional plane
            let mut inside = 0;
            for ip in 0..nphi {
                let phi = (ip as f64 + 0.5) / nphi as f64 * std::f64::consts::TAU;
                let (x, z) = (rad * phi.cos(), rad * phi.sin());
                if x.abs() <= 2.0 && z.abs() <= 2.0 {
                    inside += 1;
                }
            }
            expected += intensity * d_omega * w * inside as f64 / nphi as f64;
        }
    }
    let rel = (measured - expected).abs() / expected;
    assert!(
        rel < 0.02,
        "stored flux {measured} W vs integrated {expected} W ({:.2}%)",
        rel * 100.0
    );
}

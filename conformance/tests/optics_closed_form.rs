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

/// `prism` with `frame.dispersion` three bands splits its beam into three separated bands on
/// the screen, where Snell's law puts them. Closed form (f64, written here): the beam is parallel and every face flat, so each
/// channel `c` leaves the prism along one direction: incidence `i` on the first face,
/// `sin r1 = sin i / n_c`, `r2 = A - r1` at the second (apex angle `A` = 60 deg),
/// `sin e = n_c sin r2`, deviation `D = i + e - A`, with `n_c = a + b / lambda_c^2` (Cauchy,
/// `a = 1.5 - b / 0.55^2`). The ray through the slit's centre, traced through the two faces
/// to the screen, is where the band's centroid lands: the map from a point of the slit to
/// the screen is affine (planes only), so the centroid of uniformly spread photons lands
/// where the centre does.
///
/// Checked on the photons the CPU backend stores on the screen (the room light removed,
/// so that every photon there came through the slit), each carrying one channel:
/// - every photon of channel `c` arrives along the closed-form direction within 2e-4 rad
///   (the octahedral packing of the stored direction errs by < 1e-4 rad; f32 refraction
///   adds ~1e-6);
/// - the flux-weighted centroid of the band's heights is the closed-form height within five
///   standard errors of a mean of `N_c` points uniform over the band's measured extent
///   `H_c` (`5 H_c / sqrt(12 N_c)`: which photon takes which channel, and which reflects,
///   is random), plus 1e-5 for f32 positions;
/// - the three bands do not overlap: red above green above blue, with a gap between each.
#[test]
fn prism_bands_land_where_snells_law_puts_them() {
    use caustica_core::math::optics::CHANNEL_WAVELENGTH_UM;
    use caustica_core::scene::builtin::{PRISM_SCREEN_X, PRISM_SLIT_X, PRISM_SLIT_Y};
    use caustica_core::scene::{Camera, Material, Shape};

    let mut scene = builtin::prism();
    scene.lights.truncate(1); // the beam only
    let Light::Directional { direction, .. } = scene.lights[0] else {
        panic!("prism's first light is its beam");
    };
    // a camera facing the screen, so that Sspm stores every photon on it
    scene.camera = Camera {
        position: Vec3::new(0.5, 0.35, 0.0),
        target: Vec3::new(PRISM_SCREEN_X, 0.35, 0.0),
        up: Vec3::Y,
        fov_y_deg: 60.0,
        width: 320,
        height: 180,
    };
    let (center, side) = scene
        .objects
        .iter()
        .find_map(|o| match o.shape {
            Shape::Prism { center, side, .. } => Some((center, side)),
            _ => None,
        })
        .expect("a prism");
    let Some(Material::Dielectric { ior, cauchy_b, .. }) = scene.materials.get("flint") else {
        panic!("flint is a dielectric");
    };
    let (ior, b) = (*ior as f64, *cauchy_b as f64);

    // --- closed form, in the xy plane ------------------------------------------------
    let apex = 60f64.to_radians();
    let (cx, cy, s) = (center.x as f64, center.y as f64, side as f64);
    let h = s * 3f64.sqrt() / 2.0;
    let (left, right, top) = (
        [cx - s / 2.0, cy - h / 3.0],
        [cx + s / 2.0, cy - h / 3.0],
        [cx, cy + 2.0 * h / 3.0],
    );
    // outward normals of the faces the beam crosses
    let n1 = [-(30f64.to_radians().cos()), 30f64.to_radians().sin()];
    let n2 = [30f64.to_radians().cos(), 30f64.to_radians().sin()];
    let d0 = {
        let l = (direction.x as f64).hypot(direction.y as f64);
        [direction.x as f64 / l, direction.y as f64 / l]
    };
    let dot = |a: [f64; 2], b: [f64; 2]| a[0] * b[0] + a[1] * b[1];
    // where the line o + t d meets the line through p and q
    let meet = |o: [f64; 2], d: [f64; 2], p: [f64; 2], q: [f64; 2]| {
        let e = [q[0] - p[0], q[1] - p[1]];
        let den = d[0] * e[1] - d[1] * e[0];
        let t = ((p[0] - o[0]) * e[1] - (p[1] - o[1]) * e[0]) / den;
        [o[0] + t * d[0], o[1] + t * d[1]]
    };
    // the unit vector at angle `a` (radians) from the x axis
    let at = |a: f64| [a.cos(), a.sin()];
    let incidence = (-dot(d0, n1)).acos();
    let cauchy_a = ior - b / (0.55 * 0.55);
    let mut want = Vec::new(); // per channel: exit direction, height on the screen
    for lambda in CHANNEL_WAVELENGTH_UM {
        let n = cauchy_a + b / (lambda as f64 * lambda as f64);
        let r1 = (incidence.sin() / n).asin();
        let r2 = apex - r1;
        let e = (n * r2.sin()).asin();
        let deviation = incidence + e - apex;
        // the beam's angle from the x axis, turned clockwise by the deviation
        let out_angle = d0[1].atan2(d0[0]) - deviation;
        // inside: the refracted ray makes r1 with the inward normal, on the incident side
        let inward = (-n1[1]).atan2(-n1[0]);
        let in_angle = inward + r1 * (d0[1].atan2(d0[0]) - inward).signum();
        let p1 = meet([PRISM_SLIT_X as f64, PRISM_SLIT_Y as f64], d0, left, top);
        let p2 = meet(p1, at(in_angle), right, top);
        // Snell at the second face, checked against the deviation formula
        let d_in = at(in_angle);
        assert!(
            ((-dot(d_in, [-n2[0], -n2[1]])).acos().abs() - r2).abs() < 1e-9,
            "the internal ray meets the second face at r2"
        );
        let d_out = at(out_angle);
        let y = p2[1] + (PRISM_SCREEN_X as f64 - p2[0]) * d_out[1] / d_out[0];
        want.push((d_out, y));
    }

    // --- the traced photons ----------------------------------------------------------
    let mut be = CpuBackend::new().unwrap();
    let settings = SspmSettings {
        frame: FrameSettings {
            photons_w: 256,
            photons_h: 256,
            // the publications' three-way split (the spectral default is checked below)
            dispersion: caustica_core::Dispersion::ThreeBands,
            ..SspmSettings::default().frame
        },
        trace: caustica_core::TraceSettings {
            // one batch: the stored buffer holds every photon
            max_photons_per_batch: 1 << 20,
            ..SspmSettings::default().trace
        },
        fused_deposit: false,
        ..SspmSettings::default()
    };
    let mut t = Sspm::new(&mut be, &scene, settings).unwrap();
    t.frame(&mut be, &mut |_| {}).unwrap();
    let (photons, count) = t.photon_buffers().unwrap();
    let n = read_buf(&mut be, count).unwrap()[0] as usize;
    let photons = read_buf(&mut be, photons).unwrap();
    // per channel: flux, flux-weighted height, count, lowest and highest height
    let mut bands = [(0.0f64, 0.0f64, 0usize, f64::MAX, f64::MIN); 3];
    for ph in &photons[..n] {
        if (ph.position[0] - PRISM_SCREEN_X).abs() > 1e-3 {
            continue; // not on the screen
        }
        let lit: Vec<usize> = (0..3).filter(|&c| ph.flux[c] > 0.0).collect();
        assert_eq!(
            lit.len(),
            1,
            "a photon through the prism carries one channel: {ph:?}"
        );
        let c = lit[0];
        let d = unpack_unit_vector(ph.direction);
        let (wd, _) = want[c];
        let off = (d.x as f64 * wd[1] - d.y as f64 * wd[0])
            .atan2(d.x as f64 * wd[0] + d.y as f64 * wd[1])
            .abs()
            .max((d.z as f64).abs().asin());
        assert!(
            off < 2e-4,
            "channel {c}: a photon arrives {off:.2e} rad off Snell's direction ({d})"
        );
        let (f, y) = (ph.flux[c] as f64, ph.position[1] as f64);
        let band = &mut bands[c];
        band.0 += f;
        band.1 += f * y;
        band.2 += 1;
        band.3 = band.3.min(y);
        band.4 = band.4.max(y);
    }
    for (c, &(f, fy, count, lo, hi)) in bands.iter().enumerate() {
        assert!(
            count > 1000,
            "channel {c}: only {count} photons on the screen"
        );
        let centroid = fy / f;
        let tol = 5.0 * (hi - lo) / (12.0 * count as f64).sqrt() + 1e-5;
        let (_, y) = want[c];
        eprintln!(
            "channel {c}: {count} photons, band {lo:.4}..{hi:.4}, centroid {centroid:.5}, Snell {y:.5} (tolerance {tol:.1e})"
        );
        assert!(
            (centroid - y).abs() < tol,
            "channel {c}: band centroid at y = {centroid:.5}, Snell's law puts it at {y:.5}"
        );
    }
    for c in 0..2 {
        assert!(
            bands[c].3 > bands[c + 1].4,
            "bands {c} and {} overlap: {:?} and {:?}",
            c + 1,
            bands[c],
            bands[c + 1]
        );
    }
    let spread = (want[0].0[1].atan2(want[0].0[0]) - want[2].0[1].atan2(want[2].0[0])).to_degrees();
    eprintln!("red to blue: {spread:.3} deg apart");
    t.free(&mut be).unwrap();
}

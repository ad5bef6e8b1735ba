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
/// ~ (h/R)^2 * f * 0.5 ≈ 0.002 towards the lens; the 384-segment tessellation perturbs
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

/// `prism` with its beam alone (the room light removed, so that every photon on the screen
/// came through the slit), a camera facing the screen (so that Sspm stores every photon
/// there), and the closed form of its optics in f64, written here: the beam is parallel
/// and every face flat, so light of index `n` leaves the prism along one direction:
/// incidence `i` on the first face, `sin r1 = sin i / n`, `r2 = A - r1` at the second (apex
/// angle `A` = 60 deg), `sin e = n sin r2`, deviation `D = i + e - A`. The ray through the
/// slit's centre, traced through the two faces to the screen, is where the light of that
/// index centres: the map from a point of the slit to the screen is affine (planes only).
struct PrismBeam {
    scene: caustica_core::scene::Scene,
    /// The flint's index at 550 nm and Cauchy B (um^2).
    ior: f64,
    b: f64,
    /// Beam direction in the xy plane (unit).
    d0: [f64; 2],
    /// Outward normals of the faces the beam crosses.
    n1: [f64; 2],
    n2: [f64; 2],
    /// The prism's corners in the xy plane.
    left: [f64; 2],
    right: [f64; 2],
    top: [f64; 2],
}

fn dot2(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}

/// Where the line `o + t d` meets the line through `p` and `q`.
fn meet(o: [f64; 2], d: [f64; 2], p: [f64; 2], q: [f64; 2]) -> [f64; 2] {
    let e = [q[0] - p[0], q[1] - p[1]];
    let den = d[0] * e[1] - d[1] * e[0];
    let t = ((p[0] - o[0]) * e[1] - (p[1] - o[1]) * e[0]) / den;
    [o[0] + t * d[0], o[1] + t * d[1]]
}

/// The unit vector at angle `a` (radians) from the x axis.
fn at(a: f64) -> [f64; 2] {
    [a.cos(), a.sin()]
}

/// Exact unpolarised Fresnel reflectance, `eta = n_i / n_t`.
fn fresnel(ci: f64, eta: f64) -> f64 {
    let ct2 = 1.0 - eta * eta * (1.0 - ci * ci);
    if ct2 <= 0.0 {
        return 1.0;
    }
    let ct = ct2.sqrt();
    let rs = (eta * ci - ct) / (eta * ci + ct);
    let rp = (ci - eta * ct) / (ci + eta * ct);
    0.5 * (rs * rs + rp * rp)
}

impl PrismBeam {
    fn new() -> PrismBeam {
        use caustica_core::scene::builtin::PRISM_SCREEN_X;
        use caustica_core::scene::{Camera, Material, Shape};
        let mut scene = builtin::prism();
        scene.lights.truncate(1); // the beam only
        let Light::Directional { direction, .. } = scene.lights[0] else {
            panic!("prism's first light is its beam");
        };
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
        let (cx, cy, s) = (center.x as f64, center.y as f64, side as f64);
        let h = s * 3f64.sqrt() / 2.0;
        let l = (direction.x as f64).hypot(direction.y as f64);
        PrismBeam {
            scene,
            ior,
            b,
            d0: [direction.x as f64 / l, direction.y as f64 / l],
            n1: [-(30f64.to_radians().cos()), 30f64.to_radians().sin()],
            n2: [30f64.to_radians().cos(), 30f64.to_radians().sin()],
            left: [cx - s / 2.0, cy - h / 3.0],
            right: [cx + s / 2.0, cy - h / 3.0],
            top: [cx, cy + 2.0 * h / 3.0],
        }
    }

    /// The flint's index at `lambda` micrometres (Cauchy, `a = ior - b / 0.55^2`).
    fn index(&self, lambda: f64) -> f64 {
        self.ior - self.b / (0.55 * 0.55) + self.b / (lambda * lambda)
    }

    /// Incidence on the first face and the internal angles `r1`, `r2` for index `n`.
    fn angles(&self, n: f64) -> (f64, f64, f64) {
        let incidence = (-dot2(self.d0, self.n1)).acos();
        let r1 = (incidence.sin() / n).asin();
        (incidence, r1, 60f64.to_radians() - r1)
    }

    /// For index `n`: the exit direction (unit, xy plane) and the height at which the ray
    /// through the slit's centre meets the screen.
    fn exit(&self, n: f64) -> ([f64; 2], f64) {
        self.exit_from(n, caustica_core::scene::builtin::PRISM_SLIT_Y as f64)
    }

    /// [`PrismBeam::exit`] for the ray through the slit at height `slit_y`.
    fn exit_from(&self, n: f64, slit_y: f64) -> ([f64; 2], f64) {
        use caustica_core::scene::builtin::{PRISM_SCREEN_X, PRISM_SLIT_X};
        let (incidence, r1, r2) = self.angles(n);
        let e = (n * r2.sin()).asin();
        let deviation = incidence + e - 60f64.to_radians();
        // the beam's angle from the x axis, turned clockwise by the deviation
        let beam = self.d0[1].atan2(self.d0[0]);
        let out_angle = beam - deviation;
        // inside: the refracted ray makes r1 with the inward normal, on the incident side
        let inward = (-self.n1[1]).atan2(-self.n1[0]);
        let in_angle = inward + r1 * (beam - inward).signum();
        let p1 = meet([PRISM_SLIT_X as f64, slit_y], self.d0, self.left, self.top);
        let p2 = meet(p1, at(in_angle), self.right, self.top);
        // Snell at the second face, checked against the deviation formula
        let d_in = at(in_angle);
        assert!(
            ((-dot2(d_in, [-self.n2[0], -self.n2[1]])).acos().abs() - r2).abs() < 1e-9,
            "the internal ray meets the second face at r2"
        );
        let d_out = at(out_angle);
        let y = p2[1] + (PRISM_SCREEN_X as f64 - p2[0]) * d_out[1] / d_out[0];
        (d_out, y)
    }

    /// The exit direction's angle from the x axis (radians) for index `n`.
    fn exit_angle(&self, n: f64) -> f64 {
        let (d, _) = self.exit(n);
        d[1].atan2(d[0])
    }

    /// The probability that light of index `n` reflects off the second face from inside
    /// (exact Fresnel at incidence `r2`), the first step of every other path.
    fn internal_reflectance(&self, n: f64) -> f64 {
        let (_, _, r2) = self.angles(n);
        fresnel(r2.cos(), n)
    }

    /// The probability that light of index `n` crosses both faces (exact Fresnel at the
    /// incidences `i` and `r2`): the photons that reach the screen straight from the prism.
    fn transmittance(&self, n: f64) -> f64 {
        let (incidence, _, r2) = self.angles(n);
        (1.0 - fresnel(incidence.cos(), 1.0 / n)) * (1.0 - fresnel(r2.cos(), n))
    }

    /// Traces a frame of the beam on the CPU backend with `settings` and returns the
    /// photons stored on the screen.
    fn screen_photons(&self, settings: SspmSettings) -> Vec<caustica_core::device::layout::Photon> {
        use caustica_core::scene::builtin::PRISM_SCREEN_X;
        let mut be = CpuBackend::new().unwrap();
        let mut t = Sspm::new(&mut be, &self.scene, settings).unwrap();
        t.frame(&mut be, &mut |_| {}).unwrap();
        let (photons, count) = t.photon_buffers().unwrap();
        let n = read_buf(&mut be, count).unwrap()[0] as usize;
        let photons = read_buf(&mut be, photons).unwrap();
        t.free(&mut be).unwrap();
        photons[..n]
            .iter()
            .filter(|ph| (ph.position[0] - PRISM_SCREEN_X).abs() <= 1e-3)
            .copied()
            .collect()
    }
}

/// The settings of the prism tests: `w x h` photons in one batch, the photons stored in
/// the buffer (not the fused deposit) and none dropped as negligible (the ends of the
/// spectrum carry ~1e-5 of a photon's flux), `dispersion` as given.
fn prism_settings(w: u32, h: u32, dispersion: caustica_core::Dispersion) -> SspmSettings {
    SspmSettings {
        frame: FrameSettings {
            photons_w: w,
            photons_h: h,
            dispersion,
            ..SspmSettings::default().frame
        },
        trace: caustica_core::TraceSettings {
            max_photons_per_batch: 1 << 20,
            min_relative_power: 0.0,
            ..SspmSettings::default().trace
        },
        fused_deposit: false,
        ..SspmSettings::default()
    }
}

/// The angle (radians) between the stored direction of `ph` and the unit vector `w` in
/// the xy plane, including its tilt out of that plane.
fn off_direction(ph: &caustica_core::device::layout::Photon, w: [f64; 2]) -> f64 {
    let d = unpack_unit_vector(ph.direction);
    (d.x as f64 * w[1] - d.y as f64 * w[0])
        .atan2(d.x as f64 * w[0] + d.y as f64 * w[1])
        .abs()
        .max((d.z as f64).abs().asin())
}

/// `prism` with `frame.dispersion` three bands splits its beam into three separated bands on
/// the screen, where Snell's law puts them ([`PrismBeam`], with `n_c = a + b / lambda_c^2`
/// at the channels' 650, 550 and 450 nm).
///
/// Checked on the photons the CPU backend stores on the screen, each carrying one channel:
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
    let beam = PrismBeam::new();
    let want: Vec<([f64; 2], f64)> = CHANNEL_WAVELENGTH_UM
        .iter()
        .map(|&l| beam.exit(beam.index(l as f64)))
        .collect();
    let settings = SspmSettings {
        trace: caustica_core::TraceSettings {
            // one batch: the stored buffer holds every photon
            max_photons_per_batch: 1 << 20,
            ..SspmSettings::default().trace
        },
        ..prism_settings(256, 256, caustica_core::Dispersion::ThreeBands)
    };
    // per channel: flux, flux-weighted height, count, lowest and highest height
    let mut bands = [(0.0f64, 0.0f64, 0usize, f64::MAX, f64::MIN); 3];
    for ph in beam.screen_photons(settings) {
        let lit: Vec<usize> = (0..3).filter(|&c| ph.flux[c] > 0.0).collect();
        assert_eq!(
            lit.len(),
            1,
            "a photon through the prism carries one channel: {ph:?}"
        );
        let c = lit[0];
        let off = off_direction(&ph, want[c].0);
        assert!(
            off < 2e-4,
            "channel {c}: a photon arrives {off:.2e} rad off Snell's direction"
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
}

/// `prism` (spectral colour, the default) spreads its beam into a continuous spectrum whose
/// angular spread is Snell's law's for the flint's indices at 450 and 650 nm.
///
/// Each photon on the screen left the prism along the closed-form direction of its own
/// wavelength ([`PrismBeam`]); the exit angle rises monotonically with the wavelength (the
/// red is deviated least), so
/// inverting it (bisection in f64) gives each photon's wavelength `l`, to within `dl = 2e-4
/// rad / |d angle / d l|` (the stored direction's packing error, 2e-4 rad, over the
/// dispersion: at most 0.8 nm, at the red end). A photon came straight through the two
/// faces when its exit angle lies between the closed-form angles of 380 and 780 nm (within
/// 2e-4 rad) and its height on the screen between those of the rays through the slit's
/// edges at `l +- dl` (within 1e-4: f32 positions, and the octahedral direction's error
/// over the last face-to-screen leg). Checked:
/// - nearly every photon came straight through: the others reflected off the second face
///   inside the prism first, which a photon does with probability `R(r2(l))` (exact
///   Fresnel), so of `N` photons on the screen at most `m + 5 sqrt(m) + 1` with
///   `m = mean_l R N / (1 - max_l R)` (expected, over uniform wavelengths; binomial, 5
///   standard deviations);
/// - each straight photon's colour is its wavelength's: each channel's share of its flux
///   lies within the range of `wavelength_rgb`'s shares over `l +- dl`, +- 1e-5 (f32 flux
///   products);
/// - the spectrum is continuous: every 10 nm bin of 380-780 nm whose light meets the screen
///   (the deepest violet passes under it, onto the floor) holds photons (three bands would
///   fill three);
/// - the spread: the exit angles at the quantiles `q(450)` and `q(650)` of the photons'
///   angle distribution are the closed-form angles of 450 and 650 nm, and their difference
///   is Snell's spread. `q(l) = int_380^l T / int_380^780 T`, with `T` the closed-form
///   probability of crossing both faces (exact Fresnel) times the fraction of the
///   wavelength's light that meets the screen, because the photons' wavelengths are
///   uniform over 380-780 nm. A
///   quantile of `N` photons errs by at most 5 binomial standard errors `sqrt(q (1 - q) /
///   N)` (Fresnel's choice is random; the wavelength sequence is stratified, which only
///   lowers the error), i.e. by that over the wavelength density `T(l) / int T`; times the
///   angle's slope, plus 2e-4 rad.
#[test]
fn prism_spectrum_spreads_as_snells_law_says() {
    use caustica_core::math::spectrum::wavelength_rgb;
    use caustica_core::scene::builtin::{PRISM_SLIT_HALF_HEIGHT, PRISM_SLIT_Y};
    let beam = PrismBeam::new();
    let angle = |l: f64| beam.exit_angle(beam.index(l));
    let (lo, hi) = (angle(0.38), angle(0.78));
    assert!(lo < hi, "the angle rises with the wavelength");
    // the wavelength whose exit angle is `a`
    let invert = |a: f64| {
        let (mut l0, mut l1) = (0.38f64, 0.78f64);
        for _ in 0..60 {
            let m = 0.5 * (l0 + l1);
            if angle(m) < a {
                l0 = m;
            } else {
                l1 = m;
            }
        }
        0.5 * (l0 + l1)
    };
    let slope = |l: f64| ((angle(l + 1e-5) - angle(l - 1e-5)) / 2e-5).abs();
    let photons = beam.screen_photons(prism_settings(
        256,
        256,
        caustica_core::Dispersion::Spectral,
    ));
    let n = photons.len();
    assert!(n > 3000, "only {n} photons on the screen");
    let mut angles = Vec::with_capacity(n);
    let mut bins = [0u32; 40];
    let mut stray = 0usize;
    for ph in &photons {
        let d = unpack_unit_vector(ph.direction);
        assert!(
            (d.z as f64).abs() < 2e-4,
            "a photon leaves the beam's plane: {d}"
        );
        let a = (d.y as f64).atan2(d.x as f64);
        if !(a > lo - 2e-4 && a < hi + 2e-4) {
            stray += 1;
            continue;
        }
        let l = invert(a.clamp(lo, hi));
        let dl = 2e-4 / slope(l);
        // the heights the straight paths of wavelengths l +- dl reach
        let (mut y_lo, mut y_hi) = (f64::MAX, f64::MIN);
        for wl in [(l - dl).max(0.38), (l + dl).min(0.78)] {
            for edge in [-1.0, 1.0] {
                let slit = (PRISM_SLIT_Y + edge * PRISM_SLIT_HALF_HEIGHT) as f64;
                let (_, y) = beam.exit_from(beam.index(wl), slit);
                (y_lo, y_hi) = (y_lo.min(y), y_hi.max(y));
            }
        }
        let y = ph.position[1] as f64;
        if y < y_lo - 1e-4 || y > y_hi + 1e-4 {
            stray += 1;
            continue;
        }
        bins[(((l - 0.38) / 0.01) as usize).min(39)] += 1;
        // the colour of the wavelengths within dl
        let f: Vec<f64> = ph.flux.iter().map(|&x| x as f64).collect();
        let total: f64 = f.iter().sum();
        assert!(total > 0.0 && f.iter().all(|x| x.is_finite() && *x >= 0.0));
        let mut range = [(f64::MAX, f64::MIN); 3];
        let mut any = false;
        for k in 0..=20 {
            let w = wavelength_rgb((l - dl + 2.0 * dl * k as f64 / 20.0) as f32);
            let s = (w.x + w.y + w.z) as f64;
            if s <= 0.0 {
                continue;
            }
            any = true;
            for c in 0..3 {
                let share = w[c] as f64 / s;
                range[c] = (range[c].0.min(share), range[c].1.max(share));
            }
        }
        if any {
            for c in 0..3 {
                let share = f[c] / total;
                assert!(
                    share >= range[c].0 - 1e-5 && share <= range[c].1 + 1e-5,
                    "a photon at {:.1} nm (+- {:.2}) has channel {c}'s share {share:.5}, its \
                     wavelengths give {:.5}..{:.5}",
                    l * 1000.0,
                    dl * 1000.0,
                    range[c].0,
                    range[c].1
                );
            }
        }
        angles.push(a);
    }
    let r: Vec<f64> = (0..400)
        .map(|i| beam.internal_reflectance(beam.index(0.3805 + 0.001 * i as f64)))
        .collect();
    let (mean, max) = (
        r.iter().sum::<f64>() / r.len() as f64,
        r.iter().fold(0.0f64, |a, b| a.max(*b)),
    );
    let m = mean * n as f64 / (1.0 - max);
    let allowed = m + 5.0 * m.sqrt() + 1.0;
    eprintln!("{stray} of {n} photons reached the screen another way (allowed {allowed:.0})");
    assert!(
        stray as f64 <= allowed,
        "{stray} of {n} photons did not come straight through the prism (allowed {allowed:.0})"
    );
    // the fraction of wavelength l's light that meets the screen rather than the floor
    // (y = 0): the slit maps affinely onto the screen
    let on_screen = |l: f64| {
        let y = |edge: f32| {
            let slit = (PRISM_SLIT_Y + edge * PRISM_SLIT_HALF_HEIGHT) as f64;
            beam.exit_from(beam.index(l), slit).1
        };
        let (a, b) = (y(-1.0).min(y(1.0)), y(-1.0).max(y(1.0)));
        ((b - a.max(0.0)) / (b - a)).clamp(0.0, 1.0)
    };
    let first = (0..40)
        .find(|&k| on_screen(0.38 + 0.01 * k as f64) == 1.0)
        .unwrap();
    eprintln!(
        "from {} nm on, the whole band meets the screen",
        380 + 10 * first
    );
    assert!(
        bins[first..].iter().all(|&b| b > 0),
        "a gap in the spectrum (photons per 10 nm from 380 nm): {bins:?}"
    );
    // quantiles: the fraction of photons below wavelength l, from the closed form
    let t = |l: f64| beam.transmittance(beam.index(l)) * on_screen(l);
    let integral = |a: f64, b: f64| {
        let k = 4000;
        (0..k)
            .map(|i| t(a + (b - a) * (i as f64 + 0.5) / k as f64) * (b - a) / k as f64)
            .sum::<f64>()
    };
    let whole = integral(0.38, 0.78);
    angles.sort_by(f64::total_cmp); // blue (small angles, short wavelengths) first
    let mut measured = [0.0f64; 2];
    for (k, l) in [0.45f64, 0.65].into_iter().enumerate() {
        let q = integral(0.38, l) / whole;
        let got = angles[((q * n as f64) as usize).min(n - 1)];
        let density = t(l) / whole; // of the wavelength, per um
        let dq = 5.0 * (q * (1.0 - q) / n as f64).sqrt() + 1.0 / n as f64;
        let tol = dq / density * slope(l) + 2e-4;
        eprintln!(
            "{:.0} nm: quantile {q:.4}, angle {got:.5} rad, Snell {:.5} (tolerance {tol:.1e})",
            l * 1000.0,
            angle(l)
        );
        assert!(
            (got - angle(l)).abs() <= tol,
            "at {:.0} nm the spectrum leaves at {got:.5} rad, Snell's law says {:.5}",
            l * 1000.0,
            angle(l)
        );
        measured[k] = got;
    }
    let (spread, snell) = (measured[1] - measured[0], angle(0.65) - angle(0.45));
    eprintln!(
        "450 to 650 nm: {:.3} deg apart (Snell {:.3} deg); 380 to 780 nm: {:.3} deg",
        spread.to_degrees(),
        snell.to_degrees(),
        (hi - lo).to_degrees()
    );
}

/// White light through the dispersive prism stores, per channel, the flux the same prism
/// stores without dispersion. Every photon through the slit meets the prism and ends on a
/// diffuse wall (the room is closed in the beam's plane, and the paths stay in that
/// plane), wherever dispersion sends it, so the dispersive frame stores those photons'
/// emitted flux times, per channel, the mean colour weight of their wavelengths; the plain
/// frame stores their emitted flux. The weight's mean over the range is 1
/// (`math::spectrum`), and the photons' wavelengths are `N` points `u_i` of the
/// golden-ratio sequence, so by Koksma-Hlawka their mean weight is 1 within `V_c D*_N`:
/// `V_c` the total variation of channel `c`'s weight over the range, `D*_N` the star
/// discrepancy of those photons' `u_i`, both computed here, the photons found by tracing
/// every grid photon of the plain frame on the CPU (those that meet the prism: stored, or
/// ended by the bounce limit inside it). Allowed besides: the bounce-limited photons'
/// flux (at most the largest weight, 7, each) and the fixed-point rounding of both frames
/// (half a quantum per stored photon).
#[test]
fn prism_white_light_keeps_its_flux_per_channel() {
    use caustica_core::device::device_scene::DeviceScene;
    use caustica_core::math::spectrum::{
        spectral_sample, wavelength_at, wavelength_rgb, MAX_CHANNEL_WEIGHT,
    };
    use caustica_core::scene::Material;
    use caustica_core::techniques::sspm::FrameConstants;
    use caustica_cpu::kernels::trace_photons::{trace_photon, PathEnd};
    use caustica_cpu::traversal::SceneView;

    let beam = PrismBeam::new();
    let mut plain = PrismBeam::new();
    if let Some(Material::Dielectric { cauchy_b, .. }) = plain.scene.materials.get_mut("flint") {
        *cauchy_b = 0.0;
    }
    let settings = prism_settings(512, 512, caustica_core::Dispersion::Spectral);
    let render_stats = |scene: &caustica_core::scene::Scene| {
        let mut be = CpuBackend::new().unwrap();
        let mut t = Sspm::new(&mut be, scene, settings.clone()).unwrap();
        let stats = t.frame(&mut be, &mut |_| {}).unwrap();
        t.free(&mut be).unwrap();
        stats
    };
    let (d, p) = (render_stats(&beam.scene), render_stats(&plain.scene));
    assert_eq!(d.emitted_flux, p.emitted_flux);

    // the photons that meet the prism, traced one by one as the frame traces them
    let ds = DeviceScene::build(&plain.scene, Default::default()).unwrap();
    let constants = FrameConstants::new(&plain.scene, &ds, &settings);
    assert_eq!(constants.domains.len(), 1, "the beam alone emits");
    let (light, domain) = &constants.domains[0];
    let count = settings.frame.photons_w * settings.frame.photons_h;
    let params = constants.trace_params(&settings, *light, domain, 0, count);
    let view = SceneView {
        vertices: &ds.vertices,
        triangles: &ds.triangles,
        materials: &ds.materials,
        lights: &ds.lights,
        nodes: &ds.bvh_nodes,
    };
    let mut u: Vec<f64> = (0..count)
        .filter(|&i| {
            matches!(
                trace_photon(&view, &params, i).0,
                PathEnd::Stored(_) | PathEnd::BounceLimit
            )
        })
        .map(|i| spectral_sample(params.seed, i) as f64)
        .collect();
    let n = u.len();
    assert_eq!(
        n as u64,
        p.photons_stored + p.discarded.bounce_limit,
        "the photons traced one by one are the frame's"
    );
    u.sort_by(f64::total_cmp);
    let star = u
        .iter()
        .enumerate()
        .map(|(i, &x)| ((i as f64 + 1.0) / n as f64 - x).max(x - i as f64 / n as f64))
        .fold(0.0, f64::max);
    // total variation per channel (a 0.01 nm grid: the weight is piecewise monotone
    // between a few dozen extrema, which the grid resolves)
    let mut variation = [0.0f64; 3];
    let mut prev = wavelength_rgb(wavelength_at(0.0));
    for i in 1..=40_000 {
        let w = wavelength_rgb(wavelength_at(i as f32 / 40_000.0));
        for c in 0..3 {
            variation[c] += (w[c] - prev[c]).abs() as f64;
        }
        prev = w;
    }
    let per_photon = p.emitted_flux[0] / p.photons_emitted as f64;
    let bounce_limited = (d.discarded.bounce_limit + p.discarded.bounce_limit) as f64;
    let rounding =
        0.5 * (d.flux_quantum * d.photons_stored as f64 + p.flux_quantum * p.photons_stored as f64);
    for (c, v) in variation.iter().enumerate() {
        let tol = v * star * n as f64 * per_photon
            + bounce_limited * per_photon * MAX_CHANNEL_WEIGHT as f64
            + rounding;
        let diff = d.stored_flux[c] - p.stored_flux[c];
        eprintln!(
            "channel {c}: stored {:.6} W dispersive, {:.6} W plain ({:+.2e} relative; \
             allowed {:.2e}: V {:.2}, D* {star:.2e} over {n} photons)",
            d.stored_flux[c],
            p.stored_flux[c],
            diff / p.stored_flux[c],
            tol / p.stored_flux[c],
            v
        );
        assert!(
            diff.abs() <= tol,
            "channel {c}: {:.6} W stored through the dispersive prism, {:.6} W without \
             dispersion (allowed {tol:.2e})",
            d.stored_flux[c],
            p.stored_flux[c]
        );
    }
}

//! Optics shared by every backend: reflection, refraction, Fresnel, Beer-Lambert
//! absorption and the index of a dispersive dielectric against wavelength, Cauchy's
//! (Vanderstichelen 2021, "the material model shared by all techniques") or
//! KHR_materials_dispersion's Abbe-number model (`ior_model`); what wavelength a photon
//! takes is `math::spectrum`'s. Wavelengths in micrometres. Shader ports mirror these
//! functions by name.
//!
//! Conventions: directions are unit vectors in world space; `incident` points *towards*
//! the surface (the direction the light travels); `normal` is a unit normal on the side
//! the light comes from (`dot(incident, normal) < 0`). `eta` is the relative index of
//! refraction `n_incident / n_transmitted`.

use glam::Vec3;

/// Mirror reflection of `incident` about `normal`: `d - 2 (d . n) n`.
#[inline]
pub fn reflect(incident: Vec3, normal: Vec3) -> Vec3 {
    incident - 2.0 * incident.dot(normal) * normal
}

/// Snell refraction of `incident` through a surface with `normal` facing the incident
/// side and relative index `eta = n_i / n_t`. Returns `None` on total internal
/// reflection. At `eta == 1` the result is `incident` (up to rounding).
#[inline]
pub fn refract(incident: Vec3, normal: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = -incident.dot(normal);
    // cos_t^2 = 1 - eta^2 (1 - cos_i^2), written so that eta = 1 gives cos_i^2 exactly
    // (no cancellation near IOR 1 and at grazing angles).
    let cos2_t = (1.0 - eta * eta) + eta * eta * cos_i * cos_i;
    if cos2_t < 0.0 {
        return None;
    }
    let cos_t = cos2_t.sqrt();
    Some(eta * incident + (eta * cos_i - cos_t) * normal)
}

/// Exact unpolarised Fresnel reflectance of a dielectric interface (average of the s and p
/// reflectances). `cos_i` is the cosine of the incidence angle (clamped to [0, 1]),
/// `eta = n_i / n_t`. Returns 1 beyond the critical angle (total internal reflection).
#[inline]
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let cos_i = cos_i.clamp(0.0, 1.0);
    let cos2_t = (1.0 - eta * eta) + eta * eta * cos_i * cos_i; // as in `refract`
    if cos2_t <= 0.0 {
        return 1.0;
    }
    let cos_t = cos2_t.sqrt();
    // r_s = (n_i cos_i - n_t cos_t) / (n_i cos_i + n_t cos_t), divided through by n_t.
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    (0.5 * (r_s * r_s + r_p * r_p)).clamp(0.0, 1.0)
}

/// Schlick's approximation as written in Vanderstichelen 2021 (`SchlickReflectAmount`): when light
/// goes into a lower index (`eta > 1`) the transmitted cosine is used, and total internal
/// reflection returns 1.
#[inline]
pub fn fresnel_schlick(cos_i: f32, eta: f32) -> f32 {
    // r0 = ((n1 - n2) / (n1 + n2))^2 = ((eta - 1) / (eta + 1))^2
    let r0 = ((eta - 1.0) / (eta + 1.0)).powi(2);
    let mut cos_x = cos_i.clamp(0.0, 1.0);
    if eta > 1.0 {
        let sin2_t = eta * eta * (1.0 - cos_x * cos_x);
        if sin2_t > 1.0 {
            return 1.0;
        }
        cos_x = (1.0 - sin2_t).sqrt();
    }
    let x = 1.0 - cos_x;
    r0 + (1.0 - r0) * x * x * x * x * x
}

/// Values of the kernels' `fresnel_model` parameter: which reflectance a dielectric
/// interface uses (Vanderstichelen 2021 uses Schlick's approximation; the exact unpolarised Fresnel
/// equations are caustica's default).
pub mod fresnel_model {
    /// [`fresnel_dielectric`](super::fresnel_dielectric): the exact unpolarised reflectance.
    pub const EXACT: u32 = 0;
    /// [`fresnel_schlick`](super::fresnel_schlick): Vanderstichelen 2021's approximation.
    pub const SCHLICK: u32 = 1;
}

/// The reflectance of a dielectric interface under `model` (one of [`fresnel_model`]):
/// `cos_i` the incidence cosine, `eta = n_i / n_t`; 1 under total internal reflection in
/// both models. Any other value of `model` means exact.
#[inline]
pub fn fresnel_reflectance(cos_i: f32, eta: f32, model: u32) -> f32 {
    if model == fresnel_model::SCHLICK {
        fresnel_schlick(cos_i, eta)
    } else {
        fresnel_dielectric(cos_i, eta)
    }
}

/// Beer-Lambert transmittance `exp(-sigma_a * distance)` per channel; `sigma_a` in
/// 1/scene-unit, `distance` in scene units.
#[inline]
pub fn beer_lambert(sigma_a: Vec3, distance: f32) -> Vec3 {
    Vec3::new(
        (-sigma_a.x * distance).exp(),
        (-sigma_a.y * distance).exp(),
        (-sigma_a.z * distance).exp(),
    )
}

/// Wavelength in micrometres that represents each RGB channel under the three-way split
/// (`frame.dispersion` three bands, Vanderstichelen 2021): red, green, blue.
pub const CHANNEL_WAVELENGTH_UM: [f32; 3] = [0.65, 0.55, 0.45];

/// Reference wavelength (micrometres) at which a material's nominal `ior` is given.
pub const REFERENCE_WAVELENGTH_UM: f32 = 0.55;

/// Cauchy's equation `n(lambda) = A + B / lambda^2` (Vanderstichelen 2021, section 3.3), `lambda` in
/// micrometres, `B` in um^2. The material's nominal `ior` is `n` at
/// [`REFERENCE_WAVELENGTH_UM`], so `A = ior - B / 0.55^2` and `B = 0` gives `ior` at every
/// wavelength.
#[inline]
pub fn cauchy_ior(ior: f32, cauchy_b: f32, wavelength_um: f32) -> f32 {
    let a = ior - cauchy_b / (REFERENCE_WAVELENGTH_UM * REFERENCE_WAVELENGTH_UM);
    a + cauchy_b / (wavelength_um * wavelength_um)
}

/// Values of [`GpuMaterial::ior_model`](crate::device::layout::GpuMaterial::ior_model):
/// how a dielectric's index varies with wavelength, and what its `dispersion` parameter
/// is.
pub mod ior_model {
    /// [`cauchy_ior`](super::cauchy_ior): `ior` at 550 nm, `dispersion` = Cauchy's `B`
    /// (um^2).
    pub const CAUCHY: u32 = 0;
    /// [`abbe_ior`](super::abbe_ior) (KHR_materials_dispersion): `ior` = `n_d` at the d
    /// line (587.56 nm), `dispersion` = the Abbe number `V_d`.
    pub const ABBE: u32 = 1;
}

/// KHR_materials_dispersion's `1 / (lambda_F^-2 - lambda_C^-2)` (its 523655 nm^2), in
/// um^2: the Cauchy `B` of a glass is `(n_d - 1) / V_d` times this.
pub const KHR_DISPERSION_B_UM2: f32 = 0.523655;

/// KHR_materials_dispersion's `KHR_DISPERSION_B_UM2 / lambda_d^2` (its 1.5168), so that
/// [`abbe_ior`] is `n_d` at the d line.
pub const KHR_DISPERSION_D_TERM: f32 = 1.5168;

/// The index at `wavelength_um` (micrometres) of a glass with index `ior_d` at the d line
/// (587.56 nm) and Abbe number `abbe_number` (`V_d = (n_d - 1) / (n_F - n_C)`), as the
/// KHR_materials_dispersion specification defines it: the first two terms of Cauchy's
/// equation through `n_d`, `n_F` and `n_C`,
/// `n(lambda) = max(n_d + (n_d - 1) / V_d * (523655 nm^2 / lambda^2 - 1.5168), 1)`.
/// `abbe_number` > 0 (validation); `ior_d` >= 1.
#[inline]
pub fn abbe_ior(ior_d: f32, abbe_number: f32, wavelength_um: f32) -> f32 {
    let n = ior_d
        + (ior_d - 1.0) / abbe_number
            * (KHR_DISPERSION_B_UM2 / (wavelength_um * wavelength_um) - KHR_DISPERSION_D_TERM);
    n.max(1.0)
}

/// The index at `wavelength_um` (micrometres) of a dispersive dielectric of nominal index
/// `ior`, dispersion parameter `dispersion` and model `model` (one of [`ior_model`]; any
/// other value means Cauchy): [`abbe_ior`] or [`cauchy_ior`].
#[inline]
pub fn dispersive_ior(ior: f32, dispersion: f32, model: u32, wavelength_um: f32) -> f32 {
    if model == ior_model::ABBE {
        abbe_ior(ior, dispersion, wavelength_um)
    } else {
        cauchy_ior(ior, dispersion, wavelength_um)
    }
}

/// Outcome of a photon meeting a smooth dielectric.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DielectricScatter {
    /// Outgoing direction (unit when the incident direction is unit).
    pub direction: Vec3,
    /// True for reflection (Fresnel choice or total internal reflection), false for
    /// refraction.
    pub reflected: bool,
}

/// Chooses reflection with probability equal to the Fresnel reflectance of `model` (one
/// of [`fresnel_model`]) and refraction otherwise, so that photon power stays constant
/// (the expectation is right). `shading_normal` may face either side; `entering` says
/// whether the ray arrives from outside the object (decided by the geometric normal);
/// `ior` is the object's index and `xi` a uniform number in [0, 1). Total internal
/// reflection always reflects.
#[inline]
pub fn dielectric_scatter(
    incident: Vec3,
    shading_normal: Vec3,
    entering: bool,
    ior: f32,
    xi: f32,
    model: u32,
) -> DielectricScatter {
    let facing = if incident.dot(shading_normal) < 0.0 {
        shading_normal
    } else {
        -shading_normal
    };
    let eta = if entering { 1.0 / ior } else { ior };
    let cos_i = -incident.dot(facing);
    let f = fresnel_reflectance(cos_i, eta, model);
    if xi < f {
        return DielectricScatter {
            direction: reflect(incident, facing),
            reflected: true,
        };
    }
    match refract(incident, facing, eta) {
        Some(t) => DielectricScatter {
            direction: t.normalize(),
            reflected: false,
        },
        None => DielectricScatter {
            direction: reflect(incident, facing),
            reflected: true,
        },
    }
}

/// Largest radiance, irradiance or radiometric scale factor a kernel carries (f32::MAX).
/// A value that overflows (a light touching a surface: `I / d^2` with `d -> 0`; a pixel
/// footprint that flushes to zero) saturates here instead of becoming Inf, so that a
/// zero channel times it stays 0, never NaN (see `scene::limits`).
pub const RADIANCE_MAX: f32 = f32::MAX;

/// `min(x, RADIANCE_MAX)`: Inf saturates to f32::MAX; finite values pass unchanged.
#[inline]
pub fn saturate_radiance(x: f32) -> f32 {
    x.min(RADIANCE_MAX)
}

/// [`saturate_radiance`] per channel.
#[inline]
pub fn saturate_radiance3(v: Vec3) -> Vec3 {
    v.min(Vec3::splat(RADIANCE_MAX))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(theta: f32) -> Vec3 {
        // incident direction at angle theta from the normal (0, 1, 0), travelling down.
        Vec3::new(theta.sin(), -theta.cos(), 0.0)
    }

    #[test]
    fn fresnel_normal_incidence_closed_form() {
        for &n in &[1.0f32, 1.33, 1.5, 2.4, 4.0] {
            let expect = ((n - 1.0) / (n + 1.0)).powi(2);
            assert!((fresnel_dielectric(1.0, 1.0 / n) - expect).abs() < 1e-6);
            assert!((fresnel_dielectric(1.0, n) - expect).abs() < 1e-6);
            assert!((fresnel_schlick(1.0, 1.0 / n) - expect).abs() < 1e-6);
        }
    }

    #[test]
    fn fresnel_against_closed_form_s_p() {
        // Closed form in angles (Hecht): r_s = -sin(ti - tt)/sin(ti + tt),
        // r_p = tan(ti - tt)/tan(ti + tt); compared in f64.
        let n = 1.5f64;
        for i in 1..89 {
            let ti = (i as f64).to_radians();
            let tt = (ti.sin() / n).asin();
            let rs = -(ti - tt).sin() / (ti + tt).sin();
            let rp = (ti - tt).tan() / (ti + tt).tan();
            let expect = 0.5 * (rs * rs + rp * rp);
            let got = fresnel_dielectric(ti.cos() as f32, (1.0 / n) as f32) as f64;
            assert!((got - expect).abs() < 2e-6, "angle {i}: {got} vs {expect}");
        }
    }

    #[test]
    fn reflectance_plus_transmittance_is_one_and_tir_is_total() {
        for &eta in &[0.5f32, 1.0 / 1.5, 1.0, 1.33, 1.5, 2.5] {
            let critical = if eta > 1.0 {
                (1.0 / eta).asin()
            } else {
                f32::INFINITY
            };
            for i in 0..=900 {
                let theta = (i as f32 / 10.0).to_radians();
                let r = fresnel_dielectric(theta.cos(), eta);
                let t = 1.0 - r;
                assert!((0.0..=1.0).contains(&r) && (0.0..=1.0).contains(&t));
                assert!((r + t - 1.0).abs() < 1e-7);
                if theta > critical + 1e-4 {
                    assert_eq!(r, 1.0, "beyond critical angle eta {eta} theta {theta}");
                    assert!(refract(dir(theta), Vec3::Y, eta).is_none());
                    assert_eq!(fresnel_schlick(theta.cos(), eta), 1.0);
                }
            }
        }
    }

    #[test]
    fn fresnel_schlick_error_for_glass() {
        // The bound CausticMap's `FresnelModel` doc quotes: for n = 1.5, Schlick's
        // reflectance differs from the exact one by at most 0.036, reached from outside
        // near 85 degrees and from inside just below the critical angle (41.8 degrees).
        let mut worst = [(0.0f32, 0.0f32); 2];
        for (k, eta) in [1.0 / 1.5, 1.5f32].into_iter().enumerate() {
            for i in 0..=20_000 {
                let theta = i as f32 / 20_000.0 * std::f32::consts::FRAC_PI_2;
                let d = (fresnel_schlick(theta.cos(), eta) - fresnel_dielectric(theta.cos(), eta))
                    .abs();
                if d > worst[k].0 {
                    worst[k] = (d, theta.to_degrees());
                }
            }
        }
        for (d, deg) in worst {
            assert!(
                (0.034..0.037).contains(&d),
                "worst error {d} at {deg} degrees"
            );
        }
        assert!(
            (84.0..86.0).contains(&worst[0].1),
            "outside: {:?}",
            worst[0]
        );
        assert!((41.0..41.9).contains(&worst[1].1), "inside: {:?}", worst[1]);
        // the model switch picks them
        let (c, eta) = (0.3f32, 1.0 / 1.5);
        assert_eq!(
            fresnel_reflectance(c, eta, fresnel_model::EXACT),
            fresnel_dielectric(c, eta)
        );
        assert_eq!(
            fresnel_reflectance(c, eta, fresnel_model::SCHLICK),
            fresnel_schlick(c, eta)
        );
    }

    #[test]
    fn refraction_at_unit_ior_is_identity() {
        for i in 0..90 {
            let d = dir((i as f32).to_radians());
            let t = refract(d, Vec3::Y, 1.0).unwrap();
            assert!((t - d).length() < 1e-6);
            assert!(fresnel_dielectric(d.dot(-Vec3::Y), 1.0) < 1e-12);
        }
    }

    #[test]
    fn refraction_obeys_snell() {
        let eta = 1.0 / 1.5;
        for i in 0..90 {
            let ti = (i as f32).to_radians();
            let t = refract(dir(ti), Vec3::Y, eta).unwrap();
            assert!((t.length() - 1.0).abs() < 1e-5);
            let sin_t = t.x;
            assert!((sin_t - eta * ti.sin()).abs() < 1e-5);
        }
    }

    #[test]
    fn cauchy_reference_and_zero_b() {
        assert_eq!(cauchy_ior(1.5, 0.0, 0.45), 1.5);
        assert!((cauchy_ior(1.5, 0.01, 0.55) - 1.5).abs() < 1e-6);
        assert!(cauchy_ior(1.5, 0.01, 0.45) > cauchy_ior(1.5, 0.01, 0.65));
    }

    #[test]
    fn abbe_model_is_the_khr_formula() {
        // BK7: n_d 1.5168, V_d 64.17, so n_F - n_C = 0.5168 / 64.17 = 0.008054 (the
        // definition of V_d holds for the formula by construction, to its 4-5 digits)
        let (nd, v) = (1.5168f32, 64.17f32);
        let (f, d, c) = (0.48613f32, 0.58756f32, 0.65627f32);
        assert!((abbe_ior(nd, v, d) - nd).abs() < 2e-5);
        let spread = abbe_ior(nd, v, f) - abbe_ior(nd, v, c);
        assert!((spread - (nd - 1.0) / v).abs() < 2e-5, "{spread}");
        // the clamp: never below 1
        assert_eq!(abbe_ior(1.0, 1e-3, 0.78), 1.0);
        assert!(abbe_ior(1.05, 0.01, 0.78) >= 1.0);
        // the model switch
        assert_eq!(
            dispersive_ior(1.5, 0.01, ior_model::CAUCHY, 0.45),
            cauchy_ior(1.5, 0.01, 0.45)
        );
        assert_eq!(
            dispersive_ior(1.5, 40.0, ior_model::ABBE, 0.45),
            abbe_ior(1.5, 40.0, 0.45)
        );
    }

    #[test]
    fn beer_lambert_limits() {
        assert_eq!(beer_lambert(Vec3::ZERO, 10.0), Vec3::ONE);
        let t = beer_lambert(Vec3::splat(1e6), 1.0);
        assert_eq!(t, Vec3::ZERO);
        assert!(t.is_finite());
    }
}

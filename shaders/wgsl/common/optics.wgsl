// Mirror of core/src/optics.rs and backend-opencl/kernels/optics.cl: reflection,
// refraction, exact Fresnel, Beer-Lambert, Cauchy dispersion and the photon's
// reflect-or-refract choice. (These `reflect` and `refract` shadow WGSL's built-ins on
// purpose: same formulas, but in core's operation order.)

fn reflect(incident: vec3<f32>, normal: vec3<f32>) -> vec3<f32> {
    return incident - 2.0 * dot3(incident, normal) * normal;
}

// Refracted (unnormalised) direction; returns false on total internal reflection.
fn refract(incident: vec3<f32>, normal: vec3<f32>, eta: f32, out_dir: ptr<function, vec3<f32>>) -> bool {
    let cos_i = -dot3(incident, normal);
    let cos2_t = (1.0 - eta * eta) + eta * eta * cos_i * cos_i;
    if (cos2_t < 0.0) {
        return false;
    }
    let cos_t = sqrt(cos2_t);
    *out_dir = eta * incident + (eta * cos_i - cos_t) * normal;
    return true;
}

fn fresnel_dielectric(cos_i_in: f32, eta: f32) -> f32 {
    let cos_i = clampf(cos_i_in, 0.0, 1.0);
    let cos2_t = (1.0 - eta * eta) + eta * eta * cos_i * cos_i;
    if (cos2_t <= 0.0) {
        return 1.0;
    }
    let cos_t = sqrt(cos2_t);
    let r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return clampf(0.5 * (r_s * r_s + r_p * r_p), 0.0, 1.0);
}

// Vanderstichelen 2021's Schlick approximation (core: optics::fresnel_schlick): the transmitted
// cosine when light goes into the lower index, 1 under total internal reflection.
fn fresnel_schlick(cos_i: f32, eta: f32) -> f32 {
    let q = (eta - 1.0) / (eta + 1.0);
    let r0 = q * q;
    var cos_x = clampf(cos_i, 0.0, 1.0);
    if (eta > 1.0) {
        let sin2_t = eta * eta * (1.0 - cos_x * cos_x);
        if (sin2_t > 1.0) {
            return 1.0;
        }
        cos_x = sqrt(1.0 - sin2_t);
    }
    let x = 1.0 - cos_x;
    return r0 + (1.0 - r0) * x * x * x * x * x;
}

// The reflectance under `model` (core: optics::fresnel_reflectance).
fn fresnel_reflectance(cos_i: f32, eta: f32, model: u32) -> f32 {
    if (model == FRESNEL_SCHLICK) {
        return fresnel_schlick(cos_i, eta);
    }
    return fresnel_dielectric(cos_i, eta);
}

fn beer_lambert(sigma_a: vec3<f32>, distance: f32) -> vec3<f32> {
    return vec3<f32>(exp(-sigma_a.x * distance), exp(-sigma_a.y * distance),
                     exp(-sigma_a.z * distance));
}

// Wavelengths (micrometres) of the red, green and blue photon channels.
const CHANNEL_WAVELENGTH_UM = array<f32, 3>(0.65f, 0.55f, 0.45f);

fn cauchy_ior(ior: f32, cauchy_b: f32, wavelength_um: f32) -> f32 {
    let a = ior - cauchy_b / (REFERENCE_WAVELENGTH_UM * REFERENCE_WAVELENGTH_UM);
    return a + cauchy_b / (wavelength_um * wavelength_um);
}

// KHR_materials_dispersion's index from n_d and the Abbe number (core: optics::abbe_ior).
fn abbe_ior(ior_d: f32, abbe_number: f32, wavelength_um: f32) -> f32 {
    let n = ior_d + (ior_d - 1.0) / abbe_number
        * (KHR_DISPERSION_B_UM2 / (wavelength_um * wavelength_um) - KHR_DISPERSION_D_TERM);
    return max(n, 1.0);
}

// The index of a dispersive dielectric under its model (core: optics::dispersive_ior).
fn dispersive_ior(ior: f32, dispersion: f32, model: u32, wavelength_um: f32) -> f32 {
    if (model == IOR_MODEL_ABBE) {
        return abbe_ior(ior, dispersion, wavelength_um);
    }
    return cauchy_ior(ior, dispersion, wavelength_um);
}

// Reflects with probability = Fresnel reflectance of `model` (`xi` uniform in [0, 1)),
// else refracts.
fn dielectric_scatter(incident: vec3<f32>, shading_normal: vec3<f32>, entering: bool, ior: f32,
                      xi: f32, model: u32) -> vec3<f32> {
    let facing = select(-shading_normal, shading_normal, dot3(incident, shading_normal) < 0.0);
    let eta = select(ior, 1.0 / ior, entering);
    let cos_i = -dot3(incident, facing);
    let f = fresnel_reflectance(cos_i, eta, model);
    if (xi < f) {
        return reflect(incident, facing);
    }
    var t: vec3<f32>;
    if (refract(incident, facing, eta, &t)) {
        return normalize3(t);
    }
    return reflect(incident, facing);
}

// Radiance, irradiance and scale factors saturate at RADIANCE_MAX (f32::MAX, core:
// optics::RADIANCE_MAX) instead of becoming Inf (and Inf * 0 = NaN).

fn saturate_radiance(x: f32) -> f32 {
    return min(x, RADIANCE_MAX);
}

fn saturate_radiance3(v: vec3<f32>) -> vec3<f32> {
    return min(v, vec3<f32>(RADIANCE_MAX));
}

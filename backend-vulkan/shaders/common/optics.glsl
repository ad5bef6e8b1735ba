// Mirror of core/src/optics.rs and backend-opencl/kernels/optics.cl: reflection,
// refraction, exact Fresnel, Beer-Lambert, Cauchy dispersion and the photon's
// reflect-or-refract choice. OpenCL's `reflect` and `refract` are `reflect3` and
// `refract3` here: GLSL has built-ins of those names (with a different rounding
// contract) that a user function may not redeclare.

precise vec3 reflect3(vec3 incident, vec3 normal) {
    return incident - 2.0 * dot3(incident, normal) * normal;
}

// Refracted (unnormalised) direction; returns false on total internal reflection.
bool refract3(vec3 incident, vec3 normal, float eta, precise out vec3 result) {
    precise float cos_i = -dot3(incident, normal);
    precise float cos2_t = (1.0 - eta * eta) + eta * eta * cos_i * cos_i;
    if (cos2_t < 0.0) return false;
    precise float cos_t = sqrt(cos2_t);
    result = eta * incident + (eta * cos_i - cos_t) * normal;
    return true;
}

precise float fresnel_dielectric(float cos_i, float eta) {
    cos_i = clampf(cos_i, 0.0, 1.0);
    float cos2_t = (1.0 - eta * eta) + eta * eta * cos_i * cos_i;
    if (cos2_t <= 0.0) return 1.0;
    float cos_t = sqrt(cos2_t);
    float r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return clampf(0.5 * (r_s * r_s + r_p * r_p), 0.0, 1.0);
}

// Vanderstichelen 2021's Schlick approximation (core: optics::fresnel_schlick): the transmitted
// cosine when light goes into the lower index, 1 under total internal reflection.
precise float fresnel_schlick(float cos_i, float eta) {
    float q = (eta - 1.0) / (eta + 1.0);
    float r0 = q * q;
    float cos_x = clampf(cos_i, 0.0, 1.0);
    if (eta > 1.0) {
        float sin2_t = eta * eta * (1.0 - cos_x * cos_x);
        if (sin2_t > 1.0) return 1.0;
        cos_x = sqrt(1.0 - sin2_t);
    }
    float x = 1.0 - cos_x;
    return r0 + (1.0 - r0) * x * x * x * x * x;
}

// The reflectance under `model` (core: optics::fresnel_reflectance).
precise float fresnel_reflectance(float cos_i, float eta, uint model) {
    if (model == FRESNEL_SCHLICK) return fresnel_schlick(cos_i, eta);
    return fresnel_dielectric(cos_i, eta);
}

precise vec3 beer_lambert(vec3 sigma_a, float distance) {
    return vec3(exp(-sigma_a.x * distance), exp(-sigma_a.y * distance),
                exp(-sigma_a.z * distance));
}

// Wavelengths (micrometres) of the red, green and blue photon channels.
const float CHANNEL_WAVELENGTH_UM[3] = float[3](0.65, 0.55, 0.45);

precise float cauchy_ior(float ior, float cauchy_b, float wavelength_um) {
    // Through a variable: glslang would fold the constant square in double precision
    // (0.55^2 happens to round alike, 0.65^2 and 0.45^2 would not); as a run-time
    // product it rounds in f32, as Rust's.
    float reference_um = REFERENCE_WAVELENGTH_UM;
    float a = ior - cauchy_b / (reference_um * reference_um);
    return a + cauchy_b / (wavelength_um * wavelength_um);
}

// KHR_materials_dispersion's index from n_d and the Abbe number (core: optics::abbe_ior).
precise float abbe_ior(float ior_d, float abbe_number, float wavelength_um) {
    precise float n = ior_d + (ior_d - 1.0) / abbe_number
                                  * (KHR_DISPERSION_B_UM2 / (wavelength_um * wavelength_um)
                                     - KHR_DISPERSION_D_TERM);
    return max(n, 1.0);
}

// The index of a dispersive dielectric under its model (core: optics::dispersive_ior).
precise float dispersive_ior(float ior, float dispersion, uint model, float wavelength_um) {
    if (model == IOR_MODEL_ABBE) return abbe_ior(ior, dispersion, wavelength_um);
    return cauchy_ior(ior, dispersion, wavelength_um);
}

// Reflects with probability = Fresnel reflectance of `model` (`xi` uniform in [0, 1)),
// else refracts.
precise vec3 dielectric_scatter(vec3 incident, vec3 shading_normal, bool entering, float ior,
                                float xi, uint model) {
    vec3 facing = dot3(incident, shading_normal) < 0.0 ? shading_normal : -shading_normal;
    // precise: eta reaches the result only through calls, where glslang stops propagating
    precise float eta = entering ? 1.0 / ior : ior;
    float cos_i = -dot3(incident, facing);
    float f = fresnel_reflectance(cos_i, eta, model);
    if (xi < f) return reflect3(incident, facing);
    vec3 t;
    if (refract3(incident, facing, eta, t)) return normalize3(t);
    return reflect3(incident, facing);
}

// Largest radiance, irradiance or scale factor a kernel carries: f32::MAX (core:
// optics::RADIANCE_MAX). Overflow saturates instead of becoming Inf (and Inf * 0 = NaN).
float saturate_radiance(float x) { return min(x, RADIANCE_MAX); }

vec3 saturate_radiance3(vec3 v) { return min(v, vec3(RADIANCE_MAX)); }

// Mirror of core/src/optics.rs: reflection, refraction, exact Fresnel, Beer-Lambert,
// Cauchy dispersion and the photon's reflect-or-refract choice.

inline float3 reflect(float3 incident, float3 normal) {
    return incident - 2.0f * dot3(incident, normal) * normal;
}

// Refracted (unnormalised) direction; returns false on total internal reflection.
inline bool refract(float3 incident, float3 normal, float eta, float3* out) {
    float cos_i = -dot3(incident, normal);
    float cos2_t = (1.0f - eta * eta) + eta * eta * cos_i * cos_i;
    if (cos2_t < 0.0f) return false;
    float cos_t = sqrt(cos2_t);
    *out = eta * incident + (eta * cos_i - cos_t) * normal;
    return true;
}

inline float fresnel_dielectric(float cos_i, float eta) {
    cos_i = clampf(cos_i, 0.0f, 1.0f);
    float cos2_t = (1.0f - eta * eta) + eta * eta * cos_i * cos_i;
    if (cos2_t <= 0.0f) return 1.0f;
    float cos_t = sqrt(cos2_t);
    float r_s = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float r_p = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return clampf(0.5f * (r_s * r_s + r_p * r_p), 0.0f, 1.0f);
}

// Vanderstichelen 2021's Schlick approximation (core: optics::fresnel_schlick): the transmitted
// cosine when light goes into the lower index, 1 under total internal reflection.
inline float fresnel_schlick(float cos_i, float eta) {
    float q = (eta - 1.0f) / (eta + 1.0f);
    float r0 = q * q;
    float cos_x = clampf(cos_i, 0.0f, 1.0f);
    if (eta > 1.0f) {
        float sin2_t = eta * eta * (1.0f - cos_x * cos_x);
        if (sin2_t > 1.0f) return 1.0f;
        cos_x = sqrt(1.0f - sin2_t);
    }
    float x = 1.0f - cos_x;
    return r0 + (1.0f - r0) * x * x * x * x * x;
}

// The reflectance under `model` (core: optics::fresnel_reflectance).
inline float fresnel_reflectance(float cos_i, float eta, uint model) {
    return model == FRESNEL_SCHLICK ? fresnel_schlick(cos_i, eta) : fresnel_dielectric(cos_i, eta);
}

inline float3 beer_lambert(float3 sigma_a, float distance) {
    return (float3)(exp(-sigma_a.x * distance), exp(-sigma_a.y * distance),
                    exp(-sigma_a.z * distance));
}

// Wavelengths (micrometres) of the red, green and blue photon channels.
__constant float CHANNEL_WAVELENGTH_UM[3] = {0.65f, 0.55f, 0.45f};

inline float cauchy_ior(float ior, float cauchy_b, float wavelength_um) {
    float a = ior - cauchy_b / (REFERENCE_WAVELENGTH_UM * REFERENCE_WAVELENGTH_UM);
    return a + cauchy_b / (wavelength_um * wavelength_um);
}

// KHR_materials_dispersion's index from n_d and the Abbe number (core: optics::abbe_ior).
inline float abbe_ior(float ior_d, float abbe_number, float wavelength_um) {
    float n = ior_d + (ior_d - 1.0f) / abbe_number
                          * (KHR_DISPERSION_B_UM2 / (wavelength_um * wavelength_um)
                             - KHR_DISPERSION_D_TERM);
    return fmax(n, 1.0f);
}

// The index of a dispersive dielectric under its model (core: optics::dispersive_ior).
inline float dispersive_ior(float ior, float dispersion, uint model, float wavelength_um) {
    if (model == IOR_MODEL_ABBE) return abbe_ior(ior, dispersion, wavelength_um);
    return cauchy_ior(ior, dispersion, wavelength_um);
}

// Reflects with probability = Fresnel reflectance of `model` (`xi` uniform in [0, 1)),
// else refracts.
inline float3 dielectric_scatter(float3 incident, float3 shading_normal, bool entering,
                                 float ior, float xi, uint model) {
    float3 facing = dot3(incident, shading_normal) < 0.0f ? shading_normal : -shading_normal;
    float eta = entering ? 1.0f / ior : ior;
    float cos_i = -dot3(incident, facing);
    float f = fresnel_reflectance(cos_i, eta, model);
    if (xi < f) return reflect(incident, facing);
    float3 t;
    if (refract(incident, facing, eta, &t)) return normalize3(t);
    return reflect(incident, facing);
}

// Largest radiance, irradiance or scale factor a kernel carries: f32::MAX (core:
// optics::RADIANCE_MAX). Overflow saturates instead of becoming Inf (and Inf * 0 = NaN).
inline float saturate_radiance(float x) { return fmin(x, RADIANCE_MAX); }

inline float3 saturate_radiance3(float3 v) { return fmin(v, (float3)(RADIANCE_MAX)); }

// Spectral dispersion (mirror of core::math::spectrum, same names, same operations in the
// same order): the wavelength (micrometres) a photon takes at its first dispersive surface
// and its linear sRGB weight through the CIE 1931 colour-matching functions (Wyman 2013's
// multi-lobe fit), clipped at 0 and scaled so that a flat spectrum averages to white.
// Constants from the generated layout.cl (core::math::spectrum).

// Point `index` of the golden-ratio sequence rotated by the seed's hash, in [0, 1).
inline float spectral_sample(uint seed, uint index) {
    return u32_to_unit_f32(index * WAVELENGTH_STEP + pcg_hash(seed));
}

// The wavelength (micrometres) at fraction `u` of the sampled range.
inline float wavelength_at(float u) { return SPECTRUM_MIN_UM + u * SPECTRUM_WIDTH_UM; }

// One lobe of Wyman 2013's piecewise Gaussian at `nm` nanometres.
inline float cie_lobe(float nm, float weight, float mean_nm, float inv_sigma_below,
                      float inv_sigma_above) {
    float inv_sigma = nm < mean_nm ? inv_sigma_below : inv_sigma_above;
    float t = (nm - mean_nm) * inv_sigma;
    return weight * exp(-0.5f * t * t);
}

// The CIE 1931 2-degree colour-matching functions at `wavelength_um` (Wyman 2013's fit).
inline float3 cie_xyz(float wavelength_um) {
    float nm = wavelength_um * 1000.0f;
    float x = cie_lobe(nm, CIE_X0_WEIGHT, CIE_X0_MEAN_NM, CIE_X0_INV_SIGMA_BELOW,
                       CIE_X0_INV_SIGMA_ABOVE)
              + cie_lobe(nm, CIE_X1_WEIGHT, CIE_X1_MEAN_NM, CIE_X1_INV_SIGMA_BELOW,
                         CIE_X1_INV_SIGMA_ABOVE)
              + cie_lobe(nm, CIE_X2_WEIGHT, CIE_X2_MEAN_NM, CIE_X2_INV_SIGMA_BELOW,
                         CIE_X2_INV_SIGMA_ABOVE);
    float y = cie_lobe(nm, CIE_Y0_WEIGHT, CIE_Y0_MEAN_NM, CIE_Y0_INV_SIGMA_BELOW,
                       CIE_Y0_INV_SIGMA_ABOVE)
              + cie_lobe(nm, CIE_Y1_WEIGHT, CIE_Y1_MEAN_NM, CIE_Y1_INV_SIGMA_BELOW,
                         CIE_Y1_INV_SIGMA_ABOVE);
    float z = cie_lobe(nm, CIE_Z0_WEIGHT, CIE_Z0_MEAN_NM, CIE_Z0_INV_SIGMA_BELOW,
                       CIE_Z0_INV_SIGMA_ABOVE)
              + cie_lobe(nm, CIE_Z1_WEIGHT, CIE_Z1_MEAN_NM, CIE_Z1_INV_SIGMA_BELOW,
                         CIE_Z1_INV_SIGMA_ABOVE);
    return (float3)(x, y, z);
}

// CIE XYZ to linear sRGB (IEC 61966-2-1), each row summed left to right.
inline float3 xyz_to_linear_srgb(float3 c) {
    return (float3)(XYZ_TO_SRGB_00 * c.x + XYZ_TO_SRGB_01 * c.y + XYZ_TO_SRGB_02 * c.z,
                    XYZ_TO_SRGB_10 * c.x + XYZ_TO_SRGB_11 * c.y + XYZ_TO_SRGB_12 * c.z,
                    XYZ_TO_SRGB_20 * c.x + XYZ_TO_SRGB_21 * c.y + XYZ_TO_SRGB_22 * c.z);
}

// The clipped, per-channel normalised linear sRGB weight of a wavelength (micrometres).
inline float3 wavelength_rgb(float wavelength_um) {
    float3 rgb = fmax(xyz_to_linear_srgb(cie_xyz(wavelength_um)), (float3)(0.0f));
    return rgb * (float3)(SPECTRAL_RGB_SCALE_R, SPECTRAL_RGB_SCALE_G, SPECTRAL_RGB_SCALE_B);
}

// core::math::spectrum::disperse: a photon's wavelength (micrometres, returned) and flux
// (`*flux`, updated) after its first dispersive surface: spectral (the photon's point of
// the sequence and its colour) or the three-way split (channel min(floor(3 xi), 2), x3).
inline float disperse(float3* flux, uint mode, uint seed, uint index, float xi) {
    if (mode == DISPERSION_THREE_BANDS) {
        int c = min((int)(xi * 3.0f), 2);
        float3 f = *flux;
        float one[3] = {0.0f, 0.0f, 0.0f};
        one[c] = (c == 0 ? f.x : c == 1 ? f.y : f.z) * 3.0f;
        *flux = load3(one);
        return CHANNEL_WAVELENGTH_UM[c];
    }
    float wavelength = wavelength_at(spectral_sample(seed, index));
    *flux = *flux * wavelength_rgb(wavelength);
    return wavelength;
}

// core::math::spectrum::split_lane: lane `lane` of the deterministic split's three: its
// wavelength (returned) and flux (`*flux`, from the photon's).
inline float split_lane(float3* flux, uint mode, uint seed, uint index, uint lane) {
    int c = (int)min(lane, 2u);
    if (mode == DISPERSION_THREE_BANDS) {
        float3 f = *flux;
        float one[3] = {0.0f, 0.0f, 0.0f};
        one[c] = c == 0 ? f.x : c == 1 ? f.y : f.z;
        *flux = load3(one);
        return CHANNEL_WAVELENGTH_UM[c];
    }
    float wavelength = wavelength_at(((float)c + spectral_sample(seed, index)) * ONE_THIRD);
    *flux = *flux * wavelength_rgb(wavelength) * ONE_THIRD;
    return wavelength;
}

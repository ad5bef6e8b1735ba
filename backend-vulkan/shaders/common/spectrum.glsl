// Spectral dispersion (mirror of core::math::spectrum and backend-opencl's spectrum.cl,
// same names, same operations in the same order): the wavelength (micrometres) a photon
// takes at its first dispersive surface and its linear sRGB weight through the CIE 1931
// colour-matching functions (Wyman 2013's multi-lobe fit), clipped at 0 and scaled so that
// a flat spectrum averages to white. Constants from the generated layout.glsl
// (core::math::spectrum); no expression computes with two constants (prelude.glsl).

// Point `index` of the golden-ratio sequence rotated by the seed's hash, in [0, 1).
precise float spectral_sample(uint seed, uint index) {
    return u32_to_unit_f32(index * WAVELENGTH_STEP + pcg_hash(seed));
}

// The wavelength (micrometres) at fraction `u` of the sampled range.
precise float wavelength_at(float u) { return SPECTRUM_MIN_UM + u * SPECTRUM_WIDTH_UM; }

// One lobe of Wyman 2013's piecewise Gaussian at `nm` nanometres.
precise float cie_lobe(float nm, float weight, float mean_nm, float inv_sigma_below,
                       float inv_sigma_above) {
    float inv_sigma = nm < mean_nm ? inv_sigma_below : inv_sigma_above;
    precise float t = (nm - mean_nm) * inv_sigma;
    return weight * exp(-0.5 * t * t);
}

// The CIE 1931 2-degree colour-matching functions at `wavelength_um` (Wyman 2013's fit).
precise vec3 cie_xyz(float wavelength_um) {
    precise float nm = wavelength_um * 1000.0;
    precise float x = cie_lobe(nm, CIE_X0_WEIGHT, CIE_X0_MEAN_NM, CIE_X0_INV_SIGMA_BELOW,
                               CIE_X0_INV_SIGMA_ABOVE)
                      + cie_lobe(nm, CIE_X1_WEIGHT, CIE_X1_MEAN_NM, CIE_X1_INV_SIGMA_BELOW,
                                 CIE_X1_INV_SIGMA_ABOVE)
                      + cie_lobe(nm, CIE_X2_WEIGHT, CIE_X2_MEAN_NM, CIE_X2_INV_SIGMA_BELOW,
                                 CIE_X2_INV_SIGMA_ABOVE);
    precise float y = cie_lobe(nm, CIE_Y0_WEIGHT, CIE_Y0_MEAN_NM, CIE_Y0_INV_SIGMA_BELOW,
                               CIE_Y0_INV_SIGMA_ABOVE)
                      + cie_lobe(nm, CIE_Y1_WEIGHT, CIE_Y1_MEAN_NM, CIE_Y1_INV_SIGMA_BELOW,
                                 CIE_Y1_INV_SIGMA_ABOVE);
    precise float z = cie_lobe(nm, CIE_Z0_WEIGHT, CIE_Z0_MEAN_NM, CIE_Z0_INV_SIGMA_BELOW,
                               CIE_Z0_INV_SIGMA_ABOVE)
                      + cie_lobe(nm, CIE_Z1_WEIGHT, CIE_Z1_MEAN_NM, CIE_Z1_INV_SIGMA_BELOW,
                                 CIE_Z1_INV_SIGMA_ABOVE);
    return vec3(x, y, z);
}

// CIE XYZ to linear sRGB (IEC 61966-2-1), each row summed left to right.
precise vec3 xyz_to_linear_srgb(vec3 c) {
    return vec3(XYZ_TO_SRGB_00 * c.x + XYZ_TO_SRGB_01 * c.y + XYZ_TO_SRGB_02 * c.z,
                XYZ_TO_SRGB_10 * c.x + XYZ_TO_SRGB_11 * c.y + XYZ_TO_SRGB_12 * c.z,
                XYZ_TO_SRGB_20 * c.x + XYZ_TO_SRGB_21 * c.y + XYZ_TO_SRGB_22 * c.z);
}

// The clipped, per-channel normalised linear sRGB weight of a wavelength (micrometres).
precise vec3 wavelength_rgb(float wavelength_um) {
    vec3 rgb = max(xyz_to_linear_srgb(cie_xyz(wavelength_um)), vec3(0.0));
    return rgb * vec3(SPECTRAL_RGB_SCALE_R, SPECTRAL_RGB_SCALE_G, SPECTRAL_RGB_SCALE_B);
}

// core::math::spectrum::disperse: a photon's flux (returned) and wavelength (micrometres,
// `wavelength`) after its first dispersive surface: spectral (the photon's point of the
// sequence and its colour) or the three-way split (channel min(floor(3 xi), 2), x3).
precise vec3 disperse(vec3 flux, uint mode, uint seed, uint index, float xi,
                      precise out float wavelength) {
    if (mode == DISPERSION_THREE_BANDS) {
        precise float pick = xi * 3.0;
        int c = min(int(pick), 2);
        precise vec3 one = vec3(0.0, 0.0, 0.0);
        one[c] = (c == 0 ? flux.x : c == 1 ? flux.y : flux.z) * 3.0;
        wavelength = CHANNEL_WAVELENGTH_UM[c];
        return one;
    }
    wavelength = wavelength_at(spectral_sample(seed, index));
    return flux * wavelength_rgb(wavelength);
}

// core::math::spectrum::split_lane: lane `lane` of the deterministic split's three: its
// flux (returned) and wavelength (`wavelength`).
precise vec3 split_lane(vec3 flux, uint mode, uint seed, uint index, uint lane,
                        precise out float wavelength) {
    int c = int(min(lane, 2u));
    if (mode == DISPERSION_THREE_BANDS) {
        vec3 one = vec3(0.0, 0.0, 0.0);
        one[c] = c == 0 ? flux.x : c == 1 ? flux.y : flux.z;
        wavelength = CHANNEL_WAVELENGTH_UM[c];
        return one;
    }
    wavelength = wavelength_at((float(c) + spectral_sample(seed, index)) * ONE_THIRD);
    return flux * wavelength_rgb(wavelength) * ONE_THIRD;
}

// Spectral dispersion (core::math::spectrum, same names, same operations in the same
// order): the wavelength (micrometres) a photon takes at its first dispersive surface and
// its linear sRGB weight through the CIE 1931 colour-matching functions (Wyman 2013's
// multi-lobe fit), clipped at 0 and scaled so that a flat spectrum averages to white.
// Constants from the generated layout.wgsl (core::math::spectrum).

// Point `index` of the golden-ratio sequence rotated by the seed's hash, in [0, 1).
fn spectral_sample(seed: u32, index: u32) -> f32 {
    return u32_to_unit_f32(index * WAVELENGTH_STEP + pcg_hash(seed));
}

// The wavelength (micrometres) at fraction `u` of the sampled range.
fn wavelength_at(u: f32) -> f32 {
    return SPECTRUM_MIN_UM + u * SPECTRUM_WIDTH_UM;
}

// One lobe of Wyman 2013's piecewise Gaussian at `nm` nanometres.
fn cie_lobe(nm: f32, weight: f32, mean_nm: f32, inv_sigma_below: f32,
            inv_sigma_above: f32) -> f32 {
    let inv_sigma = select(inv_sigma_above, inv_sigma_below, nm < mean_nm);
    let t = (nm - mean_nm) * inv_sigma;
    return weight * exp(-0.5 * t * t);
}

// The CIE 1931 2-degree colour-matching functions at `wavelength_um` (Wyman 2013's fit).
fn cie_xyz(wavelength_um: f32) -> vec3<f32> {
    let nm = wavelength_um * 1000.0;
    let x = cie_lobe(nm, CIE_X0_WEIGHT, CIE_X0_MEAN_NM, CIE_X0_INV_SIGMA_BELOW,
                     CIE_X0_INV_SIGMA_ABOVE)
        + cie_lobe(nm, CIE_X1_WEIGHT, CIE_X1_MEAN_NM, CIE_X1_INV_SIGMA_BELOW,
                   CIE_X1_INV_SIGMA_ABOVE)
        + cie_lobe(nm, CIE_X2_WEIGHT, CIE_X2_MEAN_NM, CIE_X2_INV_SIGMA_BELOW,
                   CIE_X2_INV_SIGMA_ABOVE);
    let y = cie_lobe(nm, CIE_Y0_WEIGHT, CIE_Y0_MEAN_NM, CIE_Y0_INV_SIGMA_BELOW,
                     CIE_Y0_INV_SIGMA_ABOVE)
        + cie_lobe(nm, CIE_Y1_WEIGHT, CIE_Y1_MEAN_NM, CIE_Y1_INV_SIGMA_BELOW,
                   CIE_Y1_INV_SIGMA_ABOVE);
    let z = cie_lobe(nm, CIE_Z0_WEIGHT, CIE_Z0_MEAN_NM, CIE_Z0_INV_SIGMA_BELOW,
                     CIE_Z0_INV_SIGMA_ABOVE)
        + cie_lobe(nm, CIE_Z1_WEIGHT, CIE_Z1_MEAN_NM, CIE_Z1_INV_SIGMA_BELOW,
                   CIE_Z1_INV_SIGMA_ABOVE);
    return vec3<f32>(x, y, z);
}

// CIE XYZ to linear sRGB (IEC 61966-2-1), each row summed left to right.
fn xyz_to_linear_srgb(c: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(XYZ_TO_SRGB_00 * c.x + XYZ_TO_SRGB_01 * c.y + XYZ_TO_SRGB_02 * c.z,
                     XYZ_TO_SRGB_10 * c.x + XYZ_TO_SRGB_11 * c.y + XYZ_TO_SRGB_12 * c.z,
                     XYZ_TO_SRGB_20 * c.x + XYZ_TO_SRGB_21 * c.y + XYZ_TO_SRGB_22 * c.z);
}

// The clipped, per-channel normalised linear sRGB weight of a wavelength (micrometres).
fn wavelength_rgb(wavelength_um: f32) -> vec3<f32> {
    let rgb = max(xyz_to_linear_srgb(cie_xyz(wavelength_um)), vec3<f32>(0.0, 0.0, 0.0));
    return rgb * vec3<f32>(SPECTRAL_RGB_SCALE_R, SPECTRAL_RGB_SCALE_G, SPECTRAL_RGB_SCALE_B);
}

// A photon's wavelength (micrometres) and flux after its first dispersive surface.
struct Dispersed {
    wavelength: f32,
    flux: vec3<f32>,
}

// core::math::spectrum::disperse: spectral (the photon's point of the sequence and its
// colour) or the three-way split (channel min(floor(3 xi), 2), x3).
fn disperse(flux: vec3<f32>, mode: u32, seed: u32, index: u32, xi: f32) -> Dispersed {
    if (mode == DISPERSION_THREE_BANDS) {
        let c = min(i32(xi * 3.0), 2);
        var one = vec3<f32>(0.0, 0.0, 0.0);
        one[c] = select(select(flux.z, flux.y, c == 1), flux.x, c == 0) * 3.0;
        return Dispersed(CHANNEL_WAVELENGTH_UM[c], one);
    }
    let wavelength = wavelength_at(spectral_sample(seed, index));
    return Dispersed(wavelength, flux * wavelength_rgb(wavelength));
}

// core::math::spectrum::split_lane: lane `lane` of the deterministic split's three.
fn split_lane(flux: vec3<f32>, mode: u32, seed: u32, index: u32, lane: u32) -> Dispersed {
    let c = i32(min(lane, 2u));
    if (mode == DISPERSION_THREE_BANDS) {
        var one = vec3<f32>(0.0, 0.0, 0.0);
        one[c] = select(select(flux.z, flux.y, c == 1), flux.x, c == 0);
        return Dispersed(CHANNEL_WAVELENGTH_UM[c], one);
    }
    let wavelength = wavelength_at((f32(c) + spectral_sample(seed, index)) * ONE_THIRD);
    return Dispersed(wavelength, flux * wavelength_rgb(wavelength) * ONE_THIRD);
}

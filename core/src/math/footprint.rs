//! Pixel footprint (Kim 2019, section 30.3.1.3, Eq. 4) and the surface area a pixel covers.
//!
//! Eq. 4 (lost in the extraction; rederived): a pixel of a `w` x `h` image with field of
//! view angles `theta_x`, `theta_y` covers, on a plane parallel to the image plane at view
//! depth `d`, a rectangle of area
//!
//! `a_p = (2 d tan(theta_x / 2) / w) * (2 d tan(theta_y / 2) / h)`.
//!
//! The source uses `d` as "the distance from the eye to the pixel"; that is exact for the
//! view depth (distance along the camera axis). A surface with unit normal `n` seen along
//! the unit view ray `omega` covers `a_p * |omega . f| / |omega . n|` of surface, where `f`
//! is the camera's forward axis: the pixel pencil has cross-section `a_p |omega . f|` and
//! meets the surface obliquely. Radiance stored from flux (Eq. 5) divides by this surface
//! area: `L = f_r * Phi / A_surface`.

/// Kim 2019, Eq. 4: world-space area (scene units^2) of one pixel at view depth `depth` on a
/// plane parallel to the image plane.
#[inline]
pub fn pixel_footprint(
    depth: f32,
    width: u32,
    height: u32,
    tan_half_fov_x: f32,
    tan_half_fov_y: f32,
) -> f32 {
    let sx = 2.0 * depth * tan_half_fov_x / width as f32;
    let sy = 2.0 * depth * tan_half_fov_y / height as f32;
    sx * sy
}

/// Smallest cosine used for obliquity, so that a surface seen edge-on gets a large but
/// finite area instead of a division by zero.
pub const MIN_COSINE: f32 = 1e-4;

/// Surface area (scene units^2) that a pixel with plane-parallel footprint `footprint`
/// covers on a surface, given `cos_axis = |omega . f|` and `cos_normal = |omega . n|`.
#[inline]
pub fn pixel_surface_area(footprint: f32, cos_axis: f32, cos_normal: f32) -> f32 {
    footprint * cos_axis.abs() / cos_normal.abs().max(MIN_COSINE)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn footprint_tiles_the_view_plane() {
        // w*h pixels at depth d cover the whole view rectangle (2 d tan_x)(2 d tan_y).
        let (w, h, tx, ty, d) = (640u32, 480u32, 0.5f32, 0.375f32, 3.0f32);
        let total = pixel_footprint(d, w, h, tx, ty) * (w * h) as f32;
        let expect = (2.0 * d * tx) * (2.0 * d * ty);
        assert!((total - expect).abs() / expect < 1e-5);
        assert_eq!(pixel_surface_area(1.0, 1.0, 1.0), 1.0);
        assert!(pixel_surface_area(1.0, 1.0, 0.0).is_finite());
    }
}

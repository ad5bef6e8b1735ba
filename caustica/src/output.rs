//! Writing frames: linear EXR for data, tone-mapped sRGB PNG for looking, JSON stats.

use caustica_core::image::Image;
use std::path::Path;

/// Writes a linear RGBA f32 OpenEXR file.
pub fn write_exr(path: &Path, img: &Image) -> Result<(), String> {
    let w = img.width as usize;
    exr::prelude::write_rgba_file(path, w, img.height as usize, |x, y| {
        let p = img.pixels[y * w + x];
        (p[0], p[1], p[2], p[3])
    })
    .map_err(|e| format!("{}: {e}", path.display()))
}

/// Narkowicz's ACES filmic fit, then the sRGB transfer function, after `exposure`.
pub fn tone_map(linear: f32, exposure: f32) -> u8 {
    let x = (linear * exposure).max(0.0);
    let x = if x.is_finite() { x } else { 0.0 };
    let y = ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0);
    let s = if y <= 0.003_130_8 {
        12.92 * y
    } else {
        1.055 * y.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0 + 0.5) as u8
}

/// Writes a tone-mapped 8-bit sRGB PNG.
pub fn write_png(path: &Path, img: &Image, exposure: f32) -> Result<(), String> {
    let mut buf = image::RgbImage::new(img.width, img.height);
    for (i, px) in buf.pixels_mut().enumerate() {
        let p = img.pixels[i];
        *px = image::Rgb([
            tone_map(p[0], exposure),
            tone_map(p[1], exposure),
            tone_map(p[2], exposure),
        ]);
    }
    buf.save(path)
        .map_err(|e| format!("{}: {e}", path.display()))
}

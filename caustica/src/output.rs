//! Writing frames: linear EXR for data, tone-mapped sRGB PNG for looking, JSON stats.

use caustica_core::frame::image::{tone_map, Image};
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

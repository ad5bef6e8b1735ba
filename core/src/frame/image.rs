//! Host-side images read back from a backend.

/// Linear RGBA f32 image, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    /// Width (pixels).
    pub width: u32,
    /// Height (pixels).
    pub height: u32,
    /// `width * height` texels, row-major from the top-left (linear RGBA).
    pub pixels: Vec<[f32; 4]>,
}

impl Image {
    /// An image from its pixels; panics unless `pixels.len() == width * height`.
    pub fn new(width: u32, height: u32, pixels: Vec<[f32; 4]>) -> Image {
        assert_eq!(pixels.len(), (width * height) as usize);
        Image {
            width,
            height,
            pixels,
        }
    }

    /// The pixel at column `x`, row `y` (from the top-left).
    pub fn at(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// True when every channel of every pixel is finite.
    pub fn all_finite(&self) -> bool {
        self.pixels.iter().all(|p| p.iter().all(|c| c.is_finite()))
    }

    /// Sum of the rgb channels over all pixels (f64).
    pub fn sum_rgb(&self) -> [f64; 3] {
        let mut s = [0.0f64; 3];
        for p in &self.pixels {
            for c in 0..3 {
                s[c] += p[c] as f64;
            }
        }
        s
    }
}

/// Rec. 709 luminance of linear rgb.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
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

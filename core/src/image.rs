//! Host-side images read back from a backend.

/// Linear RGBA f32 image, row-major from the top-left.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

impl Image {
    pub fn new(width: u32, height: u32, pixels: Vec<[f32; 4]>) -> Image {
        assert_eq!(pixels.len(), (width * height) as usize);
        Image {
            width,
            height,
            pixels,
        }
    }

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

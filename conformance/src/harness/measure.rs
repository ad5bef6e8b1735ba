//! Numbers the checks measure and report.

use glam::Vec3;

/// Relative L2 error `||b - a|| / ||a||` over the rgb channels of the pixels `mask` selects
/// (`a` is the reference). 0 when both are zero, infinite when only `a` is.
pub fn relative_l2(a: &[[f32; 4]], b: &[[f32; 4]], mask: Option<&[bool]>) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for i in 0..a.len().min(b.len()) {
        if mask.is_some_and(|m| !m[i]) {
            continue;
        }
        for ch in 0..3 {
            let (x, y) = (a[i][ch] as f64, b[i][ch] as f64);
            num += (x - y) * (x - y);
            den += x * x;
        }
    }
    if num == 0.0 {
        0.0
    } else if den == 0.0 {
        f64::INFINITY
    } else {
        (num / den).sqrt()
    }
}

/// `100 num / den` (100 when `den` is 0).
pub(crate) fn pct(num: u64, den: u64) -> f64 {
    if den == 0 {
        100.0
    } else {
        100.0 * num as f64 / den as f64
    }
}

/// A `[f32; 3]` of a device struct as a vector.
pub(crate) fn v3(a: [f32; 3]) -> Vec3 {
    Vec3::from(a)
}

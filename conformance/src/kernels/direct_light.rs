//! `direct_light` on the reference's G-buffer: a pixel agrees within [`DIRECT_REL`] (plus
//! [`DIRECT_FLOOR`] of the channel's maximum), and [`DIRECT_AGREEMENT`] of the pixels must.
//! The same per-pixel comparison judges the direct image of a whole frame
//! ([`crate::techniques::sspm::compare_frames`]).

use crate::harness::fixture::{Fixture, ReferenceInputs};
use crate::harness::measure::{pct, relative_l2};
use crate::harness::tolerance::{DIRECT_AGREEMENT, DIRECT_FLOOR, DIRECT_REL};
use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;

/// True when `a` and `b` agree as [`DIRECT_REL`] says; `floor` is per channel.
fn direct_pixel_agrees(a: [f32; 4], b: [f32; 4], floor: [f32; 3]) -> bool {
    (0..3).all(|ch| (a[ch] - b[ch]).abs() <= DIRECT_REL * a[ch].abs().max(b[ch].abs()) + floor[ch])
        && a[3].to_bits() == b[3].to_bits()
}

fn channel_max(img: &[[f32; 4]]) -> [f32; 3] {
    let mut m = [0.0f32; 3];
    for p in img {
        for ch in 0..3 {
            if p[ch].is_finite() {
                m[ch] = m[ch].max(p[ch].abs());
            }
        }
    }
    m
}

/// Per-pixel comparison of two direct-light images over the pixels `mask` selects.
pub(crate) fn compare_direct(
    what: &str,
    width: u32,
    a: &[[f32; 4]],
    b: &[[f32; 4]],
    mask: Option<&[bool]>,
) -> Verdict {
    let mut v = Verdict::new(what);
    let floor = channel_max(a).map(|m| DIRECT_FLOOR * m);
    let (mut n, mut good, mut first_bad) = (0u64, 0u64, None);
    for i in 0..a.len() {
        if mask.is_some_and(|m| !m[i]) {
            continue;
        }
        n += 1;
        if direct_pixel_agrees(a[i], b[i], floor) {
            good += 1;
        } else {
            first_bad.get_or_insert(format!(
                "({}, {}): {:?} vs cpu {:?}",
                i as u32 % width,
                i as u32 / width,
                b[i],
                a[i]
            ));
        }
    }
    let l2 = relative_l2(a, b, mask);
    v.check(good as f64 >= DIRECT_AGREEMENT * n as f64, || {
        format!(
            "agrees on only {good}/{n} pixels (need {}%), first {}",
            100.0 * DIRECT_AGREEMENT,
            first_bad.clone().unwrap_or_default()
        )
    });
    v.note(format!(
        "agrees on {good}/{n} pixels ({:.3}%); relative L2 {l2:.3e}",
        pct(good, n)
    ));
    v
}

/// `direct_light` on the reference's G-buffer.
pub fn check_direct(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let a = fx.run_direct(r, &inputs.gbuffer)?;
    let b = fx.run_direct(c, &inputs.gbuffer)?;
    Ok(compare_direct(
        "direct_light",
        fx.camera.width,
        &a,
        &b,
        None,
    ))
}

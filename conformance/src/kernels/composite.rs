//! `composite` on the reference's direct and filtered images: bitwise equal.

use crate::harness::fixture::{run_composite, ReferenceInputs};
use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;

/// `composite` on the reference's direct and filtered images: exact. Each output channel
/// is one IEEE addition, correctly rounded on every backend (nothing to contract into an
/// FMA); alpha is the constant 1. The only licence is subnormal flushing: a channel whose
/// operands or sum are subnormal may come back as zero on a GPU.
pub fn check_composite(
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("composite");
    let a = run_composite(r, &inputs.direct, &inputs.filtered)?;
    let b = run_composite(c, &inputs.direct, &inputs.filtered)?;
    let subnormal = |x: f32| x != 0.0 && x.abs() < f32::MIN_POSITIVE;
    let mut differ = 0u64;
    for i in 0..a.len() {
        for ch in 0..4 {
            let (x, y) = (a[i][ch], b[i][ch]);
            let flushed = ch < 3
                && (subnormal(inputs.direct[i][ch])
                    || subnormal(inputs.filtered[i][ch])
                    || subnormal(x))
                && y.abs() < f32::MIN_POSITIVE;
            if x.to_bits() != y.to_bits() && !flushed {
                differ += 1;
            }
        }
    }
    v.check(differ == 0, || {
        format!("{differ} channels are not bitwise equal")
    });
    v.note(format!("{} pixels, {differ} channels differ", a.len()));
    Ok(v)
}

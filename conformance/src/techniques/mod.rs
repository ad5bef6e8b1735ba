//! Whole techniques compared with the reference (the second level of comparison, see
//! [`crate::harness`]): one file per
//! technique, each rendering a frame on both backends and comparing photon statistics and
//! images after the technique's own filter.

pub mod sspm;

/// One frame of `t` on `b`: every requested output read back and checked finite, the
/// camera-space ones returned by name (what the bitwise comparisons of updates against
/// fresh techniques compare).
pub fn frame_outputs(
    t: &mut dyn caustica_core::Technique,
    b: &mut dyn caustica_core::Backend,
) -> Vec<(String, Vec<[f32; 4]>)> {
    t.frame(b, &mut |_| {}).expect("frame");
    t.outputs()
        .into_iter()
        .filter(|o| o.requested)
        .filter_map(|o| {
            let img = t.read_output(b, o.output).expect("read");
            assert!(img.all_finite(), "{}: not finite", o.name);
            o.camera_space.then(|| (o.name.to_string(), img.pixels))
        })
        .collect()
}

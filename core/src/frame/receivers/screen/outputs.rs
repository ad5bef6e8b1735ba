//! The screen receiver's device images of a frame, by [`Output`].

use crate::device::handle::ImageBuf;
use crate::frame::output::Output;

/// The outputs the screen receiver gives a technique.
pub const OUTPUTS: [Output; 4] = [
    Output::Composite,
    Output::Direct,
    Output::RawCaustics,
    Output::FilteredCaustics,
];

/// Device images of a frame (handles; read them with `read_output`). An image
/// is `None` when it was not requested, or when the plan knows it is zero (no light emits
/// photons): `read_output` then returns zeros without a device buffer.
#[derive(Clone, Copy, Debug)]
pub struct FrameImages {
    /// Image width (pixels).
    pub width: u32,
    /// Image height (pixels).
    pub height: u32,
    /// Direct light + filtered caustics (the direct image's handle when there are no
    /// caustics).
    pub composite: Option<ImageBuf>,
    /// Direct light only (shadow rays, specular chains from mirror/glass pixels).
    pub direct: Option<ImageBuf>,
    /// Caustic radiance straight from the photon map (alpha: mean hit distance).
    pub raw_caustics: Option<ImageBuf>,
    /// Caustic radiance after the filter (alpha: the density gather's radius in pixels,
    /// or the bilateral gather's mean hit distance).
    pub filtered_caustics: Option<ImageBuf>,
}

impl FrameImages {
    /// The handle of `output`, if it has a device buffer (`None` for an output the screen
    /// receiver does not make).
    pub fn get(&self, output: Output) -> Option<ImageBuf> {
        match output {
            Output::Composite => self.composite,
            Output::Direct => self.direct,
            Output::RawCaustics => self.raw_caustics,
            Output::FilteredCaustics => self.filtered_caustics,
            _ => None,
        }
    }
}

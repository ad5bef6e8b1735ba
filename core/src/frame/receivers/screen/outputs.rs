//! Sspm's outputs: the images a caller can ask a frame for, and their device handles.

use crate::device::handle::ImageBuf;
use serde::{Deserialize, Serialize};

/// The images a caller asks a frame for (all by default). Composite needs direct light
/// and filtered caustics internally even when they are not asked for themselves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct Outputs {
    /// Direct light + filtered caustics.
    pub composite: bool,
    /// Direct light alone.
    pub direct: bool,
    /// Caustic radiance straight from the screen-space photon map.
    pub raw_caustics: bool,
    /// Caustic radiance after the bilateral gather.
    pub filtered_caustics: bool,
}

impl Default for Outputs {
    fn default() -> Self {
        Outputs {
            composite: true,
            direct: true,
            raw_caustics: true,
            filtered_caustics: true,
        }
    }
}

impl Outputs {
    /// Only the filtered caustics (a renderer that does its own direct light).
    pub const CAUSTICS_ONLY: Outputs = Outputs {
        composite: false,
        direct: false,
        raw_caustics: false,
        filtered_caustics: true,
    };

    /// Names ([`Output::stem`]) of the requested outputs.
    pub fn names(&self) -> Vec<String> {
        Output::ALL
            .iter()
            .filter(|x| x.requested(self))
            .map(|x| x.stem().to_string())
            .collect()
    }

    /// Whether at least one output is requested.
    pub fn any(&self) -> bool {
        self.composite || self.direct || self.raw_caustics || self.filtered_caustics
    }
}

/// One of a frame's output images.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Output {
    /// Direct light + filtered caustics.
    Composite,
    /// Direct light alone (shadow rays, specular chains from mirror and glass pixels).
    Direct,
    /// Caustic radiance straight from the screen-space photon map (alpha: mean hit
    /// distance).
    RawCaustics,
    /// Caustic radiance after the filter (`SspmSettings::filter`; alpha: the density
    /// gather's radius in pixels where it gave light, or the bilateral gather's mean hit distance).
    FilteredCaustics,
}

impl Output {
    /// Every output, in the fixed order of [`crate::frame::technique::Technique::outputs`].
    pub const ALL: [Output; 4] = [
        Output::Composite,
        Output::Direct,
        Output::RawCaustics,
        Output::FilteredCaustics,
    ];

    /// File-name stem (`composite`, `direct`, `caustics_raw`, `caustics_filtered`).
    pub fn stem(&self) -> &'static str {
        match self {
            Output::Composite => "composite",
            Output::Direct => "direct",
            Output::RawCaustics => "caustics_raw",
            Output::FilteredCaustics => "caustics_filtered",
        }
    }

    /// The output whose [`Output::stem`] is `stem`.
    pub fn from_stem(stem: &str) -> Option<Output> {
        Output::ALL.into_iter().find(|o| o.stem() == stem)
    }

    /// What the image holds.
    pub fn description(&self) -> &'static str {
        match self {
            Output::Composite => "direct light + filtered caustics",
            Output::Direct => "direct light alone (shadow rays, specular chains)",
            Output::RawCaustics => "caustic radiance straight from the screen-space photon map",
            Output::FilteredCaustics => "caustic radiance after the gather",
        }
    }

    /// Whether `o` asks for this output.
    pub fn requested(&self, o: &Outputs) -> bool {
        match self {
            Output::Composite => o.composite,
            Output::Direct => o.direct,
            Output::RawCaustics => o.raw_caustics,
            Output::FilteredCaustics => o.filtered_caustics,
        }
    }
}

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
    /// The handle of `output`, if it has a device buffer.
    pub fn get(&self, output: Output) -> Option<ImageBuf> {
        match output {
            Output::Composite => self.composite,
            Output::Direct => self.direct,
            Output::RawCaustics => self.raw_caustics,
            Output::FilteredCaustics => self.filtered_caustics,
        }
    }
}

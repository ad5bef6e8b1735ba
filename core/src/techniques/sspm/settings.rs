//! Every parameter of Sspm, with its defaults and validation: the shared `frame` and
//! `trace` blocks, the screen receiver's `screen` block, and Sspm's own knobs.

use crate::frame::emission::PointEmission;
use crate::frame::error::Error;
use crate::frame::receivers::screen::ScreenSettings;
use crate::frame::settings::{FrameSettings, TechniqueSettings, TraceSettings};
use serde::{Deserialize, Serialize};

/// Every parameter of the technique; defaults from Kim 2019 where it gives them (its
/// figures use 2k x 2k photons per light).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SspmSettings {
    /// What every technique shares: photon grid, seed, accumulation, filter chain,
    /// outputs, pruning.
    pub frame: FrameSettings,
    /// How photons are followed.
    pub trace: TraceSettings,
    /// The screen receiver: the store test and the gather filter.
    pub screen: ScreenSettings,
    /// Point-light emission domain.
    pub point_emission: PointEmission,
    /// The fused pass (default): `trace_photons` deposits each stored photon into the
    /// screen photon map where its path ends, as `deposit_screen` would (no photon buffer,
    /// no second pass; 0.1-0.4 ms less trace + deposit + gather on the H200, README). Off:
    /// the photons are stored (the buffer of [`crate::Sspm::photon_buffers`], for a caller
    /// that reads them) and `deposit_screen` deposits them. The CPU's image is bitwise the
    /// same either way; a GPU's within `deposit_screen`'s own agreement
    /// (`conformance`'s `sspm_fused_trace_deposits_what_its_trace_stores`).
    pub fused_deposit: bool,
}

impl Default for SspmSettings {
    fn default() -> Self {
        SspmSettings {
            frame: FrameSettings::seeded(0x5350_4d31),
            trace: TraceSettings::default(),
            screen: ScreenSettings::default(),
            point_emission: PointEmission::CasterCone,
            fused_deposit: true,
        }
    }
}

impl TechniqueSettings for SspmSettings {
    fn frame(&self) -> &FrameSettings {
        &self.frame
    }

    fn frame_mut(&mut self) -> &mut FrameSettings {
        &mut self.frame
    }
}

impl SspmSettings {
    /// Rejects parameters that cannot give a meaningful frame.
    pub fn validate(&self) -> Result<(), Error> {
        self.frame.validate()?;
        self.frame.check_outputs(
            "sspm",
            &crate::frame::receivers::screen::ScreenReceiver::OUTPUTS,
        )?;
        self.trace.validate()?;
        self.screen.validate()
    }
}

//! Every parameter of CausticMap, with its defaults and validation: the shared `frame`
//! and `trace` blocks, the light view planes' `planes` and the caustic atlas's `atlas`.

use crate::frame::error::Error;
use crate::frame::receivers::atlas::settings::{AtlasConfig, AtlasSettings, PlaneSettings};
use crate::frame::settings::{FrameSettings, TechniqueSettings, TraceSettings};
use serde::{Deserialize, Serialize};

/// CausticMap's settings (Vanderstichelen 2021; defaults from its section 4 where it
/// gives them): the shared `frame` and `trace` blocks (a light's view plane has
/// `frame.photons_w x frame.photons_h` texels, one photon each; a light among the casters
/// gets six cube faces of `photons_w / sqrt 6` texels a side; `trace.min_relative_power`
/// is relative to the flux of the plane's centre texel), the view planes' `planes` and the
/// caustic atlas's `atlas`. `frame.temporal` blends the filtered caustics as the camera
/// sees them (useful when the seed changes every frame; the history survives camera
/// moves, it is reprojected); `frame.accumulate` traces new photons into the atlas sums
/// of the frames before, and a camera move keeps them (they are in texture space).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CausticMapSettings {
    /// What every technique shares: photon grid, seed, accumulation, filter chain,
    /// outputs, pruning, the camera's specular chains.
    pub frame: FrameSettings,
    /// How photons are followed.
    pub trace: TraceSettings,
    /// The light view planes and the photons' optics.
    pub planes: PlaneSettings,
    /// The caustic atlas: its size, filter and memory.
    pub atlas: AtlasSettings,
}

impl Default for CausticMapSettings {
    fn default() -> Self {
        CausticMapSettings {
            frame: FrameSettings::seeded(0x434d_4150),
            trace: TraceSettings::default(),
            planes: PlaneSettings::default(),
            atlas: AtlasSettings::default(),
        }
    }
}

impl TechniqueSettings for CausticMapSettings {
    fn frame(&self) -> &FrameSettings {
        &self.frame
    }

    fn frame_mut(&mut self) -> &mut FrameSettings {
        &mut self.frame
    }
}

impl CausticMapSettings {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), Error> {
        self.frame.validate()?;
        self.frame
            .check_outputs("caustic-map", &crate::frame::receivers::atlas::OUTPUTS)?;
        self.trace.validate()?;
        self.planes.validate()?;
        self.atlas.validate()
    }

    /// What the atlas receiver is made with.
    pub fn atlas_config(&self) -> AtlasConfig {
        AtlasConfig {
            frame: self.frame.clone(),
            planes: self.planes,
            atlas: self.atlas,
        }
    }
}

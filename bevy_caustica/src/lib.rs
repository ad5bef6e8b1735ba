//! `bevy_caustica`: caustics (and, opt in, photon-mapped indirect light) from
//! [caustica](../caustica) in a Bevy 0.20 app, rendered on Bevy's own wgpu device inside
//! Bevy's frame.
//!
//! Add [`CausticaPlugin`] and put a [`Caustics`] component on a `Camera3d` that has
//! `Hdr`. The plugin reads every `Mesh3d` with a `MeshMaterial3d<StandardMaterial>`, every
//! `PointLight`, `SpotLight` and `DirectionalLight`, builds caustica's scene from them
//! (see [`convert`] for the materials and the units), runs the camera's technique in
//! Bevy's render schedule on Bevy's `RenderDevice`, and adds the light it computes to the
//! view's HDR target before tonemapping.
//!
//! What it relies on in Bevy: glass (`specular_transmission > 0`) and mirrors keep
//! casting Bevy's shadows (the default; a specular object with `NotShadowCaster` would let
//! Bevy's direct light through it as well, counting it twice, and is warned about);
//! caustica adds the light that passes through or reflects off them, which Bevy does not
//! compute. The camera must have `Hdr` (without it there is no linear target to add to:
//! warned once, the image is left alone) and a perspective projection.
//!
//! Degrade, never panic: a device caustica cannot run on, a scene without specular
//! objects, a camera without `Hdr`, a mesh caustica cannot take (no positions, another
//! topology than `TriangleList`) are each logged once and leave Bevy's image as it would
//! be without the plugin (for a mesh: the rest of the scene still renders).

pub mod convert;
mod render;
mod world;

use bevy::prelude::*;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

pub use render::added_output;

/// Which of caustica's techniques a camera runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Reflect)]
pub enum CausticsTechnique {
    /// Screen-space photon mapping: photons splatted in the camera's screen space.
    #[default]
    Sspm,
    /// Texture-space caustic maps from the lights' view planes.
    CausticMap,
    /// Coarse-to-fine photon emission into caustic maps.
    AdaptiveCaustics,
    /// Multi-bounce indirect (diffuse) light by photon splatting; opt in: Bevy computes no
    /// such light, so this adds light Bevy's image never had.
    PhotonGi,
}

impl CausticsTechnique {
    /// caustica's registry name.
    pub fn registry_name(self) -> &'static str {
        match self {
            CausticsTechnique::Sspm => "sspm",
            CausticsTechnique::CausticMap => "caustic-map",
            CausticsTechnique::AdaptiveCaustics => "adaptive-caustics",
            CausticsTechnique::PhotonGi => "photon-gi",
        }
    }

    /// All four.
    pub const ALL: [CausticsTechnique; 4] = [
        CausticsTechnique::Sspm,
        CausticsTechnique::CausticMap,
        CausticsTechnique::AdaptiveCaustics,
        CausticsTechnique::PhotonGi,
    ];
}

/// Put on a `Camera3d` (with `Hdr`) to add caustica's light to what it renders. Changing
/// it at run time changes that camera's technique only (its settings in place, or a new
/// technique for another kind).
#[derive(Component, Clone, Debug, PartialEq)]
pub struct Caustics {
    /// The technique.
    pub technique: CausticsTechnique,
    /// Photons per light per frame, as a square grid of `photons x photons`.
    pub photons: u32,
    /// More of the technique's settings, a JSON object as `caustica::techniques::create`
    /// takes them (`serde_json::Value::Null`: the defaults), e.g. `{"atlas": {"atlas_size":
    /// 1024}}`; the photon grid and the outputs are the plugin's.
    pub settings: serde_json::Value,
    /// A factor on the added light (1: physically as computed).
    pub strength: f32,
}

impl Default for Caustics {
    fn default() -> Self {
        Caustics {
            technique: CausticsTechnique::Sspm,
            photons: 512,
            settings: serde_json::Value::Null,
            strength: 1.0,
        }
    }
}

/// Where a camera's caustics stand.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum CausticsStatus {
    /// Not rendered yet.
    #[default]
    Pending,
    /// Rendering: the light is added to the camera's image every frame.
    Active,
    /// Nothing is added, and why (logged once): no specular object, no light, a camera
    /// without `Hdr`, a device caustica cannot run on, a technique that failed.
    Inactive(String),
}

/// One camera's figures, a frame or more after the frame they describe.
#[derive(Clone, Debug, Default)]
pub struct CameraCaustics {
    /// The technique's registry name.
    pub technique: &'static str,
    /// Where it stands.
    pub status: CausticsStatus,
    /// The last frame whose device work has finished: pass times, photons, host waits.
    pub last: Option<caustica::FrameStats>,
    /// Frames whose statistics came back.
    pub frames_completed: u64,
    /// Frames recorded into Bevy's frame.
    pub frames_recorded: u64,
    /// Techniques built for this camera (the first build counts; a moved object, light or
    /// camera never does).
    pub builds: u64,
    /// Updates through caustica's update API without a rebuild (lights, instances,
    /// vertices, materials, camera, settings), each call counted.
    pub updates: u64,
    /// Host time of the last frame's updates (or build) in Bevy's render schedule (ms).
    pub host_update_ms: f64,
    /// Host time of the last frame's recording and encoding into Bevy's encoder (ms).
    pub host_record_ms: f64,
}

/// caustica's figures per camera (by the camera's entity in the main world), written by
/// the render world when a frame's device work has finished and its statistics came back
/// (never waited for).
#[derive(Resource, Clone, Default)]
pub struct CausticaStats(pub(crate) Arc<Mutex<HashMap<Entity, CameraCaustics>>>);

impl CausticaStats {
    /// A camera's figures.
    pub fn get(&self, camera: Entity) -> Option<CameraCaustics> {
        self.0.lock().ok()?.get(&camera).cloned()
    }

    /// Every camera's figures.
    pub fn all(&self) -> HashMap<Entity, CameraCaustics> {
        self.0.lock().map(|m| m.clone()).unwrap_or_default()
    }

    pub(crate) fn with(&self, camera: Entity, f: impl FnOnce(&mut CameraCaustics)) {
        if let Ok(mut m) = self.0.lock() {
            f(m.entry(camera).or_default());
        }
    }
}

/// The plugin: see the crate's documentation.
#[derive(Default)]
pub struct CausticaPlugin;

impl Plugin for CausticaPlugin {
    fn build(&self, app: &mut App) {
        let stats = CausticaStats::default();
        app.insert_resource(stats.clone());
        world::build(app);
        // caustica's backend opens on Bevy's device on the first render frame with a
        // `Caustics` camera, not here: an app that never asks for caustics keeps Bevy's
        // device as it was.
        render::build(app, stats);
    }
}

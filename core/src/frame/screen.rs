//! The camera's own images, which every technique shares and the frame host owns: the
//! G-buffer (`primary_gbuffer`), the direct light (`direct_light`: shadow rays and
//! specular chains) and the composite (`composite`: direct plus the technique's light).
//! A technique says which it needs ([`ScreenNeeds`]); the host creates exactly those, at
//! the camera's size, and records their passes.

use crate::device::handle::{GBufferPlanes, ImageBuf, ResourceId, SceneArgs};
use crate::device::layout::{DirectParams, GpuCamera};
use crate::frame::allocation::planned_allocation;
use crate::frame::error::Error;
use crate::frame::plan::BufferPlan;
use crate::kernels::{Composite, DirectLight, PrimaryGbuffer};
use crate::recording::Recording;

/// How a technique lights its direct image (`direct_light`'s parameters besides the
/// camera and the lights).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DirectLighting {
    /// Mirror and glass bounces a camera path follows before it gives up.
    pub max_specular_depth: u32,
    /// Path weight below which a specular chain stops (fraction of the pixel's weight).
    pub min_weight: f32,
    /// One of [`crate::math::optics::fresnel_model`].
    pub fresnel_model: u32,
}

impl DirectLighting {
    /// `direct_light`'s parameters for `camera` and `light_count` lights.
    pub fn params(&self, camera: GpuCamera, light_count: u32) -> DirectParams {
        DirectParams {
            camera,
            light_count,
            max_specular_depth: self.max_specular_depth,
            min_weight: self.min_weight,
            fresnel_model: self.fresnel_model,
        }
    }
}

/// The camera images a technique's frame needs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenNeeds {
    /// The G-buffer (every screen-space pass reads it).
    pub gbuffer: bool,
    /// The direct image and how it is lit.
    pub direct: Option<DirectLighting>,
    /// The composite image (direct + the technique's light); without the direct image it
    /// is not made.
    pub composite: bool,
}

impl ScreenNeeds {
    /// No camera image at all.
    pub const NONE: ScreenNeeds = ScreenNeeds {
        gbuffer: false,
        direct: None,
        composite: false,
    };
}

/// The camera images of one frame size, as the host holds them.
#[derive(Clone, Debug)]
pub struct ScreenTargets {
    /// What they were made for.
    pub needs: ScreenNeeds,
    /// The image size they were made for (pixels).
    pub size: (u32, u32),
    /// The G-buffer's planes.
    pub gbuffer: Option<GBufferPlanes>,
    /// Direct light (linear radiance, W/(sr m^2)).
    pub direct: Option<ImageBuf>,
    /// Direct light plus the technique's light (linear radiance).
    pub composite: Option<ImageBuf>,
    /// Their buffers, bytes and plan entries.
    pub owned: Vec<ResourceId>,
    /// Bytes of all of them.
    pub bytes: u64,
    /// Name and size of each, for the frame plan.
    pub buffers: Vec<BufferPlan>,
}

impl ScreenTargets {
    /// No images (a host before its technique said what it needs).
    pub fn none() -> ScreenTargets {
        ScreenTargets {
            needs: ScreenNeeds::NONE,
            size: (0, 0),
            gbuffer: None,
            direct: None,
            composite: None,
            owned: Vec::new(),
            bytes: 0,
            buffers: Vec::new(),
        }
    }

    /// Records the creation of the images `needs` asks for at `camera`'s size, each
    /// checked against `backend`'s limits; the caller executes the recording.
    pub fn create(
        backend: &dyn crate::backend::Backend,
        rec: &mut Recording,
        camera: GpuCamera,
        needs: ScreenNeeds,
    ) -> Result<ScreenTargets, Error> {
        let pixels = camera.width * camera.height;
        let mut own = Recording::new();
        let gbuffer = needs.gbuffer.then(|| own.create_gbuffer(pixels));
        let direct = needs.direct.map(|_| own.create(pixels, "direct image"));
        let composite =
            (needs.composite && direct.is_some()).then(|| own.create(pixels, "composite image"));
        let alloc = planned_allocation(backend, &own, Some((camera.width, camera.height)))?;
        rec.steps.extend(own.steps);
        Ok(ScreenTargets {
            needs,
            size: (camera.width, camera.height),
            gbuffer,
            direct,
            composite,
            owned: alloc.owned,
            bytes: alloc.bytes,
            buffers: alloc.buffers,
        })
    }

    /// Records the G-buffer and the direct light for `camera` over `scene` with
    /// `light_count` lights (each only if made).
    pub fn record_visibility(
        &self,
        rec: &mut Recording,
        scene: SceneArgs,
        camera: GpuCamera,
        light_count: u32,
    ) {
        let Some(g) = self.gbuffer else {
            return;
        };
        rec.kernel(PrimaryGbuffer {
            scene,
            camera,
            gbuffer: g,
        });
        if let (Some(out), Some(d)) = (self.direct, self.needs.direct) {
            rec.kernel(DirectLight {
                scene,
                params: d.params(camera, light_count),
                gbuffer: g,
                out,
            });
        }
    }

    /// Records the composite of the direct light and `light` (a camera-space image of
    /// the technique's), where a composite image is made.
    pub fn record_composite(&self, rec: &mut Recording, light: ImageBuf) {
        if let (Some(direct), Some(out)) = (self.direct, self.composite) {
            rec.kernel(Composite {
                direct,
                caustics: light,
                out,
            });
        }
    }
}

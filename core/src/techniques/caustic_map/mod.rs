//! CausticMap (seed 001, "Real-time caustics via texture-space photon mapping"): photons
//! shot from each light's view plane ([`crate::frame::emission::light_view_plane`]) deposit into a
//! caustic atlas in the receivers' texture space ([`crate::frame::receivers::atlas::layout`]), which
//! the final pass samples wherever a camera path ends on a receiver (directly, in a
//! mirror or through glass). Passes:
//!
//! 1. photon work, only when the atlas is stale (new lights, settings or seed; never for
//!    a camera move): per light view plane and per batch `trace_photons` (the
//!    `SURFACE_STORE` and `FUSED_DEPOSIT` variant: each stored photon's uv and triangle
//!    go straight into the atlas's fixed-point sums, as the CPU's `caustic_map::deposit_atlas` adds them;
//!    no photon buffer, no second pass; AdaptiveCaustics' traversal keeps its slots and
//!    `refine_clusters` deposits), then `gather_caustic_map` (001's N x N gather, fixed to keep flux, as
//!    irradiance; and N = 1 for the raw map when asked), or with `gather: density` Sspm's
//!    density-adaptive gather on the atlas (`photon_count_table`, `gather_footprint`,
//!    `density_gather` twice, `GatherParams::surface` ATLAS);
//! 2. every frame: `primary_gbuffer` and `direct_light` (as Sspm), `caustic_map_lookup`
//!    (the camera's specular ray tree reading the map) and `composite`.
//!
//! **Tiles only for reached receivers.** The deposit also marks every photon's triangle
//! in a reach mask. After the photon pass the mask is read back: when the set of
//! receivers the photons reached differs from the set that has tiles, the atlas is laid
//! out anew for the reached ones (they share the whole atlas, so their texel density
//! rises) and the same photons are traced (counter-based random numbers: the same paths)
//! and deposited again. Which receivers the photons reach
//! does not depend on the layout, so the second pass reaches the same set, and a technique
//! updated into a state lays its atlas out exactly as a fresh one built in that state (the
//! seam tests compare them bitwise). A receiver no photon reaches owns no tile; a light
//! moving over a scene pays the second pass only on the frames whose reached set changes.
//! With pruning off every receiver keeps its tile. AdaptiveCaustics keeps every
//! receiver's tile too: its caustic-map-error metric refines clusters by the atlas
//! texels their photons land in, so its photons (and the receivers they reach) depend on
//! the layout, and a second pass on a new layout need not reach the same set.
//!
//! Not built yet (TODO(issue 16)): a footprint carried through curved glass (the lookup
//! unfolds the pixel's square along the path, blind to focusing).

pub use crate::frame::emission::view_planes::ViewPlanes;
pub use crate::frame::receivers::atlas::settings::{
    CausticMapOutputs, CausticMapSettings, EmissionPlane, FresnelModel, FresnelSplit, MapGather,
    ATLAS_BYTES_PER_TEXEL, DENSITY_GATHER_BYTES_PER_TEXEL, MAX_ATLAS_SIZE,
};

use crate::backend::{read_buf, Backend};
use crate::device::device_scene::{BuildBudget, DeviceScene, InstanceUpdate, SceneInstances};
use crate::device::handle::{Buf, GBufferPlanes, ImageBuf, PhotonMapPlanes, ResourceId, SceneArgs};
use crate::device::layout::*;
use crate::frame::allocation::planned_allocation;
use crate::frame::receivers::atlas::layout::{AtlasLayout, AtlasReceivers};
use crate::frame::error::Error;
use crate::frame::image::Image;
use crate::frame::irradiance_passes::FilterChain;
use crate::frame::plan::{FramePlan, PassPlan, SceneFeatures};
use crate::frame::stats::FrameStats;
use crate::frame::submitted::RecordedFrame;
use crate::frame::technique::{OutputInfo, Progress, Technique};
use crate::kernels::{
    AtlasDeposit, CausticMapLookup, Composite, DensityGather, DirectLight, FusedDeposit,
    GatherCausticMap, GatherFootprint, PhotonCountTable, PrimaryGbuffer, TracePhotons,
    TraceVariant,
};
use crate::recording::{Recording, Step};
use crate::scene::Scene;
use crate::techniques::adaptive_caustics::{
    self, AdaptiveCausticsSettings, AdaptiveSetup, AtlasTarget, DepositTarget, PhotonOptics,
    Traversal,
};
use std::time::Instant;

/// The device side of the caustic atlas (exists when the scene has casters, receivers
/// and a light that emits, or with pruning off).
#[derive(Clone, Copy, Debug)]
struct AtlasBuffers {
    triangle_tiles: Buf<u32>,
    tiles: Buf<AtlasTileTexel>,
    texels: Buf<AtlasTexel>,
    sums: PhotonMapPlanes,
    map: ImageBuf,
    raw_map: Option<ImageBuf>,
    photons: Buf<Photon>,
    photon_count: Buf<u32>,
    counters: Buf<u32>,
    /// One bit per scene triangle that a photon of this atlas reached
    /// (`math::map_gather::triangle_reach_bit`), cleared with the sums.
    triangle_reach: Buf<u32>,
    density: Option<DensityBuffers>,
}

/// The density gather's buffers on the atlas (`gather: density`).
#[derive(Clone, Copy, Debug)]
struct DensityBuffers {
    /// Photon-count summed-area table, a `u32` per texel.
    table: Buf<u32>,
    /// The atlas's edge texels (`math::density_gather::atlas_edge_texel`), uploaded once.
    edge: ImageBuf,
    /// `gather_footprint`'s output.
    footprint: ImageBuf,
    /// The row pass's output.
    rows: ImageBuf,
    /// The passes' source index (`math::density_gather::source_index_len`), zeroed each
    /// frame.
    source_index: Buf<u32>,
    /// A one-texel G-buffer: the kernels bind one, and on the atlas read none.
    gbuffer: GBufferPlanes,
}

/// The photon passes of each gather, in order (the camera-only frame skips them all).
const BOX_GATHER_PASSES: [&str; 1] = ["gather_caustic_map"];
const DENSITY_GATHER_PASSES: [&str; 3] =
    ["photon_count_table", "gather_footprint", "density_gather"];

/// The frame's camera-sized images.
#[derive(Clone, Copy, Debug, Default)]
struct Images {
    gbuffer: Option<GBufferPlanes>,
    direct: Option<ImageBuf>,
    raw: Option<ImageBuf>,
    filtered: Option<ImageBuf>,
    composite: Option<ImageBuf>,
    /// The opt-in temporal blend and A-Trous iterations on the filtered caustics.
    filters: Option<FilterChain>,
}

/// One output image of CausticMap: the names are Sspm's, so that both write the same
/// files, plus the atlas.
const OUTPUTS: [(&str, &str); 5] = [
    (
        "composite",
        "direct light + caustics from the gathered caustic map",
    ),
    (
        "direct",
        "direct light alone (shadow rays, specular chains)",
    ),
    (
        "caustics_raw",
        "caustic radiance from the raw caustic map, as the camera sees it",
    ),
    (
        "caustics_filtered",
        "caustic radiance from the gathered caustic map, as the camera sees it",
    ),
    (
        "caustic_atlas",
        "the gathered caustic map: irradiance (W/m^2) per atlas texel",
    ),
];

/// The density gather's parameters on an atlas of `settings.atlas_size` texels a side
/// (`gather: density`; `axis` 0: the row pass, 1: the column pass): the atlas is the
/// grid, edge weights only keep the gather inside a tile
/// ([`ATLAS_SIGMA_DEPTH`](crate::math::density_gather::ATLAS_SIGMA_DEPTH), no normal term),
/// the quanta are the atlas sums'.
pub fn atlas_gather_params(
    settings: &CausticMapSettings,
    flux_quantum: f32,
    hit_distance_quantum: f32,
    axis: u32,
) -> GatherParams {
    GatherParams {
        camera: GpuCamera {
            width: settings.atlas_size,
            height: settings.atlas_size,
            ..Default::default()
        },
        max_radius_px: settings.max_radius_texels,
        sigma_depth: crate::math::density_gather::ATLAS_SIGMA_DEPTH,
        normal_power: 0.0,
        axis,
        hit_distance_quantum,
        knn_photons: settings.knn_photons,
        flux_quantum,
        table_block: crate::math::density_gather::table_block(settings.max_radius_texels),
        surface: gather_surface::ATLAS,
        ..Default::default()
    }
}

/// The tiles buffer: layout `l`'s tiles, then zero tiles up to `len` (one slot per
/// receiver, so that a new layout fits the same buffer; no triangle points at a padding
/// tile).
fn tile_buffer(l: &AtlasLayout, len: usize) -> Vec<AtlasTileTexel> {
    let mut tiles = l.tiles.clone();
    tiles.resize(len.max(tiles.len()), [0; 4]);
    tiles
}

/// The density gather's edge texels of layout `l`
/// ([`crate::math::density_gather::atlas_edge_texels`]: uncovered texels name the
/// covered neighbour that inherits their flux).
fn atlas_edge_texels(l: &AtlasLayout) -> Vec<[f32; 4]> {
    crate::math::density_gather::atlas_edge_texels(&l.texels, l.plan.size.0)
}

/// CausticMap on one backend, for one scene.
pub struct CausticMap {
    /// Registry name: `caustic-map`, or `adaptive-caustics` with a traversal.
    name: &'static str,
    /// Seed 004's hierarchical emission (AdaptiveCaustics) instead of the dense planes.
    adaptive: Option<AdaptiveSetup>,
    settings: CausticMapSettings,
    model: Scene,
    scene: SceneArgs,
    bounds: crate::math::geometry::Aabb,
    caster_bounds: crate::math::geometry::Aabb,
    caster_spheres: crate::device::caster_spheres::CasterSpheres,
    has_dispersion: bool,
    degenerate_triangles: u64,
    camera: GpuCamera,
    emission: ViewPlanes,
    variant: TraceVariant,
    layout_summary: String,
    /// The diffuse receivers and their triangles (with an atlas): the atlas is laid out
    /// from them whenever the set of reached receivers changes.
    receivers: Option<AtlasReceivers>,
    /// Per receiver (in `receivers` order): whether it owns a tile now.
    tiled: Vec<bool>,
    plan: FramePlan,
    atlas: Option<AtlasBuffers>,
    images: Images,
    /// The atlas holds the photons of the current lights, settings and seed.
    atlas_valid: bool,
    /// Device buffers owned, by lifetime: the uploaded scene, the atlas, the camera images.
    scene_owned: Vec<ResourceId>,
    atlas_owned: Vec<ResourceId>,
    image_owned: Vec<ResourceId>,
    scene_bytes: u64,
    atlas_bytes: u64,
    image_bytes: u64,
    reference: Option<Image>,
    /// The acceleration structure's levels, to move instances without a rebuild.
    instances: SceneInstances,
    /// The device's largest buffer (bytes): batches hold at most that many photons.
    max_buffer_bytes: u64,
    /// The triangle budget the scene was built under.
    max_triangles: u64,
    /// The uploaded scene's buffers, as the plan lists them.
    scene_buffers: Vec<crate::frame::plan::BufferPlan>,
}

/// The uploaded scene and what the technique derives from it, kept when only the
/// settings change ([`Technique::set_settings`]).
struct UploadedScene {
    scene: SceneArgs,
    owned: Vec<ResourceId>,
    bytes: u64,
    buffers: Vec<crate::frame::plan::BufferPlan>,
    bounds: crate::math::geometry::Aabb,
    caster_bounds: crate::math::geometry::Aabb,
    caster_spheres: crate::device::caster_spheres::CasterSpheres,
    has_dispersion: bool,
    degenerate_triangles: u64,
    instances: SceneInstances,
    /// Every diffuse receiver, where the scene has casters and receivers.
    receivers: Option<AtlasReceivers>,
    /// AdaptiveCaustics' caster boxes and their objects (empty for CausticMap).
    caster_boxes: Vec<crate::math::geometry::Aabb>,
    caster_objects: Vec<u32>,
    max_triangles: u64,
}

impl UploadedScene {
    /// Builds and uploads `scene` (validated) under the triangle budget.
    fn upload(
        backend: &mut dyn Backend,
        scene: &Scene,
        max_triangles: u64,
        adaptive: bool,
    ) -> Result<UploadedScene, Error> {
        let ds = DeviceScene::build(scene, BuildBudget { max_triangles })?;
        let receiver = crate::frame::receivers::atlas::layout::atlas_receivers(scene);
        let features = SceneFeatures::of(scene);
        let receivers = ((features.mirrors || features.dielectrics) && receiver.iter().any(|r| *r))
            .then(|| AtlasReceivers::of(&ds, &receiver));
        let (caster_boxes, caster_objects) = if adaptive {
            (
                adaptive_caustics::caster_boxes(&ds),
                adaptive_caustics::caster_boxes_by_object(&ds)
                    .into_iter()
                    .map(|(o, _)| o)
                    .collect(),
            )
        } else {
            (Vec::new(), Vec::new())
        };
        let mut rec = Recording::new();
        let scene_args = rec.upload_scene(&ds);
        let alloc = planned_allocation(backend, &rec, None)?;
        backend.execute(&rec)?;
        Ok(UploadedScene {
            scene: scene_args,
            owned: alloc.owned,
            bytes: alloc.bytes,
            buffers: alloc.buffers,
            bounds: ds.bounds,
            caster_bounds: ds.caster_bounds,
            caster_spheres: ds.caster_spheres,
            has_dispersion: ds.has_dispersion,
            degenerate_triangles: ds.degenerate_triangles,
            instances: ds.instances,
            receivers,
            caster_boxes,
            caster_objects,
            max_triangles,
        })
    }
}

impl CausticMap {
    /// Validates the scene and settings, uploads the scene, lays out the atlas and
    /// creates the buffers the plan needs.
    pub fn new(
        backend: &mut dyn Backend,
        scene: &Scene,
        settings: CausticMapSettings,
    ) -> Result<CausticMap, Error> {
        Self::build(backend, scene, settings, None)
    }

    /// [`CausticMap::new`], with seed 004's adaptive emission when `adaptive` is given
    /// (AdaptiveCaustics; its settings validated by the caller).
    pub(crate) fn build(
        backend: &mut dyn Backend,
        scene: &Scene,
        settings: CausticMapSettings,
        adaptive: Option<AdaptiveCausticsSettings>,
    ) -> Result<CausticMap, Error> {
        settings.validate()?;
        scene
            .validate()
            .map_err(|p| Error::InvalidScene(format!("{}: {}", p[0].path, p[0].reason)))?;
        let uploaded =
            UploadedScene::upload(backend, scene, settings.max_triangles, adaptive.is_some())?;
        let scene_owned = uploaded.owned.clone();
        match Self::assemble(backend, scene, settings, adaptive, uploaded) {
            Ok(t) => Ok(t),
            Err(e) => {
                let _ = Self::free_ids(backend, scene_owned);
                Err(e)
            }
        }
    }

    /// The technique over an uploaded scene: plans the emission, lays out the atlas and
    /// creates the atlas's and the images' buffers. On an error, what it created is freed
    /// (the uploaded scene is the caller's).
    fn assemble(
        backend: &mut dyn Backend,
        scene: &Scene,
        settings: CausticMapSettings,
        adaptive: Option<AdaptiveCausticsSettings>,
        uploaded: UploadedScene,
    ) -> Result<CausticMap, Error> {
        let mut emission = ViewPlanes::new(
            scene,
            uploaded.bounds,
            uploaded.caster_bounds,
            uploaded.caster_spheres,
            uploaded.has_dispersion,
            &settings,
        );
        if let Some(a) = &adaptive {
            adaptive_caustics::fit_planes(&mut emission, &a.traversal(), uploaded.has_dispersion);
        }
        emission.check_light_flux()?;
        let features = SceneFeatures::of(scene);
        let casters = features.mirrors || features.dielectrics;
        let emits = !emission.planes.is_empty();
        let wants_caustics = {
            let o = &settings.outputs;
            o.composite || o.raw_caustics || o.filtered_caustics || o.atlas
        };
        let has_receivers = crate::frame::receivers::atlas::layout::atlas_receivers(scene)
            .iter()
            .any(|r| *r);
        let with_atlas = casters
            && has_receivers
            && (emits || !settings.prune)
            && (wants_caustics || !settings.prune);
        if with_atlas && settings.atlas_bytes() > settings.max_atlas_bytes {
            return Err(crate::device::error::BackendError::OutOfMemory {
                bytes: settings.atlas_bytes(),
                what: format!(
                    "caustic atlas of {0}x{0} texels: over max_atlas_bytes ({1} bytes); a \
                     smaller atlas_size, or a larger max_atlas_bytes where the device holds it",
                    settings.atlas_size, settings.max_atlas_bytes
                ),
            }
            .into());
        }
        // at creation every receiver owns a tile (and has its UVs checked); the first
        // photon pass keeps the reached ones
        let tiled = vec![true; uploaded.receivers.as_ref().map_or(0, |r| r.objects.len())];
        let layout = match (&uploaded.receivers, with_atlas) {
            (Some(r), true) => Some(Self::lay_out(scene, r, &tiled, settings.atlas_size)?),
            _ => None,
        };
        let mut variant = features.trace_variant();
        variant.surface_store = true;
        // the split only changes dielectrics: a scene without one runs the plain variant
        variant.fresnel_split =
            settings.fresnel_split == FresnelSplit::Deterministic && features.dielectrics;
        variant.adaptive = adaptive.is_some();
        // CausticMap's photons go straight into the atlas; the adaptive traversal keeps
        // its slots for refine_clusters to judge
        variant.fused_deposit = adaptive.is_none();
        let mut t = CausticMap {
            name: if adaptive.is_some() {
                "adaptive-caustics"
            } else {
                "caustic-map"
            },
            adaptive: adaptive.map(|settings| AdaptiveSetup {
                settings,
                traversal: None,
                caster_boxes: uploaded.caster_boxes,
                caster_objects: uploaded.caster_objects,
            }),
            settings,
            model: scene.clone(),
            scene: uploaded.scene,
            bounds: uploaded.bounds,
            caster_bounds: uploaded.caster_bounds,
            caster_spheres: uploaded.caster_spheres,
            has_dispersion: uploaded.has_dispersion,
            degenerate_triangles: uploaded.degenerate_triangles,
            camera: GpuCamera::from_camera(&scene.camera),
            emission,
            variant,
            layout_summary: String::new(),
            receivers: uploaded.receivers,
            tiled,
            plan: FramePlan {
                prune: true,
                features,
                outputs: Vec::new(),
                lights: Vec::new(),
                trace_variant: None,
                passes: Vec::new(),
                buffers: uploaded.buffers.clone(),
            },
            atlas: None,
            images: Images::default(),
            atlas_valid: false,
            scene_owned: uploaded.owned,
            atlas_owned: Vec::new(),
            image_owned: Vec::new(),
            scene_bytes: uploaded.bytes,
            atlas_bytes: 0,
            image_bytes: 0,
            reference: None,
            instances: uploaded.instances,
            max_buffer_bytes: backend.capabilities().max_buffer_bytes,
            max_triangles: uploaded.max_triangles,
            scene_buffers: uploaded.buffers,
        };
        let made = (|| {
            if let Some(l) = &layout {
                t.make_atlas(backend, l)?;
            }
            t.make_images(backend)
        })();
        if let Err(e) = made {
            // the scene is the caller's
            t.scene_owned.clear();
            t.scene_bytes = 0;
            let _ = t.free_all(backend);
            return Err(e);
        }
        t.replan(casters, has_receivers);
        Ok(t)
    }

    /// The uploaded scene as it is now (moved instances, receivers and caster boxes
    /// followed), for [`CausticMap::assemble`] with other settings. The buffers stay this
    /// technique's until it hands them over.
    fn uploaded_scene(&self) -> UploadedScene {
        UploadedScene {
            scene: self.scene,
            owned: self.scene_owned.clone(),
            bytes: self.scene_bytes,
            buffers: self.scene_buffers.clone(),
            bounds: self.bounds,
            caster_bounds: self.caster_bounds,
            caster_spheres: self.caster_spheres,
            has_dispersion: self.has_dispersion,
            degenerate_triangles: self.degenerate_triangles,
            instances: self.instances.clone(),
            receivers: self.receivers.clone(),
            caster_boxes: self
                .adaptive
                .as_ref()
                .map_or_else(Vec::new, |a| a.caster_boxes.clone()),
            caster_objects: self
                .adaptive
                .as_ref()
                .map_or_else(Vec::new, |a| a.caster_objects.clone()),
            max_triangles: self.max_triangles,
        }
    }

    /// Uploads the atlas layout and creates the atlas's sums, maps and photon buffers.
    fn make_atlas(&mut self, backend: &mut dyn Backend, l: &AtlasLayout) -> Result<(), Error> {
        let s = &self.settings;
        let texels = l.texels.len() as u32;
        let per_plane = self
            .emission
            .planes
            .iter()
            .map(|(_, _, p)| p.texels())
            .max()
            .unwrap_or(1);
        let cap = crate::frame::allocation::photons_per_batch(
            per_plane,
            s.max_photons_per_batch,
            self.max_buffer_bytes,
        );
        // photons a batch stores: none with the fused deposit (each goes into the atlas)
        // nor with the adaptive traversal (it traces into its own slots)
        let cap = if self.variant.fused_deposit || self.adaptive.is_some() {
            1
        } else if self.variant.fresnel_split {
            // the split stores up to split_budget per photon
            cap.max(s.split_budget)
        } else {
            cap
        };
        let mut rec = Recording::new();
        let all_receivers = self.tiled.len().max(1);
        let triangles = l.triangle_tiles.len() as u32;
        let a = AtlasBuffers {
            triangle_tiles: rec.upload(&l.triangle_tiles, "atlas triangle tiles"),
            tiles: rec.upload(&tile_buffer(l, all_receivers), "atlas tiles"),
            texels: rec.upload(&l.texels, "atlas texels"),
            sums: rec.create_photon_map(texels),
            map: rec.create(texels, "caustic map"),
            raw_map: (s.outputs.raw_caustics || !s.prune)
                .then(|| rec.create(texels, "raw caustic map")),
            photons: rec.create(cap, "photons"),
            photon_count: rec.create(1, "photon count"),
            counters: rec.create(counter::WORDS as u32, "photon counters"),
            triangle_reach: rec.create(
                crate::math::map_gather::triangle_reach_words(triangles),
                "atlas triangle reach",
            ),
            density: (s.gather == MapGather::Density).then(|| DensityBuffers {
                table: rec.create(texels, "atlas photon count table"),
                edge: rec.upload(&atlas_edge_texels(l), "atlas edge texels"),
                footprint: rec.create(texels, "atlas gather footprints"),
                rows: rec.create(texels, "atlas gather rows"),
                source_index: rec.create(
                    crate::math::density_gather::source_index_len(s.atlas_size, s.atlas_size),
                    "atlas gather source index",
                ),
                gbuffer: rec.create_gbuffer(1),
            }),
        };
        let finest = self
            .emission
            .planes
            .iter()
            .map(|(_, _, p)| p.resolution.0)
            .max()
            .unwrap_or(1);
        if let Some(ad) = &mut self.adaptive {
            let levels = (finest / ad.settings.start_grid).max(1).ilog2();
            ad.traversal = Some(Traversal::record(
                &mut rec,
                &ad.settings.traversal(),
                levels,
                &ad.caster_boxes,
                false,
            ));
        }
        let alloc = planned_allocation(backend, &rec, None)?;
        backend.execute(&rec)?;
        self.atlas = Some(a);
        self.atlas_owned = alloc.owned;
        self.atlas_bytes = alloc.bytes;
        self.plan.buffers.extend(alloc.buffers);
        self.layout_summary = self.describe_layout(l);
        Ok(())
    }

    /// Lays the atlas out for the receivers flagged in `include`; a receiver whose UVs
    /// cannot address a map is named by its scene object.
    fn lay_out(
        scene: &Scene,
        receivers: &AtlasReceivers,
        include: &[bool],
        atlas_size: u32,
    ) -> Result<AtlasLayout, Error> {
        receivers
            .layout(include, (atlas_size, atlas_size))
            .map_err(|e| match e {
                crate::frame::receivers::atlas::layout::AtlasError::BadUvs { receiver, reason } => {
                    Error::InvalidScene(format!(
                        "objects[{receiver}] ('{}'): its UVs cannot address a caustic map: \
                         {reason}",
                        scene.objects[receiver as usize].name
                    ))
                }
                other => Error::InvalidScene(other.to_string()),
            })
    }

    /// The plan's words for layout `l`.
    fn describe_layout(&self, l: &AtlasLayout) -> String {
        let left_out = self.tiled.iter().filter(|t| !**t).count();
        format!(
            "{} tiles in {}x{} texels at {:.4} texels per scene unit^2, {} texels covered{}",
            l.tiles.len(),
            l.plan.size.0,
            l.plan.size.1,
            l.plan.texels_per_unit_area,
            l.covered_texels,
            if left_out == 0 {
                String::new()
            } else {
                format!("; {left_out} receivers no photon reaches own no tile")
            }
        )
    }

    /// Lays the atlas out anew for the receivers flagged in `include` and writes the
    /// layout's buffers in place (no buffer is reallocated); the plan states the new
    /// layout.
    fn relayout(
        &mut self,
        backend: &mut dyn Backend,
        a: AtlasBuffers,
        include: &[bool],
    ) -> Result<(), Error> {
        let Some(r) = &self.receivers else {
            return Ok(());
        };
        let l = Self::lay_out(&self.model, r, include, self.settings.atlas_size)?;
        let mut rec = Recording::new();
        rec.update(a.triangle_tiles, &l.triangle_tiles, "atlas triangle tiles")?;
        rec.update(
            a.tiles,
            &tile_buffer(&l, a.tiles.len as usize),
            "atlas tiles",
        )?;
        rec.update(a.texels, &l.texels, "atlas texels")?;
        if let Some(d) = a.density {
            rec.update(d.edge, &atlas_edge_texels(&l), "atlas edge texels")?;
        }
        backend.execute(&rec)?;
        self.tiled = include.to_vec();
        self.layout_summary = self.describe_layout(&l);
        self.replan(true, true);
        Ok(())
    }

    /// Creates the camera-sized images the outputs need.
    fn make_images(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        let o = self.settings.outputs;
        let keep = |x: bool| x || !self.settings.prune;
        let pixels = self.camera.width * self.camera.height;
        let caustics = self.atlas.is_some();
        let mut rec = Recording::new();
        let direct_needed = keep(o.direct || o.composite);
        let s = &self.settings;
        let filtered_needed = caustics && keep(o.filtered_caustics || o.composite);
        let filters = (filtered_needed && (s.temporal || s.atrous_iterations > 0)).then(|| {
            FilterChain::create(
                &mut rec,
                pixels,
                self.camera,
                s.temporal,
                s.atrous_iterations > 0,
            )
        });
        let images = Images {
            // direct light and the filters' edge stopping read the camera's G-buffer
            gbuffer: (direct_needed || filters.is_some()).then(|| rec.create_gbuffer(pixels)),
            filters,
            direct: direct_needed.then(|| rec.create(pixels, "direct image")),
            raw: (caustics && keep(o.raw_caustics))
                .then(|| rec.create(pixels, "raw caustics image")),
            filtered: filtered_needed.then(|| rec.create(pixels, "filtered caustics image")),
            composite: (caustics && keep(o.composite))
                .then(|| rec.create(pixels, "composite image")),
        };
        let alloc =
            planned_allocation(backend, &rec, Some((self.camera.width, self.camera.height)))?;
        backend.execute(&rec)?;
        self.images = images;
        self.image_owned = alloc.owned;
        self.image_bytes = alloc.bytes;
        self.plan
            .buffers
            .retain(|b| !b.name.contains("image") && !b.name.starts_with("gbuffer"));
        self.plan.buffers.extend(alloc.buffers);
        Ok(())
    }

    fn free_ids(backend: &mut dyn Backend, ids: Vec<ResourceId>) -> Result<(), Error> {
        let mut rec = Recording::new();
        for id in ids {
            rec.steps.push(Step::Free { id });
        }
        backend.execute(&rec)?;
        Ok(())
    }

    fn free_all(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        let ids: Vec<ResourceId> = std::mem::take(&mut self.image_owned)
            .into_iter()
            .chain(std::mem::take(&mut self.atlas_owned))
            .chain(std::mem::take(&mut self.scene_owned))
            .collect();
        self.atlas = None;
        if let Some(a) = &mut self.adaptive {
            a.traversal = None;
        }
        self.images = Images::default();
        Self::free_ids(backend, ids)
    }

    /// The frame plan from the emission, the atlas and the images.
    fn replan(&mut self, casters: bool, receivers: bool) {
        let lights = self.emission.light_plans();
        let atlas = self.atlas.is_some();
        let photons = atlas && !self.emission.planes.is_empty();
        let why_no_atlas = if !casters {
            "no specular surface (caustic caster) in the scene"
        } else if !receivers {
            "no diffuse receiver in the scene"
        } else if self.emission.planes.is_empty() {
            "no light emits photons towards a caster"
        } else {
            "no caustic output was requested"
        };
        let mut passes = Vec::new();
        let mut pass = |name: &str, runs: bool, yes: &str, no: &str| {
            passes.push(PassPlan {
                name: name.into(),
                runs,
                reason: if runs { yes.into() } else { no.into() },
            });
        };
        let i = self.images;
        pass(
            "primary_gbuffer",
            i.gbuffer.is_some(),
            "direct light or the temporal and A-Trous filters read the G-buffer",
            "neither direct light nor the composite nor a filter was requested",
        );
        pass(
            "direct_light",
            i.direct.is_some(),
            "direct or composite requested",
            "neither direct light nor the composite was requested",
        );
        let layout = format!("the caustic atlas: {}", self.layout_summary);
        let stale = format!("when the atlas is stale (lights, settings or seed changed); {layout}");
        if let Some(a) = &self.adaptive {
            let traversal = format!(
                "seed 004's traversal ({:?} metric, {}^2 start grid, batches of {} clusters), \
                 {stale}",
                a.settings.metric,
                a.settings.start_grid,
                a.traversal.as_ref().map_or(0, |t| t.batch_clusters)
            );
            for name in ["trace_photons", "refine_clusters"] {
                pass(name, photons, &traversal, why_no_atlas);
            }
        } else {
            pass(
                "trace_photons",
                photons,
                &format!("each stored photon straight into the atlas, {stale}"),
                why_no_atlas,
            );
        }
        let density = self.atlas.is_some_and(|a| a.density.is_some());
        let raw_map = self.atlas.is_some_and(|a| a.raw_map.is_some());
        pass(
            "gather_caustic_map",
            photons && (!density || raw_map),
            &if density {
                format!("the raw map (N = 1), {stale}")
            } else {
                format!("001's N x N gather, {stale}")
            },
            if !photons {
                why_no_atlas
            } else {
                "the density gather filters the map and no raw map was requested"
            },
        );
        for name in DENSITY_GATHER_PASSES {
            pass(
                name,
                photons && density,
                &format!("the density gather on the atlas, {stale}"),
                if !photons {
                    why_no_atlas
                } else {
                    "the map's gather is 001's N x N box (gather: box)"
                },
            );
        }
        pass(
            "caustic_map_lookup",
            i.filtered.is_some() || i.raw.is_some(),
            "caustics seen by the camera were requested",
            if atlas {
                "no camera-space caustic output was requested"
            } else {
                why_no_atlas
            },
        );
        let chain = i.filters;
        pass(
            "temporal_blend",
            chain.is_some_and(|f| f.temporal.is_some()),
            "setting temporal: the filtered caustics over reprojected history",
            if self.settings.temporal {
                "no filtered caustics are made"
            } else {
                "temporal off"
            },
        );
        pass(
            "atrous_filter",
            chain.is_some_and(|f| f.atrous.is_some()),
            "setting atrous_iterations, on the filtered caustics as the camera sees them",
            if self.settings.atrous_iterations > 0 {
                "no filtered caustics are made"
            } else {
                "atrous_iterations = 0"
            },
        );
        pass(
            "composite",
            i.composite.is_some(),
            "composite requested",
            if atlas {
                "composite not requested"
            } else {
                why_no_atlas
            },
        );
        let o = self.settings.outputs;
        self.plan = FramePlan {
            prune: self.settings.prune,
            features: self.plan.features,
            outputs: OUTPUTS
                .iter()
                .zip([
                    o.composite,
                    o.direct,
                    o.raw_caustics,
                    o.filtered_caustics,
                    o.atlas,
                ])
                .filter(|(_, r)| *r)
                .map(|((n, _), _)| n.to_string())
                .collect(),
            lights,
            trace_variant: photons.then_some(self.variant),
            passes,
            buffers: std::mem::take(&mut self.plan.buffers),
        };
    }

    pub(crate) fn run(
        backend: &mut dyn Backend,
        rec: &Recording,
        stats: &mut FrameStats,
    ) -> Result<(), Error> {
        for t in backend.execute(rec)? {
            stats.add_pass_time(t.kernel, t.seconds);
        }
        Ok(())
    }

    /// The density gather's parameters on the atlas (`axis` 0: rows).
    fn atlas_gather_params(&self, axis: u32) -> GatherParams {
        atlas_gather_params(
            &self.settings,
            self.emission.flux_quantum,
            self.emission.hit_distance_quantum,
            axis,
        )
    }

    fn atlas_params(&self, a: &AtlasBuffers, gather_width: u32) -> AtlasParams {
        AtlasParams {
            width: self.settings.atlas_size,
            height: self.settings.atlas_size,
            flux_quantum: self.emission.flux_quantum,
            hit_distance_quantum: self.emission.hit_distance_quantum,
            photon_capacity: a.photons.len,
            gather_width,
            _pad: [0; 2],
        }
    }

    /// The photon passes: clear the atlas, trace and deposit every plane in batches (twice
    /// when the reached receivers change: see the module doc), gather. Fills the photon
    /// accounting of `stats`.
    fn photon_pass(
        &mut self,
        backend: &mut dyn Backend,
        a: AtlasBuffers,
        stats: &mut FrameStats,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(), Error> {
        let before = stats.clone();
        let mut adaptive = self.trace_and_deposit(backend, a, stats, progress)?;
        if self.settings.prune && self.adaptive.is_none() {
            if let Some(r) = &self.receivers {
                let reached = r.reached(&read_buf(backend, a.triangle_reach)?);
                if reached != self.tiled {
                    self.relayout(backend, a, &reached)?;
                    // the same photons into the new tiles: the photon accounting is the
                    // second pass's, the device time both passes'
                    let first = std::mem::replace(stats, before);
                    stats.plan = Some(self.plan.clone());
                    adaptive = self.trace_and_deposit(backend, a, stats, progress)?;
                    stats.absorb_pass_times(&first);
                }
            }
        }
        let s = self.settings.clone();
        let deposit = self.atlas_params(&a, 1);
        let traversal = self.adaptive.as_ref().and_then(|t| t.traversal.as_ref());
        let mut rec = Recording::new();
        if let Some(d) = a.density {
            let rows = self.atlas_gather_params(0);
            let columns = self.atlas_gather_params(1);
            for params in [rows, columns] {
                rec.kernel(PhotonCountTable {
                    params,
                    photon_map: a.sums,
                    table: d.table,
                    gbuffer: d.gbuffer,
                    edge: d.edge,
                });
            }
            rec.clear(d.source_index);
            rec.kernel(GatherFootprint {
                params: rows,
                photon_map: a.sums,
                table: d.table,
                out: d.footprint,
                edge: d.edge,
                source_index: d.source_index,
            });
            for (params, input, out) in [(rows, d.footprint, d.rows), (columns, d.rows, a.map)] {
                rec.kernel(DensityGather {
                    params,
                    gbuffer: d.gbuffer,
                    edge: d.edge,
                    input,
                    out,
                    source_index: d.source_index,
                });
            }
        } else {
            rec.kernel(GatherCausticMap {
                params: self.atlas_params(&a, s.gather_width),
                texels: a.texels,
                tiles: a.tiles,
                atlas: a.sums,
                out: a.map,
            });
        }
        if let Some(raw) = a.raw_map {
            rec.kernel(GatherCausticMap {
                params: deposit,
                texels: a.texels,
                tiles: a.tiles,
                atlas: a.sums,
                out: raw,
            });
        }
        Self::run(backend, &rec, stats)?;
        let c = read_buf(backend, a.counters)?;
        stats.read_counters(&c, self.emission.flux_quantum);
        if let Some(t) = traversal {
            t.output_stats(backend, self.emission.flux_quantum, stats, adaptive)?;
        }
        self.atlas_valid = true;
        Ok(())
    }

    /// Clears the atlas sums, counters and reach mask, then traces and deposits every
    /// plane in batches; fills the photon accounting of `stats` and returns the adaptive
    /// traversal's statistics.
    fn trace_and_deposit(
        &mut self,
        backend: &mut dyn Backend,
        a: AtlasBuffers,
        stats: &mut FrameStats,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<crate::frame::stats::AdaptiveStats, Error> {
        let s = self.settings.clone();
        let mut rec = Recording::new();
        rec.clear_photon_map(&a.sums);
        rec.clear(a.counters);
        rec.clear(a.triangle_reach);
        Self::run(backend, &rec, stats)?;
        stats.variants.push(crate::kernels::variant_label(
            "trace_photons",
            &self.variant.constants(),
        ));
        let total: u64 = self
            .emission
            .planes
            .iter()
            .map(|(_, _, p)| p.texels())
            .sum();
        let mut done = 0u64;
        let deposit = self.atlas_params(&a, 1);
        let traversal = self.adaptive.as_ref().and_then(|t| t.traversal.as_ref());
        let mut adaptive = crate::frame::stats::AdaptiveStats::default();
        if let Some(t) = traversal {
            let mut rec = Recording::new();
            rec.clear(t.output_counters);
            Self::run(backend, &rec, stats)?;
        }
        for (light, k, plane) in &self.emission.planes {
            let n = plane.texels();
            let flux = plane.power.as_dvec3() * plane.plane_measure();
            for c in 0..3 {
                stats.emitted_flux[c] += flux[c];
            }
            if let Some(t) = traversal {
                let target = DepositTarget::Atlas(AtlasTarget {
                    triangle_tiles: a.triangle_tiles,
                    tiles: a.tiles,
                    sums: a.sums,
                    atlas_width: s.atlas_size,
                    flux_quantum: self.emission.flux_quantum,
                    hit_distance_quantum: self.emission.hit_distance_quantum,
                    trace_counters: a.counters,
                });
                let optics = PhotonOptics {
                    max_bounces: s.max_bounces,
                    min_relative_power: s.min_relative_power,
                    fresnel_model: s.fresnel.kernel_value(),
                    caster_spheres: self.emission.caster_spheres,
                };
                let before = adaptive.photons_processed;
                t.run_plane(
                    backend,
                    self.scene,
                    self.variant,
                    &target,
                    (*light, plane, ViewPlanes::plane_seed(s.seed, *light, *k)),
                    optics,
                    stats,
                    &mut adaptive,
                    &mut |traced| {
                        progress(Progress {
                            photons_done: (done + traced - before).min(total),
                            photons_total: total,
                        })
                    },
                )?;
                done += adaptive.photons_processed - before;
                continue;
            }
            stats.photons_emitted += n;
            let mut first = 0u64;
            // the fused deposit stores nothing: a batch is bounded by the settings and the
            // largest launch only
            let per_batch = crate::frame::allocation::photons_per_batch(
                n,
                s.max_photons_per_batch,
                self.max_buffer_bytes,
            ) as u64;
            while first < n {
                let count = (n - first).min(per_batch) as u32;
                let mut rec = Recording::new();
                rec.kernel(TracePhotons {
                    scene: self.scene,
                    variant: self.variant,
                    params: TraceParams {
                        split_budget: s.split_budget,
                        fresnel_model: s.fresnel.kernel_value(),
                        ..self.emission.trace_params(
                            plane,
                            *light,
                            (first as u32, count),
                            ViewPlanes::plane_seed(s.seed, *light, *k),
                            s.max_bounces,
                            s.min_relative_power,
                        )
                    },
                    photons: a.photons,
                    photon_count: a.photon_count,
                    counters: a.counters,
                    clusters: None,
                    deposit: Some(FusedDeposit::Atlas(AtlasDeposit {
                        params: deposit,
                        triangle_tiles: a.triangle_tiles,
                        tiles: a.tiles,
                        triangle_reach: a.triangle_reach,
                        sums: a.sums,
                    })),
                });
                Self::run(backend, &rec, stats)?;
                stats.batches += 1;
                first += count as u64;
                done += count as u64;
                progress(Progress {
                    photons_done: done,
                    photons_total: total,
                });
            }
        }
        Ok(adaptive)
    }

    /// Renders one frame: the photon passes only when the atlas is stale, then the
    /// camera's passes.
    pub fn frame(
        &mut self,
        backend: &mut dyn Backend,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<FrameStats, Error> {
        let start = Instant::now();
        let mut stats = self.photon_passes(backend, progress)?;
        let rec = self.camera_recording();
        Self::run(backend, &rec, &mut stats)?;
        if let Some(f) = &mut self.images.filters {
            f.end_frame(self.camera);
        }
        stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        if let Some(r) = &self.reference {
            let filtered = self.read_output(backend, "caustics_filtered")?;
            stats.error = Some(crate::frame::metrics::compare(&filtered, r));
        }
        Ok(stats)
    }

    /// Records a frame for a host's frame loop (issue 19 point 2;
    /// [`crate::frame::technique::Technique::record_frame`]): a stale atlas's photon pass
    /// runs here, waited for (it reads the reach mask back to lay the tiles out, and its
    /// statistics are complete when this returns); the camera's passes are recorded. When
    /// only the camera moved, nothing waits.
    pub fn record_frame(&mut self, backend: &mut dyn Backend) -> Result<RecordedFrame, Error> {
        let start = Instant::now();
        let mut stats = self.photon_passes(backend, &mut |_| {})?;
        let recording = self.camera_recording();
        if let Some(f) = &mut self.images.filters {
            f.end_frame(self.camera);
        }
        stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(RecordedFrame {
            recording,
            readbacks: Vec::new(),
            stats,
            counters: None,
        })
    }

    /// The frame's statistics, after the photon passes if the atlas is stale (run and
    /// waited for), or with those passes listed as skipped when only the camera changed.
    fn photon_passes(
        &mut self,
        backend: &mut dyn Backend,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<FrameStats, Error> {
        let caps = backend.capabilities();
        let mut stats = FrameStats {
            technique: self.name.into(),
            backend: backend.name().into(),
            device: caps.device.clone(),
            width: self.camera.width,
            height: self.camera.height,
            timing: if caps.timestamps {
                "device timestamps".into()
            } else {
                "host wall clock".into()
            },
            flux_quantum: self.emission.flux_quantum as f64,
            bytes_allocated: self.scene_bytes + self.atlas_bytes + self.image_bytes,
            degenerate_triangles: self.degenerate_triangles,
            plan: Some(self.plan.clone()),
            ..Default::default()
        };
        for p in self.plan.passes.iter().filter(|p| !p.runs) {
            stats.skip(&p.name, p.reason.clone());
        }
        let photons = self.plan.trace_variant.is_some();
        match self.atlas {
            Some(a) if photons && !self.atlas_valid => {
                self.photon_pass(backend, a, &mut stats, progress)?
            }
            Some(_) if photons => {
                for name in ["trace_photons", "refine_clusters"]
                    .into_iter()
                    .chain(BOX_GATHER_PASSES)
                    .chain(DENSITY_GATHER_PASSES)
                    .filter(|n| self.plan.runs(n))
                {
                    stats.skip(
                        name,
                        "only the camera changed since the caustic atlas was made: it is reused",
                    );
                }
            }
            _ => {}
        }
        Ok(stats)
    }

    /// The camera's passes: G-buffer, direct light, the caustic-map lookups through
    /// mirrors and glass, the opt-in temporal blend and A-Trous, the composite.
    fn camera_recording(&self) -> Recording {
        let cam = self.camera;
        let i = self.images;
        let mut rec = Recording::new();
        if let Some(g) = i.gbuffer {
            rec.kernel(PrimaryGbuffer {
                scene: self.scene,
                camera: cam,
                gbuffer: g,
            });
        }
        if let (Some(g), Some(direct)) = (i.gbuffer, i.direct) {
            rec.kernel(DirectLight {
                scene: self.scene,
                params: DirectParams {
                    camera: cam,
                    light_count: self.model.lights.len() as u32,
                    max_specular_depth: self.settings.max_specular_depth,
                    min_weight: 1e-3,
                    fresnel_model: self.settings.fresnel.kernel_value(),
                },
                gbuffer: g,
                out: direct,
            });
        }
        if let Some(a) = self.atlas {
            let params = MapLookupParams {
                camera: cam,
                atlas_width: self.settings.atlas_size,
                max_specular_depth: self.settings.max_specular_depth,
                min_weight: 1e-3,
                fresnel_model: self.settings.fresnel.kernel_value(),
            };
            // the filtered caustics through the opt-in temporal blend and A-Trous
            // iterations: the lookup writes the chain's input
            let into = |out: Option<ImageBuf>| match (i.filters, out) {
                (Some(f), Some(o)) => Some(f.input(o)),
                _ => out,
            };
            for (map, out) in [(Some(a.map), into(i.filtered)), (a.raw_map, i.raw)] {
                if let (Some(map), Some(out)) = (map, out) {
                    rec.kernel(CausticMapLookup {
                        scene: self.scene,
                        params,
                        triangle_tiles: a.triangle_tiles,
                        tiles: a.tiles,
                        texels: a.texels,
                        map,
                        out,
                    });
                }
            }
            if let (Some(f), Some(filtered), Some(g)) = (i.filters, i.filtered, i.gbuffer) {
                let s = &self.settings;
                let iterations = (s.atrous_iterations, s.atrous_clip_sigmas);
                f.record(&mut rec, cam, g, iterations, filtered);
            }
            if let (Some(direct), Some(filtered), Some(out)) = (i.direct, i.filtered, i.composite) {
                rec.kernel(Composite {
                    direct,
                    caustics: filtered,
                    out,
                });
            }
        }
        rec
    }

    /// The atlas layout as the kernels read it now, per atlas texel (row-major):
    /// `[world area bits, tile]` ([`AtlasTexel`]; `NO_TILE` and area 0 outside the tiles),
    /// read back from the device; `None` without an atlas. With the `caustic_atlas`
    /// output (irradiance, W/m^2) it gives each texel's flux, `E x area`. The layout
    /// follows the receivers the last photon pass reached (see the module doc).
    pub fn atlas_texels(
        &self,
        backend: &mut dyn Backend,
    ) -> Result<Option<Vec<AtlasTexel>>, Error> {
        match self.atlas {
            Some(a) => Ok(Some(read_buf(backend, a.texels)?)),
            None => Ok(None),
        }
    }

    fn requested(&self, name: &str) -> bool {
        let o = &self.settings.outputs;
        match name {
            "composite" => o.composite,
            "direct" => o.direct,
            "caustics_raw" => o.raw_caustics,
            "caustics_filtered" => o.filtered_caustics,
            "caustic_atlas" => o.atlas,
            _ => false,
        }
    }

    /// Reads output `name` back (see [`OUTPUTS`]): camera-sized radiance, or the atlas
    /// (irradiance, `atlas_size` square). An output the plan knows to be zero reads as
    /// zeros.
    pub fn read_output(&self, backend: &mut dyn Backend, name: &str) -> Result<Image, Error> {
        if !OUTPUTS.iter().any(|(n, _)| *n == name) {
            return Err(Error::InvalidParameter(format!(
                "caustic-map has no output '{name}'; outputs: {}",
                OUTPUTS.map(|(n, _)| n).join(", ")
            )));
        }
        if !self.requested(name) {
            return Err(Error::InvalidParameter(format!(
                "output '{name}' was not requested (CausticMapSettings::outputs)"
            )));
        }
        let (w, h) = (self.camera.width, self.camera.height);
        let i = self.images;
        let buf = match name {
            "composite" => i.composite.or(i.direct),
            "direct" => i.direct,
            "caustics_raw" => i.raw,
            "caustics_filtered" => i.filtered,
            _ => {
                let side = self.settings.atlas_size;
                return match self.atlas {
                    Some(a) => Ok(Image::new(side, side, read_buf(backend, a.map)?)),
                    None => Ok(Image::new(
                        side,
                        side,
                        vec![[0.0; 4]; side as usize * side as usize],
                    )),
                };
            }
        };
        match buf {
            Some(b) => Ok(Image::new(w, h, read_buf(backend, b)?)),
            None => Ok(Image::new(w, h, vec![[0.0; 4]; w as usize * h as usize])),
        }
    }

    /// The settings in effect.
    pub fn settings(&self) -> &CausticMapSettings {
        &self.settings
    }

    /// Moves the camera. The atlas stays valid (no photon pass on the next frame); a new
    /// image size remakes only the camera-sized images.
    pub fn set_camera(
        &mut self,
        backend: &mut dyn Backend,
        camera: &crate::scene::Camera,
    ) -> Result<(), Error> {
        let model = crate::frame::technique::with_camera(&self.model, camera)?;
        let new = GpuCamera::from_camera(camera);
        let resized = (new.width, new.height) != (self.camera.width, self.camera.height);
        self.camera = new;
        self.model = model;
        if resized {
            Self::free_ids(backend, std::mem::take(&mut self.image_owned))?;
            self.images = Images::default();
            self.make_images(backend)?;
            self.reference = None;
        }
        Ok(())
    }

    /// Replaces the lights (same number: uploaded into the light buffer; else a new light
    /// buffer); the geometry, its acceleration structure and the atlas buffers stay, the
    /// atlas is remade on the next frame (laid out anew there if the new lights' photons
    /// reach other receivers).
    pub fn set_lights(
        &mut self,
        backend: &mut dyn Backend,
        lights: &[crate::scene::Light],
    ) -> Result<(), Error> {
        let model = crate::frame::technique::with_lights(&self.model, lights)?;
        let Some(emission) =
            self.plan_emission(&model, self.bounds, self.caster_bounds, self.caster_spheres)?
        else {
            return self.rebuild_as(backend, &model);
        };
        let gpu: Vec<GpuLight> = lights
            .iter()
            .map(crate::device::device_scene::gpu_light)
            .collect();
        let mut rec = Recording::new();
        if gpu.len() as u32 == self.scene.lights.len {
            rec.update(self.scene.lights, &gpu, "lights")?;
            backend.execute(&rec)?;
        } else {
            let new = rec.upload(&gpu, "lights");
            planned_allocation(backend, &rec, None)?;
            rec.steps.push(Step::Free {
                id: self.scene.lights.id,
            });
            backend.execute(&rec)?;
            for id in &mut self.scene_owned {
                if *id == self.scene.lights.id {
                    *id = new.id;
                }
            }
            self.scene.lights = new;
        }
        self.model = model;
        self.emission = emission;
        self.atlas_valid = false;
        if let Some(f) = &mut self.images.filters {
            f.reset();
        }
        let f = self.plan.features;
        self.replan(f.mirrors || f.dielectrics, true);
        Ok(())
    }

    /// The emission of `model` with the scene bounds given, or `None` when the passes or
    /// buffer sizes it needs differ from this technique's (then it must be built anew).
    fn plan_emission(
        &self,
        model: &Scene,
        bounds: crate::math::geometry::Aabb,
        caster_bounds: crate::math::geometry::Aabb,
        caster_spheres: crate::device::caster_spheres::CasterSpheres,
    ) -> Result<Option<ViewPlanes>, Error> {
        let mut emission = ViewPlanes::new(
            model,
            bounds,
            caster_bounds,
            caster_spheres,
            self.has_dispersion,
            &self.settings,
        );
        if let Some(a) = &self.adaptive {
            // the traversal's pyramid and its coarse photons' quantum, as at creation
            adaptive_caustics::fit_planes(&mut emission, &a.settings.traversal(), self.has_dispersion);
        }
        emission.check_light_flux()?;
        // the traversal's buffers hold planes down to its finest level
        let deeper = self.adaptive.as_ref().is_some_and(|a| {
            let start = a.settings.start_grid;
            let finest = |e: &ViewPlanes| {
                e.planes
                    .iter()
                    .map(|(_, _, p)| (p.resolution.0 / start).max(1).ilog2())
                    .max()
                    .unwrap_or(0)
            };
            finest(&emission) > finest(&self.emission)
        });
        let per_plane = emission
            .planes
            .iter()
            .map(|(_, _, p)| p.texels())
            .max()
            .unwrap_or(0);
        let had_photons = self.plan.trace_variant.is_some();
        let rebuild = (emission.planes.is_empty() == had_photons && self.settings.prune)
            || deeper
            || (self.adaptive.is_none()
                && self.atlas.is_some_and(|a| {
                    crate::frame::allocation::photons_per_batch(
                        per_plane,
                        self.settings.max_photons_per_batch,
                        self.max_buffer_bytes,
                    ) > a.photons.len
                }));
        Ok((!rebuild).then_some(emission))
    }

    /// Builds this technique anew for `model` on the same backend (with the same
    /// traversal, for AdaptiveCaustics), keeping the reference image.
    fn rebuild_as(&mut self, backend: &mut dyn Backend, model: &Scene) -> Result<(), Error> {
        let settings = self.settings.clone();
        let adaptive = self.adaptive.as_ref().map(|a| a.settings.clone());
        let fresh = CausticMap::build(backend, model, settings, adaptive)?;
        let old = std::mem::replace(self, fresh);
        let reference = old.reference.clone();
        old.free(backend)?;
        self.reference = reference;
        Ok(())
    }

    /// Moves instances for the next frames ([`crate::frame::technique::Technique::set_object_transforms`]):
    /// the moved objects' world vertices and the top level are rewritten in place, the
    /// light view planes re-aimed at the new caster bounds, and a moved receiver's tile
    /// sizes follow its new area (the atlas is laid out again for every receiver, as at
    /// creation, and the next photon pass keeps the reached ones); AdaptiveCaustics'
    /// traversal gets the moved casters' boxes. The technique is built anew only where
    /// [`CausticMap::set_lights`] would be. On an error nothing changes.
    pub fn set_object_transforms(
        &mut self,
        backend: &mut dyn Backend,
        moves: &[(usize, crate::scene::Transform)],
    ) -> Result<(), Error> {
        let model = crate::frame::technique::with_transforms(&self.model, moves)?;
        let mut instances = self.instances.clone();
        let m = instances.move_instances(moves)?;
        self.update_instances(backend, model, instances, InstanceUpdate::Moved(m))
    }

    /// Deforms an instance for the next frames
    /// ([`crate::frame::technique::Technique::set_object_vertices`]): its BLAS rebuilt in
    /// place, then as a move (a deformed receiver's triangles follow into the atlas, which
    /// is laid out anew). On an error nothing changes.
    pub fn set_object_vertices(
        &mut self,
        backend: &mut dyn Backend,
        object: usize,
        positions: &[glam::Vec3],
        normals: &[glam::Vec3],
    ) -> Result<(), Error> {
        let d = crate::frame::technique::deformation(
            &self.model,
            &self.instances,
            object,
            positions,
            normals,
        )?;
        self.update_instances(backend, d.model, d.instances, d.update)
    }

    /// Applies an instance update already made to `instances` (a copy of the technique's)
    /// for `model`, the scene after it.
    fn update_instances(
        &mut self,
        backend: &mut dyn Backend,
        model: Scene,
        instances: SceneInstances,
        u: InstanceUpdate,
    ) -> Result<(), Error> {
        let m = u.moved();
        let Some(emission) =
            self.plan_emission(&model, m.bounds, m.caster_bounds, m.caster_spheres)?
        else {
            return self.rebuild_as(backend, &model);
        };
        let mut receivers = self.receivers.clone();
        if let (Some(r), InstanceUpdate::Deformed(d)) = (receivers.as_mut(), &u) {
            // the deformed level's triangles in their new order
            r.reorder_triangles(d.triangles.0, &d.triangles.1);
        }
        let receivers_moved = receivers
            .as_mut()
            .is_some_and(|r| r.move_vertices(&m.vertices));
        let mut rec = Recording::new();
        rec.update_instances(&u, &self.scene)?;
        backend.execute(&rec)?;
        if let Some(ad) = &mut self.adaptive {
            // the traversal's caster boxes follow the moved casters
            adaptive_caustics::follow_moved_casters(
                &mut ad.caster_boxes,
                &ad.caster_objects,
                &instances.levels,
            );
            if let Some(t) = &mut ad.traversal {
                t.set_caster_boxes(&ad.caster_boxes);
            }
        }
        self.instances = instances;
        self.receivers = receivers;
        self.bounds = m.bounds;
        self.caster_bounds = m.caster_bounds;
        self.caster_spheres = m.caster_spheres;
        self.model = model;
        self.emission = emission;
        self.atlas_valid = false;
        if let Some(f) = &mut self.images.filters {
            f.reset();
        }
        if let (true, Some(a)) = (receivers_moved, self.atlas) {
            let all = vec![true; self.tiled.len()];
            self.relayout(backend, a, &all)?;
        }
        let f = self.plan.features;
        self.replan(f.mirrors || f.dielectrics, true);
        Ok(())
    }

    /// Replaces the materials' parameters for the next frames
    /// ([`crate::frame::material_update`]): the table is uploaded in place and the atlas
    /// remade on the next frame; when the scene's features or dispersion change (the trace
    /// variant, the quanta), the technique is built anew on the same backend (with the
    /// same traversal, for AdaptiveCaustics). On an error nothing changes.
    pub fn set_materials(
        &mut self,
        backend: &mut dyn Backend,
        materials: &std::collections::BTreeMap<String, crate::scene::Material>,
    ) -> Result<(), Error> {
        let u = crate::frame::material_update::material_update(&self.model, materials)?;
        if !u.same_plan {
            let settings = self.settings.clone();
            let adaptive = self.adaptive.as_ref().map(|a| a.settings.clone());
            let fresh = CausticMap::build(backend, &u.model, settings, adaptive)?;
            let old = std::mem::replace(self, fresh);
            let reference = old.reference.clone();
            old.free(backend)?;
            self.reference = reference;
            return Ok(());
        }
        let mut rec = Recording::new();
        rec.update(self.scene.materials, &u.gpu, "materials")?;
        backend.execute(&rec)?;
        self.model = u.model;
        self.atlas_valid = false;
        if let Some(f) = &mut self.images.filters {
            f.reset();
        }
        Ok(())
    }

    /// Sets the frame seed; the atlas is remade on the next frame (the temporal history
    /// is kept: accumulating over seeds is what it is for).
    pub fn set_seed(&mut self, seed: u32) {
        if seed != self.settings.seed {
            self.settings.seed = seed;
            self.atlas_valid = false;
        }
    }

    /// Releases every device buffer.
    pub fn free(mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        self.free_all(backend)
    }
}

impl Drop for CausticMap {
    fn drop(&mut self) {
        crate::frame::technique::report_leak(
            self.name,
            self.scene_owned.len() + self.atlas_owned.len() + self.image_owned.len(),
            self.scene_bytes + self.atlas_bytes + self.image_bytes,
        );
    }
}

impl Technique for CausticMap {
    fn name(&self) -> &'static str {
        self.name
    }

    fn frame(
        &mut self,
        backend: &mut dyn Backend,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<FrameStats, Error> {
        CausticMap::frame(self, backend, progress)
    }

    fn record_frame(&mut self, backend: &mut dyn Backend) -> Result<RecordedFrame, Error> {
        CausticMap::record_frame(self, backend)
    }

    fn outputs(&self) -> Vec<OutputInfo> {
        OUTPUTS
            .iter()
            .map(|(name, description)| OutputInfo {
                name,
                description,
                requested: self.requested(name),
                camera_space: *name != "caustic_atlas",
            })
            .collect()
    }

    fn read_output(&self, backend: &mut dyn Backend, name: &str) -> Result<Image, Error> {
        CausticMap::read_output(self, backend, name)
    }

    fn estimate_outputs(&self) -> (&'static str, &'static str) {
        ("caustics_filtered", "caustics_raw")
    }

    fn settings_json(&self) -> serde_json::Value {
        match &self.adaptive {
            Some(a) => serde_json::to_value(AdaptiveCausticsSettings {
                map: self.settings.clone(),
                ..a.settings.clone()
            }),
            None => serde_json::to_value(&self.settings),
        }
        .unwrap_or(serde_json::Value::Null)
    }

    fn set_seed(&mut self, seed: u32) {
        CausticMap::set_seed(self, seed)
    }

    fn set_camera(
        &mut self,
        backend: &mut dyn Backend,
        camera: &crate::scene::Camera,
    ) -> Result<(), Error> {
        CausticMap::set_camera(self, backend, camera)
    }

    fn set_lights(
        &mut self,
        backend: &mut dyn Backend,
        lights: &[crate::scene::Light],
    ) -> Result<(), Error> {
        CausticMap::set_lights(self, backend, lights)
    }

    fn set_object_transforms(
        &mut self,
        backend: &mut dyn Backend,
        moves: &[(usize, crate::scene::Transform)],
    ) -> Result<(), Error> {
        CausticMap::set_object_transforms(self, backend, moves)
    }

    fn set_object_vertices(
        &mut self,
        backend: &mut dyn Backend,
        object: usize,
        positions: &[glam::Vec3],
        normals: &[glam::Vec3],
    ) -> Result<(), Error> {
        CausticMap::set_object_vertices(self, backend, object, positions, normals)
    }

    fn set_materials(
        &mut self,
        backend: &mut dyn Backend,
        materials: &std::collections::BTreeMap<String, crate::scene::Material>,
    ) -> Result<(), Error> {
        CausticMap::set_materials(self, backend, materials)
    }

    fn set_settings(
        &mut self,
        backend: &mut dyn Backend,
        settings: &serde_json::Value,
    ) -> Result<(), Error> {
        // the technique is assembled anew over the uploaded scene (rebuilt only for a new
        // triangle budget); the old one stays until the new one exists
        let (map, adaptive) = match &self.adaptive {
            None => (
                serde_json::from_value::<CausticMapSettings>(settings.clone())
                    .map_err(|e| Error::InvalidParameter(format!("caustic-map settings: {e}")))?,
                None,
            ),
            Some(_) => {
                let a = AdaptiveCausticsSettings::from_json(settings)?;
                (a.map.clone(), Some(a))
            }
        };
        map.validate()?;
        if map.max_triangles != self.max_triangles {
            let fresh = CausticMap::build(backend, &self.model, map, adaptive)?;
            let old = std::mem::replace(self, fresh);
            self.reference = old.reference.clone();
            return old.free(backend);
        }
        let fresh =
            CausticMap::assemble(backend, &self.model, map, adaptive, self.uploaded_scene())?;
        let mut old = std::mem::replace(self, fresh);
        self.reference = old.reference.clone();
        // the scene is the new technique's now
        old.scene_owned.clear();
        old.scene_bytes = 0;
        old.free(backend)
    }

    fn set_reference(&mut self, reference: Option<Image>) -> Result<(), Error> {
        if let Some(r) = &reference {
            if (r.width, r.height) != (self.camera.width, self.camera.height) {
                return Err(Error::InvalidParameter(format!(
                    "reference is {}x{}, the frame {}x{}",
                    r.width, r.height, self.camera.width, self.camera.height
                )));
            }
        }
        self.reference = reference;
        Ok(())
    }

    fn plan(&self) -> &FramePlan {
        &self.plan
    }

    fn free(self: Box<Self>, backend: &mut dyn Backend) -> Result<(), Error> {
        CausticMap::free(*self, backend)
    }
}

/// The registry's constructor: `settings` is a JSON object of [`CausticMapSettings`]
/// fields (missing fields take their defaults, unknown ones are an error).
pub fn create(
    backend: &mut dyn Backend,
    scene: &Scene,
    settings: &serde_json::Value,
) -> Result<Box<dyn Technique>, Error> {
    let settings: CausticMapSettings = serde_json::from_value(settings.clone())
        .map_err(|e| Error::InvalidParameter(format!("caustic-map settings: {e}")))?;
    Ok(Box::new(CausticMap::new(backend, scene, settings)?))
}

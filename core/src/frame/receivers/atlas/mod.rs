//! Vanderstichelen 2021's caustic map as a receiver: photons deposited into the diffuse receivers'
//! texture space (one atlas of tiles, fixed-point sums per texel), gathered into
//! irradiance (Vanderstichelen 2021's N x N gather fixed to keep flux, or the density-adaptive gather on
//! the atlas), and looked up by the camera's specular ray tree (`caustic_map_lookup`),
//! directly, in mirrors and through glass; then the opt-in temporal blend and A-Trous
//! iterations and the composite over the frame host's direct light.
//!
//! - [`layout`]: the atlas's tiles over the receivers' UV charts;
//! - [`settings`]: the map's parameters (CausticMap's settings).
//!
//! **Tiles only for reached receivers.** The deposit also marks every photon's triangle
//! in a reach mask. A technique may read it back after its photon pass
//! ([`AtlasReceiver::reached`]) and lay the atlas out anew for the receivers the photons
//! reached ([`AtlasReceiver::relayout`]), so that they share the whole atlas; the receiver
//! does not know where its photons come from.

pub mod layout;
pub mod settings;

use crate::backend::{read_buf, Backend};
use crate::device::handle::{Buf, GBufferPlanes, ImageBuf, PhotonMapPlanes};
use crate::device::layout::{
    counter, gather_surface, AtlasParams, AtlasTexel, AtlasTileTexel, GatherParams, GpuCamera,
    MapLookupParams, Photon,
};
use crate::frame::allocation::{planned_allocation, Allocation};
use crate::frame::error::Error;
use crate::frame::host::FrameHost;
use crate::frame::image::Image;
use crate::frame::irradiance_passes::FilterChain;
use crate::frame::output::Output;
use crate::frame::plan::{FramePlan, LightPlan, PassPlan, SceneFeatures};
use crate::frame::screen::{DirectLighting, ScreenNeeds};
use crate::kernels::{
    AtlasDeposit, CausticMapLookup, DensityGather, GatherCausticMap, GatherFootprint,
    PhotonCountTable, TraceVariant,
};
use crate::recording::Recording;
use layout::{AtlasLayout, AtlasReceivers};
use settings::{AtlasConfig, MapGather};

/// The photon passes of each gather, in order (a frame that reuses the atlas skips them).
pub const BOX_GATHER_PASSES: [&str; 1] = ["gather_caustic_map"];
/// The density gather's passes on the atlas.
pub const DENSITY_GATHER_PASSES: [&str; 3] =
    ["photon_count_table", "gather_footprint", "density_gather"];

/// The outputs of the caustic map: the screen receiver's, so that every technique writes
/// the same files, plus the atlas.
pub const OUTPUTS: [Output; 5] = [
    Output::Composite,
    Output::Direct,
    Output::RawCaustics,
    Output::FilteredCaustics,
    Output::CausticAtlas,
];

/// The fixed-point quanta of the atlas's sums (the emission's).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtlasQuanta {
    /// Flux per fixed-point unit (W), a power of two.
    pub flux_quantum: f32,
    /// Hit distance per fixed-point unit (scene units), a power of two.
    pub hit_distance_quantum: f32,
}

impl AtlasQuanta {
    /// The quanta of the view planes' photons.
    pub fn of(planes: &crate::frame::emission::view_planes::ViewPlanes) -> AtlasQuanta {
        AtlasQuanta {
            flux_quantum: planes.flux_quantum,
            hit_distance_quantum: planes.hit_distance_quantum,
        }
    }
}

/// The density gather's parameters on an atlas of `settings.atlas.atlas_size` texels a side
/// (`gather: density`; `axis` 0: the row pass, 1: the column pass): the atlas is the
/// grid, edge weights only keep the gather inside a tile
/// ([`ATLAS_SIGMA_DEPTH`](crate::math::density_gather::ATLAS_SIGMA_DEPTH), no normal term),
/// the quanta are the atlas sums'.
pub fn atlas_gather_params(
    settings: &AtlasConfig,
    flux_quantum: f32,
    hit_distance_quantum: f32,
    axis: u32,
) -> GatherParams {
    GatherParams {
        camera: GpuCamera {
            width: settings.atlas.atlas_size,
            height: settings.atlas.atlas_size,
            ..Default::default()
        },
        max_radius_px: settings.atlas.max_radius_texels,
        sigma_depth: crate::math::density_gather::ATLAS_SIGMA_DEPTH,
        normal_power: 0.0,
        axis,
        hit_distance_quantum,
        knn_photons: settings.atlas.knn_photons,
        flux_quantum,
        table_block: crate::math::density_gather::table_block(settings.atlas.max_radius_texels),
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

/// The device side of the caustic atlas.
#[derive(Clone, Copy, Debug)]
pub struct AtlasBuffers {
    /// Per scene triangle: its receiver's tile.
    pub triangle_tiles: Buf<u32>,
    /// The tiles (one slot per receiver).
    pub tiles: Buf<AtlasTileTexel>,
    /// Per atlas texel: its world area and tile.
    pub texels: Buf<AtlasTexel>,
    /// The fixed-point sums photons deposit into.
    pub sums: PhotonMapPlanes,
    /// Per texel, where in it its photons lie: the sums of their offsets and their count
    /// ([`crate::math::map_gather::CENTROID_WORDS`] words), cleared with the sums.
    pub centroids: Buf<u32>,
    /// The gathered map (irradiance, W/m^2).
    pub map: ImageBuf,
    /// The raw map (N = 1), where asked for.
    pub raw_map: Option<ImageBuf>,
    /// The one-slot photon buffer a fused trace binds (it stores none).
    pub photons: Buf<Photon>,
    /// Its count.
    pub photon_count: Buf<u32>,
    /// The photon counters (`layout::counter`).
    pub counters: Buf<u32>,
    /// One bit per scene triangle that a photon of this atlas reached
    /// (`math::map_gather::triangle_reach_bit`), cleared with the sums.
    pub triangle_reach: Buf<u32>,
    density: Option<DensityBuffers>,
}

/// The density gather's buffers on the atlas (`gather: density`).
#[derive(Clone, Copy, Debug)]
struct DensityBuffers {
    /// Photon-count summed-area table, a `u32` per texel.
    table: Buf<u32>,
    /// The atlas's edge texels (`math::density_gather::atlas_edge_texel`).
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

/// The camera-sized caustic images.
#[derive(Clone, Copy, Debug, Default)]
struct CameraImages {
    raw: Option<ImageBuf>,
    filtered: Option<ImageBuf>,
    /// The opt-in temporal blend and A-Trous iterations on the filtered caustics.
    filters: Option<FilterChain>,
}

/// The caustic-map receiver of one technique.
#[derive(Debug)]
pub struct AtlasReceiver {
    settings: AtlasConfig,
    quanta: AtlasQuanta,
    /// Per receiver (in the host's receivers order): whether it owns a tile now.
    tiled: Vec<bool>,
    layout_summary: String,
    atlas: Option<AtlasBuffers>,
    images: CameraImages,
    atlas_owned: Allocation,
    image_owned: Allocation,
    /// Photon passes whose photons the sums hold (progressive accumulation).
    accumulated: u32,
}

/// Whether a frame of `host`'s scene with `settings` has an atlas: casters, receivers, a
/// light that emits (`emits`) and a caustic output, or pruning off.
pub fn with_atlas(host: &FrameHost, settings: &AtlasConfig, emits: bool) -> bool {
    let features = SceneFeatures::of(host.model());
    let casters = features.mirrors || features.dielectrics;
    let o = &settings.frame.outputs;
    let wants = o.any_of(&[
        Output::Composite,
        Output::RawCaustics,
        Output::FilteredCaustics,
        Output::CausticAtlas,
    ]);
    casters
        && host.receivers().is_some()
        && (emits || !settings.frame.prune)
        && (wants || !settings.frame.prune)
}

/// Lays the atlas out for the receivers flagged in `include`; a receiver whose UVs cannot
/// address a map is named by its scene object.
fn lay_out(
    host: &FrameHost,
    receivers: &AtlasReceivers,
    include: &[bool],
    atlas_size: u32,
) -> Result<AtlasLayout, Error> {
    receivers
        .layout(include, (atlas_size, atlas_size))
        .map_err(|e| match e {
            layout::AtlasError::BadUvs { receiver, reason } => Error::InvalidScene(format!(
                "objects[{receiver}] ('{}'): its UVs cannot address a caustic map: {reason}",
                host.model().objects[receiver as usize].name
            )),
            layout::AtlasError::NoArea { receiver, area } => Error::InvalidScene(format!(
                "objects[{receiver}] ('{}'): its world area is {area}, not a finite number > \
                 0 (its triangles' areas lost to f32 rounding where it is placed?), so it can \
                 hold no caustic map",
                host.model().objects[receiver as usize].name
            )),
            // the atlas is the setting's size: too small a one is the setting's problem
            layout::AtlasError::TooManyReceivers { receivers, texels } => {
                Error::InvalidParameter(format!(
                    "atlas.atlas_size {atlas_size}: the scene's {receivers} receivers need a \
                     texel each, the atlas has {texels}"
                ))
            }
            other => Error::InvalidScene(other.to_string()),
        })
}

impl AtlasReceiver {
    /// A frame that reuses the atlas (only the camera changed since it was made): each
    /// photon pass `plan` runs is skipped, with the reason, in `stats`.
    pub fn skip_photon_passes(plan: &FramePlan, stats: &mut crate::frame::stats::FrameStats) {
        for name in ["trace_photons", "refine_clusters"]
            .into_iter()
            .chain(BOX_GATHER_PASSES)
            .chain(DENSITY_GATHER_PASSES)
            .filter(|n| plan.runs(n))
        {
            stats.skip(
                name,
                "only the camera changed since the caustic atlas was made: it is reused",
            );
        }
    }

    /// The camera images the host makes for `settings` (with an atlas: `caustics`): the
    /// G-buffer where direct light or a filter reads it, the direct image where direct or
    /// composite is asked for, the composite with caustics.
    pub fn screen_needs(settings: &AtlasConfig, caustics: bool) -> ScreenNeeds {
        let o = settings.frame.outputs;
        let keep = |x: bool| x || !settings.frame.prune;
        let direct = keep(o.any_of(&[Output::Direct, Output::Composite]));
        let filters = caustics
            && keep(o.any_of(&[Output::FilteredCaustics, Output::Composite]))
            && (settings.frame.temporal || settings.frame.atrous_iterations > 0);
        ScreenNeeds {
            gbuffer: direct || filters,
            direct: direct.then_some(DirectLighting {
                max_specular_depth: settings.frame.max_specular_depth,
                min_weight: 1e-3,
                fresnel_model: settings.planes.fresnel.kernel_value(),
            }),
            composite: caustics && keep(o.has(Output::Composite)),
        }
    }

    /// Makes the receiver over `host`: with `atlas`, every receiver's tile (UVs checked),
    /// the sums, maps and reach mask, and what `extra` records into the same allocation
    /// (a traversal's buffers); then the camera-sized images. The caller's camera images
    /// must already be made. On an error nothing of it remains on the device.
    pub fn create(
        backend: &mut dyn Backend,
        host: &FrameHost,
        settings: AtlasConfig,
        quanta: AtlasQuanta,
        atlas: bool,
        extra: &mut dyn FnMut(&mut Recording),
    ) -> Result<AtlasReceiver, Error> {
        let tiled = vec![true; host.receivers().map_or(0, |r| r.objects.len())];
        let mut r = AtlasReceiver {
            settings,
            quanta,
            tiled,
            layout_summary: String::new(),
            atlas: None,
            images: CameraImages::default(),
            atlas_owned: Allocation::default(),
            image_owned: Allocation::default(),
            accumulated: 0,
        };
        let made = (|| {
            if let (Some(receivers), true) = (host.receivers(), atlas) {
                let s = &r.settings;
                if s.atlas.atlas_bytes() > s.atlas.max_atlas_bytes {
                    return Err(crate::device::error::BackendError::OutOfMemory {
                        bytes: s.atlas.atlas_bytes(),
                        what: format!(
                            "caustic atlas of {0}x{0} texels: over max_atlas_bytes ({1} bytes); \
                             a smaller atlas_size, or a larger max_atlas_bytes where the \
                             device holds it",
                            s.atlas.atlas_size, s.atlas.max_atlas_bytes
                        ),
                    }
                    .into());
                }
                let l = lay_out(host, receivers, &r.tiled, s.atlas.atlas_size)?;
                r.make_atlas(backend, &l, extra)?;
            }
            r.make_images(backend, host.camera())
        })();
        if let Err(e) = made {
            let _ = r.free(backend);
            return Err(e);
        }
        Ok(r)
    }

    /// Uploads layout `l` and creates the atlas's sums, maps and reach mask.
    fn make_atlas(
        &mut self,
        backend: &mut dyn Backend,
        l: &AtlasLayout,
        extra: &mut dyn FnMut(&mut Recording),
    ) -> Result<(), Error> {
        let s = &self.settings;
        let texels = l.texels.len() as u32;
        let mut rec = Recording::new();
        let triangles = l.triangle_tiles.len() as u32;
        let a = AtlasBuffers {
            triangle_tiles: rec.upload(&l.triangle_tiles, "atlas triangle tiles"),
            tiles: rec.upload(&tile_buffer(l, self.tiled.len().max(1)), "atlas tiles"),
            texels: rec.upload(&l.texels, "atlas texels"),
            sums: rec.create_photon_map(texels),
            centroids: rec.create(
                texels * crate::math::map_gather::CENTROID_WORDS,
                "atlas centroid sums",
            ),
            map: rec.create(texels, "caustic map"),
            raw_map: (s.frame.outputs.has(Output::RawCaustics) || !s.frame.prune)
                .then(|| rec.create(texels, "raw caustic map")),
            photons: rec.create(1, "photons"),
            photon_count: rec.create(1, "photon count"),
            counters: rec.create(counter::WORDS as u32, "photon counters"),
            triangle_reach: rec.create(
                crate::math::map_gather::triangle_reach_words(triangles),
                "atlas triangle reach",
            ),
            density: (s.atlas.gather == MapGather::Density).then(|| DensityBuffers {
                table: rec.create(texels, "atlas photon count table"),
                edge: rec.upload(&atlas_edge_texels(l), "atlas edge texels"),
                footprint: rec.create(texels, "atlas gather footprints"),
                rows: rec.create(texels, "atlas gather rows"),
                source_index: rec.create(
                    crate::math::density_gather::source_index_len(
                        s.atlas.atlas_size,
                        s.atlas.atlas_size,
                    ),
                    "atlas gather source index",
                ),
                gbuffer: rec.create_gbuffer(1),
            }),
        };
        extra(&mut rec);
        let alloc = planned_allocation(backend, &rec, None)?;
        backend.execute(&rec)?;
        self.atlas = Some(a);
        self.atlas_owned = alloc;
        self.layout_summary = self.describe_layout(l);
        Ok(())
    }

    /// Makes the camera-sized caustic images for `camera` anew (the old ones freed):
    /// after a resize, the atlas stays.
    pub fn make_images(
        &mut self,
        backend: &mut dyn Backend,
        camera: GpuCamera,
    ) -> Result<(), Error> {
        let o = self.settings.frame.outputs;
        let s = &self.settings;
        let keep = |x: bool| x || !s.frame.prune;
        let pixels = camera.width * camera.height;
        let caustics = self.atlas.is_some();
        let mut rec = Recording::new();
        let filtered_needed =
            caustics && keep(o.any_of(&[Output::FilteredCaustics, Output::Composite]));
        let filters = (filtered_needed && (s.frame.temporal || s.frame.atrous_iterations > 0))
            .then(|| {
                FilterChain::create(
                    &mut rec,
                    pixels,
                    camera,
                    s.frame.temporal,
                    s.frame.atrous_iterations > 0,
                )
            });
        let images = CameraImages {
            filters,
            raw: (caustics && keep(o.has(Output::RawCaustics)))
                .then(|| rec.create(pixels, "raw caustics image")),
            filtered: filtered_needed.then(|| rec.create(pixels, "filtered caustics image")),
        };
        let alloc = planned_allocation(backend, &rec, Some((camera.width, camera.height)))?;
        self.image_owned.free_into(&mut rec);
        backend.execute(&rec)?;
        self.images = images;
        self.image_owned = alloc;
        Ok(())
    }

    /// The settings it was made with.
    pub fn settings(&self) -> &AtlasConfig {
        &self.settings
    }

    /// The atlas buffers (with an atlas).
    pub fn atlas(&self) -> Option<AtlasBuffers> {
        self.atlas
    }

    /// The quanta in effect.
    pub fn quanta(&self) -> AtlasQuanta {
        self.quanta
    }

    /// New quanta (moved lights or casters): the history and the accumulated photons
    /// are forgotten.
    pub fn set_quanta(&mut self, quanta: AtlasQuanta) {
        self.quanta = quanta;
        self.reset_history();
    }

    /// Sets the frame seed the settings carry (an accumulation starts again).
    pub fn set_seed(&mut self, seed: u32) {
        self.settings.frame.seed = seed;
        self.restart_accumulation();
    }

    /// With progressive accumulation, the index of this photon pass among those the sums
    /// accumulate (its photons' seed: [`crate::frame::receivers::accumulation_seed`]); 0
    /// without.
    pub fn pass_index(&self) -> u32 {
        if self.settings.frame.accumulate {
            self.accumulated
        } else {
            0
        }
    }

    /// Starts the accumulation again from the next photon pass.
    pub fn restart_accumulation(&mut self) {
        self.accumulated = 0;
    }

    /// After a photon pass: with accumulation its photons stay in the sums; returns the
    /// passes they hold (0 without accumulation).
    pub fn end_photon_pass(&mut self) -> u32 {
        if self.settings.frame.accumulate {
            self.accumulated += 1;
            self.accumulated
        } else {
            0
        }
    }

    /// The quanta the gather reads the sums with: the deposit's flux quantum over the
    /// passes they hold (their mean).
    fn read_quanta(&self) -> AtlasQuanta {
        AtlasQuanta {
            flux_quantum: self.quanta.flux_quantum / (self.pass_index() + 1) as f32,
            ..self.quanta
        }
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

    /// The receivers that own a tile now (host order).
    pub fn tiled(&self) -> &[bool] {
        &self.tiled
    }

    /// The receivers the last photon pass reached, from the reach mask `reach` read back.
    pub fn reached(&self, host: &FrameHost, reach: &[u32]) -> Option<Vec<bool>> {
        host.receivers().map(|r| r.reached(reach))
    }

    /// Records the atlas laid out anew for the receivers flagged in `include`: the
    /// layout's buffers written in place (no buffer is reallocated).
    pub fn relayout(
        &mut self,
        host: &FrameHost,
        rec: &mut Recording,
        include: &[bool],
    ) -> Result<(), Error> {
        let (Some(r), Some(a)) = (host.receivers(), self.atlas) else {
            return Ok(());
        };
        let l = lay_out(host, r, include, self.settings.atlas.atlas_size)?;
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
        self.tiled = include.to_vec();
        self.layout_summary = self.describe_layout(&l);
        // the sums belong to the old layout
        self.restart_accumulation();
        Ok(())
    }

    /// `AtlasParams` of the deposit (`gather_width` 1).
    pub fn atlas_params(&self, gather_width: u32) -> AtlasParams {
        self.params_with(self.quanta, gather_width)
    }

    /// `AtlasParams` with `quanta` (the deposit's, or the gathers' reading them).
    fn params_with(&self, quanta: AtlasQuanta, gather_width: u32) -> AtlasParams {
        AtlasParams {
            width: self.settings.atlas.atlas_size,
            height: self.settings.atlas.atlas_size,
            flux_quantum: quanta.flux_quantum,
            hit_distance_quantum: quanta.hit_distance_quantum,
            photon_capacity: self.atlas.map_or(1, |a| a.photons.len),
            gather_width,
            _pad: [0; 2],
        }
    }

    /// The fused trace's deposit into the atlas.
    pub fn fused_deposit(&self) -> Option<AtlasDeposit> {
        self.atlas.map(|a| AtlasDeposit {
            params: self.atlas_params(1),
            triangle_tiles: a.triangle_tiles,
            tiles: a.tiles,
            triangle_reach: a.triangle_reach,
            sums: a.sums,
            centroids: a.centroids,
        })
    }

    /// Records the sums, counters and reach mask cleared (a photon pass's start); with
    /// progressive accumulation the sums keep the passes before.
    pub fn record_clear(&self, rec: &mut Recording) {
        if let Some(a) = self.atlas {
            if self.pass_index() == 0 {
                rec.clear_photon_map(&a.sums);
                rec.clear(a.centroids);
            }
            rec.clear(a.counters);
            rec.clear(a.triangle_reach);
        }
    }

    /// Records the gather of the sums into the map (and the raw map).
    pub fn record_gather(&self, rec: &mut Recording) {
        let Some(a) = self.atlas else {
            return;
        };
        let q = self.read_quanta();
        if let Some(d) = a.density {
            let rows =
                atlas_gather_params(&self.settings, q.flux_quantum, q.hit_distance_quantum, 0);
            let columns = GatherParams { axis: 1, ..rows };
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
                params: self.params_with(q, self.settings.atlas.gather_width),
                texels: a.texels,
                tiles: a.tiles,
                atlas: a.sums,
                out: a.map,
            });
        }
        if let Some(raw) = a.raw_map {
            rec.kernel(GatherCausticMap {
                params: self.params_with(q, 1),
                texels: a.texels,
                tiles: a.tiles,
                atlas: a.sums,
                out: raw,
            });
        }
    }

    /// Records the camera's passes after the host's visibility: the caustic-map lookups
    /// through mirrors and glass, the opt-in temporal blend and A-Trous iterations, the
    /// composite.
    pub fn record_camera(&self, host: &FrameHost, rec: &mut Recording) {
        let Some(a) = self.atlas else {
            return;
        };
        let cam = host.camera();
        let s = &self.settings;
        let i = self.images;
        let params = MapLookupParams {
            camera: cam,
            atlas_width: s.atlas.atlas_size,
            max_specular_depth: s.frame.max_specular_depth,
            min_weight: 1e-3,
            fresnel_model: s.planes.fresnel.kernel_value(),
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
                    scene: host.scene(),
                    params,
                    triangle_tiles: a.triangle_tiles,
                    tiles: a.tiles,
                    texels: a.texels,
                    map,
                    out,
                    centroids: a.centroids,
                });
            }
        }
        if let (Some(f), Some(filtered), Some(g)) = (i.filters, i.filtered, host.screen().gbuffer) {
            let iterations = (s.frame.atrous_iterations, s.frame.atrous_clip_sigmas);
            f.record(rec, cam, g, iterations, filtered);
        }
        if let Some(filtered) = i.filtered {
            host.record_composite(rec, filtered);
        }
    }

    /// After a frame seen by `camera`: its blend is the next frame's history.
    pub fn end_frame(&mut self, camera: GpuCamera) {
        if let Some(f) = &mut self.images.filters {
            f.end_frame(camera);
        }
    }

    /// Forgets the temporal history and the accumulated photons.
    pub fn reset_history(&mut self) {
        if let Some(f) = &mut self.images.filters {
            f.reset();
        }
        self.restart_accumulation();
    }

    /// The frame plan from the emission (`lights`; `photon_passes`: the emission's passes
    /// with the words that say why they run), the atlas and the camera images; the
    /// buffers are the host's and the receiver's.
    pub fn plan(
        &self,
        host: &FrameHost,
        lights: Vec<LightPlan>,
        photon_passes: &[(&str, String)],
        variant: TraceVariant,
    ) -> FramePlan {
        let features = SceneFeatures::of(host.model());
        let casters = features.mirrors || features.dielectrics;
        let emits = lights.iter().any(|l| l.emits);
        let atlas = self.atlas.is_some();
        let photons = atlas && emits;
        let why_no_atlas = if !casters {
            "no specular surface (caustic caster) in the scene"
        } else if host.receivers().is_none() {
            "no diffuse receiver in the scene"
        } else if !emits {
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
        let screen = host.screen();
        let i = self.images;
        pass(
            "primary_gbuffer",
            screen.gbuffer.is_some(),
            "direct light or the temporal and A-Trous filters read the G-buffer",
            "neither direct light nor the composite nor a filter was requested",
        );
        pass(
            "direct_light",
            screen.direct.is_some(),
            "direct or composite requested",
            "neither direct light nor the composite was requested",
        );
        let stale = self.stale_words();
        for (name, why) in photon_passes {
            pass(name, photons, why, why_no_atlas);
        }
        let density = self.atlas.is_some_and(|a| a.density.is_some());
        let raw_map = self.atlas.is_some_and(|a| a.raw_map.is_some());
        pass(
            "gather_caustic_map",
            photons && (!density || raw_map),
            &if density {
                format!("the raw map (N = 1), {stale}")
            } else {
                format!("Vanderstichelen 2021's N x N gather, {stale}")
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
                    "the map's gather is Vanderstichelen 2021's N x N box (gather: box)"
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
            if self.settings.frame.temporal {
                "no filtered caustics are made"
            } else {
                "temporal off"
            },
        );
        pass(
            "atrous_filter",
            chain.is_some_and(|f| f.atrous.is_some()),
            "setting atrous_iterations, on the filtered caustics as the camera sees them",
            if self.settings.frame.atrous_iterations > 0 {
                "no filtered caustics are made"
            } else {
                "atrous_iterations = 0"
            },
        );
        pass(
            "composite",
            screen.composite.is_some(),
            "composite requested",
            if atlas {
                "composite not requested"
            } else {
                why_no_atlas
            },
        );
        FramePlan {
            prune: self.settings.frame.prune,
            features,
            outputs: self.settings.frame.outputs.names(&OUTPUTS),
            lights,
            trace_variant: photons.then_some(variant),
            passes,
            buffers: host
                .buffer_plans()
                .into_iter()
                .chain(self.atlas_owned.buffers.iter().cloned())
                .chain(self.image_owned.buffers.iter().cloned())
                .collect(),
        }
    }

    /// The plan's words for a photon pass: when it runs, and the atlas's layout.
    pub fn stale_words(&self) -> String {
        format!(
            "when the atlas is stale (lights, settings or seed changed); the caustic atlas: {}",
            self.layout_summary
        )
    }

    /// The device image of camera-space `output` (camera-sized, linear radiance, row-major
    /// from the top-left pixel): `None` where the plan knows it is zero, and for the
    /// atlas, which is not camera-space.
    pub fn output_image(&self, host: &FrameHost, output: Output) -> Option<ImageBuf> {
        let (screen, i) = (host.screen(), self.images);
        match output {
            Output::Composite => screen.composite.or(screen.direct),
            Output::Direct => screen.direct,
            Output::RawCaustics => i.raw,
            Output::FilteredCaustics => i.filtered,
            _ => None,
        }
    }

    /// Reads the gathered caustic atlas back: irradiance (W/m^2) per texel, `atlas_size`
    /// square; zeros without an atlas.
    pub fn read_atlas(&self, backend: &mut dyn Backend) -> Result<Image, Error> {
        let side = self.settings.atlas.atlas_size;
        match self.atlas {
            Some(a) => Ok(Image::new(side, side, read_buf(backend, a.map)?)),
            None => Ok(Image::new(
                side,
                side,
                vec![[0.0; 4]; side as usize * side as usize],
            )),
        }
    }

    /// The atlas layout as the kernels read it now, per atlas texel (row-major):
    /// `[world area bits, tile]` ([`AtlasTexel`]; `NO_TILE` and area 0 outside the tiles),
    /// read back from the device; `None` without an atlas.
    pub fn atlas_texels(
        &self,
        backend: &mut dyn Backend,
    ) -> Result<Option<Vec<AtlasTexel>>, Error> {
        match self.atlas {
            Some(a) => Ok(Some(read_buf(backend, a.texels)?)),
            None => Ok(None),
        }
    }

    /// Device buffers and bytes of the receiver.
    pub fn owned(&self) -> (usize, u64) {
        (
            self.atlas_owned.owned.len() + self.image_owned.owned.len(),
            self.atlas_owned.bytes + self.image_owned.bytes,
        )
    }

    /// Releases every device buffer of the receiver.
    pub fn free(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        let mut rec = Recording::new();
        self.atlas_owned.free_into(&mut rec);
        self.image_owned.free_into(&mut rec);
        self.atlas = None;
        self.images = CameraImages::default();
        backend.execute(&rec)?;
        Ok(())
    }
}

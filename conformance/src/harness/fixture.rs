//! Fixed inputs and the drivers that run one kernel on them. A [`Fixture`] is a scene
//! uploaded to the reference and to a candidate; its `run_*` methods run one kernel
//! through a [`Recording`] on either backend with the same input buffers, read the outputs
//! back and free what they created. [`ReferenceInputs`] are every intermediate of a frame as
//! the reference computes it: the inputs the per-kernel checks upload to both backends, so
//! that only the kernel under test can make the outputs differ.

use caustica_core::backend::{read_buf, read_gbuffer, read_photon_map, Backend, BackendError};
use caustica_core::device::device_scene::DeviceScene;
use caustica_core::device::handle::SceneArgs;
use caustica_core::device::layout::{
    counter, DepositTexel, GBufferTexel, GpuCamera, Photon, TraceParams,
};
use caustica_core::kernels::Kernel;
use caustica_core::kernels::{
    BilateralGather, Composite, DensityGather, DepositScreen, DirectLight, GatherFootprint,
    PhotonCountTable, PrimaryGbuffer, ResolveCaustics, TileHitDistance, TracePhotons, TraceVariant,
};
use caustica_core::math::density_gather::{accumulate_source_index, source_index_len};
use caustica_core::recording::{Recording, Step};
use caustica_core::scene::Scene;
use caustica_core::techniques::sspm::{FrameConstants, GatherFilter};
use caustica_core::SspmSettings;

/// An edge texel of the density gather (`math::density_gather::edge_texel`).
pub type EdgeTexel = [f32; 4];

fn backend_err(kernel: &str, b: &dyn Backend) -> impl FnOnce(BackendError) -> String {
    let name = b.name();
    let kernel = kernel.to_string();
    move |e| format!("{kernel} on backend {name}: {e}")
}

/// Executes `rec`, reads what `read` asks for, then frees every buffer `rec` created.
pub fn run_and_free<T>(
    b: &mut dyn Backend,
    what: &str,
    rec: &Recording,
    read: impl FnOnce(&mut dyn Backend) -> Result<T, BackendError>,
) -> Result<T, String> {
    b.execute(rec).map_err(backend_err(what, b))?;
    let out = read(b).map_err(backend_err(what, b));
    let mut free = Recording::new();
    for s in &rec.steps {
        if let Step::Create { id, .. } | Step::Upload { id, .. } = s {
            free.steps.push(Step::Free { id: *id });
        }
    }
    b.execute(&free).map_err(backend_err("free", b))?;
    out
}

/// A scene uploaded (and `prepare_scene`d) on the reference and a candidate, with the
/// frame constants of `settings`.
pub struct Fixture {
    pub name: String,
    pub scene: Scene,
    pub settings: SspmSettings,
    pub ds: DeviceScene,
    pub args: SceneArgs,
    pub camera: GpuCamera,
    pub constants: FrameConstants,
    upload: Recording,
}

impl Fixture {
    pub fn new(
        name: &str,
        scene: &Scene,
        settings: &SspmSettings,
        reference: &mut dyn Backend,
        candidate: &mut dyn Backend,
    ) -> Result<Fixture, String> {
        scene
            .validate()
            .map_err(|p| format!("invalid scene {name}: {p:?}"))?;
        settings
            .validate()
            .map_err(|e| format!("invalid settings: {e}"))?;
        let ds = DeviceScene::build(scene, Default::default())
            .map_err(|e| format!("scene {name} does not build: {e}"))?;
        let mut rec = Recording::new();
        let args = rec.upload_scene(&ds);
        reference
            .execute(&rec)
            .map_err(backend_err("prepare_scene", reference))?;
        candidate
            .execute(&rec)
            .map_err(backend_err("prepare_scene", candidate))?;
        Ok(Fixture {
            name: name.into(),
            constants: FrameConstants::new(scene, &ds, settings),
            scene: scene.clone(),
            settings: settings.clone(),
            camera: GpuCamera::from_camera(&scene.camera),
            ds,
            args,
            upload: rec,
        })
    }

    /// Frees the scene buffers on both backends.
    pub fn release(self, reference: &mut dyn Backend, candidate: &mut dyn Backend) {
        let mut free = Recording::new();
        for s in &self.upload.steps {
            if let Step::Upload { id, .. } = s {
                free.steps.push(Step::Free { id: *id });
            }
        }
        let _ = reference.execute(&free);
        let _ = candidate.execute(&free);
    }

    pub fn pixels(&self) -> u32 {
        self.camera.width * self.camera.height
    }

    pub fn tiles_len(&self) -> u32 {
        let ts = self.settings.screen.tile_size;
        self.camera.width.div_ceil(ts) * self.camera.height.div_ceil(ts)
    }

    /// Runs `primary_gbuffer` on `b`.
    pub fn run_gbuffer(&self, b: &mut dyn Backend) -> Result<Vec<GBufferTexel>, String> {
        let mut rec = Recording::new();
        let g = rec.create_gbuffer(self.pixels());
        rec.kernel(Kernel::PrimaryGbuffer(PrimaryGbuffer {
            scene: self.args,
            camera: self.camera,
            gbuffer: g,
        }));
        run_and_free(b, "primary_gbuffer", &rec, |b| read_gbuffer(b, &g))
    }

    /// Runs `trace_photons` for every photon of light `domains[k]` in one batch; returns
    /// the stored photons and the counters.
    pub fn run_trace(
        &self,
        b: &mut dyn Backend,
        k: usize,
    ) -> Result<(Vec<Photon>, Vec<u32>), String> {
        self.run_trace_with(b, k, |_| {})
    }

    /// [`Fixture::run_trace`] with the dispatch's parameters edited by `edit` first (for
    /// example another `fresnel_model`).
    pub fn run_trace_with(
        &self,
        b: &mut dyn Backend,
        k: usize,
        edit: impl Fn(&mut TraceParams),
    ) -> Result<(Vec<Photon>, Vec<u32>), String> {
        self.run_trace_as(b, k, self.trace_variant(), edit)
    }

    /// The `trace_photons` variant a frame of this scene runs (the plan's).
    pub fn trace_variant(&self) -> TraceVariant {
        caustica_core::frame::plan::SceneFeatures::of(&self.scene).trace_variant()
    }

    /// The one batch of every photon of light `domains[k]`, as the fifth frame of an
    /// accumulation (a jitter seed of its own and stratum 4: every port's strata
    /// arithmetic is compared, not only the plain jitter).
    pub fn trace_batch(&self, k: usize) -> TraceParams {
        let (light, d) = &self.constants.domains[k];
        let count = self.settings.frame.photons_w * self.settings.frame.photons_h;
        let p = self
            .constants
            .trace_params(&self.settings, *light, d, 0, count);
        TraceParams {
            jitter_seed: p.seed ^ 0x5eed_0004,
            stratum: 4,
            ..p
        }
    }

    /// [`Fixture::run_trace_with`] with compiled variant `variant` (without
    /// `fused_deposit`: the photons are read back; a split stores up to
    /// `split_budget` photons per emitted one).
    pub fn run_trace_as(
        &self,
        b: &mut dyn Backend,
        k: usize,
        variant: TraceVariant,
        edit: impl Fn(&mut TraceParams),
    ) -> Result<(Vec<Photon>, Vec<u32>), String> {
        let mut params = self.trace_batch(k);
        edit(&mut params);
        let count = params.count;
        let capacity = if variant.fresnel_split {
            count * params.split_budget.max(1)
        } else {
            count
        };
        let mut rec = Recording::new();
        let photons = rec.create(capacity, "photons");
        let photon_count = rec.create(1, "photon count");
        let counters = rec.create(counter::WORDS as u32, "counters");
        rec.kernel(Kernel::TracePhotons(TracePhotons {
            scene: self.args,
            variant,
            params,
            photons,
            photon_count,
            counters,
            clusters: None,
            deposit: None,
        }));
        run_and_free(b, "trace_photons", &rec, |b| {
            let n = read_buf(b, photon_count)?[0] as usize;
            let mut ph = read_buf(b, photons)?;
            ph.truncate(n.min(capacity as usize));
            Ok((ph, read_buf(b, counters)?))
        })
    }

    /// Runs `deposit_screen` then `resolve_caustics` on `b` for the given G-buffer and
    /// photons.
    pub fn run_deposit(
        &self,
        b: &mut dyn Backend,
        gbuffer: &[GBufferTexel],
        photons: &[Photon],
    ) -> Result<DepositOutput, String> {
        let mut rec = Recording::new();
        let g = rec.upload_gbuffer(gbuffer);
        // A zero-length buffer is not a valid device buffer everywhere: keep one slot.
        let ph = if photons.is_empty() {
            rec.upload(&[Photon::default()], "photons")
        } else {
            rec.upload(photons, "photons")
        };
        let count = rec.upload(&[photons.len() as u32], "photon count");
        let counters = rec.create(counter::WORDS as u32, "counters");
        let map = rec.create_photon_map(self.pixels());
        let out = rec.create(self.pixels(), "raw caustics");
        let params = self
            .constants
            .deposit_params(self.camera, &self.settings, ph.len);
        rec.kernel(Kernel::DepositScreen(DepositScreen {
            params,
            gbuffer: g,
            photons: ph,
            photon_count: count,
            counters,
            photon_map: map,
        }));
        rec.kernel(Kernel::ResolveCaustics(ResolveCaustics {
            params,
            gbuffer: g,
            photon_map: map,
            out,
        }));
        run_and_free(b, "deposit_screen + resolve_caustics", &rec, |b| {
            Ok(DepositOutput {
                photon_map: read_photon_map(b, &map)?,
                counters: read_buf(b, counters)?,
                raw: read_buf(b, out)?,
            })
        })
    }

    /// Runs `tile_hit_distance` on `b`.
    pub fn run_tiles(&self, b: &mut dyn Backend, map: &[DepositTexel]) -> Result<Vec<f32>, String> {
        let mut rec = Recording::new();
        let m = rec.upload_photon_map(map);
        let tiles = rec.create(self.tiles_len(), "tiles");
        rec.kernel(Kernel::TileHitDistance(TileHitDistance {
            params: self.constants.gather_params(self.camera, &self.settings, 0),
            photon_map: m,
            tiles,
        }));
        run_and_free(b, "tile_hit_distance", &rec, |b| read_buf(b, tiles))
    }

    /// Runs one `bilateral_gather` pass (`axis` 0: horizontal, 1: vertical) on `b`.
    pub fn run_gather(
        &self,
        b: &mut dyn Backend,
        axis: u32,
        gbuffer: &[GBufferTexel],
        tiles: &[f32],
        input: &[[f32; 4]],
    ) -> Result<Vec<[f32; 4]>, String> {
        let mut rec = Recording::new();
        let g = rec.upload_gbuffer(gbuffer);
        let t = rec.upload(tiles, "tiles");
        let i = rec.upload(input, "gather input");
        let out = rec.create(self.pixels(), "gather output");
        rec.kernel(Kernel::BilateralGather(BilateralGather {
            params: self
                .constants
                .gather_params(self.camera, &self.settings, axis),
            gbuffer: g,
            tiles: t,
            input: i,
            out,
        }));
        run_and_free(b, "bilateral_gather", &rec, |b| read_buf(b, out))
    }

    /// Runs both directions of `photon_count_table` on `b` (the summed-area table).
    pub fn run_count_table(
        &self,
        b: &mut dyn Backend,
        gbuffer: &[GBufferTexel],
        map: &[DepositTexel],
    ) -> Result<(Vec<u32>, Vec<EdgeTexel>), String> {
        let mut rec = Recording::new();
        let g = rec.upload_gbuffer(gbuffer);
        let m = rec.upload_photon_map(map);
        let table = rec.create(self.pixels(), "photon count table");
        let edge = rec.create(self.pixels(), "gather edge texels");
        for axis in 0..2 {
            rec.kernel(Kernel::PhotonCountTable(PhotonCountTable {
                params: self
                    .constants
                    .gather_params(self.camera, &self.settings, axis),
                photon_map: m,
                table,
                gbuffer: g,
                edge,
            }));
        }
        run_and_free(b, "photon_count_table", &rec, |b| {
            Ok((read_buf(b, table)?, read_buf(b, edge)?))
        })
    }

    /// The density gather's source index `grid` with pass `axis`'s `sources` entered
    /// (`math::density_gather::accumulate_source_index`).
    pub fn source_index_of(&self, mut grid: Vec<u32>, axis: u32, sources: &[[f32; 4]]) -> Vec<u32> {
        let (w, h) = (self.camera.width, self.camera.height);
        let cap = self.settings.screen.max_radius_px as i32;
        accumulate_source_index(&mut grid, sources, w, h, axis, cap);
        grid
    }

    /// A zeroed source index for this fixture's camera.
    pub fn empty_source_index(&self) -> Vec<u32> {
        vec![0; source_index_len(self.camera.width, self.camera.height) as usize]
    }

    /// Runs `gather_footprint` on `b`: the normalised flux and radius per pixel, and the
    /// source index it wrote (into a zeroed one).
    pub fn run_footprint(
        &self,
        b: &mut dyn Backend,
        edge: &[EdgeTexel],
        map: &[DepositTexel],
        table: &[u32],
    ) -> Result<(Vec<[f32; 4]>, Vec<u32>), String> {
        let mut rec = Recording::new();
        let e = rec.upload(edge, "gather edge texels");
        let m = rec.upload_photon_map(map);
        let t = rec.upload(table, "photon count table");
        let out = rec.create(self.pixels(), "footprints");
        let source_index = rec.upload(&self.empty_source_index(), "gather source index");
        rec.kernel(Kernel::GatherFootprint(GatherFootprint {
            params: self.constants.gather_params(self.camera, &self.settings, 0),
            photon_map: m,
            table: t,
            edge: e,
            out,
            source_index,
        }));
        run_and_free(b, "gather_footprint", &rec, |b| {
            Ok((read_buf(b, out)?, read_buf(b, source_index)?))
        })
    }

    /// Runs one `density_gather` pass (`axis` 0: rows, 1: columns) on `b` with the source
    /// index of `input` (as the pass before would have written it): the output, and the
    /// source index after the pass.
    pub fn run_density_gather(
        &self,
        b: &mut dyn Backend,
        axis: u32,
        gbuffer: &[GBufferTexel],
        edge: &[EdgeTexel],
        input: &[[f32; 4]],
    ) -> Result<(Vec<[f32; 4]>, Vec<u32>), String> {
        let mut rec = Recording::new();
        let g = rec.upload_gbuffer(gbuffer);
        let e = rec.upload(edge, "gather edge texels");
        let i = rec.upload(input, "gather input");
        let out = rec.create(self.pixels(), "gather output");
        let index = self.source_index_of(self.empty_source_index(), axis, input);
        let source_index = rec.upload(&index, "gather source index");
        rec.kernel(Kernel::DensityGather(DensityGather {
            params: self
                .constants
                .gather_params(self.camera, &self.settings, axis),
            gbuffer: g,
            edge: e,
            input: i,
            out,
            source_index,
        }));
        run_and_free(b, "density_gather", &rec, |b| {
            Ok((read_buf(b, out)?, read_buf(b, source_index)?))
        })
    }

    /// Runs `direct_light` on `b` with the given G-buffer.
    pub fn run_direct(
        &self,
        b: &mut dyn Backend,
        gbuffer: &[GBufferTexel],
    ) -> Result<Vec<[f32; 4]>, String> {
        let mut rec = Recording::new();
        let g = rec.upload_gbuffer(gbuffer);
        let out = rec.create(self.pixels(), "direct");
        rec.kernel(Kernel::DirectLight(DirectLight {
            scene: self.args,
            params: FrameConstants::direct_params(
                self.camera,
                self.scene.lights.len() as u32,
                &self.settings,
            ),
            gbuffer: g,
            out,
        }));
        run_and_free(b, "direct_light", &rec, |b| read_buf(b, out))
    }
}

/// Runs `composite` on `b`.
pub fn run_composite(
    b: &mut dyn Backend,
    direct: &[[f32; 4]],
    caustics: &[[f32; 4]],
) -> Result<Vec<[f32; 4]>, String> {
    let mut rec = Recording::new();
    let d = rec.upload(direct, "direct");
    let c = rec.upload(caustics, "caustics");
    let out = rec.create(direct.len() as u32, "composite");
    rec.kernel(Kernel::Composite(Composite {
        direct: d,
        caustics: c,
        out,
    }));
    run_and_free(b, "composite", &rec, |b| read_buf(b, out))
}

/// What `deposit_screen` + `resolve_caustics` produce.
pub struct DepositOutput {
    pub photon_map: Vec<DepositTexel>,
    pub counters: Vec<u32>,
    /// Raw caustic radiance (alpha: mean hit distance).
    pub raw: Vec<[f32; 4]>,
}

/// Every intermediate of a frame, computed by the reference alone: the fixed inputs the
/// per-kernel checks upload to both backends.
pub struct ReferenceInputs {
    pub gbuffer: Vec<GBufferTexel>,
    /// Stored photons of every light, concatenated.
    pub photons: Vec<Photon>,
    pub photon_map: Vec<DepositTexel>,
    pub raw: Vec<[f32; 4]>,
    pub tiles: Vec<f32>,
    /// The photon counts' summed-area table (density gather).
    pub table: Vec<u32>,
    /// `gather_footprint`'s output: normalised flux and radius per pixel.
    pub footprints: Vec<[f32; 4]>,
    /// `photon_count_table`'s edge texels.
    pub edge: Vec<EdgeTexel>,
    /// The density gather's row pass of `footprints`.
    pub density_rows: Vec<[f32; 4]>,
    /// The filtered caustics with the fixture's filter (density: both passes of
    /// `density_gather`; bilateral: horizontal then vertical gather of `raw`).
    pub filtered: Vec<[f32; 4]>,
    pub direct: Vec<[f32; 4]>,
}

impl ReferenceInputs {
    pub fn new(fx: &Fixture, r: &mut dyn Backend) -> Result<ReferenceInputs, String> {
        let gbuffer = fx.run_gbuffer(r)?;
        let mut photons = Vec::new();
        for k in 0..fx.constants.domains.len() {
            photons.extend(fx.run_trace(r, k)?.0);
        }
        let DepositOutput {
            photon_map, raw, ..
        } = fx.run_deposit(r, &gbuffer, &photons)?;
        let tiles = fx.run_tiles(r, &photon_map)?;
        let (table, edge) = fx.run_count_table(r, &gbuffer, &photon_map)?;
        let footprints = fx.run_footprint(r, &edge, &photon_map, &table)?.0;
        let density_rows = fx.run_density_gather(r, 0, &gbuffer, &edge, &footprints)?.0;
        let filtered = match fx.settings.screen.filter {
            GatherFilter::Density => {
                fx.run_density_gather(r, 1, &gbuffer, &edge, &density_rows)?
                    .0
            }
            GatherFilter::Bilateral => {
                let half = fx.run_gather(r, 0, &gbuffer, &tiles, &raw)?;
                fx.run_gather(r, 1, &gbuffer, &tiles, &half)?
            }
        };
        let direct = fx.run_direct(r, &gbuffer)?;
        Ok(ReferenceInputs {
            gbuffer,
            photons,
            photon_map,
            raw,
            tiles,
            table,
            footprints,
            edge,
            density_rows,
            filtered,
            direct,
        })
    }
}

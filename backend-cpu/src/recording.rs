//! The recording interpreter: every step of a [`Recording`] at once, in order (buffer
//! steps on host memory, `memory.rs`), and each kernel run on the backend's thread pool by
//! `run_kernel`'s exhaustive match over core's kernel list, which hands the kernel's
//! buffers to its function in [`crate::kernels`].
//!
//! [`Backend::execute`]: caustica_core::backend::Backend::execute

use crate::atlas_deposit;
use crate::kernels;
use crate::memory::Storage;
use crate::traversal::{self, SceneView};
use crate::CpuBackend;
use caustica_core::backend::{BackendError, PassTime};
use caustica_core::device::handle::{GBufferPlanes, PhotonMapPlanes, ResourceId};
use caustica_core::device::layout::{
    gather_surface, GBufferTexel, GBufferView, GpuLight, Photon, PhotonMapView, RsmPhoton, RsmTexel,
};
use caustica_core::kernels::Kernel;
use caustica_core::kernels::{
    AtlasDeposit, AtrousFilter, BilateralGather, CausticMapLookup, Composite, DensityGather,
    DepositScreen, DirectLight, FusedDeposit, GatherCausticMap, GatherFootprint, PhotonCountTable,
    PrepareScene, PrimaryGbuffer, RefineClusters, ResolveCaustics, RsmImportance, SampleRsm,
    ShadingNormalCorrection, SplatPhotons, TemporalBlend, TileHitDistance, TraceIndirect,
    TracePhotons,
};
use caustica_core::recording::{Recording, Step};

impl CpuBackend {
    /// [`Backend::execute`]'s body: each step at once, in order; kernels on the backend's
    /// thread pool, timed by the host clock.
    pub(crate) fn execute_recording(
        &mut self,
        recording: &Recording,
    ) -> Result<Vec<PassTime>, BackendError> {
        let mut times = Vec::new();
        for step in &recording.steps {
            match step {
                Step::Create { id, bytes, label } => {
                    self.buffers.insert(*id, Storage::zeroed(*bytes, label)?);
                }
                Step::Upload { id, data, label } => {
                    let mut s = Storage::zeroed(data.len() as u64, label)?;
                    s.write_all(data)?;
                    self.buffers.insert(*id, s);
                }
                Step::Write {
                    id,
                    offset,
                    data,
                    label,
                } => self.get_mut(*id)?.write_at(label, *offset, data)?,
                Step::Clear { id } => self.get_mut(*id)?.clear(),
                Step::Free { id } => {
                    self.buffers.remove(*id);
                }
                Step::Kernel(k) => {
                    self.variants.note(k)?;
                    times.push(self.run_timed(k)?);
                }
            }
        }
        Ok(times)
    }

    /// Runs kernel `k` on the host: its buffers handed to its function in
    /// [`crate::kernels`] (one arm per kernel of core's list; the compiler refuses a
    /// missing one).
    pub(crate) fn run_kernel(&mut self, k: &Kernel) -> Result<(), BackendError> {
        use kernels::*;
        if let Kernel::PrepareScene(PrepareScene { scene }) = k {
            // the traversal reads the node buffer in place: only its shape is checked
            let nodes = self
                .get(scene.bvh_nodes.id)?
                .as_slice::<[u32; 4]>(scene.bvh_nodes.len)?;
            traversal::check_nodes(nodes)?;
            return Ok(());
        }
        let bufs = &self.buffers;
        let get = |id: ResourceId| bufs.get(id);
        // a photon map's planes as the atomics the deposit kernels add to
        let map_atomics =
            |m: &PhotonMapPlanes| -> Result<kernels::deposit_screen::MapPlanes<'_>, BackendError> {
                let [a, b, c] = m.planes;
                Ok([
                    get(a.id)?.as_atomic_u64(a.bytes())?,
                    get(b.id)?.as_atomic_u64(b.bytes())?,
                    get(c.id)?.as_atomic_u64(c.bytes())?,
                ])
            };
        let view =
            |s: &caustica_core::device::handle::SceneArgs| -> Result<SceneView<'_>, BackendError> {
                Ok(SceneView {
                    vertices: get(s.vertices.id)?.as_slice(s.vertices.len)?,
                    triangles: get(s.triangles.id)?.as_slice(s.triangles.len)?,
                    materials: get(s.materials.id)?.as_slice(s.materials.len)?,
                    lights: get(s.lights.id)?.as_slice(s.lights.len)?,
                    nodes: get(s.bvh_nodes.id)?.as_slice(s.bvh_nodes.len)?,
                })
            };
        match k {
            Kernel::PrepareScene(PrepareScene { .. }) => unreachable!("handled above"),
            Kernel::PrimaryGbuffer(PrimaryGbuffer {
                scene,
                camera,
                gbuffer,
            }) => {
                let pixels = camera.width as u64 * camera.height as u64;
                reserve_temporary::<GBufferTexel>(pixels, "the G-buffer")?;
                let out = primary_gbuffer::primary_gbuffer(&view(scene)?, camera);
                // plane by plane, with no second copy of the G-buffer (8192^2: 4 GiB)
                for (k, b) in gbuffer.planes.iter().enumerate() {
                    use rayon::prelude::*;
                    let plane = self.get_mut(b.id)?.as_mut_slice(b.len)?;
                    if plane.len() != out.len() {
                        return Err(BackendError::BadArgument(
                            "G-buffer plane and camera differ in size".into(),
                        ));
                    }
                    plane
                        .par_iter_mut()
                        .zip(out.par_iter())
                        .for_each(|(p, t): (&mut [u32; 4], _)| *p = t.to_planes()[k]);
                }
                Ok(())
            }
            Kernel::DirectLight(DirectLight {
                scene,
                params,
                gbuffer,
                out,
            }) => {
                let g = self.gbuffer(gbuffer)?;
                reserve_temporary::<[f32; 4]>(out.len as u64, "the direct image")?;
                let img = direct_light::direct_light(&view(scene)?, params, g);
                self.put(out.id, &img)
            }
            Kernel::TracePhotons(TracePhotons {
                scene,
                variant,
                params,
                photons,
                photon_count,
                counters,
                clusters,
                deposit,
            }) => {
                reserve_temporary::<Photon>(params.count as u64, "a photon batch")?;
                let result = match clusters.filter(|_| variant.adaptive) {
                    Some(c) => {
                        let list = get(c.id)?.as_slice::<u32>(c.len)?.to_vec();
                        trace_photons::trace_cluster_slots(&view(scene)?, params, *variant, &list)
                    }
                    None => trace_photons::trace_photons(&view(scene)?, params, *variant),
                };
                let fused = deposit.filter(|_| variant.fused_deposit);
                // the fused pass into the screen: the stored photons as deposit_screen
                // adds them
                let screen = match &fused {
                    Some(FusedDeposit::Screen(d)) => {
                        let g = self.gbuffer(&d.gbuffer)?;
                        let atomics = map_atomics(&d.photon_map)?;
                        Some(deposit_screen::deposit_screen(
                            &d.params,
                            g,
                            &result.photons,
                            atomics,
                        ))
                    }
                    _ => None,
                };
                let words = self.get_mut(counters.id)?.as_mut_slice(counters.len)?;
                result.counters.add_to(words);
                if let Some(c) = screen {
                    c.add_to(words);
                    return Ok(());
                }
                if let Some(FusedDeposit::Atlas(d)) = fused {
                    // the fused pass into the atlas, as atlas_deposit::deposit_atlas adds them
                    return self.deposit_atlas_photons(&d, &result.photons, *counters);
                }
                if result.photons.len() > photons.len as usize {
                    return Err(BackendError::BadArgument(format!(
                        "photon buffer holds {} photons, batch stored {}",
                        photons.len,
                        result.photons.len()
                    )));
                }
                self.get_mut(photons.id)?.write_prefix(&result.photons)?;
                if !variant.adaptive {
                    self.get_mut(photon_count.id)?.as_mut_slice::<u32>(1)?[0] =
                        result.photons.len() as u32;
                }
                Ok(())
            }
            Kernel::DepositScreen(DepositScreen {
                params,
                gbuffer,
                photons,
                photon_count,
                counters,
                photon_map,
            }) => {
                let n = get(photon_count.id)?.as_slice::<u32>(1)?[0].min(photons.len);
                let ph = &get(photons.id)?.as_slice(photons.len)?[..n as usize];
                let g = self.gbuffer(gbuffer)?;
                let atomics = map_atomics(photon_map)?;
                let c = deposit_screen::deposit_screen(params, g, ph, atomics);
                c.add_to(self.get_mut(counters.id)?.as_mut_slice(counters.len)?);
                Ok(())
            }
            Kernel::ResolveCaustics(ResolveCaustics {
                params,
                gbuffer,
                photon_map,
                out,
            }) => {
                let g = self.gbuffer(gbuffer)?;
                let m = self.photon_map(photon_map)?;
                reserve_temporary::<[f32; 4]>(out.len as u64, "the raw caustics image")?;
                let img = resolve_caustics::resolve_caustics(params, g, m);
                self.put(out.id, &img)
            }
            Kernel::TileHitDistance(TileHitDistance {
                params,
                photon_map,
                tiles,
            }) => {
                let m = self.photon_map(photon_map)?;
                reserve_temporary::<f32>(tiles.len as u64, "the hit-distance tiles")?;
                let t = tile_hit_distance::tile_hit_distance(params, m);
                self.put(tiles.id, &t)
            }
            Kernel::BilateralGather(BilateralGather {
                params,
                gbuffer,
                tiles,
                input,
                out,
            }) => {
                let g = self.gbuffer(gbuffer)?;
                let t = get(tiles.id)?.as_slice(tiles.len)?;
                let i = get(input.id)?.as_slice(input.len)?;
                reserve_temporary::<[f32; 4]>(out.len as u64, "a gathered image")?;
                let img = bilateral_gather::bilateral_gather(params, g, t, i);
                self.put(out.id, &img)
            }
            Kernel::PhotonCountTable(PhotonCountTable {
                params,
                photon_map,
                table,
                gbuffer,
                edge,
            }) => {
                if params.axis == 0 {
                    let rows = {
                        let m = self.photon_map(photon_map)?;
                        reserve_temporary::<u32>(table.len as u64, "the photon count table")?;
                        let mut rows = vec![0u32; table.len as usize];
                        photon_count_table::photon_count_rows(params, m, &mut rows);
                        rows
                    };
                    self.put(table.id, &rows)
                } else if params.surface == gather_surface::ATLAS {
                    // the atlas's edge texels come with its layout
                    let t = self.get_mut(table.id)?.as_mut_slice(table.len)?;
                    photon_count_table::photon_count_columns(params, t);
                    Ok(())
                } else {
                    let edges = {
                        let g = self.gbuffer(gbuffer)?;
                        reserve_temporary::<[f32; 4]>(edge.len as u64, "the edge texels")?;
                        photon_count_table::edge_texels(g, edge.len as usize)
                    };
                    let t = self.get_mut(table.id)?.as_mut_slice(table.len)?;
                    photon_count_table::photon_count_columns(params, t);
                    self.put(edge.id, &edges)
                }
            }
            Kernel::GatherFootprint(GatherFootprint {
                params,
                photon_map,
                table,
                edge,
                out,
                source_index,
            }) => {
                let m = self.photon_map(photon_map)?;
                let t = get(table.id)?.as_slice(table.len)?;
                let e = get(edge.id)?.as_slice(edge.len)?;
                reserve_temporary::<[f32; 4]>(out.len as u64, "the gather footprints")?;
                let img = gather_footprint::gather_footprint(params, e, m, t);
                let sources = get(source_index.id)?.as_slice(source_index.len)?;
                let sources = gather_footprint::source_index(params, 0, sources, &img);
                self.put(out.id, &img)?;
                self.put(source_index.id, &sources)
            }
            Kernel::DensityGather(DensityGather {
                params,
                gbuffer,
                edge,
                input,
                out,
                source_index,
            }) => {
                let g = self.gbuffer(gbuffer)?;
                let e = get(edge.id)?.as_slice(edge.len)?;
                let i = get(input.id)?.as_slice(input.len)?;
                let sources = get(source_index.id)?.as_slice(source_index.len)?;
                reserve_temporary::<[f32; 4]>(out.len as u64, "a gathered image")?;
                let img = density_gather::density_gather(params, g, e, i, sources);
                if params.axis == 0 {
                    // the row pass's output: the column pass's sources
                    let sources = gather_footprint::source_index(params, 1, sources, &img);
                    self.put(source_index.id, &sources)?;
                }
                self.put(out.id, &img)
            }
            Kernel::RefineClusters(RefineClusters {
                params,
                clusters,
                caster_rects,
                photons,
                triangle_tiles,
                tiles,
                children,
                converged,
                cluster_counts,
                counters,
                atlas,
                output_photons,
                output_count,
            }) => {
                let list = get(clusters.id)?.as_slice(clusters.len)?;
                let rects = get(caster_rects.id)?.as_slice(caster_rects.len)?;
                let ph = get(photons.id)?.as_slice(photons.len)?;
                let tt = get(triangle_tiles.id)?.as_slice(triangle_tiles.len)?;
                let tl = get(tiles.id)?.as_slice(tiles.len)?;
                let atomics = map_atomics(atlas)?;
                let r = refine_clusters::refine_clusters(params, list, rects, ph, tt, tl, atomics);
                r.counters
                    .add_to(self.get_mut(counters.id)?.as_mut_slice(counters.len)?);
                let mut counts = self
                    .get(cluster_counts.id)?
                    .as_slice::<u32>(cluster_counts.len)?
                    .to_vec();
                let mut conv = self
                    .get(converged.id)?
                    .as_slice::<u32>(converged.len)?
                    .to_vec();
                let kids = self.get_mut(children.id)?.as_mut_slice(children.len)?;
                refine_clusters::append_refined(
                    &r,
                    (kids, params.children_capacity),
                    &mut conv,
                    &mut counts,
                );
                self.get_mut(converged.id)?
                    .as_mut_slice::<u32>(converged.len)?
                    .copy_from_slice(&conv);
                self.get_mut(cluster_counts.id)?
                    .as_mut_slice::<u32>(cluster_counts.len)?
                    .copy_from_slice(&counts);
                if !r.outputs.is_empty() {
                    let mut n = self.get(output_count.id)?.as_slice::<u32>(1)?[0];
                    let out = self
                        .get_mut(output_photons.id)?
                        .as_mut_slice(output_photons.len)?;
                    refine_clusters::append_outputs(&r, out, &mut n);
                    self.get_mut(output_count.id)?.as_mut_slice::<u32>(1)?[0] = n;
                }
                Ok(())
            }
            Kernel::GatherCausticMap(GatherCausticMap {
                params,
                texels,
                tiles,
                atlas,
                out,
            }) => {
                let tx = get(texels.id)?.as_slice(texels.len)?;
                let tl = get(tiles.id)?.as_slice(tiles.len)?;
                let m = self.photon_map(atlas)?;
                reserve_temporary::<[f32; 4]>(out.len as u64, "the caustic map")?;
                let img = gather_caustic_map::gather_caustic_map(params, tx, tl, m);
                self.put(out.id, &img)
            }
            Kernel::CausticMapLookup(CausticMapLookup {
                scene,
                params,
                triangle_tiles,
                tiles,
                texels,
                map,
                out,
            }) => {
                let tt = get(triangle_tiles.id)?.as_slice(triangle_tiles.len)?;
                let tl = get(tiles.id)?.as_slice(tiles.len)?;
                let tx = get(texels.id)?.as_slice(texels.len)?;
                let m = get(map.id)?.as_slice(map.len)?;
                reserve_temporary::<[f32; 4]>(out.len as u64, "the caustics image")?;
                let img =
                    caustic_map_lookup::caustic_map_lookup(&view(scene)?, params, tt, tl, tx, m);
                self.put(out.id, &img)
            }
            Kernel::ShadingNormalCorrection(ShadingNormalCorrection {
                params,
                gbuffer,
                direction_map,
                input,
                out,
            }) => {
                let g = self.gbuffer(gbuffer)?;
                let d = self.photon_map(direction_map)?;
                let i = get(input.id)?.as_slice(input.len)?;
                reserve_temporary::<[f32; 4]>(out.len as u64, "the shading-normal correction")?;
                let img = shading_normal_correction::shading_normal_correction(params, g, d, i);
                self.put(out.id, &img)
            }
            Kernel::Composite(Composite {
                direct,
                caustics,
                out,
            }) => {
                let d = get(direct.id)?.as_slice(direct.len)?;
                let c = get(caustics.id)?.as_slice(caustics.len)?;
                reserve_temporary::<[f32; 4]>(out.len as u64, "the composite")?;
                let img = composite::composite(d, c);
                self.put(out.id, &img)
            }
            Kernel::AtrousFilter(AtrousFilter {
                params,
                gbuffer,
                input,
                details,
                out,
            }) => {
                let g = self.gbuffer(gbuffer)?;
                let i = get(input.id)?.as_slice(input.len)?;
                let d = get(details.id)?.as_slice(details.len)?;
                reserve_temporary::<[[f32; 4]; 2]>(out.len as u64, "an A-Trous iteration")?;
                let r = atrous_filter::atrous_filter_image(params, g, i, d);
                let (img, det): (Vec<[f32; 4]>, Vec<[f32; 4]>) = r.into_iter().unzip();
                self.put(details.id, &det)?;
                self.put(out.id, &img)
            }
            Kernel::RsmImportance(RsmImportance {
                params,
                lights,
                gbuffer,
                texels,
                pyramid,
            }) => {
                let plen = caustica_core::math::rsm::pyramid_len(params.side) as usize;
                let f = params.face as usize;
                if params.level == 0 {
                    let light = *get(lights.id)?
                        .as_slice::<GpuLight>(lights.len)?
                        .get(params.light as usize)
                        .ok_or_else(|| {
                            BackendError::BadArgument("rsm_importance: no such light".into())
                        })?;
                    let g = self.gbuffer(gbuffer)?;
                    let n = params.side as usize * params.side as usize;
                    let (t, imp): (Vec<RsmTexel>, Vec<f32>) = {
                        use rayon::prelude::*;
                        (0..n)
                            .into_par_iter()
                            .map(|i| {
                                rsm_importance::rsm_texel(
                                    params,
                                    &light,
                                    &g.load_gbuffer(i),
                                    i as u32,
                                )
                            })
                            .unzip()
                    };
                    self.get_mut(texels.id)?
                        .as_mut_slice::<RsmTexel>(texels.len)?[f * n..(f + 1) * n]
                        .copy_from_slice(&t);
                    self.get_mut(pyramid.id)?.as_mut_slice::<f32>(pyramid.len)?
                        [f * plen..f * plen + n]
                        .copy_from_slice(&imp);
                } else {
                    rsm_importance::rsm_level(
                        params,
                        self.get_mut(pyramid.id)?.as_mut_slice(pyramid.len)?,
                    );
                }
                Ok(())
            }
            Kernel::SampleRsm(SampleRsm {
                params,
                lights,
                texels,
                pyramid,
                photons,
            }) => {
                let light = *get(lights.id)?
                    .as_slice::<GpuLight>(lights.len)?
                    .get(params.light as usize)
                    .ok_or_else(|| BackendError::BadArgument("sample_rsm: no such light".into()))?;
                let t = get(texels.id)?.as_slice(texels.len)?;
                let pyr = get(pyramid.id)?.as_slice(pyramid.len)?;
                reserve_temporary::<RsmPhoton>(params.sample_count as u64, "the RSM photons")?;
                let out = sample_rsm::sample_rsm(params, &light, t, pyr);
                let first = params.first_sample as usize;
                self.get_mut(photons.id)?
                    .as_mut_slice::<RsmPhoton>(photons.len)?[first..first + out.len()]
                    .copy_from_slice(&out);
                Ok(())
            }
            Kernel::TraceIndirect(TraceIndirect {
                scene,
                params,
                rsm_photons,
                photons,
                photon_count,
                tile_counts,
                counters,
                gbuffer,
            }) => {
                let rsm = get(rsm_photons.id)?.as_slice::<RsmPhoton>(rsm_photons.len)?;
                let g = self.gbuffer(gbuffer)?;
                reserve_temporary::<[u32; 8]>(params.count as u64, "an indirect photon batch")?;
                let r = trace_indirect::trace_indirect(
                    &view(scene)?,
                    params,
                    rsm,
                    &g,
                    tile_counts.len as usize,
                );
                let start = get(photon_count.id)?.as_slice::<u32>(1)?[0] as usize;
                if start + r.photons.len() > photons.len as usize {
                    return Err(BackendError::BadArgument(format!(
                        "indirect photon buffer holds {} photons, {} stored",
                        photons.len,
                        start + r.photons.len()
                    )));
                }
                self.get_mut(photons.id)?
                    .as_mut_slice::<[u32; 8]>(photons.len)?[start..start + r.photons.len()]
                    .copy_from_slice(&r.photons);
                self.get_mut(photon_count.id)?.as_mut_slice::<u32>(1)?[0] =
                    (start + r.photons.len()) as u32;
                for (t, n) in self
                    .get_mut(tile_counts.id)?
                    .as_mut_slice::<u32>(tile_counts.len)?
                    .iter_mut()
                    .zip(&r.tile_counts)
                {
                    *t = t.wrapping_add(*n);
                }
                r.counters
                    .add_to(self.get_mut(counters.id)?.as_mut_slice(counters.len)?);
                Ok(())
            }
            Kernel::SplatPhotons(SplatPhotons {
                params,
                gbuffer,
                photons,
                photon_count,
                tile_counts,
                counters,
                photon_map,
                direction_map,
            }) => {
                let n = get(photon_count.id)?.as_slice::<u32>(1)?[0].min(photons.len);
                let ph = &get(photons.id)?.as_slice(photons.len)?[..n as usize];
                let tc = get(tile_counts.id)?.as_slice(tile_counts.len)?;
                let g = self.gbuffer(gbuffer)?;
                let atomics = map_atomics(photon_map)?;
                let directions = map_atomics(direction_map)?;
                let c = splat_photons::splat_photons(params, g, ph, tc, atomics, directions);
                c.add_to(self.get_mut(counters.id)?.as_mut_slice(counters.len)?);
                Ok(())
            }
            Kernel::TemporalBlend(TemporalBlend {
                params,
                gbuffer,
                input,
                history,
                history_edge,
                out,
                next_history,
                next_edge,
            }) => {
                let g = self.gbuffer(gbuffer)?;
                let i = get(input.id)?.as_slice(input.len)?;
                let hi = get(history.id)?.as_slice(history.len)?;
                let he = get(history_edge.id)?.as_slice(history_edge.len)?;
                reserve_temporary::<[[f32; 4]; 2]>(out.len as u64, "the temporal blend")?;
                let r = temporal_blend::temporal_blend_image(params, g, i, hi, he);
                let (img, edge): (Vec<[f32; 4]>, Vec<[f32; 4]>) = r.into_iter().unzip();
                self.put(out.id, &img)?;
                self.put(next_history.id, &img)?;
                self.put(next_edge.id, &edge)
            }
        }
    }

    /// The G-buffer's planes (the kernels read texels through the view).
    fn gbuffer(&self, g: &GBufferPlanes) -> Result<GBufferView<'_>, BackendError> {
        let [a, b, c, d] = g.planes;
        Ok(GBufferView {
            planes: [
                self.get(a.id)?.as_slice(a.len)?,
                self.get(b.id)?.as_slice(b.len)?,
                self.get(c.id)?.as_slice(c.len)?,
                self.get(d.id)?.as_slice(d.len)?,
            ],
        })
    }

    /// The photon map's planes.
    fn photon_map(&self, m: &PhotonMapPlanes) -> Result<PhotonMapView<'_>, BackendError> {
        let [a, b, c] = m.planes;
        Ok(PhotonMapView {
            planes: [
                self.get(a.id)?.as_slice(a.len)?,
                self.get(b.id)?.as_slice(b.len)?,
                self.get(c.id)?.as_slice(c.len)?,
            ],
        })
    }

    /// The atlas deposit of texture-space photons `ph` into atlas `d`: the fixed-point sums,
    /// the reach bits of their triangles and the deposit's counters (added to
    /// `counters`). The fused `fused_deposit` trace's second half.
    fn deposit_atlas_photons(
        &mut self,
        d: &AtlasDeposit,
        ph: &[Photon],
        counters: caustica_core::device::handle::Buf<u32>,
    ) -> Result<(), BackendError> {
        let c = {
            let tt = self
                .get(d.triangle_tiles.id)?
                .as_slice(d.triangle_tiles.len)?;
            let tl = self.get(d.tiles.id)?.as_slice(d.tiles.len)?;
            let [a, b, c] = d.sums.planes;
            let atomics = [
                self.get(a.id)?.as_atomic_u64(a.bytes())?,
                self.get(b.id)?.as_atomic_u64(b.bytes())?,
                self.get(c.id)?.as_atomic_u64(c.bytes())?,
            ];
            atlas_deposit::deposit_atlas(&d.params, tt, tl, ph, atomics)
        };
        let reach = self
            .get_mut(d.triangle_reach.id)?
            .as_mut_slice::<u32>(d.triangle_reach.len)?;
        atlas_deposit::mark_triangle_reach(ph, reach);
        c.add_to(self.get_mut(counters.id)?.as_mut_slice(counters.len)?);
        Ok(())
    }
}

/// The CPU kernels build their result in a temporary vector (rayon's `collect`, which
/// aborts when the host cannot give it) before it is copied into the destination buffer:
/// reserve that much first, so that out of host memory is an error. The reservation is
/// released at once (address space only, nothing is touched); the kernel's own
/// allocation then finds the room.
fn reserve_temporary<T>(count: u64, what: &str) -> Result<(), BackendError> {
    let bytes = count.saturating_mul(std::mem::size_of::<T>() as u64);
    let oom = || BackendError::OutOfMemory {
        bytes,
        what: format!("{what} (host memory, the CPU kernel's result)"),
    };
    let n = usize::try_from(bytes).map_err(|_| oom())?;
    let mut probe: Vec<u8> = Vec::new();
    probe.try_reserve_exact(n).map_err(|_| oom())
}

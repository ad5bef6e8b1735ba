//! The cross-backend suite, itself tested. Two promises of the checks in
//! `caustica_conformance::kernels` and `caustica_conformance::techniques` are checked with
//! "mutant" backends that wrap the CPU backend, so they run on any machine:
//!
//! - a backend that differs from the CPU only by rounding passes every comparison: the
//!   `UlpNoise` mutant nudges every float input of every kernel (vertices, normals, camera,
//!   emission domain, photon flux, filter parameters) by up to 2 ulps, as a device's
//!   different division, sqrt, sin/cos or FMA contraction would, and lets the chaotic photon
//!   paths diverge where they really do. The tolerances must absorb that;
//! - a backend with a real but small fault fails the comparison that covers the kernel:
//!   depth written as distance, 3% of the photons lost, photon flux 2% low, one fixed-point
//!   unit lost per texel, radiance 1e-4 high, a summed-area table one photon off, the
//!   density gather's flux 1e-4 high, one ulp in the composite, the caustic atlas one unit
//!   low, the caustic map's gather 1e-4 high, its lookup 1e-3 high, a photon kernel
//!   that ignores its compiled variant switches, adaptive photon slots rotated within
//!   their cluster, a refined cluster's child one texel off, a converged cluster lost,
//!   and so on.

use caustica_conformance::harness::{self, builtin_small, kernel_cases, Candidate, Report};
use caustica_conformance::kernels::{
    atrous_filter::check_atrous_filter,
    bilateral_gather::check_gather,
    caustic_map_lookup::check_caustic_map,
    check_kernel_cases,
    composite::check_composite,
    density_gather::check_density_gather,
    deposit_screen::{check_deposit, check_fused_screen_trace},
    direct_light::check_direct,
    primary_gbuffer::check_gbuffer,
    refine_clusters::{check_adaptive_caustics, check_screen_target},
    shading_normal_correction::check_photon_gi,
    temporal_blend::check_temporal_blend,
    trace_photons::{check_fused_trace, check_trace},
    KernelCheck,
};
use caustica_conformance::techniques::sspm::check_frame;
use caustica_conformance::{small_settings, strategies};
use caustica_core::backend::{read_gbuffer, Backend, BackendError, Capabilities, PassTime};
use caustica_core::device::handle::{PhotonMapPlanes, ResourceId};
use caustica_core::device::layout::{
    cluster_count, counter, deposit_word, gbuffer_to_planes, GBufferPlaneTexel, GiPhoton,
    GpuCamera, GpuVertex, Photon, RsmPhoton, RsmTexel, DEPOSIT_PLANE_WORDS, NO_MATERIAL,
};
use caustica_core::frame::output::Output;
use caustica_core::kernels::Kernel;
use caustica_core::kernels::{
    AtlasDeposit, AtrousFilter, BilateralGather, CausticMapLookup, Composite, DensityGather,
    DepositScreen, DirectLight, FusedDeposit, GatherCausticMap, GatherFootprint, PhotonCountTable,
    PrimaryGbuffer, RefineClusters, ResolveCaustics, RsmImportance, SampleRsm, ScreenDeposit,
    ShadingNormalCorrection, SplatPhotons, TemporalBlend, TileHitDistance, TraceIndirect,
    TracePhotons,
};
use caustica_core::math::density_gather::reach_grid_len;
use caustica_core::math::fixed_point::{join_u64, quantize};
use caustica_core::math::packing::{pack_rgb9e5, pack_unit_vector, unpack_rgb9e5};
use caustica_core::math::photon_clusters::entry_cluster;
use caustica_core::math::rng::pcg_hash;
use caustica_core::recording::{Recording, Step};
use caustica_core::scene::builtin::BUILTIN_SCENES;
use caustica_cpu::CpuBackend;
use proptest::strategy::{Strategy, ValueTree};
use proptest::test_runner::TestRunner;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Mutation {
    /// Correct, with different rounding: float inputs nudged by up to 2 ulps.
    UlpNoise,
    /// `prepare_scene` leaves every instance at the origin: its record's `object_from_world`
    /// becomes the identity (a traversal that ignores the instance transform).
    InstanceTransformLost,
    /// Writes into existing buffers are dropped (a backend without `Step::Write`: moved
    /// instances never reach the device).
    WritesDropped,
    /// `primary_gbuffer` writes the view distance as the view depth.
    GbufferDepthIsDistance,
    /// `primary_gbuffer` writes the (interpolated) shading normal as the geometric normal.
    GbufferGeometricIsShading,
    /// `trace_photons` loses every 30th stored photon (counted as escaped).
    DropPhotons,
    /// `trace_photons` stores photons with 2% less flux.
    PhotonFluxLow,
    /// `deposit_screen` loses one fixed-point unit of red in every texel it touches.
    DepositOffByOne,
    /// `resolve_caustics` radiance 1e-4 too high.
    ResolveHigh,
    /// `tile_hit_distance` 1e-4 too high.
    TilesHigh,
    /// `bilateral_gather` 1e-4 too high.
    GatherHigh,
    /// `photon_count_table` one photon too many in every non-zero entry.
    CountTableOffByOne,
    /// `gather_footprint` flux 1e-4 too high.
    FootprintHigh,
    /// `density_gather` 1e-4 too high.
    DensityGatherHigh,
    /// `density_gather` passes each lit pixel's radius (its alpha) on one ulp high.
    DensityGatherRadiusUlp,
    /// `gather_footprint`'s reach-grid entries one tap short: the row pass would miss
    /// each tile's farthest-reaching source's last taps.
    ReachShort,
    /// `gather_footprint`'s source mask loses the first source of every word: the row
    /// pass would skip those sources.
    SourceBitLost,
    /// `direct_light` 1e-3 too high.
    DirectHigh,
    /// `composite` one ulp off in one channel.
    CompositeUlp,
    /// `trace_photons`' fused pass (`fused_deposit`) loses one fixed-point unit of red in
    /// every atlas texel it touches.
    FusedDepositOffByOne,
    /// `trace_photons`' fused pass forgets the lowest reached triangle of every word of
    /// its reach mask (CausticMap would give that receiver no tile).
    FusedReachLost,
    /// `trace_photons`' fused pass into the screen loses one fixed-point unit of red in
    /// every pixel it touches.
    FusedScreenOffByOne,
    /// `gather_caustic_map` 1e-4 too high.
    MapGatherHigh,
    /// `caustic_map_lookup` 1e-3 too high.
    MapLookupHigh,
    /// `trace_photons` runs a compiled variant without dispersion and absorption, whatever
    /// the frame plan asked for (a backend that ignores the variant switches).
    VariantWithoutFeatures,
    /// `trace_photons`' adaptive variant writes each cluster's photons rotated by one slot.
    AdaptiveSlotsRotated,
    /// `refine_clusters` appends every seventh child one texel off.
    ClusterChildOff,
    /// `refine_clusters` loses one converged cluster per step.
    ConvergedLost,
    /// `refine_clusters` lists converged clusters without their footprints (the spread
    /// bits of the error metric's tolerance).
    FootprintSpreadLost,
    /// `refine_clusters` (screen target) drops the last photon it lists.
    OutputListShort,
    /// `temporal_blend`'s output 1% too high.
    TemporalHigh,
    /// `atrous_filter`'s output 1% too high.
    AtrousHigh,
    /// `rsm_importance` level 0's texel fluxes 1e-4 too high.
    RsmFluxHigh,
    /// `sample_rsm`'s photon fluxes 1e-4 too high.
    SampleFluxHigh,
    /// `trace_indirect`'s stored photon powers 2% too high.
    IndirectPowerHigh,
    /// `splat_photons`' red flux 0.1% low in every splatted texel (an off-by-one quantum
    /// is below the check's rounding allowance: each splat's `E x area` is a float that
    /// backends round a few ulps apart before it becomes quanta).
    SplatLow,
    /// `shading_normal_correction` 1e-4 too high.
    CorrectionHigh,
}

/// The CPU backend with a [`Mutation`].
struct Mutant {
    inner: CpuBackend,
    mutation: Mutation,
}

/// `x` moved by -2..=2 ulps, the amount a pure function of `x` (so equal inputs, such as a
/// vertex shared by two triangles, move alike and meshes stay watertight).
fn nudge(x: f32) -> f32 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let k = (pcg_hash(x.to_bits()) % 5) as i32 - 2;
    f32::from_bits((x.to_bits() as i32).wrapping_add(k) as u32)
}

fn nudge_all<const N: usize>(v: &mut [f32; N]) {
    for x in v {
        *x = nudge(*x);
    }
}

fn nudge_camera(c: &mut GpuCamera) {
    nudge_all(&mut c.position);
    nudge_all(&mut c.forward);
    nudge_all(&mut c.right);
    nudge_all(&mut c.up);
    c.tan_half_fov_x = nudge(c.tan_half_fov_x);
    c.tan_half_fov_y = nudge(c.tan_half_fov_y);
}

impl Mutant {
    fn candidate(mutation: Mutation) -> Candidate {
        let inner = CpuBackend::new().unwrap();
        Candidate {
            name: format!("mutant[{mutation:?}]"),
            device: inner.capabilities().device,
            backend: Box::new(Mutant { inner, mutation }),
        }
    }

    /// Rounding noise on a step's inputs.
    fn perturb(step: &mut Step) {
        match step {
            Step::Upload { data, label, .. } if *label == "vertices" => {
                let mut v: Vec<GpuVertex> = bytemuck::pod_collect_to_vec(data);
                for x in &mut v {
                    nudge_all(&mut x.position);
                    nudge_all(&mut x.normal);
                }
                *data = bytemuck::cast_slice(&v).to_vec();
            }
            Step::Kernel(k) => k.modify(|k| match k {
                Kernel::PrimaryGbuffer(PrimaryGbuffer { camera, .. }) => nudge_camera(camera),
                Kernel::DirectLight(DirectLight { params, .. }) => nudge_camera(&mut params.camera),
                Kernel::CausticMapLookup(CausticMapLookup { params, .. }) => {
                    nudge_camera(&mut params.camera)
                }
                Kernel::TracePhotons(TracePhotons { params, .. }) => {
                    nudge_all(&mut params.origin);
                    nudge_all(&mut params.axis);
                    nudge_all(&mut params.rect_u);
                    nudge_all(&mut params.rect_v);
                    for c in 0..3 {
                        params.photon_flux[c] = nudge(params.photon_flux[c]);
                    }
                }
                Kernel::DepositScreen(DepositScreen { params, .. })
                | Kernel::ResolveCaustics(ResolveCaustics { params, .. }) => {
                    nudge_camera(&mut params.camera)
                }
                Kernel::TileHitDistance(TileHitDistance { params, .. })
                | Kernel::BilateralGather(BilateralGather { params, .. }) => {
                    nudge_camera(&mut params.camera);
                    params.roughness = nudge(params.roughness);
                    params.sigma_depth = nudge(params.sigma_depth);
                    params.normal_power = nudge(params.normal_power);
                }
                Kernel::PhotonCountTable(PhotonCountTable { params, .. })
                | Kernel::GatherFootprint(GatherFootprint { params, .. })
                | Kernel::DensityGather(DensityGather { params, .. }) => {
                    nudge_camera(&mut params.camera);
                    params.flux_quantum = nudge(params.flux_quantum);
                    params.sigma_depth = nudge(params.sigma_depth);
                    params.normal_power = nudge(params.normal_power);
                }
                _ => {}
            }),
            _ => {}
        }
    }

    /// One fixed-point unit of red less in every texel of photon map `m` that has red.
    fn lose_a_red_unit(&mut self, m: &PhotonMapPlanes) -> Result<(), BackendError> {
        let (k, _) = deposit_word(0, 0);
        self.modify::<u32>(m.planes[k].id, |m| {
            for t in m.chunks_mut(DEPOSIT_PLANE_WORDS[k]).filter(|t| t[0] > 0) {
                t[0] -= 1;
            }
        })
    }

    /// Reads buffer `id` as `T`s, lets `f` change them, writes them back.
    fn modify<T: bytemuck::Pod>(
        &mut self,
        id: ResourceId,
        f: impl FnOnce(&mut Vec<T>),
    ) -> Result<(), BackendError> {
        let mut v: Vec<T> = bytemuck::pod_collect_to_vec(&self.inner.read(id)?);
        f(&mut v);
        let rec = Recording {
            steps: vec![Step::Upload {
                id,
                data: bytemuck::cast_slice(&v).to_vec(),
                label: "mutated",
            }],
        };
        self.inner.execute(&rec).map(|_| ())
    }

    /// A fault in a kernel's output.
    fn fault(&mut self, k: &Kernel) -> Result<(), BackendError> {
        let scale = |v: &mut Vec<[f32; 4]>, s: f32| {
            for p in v {
                for c in &mut p[..3] {
                    *c *= s;
                }
            }
        };
        match (self.mutation, k) {
            (
                Mutation::InstanceTransformLost,
                Kernel::PrepareScene(caustica_core::kernels::PrepareScene { scene }),
            ) => {
                use caustica_core::device::acceleration::{tlas_capacity, SLOT_VEC4S};
                let first = tlas_capacity(scene.levels as usize) as usize * SLOT_VEC4S;
                let levels = scene.levels as usize;
                self.modify::<[u32; 4]>(scene.bvh_nodes.id, |v| {
                    for l in 0..levels {
                        let r = first + 10 * l;
                        for (row, axis) in v[r..r + 3].iter_mut().enumerate() {
                            let mut id = [0.0f32; 4];
                            id[row] = 1.0;
                            *axis = id.map(f32::to_bits);
                        }
                    }
                })
            }
            (
                Mutation::GbufferDepthIsDistance,
                Kernel::PrimaryGbuffer(PrimaryGbuffer { gbuffer, .. }),
            ) => {
                // the texels assembled from the planes, changed, split again
                let mut g = read_gbuffer(&mut self.inner, gbuffer)?;
                for t in g.iter_mut().filter(|t| t.material != NO_MATERIAL) {
                    t.depth = t.view_distance;
                }
                for (b, p) in gbuffer.planes.iter().zip(gbuffer_to_planes(&g)) {
                    self.modify::<GBufferPlaneTexel>(b.id, |v| *v = p)?;
                }
                Ok(())
            }
            (
                Mutation::GbufferGeometricIsShading,
                Kernel::PrimaryGbuffer(PrimaryGbuffer { gbuffer, .. }),
            ) => {
                let mut g = read_gbuffer(&mut self.inner, gbuffer)?;
                for t in g.iter_mut().filter(|t| t.material != NO_MATERIAL) {
                    t.geometric_normal = pack_unit_vector(glam::Vec3::from(t.normal));
                }
                for (b, p) in gbuffer.planes.iter().zip(gbuffer_to_planes(&g)) {
                    self.modify::<GBufferPlaneTexel>(b.id, |v| *v = p)?;
                }
                Ok(())
            }
            (
                Mutation::DropPhotons,
                Kernel::TracePhotons(TracePhotons {
                    params,
                    photons,
                    photon_count,
                    counters,
                    ..
                }),
            ) => {
                let n =
                    bytemuck::pod_collect_to_vec::<u8, u32>(&self.inner.read(photon_count.id)?)[0];
                let all: Vec<Photon> = bytemuck::pod_collect_to_vec(&self.inner.read(photons.id)?);
                let (mut kept, mut dropped) = (Vec::new(), Vec::new());
                for (i, p) in all[..n as usize].iter().enumerate() {
                    if i % 30 == 29 {
                        dropped.push(*p)
                    } else {
                        kept.push(*p)
                    }
                }
                let q = params.flux_quantum;
                let kept_n = kept.len() as u32;
                self.modify::<Photon>(photons.id, |v| v[..kept.len()].copy_from_slice(&kept))?;
                self.modify::<u32>(photon_count.id, |v| v[0] = kept_n)?;
                self.modify::<u32>(counters.id, |c| {
                    c[counter::STORED] -= dropped.len() as u32;
                    c[counter::ESCAPED] += dropped.len() as u32;
                    for ch in 0..3 {
                        let w = counter::STORED_FLUX + 2 * ch;
                        let units: u64 = dropped
                            .iter()
                            .map(|p| quantize(p.flux[ch], q).units as u64)
                            .sum();
                        let s = join_u64([c[w], c[w + 1]]) - units;
                        c[w] = s as u32;
                        c[w + 1] = (s >> 32) as u32;
                    }
                })
            }
            (Mutation::PhotonFluxLow, Kernel::TracePhotons(TracePhotons { photons, .. })) => {
                self.modify::<Photon>(photons.id, |v| {
                    for p in v {
                        for c in &mut p.flux {
                            *c *= 0.98;
                        }
                    }
                })
            }
            (
                Mutation::DepositOffByOne,
                Kernel::DepositScreen(DepositScreen { photon_map, .. }),
            ) => {
                // word 0 (flux r, lo) of every texel: plane 0, index 4 * pixel
                let (k, _) = deposit_word(0, 0);
                self.modify::<u32>(photon_map.planes[k].id, |m| {
                    for t in m.chunks_mut(DEPOSIT_PLANE_WORDS[k]).filter(|t| t[0] > 0) {
                        t[0] -= 1;
                    }
                })
            }
            (Mutation::ResolveHigh, Kernel::ResolveCaustics(ResolveCaustics { out, .. })) => {
                self.modify(out.id, |v| scale(v, 1.0 + 1e-4))
            }
            (Mutation::TilesHigh, Kernel::TileHitDistance(TileHitDistance { tiles, .. })) => {
                self.modify::<f32>(tiles.id, |v| {
                    for t in v {
                        *t *= 1.0 + 1e-4;
                    }
                })
            }
            (Mutation::GatherHigh, Kernel::BilateralGather(BilateralGather { out, .. })) => {
                self.modify(out.id, |v| scale(v, 1.0 + 1e-4))
            }
            (
                Mutation::CountTableOffByOne,
                Kernel::PhotonCountTable(PhotonCountTable { params, table, .. }),
            ) if params.axis == 1 => self.modify::<u32>(table.id, |v| {
                for t in v.iter_mut().filter(|t| **t > 0) {
                    *t += 1;
                }
            }),
            (Mutation::FootprintHigh, Kernel::GatherFootprint(GatherFootprint { out, .. })) => {
                self.modify(out.id, |v| scale(v, 1.0 + 1e-4))
            }
            (
                Mutation::ReachShort,
                Kernel::GatherFootprint(GatherFootprint {
                    params,
                    source_index,
                    ..
                }),
            ) => {
                let grid = reach_grid_len(params.camera.width, params.camera.height) as usize;
                self.modify::<u32>(source_index.id, |v| {
                    for e in v[..grid].iter_mut().filter(|e| **e > 0) {
                        *e -= 1;
                    }
                })
            }
            (
                Mutation::SourceBitLost,
                Kernel::GatherFootprint(GatherFootprint {
                    params,
                    source_index,
                    ..
                }),
            ) => {
                let grid = reach_grid_len(params.camera.width, params.camera.height) as usize;
                self.modify::<u32>(source_index.id, |v| {
                    for e in &mut v[grid..] {
                        *e &= e.wrapping_sub(1);
                    }
                })
            }
            (Mutation::DensityGatherHigh, Kernel::DensityGather(DensityGather { out, .. })) => {
                self.modify(out.id, |v| scale(v, 1.0 + 1e-4))
            }
            (
                Mutation::DensityGatherRadiusUlp,
                Kernel::DensityGather(DensityGather { out, .. }),
            ) => self.modify::<[f32; 4]>(out.id, |v| {
                for p in v.iter_mut().filter(|p| p[3] > 0.0) {
                    p[3] = f32::from_bits(p[3].to_bits() + 1);
                }
            }),
            (
                Mutation::FusedDepositOffByOne,
                Kernel::TracePhotons(TracePhotons {
                    deposit: Some(FusedDeposit::Atlas(AtlasDeposit { sums, .. })),
                    ..
                }),
            ) => self.lose_a_red_unit(sums),
            (
                Mutation::FusedReachLost,
                Kernel::TracePhotons(TracePhotons {
                    deposit: Some(FusedDeposit::Atlas(AtlasDeposit { triangle_reach, .. })),
                    ..
                }),
            ) => self.modify::<u32>(triangle_reach.id, |v| {
                for w in v {
                    *w &= w.wrapping_sub(1);
                }
            }),
            (
                Mutation::FusedScreenOffByOne,
                Kernel::TracePhotons(TracePhotons {
                    deposit: Some(FusedDeposit::Screen(ScreenDeposit { photon_map, .. })),
                    ..
                }),
            ) => self.lose_a_red_unit(photon_map),
            (Mutation::MapGatherHigh, Kernel::GatherCausticMap(GatherCausticMap { out, .. })) => {
                self.modify(out.id, |v| scale(v, 1.0 + 1e-4))
            }
            (Mutation::MapLookupHigh, Kernel::CausticMapLookup(CausticMapLookup { out, .. })) => {
                self.modify(out.id, |v| scale(v, 1.0 + 1e-3))
            }
            (
                Mutation::AdaptiveSlotsRotated,
                Kernel::TracePhotons(TracePhotons {
                    variant,
                    params,
                    photons,
                    ..
                }),
            ) if variant.adaptive && !variant.fused_deposit => {
                // (the fused finest level writes no slots)
                let n = params.count as usize;
                self.modify::<Photon>(photons.id, |v| {
                    for c in v[..n].chunks_mut(4) {
                        c.rotate_left(1);
                    }
                })
            }
            (
                Mutation::ClusterChildOff,
                Kernel::RefineClusters(RefineClusters {
                    children,
                    cluster_counts,
                    ..
                }),
            ) => {
                let n =
                    bytemuck::pod_collect_to_vec::<u8, u32>(&self.inner.read(cluster_counts.id)?)
                        [cluster_count::CHILDREN] as usize;
                self.modify::<u32>(children.id, |v| {
                    let n = n.min(v.len());
                    for c in v[..n].iter_mut().skip(3).step_by(7) {
                        *c = c.wrapping_add(1);
                    }
                })
            }
            (
                Mutation::ConvergedLost,
                Kernel::RefineClusters(RefineClusters { cluster_counts, .. }),
            ) => self.modify::<u32>(cluster_counts.id, |v| {
                if v[cluster_count::CONVERGED] > 0 {
                    v[cluster_count::CONVERGED] -= 1;
                }
            }),
            (
                Mutation::FootprintSpreadLost,
                Kernel::RefineClusters(RefineClusters {
                    converged,
                    cluster_counts,
                    ..
                }),
            ) => {
                let n =
                    bytemuck::pod_collect_to_vec::<u8, u32>(&self.inner.read(cluster_counts.id)?)
                        [cluster_count::CONVERGED] as usize;
                self.modify::<u32>(converged.id, |v| {
                    let n = n.min(v.len());
                    for e in &mut v[..n] {
                        *e = entry_cluster(*e);
                    }
                })
            }
            (
                Mutation::OutputListShort,
                Kernel::RefineClusters(RefineClusters { output_count, .. }),
            ) => self.modify::<u32>(output_count.id, |v| {
                if v[0] > 0 {
                    v[0] -= 1;
                }
            }),
            (
                Mutation::RsmFluxHigh,
                Kernel::RsmImportance(RsmImportance { params, texels, .. }),
            ) if params.level == 0 => self.modify::<RsmTexel>(texels.id, |v| {
                for t in v {
                    for c in &mut t.flux {
                        *c *= 1.0 + 1e-4;
                    }
                }
            }),
            (Mutation::SampleFluxHigh, Kernel::SampleRsm(SampleRsm { photons, .. })) => {
                self.modify::<RsmPhoton>(photons.id, |v| {
                    for p in v {
                        for c in &mut p.flux {
                            *c *= 1.0 + 1e-4;
                        }
                    }
                })
            }
            (Mutation::IndirectPowerHigh, Kernel::TraceIndirect(TraceIndirect { photons, .. })) => {
                self.modify::<GiPhoton>(photons.id, |v| {
                    for p in v {
                        p.power = pack_rgb9e5(unpack_rgb9e5(p.power) * 1.02);
                    }
                })
            }
            (
                Mutation::CorrectionHigh,
                Kernel::ShadingNormalCorrection(ShadingNormalCorrection { out, .. }),
            ) => self.modify(out.id, |v| scale(v, 1.0 + 1e-4)),
            (Mutation::SplatLow, Kernel::SplatPhotons(SplatPhotons { photon_map, .. })) => {
                // word 0 (red flux, lo) of every texel, on its plane
                let (k, _) = deposit_word(0, 0);
                self.modify::<u32>(photon_map.planes[k].id, |m| {
                    for t in m.chunks_mut(DEPOSIT_PLANE_WORDS[k]).filter(|t| t[0] > 1000) {
                        t[0] -= t[0] / 1000;
                    }
                })
            }
            (Mutation::AtrousHigh, Kernel::AtrousFilter(AtrousFilter { out, .. })) => {
                self.modify(out.id, |v| scale(v, 1.0 + 1e-2))
            }
            (Mutation::TemporalHigh, Kernel::TemporalBlend(TemporalBlend { out, .. })) => {
                self.modify(out.id, |v| scale(v, 1.0 + 1e-2))
            }
            (Mutation::DirectHigh, Kernel::DirectLight(DirectLight { out, .. })) => {
                self.modify(out.id, |v| scale(v, 1.0 + 1e-3))
            }
            (Mutation::CompositeUlp, Kernel::Composite(Composite { out, .. })) => self
                .modify::<[f32; 4]>(out.id, |v| {
                    if let Some(p) = v.iter_mut().find(|p| p[0] > 0.0) {
                        p[0] = f32::from_bits(p[0].to_bits() + 1);
                    }
                }),
            _ => Ok(()),
        }
    }
}

impl Backend for Mutant {
    fn name(&self) -> &'static str {
        "mutant"
    }
    fn capabilities(&self) -> Capabilities {
        self.inner.capabilities()
    }
    fn execute(&mut self, recording: &Recording) -> Result<Vec<PassTime>, BackendError> {
        let mut times = Vec::new();
        for step in &recording.steps {
            let mut step = step.clone();
            if self.mutation == Mutation::UlpNoise {
                Self::perturb(&mut step);
            }
            if self.mutation == Mutation::WritesDropped && matches!(step, Step::Write { .. }) {
                continue;
            }
            if let (Mutation::VariantWithoutFeatures, Step::Kernel(k)) = (self.mutation, &mut step)
            {
                k.modify(|k| {
                    if let Kernel::TracePhotons(TracePhotons { variant, .. }) = k {
                        variant.dispersion = false;
                        variant.absorption = false;
                    }
                });
            }
            let one = Recording {
                steps: vec![step.clone()],
            };
            times.extend(self.inner.execute(&one)?);
            if let Step::Kernel(k) = &step {
                self.fault(k.kernel())?;
            }
        }
        Ok(times)
    }
    fn read(&mut self, id: ResourceId) -> Result<Vec<u8>, BackendError> {
        self.inner.read(id)
    }
    fn variants(&self) -> Vec<String> {
        self.inner.variants()
    }
}

/// Every check of the suite, by name.
fn kernel_checks() -> Vec<(&'static str, Box<KernelCheck>)> {
    vec![
        (
            "primary_gbuffer",
            Box::new(|fx, _, r, c| check_gbuffer(fx, r, c)),
        ),
        (
            "trace_photons",
            Box::new(|fx, _, r, c| check_trace(fx, r, c)),
        ),
        ("deposit_screen + resolve_caustics", Box::new(check_deposit)),
        (
            "tile_hit_distance + bilateral_gather",
            Box::new(check_gather),
        ),
        (
            "photon_count_table + gather_footprint + density_gather",
            Box::new(check_density_gather),
        ),
        ("direct_light", Box::new(check_direct)),
        ("photon gi kernels", Box::new(check_photon_gi)),
        ("composite", Box::new(|_, i, r, c| check_composite(i, r, c))),
        (
            "gather_caustic_map + caustic_map_lookup",
            Box::new(check_caustic_map),
        ),
        ("trace_photons (atlas deposit)", Box::new(check_fused_trace)),
        (
            "trace_photons (screen deposit)",
            Box::new(check_fused_screen_trace),
        ),
        (
            "trace_photons (adaptive) + refine_clusters",
            Box::new(check_adaptive_caustics),
        ),
        (
            "trace_photons (adaptive, world) + refine_clusters (screen)",
            Box::new(check_screen_target),
        ),
        ("temporal_blend", Box::new(check_temporal_blend)),
        ("atrous_filter", Box::new(check_atrous_filter)),
    ]
}

/// Rounding differences (the `UlpNoise` mutant) pass every per-kernel check on every
/// kernel case, and whole frames on every built-in scene and on eight generated scenes.
#[test]
fn rounding_differences_pass_every_comparison() {
    let mut report = Report::new("UlpNoise mutant, every check");
    let mut reference = harness::reference();
    let mut cand = Mutant::candidate(Mutation::UlpNoise);
    let cases = kernel_cases();
    for (_, check) in kernel_checks() {
        check_kernel_cases(
            &mut report,
            &mut reference,
            &mut cand,
            &cases,
            check.as_ref(),
        );
    }
    let mut frames: Vec<(String, _, _)> = BUILTIN_SCENES
        .iter()
        .map(|n| (n.to_string(), builtin_small(n), small_settings(64)))
        .collect();
    let mut runner = TestRunner::deterministic();
    let strategy = (strategies::scene(), strategies::sspm_settings());
    for i in 0..8 {
        let (scene, settings) = strategy.new_tree(&mut runner).unwrap().current();
        frames.push((format!("generated frame #{i}"), scene, settings));
    }
    for (name, scene, settings) in &frames {
        match check_frame(&mut reference, cand.backend.as_mut(), scene, settings) {
            Ok(v) => report.add(&cand.name, name, v),
            Err(e) => report.error(&cand.name, name, e),
        }
    }
    report.finish();
}

/// The instance faults fail the checks that cover instances: a traversal that ignores the
/// instance transform fails the frame comparison on `sphere` with its ball an instance
/// (turned and moved: object and world space differ), and a backend that drops buffer
/// writes fails the moved-equals-fresh comparison of instance_updates.rs.
#[test]
fn instance_faults_fail_the_instance_checks() {
    use caustica_core::scene::Transform;
    use caustica_core::techniques::create;
    use glam::{Quat, Vec3};
    let mut scene = builtin_small("sphere");
    let ball = scene.objects.iter().position(|o| o.name == "ball").unwrap();
    if let caustica_core::scene::Shape::Sphere { center, .. } = &mut scene.objects[ball].shape {
        let c = std::mem::replace(center, Vec3::ZERO);
        scene.objects[ball].transform = Some(Transform {
            translation: c,
            rotation: Quat::from_rotation_z(0.4),
            scale: Vec3::splat(0.9),
        });
    }
    let mut reference = harness::reference();
    let mut cand = Mutant::candidate(Mutation::InstanceTransformLost);
    let v = check_frame(
        &mut reference,
        cand.backend.as_mut(),
        &scene,
        &small_settings(64),
    )
    .expect("frames render");
    assert!(
        !v.failures.is_empty(),
        "a traversal ignoring instance transforms passed the frame check"
    );

    let mut cand = Mutant::candidate(Mutation::WritesDropped);
    let b = cand.backend.as_mut();
    let mut moved = scene.clone();
    let to = Transform {
        translation: Vec3::new(0.3, 0.6, 0.1),
        ..scene.objects[ball].transform.unwrap()
    };
    moved.objects[ball].transform = Some(to);
    let settings = serde_json::json!({ "photons_w": 64, "photons_h": 64 });
    let frame = |t: &mut Box<dyn caustica_core::Technique>, b: &mut dyn Backend| {
        t.frame(b, &mut |_| {}).expect("frame");
        t.read_output(b, Output::Composite).expect("read").pixels
    };
    let mut fresh = create("sspm", b, &moved, &settings).expect("create");
    let want = frame(&mut fresh, b);
    fresh.free(b).expect("free");
    let mut t = create("sspm", b, &scene, &settings).expect("create");
    t.set_object_transforms(b, &[(ball, to)]).expect("move");
    let got = frame(&mut t, b);
    t.free(b).expect("free");
    assert!(
        got != want,
        "a backend dropping buffer writes passed the moved-equals-fresh comparison"
    );
}

/// Each fault makes the check that covers its kernel fail on every scene where that kernel
/// has work (the glass ball, the Cornell box, the absorbing jelly).
#[test]
fn each_fault_fails_the_check_of_its_kernel() {
    let scenes = ["sphere", "cornell", "jelly"];
    let cases: Vec<_> = kernel_cases()
        .into_iter()
        .filter(|(n, _, _)| scenes.contains(&n.as_str()))
        .collect();
    let checks = kernel_checks();
    let check = |name: &str| checks.iter().find(|(n, _)| *n == name).unwrap().1.as_ref();
    let mut reference = harness::reference();
    let mut missed = Vec::new();
    for (mutation, kernel) in [
        (Mutation::GbufferDepthIsDistance, "primary_gbuffer"),
        (Mutation::GbufferGeometricIsShading, "primary_gbuffer"),
        (Mutation::DropPhotons, "trace_photons"),
        (Mutation::PhotonFluxLow, "trace_photons"),
        (
            Mutation::DepositOffByOne,
            "deposit_screen + resolve_caustics",
        ),
        (Mutation::ResolveHigh, "deposit_screen + resolve_caustics"),
        (Mutation::TilesHigh, "tile_hit_distance + bilateral_gather"),
        (Mutation::GatherHigh, "tile_hit_distance + bilateral_gather"),
        (
            Mutation::CountTableOffByOne,
            "photon_count_table + gather_footprint + density_gather",
        ),
        (
            Mutation::FootprintHigh,
            "photon_count_table + gather_footprint + density_gather",
        ),
        (
            Mutation::DensityGatherHigh,
            "photon_count_table + gather_footprint + density_gather",
        ),
        (
            Mutation::DensityGatherRadiusUlp,
            "photon_count_table + gather_footprint + density_gather",
        ),
        (
            Mutation::ReachShort,
            "photon_count_table + gather_footprint + density_gather",
        ),
        (
            Mutation::SourceBitLost,
            "photon_count_table + gather_footprint + density_gather",
        ),
        (Mutation::DirectHigh, "direct_light"),
        (Mutation::CompositeUlp, "composite"),
        (
            Mutation::FusedDepositOffByOne,
            "trace_photons (atlas deposit)",
        ),
        (Mutation::FusedReachLost, "trace_photons (atlas deposit)"),
        (
            Mutation::FusedScreenOffByOne,
            "trace_photons (screen deposit)",
        ),
        (
            Mutation::MapGatherHigh,
            "gather_caustic_map + caustic_map_lookup",
        ),
        (
            Mutation::MapLookupHigh,
            "gather_caustic_map + caustic_map_lookup",
        ),
        // the density gather run on the atlas (CausticMap's default gather)
        (
            Mutation::CountTableOffByOne,
            "gather_caustic_map + caustic_map_lookup",
        ),
        (
            Mutation::FootprintHigh,
            "gather_caustic_map + caustic_map_lookup",
        ),
        (
            Mutation::DensityGatherHigh,
            "gather_caustic_map + caustic_map_lookup",
        ),
        (
            Mutation::DensityGatherRadiusUlp,
            "gather_caustic_map + caustic_map_lookup",
        ),
        (
            Mutation::AdaptiveSlotsRotated,
            "trace_photons (adaptive) + refine_clusters",
        ),
        (
            Mutation::ClusterChildOff,
            "trace_photons (adaptive) + refine_clusters",
        ),
        (
            Mutation::ConvergedLost,
            "trace_photons (adaptive) + refine_clusters",
        ),
        (
            Mutation::FootprintSpreadLost,
            "trace_photons (adaptive) + refine_clusters",
        ),
        (
            Mutation::OutputListShort,
            "trace_photons (adaptive, world) + refine_clusters (screen)",
        ),
        (Mutation::TemporalHigh, "temporal_blend"),
        (Mutation::AtrousHigh, "atrous_filter"),
        (Mutation::RsmFluxHigh, "photon gi kernels"),
        (Mutation::SampleFluxHigh, "photon gi kernels"),
        (Mutation::IndirectPowerHigh, "photon gi kernels"),
        (Mutation::SplatLow, "photon gi kernels"),
        (Mutation::CorrectionHigh, "photon gi kernels"),
    ] {
        let mut report = Report::new(kernel);
        let mut cand = Mutant::candidate(mutation);
        check_kernel_cases(
            &mut report,
            &mut reference,
            &mut cand,
            &cases,
            check(kernel),
        );
        let passed = report.passed_cases();
        if !passed.is_empty() {
            missed.push(format!("{mutation:?} passed {kernel} on {passed:?}"));
        }
    }
    // A backend that ignores the variant's switches fails trace_photons on the scenes
    // whose features it drops: the absorbing jelly and the dispersive prism.
    let variant_cases: Vec<_> = kernel_cases()
        .into_iter()
        .filter(|(n, _, _)| n == "jelly" || n == "prism")
        .collect();
    assert_eq!(variant_cases.len(), 2, "jelly and prism are kernel cases");
    let mut report = Report::new("trace_photons");
    let mut cand = Mutant::candidate(Mutation::VariantWithoutFeatures);
    check_kernel_cases(
        &mut report,
        &mut reference,
        &mut cand,
        &variant_cases,
        check("trace_photons"),
    );
    let passed = report.passed_cases();
    if !passed.is_empty() {
        missed.push(format!(
            "VariantWithoutFeatures passed trace_photons on {passed:?}"
        ));
    }
    // Lost photons also fail the whole-frame comparison (photons the trace stores and a
    // deposit pass reads: the fault lives in the photon buffer, which the fused deposit
    // does without).
    let mut cand = Mutant::candidate(Mutation::DropPhotons);
    for name in scenes {
        let v = check_frame(
            &mut reference,
            cand.backend.as_mut(),
            &builtin_small(name),
            &caustica_core::SspmSettings {
                fused_deposit: false,
                ..small_settings(64)
            },
        )
        .unwrap();
        if v.passed() {
            missed.push(format!("DropPhotons passed the frame comparison on {name}"));
        }
    }
    assert!(
        missed.is_empty(),
        "faults the suite did not catch:\n{}",
        missed.join("\n")
    );
}

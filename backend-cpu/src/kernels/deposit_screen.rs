//! `deposit_screen` (Kim 2019, section 30.3.1.3): each stored photon is projected to the pixel that contains it; it is added
//! only if the pixel sees a diffuse surface (RECEIVER) at a view depth within
//! `depth_tolerance * depth` of the photon's, and the photon arrives on the side the camera
//! sees. Flux is added in fixed point (units of `flux_quantum`) with 64-bit integer
//! atomics, with the hit distance and a photon count, so the sum is exact and
//! order-independent: no photon is lost to a race (the source admits it loses some).

use super::Counters;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{
    counter, deposit_word, gbuffer_flags, DepositParams, GBufferView, Photon, DEPOSIT_PLANES,
};
use caustica_core::kernels::DepositScreen;
use caustica_core::math::fixed_point::quantize;
use caustica_core::math::packing::unpack_unit_vector;
use glam::Vec3;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Runs `deposit_screen` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &DepositScreen) -> Result<(), BackendError> {
    let DepositScreen {
        params,
        gbuffer,
        photons,
        photon_count,
        counters,
        photon_map,
    } = k;
    let n = cpu.get(photon_count.id)?.as_slice::<u32>(1)?[0].min(photons.len);
    let ph = &cpu.get(photons.id)?.as_slice(photons.len)?[..n as usize];
    let g = cpu.gbuffer(gbuffer)?;
    let atomics = cpu.map_atomics(photon_map)?;
    let c = deposit_screen(params, g, ph, atomics);
    c.add_to(cpu.get_mut(counters.id)?.as_mut_slice(counters.len)?);
    Ok(())
}

/// The photon map's planes as `u64` atomics (see [`deposit_word`]).
pub type MapPlanes<'a> = [&'a [AtomicU64]; DEPOSIT_PLANES];

/// `map[pixel].words[word, word + 1] += v` (a little-endian u64 at an even `word`), on
/// the plane that holds the word ([`deposit_word`]); the planes hold whole pairs.
pub fn add_photon_map_u64(map: &MapPlanes, pixel: u32, word: u32, v: u64) {
    let (k, at) = deposit_word(pixel, word);
    map[k][at / 2].fetch_add(v, Ordering::Relaxed);
}

/// Deposits every photon of `photons` into `map` (five `u64` sums per pixel: flux r, g,
/// b in flux quanta, hit distance in hit-distance quanta, photon count; stored in planes)
/// and returns the counters it adds to (off screen, depth mismatch, deposited, underflow,
/// saturated).
pub fn deposit_screen(
    p: &DepositParams,
    gbuffer: GBufferView,
    photons: &[Photon],
    map: MapPlanes,
) -> Counters {
    photons
        .par_chunks(4096)
        .map(|chunk| {
            let mut c = Counters::default();
            for ph in chunk {
                deposit_photon(p, &gbuffer, ph, &map, &mut c);
            }
            c
        })
        .reduce(Counters::default, Counters::merge)
}

fn deposit_photon(
    p: &DepositParams,
    gbuffer: &GBufferView,
    ph: &Photon,
    map: &MapPlanes,
    c: &mut Counters,
) {
    let pos = Vec3::from(ph.position);
    let Some((px, py, z)) = caustica_core::device::layout::project_to_pixel(&p.camera, pos) else {
        c.bump(counter::OFF_SCREEN);
        return;
    };
    let pix = (py * p.camera.width + px) as usize;
    let g = &gbuffer.load_gbuffer(pix);
    let arrives_in_front = unpack_unit_vector(ph.direction).dot(Vec3::from(g.normal)) < 0.0;
    if g.flags & gbuffer_flags::RECEIVER == 0
        || caustica_core::device::layout::off_surface(
            z,
            pos,
            Vec3::from(g.position),
            Vec3::from(g.normal),
            g.depth,
            p.depth_tolerance,
        )
        || !arrives_in_front
    {
        c.bump(counter::DEPTH_MISMATCH);
        return;
    }
    deposit_photon_texel(
        map,
        pix as u32,
        ph,
        p.flux_quantum,
        p.hit_distance_quantum,
        c,
    );
}

/// Adds photon `ph` to texel `texel` of a photon map (a screen pixel or an atlas texel):
/// its flux per channel in `flux_quantum` units, its hit distance in
/// `hit_distance_quantum` units and a count, with 64-bit integer atomics; counts underflow,
/// saturation and the deposit in `c`.
pub fn deposit_photon_texel(
    map: &MapPlanes,
    texel: u32,
    ph: &Photon,
    flux_quantum: f32,
    hit_distance_quantum: f32,
    c: &mut Counters,
) {
    for (ch, units) in photon_flux_units(ph, flux_quantum, c)
        .into_iter()
        .enumerate()
    {
        if units != 0 {
            add_photon_map_u64(map, texel, 2 * ch as u32, units as u64);
        }
    }
    let hd = quantize(ph.hit_distance, hit_distance_quantum).units as u64;
    add_photon_map_u64(map, texel, 6, hd);
    add_photon_map_u64(map, texel, 8, 1);
    c.bump(counter::DEPOSITED);
}

/// Photon `ph`'s flux per channel in `flux_quantum` units, counting underflow and
/// saturation in `c`: what every deposit adds.
pub fn photon_flux_units(ph: &Photon, flux_quantum: f32, c: &mut Counters) -> [u32; 3] {
    std::array::from_fn(|ch| {
        let q = quantize(ph.flux[ch], flux_quantum);
        if q.underflow {
            c.bump(counter::UNDERFLOW);
        }
        if q.saturated {
            c.bump(counter::SATURATED);
        }
        q.units
    })
}

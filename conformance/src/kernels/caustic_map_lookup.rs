//! CausticMap's kernels (`gather_caustic_map`, `caustic_map_lookup`), checked together on
//! the same inputs ([`check_caustic_map`], here with the last of them): the fixture's scene gets a 64x64 caustic atlas
//! over its diffuse receivers (no atlas, nothing to check, where it has none or their UVs
//! cannot address one); each kernel runs on the CPU's output uploaded to both backends, so
//! only the kernel under test differs. The gather's input is the CPU's atlas deposit of
//! 4096 generated texture-space photons (uv anywhere in `[0, 1]^2`, triangles of
//! receivers and of casters, fluxes over 12 binary orders), whose reach mask must be
//! exactly the photons' triangles.
//! - `gather_caustic_map` and the density gather on the atlas: see
//!   [`super::gather_caustic_map`];
//! - `caustic_map_lookup` on the CPU's gathered map: `direct_light`'s specular tree
//!   (the same walk, its tolerance argued there: `DIRECT_REL` per pixel on
//!   `DIRECT_AGREEMENT` of the pixels, where a ray that grazes an edge may take the other
//!   triangle) ending in a bilinear lookup of four texels (7 roundings) or the footprint's
//!   sum over texels, each weighted by its centroid's shares (the centroid of the same
//!   photons' centroid sums: 3 roundings, each share 5, their product 1, relative errors
//!   of a few 1e-7 against `DIRECT_REL`'s 1e-4); under both reflectance models (exact and
//!   Schlick).

use super::gather_caustic_map::{
    check_atlas_density_gather, compare_gather, cpu_deposit, layout, photons,
};
use crate::harness::fixture::{run_and_free, Fixture, ReferenceInputs};
use crate::harness::tolerance::{DIRECT_AGREEMENT, DIRECT_FLOOR, DIRECT_REL};
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::layout::*;
use caustica_core::frame::receivers::atlas::layout::AtlasLayout;
use caustica_core::kernels::CausticMapLookup;
use caustica_core::math::optics::fresnel_model;
use caustica_core::recording::Recording;

/// Runs `caustic_map_lookup` on `b` over `map` and its centroid sums `centroids`,
/// dielectrics under `fresnel_model`.
pub(crate) fn run_lookup(
    fx: &Fixture,
    b: &mut dyn Backend,
    l: &AtlasLayout,
    (map, centroids): (&[[f32; 4]], &[u32]),
    fresnel_model: u32,
) -> Result<Vec<[f32; 4]>, String> {
    let mut rec = Recording::new();
    let out = rec.create(fx.pixels(), "caustics");
    let triangle_tiles = rec.upload(&l.triangle_tiles, "triangle tiles");
    let tiles = rec.upload(&l.tiles, "tiles");
    let texels = rec.upload(&l.texels, "texels");
    let map = rec.upload(map, "map");
    let centroids = rec.upload(centroids, "centroid sums");
    rec.kernel(CausticMapLookup {
        scene: fx.args,
        params: MapLookupParams {
            camera: fx.camera,
            atlas_width: l.plan.size.0,
            max_specular_depth: fx.settings.frame.max_specular_depth,
            min_weight: 1e-3,
            fresnel_model,
        },
        triangle_tiles,
        tiles,
        texels,
        map,
        out,
        centroids,
    });
    run_and_free(b, "caustic_map_lookup", &rec, |b| read_buf(b, out))
}

/// The three kernels on the fixture's scene (see the module doc).
pub fn check_caustic_map(
    fx: &Fixture,
    _inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("gather_caustic_map + caustic_map_lookup");
    let Some(l) = layout(fx) else {
        return Ok(v);
    };
    let (sa, gathered) = compare_gather(&mut v, &l, r, c)?;
    check_atlas_density_gather(&mut v, &l, &sa, r, c)?;
    // the centroid sums of the same photons (compare_gather's deposit)
    let (_, _, _, centroids) = cpu_deposit(&l, &photons(&l, 4096));
    // both reflectance models of the specular chain (the exact default, Vanderstichelen 2021's Schlick)
    for model in [fresnel_model::EXACT, fresnel_model::SCHLICK] {
        let la = run_lookup(fx, r, &l, (&gathered[0], &centroids), model)?;
        let lb = run_lookup(fx, c, &l, (&gathered[0], &centroids), model)?;
        let agree = la
            .iter()
            .zip(&lb)
            .filter(|(a, b)| {
                (0..3).all(|k| (a[k] - b[k]).abs() <= DIRECT_REL * a[k].abs() + DIRECT_FLOOR)
            })
            .count();
        let frac = agree as f64 / la.len().max(1) as f64;
        v.check(frac >= DIRECT_AGREEMENT, || {
            format!(
                "caustic_map_lookup (fresnel_model {model}): {frac:.4} of pixels agree, need \
                 {DIRECT_AGREEMENT}"
            )
        });
        v.check(lb.iter().all(|p| p.iter().all(|x| x.is_finite())), || {
            format!("lookup (fresnel_model {model}): a non-finite pixel")
        });
    }
    Ok(v)
}

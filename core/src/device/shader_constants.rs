//! The constants that core shares with every shader port, listed once: enum values
//! (material, light and emission kinds, cluster fates, ...), counter and word indices,
//! bit flags, fixed sizes and the few `f32` constants the ports use by name. The shaders'
//! generated layout files ([`super::shader_layouts`]) declare exactly these, with values
//! read from the Rust constants below, so no port keeps a copy of a number by hand.
//!
//! Each [`ConstGroup`] is one Rust module or item and the shader names of its constants:
//! a module's constants take the module's shader prefix (`counter::STORED` is
//! `COUNTER_STORED`), a lone constant keeps its name.

use super::acceleration::{self, instance_flags};
use super::launch::{
    dispatch_word, DEFAULT_WORKGROUP_SIZE, DISPATCH_MAX_GROUPS_X, DISPATCH_RECORD_WORDS,
    DISPATCH_TRACE_WIDTH,
};
use super::layout::{
    cluster_count, counter, emission_kind, gather_surface, gbuffer_flags, light_kind,
    material_kind, photon_plan_word, DepositTexel, DEPOSIT_TEXEL_WORDS, MAX_CASTER_SPHERES,
    MAX_SPECULAR_DEPTH, MAX_SPLIT_BRANCHES, NO_MATERIAL, NO_PLAN_BIT, NO_TILE, VISIBLE_TOLERANCE,
};
use crate::math::gi_photon::gi_store;
use crate::math::optics::ior_model;
use crate::math::path_sort::{path_sort_phase, PATH_SORT_BITS, PATH_SORT_BUCKETS};
use crate::math::photon_clusters::{
    cluster_fate, cluster_metric, cluster_relevance, cluster_target, CLUSTER_ID_MASK,
    CONVERGENCE_CELLS, MAX_ERROR_TEXELS, NO_TRIANGLE, SEED_TILE,
};
use crate::math::rsm::{rsm_sampling, rsm_texel_kind};
use crate::math::spectrum::{self, dispersion_mode};
use crate::math::{density_gather, footprint, geometry, map_gather, optics, sampling};
use std::mem::offset_of;

/// A constant's value and how the shading languages spell its type.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShaderValue {
    /// An unsigned value: WGSL `u32`, GLSL `uint`, OpenCL C a `u`-suffixed literal.
    U32(u32),
    /// A word index, count or array length: WGSL `u32`, GLSL `uint`, OpenCL C a plain
    /// (`int`) literal, so that array bounds and index arithmetic there stay as signed
    /// as with a written-out number.
    Index(u32),
    /// A signed value: WGSL `i32`, GLSL `int`, OpenCL C a plain literal.
    I32(i32),
    /// A single-precision value: WGSL `f32`, GLSL `float`, OpenCL C an `f`-suffixed
    /// literal; written with the shortest decimal that reads back as the same `f32`.
    F32(f32),
}

/// One shared constant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShaderConst {
    /// The name every shader port uses.
    pub name: &'static str,
    /// Its value, from the Rust constant.
    pub value: ShaderValue,
}

/// The constants of one Rust module or item.
#[derive(Clone, Debug, PartialEq)]
pub struct ConstGroup {
    /// The Rust path they come from (written above them in the generated files).
    pub source: &'static str,
    /// The constants, in the module's order.
    pub consts: Vec<ShaderConst>,
}

/// `ShaderConst`s named `$prefix` + the Rust name, of kind `$kind`, from `$module`.
macro_rules! prefixed {
    ($prefix:literal, $kind:ident, $module:ident { $($c:ident),* $(,)? }) => {
        vec![$(ShaderConst {
            name: concat!($prefix, stringify!($c)),
            value: ShaderValue::$kind($module::$c as _),
        }),*]
    };
}

/// A `ShaderConst` named `$name` of kind `$kind` with value `$value`.
macro_rules! named {
    ($name:literal, $kind:ident, $value:expr) => {
        ShaderConst {
            name: $name,
            value: ShaderValue::$kind($value as _),
        }
    };
}

/// A group from `source`.
fn group(source: &'static str, consts: Vec<ShaderConst>) -> ConstGroup {
    ConstGroup { source, consts }
}

/// Every shared constant, grouped by where it is defined, in the order the generated
/// files declare them.
pub fn groups() -> Vec<ConstGroup> {
    let word = |offset: usize| (offset / 4) as u32;
    vec![
        group(
            "core::device::layout::material_kind",
            prefixed!("MATERIAL_", U32, material_kind { DIFFUSE, MIRROR, DIELECTRIC }),
        ),
        group(
            "core::device::layout::light_kind",
            prefixed!("LIGHT_", U32, light_kind { POINT, SPOT, DIRECTIONAL }),
        ),
        group(
            "core::device::layout::emission_kind",
            prefixed!("EMISSION_", U32, emission_kind { CONE, RECTANGLE, VIEW_PLANE }),
        ),
        group(
            "core::device::layout::gbuffer_flags",
            prefixed!("GBUFFER_", U32, gbuffer_flags { RECEIVER }),
        ),
        group(
            "core::device::layout::gather_surface",
            prefixed!("GATHER_SURFACE_", U32, gather_surface { SCREEN, ATLAS }),
        ),
        group(
            "core::device::layout::counter (word offsets into the counter buffer)",
            prefixed!(
                "COUNTER_",
                Index,
                counter {
                    STORED,
                    NO_SPECULAR,
                    ESCAPED,
                    NEGLIGIBLE,
                    BOUNCE_LIMIT,
                    OFF_SCREEN,
                    DEPTH_MISMATCH,
                    DEPOSITED,
                    UNDERFLOW,
                    SATURATED,
                    RAYS,
                    STORED_FLUX,
                    SPLITS,
                    WORDS,
                }
            ),
        ),
        group(
            "core::device::layout::cluster_count (words of refine_clusters' counts)",
            prefixed!(
                "CLUSTER_COUNT_",
                Index,
                cluster_count {
                    CHILDREN,
                    OUTPUT,
                    DISCARDED,
                    OUTPUT_PHOTONS,
                    CONVERGED,
                    OVERFLOW,
                    WORDS,
                }
            ),
        ),
        group(
            "core::device::layout::DepositTexel (its u32 words: flux r, g, b at 0, 2, 4)",
            vec![
                named!("DEPOSIT_TEXEL_WORDS", Index, DEPOSIT_TEXEL_WORDS),
                named!("DEPOSIT_FLUX", Index, word(offset_of!(DepositTexel, flux))),
                named!(
                    "DEPOSIT_HIT_DISTANCE",
                    Index,
                    word(offset_of!(DepositTexel, hit_distance))
                ),
                named!("DEPOSIT_PHOTONS", Index, word(offset_of!(DepositTexel, photons))),
            ],
        ),
        group(
            "core::device::layout",
            vec![
                named!("NO_MATERIAL", U32, NO_MATERIAL),
                named!("NO_TILE", U32, NO_TILE),
                named!("MAX_SPLIT_BRANCHES", Index, MAX_SPLIT_BRANCHES),
                named!("MAX_CASTER_SPHERES", Index, MAX_CASTER_SPHERES),
                named!("MAX_SPECULAR_DEPTH", Index, MAX_SPECULAR_DEPTH),
                named!("VISIBLE_TOLERANCE", F32, VISIBLE_TOLERANCE),
            ],
        ),
        group(
            "core::device::launch::DEFAULT_WORKGROUP_SIZE (every kernel's invocations per workgroup)",
            vec![named!("WORKGROUP_SIZE", Index, DEFAULT_WORKGROUP_SIZE)],
        ),
        group(
            "core::device::launch (dispatch records of indirect launches)",
            vec![
                named!("DISPATCH_RECORD_WORDS", Index, DISPATCH_RECORD_WORDS),
                named!("DISPATCH_MAX_GROUPS_X", U32, DISPATCH_MAX_GROUPS_X),
                named!("DISPATCH_TRACE_WIDTH", U32, DISPATCH_TRACE_WIDTH),
            ],
        ),
        group(
            "core::device::launch::dispatch_word (words of a dispatch record)",
            prefixed!(
                "DISPATCH_",
                Index,
                dispatch_word {
                    GROUPS_X,
                    GROUPS_Y,
                    GROUPS_Z,
                    WIDTH,
                    HEIGHT,
                    DEPTH,
                    THREADS,
                    ITEMS,
                }
            ),
        ),
        group(
            "core::device::layout::photon_plan_word (PhotonGi's photon plan on the device)",
            prefixed!(
                "PLAN_",
                Index,
                photon_plan_word {
                    MASK,
                    ROW,
                    POWER_SCALE,
                    FLUX_QUANTUM,
                    RESOLVE_QUANTUM,
                    COUNTS,
                }
            ),
        ),
        group(
            "core::device::layout::NO_PLAN_BIT",
            vec![named!("NO_PLAN_BIT", U32, NO_PLAN_BIT)],
        ),
        group(
            "core::math::photon_plan",
            vec![named!(
                "RSM_SEEN_MIN_TOP",
                F32,
                crate::math::photon_plan::RSM_SEEN_MIN_TOP
            )],
        ),
        group(
            "core::device::acceleration::instance_flags",
            prefixed!("INSTANCE_", U32, instance_flags { IDENTITY }),
        ),
        group(
            "core::device::acceleration",
            vec![
                named!("SINGLE_LEVEL_MARK", U32, acceleration::SINGLE_LEVEL_MARK),
                named!("SINGLE_LEVEL_SLOT", U32, acceleration::SINGLE_LEVEL_SLOT),
                named!(
                    "CULLING_MIN_COMPONENT",
                    F32,
                    acceleration::CULLING_MIN_COMPONENT
                ),
            ],
        ),
        group(
            "core::math::optics",
            vec![
                named!("FRESNEL_EXACT", U32, optics::fresnel_model::EXACT),
                named!("FRESNEL_SCHLICK", U32, optics::fresnel_model::SCHLICK),
                named!(
                    "REFERENCE_WAVELENGTH_UM",
                    F32,
                    optics::REFERENCE_WAVELENGTH_UM
                ),
                named!("RADIANCE_MAX", F32, optics::RADIANCE_MAX),
                named!("KHR_DISPERSION_B_UM2", F32, optics::KHR_DISPERSION_B_UM2),
                named!("KHR_DISPERSION_D_TERM", F32, optics::KHR_DISPERSION_D_TERM),
            ],
        ),
        group(
            "core::math::optics::ior_model",
            prefixed!("IOR_MODEL_", U32, ior_model { CAUCHY, ABBE }),
        ),
        group(
            "core::math::spectrum",
            [
                vec![
                    named!("SPECTRUM_MIN_UM", F32, spectrum::SPECTRUM_MIN_UM),
                    named!("SPECTRUM_WIDTH_UM", F32, spectrum::SPECTRUM_WIDTH_UM),
                    named!("SPECTRUM_MAX_UM", F32, spectrum::SPECTRUM_MAX_UM),
                    named!("WAVELENGTH_STEP", U32, spectrum::WAVELENGTH_STEP),
                    named!("ONE_THIRD", F32, spectrum::ONE_THIRD),
                ],
                prefixed!("DISPERSION_", U32, dispersion_mode { SPECTRAL, THREE_BANDS }),
            ]
            .concat(),
        ),
        group(
            "core::math::spectrum::CIE_X_LOBES, CIE_Y_LOBES, CIE_Z_LOBES (Wyman 2013's fit: \
             weight, mean in nm, 1/sigma below and from the mean)",
            cie_lobe_constants(),
        ),
        group(
            "core::math::spectrum::XYZ_TO_LINEAR_SRGB (row, column) and SPECTRAL_RGB_SCALE",
            spectral_rgb_constants(),
        ),
        group(
            "core::math::geometry",
            vec![
                named!("OFFSET_REL", F32, geometry::OFFSET_REL),
                named!("OFFSET_MIN_SCALE", F32, geometry::OFFSET_MIN_SCALE),
                named!("SPHERE_TEST_SLACK", F32, geometry::SPHERE_TEST_SLACK),
            ],
        ),
        group(
            "core::math::footprint",
            vec![named!("MIN_COSINE", F32, footprint::MIN_COSINE)],
        ),
        group(
            "core::math::sampling",
            vec![
                named!("PHOTON_TILE", U32, sampling::PHOTON_TILE),
                named!("NARROW_CONE", F32, sampling::NARROW_CONE),
            ],
        ),
        group(
            "core::math::rng::R2_STEP (the R2 sequence's steps, 0.32 fixed point)",
            vec![
                named!("R2_STEP_X", U32, crate::math::rng::R2_STEP[0]),
                named!("R2_STEP_Y", U32, crate::math::rng::R2_STEP[1]),
            ],
        ),
        group(
            "core::math::density_gather",
            vec![
                named!(
                    "MIN_WINDOW_HALF_WIDTH",
                    I32,
                    density_gather::MIN_WINDOW_HALF_WIDTH
                ),
                named!("COUNT_CLAMP_PER_K", U32, density_gather::COUNT_CLAMP_PER_K),
                named!("SCAN_THREADS", U32, density_gather::SCAN_THREADS),
                named!("COLUMN_CHUNKS", U32, density_gather::COLUMN_CHUNKS),
                named!("SCAN_COLUMNS", U32, density_gather::SCAN_COLUMNS),
                named!(
                    "EDGE_TEXEL_NOT_RECEIVER",
                    F32,
                    density_gather::EDGE_TEXEL_NOT_RECEIVER
                ),
                named!("COLUMN_PASS_TILE", U32, density_gather::COLUMN_PASS_TILE),
                named!("REACH_TILE", I32, density_gather::REACH_TILE),
            ],
        ),
        group(
            "core::math::map_gather",
            vec![
                named!("TILE_FULLY_COVERED", U32, map_gather::TILE_FULLY_COVERED),
                named!("MAX_FOOTPRINT_TEXELS", F32, map_gather::MAX_FOOTPRINT_TEXELS),
                named!("CENTROID_WORDS", Index, map_gather::CENTROID_WORDS),
                named!("CENTROID_SUBTEXELS", U32, map_gather::CENTROID_SUBTEXELS),
                named!("CENTROID_MAX_PHOTONS", U32, map_gather::CENTROID_MAX_PHOTONS),
            ],
        ),
        group(
            "core::math::photon_clusters",
            [
                vec![named!("NO_TRIANGLE", U32, NO_TRIANGLE)],
                prefixed!("CLUSTER_METRIC_", U32, cluster_metric { LEVEL, ERROR }),
                prefixed!("CLUSTER_", U32, cluster_fate { DISCARDED, OUTPUT, REFINED }),
                prefixed!("CLUSTER_RELEVANCE_", U32, cluster_relevance { PHOTONS, BOUNDS }),
                prefixed!("CLUSTER_TARGET_", U32, cluster_target { ATLAS, SCREEN }),
                vec![
                    named!("MAX_ERROR_TEXELS", U32, MAX_ERROR_TEXELS),
                    named!("CLUSTER_ID_MASK", U32, CLUSTER_ID_MASK),
                    named!("CONVERGENCE_CELLS", U32, CONVERGENCE_CELLS),
                    named!("SEED_TILE", U32, SEED_TILE),
                ],
            ]
            .concat(),
        ),
        group(
            "core::math::rsm",
            [
                prefixed!("RSM_TEXEL_", U32, rsm_texel_kind { NONE, DIFFUSE, SPECULAR }),
                prefixed!("RSM_SAMPLING_", U32, rsm_sampling { IMPORTANCE, UNIFORM }),
            ]
            .concat(),
        ),
        group(
            "core::math::gi_photon::gi_store",
            prefixed!("GI_STORE_", U32, gi_store { PACKED, FLOAT }),
        ),
        group(
            "core::math::path_sort",
            [
                vec![
                    named!("PATH_SORT_BITS", U32, PATH_SORT_BITS),
                    named!("PATH_SORT_BUCKETS", Index, PATH_SORT_BUCKETS),
                ],
                prefixed!(
                    "PATH_SORT_",
                    U32,
                    path_sort_phase {
                        SCAN,
                        SCATTER
                    }
                ),
            ]
            .concat(),
        ),
    ]
}

/// The lobes of the colour-matching fit, `CIE_<X|Y|Z><k>_<WEIGHT|MEAN_NM|INV_SIGMA_BELOW|
/// INV_SIGMA_ABOVE>` (`spectrum::cie_xyz` sums lobe 0, 1, 2 of each function).
fn cie_lobe_constants() -> Vec<ShaderConst> {
    const NAMES: [[[&str; 4]; 3]; 3] = [
        [
            [
                "CIE_X0_WEIGHT",
                "CIE_X0_MEAN_NM",
                "CIE_X0_INV_SIGMA_BELOW",
                "CIE_X0_INV_SIGMA_ABOVE",
            ],
            [
                "CIE_X1_WEIGHT",
                "CIE_X1_MEAN_NM",
                "CIE_X1_INV_SIGMA_BELOW",
                "CIE_X1_INV_SIGMA_ABOVE",
            ],
            [
                "CIE_X2_WEIGHT",
                "CIE_X2_MEAN_NM",
                "CIE_X2_INV_SIGMA_BELOW",
                "CIE_X2_INV_SIGMA_ABOVE",
            ],
        ],
        [
            [
                "CIE_Y0_WEIGHT",
                "CIE_Y0_MEAN_NM",
                "CIE_Y0_INV_SIGMA_BELOW",
                "CIE_Y0_INV_SIGMA_ABOVE",
            ],
            [
                "CIE_Y1_WEIGHT",
                "CIE_Y1_MEAN_NM",
                "CIE_Y1_INV_SIGMA_BELOW",
                "CIE_Y1_INV_SIGMA_ABOVE",
            ],
            ["", "", "", ""],
        ],
        [
            [
                "CIE_Z0_WEIGHT",
                "CIE_Z0_MEAN_NM",
                "CIE_Z0_INV_SIGMA_BELOW",
                "CIE_Z0_INV_SIGMA_ABOVE",
            ],
            [
                "CIE_Z1_WEIGHT",
                "CIE_Z1_MEAN_NM",
                "CIE_Z1_INV_SIGMA_BELOW",
                "CIE_Z1_INV_SIGMA_ABOVE",
            ],
            ["", "", "", ""],
        ],
    ];
    let lobes: [&[spectrum::CieLobe]; 3] = [
        &spectrum::CIE_X_LOBES,
        &spectrum::CIE_Y_LOBES,
        &spectrum::CIE_Z_LOBES,
    ];
    let mut out = Vec::new();
    for (f, lobes) in lobes.iter().enumerate() {
        for (k, l) in lobes.iter().enumerate() {
            let values = [l.weight, l.mean_nm, l.inv_sigma_below, l.inv_sigma_above];
            for (name, v) in NAMES[f][k].iter().zip(values) {
                out.push(ShaderConst {
                    name,
                    value: ShaderValue::F32(v),
                });
            }
        }
    }
    out
}

/// `XYZ_TO_SRGB_<row><column>` and `SPECTRAL_RGB_SCALE_<R|G|B>`.
fn spectral_rgb_constants() -> Vec<ShaderConst> {
    const M: [[&str; 3]; 3] = [
        ["XYZ_TO_SRGB_00", "XYZ_TO_SRGB_01", "XYZ_TO_SRGB_02"],
        ["XYZ_TO_SRGB_10", "XYZ_TO_SRGB_11", "XYZ_TO_SRGB_12"],
        ["XYZ_TO_SRGB_20", "XYZ_TO_SRGB_21", "XYZ_TO_SRGB_22"],
    ];
    const S: [&str; 3] = [
        "SPECTRAL_RGB_SCALE_R",
        "SPECTRAL_RGB_SCALE_G",
        "SPECTRAL_RGB_SCALE_B",
    ];
    let mut out = Vec::new();
    for (r, row) in spectrum::XYZ_TO_LINEAR_SRGB.iter().enumerate() {
        for (c, v) in row.iter().enumerate() {
            out.push(ShaderConst {
                name: M[r][c],
                value: ShaderValue::F32(*v),
            });
        }
    }
    for (name, v) in S.iter().zip(spectrum::SPECTRAL_RGB_SCALE) {
        out.push(ShaderConst {
            name,
            value: ShaderValue::F32(v),
        });
    }
    out
}

/// Struct fields whose array length the shaders spell with a shared constant rather than
/// a number: (struct, field, constant). The generator checks that the constant's value
/// is the field's outermost length.
pub const ARRAY_LENGTHS: &[(&str, &str, &str)] =
    &[("TraceParams", "caster_spheres", "MAX_CASTER_SPHERES")];

/// The constant called `name`.
pub fn find(name: &str) -> Option<ShaderConst> {
    groups()
        .into_iter()
        .flat_map(|g| g.consts)
        .find(|c| c.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    #[test]
    fn names_are_unique_and_shader_style() {
        let mut seen = BTreeSet::new();
        for c in groups().iter().flat_map(|g| g.consts.iter()) {
            assert!(seen.insert(c.name), "{} listed twice", c.name);
            assert!(
                c.name
                    .chars()
                    .all(|ch| ch.is_ascii_uppercase() || ch.is_ascii_digit() || ch == '_'),
                "{}: not an upper-case name",
                c.name
            );
        }
    }

    #[test]
    fn values_are_the_rust_constants() {
        assert_eq!(
            find("COUNTER_STORED_FLUX").map(|c| c.value),
            Some(ShaderValue::Index(counter::STORED_FLUX as u32))
        );
        assert_eq!(
            find("DEPOSIT_PHOTONS").map(|c| c.value),
            Some(ShaderValue::Index(8))
        );
        assert_eq!(
            find("CLUSTER_TARGET_SCREEN").map(|c| c.value),
            Some(ShaderValue::U32(cluster_target::SCREEN))
        );
        assert_eq!(
            find("REACH_TILE").map(|c| c.value),
            Some(ShaderValue::I32(8))
        );
    }
}

//! A description of the [`layout`](super::layout) structs that shaders mirror, built from
//! `offset_of!` and `size_of` so that it cannot drift from the structs: each struct's
//! name, size and fields (name, byte offset, byte size, element kind and array shape),
//! and [`StructLayout::leaves`], the struct flattened to its 4-byte scalars. The shader
//! crates' layout tests compare their WGSL / SPIR-V layouts with this table instead of
//! listing the fields themselves.
//!
//! Every field of a listed struct must be named in the table: the listing destructures
//! the struct without `..`, so a field added to a struct and not here does not compile.

use super::layout::{
    AtlasParams, AtrousParams, CorrectionParams, DepositParams, DepositTexel, DirectParams,
    GBufferTexel, GatherParams, GiPhoton, GpuCamera, GpuLight, GpuMaterial, GpuTriangle, GpuVertex,
    IndirectPath, IndirectTraceParams, MapLookupParams, PathSortParams, Photon, PlacementParams,
    PlanParams, RefineParams, RsmParams, RsmPhoton, RsmTexel, SeedParams, SplatParams,
    TemporalParams, TraceParams,
};
use std::mem::{offset_of, size_of};
use std::sync::LazyLock;

/// The kind of a 4-byte scalar.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Scalar {
    /// `f32` (WGSL `f32`, GLSL `float`).
    F32,
    /// `u32` (WGSL `u32`, GLSL `uint`).
    U32,
}

/// What one element of a field is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Elem {
    /// A 4-byte scalar.
    Scalar(Scalar),
    /// A nested struct of this table, by name (e.g. `GpuCamera` in the parameter blocks).
    Struct(&'static str),
}

/// One field of a struct.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FieldLayout {
    /// The Rust field name (`_pad` for explicit padding).
    pub name: &'static str,
    /// Byte offset in the struct (`offset_of!`).
    pub offset: usize,
    /// Byte size of the whole field (`size_of` of its type).
    pub size: usize,
    /// The kind of its elements.
    pub elem: Elem,
    /// Array lengths, outermost first; empty for a single element (`[[u32; 2]; 3]` is
    /// `[3, 2]`).
    pub dims: Vec<usize>,
}

impl FieldLayout {
    /// True for explicit padding (`_pad`, `_pad0`, ...).
    pub fn is_pad(&self) -> bool {
        self.name.starts_with("_pad")
    }

    /// Number of elements (the product of [`dims`](Self::dims); 1 for a single element).
    pub fn count(&self) -> usize {
        self.dims.iter().product()
    }
}

/// One `#[repr(C)]` Pod struct.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct StructLayout {
    /// The Rust (and shader) struct name.
    pub name: &'static str,
    /// `size_of` the struct.
    pub size: usize,
    /// Its fields in declaration order.
    pub fields: Vec<FieldLayout>,
}

/// One 4-byte scalar of a flattened struct.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Leaf {
    /// Byte offset from the start of the outermost struct.
    pub offset: usize,
    /// Its kind.
    pub scalar: Scalar,
    /// A readable path to it, e.g. `DirectParams.camera.position[2]`.
    pub path: String,
}

impl StructLayout {
    /// The field called `name`.
    pub fn field(&self, name: &str) -> Option<&FieldLayout> {
        self.fields.iter().find(|f| f.name == name)
    }

    /// The struct flattened to its 4-byte scalars, in field order, nested structs
    /// expanded (through [`find`]); paths start with the struct's name.
    ///
    /// # Panics
    /// If a nested struct is not in the table (the unit tests rule this out).
    pub fn leaves(&self) -> Vec<Leaf> {
        let mut out = Vec::new();
        self.push_leaves(0, self.name, &mut out);
        out
    }

    fn push_leaves(&self, base: usize, path: &str, out: &mut Vec<Leaf>) {
        for f in &self.fields {
            let elem_size = f.size / f.count();
            for i in 0..f.count() {
                // the index tuple of element i, row-major
                let mut idx = String::new();
                let mut rest = i;
                let mut stride = f.count();
                for &d in &f.dims {
                    stride /= d;
                    idx.push_str(&format!("[{}]", rest / stride));
                    rest %= stride;
                }
                let at = base + f.offset + i * elem_size;
                let p = format!("{path}.{}{idx}", f.name);
                match f.elem {
                    Elem::Scalar(scalar) => out.push(Leaf {
                        offset: at,
                        scalar,
                        path: p,
                    }),
                    Elem::Struct(name) => find(name)
                        .unwrap_or_else(|| panic!("{p}: struct {name} is not in the table"))
                        .push_leaves(at, &p, out),
                }
            }
        }
    }
}

/// A field type the table can describe: a scalar, an array of them, or a listed struct.
trait Describe {
    /// The element kind; pushes the array lengths, outermost first.
    fn describe(dims: &mut Vec<usize>) -> Elem;
}

impl Describe for f32 {
    fn describe(_: &mut Vec<usize>) -> Elem {
        Elem::Scalar(Scalar::F32)
    }
}

impl Describe for u32 {
    fn describe(_: &mut Vec<usize>) -> Elem {
        Elem::Scalar(Scalar::U32)
    }
}

impl<T: Describe, const N: usize> Describe for [T; N] {
    fn describe(dims: &mut Vec<usize>) -> Elem {
        dims.push(N);
        T::describe(dims)
    }
}

/// The layout of field `name` at `offset`, whose type `F` is named by the accessor `_get`.
fn field<S, F: Describe>(name: &'static str, offset: usize, _get: fn(&S) -> &F) -> FieldLayout {
    let mut dims = Vec::new();
    let elem = F::describe(&mut dims);
    FieldLayout {
        name,
        offset,
        size: size_of::<F>(),
        elem,
        dims,
    }
}

/// Lists struct `$t` with fields `$f` in the table and makes it describable as a nested
/// field. The destructuring without `..` fails to compile if a field is left out.
macro_rules! table {
    ($($t:ident { $($f:ident),* $(,)? })*) => {
        $(
            impl Describe for $t {
                fn describe(_: &mut Vec<usize>) -> Elem {
                    Elem::Struct(stringify!($t))
                }
            }
        )*
        /// The table, in [`layout`](super::layout) order.
        fn build() -> Vec<StructLayout> {
            vec![$({
                let _every_field_listed = |v: &$t| {
                    let $t { $($f: _),* } = v;
                };
                StructLayout {
                    name: stringify!($t),
                    size: size_of::<$t>(),
                    fields: vec![$(
                        field(stringify!($f), offset_of!($t, $f), |s: &$t| &s.$f)
                    ),*],
                }
            }),*]
        }
    };
}

table! {
    GpuVertex { position, u, normal, v }
    GpuTriangle { indices, material }
    GpuMaterial { kind, ior, dispersion, ior_model, color, absorption }
    GpuLight { kind, cos_inner, cos_outer, one_minus_cos_outer, position, direction, intensity }
    GpuCamera { position, tan_half_fov_x, forward, tan_half_fov_y, right, width, up, height }
    GBufferTexel { position, depth, normal, geometric_normal, albedo, material, uv, view_distance, flags }
    Photon { position, hit_distance, flux, direction }
    DepositTexel { flux, hit_distance, photons }
    TraceParams {
        light, emission, grid_w, grid_h, first, count, seed, max_bounces,
        origin, axis, rect_u, rect_v, photon_flux, flux_quantum, split_budget, fresnel_model,
        caster_sphere_count, jitter_seed, stratum, dispersion_mode, _pad, caster_spheres
    }
    DepositParams { camera, flux_quantum, hit_distance_quantum, depth_tolerance, photon_capacity }
    GatherParams {
        camera, roughness, hit_distance_min, hit_distance_max, max_radius_px,
        sigma_depth, normal_power, axis, tile_size, hit_distance_quantum, knn_photons,
        flux_quantum, table_block, surface, _pad
    }
    DirectParams { camera, light_count, max_specular_depth, min_weight, fresnel_model }
    AtlasParams {
        width, height, flux_quantum, hit_distance_quantum, photon_capacity, gather_width, _pad
    }
    MapLookupParams { camera, atlas_width, max_specular_depth, min_weight, fresnel_model }
    AtrousParams {
        camera, iteration, last, sigma_z, sigma_n, epsilon, clip_sigmas, _pad
    }
    TemporalParams {
        camera, previous, alpha_max, sigma_z, sigma_n, epsilon, history_frames, _pad
    }
    RsmTexel { position, normal, flux, kind }
    RsmPhoton { origin, direction, flux, bounces }
    RsmParams {
        face_camera, light, face, side, level, face_count, first_sample, sample_count, seed,
        sampling, _pad
    }
    GiPhoton { position, power, normal, direction, ray_length, tile }
    IndirectTraceParams {
        camera, first, count, seed, max_bounces, max_segments, tile_size, store,
        fresnel_model, power_scale, flux_quantum, dispersion_mode, segment_first, segment_end,
        chunk_first, chunk_size, queue_keys, key_origin_min, queue_order, key_origin_scale, _pad
    }
    IndirectPath { origin, index, direction, bounces, flux, wavelength }
    PathSortParams { phase, count_word, _pad }
    SplatParams {
        camera, tile_size, power_scale, flux_quantum, max_splat_px, max_ray_length,
        min_length_scale, density_radius_min, density_radius_max, photons_per_pixel,
        normal_compression, max_stretch, tile_constant, min_splat_px, light_direction,
        scene_magnitude, _pad
    }
    PlacementParams {
        axis_x, axis_y, axis_z, translation, normal_x, normal_y, normal_z, object_first,
        world_first, count, _pad
    }
    CorrectionParams { width, height, max_stretch, epsilon }
    PlanParams { side, faces, bit, row_words, table_words, _pad }
    RefineParams {
        atlas_width, flux_quantum, hit_distance_quantum, level, finest, metric,
        error_from_level, grid_w, first, count, children_capacity, relevance,
        rect_count, deposit_target, error_texels, _pad, camera
    }
    SeedParams {
        grid_w, first_x, first_y, window_w, window_h, rect_count, capacity, _pad
    }
}

static TABLE: LazyLock<Vec<StructLayout>> = LazyLock::new(build);

/// Every `#[repr(C)]` Pod struct of [`layout`](super::layout) that a shader mirrors, in
/// declaration order.
pub fn structs() -> &'static [StructLayout] {
    &TABLE
}

/// The struct called `name`, if the table lists it.
pub fn find(name: &str) -> Option<&'static StructLayout> {
    structs().iter().find(|s| s.name == name)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeSet;

    /// Fields are contiguous from 0 to `size_of` (no implicit gap: padding is an explicit
    /// `_pad` field; no overlap); each field's size is its elements' sizes; nested structs
    /// are listed; the leaves are every 4-byte word once.
    #[test]
    fn fields_tile_each_struct() {
        for s in structs() {
            let mut end = 0;
            for f in &s.fields {
                let what = format!("{}.{}", s.name, f.name);
                assert_eq!(f.offset, end, "{what}: gap or overlap before it");
                assert!(f.size > 0 && f.size % 4 == 0, "{what}: size {}", f.size);
                let elem_size = match f.elem {
                    Elem::Scalar(_) => 4,
                    Elem::Struct(n) => find(n).unwrap_or_else(|| panic!("{what}: {n}")).size,
                };
                assert_eq!(f.size, elem_size * f.count(), "{what}: size vs elements");
                end = f.offset + f.size;
            }
            assert_eq!(end, s.size, "{}: fields end before size_of", s.name);
            let offsets: Vec<usize> = s.leaves().iter().map(|l| l.offset).collect();
            let words: Vec<usize> = (0..s.size).step_by(4).collect();
            assert_eq!(offsets, words, "{}: leaves", s.name);
        }
        let names: BTreeSet<&str> = structs().iter().map(|s| s.name).collect();
        assert_eq!(names.len(), structs().len(), "a struct listed twice");
    }

    #[test]
    fn nested_structs_and_arrays_flatten() {
        let d = find("DirectParams").unwrap();
        let leaves = d.leaves();
        assert_eq!(leaves[0].path, "DirectParams.camera.position[0]");
        assert_eq!(leaves[11].path, "DirectParams.camera.width");
        assert_eq!(leaves[11].scalar, Scalar::U32);
        assert_eq!(leaves[16].offset, offset_of!(DirectParams, light_count));
        let t = find("DepositTexel").unwrap();
        assert_eq!(t.field("flux").unwrap().dims, vec![3, 2]);
        assert_eq!(t.leaves()[3].path, "DepositTexel.flux[1][1]");
        assert_eq!(t.leaves()[3].offset, 12);
    }
}

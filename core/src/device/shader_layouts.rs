//! The shader ports' declarations of core's layouts, generated: from the layout table
//! ([`super::layout_table`], built with `offset_of!` and `size_of`) and the shared
//! constants ([`super::shader_constants`]) this module writes the struct declarations
//! and constants of each shading language, one file each ([`FILES`]). The files are
//! checked in; `core/tests/shader_layouts.rs` fails while one differs from what
//! [`generate`] writes and rewrites them when run as [`REGENERATE`] says.
//!
//! How a Rust field becomes a shader member (the same in WGSL and GLSL, whose vectors
//! have the same alignment in storage buffers):
//! - `f32` / `u32`: the scalar;
//! - `[T; 2]`, `[T; 3]`, `[T; 4]` of scalars: a vector (`vec2<f32>` / `vec2`, ...), where
//!   it starts at a multiple of its alignment (8, 16, 16); a 3-vector only where a 4-byte
//!   scalar follows it, which fills its 16-byte slot as in Rust;
//! - `[[T; K]; N]` (K = 2 or 4): an array of N vectors; `[T; N]` otherwise an array;
//! - a nested struct of the table: that struct;
//! - padding `_pad: [u32; N]`: N separate words `_pad0 .. _padN-1` (never a vector,
//!   which would move the struct's alignment).
//!
//! OpenCL C keeps every field as 4-byte scalars or arrays of them (`float position[3]`),
//! which lay out exactly as Rust's. Each struct's WGSL layout is computed here and must
//! equal Rust's offsets and size, or [`generate`] fails naming the field; the shader
//! crates' layout tests then check the compiled result (naga, the OpenCL device's
//! `sizeof`, the SPIR-V decorations).

use super::layout_table::{self, Elem, FieldLayout, Scalar, StructLayout};
use super::shader_constants::{self, ConstGroup, ShaderValue, ARRAY_LENGTHS};

/// A shading language with a generated layout file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Language {
    /// WGSL (caustica-shaders; the wgpu backend and Vulkan's compute kernels).
    Wgsl,
    /// OpenCL C 1.2 (the OpenCL backend).
    OpenCl,
    /// GLSL 4.60 (the Vulkan backend's ray-tracing stages).
    Glsl,
}

/// A generated file: its path from the workspace root and its language.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GeneratedFile {
    /// Path relative to the workspace root.
    pub path: &'static str,
    /// The language it is written in.
    pub language: Language,
}

/// Every generated file.
pub const FILES: [GeneratedFile; 3] = [
    GeneratedFile {
        path: "shaders/wgsl/common/layout.wgsl",
        language: Language::Wgsl,
    },
    GeneratedFile {
        path: "backend-opencl/kernels/common/layout.cl",
        language: Language::OpenCl,
    },
    GeneratedFile {
        path: "backend-vulkan/shaders/common/layout.glsl",
        language: Language::Glsl,
    },
];

/// The command that rewrites every generated file.
pub const REGENERATE: &str = "CAUSTICA_BLESS=1 cargo test -p caustica-core --test shader_layouts";

/// The text of `language`'s layout file: a header saying where it comes from, the
/// shared constants, then every struct of the table in table order (a nested struct is
/// declared before its users). Fails when a struct has a field the rules above cannot
/// express with Rust's layout.
pub fn generate(language: Language) -> Result<String, String> {
    let groups = shader_constants::groups();
    let mut out = header();
    for g in &groups {
        out.push_str(&format!("\n// {}\n", g.source));
        for c in &g.consts {
            out.push_str(&constant(language, c.name, c.value));
            out.push('\n');
        }
    }
    for s in layout_table::structs() {
        out.push('\n');
        let text = match language {
            Language::Wgsl => wgsl_struct(s, &groups)?,
            Language::OpenCl => opencl_struct(s, &groups)?,
            Language::Glsl => glsl_struct(s, &groups)?,
        };
        out.push_str(&text);
    }
    if language == Language::OpenCl {
        out.push('\n');
        out.push_str(&opencl_struct_sizes());
    }
    Ok(out)
}

/// The comment every generated file starts with (`//` comments in all three languages).
fn header() -> String {
    [
        "GENERATED FILE, do not edit: the structs of core/src/device/layout.rs (through",
        "core/src/device/layout_table.rs) and the constants of",
        "core/src/device/shader_constants.rs, written by core/src/device/shader_layouts.rs.",
        "core/tests/shader_layouts.rs fails while this file differs; regenerate with",
        &format!("  {REGENERATE}"),
        "The numbers after the struct members are their byte offsets (Rust's offset_of!).",
    ]
    .iter()
    .map(|l| format!("// {l}\n"))
    .collect()
}

/// One constant declaration.
fn constant(language: Language, name: &str, value: ShaderValue) -> String {
    match (language, value) {
        (Language::Wgsl, ShaderValue::U32(v) | ShaderValue::Index(v)) => {
            format!("const {name}: u32 = {}u;", unsigned(v))
        }
        (Language::Wgsl, ShaderValue::I32(v)) => format!("const {name}: i32 = {v};"),
        (Language::Wgsl, ShaderValue::F32(v)) => format!("const {name}: f32 = {}f;", float(v)),
        (Language::Glsl, ShaderValue::U32(v) | ShaderValue::Index(v)) => {
            format!("const uint {name} = {}u;", unsigned(v))
        }
        (Language::Glsl, ShaderValue::I32(v)) => format!("const int {name} = {v};"),
        (Language::Glsl, ShaderValue::F32(v)) => format!("const float {name} = {};", float(v)),
        (Language::OpenCl, ShaderValue::U32(v)) => format!("#define {name} {}u", unsigned(v)),
        (Language::OpenCl, ShaderValue::Index(v)) => format!("#define {name} {v}"),
        (Language::OpenCl, ShaderValue::I32(v)) if v < 0 => format!("#define {name} ({v})"),
        (Language::OpenCl, ShaderValue::I32(v)) => format!("#define {name} {v}"),
        (Language::OpenCl, ShaderValue::F32(v)) if v.is_sign_negative() => {
            format!("#define {name} ({}f)", float(v))
        }
        (Language::OpenCl, ShaderValue::F32(v)) => format!("#define {name} {}f", float(v)),
    }
}

/// An unsigned literal's digits: hexadecimal from 2^16 up (masks and sentinels), else
/// decimal.
fn unsigned(v: u32) -> String {
    if v >= 1 << 16 {
        format!("{v:#x}")
    } else {
        v.to_string()
    }
}

/// The shortest decimal that reads back as `v` (Rust's `Debug`: `0.0001`, `3.0517578e-5`,
/// `32.0`), valid as a WGSL, GLSL and C floating literal before a suffix.
///
/// # Panics
/// On a non-finite value, which no language spells as a literal.
fn float(v: f32) -> String {
    assert!(v.is_finite(), "{v}: no literal for a non-finite constant");
    format!("{v:?}")
}

// ---------------------------------------------------------------------------------------
// Members: the fields as the vector languages (WGSL, GLSL) see them.

/// The shape of one WGSL / GLSL member.
#[derive(Clone, Debug, PartialEq)]
enum Shape {
    /// A 4-byte scalar.
    Scalar(Scalar),
    /// A vector of 2, 3 or 4 scalars.
    Vector(Scalar, usize),
    /// A struct of the table.
    Struct(&'static str),
    /// An array of `len` elements of the inner shape; `named` is the constant that
    /// spells the length, if any.
    Array(Box<Shape>, usize, Option<&'static str>),
}

/// One member: name, shape, Rust byte offset.
#[derive(Clone, Debug, PartialEq)]
struct Member {
    name: String,
    shape: Shape,
    offset: usize,
}

/// The constant that spells the outer length of `s.field`, checked against `len`.
fn length_name(
    s: &StructLayout,
    f: &FieldLayout,
    len: usize,
    groups: &[ConstGroup],
) -> Result<Option<&'static str>, String> {
    let Some(&(_, _, name)) = ARRAY_LENGTHS
        .iter()
        .find(|(st, field, _)| *st == s.name && *field == f.name)
    else {
        return Ok(None);
    };
    let value = groups
        .iter()
        .flat_map(|g| g.consts.iter())
        .find(|c| c.name == name)
        .map(|c| c.value);
    match value {
        Some(ShaderValue::Index(v) | ShaderValue::U32(v)) if v as usize == len => Ok(Some(name)),
        other => Err(format!(
            "{}.{}: length {len} spelled {name}, which is {other:?}",
            s.name, f.name
        )),
    }
}

/// The members of `s` for WGSL and GLSL ([module docs](self)).
fn vector_members(s: &StructLayout, groups: &[ConstGroup]) -> Result<Vec<Member>, String> {
    let mut out = Vec::new();
    for (i, f) in s.fields.iter().enumerate() {
        let what = format!("{}.{}", s.name, f.name);
        if f.is_pad() {
            push_pad(f, &what, &mut out)?;
            continue;
        }
        let next_is_scalar = s
            .fields
            .get(i + 1)
            .is_some_and(|n| n.dims.is_empty() && matches!(n.elem, Elem::Scalar(_)));
        let shape = match (f.elem, f.dims.as_slice()) {
            (Elem::Scalar(k), []) => Shape::Scalar(k),
            (Elem::Struct(n), []) => Shape::Struct(n),
            (Elem::Scalar(k), [3]) if next_is_scalar => Shape::Vector(k, 3),
            (Elem::Scalar(_), [3]) => {
                return Err(format!(
                    "{what}: a 3-vector not followed by a 4-byte scalar would leave a gap"
                ))
            }
            (Elem::Scalar(k), [n @ (2 | 4)]) => Shape::Vector(k, *n),
            (Elem::Scalar(k), [len, n @ (2 | 4)]) => Shape::Array(
                Box::new(Shape::Vector(k, *n)),
                *len,
                length_name(s, f, *len, groups)?,
            ),
            (Elem::Scalar(k), [len]) => Shape::Array(
                Box::new(Shape::Scalar(k)),
                *len,
                length_name(s, f, *len, groups)?,
            ),
            (Elem::Struct(n), [len]) => Shape::Array(
                Box::new(Shape::Struct(n)),
                *len,
                length_name(s, f, *len, groups)?,
            ),
            (_, dims) => return Err(format!("{what}: no member shape for dimensions {dims:?}")),
        };
        out.push(Member {
            name: f.name.to_owned(),
            shape,
            offset: f.offset,
        });
    }
    check_vector_layout(s, &out, groups)?;
    Ok(out)
}

/// A pad field as separate u32 words (`_pad` for one, `_pad0 ..` for an array).
fn push_pad(f: &FieldLayout, what: &str, out: &mut Vec<Member>) -> Result<(), String> {
    let Elem::Scalar(k) = f.elem else {
        return Err(format!("{what}: padding must be scalars"));
    };
    match f.dims.as_slice() {
        [] => out.push(Member {
            name: f.name.to_owned(),
            shape: Shape::Scalar(k),
            offset: f.offset,
        }),
        [n] => out.extend((0..*n).map(|j| Member {
            name: format!("{}{j}", f.name),
            shape: Shape::Scalar(k),
            offset: f.offset + 4 * j,
        })),
        dims => return Err(format!("{what}: padding of dimensions {dims:?}")),
    }
    Ok(())
}

/// (alignment, size) in bytes of a shape under WGSL's storage rules (GLSL std430's
/// for these shapes).
fn align_size(shape: &Shape, groups: &[ConstGroup]) -> Result<(usize, usize), String> {
    Ok(match shape {
        Shape::Scalar(_) => (4, 4),
        Shape::Vector(_, 2) => (8, 8),
        Shape::Vector(_, 3) => (16, 12),
        Shape::Vector(_, n) => (16, 4 * n),
        Shape::Struct(name) => {
            let s = layout_table::find(name).ok_or_else(|| format!("{name}: not in the table"))?;
            let mut align = 4;
            for m in &vector_members(s, groups)? {
                align = align.max(align_size(&m.shape, groups)?.0);
            }
            (align, s.size)
        }
        Shape::Array(inner, len, _) => {
            let (a, s) = align_size(inner, groups)?;
            (a, len * s.div_ceil(a) * a)
        }
    })
}

/// Places `members` by the alignment rules and compares with Rust's offsets and size.
fn check_vector_layout(
    s: &StructLayout,
    members: &[Member],
    groups: &[ConstGroup],
) -> Result<(), String> {
    let (mut end, mut align) = (0usize, 4usize);
    for m in members {
        let (a, size) = align_size(&m.shape, groups)?;
        let at = end.div_ceil(a) * a;
        if at != m.offset {
            return Err(format!(
                "{}.{}: the shader places it at byte {at}, Rust at {}",
                s.name, m.name, m.offset
            ));
        }
        end = at + size;
        align = align.max(a);
    }
    let size = end.div_ceil(align) * align;
    if size != s.size {
        return Err(format!(
            "{}: {size} bytes in the shader, {} in Rust",
            s.name, s.size
        ));
    }
    Ok(())
}

/// The comment line above a struct.
fn struct_comment(s: &StructLayout) -> String {
    format!("// core::device::layout::{}, {} bytes\n", s.name, s.size)
}

// ---------------------------------------------------------------------------------------
// WGSL

fn wgsl_scalar(k: Scalar) -> &'static str {
    match k {
        Scalar::F32 => "f32",
        Scalar::U32 => "u32",
    }
}

fn wgsl_type(shape: &Shape) -> String {
    match shape {
        Shape::Scalar(k) => wgsl_scalar(*k).to_owned(),
        Shape::Vector(k, n) => format!("vec{n}<{}>", wgsl_scalar(*k)),
        Shape::Struct(n) => (*n).to_owned(),
        Shape::Array(inner, len, named) => match named {
            Some(c) => format!("array<{}, {c}>", wgsl_type(inner)),
            None => format!("array<{}, {len}>", wgsl_type(inner)),
        },
    }
}

fn wgsl_struct(s: &StructLayout, groups: &[ConstGroup]) -> Result<String, String> {
    let mut out = struct_comment(s);
    out.push_str(&format!("struct {} {{\n", s.name));
    for m in vector_members(s, groups)? {
        out.push_str(&format!(
            "    {}: {}, // {}\n",
            m.name,
            wgsl_type(&m.shape),
            m.offset
        ));
    }
    out.push_str("}\n");
    Ok(out)
}

// ---------------------------------------------------------------------------------------
// GLSL

fn glsl_scalar(k: Scalar) -> &'static str {
    match k {
        Scalar::F32 => "float",
        Scalar::U32 => "uint",
    }
}

/// The type and the array suffix of a GLSL member (`vec4`, `[MAX_CASTER_SPHERES]`).
fn glsl_type(shape: &Shape) -> (String, String) {
    match shape {
        Shape::Scalar(k) => (glsl_scalar(*k).to_owned(), String::new()),
        Shape::Vector(Scalar::F32, n) => (format!("vec{n}"), String::new()),
        Shape::Vector(Scalar::U32, n) => (format!("uvec{n}"), String::new()),
        Shape::Struct(n) => ((*n).to_owned(), String::new()),
        Shape::Array(inner, len, named) => {
            let (t, suffix) = glsl_type(inner);
            let n = named.map_or_else(|| len.to_string(), str::to_owned);
            (t, format!("[{n}]{suffix}"))
        }
    }
}

fn glsl_struct(s: &StructLayout, groups: &[ConstGroup]) -> Result<String, String> {
    let mut out = struct_comment(s);
    out.push_str(&format!("struct {} {{\n", s.name));
    for m in vector_members(s, groups)? {
        let (t, suffix) = glsl_type(&m.shape);
        out.push_str(&format!("    {t} {}{suffix}; // {}\n", m.name, m.offset));
    }
    out.push_str("};\n");
    Ok(out)
}

// ---------------------------------------------------------------------------------------
// OpenCL C

fn opencl_struct(s: &StructLayout, groups: &[ConstGroup]) -> Result<String, String> {
    let mut out = struct_comment(s);
    out.push_str("typedef struct {\n");
    for f in &s.fields {
        let what = format!("{}.{}", s.name, f.name);
        if f.is_pad() {
            // separate words, as in WGSL and GLSL
            let mut words = Vec::new();
            push_pad(f, &what, &mut words)?;
            for w in words {
                out.push_str(&format!("    uint {}; // {}\n", w.name, w.offset));
            }
            continue;
        }
        let ty = match f.elem {
            Elem::Scalar(Scalar::F32) => "float",
            Elem::Scalar(Scalar::U32) => "uint",
            Elem::Struct(n) => n,
        };
        // only the outermost length may be spelled with a constant (ARRAY_LENGTHS)
        let mut suffix = String::new();
        for (d, &len) in f.dims.iter().enumerate() {
            let named = if d == 0 {
                length_name(s, f, len, groups)?
            } else {
                None
            };
            match named {
                Some(c) => suffix.push_str(&format!("[{c}]")),
                None => suffix.push_str(&format!("[{len}]")),
            }
        }
        out.push_str(&format!("    {ty} {}{suffix}; // {}\n", f.name, f.offset));
    }
    out.push_str(&format!("}} {};\n", s.name));
    Ok(out)
}

/// The probe kernel: `sizeof` of every struct in table order, which
/// `OpenClBackend::device_struct_sizes` reads and its test compares with `size_of`.
fn opencl_struct_sizes() -> String {
    let mut out = String::from(
        "// sizeof of every struct above, in this order (the OpenCL backend's\n\
         // device_struct_sizes; its test compares them with Rust's size_of)\n\
         __kernel void struct_sizes(__global uint* out) {\n",
    );
    for (i, s) in layout_table::structs().iter().enumerate() {
        out.push_str(&format!("    out[{i}] = sizeof({});\n", s.name));
    }
    out.push_str("}\n");
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_language_generates() {
        for f in FILES {
            let text = generate(f.language).unwrap_or_else(|e| panic!("{}: {e}", f.path));
            assert!(text.starts_with("// GENERATED FILE"), "{}", f.path);
            for s in layout_table::structs() {
                assert!(text.contains(s.name), "{}: {}", f.path, s.name);
            }
        }
    }

    #[test]
    fn members_follow_the_rules() {
        let wgsl = generate(Language::Wgsl).unwrap();
        assert!(wgsl.contains("    position: vec3<f32>, // 0\n    u: f32, // 12\n"));
        assert!(wgsl.contains("caster_spheres: array<vec4<f32>, MAX_CASTER_SPHERES>, // 144"));
        assert!(wgsl.contains("    _pad0: u32, // 116\n    _pad1: u32, // 120\n"));
        assert!(wgsl.contains("const NO_TILE: u32 = 0xffffffffu;"));
        assert!(wgsl.contains("const OFFSET_REL: f32 = 3.0517578e-5f;"));
        let cl = generate(Language::OpenCl).unwrap();
        assert!(cl.contains("    float caster_spheres[MAX_CASTER_SPHERES][4]; // 144\n"));
        assert!(cl.contains("    uint flux[3][2]; // 0\n"));
        assert!(cl.contains("#define COUNTER_STORED_FLUX 12\n"));
        assert!(cl.contains("#define EDGE_TEXEL_NOT_RECEIVER (-1.0f)\n"));
        assert!(cl.contains("    uint _pad0; // 24\n    uint _pad1; // 28\n} AtlasParams;"));
        let glsl = generate(Language::Glsl).unwrap();
        assert!(glsl.contains("    vec4 caster_spheres[MAX_CASTER_SPHERES]; // 144\n"));
        assert!(glsl.contains("    uvec3 indices; // 0\n"));
        assert!(glsl.contains("const int REACH_TILE = 8;"));
    }

    /// Every float constant's literal reads back as its `f32` both ways the compilers
    /// read it: straight to `f32` (WGSL and OpenCL C with the `f` suffix) and through
    /// `f64` (glslang, which keeps float constants in double precision).
    #[test]
    fn float_literals_read_back_exactly() {
        for c in shader_constants::groups()
            .iter()
            .flat_map(|g| g.consts.iter())
        {
            if let ShaderValue::F32(v) = c.value {
                let text = float(v);
                assert_eq!(
                    text.parse::<f32>().unwrap().to_bits(),
                    v.to_bits(),
                    "{}",
                    c.name
                );
                let via_f64 = text.parse::<f64>().unwrap() as f32;
                assert_eq!(via_f64.to_bits(), v.to_bits(), "{} through f64", c.name);
            }
        }
    }

    #[test]
    fn a_layout_the_rules_cannot_express_fails() {
        let s = StructLayout {
            name: "Gap",
            size: 32,
            fields: vec![
                FieldLayout {
                    name: "a",
                    offset: 0,
                    size: 12,
                    elem: Elem::Scalar(Scalar::F32),
                    dims: vec![3],
                },
                FieldLayout {
                    name: "b",
                    offset: 12,
                    size: 16,
                    elem: Elem::Scalar(Scalar::F32),
                    dims: vec![4],
                },
                FieldLayout {
                    name: "c",
                    offset: 28,
                    size: 4,
                    elem: Elem::Scalar(Scalar::U32),
                    dims: vec![],
                },
            ],
        };
        let e = vector_members(&s, &shader_constants::groups()).unwrap_err();
        assert!(e.contains("Gap.a"), "{e}");
        let s = StructLayout {
            fields: vec![
                FieldLayout {
                    dims: vec![],
                    size: 4,
                    ..s.fields[0].clone()
                },
                FieldLayout {
                    offset: 4,
                    ..s.fields[1].clone()
                },
            ],
            size: 20,
            ..s
        };
        let e = vector_members(&s, &shader_constants::groups()).unwrap_err();
        assert!(e.contains("Gap.b") && e.contains("byte 16"), "{e}");
    }
}

//! The GLSL mirrors of core's Pod structs (`shaders/common/types.glsl`) have core's layout
//! in the SPIR-V this backend loads (layout is tested, not commented).
//!
//! The stages are compiled with `glslc -O`, which strips every OpName, so a struct is
//! found by where it is bound: [`BOUND`] names, for every descriptor binding of every
//! stage whose block holds a struct, the core struct it holds. For each such binding the
//! struct's layout, read from the SPIR-V's Offset and ArrayStride decorations (a small
//! reader below: OpTypeStruct, OpMemberDecorate Offset, OpDecorate ArrayStride, the scalar,
//! vector and array types), is flattened to its 4-byte scalars and compared, scalar by
//! scalar (byte offset and float/unsigned kind), with core's layout table
//! (`caustica_core::device::layout_table`: `offset_of!` and the field types); its size
//! (array stride, or extent in a uniform block) with `size_of`. The blocks are
//! declared `layout(scalar)`; types.glsl also says that the same structs lay out
//! identically under std430 (and the uniform-block structs under std140), so those rules
//! are computed from the SPIR-V types and compared with the decorated offsets too.
//!
//! Every struct-holding binding in the SPIR-V must be listed in [`BOUND`], every listed
//! binding must exist, and every struct declared in types.glsl is either bound somewhere
//! (and so checked) or listed in [`NOT_BOUND`] with the reason. A sensitivity test moves
//! each checked Offset and ArrayStride decoration by 4 bytes and requires a failure.

use caustica_core::device::layout_table as table;
use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::Path;

// ---------------------------------------------------------------------------------------
// Core's side: every 4-byte scalar of a Pod struct, from core's layout table.

/// The kind of a 4-byte scalar.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    F32,
    U32,
    I32,
}

/// One 4-byte scalar of a layout: byte offset, kind, and a readable path to it.
#[derive(Clone, Debug)]
struct Leaf {
    offset: usize,
    kind: Scalar,
    path: String,
}

/// A core struct's name, `size_of` and scalars.
struct CoreStruct {
    name: &'static str,
    size: usize,
    leaves: Vec<Leaf>,
}

/// Every core Pod struct that types.glsl mirrors: core's layout table
/// (`caustica_core::device::layout_table`, built with `offset_of!` and `size_of`), each
/// flattened to its 4-byte scalars (nested structs expanded), after checking that the
/// scalars cover its bytes once (a Pod struct has no padding).
fn core_structs() -> Vec<CoreStruct> {
    table::structs()
        .iter()
        .map(|s| {
            let leaves: Vec<Leaf> = s
                .leaves()
                .into_iter()
                .map(|l| Leaf {
                    offset: l.offset,
                    kind: match l.scalar {
                        table::Scalar::F32 => Scalar::F32,
                        table::Scalar::U32 => Scalar::U32,
                    },
                    path: l.path,
                })
                .collect();
            let words: BTreeSet<usize> = leaves.iter().map(|l| l.offset).collect();
            assert!(
                words.len() == leaves.len() && words.iter().copied().eq((0..s.size).step_by(4)),
                "{}: core's table does not cover its {} bytes once",
                s.name,
                s.size
            );
            CoreStruct {
                name: s.name,
                size: s.size,
                leaves,
            }
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// Which stage binds which struct.

/// How a descriptor's block holds the struct.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Holds {
    /// A storage buffer `{ T items[]; }`: the struct is the runtime array's element.
    Elements,
    /// A uniform block `{ T p; }`: the struct is the block's only member.
    Member,
}

/// Every binding (stage file, set 0 binding, how, core struct) whose block holds a struct,
/// in every stage under `spirv/`. Nested structs are checked as part of their parent
/// (`DirectParams.camera` is a `GpuCamera`).
const BOUND: &[(&str, u32, Holds, &str)] = &[
    // scene buffers, common/scene.glsl
    ("primary_gbuffer.rgen", 1, Holds::Elements, "GpuVertex"),
    ("primary_gbuffer.rgen", 2, Holds::Elements, "GpuTriangle"),
    ("primary_gbuffer.rgen", 3, Holds::Elements, "GpuMaterial"),
    ("direct_light.rgen", 1, Holds::Elements, "GpuVertex"),
    ("direct_light.rgen", 2, Holds::Elements, "GpuTriangle"),
    ("direct_light.rgen", 3, Holds::Elements, "GpuMaterial"),
    ("trace_photons.rgen", 1, Holds::Elements, "GpuVertex"),
    ("trace_photons.rgen", 2, Holds::Elements, "GpuTriangle"),
    ("trace_photons.rgen", 3, Holds::Elements, "GpuMaterial"),
    ("caustic_map_lookup.rgen", 1, Holds::Elements, "GpuVertex"),
    ("caustic_map_lookup.rgen", 2, Holds::Elements, "GpuTriangle"),
    ("caustic_map_lookup.rgen", 3, Holds::Elements, "GpuMaterial"),
    // lights
    ("direct_light.rgen", 4, Holds::Elements, "GpuLight"),
    ("trace_photons.rgen", 4, Holds::Elements, "GpuLight"),
    // parameter blocks
    ("primary_gbuffer.rgen", 5, Holds::Member, "GpuCamera"),
    ("direct_light.rgen", 5, Holds::Member, "DirectParams"),
    ("trace_photons.rgen", 5, Holds::Member, "TraceParams"),
    ("trace_photons.rgen", 10, Holds::Member, "AtlasParams"),
    ("trace_photons.rgen", 17, Holds::Member, "DepositParams"),
    (
        "caustic_map_lookup.rgen",
        5,
        Holds::Member,
        "MapLookupParams",
    ),
    // outputs and inputs
    ("trace_photons.rgen", 6, Holds::Elements, "Photon"),
    ("trace_indirect.rgen", 1, Holds::Elements, "GpuVertex"),
    ("trace_indirect.rgen", 2, Holds::Elements, "GpuTriangle"),
    ("trace_indirect.rgen", 3, Holds::Elements, "GpuMaterial"),
    (
        "trace_indirect.rgen",
        5,
        Holds::Member,
        "IndirectTraceParams",
    ),
    ("trace_indirect.rgen", 6, Holds::Elements, "RsmPhoton"),
];

/// Structs of types.glsl that no stage binds, with the reason. They appear in no SPIR-V
/// (glslang emits no type for an unused declaration), so nothing here can check them;
/// the test fails if one gets bound somewhere without a [`BOUND`] row.
const NOT_BOUND: &[(&str, &str)] = &[
    (
        "RsmTexel",
        "rsm_importance and sample_rsm run on Vulkan as compute pipelines from \
         caustica-shaders' WGSL, whose layouts that crate's tests check",
    ),
    (
        "RsmParams",
        "rsm_importance and sample_rsm run on Vulkan as compute pipelines from \
         caustica-shaders' WGSL, whose layouts that crate's tests check",
    ),
    (
        "GiPhoton",
        "trace_indirect.rgen writes photons as uvec4 pairs (GiPhoton or Photon by the \
         store setting); splat_photons runs on Vulkan from caustica-shaders' WGSL, whose \
         layouts that crate's tests check",
    ),
    (
        "SplatParams",
        "splat_photons runs on Vulkan as a compute pipeline from caustica-shaders' WGSL, \
         whose layouts that crate's tests check",
    ),
    (
        "AtrousParams",
        "atrous_filter runs on Vulkan as a compute pipeline from caustica-shaders' WGSL, \
         whose layouts that crate's tests check",
    ),
    (
        "CorrectionParams",
        "shading_normal_correction runs on Vulkan as a compute pipeline from \
         caustica-shaders' WGSL, whose layouts that crate's tests check",
    ),
    (
        "TemporalParams",
        "temporal_blend runs on Vulkan as a compute pipeline from caustica-shaders' WGSL, \
         whose layouts that crate's tests check",
    ),
    (
        "RefineParams",
        "refine_clusters runs on Vulkan as a compute pipeline from caustica-shaders' WGSL, \
         whose layouts that crate's tests check",
    ),
    (
        "GBufferTexel",
        "bound as four planes of uvec4 (core's GBUFFER_PLANES, 16 bytes a pixel each) and \
         assembled by bit casts in common/gbuffer.glsl, so it lives only in registers",
    ),
    (
        "DepositTexel",
        "deposit_screen, resolve_caustics and tile_hit_distance run on Vulkan as compute \
         pipelines from caustica-shaders' WGSL, whose layouts that crate's tests check",
    ),
    (
        "GatherParams",
        "tile_hit_distance and bilateral_gather run from WGSL (see DepositTexel)",
    ),
    (
        "HitPayload",
        "not a core struct: the ray payload passed between stages, never in a buffer",
    ),
];

// ---------------------------------------------------------------------------------------
// A small SPIR-V reader: the types, constants, decorations and variables a layout needs.

/// A SPIR-V type.
#[derive(Clone, Debug)]
enum Ty {
    Int { width: u32, signed: bool },
    Float { width: u32 },
    Vector { component: u32, count: u32 },
    Array { element: u32, length: u32 },
    RuntimeArray { element: u32 },
    Struct { members: Vec<u32> },
    Pointer { pointee: u32 },
}

/// What this test reads from one SPIR-V module.
#[derive(Clone, Debug, Default)]
struct Module {
    types: HashMap<u32, Ty>,
    /// OpConstant values (first word), for array lengths.
    constants: HashMap<u32, u32>,
    /// (struct id, member index) -> Offset.
    offsets: HashMap<(u32, u32), u32>,
    /// array type id -> ArrayStride.
    strides: HashMap<u32, u32>,
    /// variable id -> (pointer type id, storage class).
    variables: BTreeMap<u32, (u32, u32)>,
    /// variable id -> DescriptorSet.
    sets: HashMap<u32, u32>,
    /// variable id -> Binding.
    bindings: HashMap<u32, u32>,
}

const MAGIC: u32 = 0x0723_0203;
const OP_TYPE_INT: u32 = 21;
const OP_TYPE_FLOAT: u32 = 22;
const OP_TYPE_VECTOR: u32 = 23;
const OP_TYPE_ARRAY: u32 = 28;
const OP_TYPE_RUNTIME_ARRAY: u32 = 29;
const OP_TYPE_STRUCT: u32 = 30;
const OP_TYPE_POINTER: u32 = 32;
const OP_CONSTANT: u32 = 43;
const OP_VARIABLE: u32 = 59;
const OP_DECORATE: u32 = 71;
const OP_MEMBER_DECORATE: u32 = 72;
const DECORATION_ARRAY_STRIDE: u32 = 6;
const DECORATION_BINDING: u32 = 33;
const DECORATION_DESCRIPTOR_SET: u32 = 34;
const DECORATION_OFFSET: u32 = 35;
const STORAGE_UNIFORM: u32 = 2;
const STORAGE_STORAGE_BUFFER: u32 = 12;

/// The words of a little-endian SPIR-V file.
fn words(bytes: &[u8]) -> Vec<u32> {
    let whole_words = bytes.chunks_exact(4).remainder().is_empty();
    assert!(whole_words && bytes.len() >= 20, "not SPIR-V");
    bytes
        .chunks_exact(4)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect()
}

/// Each instruction after the 5-word header: (word index of its first word, opcode,
/// operands).
fn instructions(words: &[u32]) -> Vec<(usize, u32, &[u32])> {
    assert_eq!(words[0], MAGIC, "not little-endian SPIR-V");
    let mut out = Vec::new();
    let mut i = 5;
    while i < words.len() {
        let count = (words[i] >> 16) as usize;
        assert!(
            count > 0 && i + count <= words.len(),
            "bad instruction at word {i}"
        );
        out.push((i, words[i] & 0xffff, &words[i + 1..i + count]));
        i += count;
    }
    out
}

fn parse(words: &[u32]) -> Module {
    let mut m = Module::default();
    for (_, op, a) in instructions(words) {
        match op {
            OP_TYPE_INT => {
                m.types.insert(
                    a[0],
                    Ty::Int {
                        width: a[1],
                        signed: a[2] != 0,
                    },
                );
            }
            OP_TYPE_FLOAT => {
                m.types.insert(a[0], Ty::Float { width: a[1] });
            }
            OP_TYPE_VECTOR => {
                m.types.insert(
                    a[0],
                    Ty::Vector {
                        component: a[1],
                        count: a[2],
                    },
                );
            }
            OP_TYPE_ARRAY => {
                // the length is a constant id, resolved when used
                m.types.insert(
                    a[0],
                    Ty::Array {
                        element: a[1],
                        length: a[2],
                    },
                );
            }
            OP_TYPE_RUNTIME_ARRAY => {
                m.types.insert(a[0], Ty::RuntimeArray { element: a[1] });
            }
            OP_TYPE_STRUCT => {
                m.types.insert(
                    a[0],
                    Ty::Struct {
                        members: a[1..].to_vec(),
                    },
                );
            }
            OP_TYPE_POINTER => {
                m.types.insert(a[0], Ty::Pointer { pointee: a[2] });
            }
            OP_CONSTANT => {
                m.constants.insert(a[1], a[2]);
            }
            OP_VARIABLE => {
                m.variables.insert(a[1], (a[0], a[2]));
            }
            OP_DECORATE => match a[1] {
                DECORATION_ARRAY_STRIDE => {
                    m.strides.insert(a[0], a[2]);
                }
                DECORATION_BINDING => {
                    m.bindings.insert(a[0], a[2]);
                }
                DECORATION_DESCRIPTOR_SET => {
                    m.sets.insert(a[0], a[2]);
                }
                _ => {}
            },
            OP_MEMBER_DECORATE if a[2] == DECORATION_OFFSET => {
                m.offsets.insert((a[0], a[1]), a[3]);
            }
            _ => {}
        }
    }
    m
}

impl Module {
    fn ty(&self, id: u32) -> Result<&Ty, String> {
        self.types
            .get(&id)
            .ok_or_else(|| format!("%{id} is not a type this reader knows"))
    }

    fn offset(&self, id: u32, member: usize) -> Result<usize, String> {
        self.offsets
            .get(&(id, member as u32))
            .map(|&o| o as usize)
            .ok_or_else(|| format!("struct %{id} member {member} has no Offset"))
    }

    fn stride(&self, id: u32) -> Result<usize, String> {
        self.strides
            .get(&id)
            .map(|&s| s as usize)
            .ok_or_else(|| format!("array %{id} has no ArrayStride"))
    }

    fn length(&self, constant: u32) -> Result<usize, String> {
        self.constants
            .get(&constant)
            .map(|&n| n as usize)
            .ok_or_else(|| format!("array length %{constant} is not a constant"))
    }

    /// The 4-byte scalars of type `id` placed at `base`, by its decorations.
    fn leaves(&self, id: u32, base: usize, path: &str, out: &mut Vec<Leaf>) -> Result<(), String> {
        let scalar = |kind| Leaf {
            offset: base,
            kind,
            path: path.to_owned(),
        };
        match self.ty(id)? {
            Ty::Float { width: 32 } => out.push(scalar(Scalar::F32)),
            Ty::Int {
                width: 32,
                signed: false,
            } => out.push(scalar(Scalar::U32)),
            Ty::Int {
                width: 32,
                signed: true,
            } => out.push(scalar(Scalar::I32)),
            &Ty::Vector { component, count } => {
                for i in 0..count as usize {
                    self.leaves(component, base + 4 * i, &format!("{path}[{i}]"), out)?;
                }
            }
            &Ty::Array { element, length } => {
                let stride = self.stride(id)?;
                for i in 0..self.length(length)? {
                    self.leaves(element, base + i * stride, &format!("{path}[{i}]"), out)?;
                }
            }
            Ty::Struct { members } => {
                for (i, &t) in members.iter().enumerate() {
                    let at = base + self.offset(id, i)?;
                    self.leaves(t, at, &format!("{path}.m{i}"), out)?;
                }
            }
            other => return Err(format!("{path}: unexpected type {other:?}")),
        }
        Ok(())
    }

    /// The bytes type `id` spans by its decorations: from 0 to the end of its last scalar.
    fn extent(&self, id: u32) -> Result<usize, String> {
        let mut leaves = Vec::new();
        self.leaves(id, 0, "", &mut leaves)?;
        Ok(leaves.iter().map(|l| l.offset + 4).max().unwrap_or(0))
    }

    /// Every variable with a descriptor binding whose block holds a struct: (set, binding,
    /// how, struct type id, the array type id for `Holds::Elements`, the block type id).
    fn bound_structs(&self) -> Result<Vec<BoundStruct>, String> {
        let mut out = Vec::new();
        for (&var, &(ptr, class)) in &self.variables {
            let Some(&binding) = self.bindings.get(&var) else {
                continue;
            };
            let set = self.sets.get(&var).copied().unwrap_or(0);
            let &Ty::Pointer { pointee } = self.ty(ptr)? else {
                return Err(format!("variable %{var} is not a pointer"));
            };
            let Ok(Ty::Struct { members }) = self.ty(pointee) else {
                continue; // an acceleration structure or image
            };
            let what = format!("set {set} binding {binding}");
            if members.len() != 1 || self.offset(pointee, 0)? != 0 {
                return Err(format!("{what}: block is not one member at offset 0"));
            }
            let (holds, array, inner) = match (class, self.ty(members[0])?) {
                (STORAGE_STORAGE_BUFFER, &Ty::RuntimeArray { element }) => {
                    (Holds::Elements, Some(members[0]), element)
                }
                (STORAGE_UNIFORM, _) => (Holds::Member, None, members[0]),
                (c, t) => return Err(format!("{what}: storage class {c} holding {t:?}")),
            };
            if matches!(self.ty(inner)?, Ty::Struct { .. }) {
                out.push(BoundStruct {
                    set,
                    binding,
                    holds,
                    ty: inner,
                    array,
                    block: pointee,
                });
            }
        }
        Ok(out)
    }
}

/// A struct held by a descriptor's block.
#[derive(Clone, Copy, Debug)]
struct BoundStruct {
    set: u32,
    binding: u32,
    holds: Holds,
    /// The struct's type id.
    ty: u32,
    /// The runtime array's type id (`Holds::Elements`).
    array: Option<u32>,
    /// The block's type id.
    block: u32,
}

// ---------------------------------------------------------------------------------------
// std430 / std140 rules, computed from the SPIR-V types.

#[derive(Clone, Copy, Debug)]
enum Rules {
    Std430,
    Std140,
}

fn round_up(x: usize, to: usize) -> usize {
    x.div_ceil(to) * to
}

/// (base alignment, size) of type `id` under `rules`.
fn rule_layout(m: &Module, id: u32, rules: Rules) -> Result<(usize, usize), String> {
    let std140 = matches!(rules, Rules::Std140);
    Ok(match m.ty(id)? {
        Ty::Float { width: 32 } | Ty::Int { width: 32, .. } => (4, 4),
        &Ty::Vector { count, .. } => (if count == 2 { 8 } else { 16 }, 4 * count as usize),
        &Ty::Array { element, length } => {
            let (a, s) = rule_layout(m, element, rules)?;
            let align = if std140 { round_up(a, 16) } else { a };
            (align, m.length(length)? * round_up(s, align))
        }
        // the last member of a storage block; it adds no bytes to the block's size
        &Ty::RuntimeArray { element } => {
            let (a, _) = rule_layout(m, element, rules)?;
            (if std140 { round_up(a, 16) } else { a }, 0)
        }
        Ty::Struct { members } => {
            let mut align = if std140 { 16 } else { 4 };
            let mut end = 0;
            for &t in members {
                let (a, s) = rule_layout(m, t, rules)?;
                align = align.max(a);
                end = round_up(end, a) + s;
            }
            (align, round_up(end, align))
        }
        other => return Err(format!("%{id}: no {rules:?} layout for {other:?}")),
    })
}

/// Compares the decorated offsets and strides inside type `id` with those `rules` give.
fn check_rules(m: &Module, id: u32, rules: Rules, path: &str, errors: &mut Vec<String>) {
    let result = (|| -> Result<(), String> {
        match m.ty(id)? {
            &Ty::Array { element, .. } | &Ty::RuntimeArray { element } => {
                let (a, s) = rule_layout(m, element, rules)?;
                let align = if matches!(rules, Rules::Std140) {
                    round_up(a, 16)
                } else {
                    a
                };
                let want = round_up(s, align);
                if m.stride(id)? != want {
                    errors.push(format!(
                        "{path}: ArrayStride {} but {rules:?} gives {want}",
                        m.stride(id)?
                    ));
                }
                check_rules(m, element, rules, &format!("{path}[]"), errors);
            }
            Ty::Struct { members } => {
                let mut end = 0;
                for (i, &t) in members.iter().enumerate() {
                    let (a, s) = rule_layout(m, t, rules)?;
                    let want = round_up(end, a);
                    let got = m.offset(id, i)?;
                    if got != want {
                        errors.push(format!(
                            "{path}.m{i}: Offset {got} but {rules:?} gives {want}"
                        ));
                    }
                    end = want + s;
                    check_rules(m, t, rules, &format!("{path}.m{i}"), errors);
                }
            }
            _ => {}
        }
        Ok(())
    })();
    if let Err(e) = result {
        errors.push(format!("{path}: {e}"));
    }
}

// ---------------------------------------------------------------------------------------
// The check.

/// The stage files under `spirv/` (`<stage>.spv`), sorted, with their bytes.
fn stages() -> Vec<(String, Vec<u8>)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("spirv");
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "spv"))
        .map(|p| {
            let stage = p.file_stem().unwrap().to_str().unwrap().to_owned();
            (stage, std::fs::read(&p).unwrap())
        })
        .collect();
    out.sort();
    out
}

/// Everything wrong with stage `stage` (SPIR-V `words`) against core and [`BOUND`]; empty
/// when its layouts are core's.
fn stage_errors(stage: &str, words: &[u32], core: &[CoreStruct]) -> Vec<String> {
    let m = parse(words);
    let mut errors = Vec::new();
    let bound = match m.bound_structs() {
        Ok(b) => b,
        Err(e) => return vec![format!("{stage}: {e}")],
    };
    // every listed binding of this stage exists
    for &(s, binding, holds, name) in BOUND.iter().filter(|b| b.0 == stage) {
        if !bound
            .iter()
            .any(|b| b.set == 0 && b.binding == binding && b.holds == holds)
        {
            errors.push(format!(
                "{stage}: binding {binding} ({holds:?} {name}) holds no struct in {s}.spv"
            ));
        }
    }
    for b in bound {
        let what = format!("{stage} binding {}", b.binding);
        let Some(&(_, _, holds, name)) = BOUND
            .iter()
            .find(|r| r.0 == stage && b.set == 0 && r.1 == b.binding)
        else {
            errors.push(format!(
                "{what} (set {}) holds a struct that BOUND does not name",
                b.set
            ));
            continue;
        };
        if holds != b.holds {
            errors.push(format!("{what}: holds {:?}, BOUND says {holds:?}", b.holds));
            continue;
        }
        let what = format!("{what}: {name}");
        let c = core
            .iter()
            .find(|c| c.name == name)
            .unwrap_or_else(|| panic!("{name}: not a core struct of this test"));
        // scalar by scalar
        let mut leaves = Vec::new();
        if let Err(e) = m.leaves(b.ty, 0, name, &mut leaves) {
            errors.push(format!("{what}: {e}"));
            continue;
        }
        let n = leaves.len().max(c.leaves.len());
        for i in 0..n {
            match (leaves.get(i), c.leaves.get(i)) {
                (Some(g), Some(r)) if g.offset == r.offset && g.kind == r.kind => {}
                (g, r) => {
                    let show = |l: Option<&Leaf>| match l {
                        Some(l) => format!("{:?} at {} ({})", l.kind, l.offset, l.path),
                        None => "nothing".to_owned(),
                    };
                    errors.push(format!(
                        "{what}: scalar {i}: SPIR-V {} but core {}",
                        show(g),
                        show(r)
                    ));
                    break;
                }
            }
        }
        // size: the array stride indexes the buffer; a uniform block spans the struct
        match b.array {
            Some(array) => match m.stride(array) {
                Ok(s) if s == c.size => {}
                Ok(s) => errors.push(format!("{what}: ArrayStride {s} but size_of is {}", c.size)),
                Err(e) => errors.push(format!("{what}: {e}")),
            },
            None => match m.extent(b.ty) {
                Ok(e) if e == c.size => {}
                Ok(e) => errors.push(format!("{what}: spans {e} bytes but size_of is {}", c.size)),
                Err(e) => errors.push(format!("{what}: {e}")),
            },
        }
        // the same offsets under std430, and under std140 for a uniform block's struct
        check_rules(&m, b.block, Rules::Std430, &what, &mut errors);
        if b.holds == Holds::Member {
            check_rules(&m, b.block, Rules::Std140, &what, &mut errors);
        }
    }
    errors
}

#[test]
fn glsl_layouts_in_the_spirv_match_core() {
    let core = core_structs();
    let stages = stages();
    assert!(!stages.is_empty(), "no SPIR-V under spirv/");
    let mut errors = Vec::new();
    for (stage, bytes) in &stages {
        errors.extend(stage_errors(stage, &words(bytes), &core));
    }
    for (stage, ..) in BOUND {
        assert!(
            stages.iter().any(|(s, _)| s == stage),
            "BOUND names {stage}, which has no spirv/{stage}.spv"
        );
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

/// Every struct of types.glsl is a core struct bound (so checked) by some stage, or is
/// listed in `NOT_BOUND`; every core struct of this test is declared there.
#[test]
fn every_mirrored_struct_is_checked_or_accounted_for() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders/common/types.glsl");
    let text = std::fs::read_to_string(&path).unwrap();
    let declared: BTreeSet<&str> = text
        .lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .filter_map(|l| l.trim_start().strip_prefix("struct "))
        .map(|rest| {
            rest.split(|c: char| !c.is_alphanumeric() && c != '_')
                .next()
                .unwrap()
        })
        .collect();
    let bound: BTreeSet<&str> = BOUND.iter().map(|b| b.3).collect();
    let not_bound: BTreeSet<&str> = NOT_BOUND.iter().map(|n| n.0).collect();
    assert!(bound.is_disjoint(&not_bound), "a struct both bound and not");
    let accounted: BTreeSet<&str> = bound.union(&not_bound).copied().collect();
    assert_eq!(
        declared, accounted,
        "types.glsl's structs vs BOUND + NOT_BOUND"
    );
    let core: BTreeSet<&str> = core_structs().iter().map(|c| c.name).collect();
    for name in &core {
        assert!(declared.contains(name), "types.glsl does not mirror {name}");
    }
    for name in &bound {
        assert!(core.contains(name), "BOUND names {name}, not a core struct");
    }
}

/// The check is sensitive: moving any Offset or ArrayStride decoration that it reads by 4
/// bytes (in a copy of the module) makes it fail.
#[test]
fn a_moved_offset_or_stride_fails() {
    let core = core_structs();
    let mut tried = 0;
    for (stage, bytes) in stages() {
        let words = words(&bytes);
        let m = parse(&words);
        let Ok(bound) = m.bound_structs() else {
            panic!("{stage}: unreadable");
        };
        if !BOUND.iter().any(|b| b.0 == stage) {
            continue;
        }
        // the struct and array types the check reads: every type reachable from a bound block
        let mut reached = BTreeSet::new();
        let mut todo: Vec<u32> = bound.iter().map(|b| b.block).collect();
        while let Some(id) = todo.pop() {
            if !reached.insert(id) {
                continue;
            }
            match m.ty(id).unwrap() {
                &Ty::Vector { component, .. } => todo.push(component),
                &Ty::Array { element, .. } | &Ty::RuntimeArray { element } => todo.push(element),
                Ty::Struct { members } => todo.extend(members),
                _ => {}
            }
        }
        for (at, op, a) in instructions(&words) {
            // the decoration's value word: OpMemberDecorate s m Offset v / OpDecorate t ArrayStride v
            let value = match op {
                OP_MEMBER_DECORATE if a[2] == DECORATION_OFFSET && reached.contains(&a[0]) => {
                    at + 4
                }
                OP_DECORATE if a[1] == DECORATION_ARRAY_STRIDE && reached.contains(&a[0]) => at + 3,
                _ => continue,
            };
            let mut moved = words.clone();
            moved[value] += 4;
            assert!(
                !stage_errors(&stage, &moved, &core).is_empty(),
                "{stage}: moving the decoration at word {at} by 4 bytes went unnoticed"
            );
            tried += 1;
        }
    }
    assert!(tried > 100, "only {tried} decorations tried");
}

//! Every WGSL kernel module, assembled by [`caustica_shaders::module_source`] as both GPU
//! backends assemble it (the shared files named by the kernel's `// needs:` line, in
//! order, then the kernel file), parses and validates with naga; the shared structs' WGSL
//! layouts equal core's `#[repr(C)]` layouts byte for byte (layout is tested,
//! not commented); each kernel's bindings are those the host binds (group 0, in order,
//! with the address space and access it expects); the crate's tables list every file
//! under `wgsl/`.

use caustica_core::device::layout_table as table;
use caustica_core::kernels::{kernel_info, ShaderBinding};
use caustica_shaders::{module_source, COMMON, KERNELS};
use naga::valid::{Capabilities, ValidationFlags, Validator};
use std::collections::BTreeSet;
use std::path::Path;

/// Stems of the `.wgsl` files directly in `dir`, sorted.
fn wgsl_stems(dir: &Path) -> Vec<String> {
    let mut stems: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .map(|p| {
            assert_eq!(
                p.extension().and_then(|x| x.to_str()),
                Some("wgsl"),
                "{}: not a .wgsl file",
                p.display()
            );
            p.file_stem().unwrap().to_str().unwrap().to_owned()
        })
        .collect();
    stems.sort();
    stems
}

/// `KERNELS` lists every file in `wgsl/` and `COMMON` every file in `wgsl/common/`, once
/// each, with the file's text: a file added without a table row (or a row left behind by
/// a removed file) fails here.
#[test]
fn tables_list_every_file() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("wgsl");
    for (table, rows, dir) in [
        ("KERNELS", KERNELS, dir.clone()),
        ("COMMON", COMMON, dir.join("common")),
    ] {
        let mut names: Vec<String> = rows.iter().map(|(n, _)| n.to_string()).collect();
        names.sort();
        let unique: BTreeSet<&String> = names.iter().collect();
        assert_eq!(unique.len(), names.len(), "{table}: a name twice");
        assert_eq!(names, wgsl_stems(&dir), "{table} vs {}", dir.display());
        for (n, text) in rows {
            let path = dir.join(format!("{n}.wgsl"));
            let disk = std::fs::read_to_string(&path).unwrap();
            assert_eq!(*text, disk, "{}: table text differs", path.display());
        }
    }
}

/// The registry kernel names, in table order.
fn kernels() -> impl Iterator<Item = &'static str> {
    KERNELS.iter().map(|(n, _)| *n)
}

/// Parses and validates one kernel module; panics with naga's report on failure.
fn validated_module(kernel: &str) -> naga::Module {
    let src = module_source(kernel).unwrap_or_else(|e| panic!("{kernel}: {e}"));
    let path = format!("{kernel}.wgsl (assembled)");
    let module = match naga::front::wgsl::parse_str(&src) {
        Ok(m) => m,
        Err(e) => panic!(
            "{kernel}: WGSL parse error\n{}",
            e.emit_to_string_with_path(&src, &path)
        ),
    };
    let mut validator = Validator::new(ValidationFlags::all(), Capabilities::default());
    if let Err(e) = validator.validate(&module) {
        panic!(
            "{kernel}: naga validation error\n{}",
            e.emit_to_string_with_path(&src, &path)
        );
    }
    module
}

#[test]
fn kernels_parse_and_validate() {
    let mut failures = Vec::new();
    for k in kernels() {
        if let Err(e) = std::panic::catch_unwind(|| validated_module(k)) {
            let msg = e
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| e.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default();
            failures.push(msg);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

#[test]
fn every_kernel_has_one_entry_point_main_with_its_declared_workgroup_size() {
    for k in kernels() {
        let m = validated_module(k);
        assert_eq!(m.entry_points.len(), 1, "{k}: entry points");
        let ep = &m.entry_points[0];
        assert_eq!(ep.name, "main", "{k}");
        assert_eq!(ep.stage, naga::ShaderStage::Compute, "{k}");
        let declared = kernel_info(k).expect("declared kernel").workgroup_size;
        assert_eq!(ep.workgroup_size, [declared, 1, 1], "{k}");
    }
}

/// One Rust field: name, byte offset, byte size.
type Field = (&'static str, usize, usize);

/// Structs of core's layout table that no WGSL module declares, with the reason.
const NOT_IN_WGSL: &[(&str, &str)] = &[(
    "DepositTexel",
    "the WGSL kernels address the deposit buffer as flat u32 words (atomics), not as a struct",
)];

/// Core's layouts (from `caustica_core::device::layout_table`, built with `offset_of!` and
/// `size_of`) of every struct the WGSL mirrors: name, size, fields.
fn rust_layouts() -> Vec<(&'static str, usize, Vec<Field>)> {
    for (n, _) in NOT_IN_WGSL {
        assert!(
            table::find(n).is_some(),
            "NOT_IN_WGSL names {n}, not in core's table"
        );
    }
    table::structs()
        .iter()
        .filter(|s| !NOT_IN_WGSL.iter().any(|(n, _)| *n == s.name))
        .map(|s| {
            let fields = s
                .fields
                .iter()
                .map(|f| (f.name, f.offset, f.size))
                .collect();
            (s.name, s.size, fields)
        })
        .collect()
}

/// A WGSL member name mapped to (Rust field, byte offset within it): `_pad0/_pad1/_pad2`
/// are the words of Rust's `_pad: [u32; 3]`.
fn rust_field_of(member: &str) -> (&str, usize) {
    match member.strip_prefix("_pad") {
        Some(d) if !d.is_empty() && d.chars().all(|c| c.is_ascii_digit()) => {
            ("_pad", 4 * d.parse::<usize>().unwrap())
        }
        _ => (member, 0),
    }
}

#[test]
fn struct_layouts_match_core() {
    let rust = rust_layouts();
    let mut seen = BTreeSet::new();
    for k in kernels() {
        let m = validated_module(k);
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(m.to_ctx()).expect("layouter");
        for (handle, ty) in m.types.iter() {
            let naga::TypeInner::Struct { members, span } = &ty.inner else {
                continue;
            };
            let Some(name) = ty.name.as_deref() else {
                continue;
            };
            let Some((_, rsize, rfields)) = rust.iter().find(|(n, _, _)| *n == name) else {
                continue;
            };
            let what = format!("{k}: struct {name}");
            // Pod structs have no implicit padding: the listed fields must fill the struct
            // (a Rust field missing from the list above fails here)
            let listed: usize = rfields.iter().map(|f| f.2).sum();
            assert_eq!(
                listed, *rsize,
                "{name}: the Rust field list here is incomplete"
            );
            assert_eq!(
                *span as usize, *rsize,
                "{what}: size (WGSL span vs size_of)"
            );
            assert_eq!(
                layouter[handle].size as usize, *rsize,
                "{what}: layouter size"
            );
            let mut covered: BTreeSet<(&str, usize)> = BTreeSet::new();
            for mem in members {
                let mname = mem.name.as_deref().unwrap_or("<unnamed>");
                let (field, within) = rust_field_of(mname);
                let Some(&(_, roff, rsz)) = rfields.iter().find(|(f, _, _)| *f == field) else {
                    panic!("{what}: member {mname} has no Rust field {field}");
                };
                let msize = layouter[mem.ty].size as usize;
                assert_eq!(
                    mem.offset as usize,
                    roff + within,
                    "{what}.{mname}: offset (WGSL vs offset_of!({name}, {field}) + {within})"
                );
                assert!(
                    within + msize <= rsz,
                    "{what}.{mname}: {msize} bytes at +{within} overrun Rust's {rsz}-byte {field}"
                );
                // a `_padN` member is one u32 word of Rust's pad array; others are whole
                let expect = if field != mname { 4 } else { rsz };
                assert_eq!(
                    msize, expect,
                    "{what}.{mname}: size (WGSL vs Rust's {field})"
                );
                for b in within..within + msize {
                    assert!(
                        covered.insert((field, b)),
                        "{what}.{mname}: overlapping members"
                    );
                }
            }
            for (f, _, sz) in rfields {
                for b in 0..*sz {
                    assert!(
                        covered.contains(&(*f, b)),
                        "{what}: Rust field {f} byte {b} has no WGSL member"
                    );
                }
            }
            seen.insert(name.to_owned());
        }
    }
    let missing: Vec<_> = rust
        .iter()
        .map(|(n, _, _)| *n)
        .filter(|n| !seen.contains(*n))
        .collect();
    assert!(
        missing.is_empty(),
        "structs not found in any module: {missing:?}"
    );
}

/// How the host binds a buffer.
#[derive(Debug, PartialEq, Clone, Copy)]
enum Kind {
    /// `var<storage, read>`
    Read,
    /// `var<storage, read_write>`
    ReadWrite,
    /// `var<uniform>`
    Uniform,
}

/// The bindings the host binds, derived from the kernel's declaration in core
/// (`caustica_core::kernels`, counts dropped): the WGSL must declare exactly these.
fn expected_bindings(kernel: &str) -> Vec<(&'static str, Kind)> {
    let info = kernel_info(kernel).unwrap_or_else(|| panic!("{kernel}: not in core's kernel list"));
    info.wgsl_bindings()
        .into_iter()
        .map(|(name, b)| {
            let kind = match b {
                ShaderBinding::Uniform => Kind::Uniform,
                ShaderBinding::StorageRead => Kind::Read,
                ShaderBinding::StorageReadWrite => Kind::ReadWrite,
                ShaderBinding::AccelerationStructure => {
                    panic!("{kernel}: WGSL binds no acceleration structure")
                }
            };
            (name, kind)
        })
        .collect()
}

/// Every kernel of core's list that launches work has a WGSL module here.
#[test]
fn every_declared_kernel_has_a_module() {
    for k in caustica_core::kernels::KERNELS {
        if k.name == "prepare_scene" {
            continue; // launches nothing on GPU-style backends
        }
        assert!(kernels().any(|n| n == k.name), "{}: no WGSL module", k.name);
    }
}

/// Bindings are group 0, numbered 0.. in the host's order, and every one is used by the
/// entry point (wgpu derives the bind group layout from the bindings the entry point
/// uses; an unused one would be missing from it).
#[test]
fn bindings_match_the_host() {
    for k in kernels() {
        let m = validated_module(k);
        let info = Validator::new(ValidationFlags::all(), Capabilities::default())
            .validate(&m)
            .unwrap();
        let ep_info = info.get_entry_point(0);
        let mut got = Vec::new();
        for (h, var) in m.global_variables.iter() {
            let Some(b) = &var.binding else { continue };
            let kind = match var.space {
                naga::AddressSpace::Uniform => Kind::Uniform,
                naga::AddressSpace::Storage { access } => {
                    if access.contains(naga::StorageAccess::STORE) {
                        Kind::ReadWrite
                    } else {
                        Kind::Read
                    }
                }
                other => panic!("{k}: binding {} in address space {other:?}", b.binding),
            };
            assert_eq!(b.group, 0, "{k}: group");
            assert!(
                !ep_info[h].is_empty(),
                "{k}: binding {} unused by main",
                b.binding
            );
            got.push((b.binding, var.name.clone().unwrap_or_default(), kind));
        }
        got.sort_by_key(|g| g.0);
        let want = expected_bindings(k);
        let got_list: Vec<_> = got.iter().map(|(i, n, kd)| (*i, n.as_str(), *kd)).collect();
        let want_list: Vec<_> = want
            .iter()
            .enumerate()
            .map(|(i, (n, kd))| (i as u32, *n, *kd))
            .collect();
        assert_eq!(got_list, want_list, "{k}: bindings");
    }
}

/// Shared files declare no bindings (the kernel file owns its binding list).
#[test]
fn common_files_declare_no_bindings() {
    for (n, text) in COMMON {
        for (line_no, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            assert!(
                !code.contains("@binding") && !code.contains("@group"),
                "common/{n}.wgsl:{}: declares a binding",
                line_no + 1
            );
        }
    }
}

/// True when expression `e` of `f` has the same value in every invocation of a workgroup
/// by WGSL's uniformity rules, in the simple form the kernels use: literals and constants,
/// the entry point's `workgroup_id` and `num_workgroups`, loads from uniform or read-only
/// storage globals at uniform indices, `arrayLength` of a global, and operators, math and
/// conversions over such values.
fn uniform_expr(m: &naga::Module, f: &naga::Function, e: naga::Handle<naga::Expression>) -> bool {
    use naga::Expression as E;
    let u = |h| uniform_expr(m, f, h);
    match f.expressions[e] {
        E::Literal(_) | E::Constant(_) | E::ZeroValue(_) => true,
        E::FunctionArgument(i) => matches!(
            f.arguments[i as usize].binding,
            Some(naga::Binding::BuiltIn(
                naga::BuiltIn::WorkGroupId | naga::BuiltIn::NumWorkGroups
            ))
        ),
        E::GlobalVariable(g) => match m.global_variables[g].space {
            naga::AddressSpace::Uniform => true,
            naga::AddressSpace::Storage { access } => !access.contains(naga::StorageAccess::STORE),
            _ => false,
        },
        E::Load { pointer } => u(pointer),
        E::ArrayLength(p) => matches!(f.expressions[p], E::GlobalVariable(_)),
        E::AccessIndex { base, .. } => u(base),
        E::Access { base, index } => u(base) && u(index),
        E::Binary { left, right, .. } => u(left) && u(right),
        E::Unary { expr, .. } | E::As { expr, .. } => u(expr),
        E::Select {
            condition,
            accept,
            reject,
        } => u(condition) && u(accept) && u(reject),
        E::Math {
            arg,
            arg1,
            arg2,
            arg3,
            ..
        } => u(arg) && [arg1, arg2, arg3].into_iter().flatten().all(u),
        _ => false,
    }
}

/// True when every `return` in `block` (statements of `f`) is a workgroup-uniform early
/// exit: the only statement of a top-level `if` without `else` whose condition is
/// [`uniform_expr`]. Such an exit skips the later barriers in every invocation alike.
fn only_uniform_exits(m: &naga::Module, f: &naga::Function, block: &naga::Block) -> bool {
    use naga::Statement as S;
    block.iter().all(|s| match s {
        S::If {
            condition,
            accept,
            reject,
        } if may_return(accept) || may_return(reject) => {
            reject.is_empty()
                && accept.len() == 1
                && matches!(accept.iter().next(), Some(S::Return { value: None }))
                && uniform_expr(m, f, *condition)
        }
        other => !may_return(&naga::Block::from_vec(vec![other.clone()])),
    })
}

/// True when `block` holds a `return` anywhere inside it.
fn may_return(block: &naga::Block) -> bool {
    use naga::Statement as S;
    block.iter().any(|s| match s {
        S::Return { .. } => true,
        S::Block(b) => may_return(b),
        S::If { accept, reject, .. } => may_return(accept) || may_return(reject),
        S::Loop {
            body, continuing, ..
        } => may_return(body) || may_return(continuing),
        S::Switch { cases, .. } => cases.iter().any(|c| may_return(&c.body)),
        _ => false,
    })
}

/// Every call of `f` (a barrier function) or barrier statement in `block`, as
/// (top level, index in block).
fn barrier_sites(
    block: &naga::Block,
    barrier_fns: &BTreeSet<naga::Handle<naga::Function>>,
    top: bool,
    out: &mut Vec<(bool, usize)>,
) {
    use naga::Statement as S;
    for (i, s) in block.iter().enumerate() {
        match s {
            S::ControlBarrier(_) | S::MemoryBarrier(_) => out.push((top, i)),
            S::Call { function, .. } if barrier_fns.contains(function) => out.push((top, i)),
            S::Block(b) => barrier_sites(b, barrier_fns, false, out),
            S::If { accept, reject, .. } => {
                barrier_sites(accept, barrier_fns, false, out);
                barrier_sites(reject, barrier_fns, false, out);
            }
            S::Loop {
                body, continuing, ..
            } => {
                barrier_sites(body, barrier_fns, false, out);
                barrier_sites(continuing, barrier_fns, false, out);
            }
            S::Switch { cases, .. } => {
                for c in cases {
                    barrier_sites(&c.body, barrier_fns, false, out);
                }
            }
            _ => {}
        }
    }
}

/// naga 30 does not enforce WGSL's rule that barriers sit in uniform control flow (its
/// uniformity analysis only reports expressions), but Tint does, and a barrier that some
/// invocations skip hangs or corrupts the group. This is the simple sufficient form the
/// kernels follow: a barrier, or a call of a function that holds one, only at the top
/// level of a function body (not inside an if, loop or switch) and after no `return` but
/// a workgroup-uniform early exit ([`only_uniform_exits`]).
#[test]
fn barriers_in_uniform_control_flow() {
    for k in kernels() {
        let m = validated_module(k);
        // functions that hold a barrier, directly or through calls (fixed point)
        let mut barrier_fns = BTreeSet::new();
        loop {
            let before = barrier_fns.len();
            for (h, f) in m.functions.iter() {
                let mut sites = Vec::new();
                barrier_sites(&f.body, &barrier_fns, true, &mut sites);
                if !sites.is_empty() {
                    barrier_fns.insert(h);
                }
            }
            if barrier_fns.len() == before {
                break;
            }
        }
        let bodies = m
            .functions
            .iter()
            .map(|(_, f)| f)
            .chain(m.entry_points.iter().map(|e| &e.function));
        for f in bodies {
            let name = f.name.as_deref().unwrap_or("?");
            let mut sites = Vec::new();
            barrier_sites(&f.body, &barrier_fns, true, &mut sites);
            for (top, i) in sites {
                assert!(
                    top,
                    "{k}: {name}: barrier (or barrier function call) inside control flow"
                );
                let before = naga::Block::from_vec(f.body.iter().take(i).cloned().collect());
                assert!(
                    only_uniform_exits(&m, f, &before),
                    "{k}: {name}: barrier after a possible return"
                );
            }
        }
    }
}

/// WebGPU's default `maxComputeWorkgroupStorageSize` (bytes): a host that creates its device
/// with the default limits (a browser; a renderer that does not ask for the adapter's) can
/// run every kernel.
const DEFAULT_WORKGROUP_STORAGE: u32 = 16384;

#[test]
fn every_kernel_fits_the_default_workgroup_storage() {
    for k in kernels() {
        let m = validated_module(k);
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(m.to_ctx()).expect("layouter");
        let bytes: u32 = m
            .global_variables
            .iter()
            .filter(|(_, g)| g.space == naga::AddressSpace::WorkGroup)
            // each variable counted as WebGPU counts it: its size rounded up to 16
            .map(|(_, g)| layouter[g.ty].size.next_multiple_of(16))
            .sum();
        assert!(
            bytes <= DEFAULT_WORKGROUP_STORAGE,
            "{k}: {bytes} bytes of workgroup memory, over WebGPU's default {DEFAULT_WORKGROUP_STORAGE}"
        );
    }
}

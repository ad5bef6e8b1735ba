// Software traversal of core's flattened BVH: obvhs's compressed wide BVH8 (Ylitie et al.
// 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs"), each
// 80-byte node uploaded as five vec4<u32>:
//   [0].xyz  p, the node grid origin (float bits)      [0].w  e[0..3] exponents, imask
//   [1].x    child_base_idx  [1].y primitive_base_idx  [1].zw child_meta[8]
//   [2]      child_min_x[8], child_max_x[8]            [3] y planes   [4] z planes
// The node test, child order and primitive order are those of the CPU backend's obvhs
// traversal, so both find the same closest hit; triangles are stored in leaf order, so a
// primitive index is a triangle index. Mirror of backend-opencl/kernels/traversal.cl and
// backend-cpu/src/traversal.rs.
//
// Reads the kernel's module-scope bindings `nodes` (array<vec4<u32>>, 5 per node; the
// node count is arrayLength(&nodes) / 5, 0 for the host's 16-byte dummy), `vertices`
// and `triangles`.

// Child boxes are entered where their exit t >= CWBVH_T_MIN = 0. obvhs clamps the entry t
// to 1e-4 (its EPSILON), which culls every box closer than 1e-4 units: whole scenes at
// 1e-4 scale lost their hits (stiff case `scale-1e-4`). Mirrors backend-cpu/src/traversal.rs.
const CWBVH_T_MIN: f32 = 0.0f;
const TRAVERSAL_STACK_SIZE: u32 = 32u;

struct Hit {
    t: f32,
    triangle: u32,
    u: f32,
    v: f32,
}

// core's device::acceleration::culling_component: a direction component as node culling
// sees it, at least CULLING_MIN_COMPONENT in magnitude (a zero's sign bit kept, so that the
// slab test's side choice matches the inverse); its inverse is then taken exactly.
fn culling_component(c: f32) -> f32 {
    return select(c, copysign_f32(CULLING_MIN_COMPONENT, c), abs(c) < CULLING_MIN_COMPONENT);
}

fn octant_inv4(d: vec3<f32>) -> u32 {
    return select(0x04040404u, 0u, d.x < 0.0) | select(0x02020202u, 0u, d.y < 0.0) |
           select(0x01010101u, 0u, d.z < 0.0);
}

// Byte `b` (0..7) of the little-endian u64 whose halves are `lo`, `hi`: OpenCL's
// `byte_of((ulong)lo | ((ulong)hi << 32), b)`.
fn byte_of(lo: u32, hi: u32, b: u32) -> u32 {
    return (select(lo, hi, b >= 4u) >> ((b & 3u) * 8u)) & 0xFFu;
}

fn firstbithigh(x: u32) -> u32 {
    return 31u - countLeadingZeros(x);
}

// Hit mask of a node's children: inner children set a bit in the top byte (at their
// octant-ordered slot), leaves their unary primitive count in the low 24 bits.
//
// The OpenCL (and obvhs) code decodes all eight children's meta bytes at once in u64
// lanes; WGSL has no u64, so each child's byte `m = byte_of(meta)` is decoded alone. The
// per-byte form is the same function because each 64-bit expression reads and writes
// only bits of the byte it produces:
//   is_inner8   = (meta8 & (meta8 << 1)) & 0x1010..10: bit 8k+4 of `meta8 << 1` is bit
//                 8k+3 of meta8 (same byte; the bit shifted in from the byte below lands
//                 on bit 8k, which the mask drops), so byte k = (m & (m << 1)) & 0x10.
//   inner_mask8 = (is_inner8 >> 4) * 0xff: the shift moves bit 8k+4 to 8k (same byte),
//                 leaving 0 or 1 per byte, and 1 * 0xff fits a byte, so the product has
//                 no carries between bytes: byte k = (is_inner >> 4) * 0xff.
//   bit_index8  = (meta8 ^ (oct_inv8 & inner_mask8)) & 0x1f..1f: &, ^ are bitwise, and
//                 byte k of oct_inv8 = (oct_inv4 << 32 | oct_inv4) is byte k & 3 of
//                 oct_inv4: byte k = (m ^ (byte_of(oct_inv4, oct_inv4, k) & mask)) & 0x1f.
//   child_bits8 = (meta8 >> 5) & 0x0707..07: bits 8k..8k+2 of the shift are bits
//                 8k+5..8k+7 of meta8 (same byte; bits from byte k+1 land on 8k+3 and up,
//                 which the mask drops): byte k = (m >> 5) & 7.
// The child planes are bytes of the (lo, hi) halves as well, so byte_of reads them.
fn cwbvh_node_hits(index: u32, origin: vec3<f32>, dir: vec3<f32>, inv_dir: vec3<f32>,
                   t_max: f32, oct_inv4: u32) -> u32 {
    let n0 = nodes[index * 5u + 0u];
    let n1 = nodes[index * 5u + 1u];
    let nx = nodes[index * 5u + 2u];
    let ny = nodes[index * 5u + 3u];
    let nz = nodes[index * 5u + 4u];
    let p = vec3<f32>(bitcast<f32>(n0.x), bitcast<f32>(n0.y), bitcast<f32>(n0.z));
    let extent = vec3<f32>(bitcast<f32>((n0.w & 0xFFu) << 23u),
                           bitcast<f32>(((n0.w >> 8u) & 0xFFu) << 23u),
                           bitcast<f32>(((n0.w >> 16u) & 0xFFu) << 23u));
    let adj_dir_inv = extent * inv_dir;
    let adj_origin = (p - origin) * inv_dir;
    let rdx = dir.x < 0.0;
    let rdy = dir.y < 0.0;
    let rdz = dir.z < 0.0;

    var hit_mask = 0u;
    for (var child = 0u; child < 8u; child++) {
        // (min planes are the .xy halves, max planes the .zw halves)
        let lo_x = f32(select(byte_of(nx.x, nx.y, child), byte_of(nx.z, nx.w, child), rdx));
        let hi_x = f32(select(byte_of(nx.z, nx.w, child), byte_of(nx.x, nx.y, child), rdx));
        let lo_y = f32(select(byte_of(ny.x, ny.y, child), byte_of(ny.z, ny.w, child), rdy));
        let hi_y = f32(select(byte_of(ny.z, ny.w, child), byte_of(ny.x, ny.y, child), rdy));
        let lo_z = f32(select(byte_of(nz.x, nz.y, child), byte_of(nz.z, nz.w, child), rdz));
        let hi_z = f32(select(byte_of(nz.z, nz.w, child), byte_of(nz.x, nz.y, child), rdz));
        let tmin3 = vec3<f32>(lo_x, lo_y, lo_z) * adj_dir_inv + adj_origin;
        let tmax3 = vec3<f32>(hi_x, hi_y, hi_z) * adj_dir_inv + adj_origin;
        let tmin = max(max(max(tmin3.x, tmin3.y), tmin3.z), CWBVH_T_MIN);
        let tmax = min(min(min(tmax3.x, tmax3.y), tmax3.z), t_max);
        if (tmin <= tmax) {
            let m = byte_of(n1.z, n1.w, child);
            let is_inner = (m & (m << 1u)) & 0x10u;
            let inner_mask = (is_inner >> 4u) * 0xffu;
            let bit_index = (m ^ (byte_of(oct_inv4, oct_inv4, child) & inner_mask)) & 0x1fu;
            let child_bits = (m >> 5u) & 0x07u;
            hit_mask |= child_bits << bit_index;
        }
    }
    return hit_mask;
}

// Corner `k` of triangle `i` in its level's space, from the node buffer's corner region at
// vec4 `corners` (core::device::acceleration::TRIANGLE_CORNER_VEC4S; the CPU backend reads
// the same values through the vertex indices).
fn triangle_corner(i: u32, k: u32, corners: u32) -> vec3<f32> {
    let v = nodes[corners + 3u * i + k];
    return vec3<f32>(bitcast<f32>(v.x), bitcast<f32>(v.y), bitcast<f32>(v.z));
}

// `row.xyz . p + row.w * w`, in the CPU backend's order (affine_row).
fn affine_row(r: vec4<u32>, p: vec3<f32>, w: f32) -> f32 {
    return p.x * bitcast<f32>(r.x) + p.y * bitcast<f32>(r.y) + p.z * bitcast<f32>(r.z) +
           w * bitcast<f32>(r.w);
}

// The ray as one level's nodes see it (the CPU backend's LevelRay; its watertight form is
// a separate variable: naga's SPIR-V output cannot pass a pointer into a struct member).
// `t_scale` takes the ray's t to the culling ray's (1 in world space).
struct LevelRay {
    origin: vec3<f32>,
    tdir: vec3<f32>,
    inv_dir: vec3<f32>,
    oct_inv4: u32,
    t_scale: f32,
}

fn level_ray(origin: vec3<f32>, dir: vec3<f32>, t_scale: f32) -> LevelRay {
    let tdir = vec3<f32>(culling_component(dir.x), culling_component(dir.y),
                         culling_component(dir.z));
    return LevelRay(origin, tdir, vec3<f32>(1.0f / tdir.x, 1.0f / tdir.y, 1.0f / tdir.z),
                    octant_inv4(tdir), t_scale);
}

// The power of two that brings d's largest component into [1, 2) (the CPU backend's
// culling_scale: object-space directions are ~1/scale long, and CULLING_MIN_COMPONENT is
// a floor for directions of about unit size).
fn culling_scale(d: vec3<f32>) -> f32 {
    let e = (bitcast<u32>(max(max(abs(d.x), abs(d.y)), abs(d.z))) >> 23u) & 0xffu;
    if (e == 0u || e >= 254u) {
        return 1.0;
    }
    return bitcast<f32>((254u - e) << 23u);
}

// Closest hit with 0 < t < t_max (any_hit = false), or any hit (any_hit = true). `t_max`
// NO_T_MAX stands for OpenCL's INFINITY. Two levels (core::device::acceleration; the CPU
// backend's `traverse` says how): a TLAS leaf is an instance record; entering it pushes
// the TLAS's remaining work, moves the ray into object space (not for the static level)
// and starts at the BLAS root; when the stack is back at its depth on entry the world ray
// returns. Popped groups without inner-node bits are the TLAS's remaining instances.
fn traverse_cwbvh(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, any_hit: bool,
                  hit: ptr<function, Hit>) -> bool {
    let node_count = arrayLength(&nodes) / 5u;
    if (node_count == 0u) {
        return false;
    }
    let world = level_ray(origin, dir, 1.0);
    var level = world;
    let world_wray = watertight_ray(origin, dir);
    var wray = world_wray;
    var stack: array<vec2<u32>, TRAVERSAL_STACK_SIZE>;
    var sp = 0u;
    var current_group = vec2<u32>(0u, 0x80000000u);
    var primitive_group = vec2<u32>(0u, 0u);
    var in_blas = false;
    var blas_sp = 0u;
    var corners = 0u;
    var found = false;
    var closest = t_max;
    // the static level alone: start at its BLAS root with the world ray
    // (core::device::acceleration::SINGLE_LEVEL_MARK)
    if (node_count > SINGLE_LEVEL_SLOT) {
        let single = nodes[SINGLE_LEVEL_SLOT * 5u];
        if (single.x == SINGLE_LEVEL_MARK) {
            in_blas = true;
            corners = single.z;
            current_group = vec2<u32>(single.y, 0x80000000u);
        }
    }
    loop {
        while (primitive_group.y != 0u) {
            let bit = firstbithigh(primitive_group.y);
            primitive_group.y &= ~(1u << bit);
            let prim = primitive_group.x + bit;
            if (!in_blas) {
                // a TLAS leaf: enter the instance whose record is at slot 2 * prim
                if (primitive_group.y != 0u && sp < TRAVERSAL_STACK_SIZE) {
                    stack[sp] = primitive_group;
                    sp += 1u;
                }
                if ((current_group.y & 0xff000000u) != 0u && sp < TRAVERSAL_STACK_SIZE) {
                    stack[sp] = current_group;
                    sp += 1u;
                }
                let r = 2u * prim * 5u;
                let info = nodes[r + 3u];
                if ((info.y & INSTANCE_IDENTITY) == 0u) {
                    let o = vec3<f32>(affine_row(nodes[r], origin, 1.0),
                                      affine_row(nodes[r + 1u], origin, 1.0),
                                      affine_row(nodes[r + 2u], origin, 1.0));
                    let d = vec3<f32>(affine_row(nodes[r], dir, 0.0),
                                      affine_row(nodes[r + 1u], dir, 0.0),
                                      affine_row(nodes[r + 2u], dir, 0.0));
                    let c = culling_scale(d);
                    level = level_ray(o, d * c, 1.0 / c);
                    wray = watertight_ray(o, d);
                }
                corners = nodes[r + 8u].y;
                in_blas = true;
                blas_sp = sp;
                current_group = vec2<u32>(info.x, 0x80000000u);
                break;
            }
            let a = triangle_corner(prim, 0u, corners);
            let b = triangle_corner(prim, 1u, corners);
            let c = triangle_corner(prim, 2u, corners);
            var h: TriangleHit;
            if (intersect_watertight(&wray, a, b, c, 0.0, closest, &h) && h.t < closest) {
                found = true;
                closest = h.t;
                (*hit).t = h.t;
                (*hit).triangle = prim;
                (*hit).u = h.u;
                (*hit).v = h.v;
                if (any_hit) {
                    return true;
                }
            }
        }
        primitive_group = vec2<u32>(0u, 0u);
        if ((current_group.y & 0xff000000u) != 0u) {
            let hits_imask = current_group.y;
            let child_index_offset = firstbithigh(hits_imask);
            let child_index_base = current_group.x;
            current_group.y &= ~(1u << child_index_offset);
            if ((current_group.y & 0xff000000u) != 0u) {
                // obvhs's BVH8 depth stays far below the stack size; a deeper tree
                // (degenerate input) loses the group rather than writing out of bounds.
                if (sp < TRAVERSAL_STACK_SIZE) {
                    stack[sp] = current_group;
                    sp += 1u;
                }
            }
            let slot_index = (child_index_offset - 24u) ^ (level.oct_inv4 & 0xffu);
            let relative_index = countOneBits(hits_imask & ~(0xffffffffu << slot_index));
            let child = child_index_base + relative_index;
            // `level` is the world ray outside a BLAS (t_scale 1: `closest` exactly)
            let hitmask = cwbvh_node_hits(child, level.origin, level.tdir, level.inv_dir,
                                          closest * level.t_scale, level.oct_inv4);
            let n0 = nodes[child * 5u + 0u];
            let n1 = nodes[child * 5u + 1u];
            current_group = vec2<u32>(n1.x, (hitmask & 0xff000000u) | (n0.w >> 24u));
            primitive_group = vec2<u32>(n1.y, hitmask & 0x00ffffffu);
        } else {
            current_group = vec2<u32>(0u, 0u);
        }
        if (primitive_group.y == 0u && (current_group.y & 0xff000000u) == 0u) {
            if (in_blas && sp == blas_sp) {
                // the instance is done: back to the world ray and the TLAS
                in_blas = false;
                level = world;
                wray = world_wray;
            }
            if (sp == 0u) {
                break;
            }
            sp -= 1u;
            let g = stack[sp];
            if ((g.y & 0xff000000u) != 0u) {
                current_group = g;
            } else {
                primitive_group = g;
            }
        }
    }
    return found;
}

fn closest_hit(origin: vec3<f32>, dir: vec3<f32>, t_max: f32, hit: ptr<function, Hit>) -> bool {
    return traverse_cwbvh(origin, dir, t_max, false, hit);
}

fn occluded(origin: vec3<f32>, dir: vec3<f32>, t_max: f32) -> bool {
    var h: Hit;
    return traverse_cwbvh(origin, dir, t_max, true, &h);
}

// The surface at a hit (scene.cl's hit_surface; here because it reads the `vertices` and
// `triangles` bindings, which kernels without a scene, such as deposit_screen, do not
// declare, and scene.wgsl is shared with those).
fn hit_surface(hit: Hit) -> SurfacePoint {
    let t = triangles[hit.triangle];
    return surface_point(vertices[t.indices[0]], vertices[t.indices[1]],
                         vertices[t.indices[2]], hit.u, hit.v);
}

// Software traversal of core's flattened BVH: obvhs's compressed wide BVH8 (Ylitie et al.
// 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs"), each
// 80-byte node uploaded as five uint4:
//   [0].xyz  p, the node grid origin (float bits)      [0].w  e[0..3] exponents, imask
//   [1].x    child_base_idx  [1].y primitive_base_idx  [1].zw child_meta[8]
//   [2]      child_min_x[8], child_max_x[8]            [3] y planes   [4] z planes
// The node test, child order and primitive order are those of the CPU backend's obvhs
// traversal, so both find the same closest hit; triangles are stored in leaf order, so
// a primitive index is a triangle index. Mirrors backend-cpu/src/traversal.rs.

// Child boxes are entered where their exit t >= CWBVH_T_MIN = 0. obvhs clamps the entry t
// to 1e-4 (its EPSILON), which culls every box closer than 1e-4 units: whole scenes at
// 1e-4 scale lost their hits (stiff case `scale-1e-4`). Mirrors backend-cpu/src/traversal.rs.
#define CWBVH_T_MIN 0.0f
#define TRAVERSAL_STACK_SIZE 32

typedef struct {
    float t;
    uint triangle;
    float u;
    float v;
} Hit;

// core's device::acceleration::culling_component: a direction component as node culling
// sees it, at least CULLING_MIN_COMPONENT in magnitude (a zero's sign bit kept, so that the
// slab test's side choice matches the inverse); its inverse is then taken exactly.
inline float culling_component(float c) {
    return fabs(c) < CULLING_MIN_COMPONENT ? copysign(CULLING_MIN_COMPONENT, c) : c;
}

inline uint octant_inv4(float3 d) {
    return (d.x < 0.0f ? 0u : 0x04040404u) | (d.y < 0.0f ? 0u : 0x02020202u) |
           (d.z < 0.0f ? 0u : 0x01010101u);
}

inline uint byte_of(ulong x, uint b) { return (uint)(x >> (b * 8u)) & 0xFFu; }

inline uint firstbithigh(uint x) { return 31u - clz(x); }

// Hit mask of a node's children: inner children set a bit in the top byte (at their
// octant-ordered slot), leaves their unary primitive count in the low 24 bits.
inline uint cwbvh_node_hits(__global const uint4* nodes, uint index, float3 origin,
                            float3 dir, float3 inv_dir, float t_max, uint oct_inv4) {
    uint4 n0 = nodes[index * 5u + 0u];
    uint4 n1 = nodes[index * 5u + 1u];
    uint4 nx = nodes[index * 5u + 2u];
    uint4 ny = nodes[index * 5u + 3u];
    uint4 nz = nodes[index * 5u + 4u];
    float3 p = (float3)(as_float(n0.x), as_float(n0.y), as_float(n0.z));
    float3 extent = (float3)(as_float((n0.w & 0xFFu) << 23), as_float(((n0.w >> 8) & 0xFFu) << 23),
                             as_float(((n0.w >> 16) & 0xFFu) << 23));
    float3 adj_dir_inv = extent * inv_dir;
    float3 adj_origin = (p - origin) * inv_dir;

    ulong meta8 = (ulong)n1.z | ((ulong)n1.w << 32);
    ulong oct_inv8 = (ulong)oct_inv4 | ((ulong)oct_inv4 << 32);
    ulong is_inner8 = (meta8 & (meta8 << 1)) & 0x1010101010101010ul;
    ulong inner_mask8 = (is_inner8 >> 4) * 0xfful;
    ulong bit_index8 = (meta8 ^ (oct_inv8 & inner_mask8)) & 0x1f1f1f1f1f1f1f1ful;
    ulong child_bits8 = (meta8 >> 5) & 0x0707070707070707ul;

    ulong min_x = (ulong)nx.x | ((ulong)nx.y << 32), max_x = (ulong)nx.z | ((ulong)nx.w << 32);
    ulong min_y = (ulong)ny.x | ((ulong)ny.y << 32), max_y = (ulong)ny.z | ((ulong)ny.w << 32);
    ulong min_z = (ulong)nz.x | ((ulong)nz.y << 32), max_z = (ulong)nz.z | ((ulong)nz.w << 32);
    bool rdx = dir.x < 0.0f, rdy = dir.y < 0.0f, rdz = dir.z < 0.0f;

    uint hit_mask = 0u;
    for (uint child = 0u; child < 8u; child++) {
        float lo_x = (float)byte_of(rdx ? max_x : min_x, child);
        float hi_x = (float)byte_of(rdx ? min_x : max_x, child);
        float lo_y = (float)byte_of(rdy ? max_y : min_y, child);
        float hi_y = (float)byte_of(rdy ? min_y : max_y, child);
        float lo_z = (float)byte_of(rdz ? max_z : min_z, child);
        float hi_z = (float)byte_of(rdz ? min_z : max_z, child);
        float3 tmin3 = (float3)(lo_x, lo_y, lo_z) * adj_dir_inv + adj_origin;
        float3 tmax3 = (float3)(hi_x, hi_y, hi_z) * adj_dir_inv + adj_origin;
        float tmin = fmax(fmax(fmax(tmin3.x, tmin3.y), tmin3.z), CWBVH_T_MIN);
        float tmax = fmin(fmin(fmin(tmax3.x, tmax3.y), tmax3.z), t_max);
        if (tmin <= tmax) {
            hit_mask |= byte_of(child_bits8, child) << byte_of(bit_index8, child);
        }
    }
    return hit_mask;
}

// Corner `k` of triangle `i` in its level's space, from the node buffer's corner region at
// vec4 `corners` (core::device::acceleration::TRIANGLE_CORNER_VEC4S; the CPU backend reads
// the same values through the vertex indices).
inline float3 triangle_corner(__global const uint4* nodes, uint i, uint k, uint corners) {
    uint4 v = nodes[corners + 3u * i + k];
    return (float3)(as_float(v.x), as_float(v.y), as_float(v.z));
}

// `row.xyz . p + row.w * w`, in the CPU backend's order (affine_row; FP_CONTRACT is off).
inline float affine_row(uint4 r, float3 p, float w) {
    return p.x * as_float(r.x) + p.y * as_float(r.y) + p.z * as_float(r.z) + w * as_float(r.w);
}

// The ray as one level sees it (the CPU backend's LevelRay); `t_scale` takes the ray's t
// to the culling ray's (1 in world space).
typedef struct {
    float3 origin;
    float3 tdir;
    float3 inv_dir;
    uint oct_inv4;
    float t_scale;
} LevelRay;

inline LevelRay level_ray(float3 origin, float3 dir, float t_scale) {
    LevelRay l;
    l.origin = origin;
    l.tdir = (float3)(culling_component(dir.x), culling_component(dir.y),
                      culling_component(dir.z));
    l.inv_dir = (float3)(1.0f / l.tdir.x, 1.0f / l.tdir.y, 1.0f / l.tdir.z);
    l.oct_inv4 = octant_inv4(l.tdir);
    l.t_scale = t_scale;
    return l;
}

// The power of two that brings d's largest component into [1, 2) (the CPU backend's
// culling_scale: object-space directions are ~1/scale long, and CULLING_MIN_COMPONENT is
// a floor for directions of about unit size).
inline float culling_scale(float3 d) {
    uint e = (as_uint(fmax(fmax(fabs(d.x), fabs(d.y)), fabs(d.z))) >> 23) & 0xffu;
    if (e == 0u || e >= 254u) return 1.0f;
    return as_float((254u - e) << 23);
}

// Closest hit with 0 < t < t_max (any_hit = false), or any hit (any_hit = true). Two levels
// (core::device::acceleration; the CPU backend's `traverse` says how): a TLAS leaf is an
// instance record; entering it pushes the TLAS's remaining work, moves the ray into object
// space (not for the static level) and starts at the BLAS root; when the stack is back at
// its depth on entry the world ray returns. Popped groups without inner-node bits are the
// TLAS's remaining instances.
inline bool traverse_cwbvh(__global const uint4* nodes, uint node_count,
                           __global const GpuVertex* vertices,
                           __global const GpuTriangle* triangles, float3 origin, float3 dir,
                           float t_max, bool any_hit, Hit* hit) {
    if (node_count == 0u) return false;
    LevelRay world = level_ray(origin, dir, 1.0f);
    LevelRay level = world;
    WatertightRay world_wray = watertight_ray(origin, dir);
    WatertightRay wray = world_wray;
    uint2 stack[TRAVERSAL_STACK_SIZE];
    uint sp = 0u;
    uint2 current_group = (uint2)(0u, 0x80000000u);
    uint2 primitive_group = (uint2)(0u, 0u);
    bool in_blas = false;
    uint blas_sp = 0u;
    uint corners = 0u;
    bool found = false;
    float closest = t_max;
    // the static level alone: start at its BLAS root with the world ray
    // (core::device::acceleration::SINGLE_LEVEL_MARK)
    if (node_count > SINGLE_LEVEL_SLOT) {
        uint4 single = nodes[SINGLE_LEVEL_SLOT * 5u];
        if (single.x == SINGLE_LEVEL_MARK) {
            in_blas = true;
            corners = single.z;
            current_group = (uint2)(single.y, 0x80000000u);
        }
    }
    for (;;) {
        while (primitive_group.y != 0u) {
            uint bit = firstbithigh(primitive_group.y);
            primitive_group.y &= ~(1u << bit);
            uint prim = primitive_group.x + bit;
            if (!in_blas) {
                // a TLAS leaf: enter the instance whose record is at slot 2 * prim
                if (primitive_group.y != 0u && sp < TRAVERSAL_STACK_SIZE)
                    stack[sp++] = primitive_group;
                if ((current_group.y & 0xff000000u) != 0u && sp < TRAVERSAL_STACK_SIZE)
                    stack[sp++] = current_group;
                uint r = 2u * prim * 5u;
                uint4 info = nodes[r + 3u];
                if ((info.y & INSTANCE_IDENTITY) == 0u) {
                    float3 o = (float3)(affine_row(nodes[r], origin, 1.0f),
                                        affine_row(nodes[r + 1u], origin, 1.0f),
                                        affine_row(nodes[r + 2u], origin, 1.0f));
                    float3 d = (float3)(affine_row(nodes[r], dir, 0.0f),
                                        affine_row(nodes[r + 1u], dir, 0.0f),
                                        affine_row(nodes[r + 2u], dir, 0.0f));
                    float c = culling_scale(d);
                    level = level_ray(o, d * c, 1.0f / c);
                    wray = watertight_ray(o, d);
                }
                corners = nodes[r + 8u].y;
                in_blas = true;
                blas_sp = sp;
                current_group = (uint2)(info.x, 0x80000000u);
                break;
            }
            float3 a = triangle_corner(nodes, prim, 0u, corners);
            float3 b = triangle_corner(nodes, prim, 1u, corners);
            float3 c = triangle_corner(nodes, prim, 2u, corners);
            TriangleHit h;
            if (intersect_watertight(&wray, a, b, c, 0.0f, closest, &h) && h.t < closest) {
                found = true;
                closest = h.t;
                hit->t = h.t;
                hit->triangle = prim;
                hit->u = h.u;
                hit->v = h.v;
                if (any_hit) return true;
            }
        }
        primitive_group = (uint2)(0u, 0u);
        if ((current_group.y & 0xff000000u) != 0u) {
            uint hits_imask = current_group.y;
            uint child_index_offset = firstbithigh(hits_imask);
            uint child_index_base = current_group.x;
            current_group.y &= ~(1u << child_index_offset);
            if ((current_group.y & 0xff000000u) != 0u) {
                // obvhs's BVH8 depth stays far below the stack size; a deeper tree
                // (degenerate input) loses the group rather than writing out of bounds.
                if (sp < TRAVERSAL_STACK_SIZE) stack[sp++] = current_group;
            }
            uint slot_index = (child_index_offset - 24u) ^ (level.oct_inv4 & 0xffu);
            uint relative_index = popcount(hits_imask & ~(0xffffffffu << slot_index));
            uint child = child_index_base + relative_index;
            // `level` is the world ray outside a BLAS (t_scale 1: `closest` exactly)
            uint hitmask = cwbvh_node_hits(nodes, child, level.origin, level.tdir, level.inv_dir,
                                           closest * level.t_scale, level.oct_inv4);
            uint4 n0 = nodes[child * 5u + 0u];
            uint4 n1 = nodes[child * 5u + 1u];
            current_group = (uint2)(n1.x, (hitmask & 0xff000000u) | (n0.w >> 24));
            primitive_group = (uint2)(n1.y, hitmask & 0x00ffffffu);
        } else {
            current_group = (uint2)(0u, 0u);
        }
        if (primitive_group.y == 0u && (current_group.y & 0xff000000u) == 0u) {
            if (in_blas && sp == blas_sp) {
                // the instance is done: back to the world ray and the TLAS
                in_blas = false;
                level = world;
                wray = world_wray;
            }
            if (sp == 0u) break;
            uint2 g = stack[--sp];
            if ((g.y & 0xff000000u) != 0u)
                current_group = g;
            else
                primitive_group = g;
        }
    }
    return found;
}

inline bool closest_hit(__global const uint4* nodes, uint node_count,
                        __global const GpuVertex* vertices, __global const GpuTriangle* triangles,
                        float3 origin, float3 dir, float t_max, Hit* hit) {
    return traverse_cwbvh(nodes, node_count, vertices, triangles, origin, dir, t_max, false, hit);
}

inline bool occluded(__global const uint4* nodes, uint node_count,
                     __global const GpuVertex* vertices, __global const GpuTriangle* triangles,
                     float3 origin, float3 dir, float t_max) {
    Hit h;
    return traverse_cwbvh(nodes, node_count, vertices, triangles, origin, dir, t_max, true, &h);
}

// The hand-written start of every stage, after the generated layout.glsl (core's structs
// and shared constants): what GLSL spells differently from Rust (PI_F, TAU_F, NO_T_MAX)
// and the ray payload of the Vulkan stages. Spaces: world positions and directions;
// `depth` is view depth; pixel (0, 0) top-left.
//
// Layouts: blocks that hold layout.glsl's structs are declared `layout(scalar)`
// (GL_EXT_scalar_block_layout; the device enables scalarBlockLayout): every member sits
// at the next multiple of 4, exactly as in Rust, so `vec3 position; float u;` is 16
// bytes as `[f32; 3], f32`. The structs are laid out identically under std430, and the
// parameter structs (the uniform blocks) under std140 too: every vec3 is followed by a
// 4-byte scalar, every vec4 and nested struct starts at a multiple of 16, and their pad
// arrays are separate words, so a block may switch layout without moving a byte (the
// generator checks the offsets, tests/glsl_layouts.rs the compiled SPIR-V's).
//
// Floating point: the OpenCL port compiles with FP_CONTRACT OFF so that every product
// and sum rounds as in Rust. GLSL has no such switch; instead every function that
// computes with floats returns `precise` (and its float out-parameters and the kernels'
// float locals are `precise`), which glslang propagates to every operation that feeds
// the value: each float add, sub, mul and div carries SPIR-V NoContraction, so neither
// spirv-opt nor the driver may fuse a * b + c or reassociate (scripts/compile-shaders.sh
// fails if a float operation of a stage lacks it). glslang folds constant float
// expressions in double precision, so no shader computes with two constants (such an
// expression goes through a variable, see cauchy_ior). Division, sqrt, exp, sin and cos
// remain only as accurate as Vulkan requires (a few ulp), as in the OpenCL and WGSL ports.

// The closest-hit payload (location 0) shared by the ray generation, closest-hit and miss
// stages: hit distance, triangle index (NO_HIT on a miss) and the barycentrics (u, v) of
// vertices 1 and 2 (vertex 0 weighs 1 - u - v), core's convention.
struct HitPayload { float t; uint triangle; vec2 bary; };
const uint NO_HIT = 0xffffffffu;

const float PI_F = 3.14159265358979323846;
const float TAU_F = 6.28318530717958647692;
// Stands for OpenCL's INFINITY as a ray's t_max ("no limit"): traceRayEXT needs finite
// values, and this is f32::MAX.
const float NO_T_MAX = 3.4028235e38;

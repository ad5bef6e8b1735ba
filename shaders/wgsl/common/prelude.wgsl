// The hand-written start of every WGSL module, after the generated layout.wgsl (core's
// structs and shared constants): what WGSL spells differently from Rust (PI_F, TAU_F,
// NO_T_MAX) and core's deposit_word. Spaces: world positions and directions; `depth` is
// view depth; pixel (0, 0) top-left.
//
// No binding is declared in a shared file. Shared functions may read module-scope
// variables that the kernel file declares with exactly these names: `vertices`,
// `triangles`, `materials`, `lights`, `nodes` (traversal.wgsl) and `lc`, `counters`
// (fixed_point.wgsl).
//
// Floating point: the OpenCL port compiles with FP_CONTRACT OFF so that every product
// and sum rounds as in Rust. WGSL has no such switch: a driver may fuse a * b + c into
// an fma (naga emits no NoContraction), and WGSL's division, sqrt, exp, pow, sin and cos
// are only accurate to a few ulp. The shared files keep the operation order of the
// Rust and OpenCL code so that they round the same wherever the device does.

// The photon map is u32 words, DEPOSIT_TEXEL_WORDS per pixel (DepositTexel's five u64
// sums as (lo, hi) words), stored in planes of at most 4 words a pixel (core's
// DEPOSIT_PLANES: words 0-3, 4-7, 8-9).
// core's deposit_word: (plane, index in the plane) of word `word` of pixel `pixel`.
fn deposit_word(pixel: u32, word: u32) -> vec2<u32> {
    let k = word / 4u;
    let n = select(4u, 2u, k == 2u);
    return vec2<u32>(k, pixel * n + (word - 4u * k));
}

// f32 literals carry the `f` suffix so that naga parses them straight to f32, as Rust
// does (an unsuffixed literal would round through f64 first).
const PI_F: f32 = 3.14159265358979323846f;
const TAU_F: f32 = 6.28318530717958647692f;

// WGSL has no infinity literal (and a runtime infinity is allowed to be indeterminate), so
// "no t_max" (Rust's f32::INFINITY, OpenCL's INFINITY) is f32::MAX. The only difference:
// a hit at exactly t = f32::MAX, or a box entered at t = +inf, counts on the CPU and not
// here; neither occurs with finite scenes.
const NO_T_MAX: f32 = 3.4028235e38f;

// The hand-written start of every program, after the generated layout.cl (core's structs
// and shared constants, each struct built from 4-byte scalars in Rust's order so that
// OpenCL C and Rust agree byte for byte; its `struct_sizes` lets the host check every
// size against Rust's `size_of`). Spaces: world positions and directions; `depth` is view
// depth; pixel (0, 0) top-left.

// Strict IEEE single precision: no fused multiply-add, so that every product and sum is
// rounded as in the Rust reference (which never contracts).
#pragma OPENCL FP_CONTRACT OFF

#define PI_F 3.14159265358979323846f
#define TAU_F 6.28318530717958647692f

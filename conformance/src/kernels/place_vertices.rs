//! `place_vertices`: an instance's run of world vertices placed from its object-space
//! vertices, compared with the CPU's (core's definition) coordinate by coordinate.
//!
//! Each position coordinate is `((a x + b y) + c z) + t`, each normal coordinate the same
//! sum of three products before the renormalisation. A port that rounds every operation
//! by itself (OpenCL: `FP_CONTRACT OFF`) computes the CPU's bits; a driver that fuses a
//! product into the next sum (WGSL allows it) rounds each such pair once instead of
//! twice. Either result is within `gamma_4 S` of the exact sum, `S` the sum of the terms'
//! magnitudes and `gamma_n = n u / (1 - n u)`, `u = 2^-24` (Higham, Accuracy and
//! Stability, 3.1), so two ports differ by at most `2 gamma_4 S` per position coordinate.
//! A normal `m` of length `l` whose components are each within `e = 2 gamma_3 S` moves,
//! once divided by its length, by at most `2 e / l` per component, plus the
//! renormalisation's own rounding: on a Vulkan device (the SPIR-V environment's precision
//! table, which WGSL follows) sqrt is inherited from `1 / inversesqrt` (2 + 2.5 ulp) and
//! the division in `1 / sqrt` adds 2.5, about 7 ulp, the squared length's sums and the
//! product a few more, and the host's own rounding 3 or 4: `32 u` covers them. A normal
//! whose squared length is subnormal (`l` below 2^-63) may fall back to +Y on a device
//! that flushes subnormals; such normals (and those within the sums' error of zero) are
//! not compared. Vertices outside the run and `u`, `v` are bitwise kept.

use crate::harness::fixture::run_and_free;
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::layout::{GpuVertex, PlacementParams};
use caustica_core::device::placement::params_matrices;
use caustica_core::kernels::PlaceVertices;
use caustica_core::recording::Recording;

/// The world vertices `place_vertices` leaves on `b`: `object` uploaded as the object
/// vertices, `world` as the world vertices before it runs.
pub fn run_place(
    b: &mut dyn Backend,
    params: &PlacementParams,
    object: &[GpuVertex],
    world: &[GpuVertex],
) -> Result<Vec<GpuVertex>, String> {
    let mut rec = Recording::new();
    let object_vertices = rec.upload(object, "object vertices");
    let vertices = rec.upload(world, "vertices");
    rec.kernel(PlaceVertices {
        params: *params,
        object_vertices,
        vertices,
    });
    run_and_free(b, "place_vertices", &rec, |b| read_buf(b, vertices))
}

const U: f64 = 1.0 / 16_777_216.0;

fn gamma(n: f64) -> f64 {
    n * U / (1.0 - n * U)
}

/// `place_vertices` on the reference `r` and the candidate `c` (see the module doc).
pub fn check_place_vertices(
    r: &mut dyn Backend,
    c: &mut dyn Backend,
    params: &PlacementParams,
    object: &[GpuVertex],
    world: &[GpuVertex],
) -> Result<Verdict, String> {
    let mut v = Verdict::new("place_vertices");
    let a = run_place(r, params, object, world)?;
    let b = run_place(c, params, object, world)?;
    let (m, nm) = params_matrices(params);
    let run = params.world_first as usize..(params.world_first + params.count) as usize;
    let (mut kept, mut far, mut bitwise) = (0usize, 0usize, 0usize);
    for (i, (x, y)) in a.iter().zip(&b).enumerate() {
        let words = |g: &GpuVertex| bytemuck::cast::<GpuVertex, [u32; 8]>(*g);
        if words(x) == words(y) {
            bitwise += 1;
        }
        if !run.contains(&i) {
            kept += (words(x) != words(&world[i])) as usize + (words(y) != words(&world[i])) as usize;
            continue;
        }
        let o = object[params.object_first as usize + i - run.start];
        let (p, n) = (o.position.map(f64::from), o.normal.map(f64::from));
        let cols = |c: [glam::Vec3A; 3], k: usize| [c[0][k] as f64, c[1][k] as f64, c[2][k] as f64];
        let linear = [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis];
        let normal = [nm.x_axis, nm.y_axis, nm.z_axis];
        let mut ok = x.u.to_bits() == y.u.to_bits() && x.v.to_bits() == y.v.to_bits();
        // the normal before its renormalisation, in f64, and its terms' magnitudes
        let mut s_n = 0.0f64;
        let mut len2 = 0.0f64;
        for k in 0..3 {
            let a = cols(linear, k);
            let s = a[0].abs() * p[0].abs()
                + a[1].abs() * p[1].abs()
                + a[2].abs() * p[2].abs()
                + (m.translation[k] as f64).abs();
            let tol = 2.0 * gamma(4.0) * s + f64::from(f32::MIN_POSITIVE);
            ok &= (x.position[k] as f64 - y.position[k] as f64).abs() <= tol;
            let b = cols(normal, k);
            let mk = b[0] * n[0] + b[1] * n[1] + b[2] * n[2];
            len2 += mk * mk;
            s_n = s_n.max(b[0].abs() * n[0].abs() + b[1].abs() * n[1].abs() + b[2].abs() * n[2].abs());
        }
        let l = len2.sqrt();
        // a normal whose length is within the sums' error of zero may fall back to +Y on
        // one side only
        let e = 2.0 * gamma(3.0) * s_n;
        if l > 4.0 * e && l > 2f64.powi(-60) {
            let tol = 2.0 * e / l + 32.0 * U;
            for k in 0..3 {
                ok &= (x.normal[k] as f64 - y.normal[k] as f64).abs() <= tol;
            }
        }
        far += !ok as usize;
    }
    v.check(a.len() == b.len() && kept == 0, || {
        format!("{kept} vertices outside the run changed")
    });
    v.check(far == 0, || {
        format!("{far} of {} placed vertices beyond the bound", params.count)
    });
    v.note(format!(
        "{} placed, {bitwise} of {} vertices bitwise the CPU's",
        params.count,
        a.len()
    ));
    Ok(v)
}

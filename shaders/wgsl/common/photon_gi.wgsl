// Mirror of core::math::{rsm, gi_photon, photon_splat, path_sort} and packing's rgb9e5
// (PhotonGi, Smal 2019), function by function with the same names; backend-opencl/kernels/
// common/photon_gi.cl is the OpenCL C twin.

// rsm::luminance (Rec. 709).
// A level-0 texel's pyramid entry: its importance, or 1 under uniform sampling
// (core::math::rsm::pyramid_weight).
fn pyramid_weight(sampling: u32, imp: f32) -> f32 {
    return select(imp, 1.0, sampling == RSM_SAMPLING_UNIFORM);
}

fn luminance(c: vec3<f32>) -> f32 {
    return 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
}

// rsm::level_count: log2(side) + 1.
fn level_count(side: u32) -> u32 {
    return countTrailingZeros(max(side, 1u)) + 1u;
}

// rsm::level_offset: sum of (side >> j)^2 over j < level.
fn level_offset(side: u32, level: u32) -> u32 {
    var off = 0u;
    for (var j = 0u; j < level; j++) {
        let s = side >> j;
        off += s * s;
    }
    return off;
}

// rsm::pyramid_len.
fn pyramid_len(side: u32) -> u32 {
    return level_offset(side, level_count(side));
}

// rsm::texel_arriving_flux: intensity x falloff x the texel's solid angle.
fn texel_arriving_flux(intensity: vec3<f32>, falloff: f32, ix: u32, iy: u32, side: u32,
                       tan_half_fov: f32) -> vec3<f32> {
    let centre = (2.0 * tan_half_fov / f32(side)) * (2.0 * tan_half_fov / f32(side));
    let w = view_plane_texel_weight(ix, iy, side, side, tan_half_fov, tan_half_fov);
    return intensity * (falloff * (centre * w));
}

// rsm::ortho_texel_flux: irradiance x the orthographic texel's area.
fn ortho_texel_flux(irradiance: vec3<f32>, side: u32, half: f32) -> vec3<f32> {
    let edge = 2.0 * half / f32(side);
    return irradiance * (edge * edge);
}

// rsm::ortho_origin: p projected onto the orthographic face's plane.
fn ortho_origin(p: vec3<f32>, plane_point: vec3<f32>, forward: vec3<f32>) -> vec3<f32> {
    return p - forward * dot3(p - plane_point, forward);
}

// rsm::radical_inverse2.
fn radical_inverse2(i: u32) -> f32 {
    return f32(reverseBits(i) >> 8u) * (1.0 / 16777216.0);
}

const RSM_ONE_MINUS_ULP: f32 = 0.99999994f;

fn wrap_unit(x: f32) -> f32 {
    let y = select(x, x - 1.0, x >= 1.0);
    return min(y, RSM_ONE_MINUS_ULP);
}

// rsm::hammersley: point i of the n-point set rotated by shift.
fn hammersley(i: u32, n: u32, shift: vec2<f32>) -> vec2<f32> {
    let u = vec2<f32>((f32(i) + 0.5) / f32(max(n, 1u)), radical_inverse2(i)) + shift;
    return vec2<f32>(wrap_unit(u.x), wrap_unit(u.y));
}

// rsm::chunk_photons: the photons of a launch's chunk below count.
fn chunk_photons(count: u32, chunk_first: u32, chunk_size: u32) -> u32 {
    return min(count - min(chunk_first, count), chunk_size);
}

// rsm::coherent_sample_order: the sample thread t of a launch over n samples traces.
fn coherent_sample_order(t: u32, n: u32) -> u32 {
    if (n < 64u) {
        return t;
    }
    let m = 31u - countLeadingZeros(n);
    if (t >= (1u << m)) {
        return t;
    }
    let k = (m - 5u) / 2u;
    let hi = m - k;
    return ((t & ((1u << hi) - 1u)) << k) | (t >> hi);
}

// wavelet_warp::warp_ratio: part / whole clamped to [0, 1], 0 when whole is 0.
fn warp_ratio(part: f32, whole: f32) -> f32 {
    if (whole > 0.0) {
        return clamp(part / whole, 0.0, 1.0);
    }
    return 0.0;
}

// wavelet_warp::warp_split: (first part?, rescaled u, probability) as x, y, z; x is 1.0
// for the first part.
fn warp_split(u: f32, p: f32) -> vec3<f32> {
    if (u < p) {
        return vec3<f32>(1.0, min(u / p, RSM_ONE_MINUS_ULP), p);
    }
    let q = 1.0 - p;
    return vec3<f32>(0.0, clamp((u - p) / q, 0.0, RSM_ONE_MINUS_ULP), q);
}

// rsm::cosine_hemisphere (Malley).
fn cosine_hemisphere(u: vec2<f32>, n: vec3<f32>) -> vec3<f32> {
    let r = sqrt(u.x);
    let phi = TAU_F * u.y;
    let z = sqrt(max(1.0 - u.x, 0.0));
    return to_world(vec3<f32>(r * cos(phi), r * sin(phi), z), n);
}

// rsm::russian_roulette: w = 1 survives with the returned flux (xyz), 0 absorbed.
fn russian_roulette(flux: vec3<f32>, albedo: vec3<f32>, xi: f32) -> vec4<f32> {
    let reflected = flux * albedo;
    let m = max_element3(flux);
    if (!(m > 0.0)) {
        return vec4<f32>(0.0);
    }
    let q = clamp(max_element3(reflected) / m, 0.0, 1.0);
    if (xi < q) {
        return vec4<f32>(reflected / q, 1.0);
    }
    return vec4<f32>(0.0);
}

// core::math::path_sort::path_sort_key (trace_indirect's queue keys, the sorted_waves
// schedule).
fn path_sort_key(origin: vec3<f32>, direction: vec3<f32>, origin_min: vec3<f32>,
                 origin_scale: vec3<f32>) -> u32 {
    let top = f32((1u << PATH_SORT_BITS) - 1u);
    let c = vec3<u32>(min(max((origin - origin_min) * origin_scale, vec3<f32>(0.0)),
                          vec3<f32>(top)));
    var morton = 0u;
    for (var b = 0u; b < PATH_SORT_BITS; b++) {
        morton |= ((c.x >> b) & 1u) << (3u * b) | ((c.y >> b) & 1u) << (3u * b + 1u) |
                  ((c.z >> b) & 1u) << (3u * b + 2u);
    }
    let octant = select(0u, 1u, direction.x < 0.0) | select(0u, 2u, direction.y < 0.0) |
                 select(0u, 4u, direction.z < 0.0);
    return octant << (3u * PATH_SORT_BITS) | morton;
}

// gi_photon::screen_tile.
fn screen_tile(x: u32, y: u32, width: u32, tile_size: u32) -> u32 {
    let t = max(tile_size, 1u);
    let tiles_x = (width + t - 1u) / t;
    return (y / t) * tiles_x + x / t;
}

// packing::pow2: 2^k from its bits (k in -126..=127).
fn pow2(k: i32) -> f32 {
    return bitcast<f32>(u32(k + 127) << 23u);
}

// packing::pack_rgb9e5 (exact arithmetic only).
fn pack_rgb9e5(rgb: vec3<f32>) -> u32 {
    let MAX = 65408.0;
    let r = select(clamp(rgb.x, 0.0, MAX), 0.0, is_nan_f32(rgb.x));
    let g = select(clamp(rgb.y, 0.0, MAX), 0.0, is_nan_f32(rgb.y));
    let b = select(clamp(rgb.z, 0.0, MAX), 0.0, is_nan_f32(rgb.z));
    let max_c = max(max(r, g), b);
    if (max_c == 0.0) {
        return 0u;
    }
    let e = i32((bitcast<u32>(max_c) >> 23u) & 0xffu) - 127;
    var exp_shared = max(e, -16) + 1 + 15;
    var scale = pow2(9 + 15 - exp_shared);
    if (u32(floor(max_c * scale + 0.5)) == 512u) {
        exp_shared += 1;
        scale *= 0.5;
    }
    let qr = min(u32(floor(r * scale + 0.5)), 511u);
    let qg = min(u32(floor(g * scale + 0.5)), 511u);
    let qb = min(u32(floor(b * scale + 0.5)), 511u);
    return qr | (qg << 9u) | (qb << 18u) | (u32(exp_shared) << 27u);
}

// packing::unpack_rgb9e5.
fn unpack_rgb9e5(p: u32) -> vec3<f32> {
    let scale = pow2(i32(p >> 27u) - 15 - 9);
    return vec3<f32>(f32(p & 511u) * scale, f32((p >> 9u) & 511u) * scale,
                     f32((p >> 18u) & 511u) * scale);
}

// photon_splat::ray_length_scale (Eq. 2).
fn ray_length_scale(ray_length: f32, c: SplatParams) -> f32 {
    return clamp(ray_length / c.max_ray_length, c.min_length_scale, 1.0);
}

// photon_splat::density_scale (Eqs. 5-6).
fn density_scale(z_view: f32, tile_constant: f32, photons_in_tile: u32, c: SplatParams) -> f32 {
    var r = c.density_radius_max;
    if (photons_in_tile > 0u) {
        r = sqrt(z_view * z_view * tile_constant / (PI_F * f32(photons_in_tile)));
    }
    return clamp(r, c.density_radius_min, c.density_radius_max) * c.photons_per_pixel;
}

// photon_splat::min_splat_scale: min_px pixel footprints at view depth z.
fn min_splat_scale(z_view: f32, tan_half_fov_y: f32, height: u32, min_px: f32) -> f32 {
    return min_px * (2.0 * z_view * tan_half_fov_y / f32(height));
}

// photon_splat::light_stretch (Eq. 7).
fn light_stretch(normal: vec3<f32>, to_light: vec3<f32>, c: SplatParams) -> f32 {
    let cs = clamp(dot3(normal, to_light), 0.0, 1.0);
    if (cs > 0.0) {
        return min(1.0 / cs, c.max_stretch);
    }
    return c.max_stretch;
}

// photon_splat::SplatKernel: frame (n, u, t) and half-axes along them.
struct SplatKernel {
    n: vec3<f32>,
    u: vec3<f32>,
    t: vec3<f32>,
    axes: vec3<f32>,
}

// photon_splat::splat_kernel.
fn splat_kernel(normal: vec3<f32>, to_light: vec3<f32>, s: f32, c: SplatParams) -> SplatKernel {
    var k: SplatKernel;
    let n = normalize3(normal);
    let along = to_light - dot3(to_light, n) * n;
    if (dot3(along, along) > 1e-12) {
        k.u = normalize3(along);
    } else {
        var b: vec3<f32>;
        k.u = orthonormal_basis(n, &b);
    }
    k.n = n;
    k.t = cross3(n, k.u);
    let su = light_stretch(n, to_light, c);
    k.axes = vec3<f32>(c.normal_compression * s, su * s, s);
    return k;
}

// SplatKernel::ellipse_area: pi |u| |t|.
fn ellipse_area(k: SplatKernel) -> f32 {
    return PI_F * k.axes.y * k.axes.z;
}

// photon_splat::SplatKernel::frame: v along n, u and t.
fn splat_frame(k: SplatKernel, v: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(dot3(v, k.n), dot3(v, k.u), dot3(v, k.t));
}

// SplatKernel::contains.
fn kernel_contains(k: SplatKernel, centre: vec3<f32>, p: vec3<f32>) -> bool {
    let q = splat_frame(k, p - centre) / k.axes;
    return dot3(q, q) <= 1.0;
}

// photon_splat::splat_irradiance (Eq. 9).
fn splat_irradiance(power: vec3<f32>, k: SplatKernel) -> vec3<f32> {
    let a = ellipse_area(k);
    if (a > 0.0) {
        return power / a;
    }
    return vec3<f32>(0.0);
}

// layout::gbuffer_pixel_area: the surface area pixel `index` covers.
fn gbuffer_pixel_area(cam: GpuCamera, index: u32, g: GBufferTexel) -> f32 {
    let ray = camera_ray(cam, index % cam.width, index / cam.width);
    let footprint = pixel_footprint(g.depth, cam.width, cam.height, cam.tan_half_fov_x,
                                    cam.tan_half_fov_y);
    return pixel_surface_area(footprint, dot3(ray, cam.forward), dot3(ray, g.normal));
}

// backend-cpu splat_photons::splat_reach_px: half-width in pixels a splat of bounding radius
// `radius` around view depth z can reach; 0xffffffff when it reaches the camera plane.
fn splat_reach_px(p: SplatParams, radius: f32, z: f32) -> u32 {
    let near = z - radius;
    if (!(near > 0.0)) {
        return 0xffffffffu;
    }
    let pixel = 2.0 * p.camera.tan_half_fov_y / f32(p.camera.height);
    let r = ceil(radius / (near * pixel)) + 1.0;
    if (r >= 4194304.0) {
        return 0xffffffffu;
    }
    return u32(r);
}

// irradiance_filter::light_direction_deposit: a splat contribution's flux (W) from unit
// light direction `to_light` adds w (to_light + 1) / 2 per axis (xyz) and its weight w,
// the flux's luminance (w).
fn light_direction_deposit(flux: vec3<f32>, to_light: vec3<f32>) -> vec4<f32> {
    let w = luminance(flux);
    return vec4<f32>((to_light + vec3<f32>(1.0)) * (0.5 * w), w);
}

// core::device::layout::splat_box_margin: how far the kernel's box is widened for rounding
// (scene: the scene's largest absolute coordinate).
fn splat_box_margin(cam: GpuCamera, centre: vec3<f32>, axes: vec3<f32>, scene: f32) -> f32 {
    return 1e-5 * (max_element3(abs(centre)) + max_element3(abs(cam.position)) +
                   max_element3(axes) + scene);
}

// core::device::layout::SplatRays: the eye (less the centre) and the camera's forward,
// right and up in the kernel's frame, the widened box's half-extents (half_axes.x < 0: no test).
struct SplatRays {
    eye: vec3<f32>,
    forward: vec3<f32>,
    right: vec3<f32>,
    up: vec3<f32>,
    half_axes: vec3<f32>,
}

// core::device::layout::splat_rays.
fn splat_rays(cam: GpuCamera, centre: vec3<f32>, k: SplatKernel, scene: f32) -> SplatRays {
    var r: SplatRays;
    r.eye = splat_frame(k, cam.position - centre);
    r.forward = splat_frame(k, cam.forward);
    r.right = splat_frame(k, cam.right);
    r.up = splat_frame(k, cam.up);
    // twice the margin, and the image-plane point's rounding (see the Rust doc)
    r.half_axes = k.axes + vec3<f32>(2.0 * splat_box_margin(cam, centre, k.axes, scene) *
                                     (1.0 + abs(cam.tan_half_fov_x) + abs(cam.tan_half_fov_y)));
    let finite = all_finite3(r.eye) && all_finite3(r.forward) && all_finite3(r.right) &&
                 all_finite3(r.up) && all_finite3(r.half_axes);
    if (cam.tan_half_fov_x < 0.0 || !finite) {
        r.half_axes = vec3<f32>(-1.0);
    }
    return r;
}

// core::device::layout::splat_ray_may_hit: whether pixel (px, py)'s centre ray's line may
// meet the widened box (the separating axes e_i x d; see the Rust doc).
fn splat_ray_may_hit(r: SplatRays, cam: GpuCamera, px: u32, py: u32) -> bool {
    if (r.half_axes.x < 0.0) {
        return true;
    }
    // camera_ray's image-plane point without its per-pixel division (the margin holds it)
    let sx = (f32(px) + 0.5) * (2.0 * cam.tan_half_fov_x / f32(cam.width)) - cam.tan_half_fov_x;
    let sy = cam.tan_half_fov_y - (f32(py) + 0.5) * (2.0 * cam.tan_half_fov_y / f32(cam.height));
    let d = r.forward + sx * r.right + sy * r.up;
    let c = cross3(r.eye, d);
    let a = abs(d);
    let h = r.half_axes;
    // "not separated": a NaN from an overflow keeps the pixel
    return !(abs(c.x) > h.y * a.z + h.z * a.y || abs(c.y) > h.x * a.z + h.z * a.x ||
             abs(c.z) > h.x * a.y + h.y * a.x);
}

// core::device::layout::splat_screen_rect: the pixels (x0, x1, y0, y1), inclusive, that
// splat_photons tests: the square of r pixels around (px, py) in the image, narrowed to
// the screen bounds of the kernel's box (widened for rounding; see the Rust doc).
fn splat_screen_rect(cam: GpuCamera, centre: vec3<f32>, k: SplatKernel, px: u32, py: u32,
                     r: u32, scene: f32) -> vec4<i32> {
    let n = k.n;
    let u = k.u;
    let t = k.t;
    let axes = k.axes;
    let w = i32(cam.width);
    let h = i32(cam.height);
    let ri = i32(min(r, 1u << 24u));
    let square = vec4<i32>(max(i32(px) - ri, 0), min(i32(px) + ri, w - 1),
                           max(i32(py) - ri, 0), min(i32(py) + ri, h - 1));
    let a = axes + vec3<f32>(splat_box_margin(cam, centre, axes, scene));
    var lo_x = 3.4028235e38;
    var hi_x = -3.4028235e38;
    var lo_y = 3.4028235e38;
    var hi_y = -3.4028235e38;
    for (var corner = 0u; corner < 8u; corner++) {
        let sn = select(-1.0, 1.0, (corner & 1u) != 0u);
        let su = select(-1.0, 1.0, (corner & 2u) != 0u);
        let st = select(-1.0, 1.0, (corner & 4u) != 0u);
        let c = centre + n * (sn * a.x) + u * (su * a.y) + t * (st * a.z);
        var fx: f32;
        var fy: f32;
        var z: f32;
        if (!project_to_screen(cam, c, &fx, &fy, &z)) {
            return square;
        }
        if (!(is_finite_f32(fx) && is_finite_f32(fy))) {
            return square;
        }
        lo_x = min(lo_x, fx);
        hi_x = max(hi_x, fx);
        lo_y = min(lo_y, fy);
        hi_y = max(hi_y, fy);
    }
    return vec4<i32>(i32(clamp(floor(lo_x) - 1.0, f32(square.x), f32(square.y))),
                     i32(clamp(floor(hi_x) + 1.0, f32(square.x), f32(square.y))),
                     i32(clamp(floor(lo_y) - 1.0, f32(square.z), f32(square.w))),
                     i32(clamp(floor(hi_y) + 1.0, f32(square.z), f32(square.w))));
}

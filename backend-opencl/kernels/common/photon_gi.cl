// Mirror of core::math::{rsm, gi_photon, photon_splat, path_sort} and packing's rgb9e5 (PhotonGi,
// Smal 2019), function by function with the same names; shaders/wgsl/common/photon_gi.wgsl
// is the WGSL twin.

// rsm::luminance (Rec. 709).
// A level-0 texel's pyramid entry: its importance, or 1 under uniform sampling
// (core::math::rsm::pyramid_weight).
inline float pyramid_weight(uint sampling, float imp) {
    return sampling == RSM_SAMPLING_UNIFORM ? 1.0f : imp;
}
inline float luminance(float3 c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

// rsm::level_count: log2(side) + 1 (side a power of two; OpenCL 1.2 has clz, not ctz).
inline uint level_count(uint side) { return 32u - (uint)clz(max(side, 1u)); }

// rsm::level_offset: sum of (side >> j)^2 over j < level.
inline uint level_offset(uint side, uint level) {
    uint off = 0u;
    for (uint j = 0u; j < level; j++) {
        uint s = side >> j;
        off += s * s;
    }
    return off;
}

// rsm::pyramid_len.
inline uint pyramid_len(uint side) { return level_offset(side, level_count(side)); }

// rsm::texel_arriving_flux: intensity x falloff x the texel's solid angle.
inline float3 texel_arriving_flux(float3 intensity, float falloff, uint ix, uint iy, uint side,
                                  float tan_half_fov) {
    float centre = (2.0f * tan_half_fov / (float)side) * (2.0f * tan_half_fov / (float)side);
    float w = view_plane_texel_weight(ix, iy, side, side, tan_half_fov, tan_half_fov);
    return intensity * (falloff * (centre * w));
}

// rsm::ortho_texel_flux: irradiance x the orthographic texel's area.
inline float3 ortho_texel_flux(float3 irradiance, uint side, float half_extent) {
    float edge = 2.0f * half_extent / (float)side;
    return irradiance * (edge * edge);
}

// rsm::ortho_origin: p projected onto the orthographic face's plane.
inline float3 ortho_origin(float3 p, float3 plane_point, float3 forward) {
    return p - forward * dot3(p - plane_point, forward);
}

// rsm::radical_inverse2 (bit reversal by swaps).
inline float radical_inverse2(uint i) {
    uint b = i;
    b = (b << 16) | (b >> 16);
    b = ((b & 0x00ff00ffu) << 8) | ((b & 0xff00ff00u) >> 8);
    b = ((b & 0x0f0f0f0fu) << 4) | ((b & 0xf0f0f0f0u) >> 4);
    b = ((b & 0x33333333u) << 2) | ((b & 0xccccccccu) >> 2);
    b = ((b & 0x55555555u) << 1) | ((b & 0xaaaaaaaau) >> 1);
    return (float)(b >> 8) * (1.0f / 16777216.0f);
}

#define RSM_ONE_MINUS_ULP 0.99999994f

inline float wrap_unit(float x) { return min(x >= 1.0f ? x - 1.0f : x, RSM_ONE_MINUS_ULP); }

// rsm::hammersley: point i of the n-point set rotated by shift.
inline float2 hammersley(uint i, uint n, float2 shift) {
    float2 u = (float2)(((float)i + 0.5f) / (float)max(n, 1u), radical_inverse2(i)) + shift;
    return (float2)(wrap_unit(u.x), wrap_unit(u.y));
}

// rsm::chunk_photons: the photons of a launch's chunk below count.
inline uint chunk_photons(uint count, uint chunk_first, uint chunk_size) {
    return min(count - min(chunk_first, count), chunk_size);
}

// rsm::coherent_sample_order: the sample thread t of a launch over n samples traces.
inline uint coherent_sample_order(uint t, uint n) {
    if (n < 64u) return t;
    uint m = 31u - clz(n);
    if (t >= (1u << m)) return t;
    uint k = (m - 5u) / 2u;
    uint hi = m - k;
    return ((t & ((1u << hi) - 1u)) << k) | (t >> hi);
}

// wavelet_warp::warp_ratio.
inline float warp_ratio(float part, float whole) {
    return whole > 0.0f ? clamp(part / whole, 0.0f, 1.0f) : 0.0f;
}

// wavelet_warp::warp_split: (first part? 1 : 0, rescaled u, probability).
inline float3 warp_split(float u, float p) {
    if (u < p) return (float3)(1.0f, min(u / p, RSM_ONE_MINUS_ULP), p);
    float q = 1.0f - p;
    return (float3)(0.0f, clamp((u - p) / q, 0.0f, RSM_ONE_MINUS_ULP), q);
}

// rsm::cosine_hemisphere (Malley).
inline float3 cosine_hemisphere(float2 u, float3 n) {
    float r = sqrt(u.x);
    float phi = TAU_F * u.y;
    float z = sqrt(max(1.0f - u.x, 0.0f));
    return to_world((float3)(r * cos(phi), r * sin(phi), z), n);
}

// rsm::russian_roulette: w = 1 survives with flux xyz, 0 absorbed.
inline float4 russian_roulette(float3 flux, float3 albedo, float xi) {
    float3 reflected = flux * albedo;
    float m = max_element3(flux);
    if (!(m > 0.0f)) return (float4)(0.0f);
    float q = clamp(max_element3(reflected) / m, 0.0f, 1.0f);
    if (xi < q) return (float4)(reflected / q, 1.0f);
    return (float4)(0.0f);
}

// gi_photon::screen_tile.
inline uint screen_tile(uint x, uint y, uint width, uint tile_size) {
    uint t = max(tile_size, 1u);
    uint tiles_x = (width + t - 1u) / t;
    return (y / t) * tiles_x + x / t;
}

// packing::pow2.
inline float pow2(int k) { return as_float((uint)(k + 127) << 23); }

inline float clamp_not_nan(float x, float hi) { return isnan(x) ? 0.0f : clamp(x, 0.0f, hi); }

// packing::pack_rgb9e5 (exact arithmetic only).
inline uint pack_rgb9e5(float3 rgb) {
    float r = clamp_not_nan(rgb.x, 65408.0f), g = clamp_not_nan(rgb.y, 65408.0f),
          b = clamp_not_nan(rgb.z, 65408.0f);
    float max_c = max(max(r, g), b);
    if (max_c == 0.0f) return 0u;
    int e = (int)((as_uint(max_c) >> 23) & 0xffu) - 127;
    int exp_shared = max(e, -16) + 1 + 15;
    float scale = pow2(9 + 15 - exp_shared);
    if ((uint)floor(max_c * scale + 0.5f) == 512u) {
        exp_shared += 1;
        scale *= 0.5f;
    }
    uint qr = min((uint)floor(r * scale + 0.5f), 511u);
    uint qg = min((uint)floor(g * scale + 0.5f), 511u);
    uint qb = min((uint)floor(b * scale + 0.5f), 511u);
    return qr | (qg << 9) | (qb << 18) | ((uint)exp_shared << 27);
}

// packing::unpack_rgb9e5.
inline float3 unpack_rgb9e5(uint p) {
    float scale = pow2((int)(p >> 27) - 15 - 9);
    return (float3)((float)(p & 511u) * scale, (float)((p >> 9) & 511u) * scale,
                    (float)((p >> 18) & 511u) * scale);
}

// photon_splat::ray_length_scale (Eq. 2).
inline float ray_length_scale(float ray_length, __global const SplatParams* c) {
    return clamp(ray_length / c->max_ray_length, c->min_length_scale, 1.0f);
}

// photon_splat::density_scale (Eqs. 5-6).
inline float density_scale(float z_view, float tile_constant, uint photons_in_tile,
                           __global const SplatParams* c) {
    float r = c->density_radius_max;
    if (photons_in_tile > 0u)
        r = sqrt(z_view * z_view * tile_constant / (PI_F * (float)photons_in_tile));
    return clamp(r, c->density_radius_min, c->density_radius_max) * c->photons_per_pixel;
}

// photon_splat::min_splat_scale: min_px pixel footprints at view depth z.
inline float min_splat_scale(float z_view, float tan_half_fov_y, uint height, float min_px) {
    return min_px * (2.0f * z_view * tan_half_fov_y / (float)height);
}

// photon_splat::light_stretch (Eq. 7).
inline float light_stretch(float3 normal, float3 to_light, __global const SplatParams* c) {
    float cs = clamp(dot3(normal, to_light), 0.0f, 1.0f);
    return cs > 0.0f ? min(1.0f / cs, c->max_stretch) : c->max_stretch;
}

// photon_splat::SplatKernel.
typedef struct { float3 n; float3 u; float3 t; float3 axes; } SplatKernel;

// photon_splat::splat_kernel.
inline SplatKernel splat_kernel(float3 normal, float3 to_light, float s,
                                __global const SplatParams* c) {
    SplatKernel k;
    float3 n = normalize3(normal);
    float3 along = to_light - dot3(to_light, n) * n;
    if (dot3(along, along) > 1e-12f) {
        k.u = normalize3(along);
    } else {
        float3 b;
        k.u = orthonormal_basis(n, &b);
    }
    k.n = n;
    k.t = cross3(n, k.u);
    float su = light_stretch(n, to_light, c);
    k.axes = (float3)(c->normal_compression * s, su * s, s);
    return k;
}

// SplatKernel::ellipse_area.
inline float ellipse_area(const SplatKernel* k) { return PI_F * k->axes.y * k->axes.z; }

// photon_splat::SplatKernel::frame: v along n, u and t.
inline float3 splat_frame(const SplatKernel* k, float3 v) {
    return (float3)(dot3(v, k->n), dot3(v, k->u), dot3(v, k->t));
}

// SplatKernel::contains.
inline bool kernel_contains(const SplatKernel* k, float3 centre, float3 p) {
    float3 q = splat_frame(k, p - centre) / k->axes;
    return dot3(q, q) <= 1.0f;
}

// photon_splat::splat_irradiance (Eq. 9).
inline float3 splat_irradiance(float3 power, const SplatKernel* k) {
    float a = ellipse_area(k);
    return a > 0.0f ? power / a : (float3)(0.0f);
}

// core::device::layout::splat_box_margin: how far the kernel's box is widened for rounding
// (scene: the scene's largest absolute coordinate).
inline float splat_box_margin(__global const GpuCamera* cam, float3 centre, float3 axes,
                              float scene) {
    return 1e-5f * (max_element3(fabs(centre)) + max_element3(fabs(load3g(cam->position))) +
                    max_element3(axes) + scene);
}

// core::device::layout::splat_screen_rect: the pixels (x0, x1, y0, y1), inclusive, that
// splat_photons tests: the square of r pixels around (px, py) in the image, narrowed to
// the screen bounds of the kernel's box (widened for rounding; see the Rust doc).
inline int4 splat_screen_rect(__global const GpuCamera* cam, float3 centre, const SplatKernel* k,
                              uint px, uint py, uint r, float scene) {
    float3 n = k->n, u = k->u, t = k->t, axes = k->axes;
    int w = (int)cam->width, h = (int)cam->height;
    int ri = (int)min(r, 1u << 24);
    int4 square = (int4)(max((int)px - ri, 0), min((int)px + ri, w - 1), max((int)py - ri, 0),
                         min((int)py + ri, h - 1));
    float3 a = axes + (float3)(splat_box_margin(cam, centre, axes, scene));
    float lo_x = FLT_MAX, hi_x = -FLT_MAX, lo_y = FLT_MAX, hi_y = -FLT_MAX;
    for (uint corner = 0u; corner < 8u; corner++) {
        float sn = (corner & 1u) != 0u ? 1.0f : -1.0f;
        float su = (corner & 2u) != 0u ? 1.0f : -1.0f;
        float st = (corner & 4u) != 0u ? 1.0f : -1.0f;
        float3 c = centre + n * (sn * a.x) + u * (su * a.y) + t * (st * a.z);
        float fx, fy, z;
        if (!project_to_screen(cam, c, &fx, &fy, &z)) return square;
        if (!(isfinite(fx) && isfinite(fy))) return square;
        lo_x = fmin(lo_x, fx);
        hi_x = fmax(hi_x, fx);
        lo_y = fmin(lo_y, fy);
        hi_y = fmax(hi_y, fy);
    }
    return (int4)((int)clamp(floor(lo_x) - 1.0f, (float)square.x, (float)square.y),
                  (int)clamp(floor(hi_x) + 1.0f, (float)square.x, (float)square.y),
                  (int)clamp(floor(lo_y) - 1.0f, (float)square.z, (float)square.w),
                  (int)clamp(floor(hi_y) + 1.0f, (float)square.z, (float)square.w));
}

// core::device::layout::SplatRays: the eye (less the centre) and the camera's forward, right
// and up in the kernel's frame, the widened box's half-extents (half_axes.x < 0: no test).
typedef struct {
    float3 eye;
    float3 forward;
    float3 right;
    float3 up;
    float3 half_axes;
} SplatRays;

// core::device::layout::splat_rays.
inline SplatRays splat_rays(__global const GpuCamera* cam, float3 centre, const SplatKernel* k,
                            float scene) {
    SplatRays r;
    r.eye = splat_frame(k, load3g(cam->position) - centre);
    r.forward = splat_frame(k, load3g(cam->forward));
    r.right = splat_frame(k, load3g(cam->right));
    r.up = splat_frame(k, load3g(cam->up));
    // twice the margin, and the image-plane point's rounding (see the Rust doc)
    r.half_axes = k->axes + (float3)(2.0f * splat_box_margin(cam, centre, k->axes, scene) *
                                     (1.0f + fabs(cam->tan_half_fov_x) + fabs(cam->tan_half_fov_y)));
    bool finite = all_finite3(r.eye) && all_finite3(r.forward) && all_finite3(r.right) &&
                  all_finite3(r.up) && all_finite3(r.half_axes);
    if (cam->tan_half_fov_x < 0.0f || !finite) r.half_axes = (float3)(-1.0f);
    return r;
}

// core::device::layout::splat_ray_may_hit: whether pixel (px, py)'s centre ray's line may
// meet the widened box (the separating axes e_i x d; see the Rust doc).
inline bool splat_ray_may_hit(const SplatRays* r, __global const GpuCamera* cam, uint px, uint py) {
    if (r->half_axes.x < 0.0f) return true;
    // camera_ray's image-plane point without its per-pixel division (the margin holds it)
    float sx = ((float)px + 0.5f) * (2.0f * cam->tan_half_fov_x / (float)cam->width) -
               cam->tan_half_fov_x;
    float sy = cam->tan_half_fov_y -
               ((float)py + 0.5f) * (2.0f * cam->tan_half_fov_y / (float)cam->height);
    float3 d = r->forward + sx * r->right + sy * r->up;
    float3 c = cross3(r->eye, d);
    float3 a = fabs(d), h = r->half_axes;
    // "not separated": a NaN from an overflow keeps the pixel
    return !(fabs(c.x) > h.y * a.z + h.z * a.y || fabs(c.y) > h.x * a.z + h.z * a.x ||
             fabs(c.z) > h.x * a.y + h.y * a.x);
}

// layout::gbuffer_pixel_area.
inline float gbuffer_pixel_area(__global const GpuCamera* cam, uint index, const GBufferTexel* g) {
    float3 ray = camera_ray(cam, index % cam->width, index / cam->width);
    float footprint = pixel_footprint(g->depth, cam->width, cam->height, cam->tan_half_fov_x,
                                      cam->tan_half_fov_y);
    return pixel_surface_area(footprint, dot3(ray, load3g(cam->forward)),
                              dot3(ray, load3(g->normal)));
}

// backend-cpu splat_photons::splat_reach_px.
inline uint splat_reach_px(__global const SplatParams* p, float radius, float z) {
    float near_z = z - radius;
    if (!(near_z > 0.0f)) return 0xffffffffu;
    float pixel = 2.0f * p->camera.tan_half_fov_y / (float)p->camera.height;
    float r = ceil(radius / (near_z * pixel)) + 1.0f;
    return r >= 4194304.0f ? 0xffffffffu : (uint)r;
}

// irradiance_filter::light_direction_deposit: a splat contribution's flux (W) from unit
// light direction `to_light` adds w (to_light + 1) / 2 per axis (xyz) and its weight w,
// the flux's luminance (w).
inline float4 light_direction_deposit(float3 flux, float3 to_light) {
    float w = luminance(flux);
    float3 d = (to_light + (float3)(1.0f)) * (0.5f * w);
    return (float4)(d.x, d.y, d.z, w);
}

// core::math::path_sort::path_sort_key: the direction's octant above the Morton code of
// the origin's cell (one subtraction and one product per axis, not contracted).
inline uint path_sort_key(float3 origin, float3 direction, float3 origin_min,
                          float3 origin_scale) {
    float top = (float)((1u << PATH_SORT_BITS) - 1u);
    float3 c = fmin(fmax((origin - origin_min) * origin_scale, (float3)(0.0f)), (float3)(top));
    uint x = (uint)c.x, y = (uint)c.y, z = (uint)c.z;
    uint morton = 0u;
    for (uint b = 0u; b < PATH_SORT_BITS; b++)
        morton |= ((x >> b) & 1u) << (3u * b) | ((y >> b) & 1u) << (3u * b + 1u) |
                  ((z >> b) & 1u) << (3u * b + 2u);
    uint octant = (direction.x < 0.0f ? 1u : 0u) | (direction.y < 0.0f ? 2u : 0u) |
                  (direction.z < 0.0f ? 4u : 0u);
    return octant << (3u * PATH_SORT_BITS) | morton;
}

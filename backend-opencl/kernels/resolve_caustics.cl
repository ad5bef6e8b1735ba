// resolve_caustics (Kim 2019 Eq. 5): radiance L = (albedo / pi) * Phi / A from the pixel's
// fixed-point flux sum; alpha = mean hit distance. Mirror of
// backend-cpu/src/kernels/resolve_caustics.rs::resolve_caustics, which scales in f64. Where
// the device has doubles (cl_khr_fp64: PoCL, NVIDIA) this does the same f64 operations and
// matches bitwise; otherwise the 64-bit sums are split exactly into hi * 2^32 and lo and
// scaled in f32, a few f32 roundings (<= ~4 ulp) away from the CPU.

#ifdef cl_khr_fp64
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double wide_t;
#define WIDE_PI 3.14159265358979323846
#else
typedef float wide_t;
#define WIDE_PI PI_F
#endif

// saturate_radiance in the wide type: at most FLT_MAX, so that times an albedo in [0, 1]
// and cast to float it stays finite (CPU: deposit_screen.rs::saturate_wide).
inline wide_t saturate_wide(wide_t x) { return fmin(x, (wide_t)RADIANCE_MAX); }

inline wide_t join_u64_wide(uint lo, uint hi) {
#ifdef cl_khr_fp64
    return (double)((ulong)lo | ((ulong)hi << 32));
#else
    return (float)hi * 4294967296.0f + (float)lo;
#endif
}

__kernel void resolve_caustics(__global const DepositParams* p,
                               GBUFFER_PARAMS(__global const),
                               PHOTON_MAP_PARAMS(__global const), __global float4* out) {
    uint i = get_global_id(0);
    __global const GpuCamera* cam = &p->camera;
    if (i >= cam->width * cam->height) return;
    GBufferTexel gt = load_gbuffer(GBUFFER_ARGS, i);
    const GBufferTexel* g = &gt;
    uint t[10];
    for (uint k = 0u; k < 10u; k++) t[k] = photon_map_word(PHOTON_MAP_ARGS, i, k);
    if ((t[8] == 0u && t[9] == 0u) || (g->flags & GBUFFER_RECEIVER) == 0u) {
        out[i] = (float4)(0.0f);
        return;
    }
    float3 ray = camera_ray(cam, i % cam->width, i / cam->width);
    float footprint = pixel_footprint(g->depth, cam->width, cam->height, cam->tan_half_fov_x,
                                      cam->tan_half_fov_y);
    float area = pixel_surface_area(footprint, dot3(ray, load3g(cam->forward)),
                                    dot3(ray, load3(g->normal)));
    wide_t scale = saturate_wide((wide_t)p->flux_quantum / (WIDE_PI * (wide_t)area));
    wide_t n = join_u64_wide(t[8], t[9]);
    float4 l;
    l.x = (float)(saturate_wide(join_u64_wide(t[0], t[1]) * scale) * (wide_t)g->albedo[0]);
    l.y = (float)(saturate_wide(join_u64_wide(t[2], t[3]) * scale) * (wide_t)g->albedo[1]);
    l.z = (float)(saturate_wide(join_u64_wide(t[4], t[5]) * scale) * (wide_t)g->albedo[2]);
    l.w = (float)(join_u64_wide(t[6], t[7]) * (wide_t)p->hit_distance_quantum / n);
    out[i] = l;
}

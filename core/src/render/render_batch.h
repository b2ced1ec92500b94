/* render_batch.h -- the indirect phase's pixel batch (structure of arrays, padded to whole vector
 * lanes) and the kernels that add one VPL's shadow-mapped light to every pixel of it, one per
 * instruction set (isa.h): render_kernel.c (scalar, the reference), render_kernel_sse2.c (4
 * lanes) and render_kernel_avx2.c (8 lanes, FMA, gathered texels). Every kernel computes the
 * same formula in the same order and differs from the scalar one only by rounding (FMA, vector
 * square roots); test_isa bounds the difference. Internal to libiircore. */
#ifndef IIR_RENDER_BATCH_H
#define IIR_RENDER_BATCH_H

#include "iir/bsdf.h"
#include "iir/isa.h"
#include "iir/shadowmap.h"
#include "render_internal.h"

enum {
    IIR_BATCH = 256,     /* pixels per batch: 10 KB of stack */
    IIR_BATCH_LANES = 8, /* batches are padded to a multiple of this with never-lit pixels */
};

typedef struct iir_pixel_batch {
    int m;        /* pixels; the arrays are valid up to m rounded up to IIR_BATCH_LANES */
    uint32_t ord; /* where its pixels begin in their class's columns (gv_columns.h) */
    uint32_t index[IIR_BATCH];
    _Alignas(32) float px[IIR_BATCH], py[IIR_BATCH], pz[IIR_BATCH]; /* position */
    _Alignas(32) float nx[IIR_BATCH], ny[IIR_BATCH], nz[IIR_BATCH]; /* normal, facing the camera */
    _Alignas(32) float Ex[IIR_BATCH], Ey[IIR_BATCH], Ez[IIR_BATCH]; /* sum of power G V (times
                                                                        receiver) */
    /* Glossy receivers (full shading): bit l of glossy[q] marks pixel 8q + l, whose BSDF is
       bsdf[j] seen from wo[j]; its light is demodulated by demod[j] (iir_gb_demod). */
    uint8_t glossy[IIR_BATCH / 8];
    iir_bsdf bsdf[IIR_BATCH];
    iir_vec3 wo[IIR_BATCH], demod_pi[IIR_BATCH]; /* demod_pi: pi / demod */
} iir_pixel_batch;

/* m rounded up to whole lanes: how far the kernels step through a batch of m pixels. */
static inline int iir_batch_padded(int m)
{
    return (m + IIR_BATCH_LANES - 1) & ~(IIR_BATCH_LANES - 1);
}

static inline bool iir_batch_is_glossy(const iir_pixel_batch *b, int j)
{
    return (b->glossy[j >> 3] >> (j & 7)) & 1u;
}

/* What every lookup of one frame shares: the clamp of G (clamp / D^2, or INFINITY), the maps'
 * relative bias (sm_bias) and the map origins' lift (iir_rt_epsilon). */
typedef struct iir_kernel_args {
    float g_max, rel_bias, eps;
} iir_kernel_args;

/* A VPL's column of G V (gv_columns.h) as a kernel uses it: none (evaluate G V), write (evaluate
 * it and store it at col[b->ord + j] for batch pixel j < b->m) or read (take it from there). */
typedef enum { IIR_GV_NONE, IIR_GV_WRITE, IIR_GV_READ } iir_gv_mode;
typedef struct iir_gv_ref {
    float *col;
    iir_gv_mode mode;
} iir_gv_ref;

/* Adds power G V of VPLs v[0 .. count) (each map's visibility) to every pixel of the batch, up
 * to iir_batch_padded(b->m); gv[i] is VPL i's column (gv NULL: none). Only the AVX2 kernel takes
 * columns (the renderer uses them with it alone); the others require gv NULL. */
typedef void (*iir_smap_kernel)(const iir_kernel_args *a, const iir_shade_vpl *v,
                                const iir_gv_ref *gv, uint32_t count, iir_pixel_batch *b);

void iir_apply_smap_scalar(const iir_kernel_args *a, const iir_shade_vpl *v, const iir_gv_ref *gv,
                           uint32_t count, iir_pixel_batch *b);
void iir_apply_smap_sse2(const iir_kernel_args *a, const iir_shade_vpl *v, const iir_gv_ref *gv,
                         uint32_t count, iir_pixel_batch *b);
void iir_apply_smap_avx2(const iir_kernel_args *a, const iir_shade_vpl *v, const iir_gv_ref *gv,
                         uint32_t count, iir_pixel_batch *b);

/* The AVX2 kernel's sums for a run of m pixels whose every VPL of v[0 .. count) reads its column
 * (gv[i].mode IIR_GV_READ), none of them glossy nor any pixel: power G V from the columns from
 * ord on, into Ex, Ey, Ez (set, up to m rounded up to whole lanes, 0 beyond m; m <= IIR_BATCH)
 * -- the kernel's sums to the bit without its batch. */
void iir_columns_sum_avx2(const iir_shade_vpl *v, const iir_gv_ref *gv, uint32_t count,
                          uint32_t ord, int m, float *Ex, float *Ey, float *Ez);

/* A vector kernel's lanes j .. j + lanes - 1 with G V in g: those through a BSDF (a glossy pixel,
 * or every lane for a glossy VPL) are added by iir_batch_add_lit and zeroed in g; the caller adds
 * the rest as diffuse. */
void iir_batch_glossy_lanes(const iir_kernel_args *a, const iir_shade_vpl *v, iir_pixel_batch *b,
                            int j, float *g, int lanes);

/* The kernel for isa (one this build and CPU support: iir_isa_supported). */
iir_smap_kernel iir_smap_kernel_for(iir_isa isa);

/* render_indirect.c: adds power G (the clamped geometry term times visibility) of VPL v to batch
 * pixel j, through the pixel's BSDF when it is glossy and the VPL's lobe when that is; the
 * kernels hand such lanes over to it. */
void iir_batch_add_lit(iir_pixel_batch *b, int j, const iir_shade_vpl *v, float G, float g_max);

/* The geometry between a VPL and a pixel: w = x - p, its squared length, the cosines times d at
 * the VPL (ci) and at the pixel (cx), and the clamped geometry term. */
typedef struct iir_vpl_geometry {
    bool lit; /* both sides face each other at a distance; otherwise G is 0 */
    iir_vec3 w;
    float d2, ci, cx, G;
} iir_vpl_geometry;

/* The geometry for VPL v at x (normal n), G clamped to g_max. A virtual spherical light's falls
 * off as 1 / (d^2 + r^2): bounded by 1 / r^2 near it, a point's beyond (its own bound, no clamp
 * needed). */
static inline iir_vpl_geometry iir_vpl_geometry_at(const iir_shade_vpl *v, iir_vec3 x, iir_vec3 n,
                                                   float g_max)
{
    iir_vpl_geometry g = {.w = iir_sub(x, v->p)};
    g.d2 = iir_length_sq(g.w);
    g.ci = iir_dot(v->n, g.w);
    g.cx = -iir_dot(n, g.w);
    g.lit = g.ci > 0.f && g.cx > 0.f && g.d2 > 0.f;
    if (!g.lit) return g;
    float inv_d2 = 1.f / g.d2;
    float falloff = v->radius > 0.f ? 1.f / (g.d2 + v->radius * v->radius) : inv_d2;
    float G = g.ci * g.cx * inv_d2 * falloff;
    g.G = G < g_max ? G : g_max;
    return g;
}

#endif

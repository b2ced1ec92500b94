/* shadowmap.h -- VPL shadow maps: rendering a VPL's paraboloid depth map with Embree packets and
 * looking points up in it. Not the map's storage and lifetime (iir_smap in vpl.h) and not shading
 * (render.h).
 *
 * Layout (vpl.h): res x res half floats (half.h), row-major, row j holds v in [j/res, (j+1)/res),
 * column i holds u in [i/res, (i+1)/res); (u, v) is the paraboloid parametrisation of the
 * hemisphere about the VPL's normal in its frame (r, u, f = normal). Texel (i, j) stores the
 * distance from the map's origin (the VPL's position lifted by iir_rt_epsilon along its normal) to
 * the first surface along the direction of the texel centre, over the map's scale (iir_smap_scale),
 * +infinity where that ray escapes. Texel centres outside the unit disk of the parametrisation (the
 * corners) are traced along the horizon direction of their angle, so lookups near the horizon, and
 * the 2x2 filter there, read sensible depths. Half floats hold a depth to 2^-11 of itself, far
 * inside the bias below (0.005 of the distance at the least), and halve the bytes the shading loop
 * reads from maps that do not fit the caches (issue 31: 16 MB of float maps at 256 VPLs of 128^2).
 *
 * The paraboloid map is conformal: a texel subtends 2 (1 + cos theta) / res radians at polar angle
 * theta, from 4/res straight up to 2/res at the horizon.
 *
 * Bias model. A receiver x at distance d from the VPL, whose normal makes angle theta_x with the
 * direction back to the VPL, passes a texel's test when d - bias <= depth, with
 *     bias = eps + d b_rel + S d texel(theta) min(tan theta_x, T),
 *     S = IIR_SMAP_SLOPE_TEXELS (1.5), T = IIR_SMAP_MAX_SLOPE (8):
 * - eps: the map origin's lift along the VPL's normal (iir_rt_epsilon);
 * - b_rel (iir_indirect_params.sm_bias, a fraction of the distance, default 0.005): float error
 *   and curved or non-planar receivers. It is also the width of the gaps light leaks into: a
 *   receiver closer than b_rel d behind an occluder counts as lit;
 * - the slope term: a texel centre up to S texels from the query direction (the 2x2 footprint)
 *   meets the receiver's plane d * angle * tan theta_x nearer or further. It is capped at about
 *   83 degrees from the normal, where G (which carries cos theta_x) is nearly 0 and an unbounded
 *   bias would let light through anything.
 *
 * Too little bias shows as self-shadowing ("acne"), too much as light under objects that touch a
 * receiver. Measured on the Cornell box (64 VPLs from the spot, 192x144 pixels, every pixel-VPL
 * pair with G > 0, against exact rays): b_rel from 0 to 0.05 moves agreement by less than 0.2%,
 * since the slope term does the work, so the default stays small to keep gaps tight.
 *
 * Resolution trades rays and memory (res^2 rays and 2 res^2 bytes per VPL, paid once at its birth)
 * against the width of the band along shadow edges where the map is wrong (a texel at 2 m spans
 * 4 m / res to 8 m / res): at 64^2 98.2% of the pairs agree (G-weighted |V_map - V_ray| 1.2%),
 * at 128^2 98.8% (0.6%), at 256^2 98.9% (0.4%, the paper's size). Most of what remains at 256^2
 * are receivers beyond the slope cap, whose light is nearly 0.
 *
 * Filtering. Lookups use 2x2 percentage-closer filtering: the four texel centres around the query
 * are each tested and the results blended with bilinear weights, so visibility is a fraction in
 * [0, 1] and shadow edges are ramps, not texel staircases. Against a nearest-texel lookup (with its
 * footprint's smaller slope term) it raises agreement at 128^2 from 97.9% to 98.8%, for three more
 * loads per lookup (the renderer gathers them: render_batch.h). */
#ifndef IIR_SHADOWMAP_H
#define IIR_SHADOWMAP_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/half.h"
#include "iir/rt.h"
#include "iir/vecmath.h"
#include "iir/vpl.h"

#ifdef __cplusplus
extern "C" {
#endif

#define IIR_SMAP_MAX_RES 4096
#define IIR_SMAP_SLOPE_TEXELS 1.5f /* the PCF footprint reaches about 1.5 texels from the query */
#define IIR_SMAP_MAX_SLOPE 8.f     /* tan theta_x cap: about 83 degrees */

/* ---- rendering maps ---- */

/* The scale of every map of a scene whose ray epsilon is eps (iir_rt_epsilon): the least power of
 * two >= 8 eps. A scene's extent is at most 1e5 eps (rt.c), so a depth over the scale is at most
 * 12500, inside a half float's range, and at 2^-11 relative precision down to 1e-3 eps. */
static inline float iir_smap_scale(float eps)
{
    return exp2f(ceilf(log2f(8.f * eps)));
}

/* Texel (i, j) of map m as a distance (INFINITY where its ray escaped). */
static inline float iir_smap_depth_at(const iir_smap *m, int i, int j)
{
    return iir_half_to_float(m->depth[(size_t)j * (size_t)m->res + (size_t)i]) * m->scale;
}

/* A stamp no map rendering has had yet (thread-safe; never 0): what iir_smap.stamp says of the
 * texels a renderer last wrote, so that work derived from them (the renderer's per-pixel columns,
 * render/gv_columns.h) is reused only while they are the same. */
uint64_t iir_smap_next_stamp(void);

/* Renders v's map at res x res (1 <= res <= IIR_SMAP_MAX_RES): (re)allocates m->depth with malloc
 * when it has no texels or another resolution, then traces one ray per texel centre from the VPL's
 * position lifted by iir_rt_epsilon(rt) along its normal, 8 adjacent texels of a row per packet,
 * counted as IIR_RAYS_SHADOWMAP in *st (added; st may be NULL). v->frame must be set
 * (iir_vpl_set_normal). Returns false, with the map released (res 0), only when allocation fails.
 * m is usually &v->smap but need not be. Thread-safe for distinct maps. */
bool iir_smap_render(iir_smap *m, const iir_rt *rt, const iir_vpl *v, int res, iir_raystats *st);
/* The rays of texels i0 .. i0 + 7 of row j of a res x res map seen from org in frame fr (lanes at
 * i >= res invalid), with AVX2: only where iir_isa_supported(IIR_ISA_AVX2). The rays
 * iir_smap_render traces, to the bit. */
void iir_smap_texel_rays_avx2(const iir_frame *fr, iir_vec3 org, int i0, int j, int res,
                              iir_ray8 *rays);

/* Renders the maps of the non-null VPLs whose smap.res != res (new VPLs, or maps of another
 * resolution), in parallel over VPLs (OpenMP), adding the rays to *st (may be NULL). Null samples'
 * maps are left alone. Returns how many maps it rendered; a map whose allocation failed is left not
 * rendered (res 0) and is not counted, so a renderer using it reports the VPL as lacking a map. */
uint32_t iir_smaps_build(iir_vpl *vpls, uint32_t n, const iir_rt *rt, int res, iir_raystats *st);
/* The same, skipping the maps not yet begun once stop(ctx) returns true (stop may be NULL): the
 * caller then sees maps missing and builds them later (they are rendered, not-yet-rendered or
 * absent, never half-written). */
uint32_t iir_smaps_build_until(iir_vpl *vpls, uint32_t n, const iir_rt *rt, int res,
                               iir_raystats *st, iir_stop_fn stop, void *ctx);
/* A frame's maps within a budget of `full` maps at res (iir refilling its set at once): the VPLs
 * without a map get one at res while the budget lasts and at res / 4 (at least 8; a sixteenth of
 * the rays) beyond it, marked coarse; the budget left then renders coarse maps again at res --
 * each in array order, so the result does not depend on the threads. Returns the maps rendered. */
uint32_t iir_smaps_build_budget(iir_vpl *vpls, uint32_t n, const iir_rt *rt, int res, uint32_t full,
                                iir_raystats *st, iir_stop_fn stop, void *ctx);
/* The same for the VPLs that have no map at all (res 0): maps of another resolution are kept (the
 * frame-time controller's new resolution is for new VPLs; every lookup uses its map's own res). */
uint32_t iir_smaps_build_missing(iir_vpl *vpls, uint32_t n, const iir_rt *rt, int res,
                                 iir_raystats *st, iir_stop_fn stop, void *ctx);

/* ---- looking points up ---- */

/* The bias (world distance) for a receiver at distance d, whose direction from the VPL has local z
 * component dz (cosine at the VPL), and with tan_x the tangent of the angle between the receiver's
 * normal and the direction back to the VPL. eps is the map origin's offset (iir_rt_epsilon). */
static inline float iir_smap_bias(float d, float dz, float tan_x, int res, float rel_bias,
                                  float eps)
{
    float texel = 2.f * (1.f + dz) / (float)res;
    float slope = tan_x < IIR_SMAP_MAX_SLOPE ? tan_x : IIR_SMAP_MAX_SLOPE; /* NaN: the cap */
    return eps + d * (rel_bias + IIR_SMAP_SLOPE_TEXELS * texel * slope);
}

/* A map prepared for many lookups: the per-map constants, computed once (iir_smap_probe_make)
 * and kept out of the caller's loop over receivers. */
typedef struct iir_smap_probe {
    const uint16_t *depth; /* half floats (half.h) */
    float inv_scale;       /* 1 / the map's scale: a distance in the map's units */
    int res;
    float half_res; /* res / 2: the paraboloid's scale */
    float max_st;   /* res - 1: the last texel centre */
    float texel;    /* 2 / res: texel angle over (1 + cos theta) */
    float rel_bias; /* the caller's constant bias, a fraction of the distance */
    float eps;      /* the map origin's lift (iir_rt_epsilon) */
} iir_smap_probe;

static inline iir_smap_probe iir_smap_probe_make(const iir_smap *m, float rel_bias, float eps)
{
    iir_smap_probe p;
    p.depth = m->depth;
    p.inv_scale = 1.f / m->scale; /* exact: a power of two */
    p.res = m->res;
    p.half_res = 0.5f * (float)m->res;
    p.max_st = (float)m->res - 1.f;
    p.texel = 2.f / (float)m->res;
    p.rel_bias = rel_bias;
    p.eps = eps;
    return p;
}

/* 2x2 PCF at texel-space point (s, t), texel centres at integers (s = u res - 1/2): the fraction
 * of the four texels around it, bilinearly weighted, whose depth is at least dist_minus_bias (in
 * the map's units: over its scale). Points beyond the outer texel centres take the border texels
 * (s, t clamped). */
static inline float iir_smap_pcf(const iir_smap_probe *p, float s, float t, float dist_minus_bias)
{
    s = s > 0.f ? (s < p->max_st ? s : p->max_st) : 0.f; /* NaN: 0 */
    t = t > 0.f ? (t < p->max_st ? t : p->max_st) : 0.f;
    int i0 = (int)s, j0 = (int)t;
    float fx = s - (float)i0, fy = t - (float)j0;
    int di = i0 + 1 < p->res, dj = j0 + 1 < p->res;
    const uint16_t *row0 = p->depth + (size_t)j0 * (size_t)p->res;
    const uint16_t *row1 = row0 + (size_t)dj * (size_t)p->res;
    float v00 = dist_minus_bias <= iir_half_to_float(row0[i0]) ? 1.f : 0.f;
    float v10 = dist_minus_bias <= iir_half_to_float(row0[i0 + di]) ? 1.f : 0.f;
    float v01 = dist_minus_bias <= iir_half_to_float(row1[i0]) ? 1.f : 0.f;
    float v11 = dist_minus_bias <= iir_half_to_float(row1[i0 + di]) ? 1.f : 0.f;
    float top = v00 + fx * (v10 - v00), bottom = v01 + fx * (v11 - v01);
    return top + fy * (bottom - top);
}

/* Visibility in [0, 1] of a receiver from its geometry in the VPL's frame: (wx, wy, wz) = x - p
 * (wz > 0), d = |x - p|, cx = -n_x . (x - p), the receiver's cosine times d (a receiver facing
 * away, cx <= 0, gets the capped slope). The bias model above, arranged for the pixel loop: one
 * division and two square roots per lookup. */
static inline float iir_smap_probe_visibility(const iir_smap_probe *p, float wx, float wy, float wz,
                                              float d, float cx)
{
    cx = cx > 1e-6f * d ? cx : 1e-6f * d;
    float sin_d = iir_safe_sqrt(d * d - cx * cx); /* sin theta_x times d */
    float inv = 1.f / ((d + wz) * cx);
    float k = p->half_res * cx * inv;     /* res / 2 / (d + wz) */
    float tan_x = sin_d * (d + wz) * inv; /* sin_d / cx */
    float slope = tan_x < IIR_SMAP_MAX_SLOPE ? tan_x : IIR_SMAP_MAX_SLOPE;
    float texel_d = (d + wz) * p->texel; /* d times the texel angle 2 (1 + dz) / res */
    float bias = p->eps + d * p->rel_bias + IIR_SMAP_SLOPE_TEXELS * texel_d * slope;
    float c = p->half_res - 0.5f;
    return iir_smap_pcf(p, wx * k + c, wy * k + c, (d - bias) * p->inv_scale);
}

/* Visibility in [0, 1] of point x (receiver normal n_x, unit) from VPL v through map m, with the
 * bias model above (rel_bias a fraction of the distance, eps = iir_rt_epsilon). Points behind the
 * VPL's surface (or at its position) get 0; a receiver facing away gets the capped slope. The map
 * must be rendered. */
static inline float iir_smap_visibility(const iir_smap *m, const iir_vpl *v, iir_vec3 x,
                                        iir_vec3 n_x, float rel_bias, float eps)
{
    iir_vec3 w = iir_sub(x, v->position);
    float d2 = iir_length_sq(w), wz = iir_dot(w, v->frame.f);
    if (!(wz > 0.f) || !(d2 > 0.f)) return 0.f;
    iir_smap_probe p = iir_smap_probe_make(m, rel_bias, eps);
    return iir_smap_probe_visibility(&p, iir_dot(w, v->frame.r), iir_dot(w, v->frame.u), wz,
                                     sqrtf(d2), -iir_dot(n_x, w));
}

#ifdef __cplusplus
}
#endif
#endif

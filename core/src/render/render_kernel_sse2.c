/* render_kernel_sse2.c -- the shadow-map kernel of the VPL sum 4 pixels a step with SSE2, part of
 * every x86-64 CPU (render_batch.h): the texel loads are scalar (SSE2 has no gather). */
#include "render_batch.h"

#include <assert.h>

#if defined(__x86_64__)
#include <emmintrin.h>

/* 4 lanes of a + b * c. */
static inline __m128 madd4(__m128 a, __m128 b, __m128 c)
{
    return _mm_add_ps(a, _mm_mul_ps(b, c));
}
static inline __m128 dot4(__m128 ax, __m128 ay, __m128 az, __m128 bx, __m128 by, __m128 bz)
{
    return madd4(madd4(_mm_mul_ps(ax, bx), ay, by), az, bz);
}

/* iir_half_to_float for 4 lanes (non-negative halves in 32-bit lanes): exact. */
static inline __m128 half_to_float4(__m128i h)
{
    __m128i inf = _mm_set1_epi32(IIR_HALF_INF);
    __m128 is_inf = _mm_castsi128_ps(_mm_cmpeq_epi32(_mm_and_si128(h, inf), inf));
    __m128i bits = _mm_slli_epi32(_mm_and_si128(h, _mm_set1_epi32(0x7fff)), 13);
    __m128 f = _mm_mul_ps(_mm_castsi128_ps(bits), _mm_set1_ps(0x1p112f));
    return _mm_or_ps(_mm_andnot_ps(is_inf, f), _mm_and_ps(is_inf, _mm_set1_ps(INFINITY)));
}

/* iir_smap_pcf for 4 lanes: the texel loads are scalar (SSE2 has no gather). */
static inline __m128 pcf4(const iir_smap_probe *p, __m128 s, __m128 t, __m128 dmb)
{
    __m128i i0 = _mm_cvttps_epi32(s), j0 = _mm_cvttps_epi32(t);
    __m128 fx = _mm_sub_ps(s, _mm_cvtepi32_ps(i0)), fy = _mm_sub_ps(t, _mm_cvtepi32_ps(j0));
    _Alignas(16) int32_t is[4], js[4];
    _Alignas(16) int32_t d00[4], d10[4], d01[4], d11[4];
    _mm_store_si128((__m128i *)is, i0);
    _mm_store_si128((__m128i *)js, j0);
    for (int l = 0; l < 4; l++) {
        int di = is[l] + 1 < p->res, dj = js[l] + 1 < p->res;
        const uint16_t *row0 = p->depth + (size_t)js[l] * (size_t)p->res;
        const uint16_t *row1 = row0 + (size_t)dj * (size_t)p->res;
        d00[l] = row0[is[l]], d10[l] = row0[is[l] + di];
        d01[l] = row1[is[l]], d11[l] = row1[is[l] + di];
    }
    __m128 one = _mm_set1_ps(1.f);
#define PASSES(d) _mm_and_ps(_mm_cmple_ps(dmb, half_to_float4(_mm_load_si128((__m128i *)d))), one)
    __m128 v00 = PASSES(d00), v10 = PASSES(d10), v01 = PASSES(d01), v11 = PASSES(d11);
#undef PASSES
    __m128 top = madd4(v00, fx, _mm_sub_ps(v10, v00)),
           bottom = madd4(v01, fx, _mm_sub_ps(v11, v01));
    return madd4(top, fy, _mm_sub_ps(bottom, top));
}

/* iir_smap_probe_visibility for 4 lanes (keep the two in step): the bias model of shadowmap.h and
 * the texel-space point, then pcf4. wx, wy, wz: x - p in the VPL's frame; cx as there. */
static inline __m128 visibility4(const iir_smap_probe *p, __m128 wx, __m128 wy, __m128 wz,
                                 __m128 d2, __m128 cx)
{
    __m128 zero = _mm_setzero_ps(), d = _mm_sqrt_ps(d2);
    cx = _mm_max_ps(cx, _mm_mul_ps(_mm_set1_ps(1e-6f), d));
    __m128 sin_d = _mm_sqrt_ps(_mm_max_ps(zero, _mm_sub_ps(d2, _mm_mul_ps(cx, cx))));
    __m128 dwz = _mm_add_ps(d, wz), inv = _mm_div_ps(_mm_set1_ps(1.f), _mm_mul_ps(dwz, cx));
    __m128 k = _mm_mul_ps(_mm_set1_ps(p->half_res), _mm_mul_ps(cx, inv));
    __m128 slope =
        _mm_min_ps(_mm_mul_ps(sin_d, _mm_mul_ps(dwz, inv)), _mm_set1_ps(IIR_SMAP_MAX_SLOPE));
    __m128 texel_d = _mm_mul_ps(dwz, _mm_set1_ps(p->texel));
    __m128 bias = madd4(madd4(_mm_set1_ps(p->eps), d, _mm_set1_ps(p->rel_bias)),
                        _mm_mul_ps(_mm_set1_ps(IIR_SMAP_SLOPE_TEXELS), texel_d), slope);
    /* Clamped with max first: a NaN (a masked-out lane) becomes 0, a valid texel. */
    __m128 c = _mm_set1_ps(p->half_res - 0.5f), hi = _mm_set1_ps(p->max_st);
    __m128 s = _mm_min_ps(_mm_max_ps(madd4(c, wx, k), zero), hi);
    __m128 t = _mm_min_ps(_mm_max_ps(madd4(c, wy, k), zero), hi);
    return pcf4(p, s, t, _mm_mul_ps(_mm_sub_ps(d, bias), _mm_set1_ps(p->inv_scale)));
}

/* Adds the glossy lanes of pixels j..j+3 (GV: their G V; every lane for a glossy VPL) through
 * the BSDFs; returns GV with those lanes zeroed (the others are added as diffuse). */
static __m128 glossy_lanes(const iir_kernel_args *a, const iir_shade_vpl *v, iir_pixel_batch *b,
                           int j, __m128 GV)
{
    _Alignas(16) float g[4];
    _mm_store_ps(g, GV);
    iir_batch_glossy_lanes(a, v, b, j, g, 4);
    return _mm_load_ps(g);
}

static void apply_one(const iir_kernel_args *a, const iir_shade_vpl *v, iir_pixel_batch *b)
{
    iir_smap_probe probe = iir_smap_probe_make(v->smap, a->rel_bias, a->eps);
    __m128 zero = _mm_setzero_ps(), g_max = _mm_set1_ps(a->g_max), one = _mm_set1_ps(1.f);
    __m128 vx = _mm_set1_ps(v->p.x), vy = _mm_set1_ps(v->p.y), vz = _mm_set1_ps(v->p.z);
    __m128 nx = _mm_set1_ps(v->n.x), ny = _mm_set1_ps(v->n.y), nz = _mm_set1_ps(v->n.z);
    __m128 rx = _mm_set1_ps(v->r.x), ry = _mm_set1_ps(v->r.y), rz = _mm_set1_ps(v->r.z);
    __m128 ux = _mm_set1_ps(v->u.x), uy = _mm_set1_ps(v->u.y), uz = _mm_set1_ps(v->u.z);
    bool sphere = v->radius > 0.f; /* iir_vpl_geometry_at's falloff */
    __m128 r2 = _mm_set1_ps(v->radius * v->radius);
    int end = iir_batch_padded(b->m);
    for (int j = 0; j < end; j += 4) {
        __m128 wx = _mm_sub_ps(_mm_load_ps(b->px + j), vx);
        __m128 wy = _mm_sub_ps(_mm_load_ps(b->py + j), vy);
        __m128 wz = _mm_sub_ps(_mm_load_ps(b->pz + j), vz);
        __m128 d2 = dot4(wx, wy, wz, wx, wy, wz), ci = dot4(nx, ny, nz, wx, wy, wz);
        __m128 cx = _mm_sub_ps(zero, dot4(_mm_load_ps(b->nx + j), _mm_load_ps(b->ny + j),
                                          _mm_load_ps(b->nz + j), wx, wy, wz));
        __m128 lit = _mm_and_ps(_mm_and_ps(_mm_cmpgt_ps(ci, zero), _mm_cmpgt_ps(cx, zero)),
                                _mm_cmpgt_ps(d2, zero));
        if (!_mm_movemask_ps(lit)) continue;
        __m128 inv_d2 = _mm_div_ps(one, d2);
        __m128 falloff = sphere ? _mm_div_ps(one, _mm_add_ps(d2, r2)) : inv_d2;
        __m128 G = _mm_min_ps(_mm_mul_ps(_mm_mul_ps(ci, cx), _mm_mul_ps(inv_d2, falloff)), g_max);
        __m128 V = visibility4(&probe, dot4(rx, ry, rz, wx, wy, wz), dot4(ux, uy, uz, wx, wy, wz),
                               ci, d2, cx);
        __m128 GV = _mm_and_ps(lit, _mm_mul_ps(G, V));
        if (((b->glossy[j >> 3] >> (j & 4)) & 0xf) || v->glossy) GV = glossy_lanes(a, v, b, j, GV);
        _mm_store_ps(b->Ex + j, madd4(_mm_load_ps(b->Ex + j), _mm_set1_ps(v->power.x), GV));
        _mm_store_ps(b->Ey + j, madd4(_mm_load_ps(b->Ey + j), _mm_set1_ps(v->power.y), GV));
        _mm_store_ps(b->Ez + j, madd4(_mm_load_ps(b->Ez + j), _mm_set1_ps(v->power.z), GV));
    }
}

void iir_apply_smap_sse2(const iir_kernel_args *a, const iir_shade_vpl *v, const iir_gv_ref *gv,
                         uint32_t count, iir_pixel_batch *b)
{
    assert(!gv && "the SSE2 kernel takes no columns");
    (void)gv;
    for (uint32_t i = 0; i < count; i++) apply_one(a, &v[i], b);
}

#endif

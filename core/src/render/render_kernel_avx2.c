/* render_kernel_avx2.c -- the shadow-map kernel of the VPL sum 8 pixels a step with AVX2 and FMA
 * (render_batch.h), its four PCF texels (half floats) fetched by one 32-bit gather per row. Built
 * with -mavx2 -mfma (CMakeLists) and called only where iir_isa_supported(IIR_ISA_AVX2). */
#include "render_batch.h"

#if defined(__x86_64__)
#include <immintrin.h>

static inline __m256 dot8(__m256 ax, __m256 ay, __m256 az, __m256 bx, __m256 by, __m256 bz)
{
    return _mm256_fmadd_ps(az, bz, _mm256_fmadd_ps(ay, by, _mm256_mul_ps(ax, bx)));
}

/* 1 where dmb <= depth, else 0. */
static inline __m256 passes(__m256 dmb, __m256 depth)
{
    return _mm256_and_ps(_mm256_cmp_ps(dmb, depth, _CMP_LE_OQ), _mm256_set1_ps(1.f));
}

/* Texels idx and idx + 1 of depth (a row's neighbours) at 8 lanes as floats, two half texels a
 * gathered 32-bit load: *left the first of each pair, *right the second. */
static inline void texel_pairs(const uint16_t *depth, __m256i idx, __m256 *left, __m256 *right)
{
    __m256i x = _mm256_i32gather_epi32((const int *)(const void *)depth, idx, 2);
    __m256i lo = _mm256_and_si256(x, _mm256_set1_epi32(0xffff)), hi = _mm256_srli_epi32(x, 16);
    /* packed: lo 0-3, hi 0-3 | lo 4-7, hi 4-7; permuted: lo 0-7 | hi 0-7 */
    __m256i halves = _mm256_permute4x64_epi64(_mm256_packus_epi32(lo, hi), 0xd8);
    *left = _mm256_cvtph_ps(_mm256_castsi256_si128(halves));
    *right = _mm256_cvtph_ps(_mm256_extracti128_si256(halves, 1));
}

/* The 2x2 PCF footprint's corner texel (i0, j0) at 8 lanes (s, t already clamped to [0, max_st])
 * as a texel index, and the blend weights fx, fy. The corner is kept off the last row and column:
 * there the weight of the texel beyond is 1 instead of the scalar path's 0 on the texel before,
 * the same blend of 0s and 1s exactly. */
static inline __m256i corner8(const iir_smap_probe *p, __m256 s, __m256 t, __m256 *fx, __m256 *fy)
{
    __m256i last = _mm256_set1_epi32(p->res - 2);
    __m256i i0 = _mm256_min_epi32(_mm256_cvttps_epi32(s), last);
    __m256i j0 = _mm256_min_epi32(_mm256_cvttps_epi32(t), last);
    *fx = _mm256_sub_ps(s, _mm256_cvtepi32_ps(i0));
    *fy = _mm256_sub_ps(t, _mm256_cvtepi32_ps(j0));
    return _mm256_add_epi32(_mm256_mullo_epi32(j0, _mm256_set1_epi32(p->res)), i0);
}

/* iir_smap_pcf for 8 lanes (s, t already clamped to [0, max_st]). */
static inline __m256 pcf8(const iir_smap_probe *p, __m256 s, __m256 t, __m256 dmb)
{
    __m256 fx, fy;
    __m256i at = corner8(p, s, t, &fx, &fy);
    __m256 d00, d10, d01, d11;
    texel_pairs(p->depth, at, &d00, &d10);
    texel_pairs(p->depth, _mm256_add_epi32(at, _mm256_set1_epi32(p->res)), &d01, &d11);
    __m256 v00 = passes(dmb, d00), v10 = passes(dmb, d10);
    __m256 v01 = passes(dmb, d01), v11 = passes(dmb, d11);
    __m256 top = _mm256_fmadd_ps(fx, _mm256_sub_ps(v10, v00), v00);
    __m256 bottom = _mm256_fmadd_ps(fx, _mm256_sub_ps(v11, v01), v01);
    return _mm256_fmadd_ps(fy, _mm256_sub_ps(bottom, top), top);
}

/* iir_smap_probe_visibility for 8 lanes up to the lookup (keep the two in step): the bias model
 * of shadowmap.h and the texel-space point (s, t) with the distance minus the bias, dmb; pcf8
 * then gives the visibility. */
static inline void lookup8(const iir_smap_probe *p, __m256 wx, __m256 wy, __m256 wz, __m256 d2,
                           __m256 cx, __m256 *s, __m256 *t, __m256 *dmb)
{
    __m256 zero = _mm256_setzero_ps(), d = _mm256_sqrt_ps(d2);
    cx = _mm256_max_ps(cx, _mm256_mul_ps(_mm256_set1_ps(1e-6f), d));
    __m256 sin_d = _mm256_sqrt_ps(_mm256_max_ps(zero, _mm256_fnmadd_ps(cx, cx, d2)));
    __m256 dwz = _mm256_add_ps(d, wz);
    __m256 inv = _mm256_div_ps(_mm256_set1_ps(1.f), _mm256_mul_ps(dwz, cx));
    __m256 k = _mm256_mul_ps(_mm256_set1_ps(p->half_res), _mm256_mul_ps(cx, inv));
    __m256 slope = _mm256_min_ps(_mm256_mul_ps(sin_d, _mm256_mul_ps(dwz, inv)),
                                 _mm256_set1_ps(IIR_SMAP_MAX_SLOPE));
    __m256 texel_d = _mm256_mul_ps(dwz, _mm256_set1_ps(p->texel));
    __m256 bias =
        _mm256_fmadd_ps(_mm256_mul_ps(_mm256_set1_ps(IIR_SMAP_SLOPE_TEXELS), texel_d), slope,
                        _mm256_fmadd_ps(d, _mm256_set1_ps(p->rel_bias), _mm256_set1_ps(p->eps)));
    /* Clamped with max first: a NaN (a masked-out lane) becomes 0, a valid texel. */
    __m256 c = _mm256_set1_ps(p->half_res - 0.5f), hi = _mm256_set1_ps(p->max_st);
    *s = _mm256_min_ps(_mm256_max_ps(_mm256_fmadd_ps(wx, k, c), zero), hi);
    *t = _mm256_min_ps(_mm256_max_ps(_mm256_fmadd_ps(wy, k, c), zero), hi);
    *dmb = _mm256_mul_ps(_mm256_sub_ps(d, bias), _mm256_set1_ps(p->inv_scale));
}

/* Asks for the cache lines of the two texel rows pcf8 will read at (s, t). */
static inline void prefetch8(const iir_smap_probe *p, __m256 s, __m256 t)
{
    __m256 fx, fy;
    _Alignas(32) int32_t at[8];
    _mm256_store_si256((__m256i *)at, corner8(p, s, t, &fx, &fy));
    for (int l = 0; l < 8; l++) {
        _mm_prefetch((const char *)(p->depth + at[l]), _MM_HINT_T0);
        _mm_prefetch((const char *)(p->depth + at[l] + p->res), _MM_HINT_T0);
    }
}

/* Adds the glossy lanes of pixels j..j+7 (GV: their G V; every lane for a glossy VPL) through
 * the BSDFs; returns GV with those lanes zeroed (the others are added as diffuse). */
static __m256 glossy_lanes(const iir_kernel_args *a, const iir_shade_vpl *v, iir_pixel_batch *b,
                           int j, __m256 GV)
{
    _Alignas(32) float g[8];
    _mm256_store_ps(g, GV);
    iir_batch_glossy_lanes(a, v, b, j, g, 8);
    return _mm256_load_ps(g);
}

/* One VPL's geometry pass: G (0 on unlit lanes), each lane's texel-space point and distance minus
 * bias, and which 8-lane groups have a lit lane; the texels' cache lines are asked for as it goes
 * (the maps do not fit the caches: waiting for each gather's lines would bound the kernel). */
typedef struct lookups {
    _Alignas(32) float S[IIR_BATCH], T[IIR_BATCH], DMB[IIR_BATCH], G[IIR_BATCH];
    uint8_t any[IIR_BATCH / 8];
} lookups;

static void geometry_pass(const iir_kernel_args *a, const iir_shade_vpl *v,
                          const iir_pixel_batch *b, lookups *L)
{
    iir_smap_probe probe = iir_smap_probe_make(v->smap, a->rel_bias, a->eps);
    __m256 zero = _mm256_setzero_ps(), g_max = _mm256_set1_ps(a->g_max), one = _mm256_set1_ps(1.f);
    __m256 vx = _mm256_set1_ps(v->p.x), vy = _mm256_set1_ps(v->p.y), vz = _mm256_set1_ps(v->p.z);
    __m256 nx = _mm256_set1_ps(v->n.x), ny = _mm256_set1_ps(v->n.y), nz = _mm256_set1_ps(v->n.z);
    __m256 rx = _mm256_set1_ps(v->r.x), ry = _mm256_set1_ps(v->r.y), rz = _mm256_set1_ps(v->r.z);
    __m256 ux = _mm256_set1_ps(v->u.x), uy = _mm256_set1_ps(v->u.y), uz = _mm256_set1_ps(v->u.z);
    bool sphere = v->radius > 0.f; /* iir_vpl_geometry_at's falloff */
    __m256 r2 = _mm256_set1_ps(v->radius * v->radius);
    for (int j = 0, end = iir_batch_padded(b->m); j < end; j += 8) {
        __m256 wx = _mm256_sub_ps(_mm256_load_ps(b->px + j), vx);
        __m256 wy = _mm256_sub_ps(_mm256_load_ps(b->py + j), vy);
        __m256 wz = _mm256_sub_ps(_mm256_load_ps(b->pz + j), vz);
        __m256 d2 = dot8(wx, wy, wz, wx, wy, wz), ci = dot8(nx, ny, nz, wx, wy, wz);
        __m256 cx = _mm256_sub_ps(zero, dot8(_mm256_load_ps(b->nx + j), _mm256_load_ps(b->ny + j),
                                             _mm256_load_ps(b->nz + j), wx, wy, wz));
        __m256 lit = _mm256_and_ps(
            _mm256_and_ps(_mm256_cmp_ps(ci, zero, _CMP_GT_OQ), _mm256_cmp_ps(cx, zero, _CMP_GT_OQ)),
            _mm256_cmp_ps(d2, zero, _CMP_GT_OQ));
        L->any[j >> 3] = _mm256_movemask_ps(lit) != 0;
        if (!L->any[j >> 3]) continue;
        __m256 inv_d2 = _mm256_div_ps(one, d2);
        __m256 falloff = sphere ? _mm256_div_ps(one, _mm256_add_ps(d2, r2)) : inv_d2;
        __m256 g = _mm256_min_ps(
            _mm256_mul_ps(_mm256_mul_ps(ci, cx), _mm256_mul_ps(inv_d2, falloff)), g_max);
        _mm256_store_ps(L->G + j, _mm256_and_ps(lit, g));
        __m256 s, t, dmb;
        lookup8(&probe, dot8(rx, ry, rz, wx, wy, wz), dot8(ux, uy, uz, wx, wy, wz), ci, d2, cx, &s,
                &t, &dmb);
        prefetch8(&probe, s, t);
        _mm256_store_ps(L->S + j, s), _mm256_store_ps(L->T + j, t);
        _mm256_store_ps(L->DMB + j, dmb);
    }
}

/* Lanes j.. of the batch (those below b->m) of a column at col (the batch's first pixel's). */
static inline __m256i below_m(const iir_pixel_batch *b, int j)
{
    __m256i lane =
        _mm256_add_epi32(_mm256_set1_epi32(j), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    return _mm256_cmpgt_epi32(_mm256_set1_epi32(b->m), lane);
}
static inline void store_column(float *col, const iir_pixel_batch *b, int j, __m256 GV)
{
    if (j + 8 <= b->m)
        _mm256_storeu_ps(col + j, GV);
    else
        _mm256_maskstore_ps(col + j, below_m(b, j), GV);
}
static inline __m256 load_column(const float *col, const iir_pixel_batch *b, int j)
{
    return j + 8 <= b->m ? _mm256_loadu_ps(col + j) : _mm256_maskload_ps(col + j, below_m(b, j));
}

/* Power times G V (lanes j..j+7) into the batch, the glossy lanes through their BSDFs. */
static inline void add_power(const iir_kernel_args *a, const iir_shade_vpl *v, iir_pixel_batch *b,
                             int j, __m256 GV)
{
    if (b->glossy[j >> 3] || v->glossy) GV = glossy_lanes(a, v, b, j, GV);
    _mm256_store_ps(b->Ex + j,
                    _mm256_fmadd_ps(_mm256_set1_ps(v->power.x), GV, _mm256_load_ps(b->Ex + j)));
    _mm256_store_ps(b->Ey + j,
                    _mm256_fmadd_ps(_mm256_set1_ps(v->power.y), GV, _mm256_load_ps(b->Ey + j)));
    _mm256_store_ps(b->Ez + j,
                    _mm256_fmadd_ps(_mm256_set1_ps(v->power.z), GV, _mm256_load_ps(b->Ez + j)));
}

/* One VPL's lookups (its geometry pass in L): power G V into the batch, and G V into its column
 * when col is not NULL (0 where no lane is lit). */
static void lookup_pass(const iir_kernel_args *a, const iir_shade_vpl *v, iir_pixel_batch *b,
                        const lookups *L, float *col)
{
    iir_smap_probe probe = iir_smap_probe_make(v->smap, a->rel_bias, a->eps);
    for (int j = 0, end = iir_batch_padded(b->m); j < end; j += 8) {
        if (!L->any[j >> 3]) {
            if (col) store_column(col, b, j, _mm256_setzero_ps());
            continue;
        }
        __m256 V = pcf8(&probe, _mm256_load_ps(L->S + j), _mm256_load_ps(L->T + j),
                        _mm256_load_ps(L->DMB + j));
        __m256 GV = _mm256_mul_ps(_mm256_load_ps(L->G + j), V); /* G is 0 on unlit lanes */
        if (col) store_column(col, b, j, GV);
        add_power(a, v, b, j, GV);
    }
}

/* One VPL's G V read from its column: the same sums as lookup_pass's (a group of 0s adds
 * nothing either way). */
static void column_pass(const iir_kernel_args *a, const iir_shade_vpl *v, iir_pixel_batch *b,
                        const float *col)
{
    for (int j = 0, end = iir_batch_padded(b->m); j < end; j += 8) {
        __m256 GV = load_column(col, b, j);
        if (_mm256_movemask_ps(_mm256_cmp_ps(GV, _mm256_setzero_ps(), _CMP_NEQ_UQ)))
            add_power(a, v, b, j, GV);
    }
}

/* Floats ahead that the columns' sum asks for (4 lines): a tile's piece of a column is a short
 * stream, a subset's VPLs read side by side -- more streams than the prefetchers follow, the loads
 * otherwise waiting on memory (at 1024x768 the columns, 48 MB, are beyond the caches). */
enum { COLUMN_AHEAD = 64 };

/* Pixels j .. j + 8 G - 1 of the columns' sum (G = 2: whole groups; G = 1: the last group, its
 * lanes from m on 0), the G groups at once: each VPL's broadcasts shared, 3 G chains of fused
 * products in flight. */
static inline __attribute__((always_inline)) void
columns_sum_groups(const iir_shade_vpl *v, const iir_gv_ref *gv, uint32_t count, uint32_t ord,
                   int j, int m, float *E[3], int G)
{
    __m256i in =
        _mm256_cmpgt_epi32(_mm256_set1_epi32(m - j), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    __m256 s[2][3];
    for (int g = 0; g < G; g++) s[g][0] = s[g][1] = s[g][2] = _mm256_setzero_ps();
    for (uint32_t i = 0; i < count; i++) {
        const float *col = gv[i].col + ord + j;
        if (G == 2) _mm_prefetch((const char *)(col + COLUMN_AHEAD), _MM_HINT_T0);
        __m256 p[3] = {_mm256_set1_ps(v[i].power.x), _mm256_set1_ps(v[i].power.y),
                       _mm256_set1_ps(v[i].power.z)};
        for (int g = 0; g < G; g++) {
            __m256 GV =
                G == 2 || j + 8 <= m ? _mm256_loadu_ps(col + 8 * g) : _mm256_maskload_ps(col, in);
            for (int q = 0; q < 3; q++) s[g][q] = _mm256_fmadd_ps(p[q], GV, s[g][q]);
        }
    }
    for (int g = 0; g < G; g++)
        for (int q = 0; q < 3; q++) _mm256_storeu_ps(E[q] + j + 8 * g, s[g][q]);
}

void iir_columns_sum_avx2(const iir_shade_vpl *v, const iir_gv_ref *gv, uint32_t count,
                          uint32_t ord, int m, float *Ex, float *Ey, float *Ez)
{
    float *E[3] = {Ex, Ey, Ez};
    int j = 0;
    for (; j + 16 <= m; j += 16) columns_sum_groups(v, gv, count, ord, j, m, E, 2);
    for (; j < m; j += 8) columns_sum_groups(v, gv, count, ord, j, m, E, 1);
}

/* Software-pipelined over the VPLs: VPL i's geometry pass (asking for its texels) runs before VPL
 * i - 1's lookups, so each VPL's lines have a whole pass's time to arrive; a VPL whose column is
 * read waits for the one before it, so that every pixel adds the VPLs in their order. */
void iir_apply_smap_avx2(const iir_kernel_args *a, const iir_shade_vpl *v, const iir_gv_ref *gv,
                         uint32_t count, iir_pixel_batch *b)
{
    lookups L[2];
    int cur = 0;
    const iir_shade_vpl *pending = NULL; /* its geometry pass is in L[1 - cur] */
    float *pending_col = NULL;
    for (uint32_t i = 0; i < count; i++) {
        iir_gv_mode mode = gv ? gv[i].mode : IIR_GV_NONE;
        if (v[i].smap->res < 2) { /* pcf8's footprint needs two texels a side (no column) */
            iir_apply_smap_scalar(a, &v[i], NULL, 1, b);
            continue;
        }
        if (mode == IIR_GV_READ) {
            if (pending) lookup_pass(a, pending, b, &L[1 - cur], pending_col);
            pending = NULL;
            column_pass(a, &v[i], b, gv[i].col + b->ord);
            continue;
        }
        geometry_pass(a, &v[i], b, &L[cur]);
        if (pending) lookup_pass(a, pending, b, &L[1 - cur], pending_col);
        pending = &v[i];
        pending_col = mode == IIR_GV_WRITE ? gv[i].col + b->ord : NULL;
        cur = 1 - cur;
    }
    if (pending) lookup_pass(a, pending, b, &L[1 - cur], pending_col);
}

#endif

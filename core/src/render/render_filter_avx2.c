/* render_filter_avx2.c -- the full-shading filter's row and column passes 8 pixels a step with AVX2
 * (render_internal.h: iir_filter_lanes): the scalar passes of render_filter.c with every tap's
 * product and sum in the same order and without FMA (this file is built with -mavx2 alone), so
 * the image is the same bit for bit. The row pass writes its sums and weights as four planes
 * (x, y, z, w) where the scalar one writes iir_filter_row structs. Called only where the CPU has
 * AVX2. */
#include "render_internal.h"

#if defined(__x86_64__)
#include <immintrin.h>

#include "render_lanes_avx2.h"

enum { CHUNK = 256 }; /* pixels of a row a step of the row pass converts to planes */

/* Lanes x .. x + 7 below `end`, as a mask for maskload/maskstore. */
static inline __m256i lanes_below(int x, int end)
{
    __m256i idx = _mm256_add_epi32(_mm256_set1_epi32(x), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    return _mm256_cmpgt_epi32(_mm256_set1_epi32(end), idx);
}

/* The weight of tap d at 8 centres: tap_weight(d) where bit `bit` of their masks is set (and, in
 * the row pass, the tap's subset has VPLs: `live`), else 0. */
static inline __m256 tap_weights(__m256i masks, int bit, float w)
{
    __m256i b = _mm256_set1_epi32((int)(1u << bit));
    __m256 similar = _mm256_castsi256_ps(_mm256_cmpeq_epi32(_mm256_and_si256(masks, b), b));
    return _mm256_and_ps(similar, _mm256_set1_ps(w));
}

static inline float end_weight(const iir_filter_lanes *f, int d)
{
    return d == -f->h || d == f->h ? f->end_weight : 1.f;
}

/* Row y's raw light and subset flags over [x0 - h, x0 + CHUNK + h + 8), zero beyond the image. */
static void chunk_planes(const iir_filter_lanes *f, int y, int x0, float *R, float *G, float *B,
                         float *L)
{
    const iir_vec3 *raw = f->raw + (size_t)y * (size_t)f->width;
    const int *live = f->live + (y % f->n) * f->n;
    int xx = x0 - f->h, end = CHUNK + 2 * IIR_FILTER_MAX_H + 8, k = 0;
    for (; k < end && xx < 0; k++, xx++) R[k] = G[k] = B[k] = L[k] = 0.f;
    for (int sx = xx % f->n; k < end && xx < f->width;
         k++, xx++, sx = sx + 1 == f->n ? 0 : sx + 1) {
        R[k] = raw[xx].x, G[k] = raw[xx].y, B[k] = raw[xx].z;
        L[k] = live[sx] ? 1.f : 0.f;
    }
    for (; k < end; k++) R[k] = G[k] = B[k] = L[k] = 0.f;
}

/* Lanes `in` of v stored at p (load_*: loaded from p); `all`: the 8 lanes, with a plain store or
 * load (the masked moves are slow). */
static inline void store_lanes(float *p, __m256i in, bool all, __m256 v)
{
    if (all)
        _mm256_storeu_ps(p, v);
    else
        _mm256_maskstore_ps(p, in, v);
}

static inline __m256i load_masks(const uint32_t *p, __m256i in, bool all)
{
    return all ? _mm256_loadu_si256((const __m256i *)p) : _mm256_maskload_epi32((const int *)p, in);
}

static inline __m256 load_lanes(const float *p, __m256i in, bool all)
{
    return all ? _mm256_loadu_ps(p) : _mm256_maskload_ps(p, in);
}

void iir_filter_rows_avx2(const iir_filter_lanes *f, int y)
{
    _Alignas(32) float R[CHUNK + 2 * IIR_FILTER_MAX_H + 8], G[sizeof R / sizeof *R],
        B[sizeof R / sizeof *R], L[sizeof R / sizeof *R];
    size_t plane = (size_t)f->width * (size_t)f->ring, row = (size_t)y * (size_t)f->width;
    size_t slot = (size_t)(y % f->ring) * (size_t)f->width;
    for (int x0 = 0; x0 < f->width; x0 += CHUNK) {
        chunk_planes(f, y, x0, R, G, B, L);
        int x1 = x0 + CHUNK < f->width ? x0 + CHUNK : f->width;
        for (int x = x0; x < x1; x += 8) {
            __m256i in = lanes_below(x, f->width);
            bool all = x + 8 <= f->width;
            __m256i masks = load_masks(f->mask + row + (size_t)x, in, all);
            __m256 r = zero(), g = zero(), b = zero(), w = zero();
            for (int d = -f->h; d <= f->h; d++) {
                int k = x - x0 + d + f->h; /* the taps' offset in the chunk's planes */
                __m256 wt =
                    _mm256_and_ps(tap_weights(masks, IIR_FILTER_MAX_H + d, end_weight(f, d)),
                                  _mm256_cmp_ps(_mm256_loadu_ps(L + k), zero(), _CMP_NEQ_OQ));
                r = _mm256_add_ps(r, _mm256_mul_ps(_mm256_loadu_ps(R + k), wt));
                g = _mm256_add_ps(g, _mm256_mul_ps(_mm256_loadu_ps(G + k), wt));
                b = _mm256_add_ps(b, _mm256_mul_ps(_mm256_loadu_ps(B + k), wt));
                w = _mm256_add_ps(w, wt);
            }
            float *out = f->planes + slot + (size_t)x;
            store_lanes(out, in, all, r);
            store_lanes(out + plane, in, all, g);
            store_lanes(out + 2 * plane, in, all, b);
            store_lanes(out + 3 * plane, in, all, w);
        }
    }
}

/* The column pass at pixels x .. x + 7 of row y (lanes `in`; `all`: the 8 of them): E. */
static v3 column8(const iir_filter_lanes *f, int y, int x, __m256i in, bool all)
{
    size_t plane = (size_t)f->width * (size_t)f->ring, row = (size_t)y * (size_t)f->width;
    __m256i masks = load_masks(f->mask + row + (size_t)x, in, all);
    __m256 r = zero(), g = zero(), b = zero(), w = zero();
    for (int d = -f->h; d <= f->h; d++) {
        if (y + d < 0 || y + d >= f->height) continue;
        __m256 wt = tap_weights(masks, IIR_FILTER_COLUMN + IIR_FILTER_MAX_H + d, end_weight(f, d));
        const float *p = f->planes + (size_t)((y + d) % f->ring) * (size_t)f->width + (size_t)x;
        r = _mm256_add_ps(r, _mm256_mul_ps(load_lanes(p, in, all), wt));
        g = _mm256_add_ps(g, _mm256_mul_ps(load_lanes(p + plane, in, all), wt));
        b = _mm256_add_ps(b, _mm256_mul_ps(load_lanes(p + 2 * plane, in, all), wt));
        w = _mm256_add_ps(w, _mm256_mul_ps(wt, load_lanes(p + 3 * plane, in, all)));
    }
    __m256 any = _mm256_cmp_ps(w, zero(), _CMP_GT_OQ);
    __m256 inv = _mm256_and_ps(any, _mm256_div_ps(_mm256_set1_ps(1.f), w));
    return scale3((v3){r, g, b}, inv);
}

void iir_filter_columns_avx2(const iir_filter_lanes *f, int y, int x0, int x1, iir_vec3 *E)
{
    for (int x = x0; x < x1; x += 8) {
        _Alignas(32) float ex[8], ey[8], ez[8];
        v3 e = column8(f, y, x, lanes_below(x, x1), x + 8 <= x1);
        _mm256_store_ps(ex, e.x), _mm256_store_ps(ey, e.y), _mm256_store_ps(ez, e.z);
        for (int l = 0; l < 8 && x + l < x1; l++) E[x + l - x0] = iir_v3(ex[l], ey[l], ez[l]);
    }
}

void iir_filter_compose_avx2(const iir_filter_lanes *f, const iir_gbuffer *gb, int y,
                             iir_image *out)
{
    size_t row = (size_t)y * (size_t)f->width;
    const iir_vec3 *albedo = gb->albedo + row;
    iir_vec3 *L = iir_image_at(out, 0, y);
    __m256 inv_pi = _mm256_set1_ps(IIR_INV_PI);
    __m256i none = _mm256_set1_epi32((int)IIR_NO_HIT);
    int x = 0;
    for (; x + 8 <= f->width; x += 8) {
        v3 e = column8(f, y, x, _mm256_set1_epi32(-1), true);
        __m256 hit = _mm256_castsi256_ps(_mm256_xor_si256(
            _mm256_cmpeq_epi32(_mm256_loadu_si256((const __m256i *)(gb->prim + row + x)), none),
            _mm256_set1_epi32(-1)));
        v3 add = mul3(scale3(load_aos(albedo + x, albedo + x + 4), inv_pi), e);
        v3 l = load_aos(L + x, L + x + 4);
        store_aos(blend3(l, add3(l, add), hit), L + x, L + x + 4);
    }
    if (x == f->width) return;
    iir_vec3 E[8];
    iir_filter_columns_avx2(f, y, x, f->width, E);
    for (int x0 = x; x < f->width; x++)
        if (gb->prim[row + (size_t)x] != IIR_NO_HIT)
            L[x] = iir_add(L[x], iir_mul(iir_scale(albedo[x], IIR_INV_PI), E[x - x0]));
}

#endif

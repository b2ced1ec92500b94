/* render_filter_avx2.c -- the full-shading filter's row and column passes 8 pixels a step with AVX2
 * (render_internal.h: iir_filter_lanes): the scalar passes of render_filter.c with every tap's
 * product and sum in the same order and without FMA (this file is built with -mavx2 alone), so
 * the image is the same bit for bit. The row pass writes its sums and weights as four planes
 * (x, y, z, w) where the scalar one writes iir_filter_row structs. Called only where the CPU has
 * AVX2. */
#include "render_internal.h"

#if defined(__x86_64__)
#include <immintrin.h>

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
    for (int k = 0, xx = x0 - f->h; k < CHUNK + 2 * IIR_FILTER_MAX_H + 8; k++, xx++) {
        bool in = xx >= 0 && xx < f->width;
        R[k] = in ? raw[xx].x : 0.f, G[k] = in ? raw[xx].y : 0.f, B[k] = in ? raw[xx].z : 0.f;
        L[k] = in && live[xx % f->n] ? 1.f : 0.f;
    }
}

void iir_filter_rows_avx2(const iir_filter_lanes *f, int y)
{
    _Alignas(32) float R[CHUNK + 2 * IIR_FILTER_MAX_H + 8], G[sizeof R / sizeof *R],
        B[sizeof R / sizeof *R], L[sizeof R / sizeof *R];
    size_t plane = (size_t)f->width * (size_t)f->height, row = (size_t)y * (size_t)f->width;
    __m256 zero = _mm256_setzero_ps();
    for (int x0 = 0; x0 < f->width; x0 += CHUNK) {
        chunk_planes(f, y, x0, R, G, B, L);
        int x1 = x0 + CHUNK < f->width ? x0 + CHUNK : f->width;
        for (int x = x0; x < x1; x += 8) {
            __m256i in = lanes_below(x, f->width);
            __m256i masks = _mm256_maskload_epi32((const int *)(f->mask + row + (size_t)x), in);
            __m256 r = zero, g = zero, b = zero, w = zero;
            for (int d = -f->h; d <= f->h; d++) {
                int k = x - x0 + d + f->h; /* the taps' offset in the chunk's planes */
                __m256 wt =
                    _mm256_and_ps(tap_weights(masks, IIR_FILTER_MAX_H + d, end_weight(f, d)),
                                  _mm256_cmp_ps(_mm256_loadu_ps(L + k), zero, _CMP_NEQ_OQ));
                r = _mm256_add_ps(r, _mm256_mul_ps(_mm256_loadu_ps(R + k), wt));
                g = _mm256_add_ps(g, _mm256_mul_ps(_mm256_loadu_ps(G + k), wt));
                b = _mm256_add_ps(b, _mm256_mul_ps(_mm256_loadu_ps(B + k), wt));
                w = _mm256_add_ps(w, wt);
            }
            float *out = f->planes + row + (size_t)x;
            _mm256_maskstore_ps(out, in, r);
            _mm256_maskstore_ps(out + plane, in, g);
            _mm256_maskstore_ps(out + 2 * plane, in, b);
            _mm256_maskstore_ps(out + 3 * plane, in, w);
        }
    }
}

void iir_filter_columns_avx2(const iir_filter_lanes *f, int y, int x0, int x1, iir_vec3 *E)
{
    size_t plane = (size_t)f->width * (size_t)f->height, row = (size_t)y * (size_t)f->width;
    __m256 zero = _mm256_setzero_ps();
    for (int x = x0; x < x1; x += 8) {
        __m256i in = lanes_below(x, x1);
        __m256i masks = _mm256_maskload_epi32((const int *)(f->mask + row + (size_t)x), in);
        __m256 r = zero, g = zero, b = zero, w = zero;
        for (int d = -f->h; d <= f->h; d++) {
            if (y + d < 0 || y + d >= f->height) continue;
            __m256 wt =
                tap_weights(masks, IIR_FILTER_COLUMN + IIR_FILTER_MAX_H + d, end_weight(f, d));
            const float *p = f->planes + (size_t)(y + d) * (size_t)f->width + (size_t)x;
            r = _mm256_add_ps(r, _mm256_mul_ps(_mm256_maskload_ps(p, in), wt));
            g = _mm256_add_ps(g, _mm256_mul_ps(_mm256_maskload_ps(p + plane, in), wt));
            b = _mm256_add_ps(b, _mm256_mul_ps(_mm256_maskload_ps(p + 2 * plane, in), wt));
            w = _mm256_add_ps(w, _mm256_mul_ps(wt, _mm256_maskload_ps(p + 3 * plane, in)));
        }
        __m256 any = _mm256_cmp_ps(w, zero, _CMP_GT_OQ);
        __m256 inv = _mm256_and_ps(any, _mm256_div_ps(_mm256_set1_ps(1.f), w));
        _Alignas(32) float ex[8], ey[8], ez[8];
        _mm256_store_ps(ex, _mm256_mul_ps(r, inv));
        _mm256_store_ps(ey, _mm256_mul_ps(g, inv));
        _mm256_store_ps(ez, _mm256_mul_ps(b, inv));
        for (int l = 0; l < 8 && x + l < x1; l++) E[x + l - x0] = iir_v3(ex[l], ey[l], ez[l]);
    }
}

#endif

/* render_lanes_avx2.h -- 8 pixels' vectors as AVX2 lanes, for the files built with -mavx2 alone
 * (render_direct_avx2.c, render_filter_avx2.c): three registers of x, y and z, the products and
 * sums the scalar iir_vec3 functions make (no FMA: the same bits), and the G-buffer's and the
 * frame's arrays of iir_vec3 moved into and out of lanes. */
#ifndef IIR_RENDER_LANES_AVX2_H
#define IIR_RENDER_LANES_AVX2_H

#include <immintrin.h>

#include "iir/rt.h"
#include "iir/vecmath.h"

typedef struct v3 {
    __m256 x, y, z;
} v3;

/* A helper whose body is prefetches alone: GCC counts such a function as one without effects and
 * drops calls to it, so it must be inlined always. */
#define IIR_PREFETCH_FN static inline __attribute__((always_inline)) void

static inline __m256 zero(void)
{
    return _mm256_setzero_ps();
}
static inline v3 mul3(v3 a, v3 b)
{
    return (v3){_mm256_mul_ps(a.x, b.x), _mm256_mul_ps(a.y, b.y), _mm256_mul_ps(a.z, b.z)};
}
static inline v3 scale3(v3 a, __m256 k)
{
    return (v3){_mm256_mul_ps(a.x, k), _mm256_mul_ps(a.y, k), _mm256_mul_ps(a.z, k)};
}
static inline v3 add3(v3 a, v3 b)
{
    return (v3){_mm256_add_ps(a.x, b.x), _mm256_add_ps(a.y, b.y), _mm256_add_ps(a.z, b.z)};
}
static inline v3 and3(v3 a, __m256 m)
{
    return (v3){_mm256_and_ps(a.x, m), _mm256_and_ps(a.y, m), _mm256_and_ps(a.z, m)};
}
static inline v3 blend3(v3 a, v3 b, __m256 m) /* b where m, else a */
{
    return (v3){_mm256_blendv_ps(a.x, b.x, m), _mm256_blendv_ps(a.y, b.y, m),
                _mm256_blendv_ps(a.z, b.z, m)};
}
static inline v3 load_planes(const float *x, const float *y, const float *z)
{
    return (v3){_mm256_load_ps(x), _mm256_load_ps(y), _mm256_load_ps(z)};
}
/* Lanes where a is not black (iir_is_black false: a NaN component counts as light). */
static inline __m256 not_black(v3 a)
{
    return _mm256_or_ps(_mm256_or_ps(_mm256_cmp_ps(a.x, zero(), _CMP_NEQ_UQ),
                                     _mm256_cmp_ps(a.y, zero(), _CMP_NEQ_UQ)),
                        _mm256_cmp_ps(a.z, zero(), _CMP_NEQ_UQ));
}

/* Lanes whose G-buffer prim is geometry, not IIR_NO_HIT: of 8 prims as lanes, or 8 from p. */
static inline __m256 hit_mask(__m256i prim)
{
    __m256i none = _mm256_cmpeq_epi32(prim, _mm256_set1_epi32((int)IIR_NO_HIT));
    return _mm256_castsi256_ps(_mm256_xor_si256(none, _mm256_set1_epi32(-1)));
}
static inline __m256 hit_lanes(const uint32_t *p)
{
    return hit_mask(_mm256_loadu_si256((const __m256i *)p));
}

/* 4 iir_vec3 at each of a and b as lanes 0..3 (a) and 4..7 (b). */
static inline v3 load_aos(const iir_vec3 *a, const iir_vec3 *b)
{
    const float *fa = &a->x, *fb = &b->x;
    __m256 p = _mm256_set_m128(_mm_loadu_ps(fb), _mm_loadu_ps(fa));         /* x0 y0 z0 x1 */
    __m256 q = _mm256_set_m128(_mm_loadu_ps(fb + 4), _mm_loadu_ps(fa + 4)); /* y1 z1 x2 y2 */
    __m256 r = _mm256_set_m128(_mm_loadu_ps(fb + 8), _mm_loadu_ps(fa + 8)); /* z2 x3 y3 z3 */
    __m256 xy = _mm256_shuffle_ps(q, r, _MM_SHUFFLE(2, 1, 3, 2));           /* x2 y2 x3 y3 */
    __m256 yz = _mm256_shuffle_ps(p, q, _MM_SHUFFLE(1, 0, 2, 1));           /* y0 z0 y1 z1 */
    return (v3){_mm256_shuffle_ps(p, xy, _MM_SHUFFLE(2, 0, 3, 0)),
                _mm256_shuffle_ps(yz, xy, _MM_SHUFFLE(3, 1, 2, 0)),
                _mm256_shuffle_ps(yz, r, _MM_SHUFFLE(3, 0, 3, 1))};
}

/* load_aos's inverse: lanes 0..3 to a, 4..7 to b. */
static inline void store_aos(v3 v, iir_vec3 *a, iir_vec3 *b)
{
    __m256 lo = _mm256_unpacklo_ps(v.x, v.y), hi = _mm256_unpackhi_ps(v.x, v.y); /* x0y0x1y1 */
    __m256 zx = _mm256_shuffle_ps(v.z, v.x, _MM_SHUFFLE(1, 1, 0, 0));            /* z0z0x1x1 */
    __m256 yz = _mm256_shuffle_ps(v.y, v.z, _MM_SHUFFLE(1, 1, 1, 1));            /* y1y1z1z1 */
    __m256 zx2 = _mm256_shuffle_ps(v.z, v.x, _MM_SHUFFLE(3, 3, 2, 2));           /* z2z2x3x3 */
    __m256 xyz3 = _mm256_shuffle_ps(hi, v.z, _MM_SHUFFLE(3, 3, 3, 2));           /* x3y3z3z3 */
    __m256 p = _mm256_shuffle_ps(lo, zx, _MM_SHUFFLE(2, 0, 1, 0));               /* x0y0z0x1 */
    __m256 q = _mm256_shuffle_ps(yz, hi, _MM_SHUFFLE(1, 0, 2, 0));               /* y1z1x2y2 */
    __m256 r = _mm256_shuffle_ps(zx2, xyz3, _MM_SHUFFLE(2, 1, 2, 0));            /* z2x3y3z3 */
    float *fa = &a->x, *fb = &b->x;
    _mm_storeu_ps(fa, _mm256_castps256_ps128(p));
    _mm_storeu_ps(fa + 4, _mm256_castps256_ps128(q));
    _mm_storeu_ps(fa + 8, _mm256_castps256_ps128(r));
    _mm_storeu_ps(fb, _mm256_extractf128_ps(p, 1));
    _mm_storeu_ps(fb + 4, _mm256_extractf128_ps(q, 1));
    _mm_storeu_ps(fb + 8, _mm256_extractf128_ps(r, 1));
}

#endif

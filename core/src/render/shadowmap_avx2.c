/* shadowmap_avx2.c -- a shadow map's texel rays 8 at a time with AVX2 (shadowmap.h:
 * iir_smap_texel_rays_avx2): shadowmap.c's texel directions and frame transform lane by lane, the
 * same operations in the same order without FMA (this file is built with -mavx2 alone), so the
 * rays and the maps are the same bit for bit. Called only where the CPU has AVX2. */
#include "iir/shadowmap.h"

#if defined(__x86_64__)
#include <immintrin.h>

static inline __m256 splat(float a)
{
    return _mm256_set1_ps(a);
}

/* a.x l + b.y l ... : iir_frame_to_world's sums, one axis (r, u, f components c). */
static inline __m256 to_world(float r, float u, float f, __m256 lx, __m256 ly, __m256 lz)
{
    return _mm256_add_ps(_mm256_add_ps(_mm256_mul_ps(splat(r), lx), _mm256_mul_ps(splat(u), ly)),
                         _mm256_mul_ps(splat(f), lz));
}

void iir_smap_texel_rays_avx2(const iir_frame *fr, iir_vec3 org, int i0, int j, int res,
                              iir_ray8 *rays)
{
    __m256 one = splat(1.f), half = splat(.5f), two = splat(2.f), fres = splat((float)res);
    __m256i lane = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    __m256i idx = _mm256_add_epi32(_mm256_set1_epi32(i0), lane);
    __m256i valid = _mm256_cmpgt_epi32(_mm256_set1_epi32(res), idx);
    idx = _mm256_min_epi32(idx, _mm256_set1_epi32(res - 1));
    /* texel_dir: the texel centre in [-1, 1]^2 */
    __m256 x = _mm256_sub_ps(
        _mm256_div_ps(_mm256_mul_ps(two, _mm256_add_ps(_mm256_cvtepi32_ps(idx), half)), fres), one);
    __m256 y = _mm256_sub_ps(
        _mm256_div_ps(_mm256_mul_ps(two, _mm256_add_ps(splat((float)j), half)), fres), one);
    __m256 r2 = _mm256_add_ps(_mm256_mul_ps(x, x), _mm256_mul_ps(y, y));
    /* outside the unit disk: the horizon direction of its angle */
    __m256 k = _mm256_div_ps(one, _mm256_sqrt_ps(r2));
    __m256 hx = _mm256_mul_ps(x, k), hy = _mm256_mul_ps(y, k);
    /* inside: iir_paraboloid_dir at uv = (x + 1) / 2, (y + 1) / 2 */
    __m256 px = _mm256_sub_ps(_mm256_mul_ps(two, _mm256_mul_ps(half, _mm256_add_ps(x, one))), one);
    __m256 py = _mm256_sub_ps(_mm256_mul_ps(two, _mm256_mul_ps(half, _mm256_add_ps(y, one))), one);
    __m256 pr2 = _mm256_add_ps(_mm256_mul_ps(px, px), _mm256_mul_ps(py, py));
    __m256 inv = _mm256_div_ps(one, _mm256_add_ps(one, pr2));
    __m256 outside = _mm256_cmp_ps(r2, one, _CMP_GT_OQ);
    __m256 lx = _mm256_blendv_ps(_mm256_mul_ps(_mm256_mul_ps(two, px), inv), hx, outside);
    __m256 ly = _mm256_blendv_ps(_mm256_mul_ps(_mm256_mul_ps(two, py), inv), hy, outside);
    __m256 lz = _mm256_andnot_ps(outside, _mm256_mul_ps(_mm256_sub_ps(one, pr2), inv));
    _mm256_storeu_ps(rays->dx, to_world(fr->r.x, fr->u.x, fr->f.x, lx, ly, lz));
    _mm256_storeu_ps(rays->dy, to_world(fr->r.y, fr->u.y, fr->f.y, lx, ly, lz));
    _mm256_storeu_ps(rays->dz, to_world(fr->r.z, fr->u.z, fr->f.z, lx, ly, lz));
    _mm256_storeu_ps(rays->ox, splat(org.x));
    _mm256_storeu_ps(rays->oy, splat(org.y));
    _mm256_storeu_ps(rays->oz, splat(org.z));
    _mm256_storeu_ps(rays->tnear, _mm256_setzero_ps());
    _mm256_storeu_ps(rays->tfar, splat(INFINITY));
    _mm256_storeu_si256((__m256i *)rays->valid, _mm256_and_si256(valid, _mm256_set1_epi32(1)));
}

#endif

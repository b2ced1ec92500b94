/* light_lanes_avx2.c -- a delta light (point, cosine or glTF spot, sun) arriving at 8 or 32
 * receivers at once with AVX2 and FMA (light.h: iir_light_sample_delta8_avx2 and _delta32_):
 * iir_light_sample_li's formulas lane by lane, with the receiver's cosine and the shadow segment
 * the renderer tests. Each vector of 8 lanes is a chain of dependent square roots and divisions
 * (~120 cycles of latency, few of work), so 32 lanes go as four vectors whose steps alternate and
 * overlap (four: the direct light ~6% faster than with two; eight were slower, their values no
 * longer in registers). Built with -mavx2 -mfma (CMakeLists) and called only where the CPU has
 * them. */
#include "iir/light.h"

#include <math.h>

#if defined(__x86_64__)
#include <immintrin.h>

#define INLINE static inline __attribute__((always_inline))

enum { MAX_H = 4 }; /* vectors of 8 lanes a call takes */

typedef struct v3 {
    __m256 x, y, z;
} v3;

INLINE __m256 dot(v3 a, v3 b)
{
    return _mm256_fmadd_ps(a.z, b.z, _mm256_fmadd_ps(a.y, b.y, _mm256_mul_ps(a.x, b.x)));
}
INLINE v3 splat(iir_vec3 a)
{
    return (v3){_mm256_set1_ps(a.x), _mm256_set1_ps(a.y), _mm256_set1_ps(a.z)};
}
INLINE v3 sub(v3 a, v3 b)
{
    return (v3){_mm256_sub_ps(a.x, b.x), _mm256_sub_ps(a.y, b.y), _mm256_sub_ps(a.z, b.z)};
}
INLINE v3 scale(v3 a, __m256 k)
{
    return (v3){_mm256_mul_ps(a.x, k), _mm256_mul_ps(a.y, k), _mm256_mul_ps(a.z, k)};
}
INLINE v3 madd(v3 a, v3 b, __m256 k) /* a + b k */
{
    return (v3){_mm256_fmadd_ps(b.x, k, a.x), _mm256_fmadd_ps(b.y, k, a.y),
                _mm256_fmadd_ps(b.z, k, a.z)};
}
INLINE __m256 gt(__m256 a, __m256 b)
{
    return _mm256_cmp_ps(a, b, _CMP_GT_OQ);
}

/* 1 / sqrt(a): the estimate (12 bits) and one Newton step, y (3 - a y^2) / 2 (~23 bits; the
 * divider's square root and division take ~25 cycles each, this ~12 in pipelined steps). */
INLINE __m256 rsqrt(__m256 a)
{
    __m256 y = _mm256_rsqrt_ps(a);
    __m256 ay2 = _mm256_mul_ps(_mm256_mul_ps(a, y), y);
    return _mm256_mul_ps(_mm256_mul_ps(_mm256_set1_ps(0.5f), y),
                         _mm256_sub_ps(_mm256_set1_ps(3.f), ay2));
}

/* The cosine spot's falloff over disk radius rho: 1 inside R_in, smoothstep down to 0 at R. */
INLINE __m256 cosine_falloff(const iir_light_eval *e, __m256 rho)
{
    __m256 R = _mm256_set1_ps(e->R), one = _mm256_set1_ps(1.f);
    __m256 t = _mm256_mul_ps(_mm256_sub_ps(R, rho), _mm256_set1_ps(1.f / (e->R - e->R_in)));
    __m256 smooth = _mm256_mul_ps(_mm256_mul_ps(t, t),
                                  _mm256_fnmadd_ps(_mm256_set1_ps(2.f), t, _mm256_set1_ps(3.f)));
    __m256 inner = _mm256_cmp_ps(rho, _mm256_set1_ps(e->R_in), _CMP_LE_OQ);
    __m256 f = _mm256_blendv_ps(smooth, one, inner);
    return _mm256_and_ps(f, _mm256_cmp_ps(rho, R, _CMP_LT_OQ));
}

/* I(w) / I0 of a spot toward unit w[h] (iir_light_eval_intensity's profile), 0 behind it, for
 * the H vectors, step by step. */
INLINE void spot_profile(const iir_light_eval *e, const v3 *w, __m256 *k, int H)
{
    __m256 cos_theta[MAX_H], rho[MAX_H], zero = _mm256_setzero_ps();
    for (int h = 0; h < H; h++) cos_theta[h] = dot(w[h], splat(e->frame.f));
    if (e->light->profile == IIR_SPOT_GLTF) {
        for (int h = 0; h < H; h++) {
            __m256 t = _mm256_mul_ps(_mm256_sub_ps(cos_theta[h], _mm256_set1_ps(e->cos_outer)),
                                     _mm256_set1_ps(e->t_scale));
            t = _mm256_min_ps(_mm256_max_ps(t, zero), _mm256_set1_ps(1.f));
            k[h] = _mm256_mul_ps(t, t);
        }
    } else {
        for (int h = 0; h < H; h++) {
            __m256 sx = dot(w[h], splat(e->frame.r)), sy = dot(w[h], splat(e->frame.u));
            rho[h] = _mm256_sqrt_ps(_mm256_fmadd_ps(sy, sy, _mm256_mul_ps(sx, sx)));
        }
        for (int h = 0; h < H; h++) k[h] = _mm256_mul_ps(cos_theta[h], cosine_falloff(e, rho[h]));
    }
    for (int h = 0; h < H; h++) k[h] = _mm256_and_ps(k[h], gt(cos_theta[h], zero));
}

INLINE void store3(float *x, float *y, float *z, v3 a, __m256 mask)
{
    _mm256_store_ps(x, _mm256_and_ps(a.x, mask));
    _mm256_store_ps(y, _mm256_and_ps(a.y, mask));
    _mm256_store_ps(z, _mm256_and_ps(a.z, mask));
}

/* A sun at the H vectors: along its direction, wherever the receiver faces it. */
INLINE void sun(const iir_light *l, const v3 *n, const v3 *o, iir_light_delta_lanes *out, int H)
{
    v3 wi = splat(iir_neg(iir_normalize(l->direction)));
    for (int h = 0; h < H; h++) {
        __m256 cos_x = dot(n[h], wi), lit = gt(cos_x, _mm256_setzero_ps());
        iir_light_delta_lanes *q = &out[h];
        store3(q->wx, q->wy, q->wz, wi, lit);
        store3(q->Ex, q->Ey, q->Ez, scale(splat(l->intensity), cos_x), lit);
        store3(q->ox, q->oy, q->oz, o[h], lit);
        store3(q->dx, q->dy, q->dz, wi, lit);
        _mm256_store_ps(q->tmax, _mm256_and_ps(_mm256_set1_ps(INFINITY), lit));
    }
}

/* The H vectors' samples: each step taken for every vector before the next step, so that one
 * vector's square roots and divisions wait while the other's run. */
INLINE void sample(const iir_light_eval *e, float eps, const iir_light_lanes *in,
                   iir_light_delta_lanes *out, int H)
{
    const iir_light *l = e->light;
    __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.f), veps = _mm256_set1_ps(eps);
    v3 x[MAX_H], n[MAX_H], o[MAX_H];
    for (int h = 0; h < H; h++) {
        x[h] = (v3){_mm256_load_ps(in[h].px), _mm256_load_ps(in[h].py), _mm256_load_ps(in[h].pz)};
        n[h] = (v3){_mm256_load_ps(in[h].nx), _mm256_load_ps(in[h].ny), _mm256_load_ps(in[h].nz)};
        o[h] = madd(x[h], n[h], veps); /* the receiver's end, on the lit side */
    }
    if (l->type == IIR_LIGHT_SUN) {
        sun(l, n, o, out, H);
        return;
    }
    v3 p = splat(l->position), d[MAX_H], s[MAX_H], wi[MAX_H];
    __m256 dist2[MAX_H], inv_dist[MAX_H], len2[MAX_H], inv_len[MAX_H], k[MAX_H];
    for (int h = 0; h < H; h++) d[h] = sub(p, x[h]), dist2[h] = dot(d[h], d[h]);
    /* the segment from the receiver's end stops eps short of the light, which lies on no surface */
    for (int h = 0; h < H; h++) s[h] = sub(p, o[h]), len2[h] = dot(s[h], s[h]);
    for (int h = 0; h < H; h++) inv_dist[h] = rsqrt(dist2[h]), inv_len[h] = rsqrt(len2[h]);
    for (int h = 0; h < H; h++) wi[h] = scale(d[h], inv_dist[h]);
    if (l->type == IIR_LIGHT_SPOT) {
        v3 w[MAX_H];
        for (int h = 0; h < H; h++) w[h] = scale(wi[h], _mm256_set1_ps(-1.f));
        spot_profile(e, w, k, H);
    } else {
        for (int h = 0; h < H; h++) k[h] = one;
    }
    for (int h = 0; h < H; h++) {
        iir_light_delta_lanes *q = &out[h];
        __m256 cos_x = dot(n[h], wi[h]);
        __m256 lit =
            _mm256_and_ps(_mm256_and_ps(gt(dist2[h], zero), gt(cos_x, zero)), gt(k[h], zero));
        __m256 Li = _mm256_mul_ps(k[h], _mm256_mul_ps(inv_dist[h], inv_dist[h]));
        store3(q->wx, q->wy, q->wz, wi[h], lit);
        store3(q->Ex, q->Ey, q->Ez, scale(splat(l->intensity), _mm256_mul_ps(Li, cos_x)), lit);
        __m256 tmax = _mm256_sub_ps(_mm256_mul_ps(len2[h], inv_len[h]), veps);
        lit = _mm256_and_ps(lit, gt(tmax, zero));
        store3(q->ox, q->oy, q->oz, o[h], lit);
        store3(q->dx, q->dy, q->dz, scale(s[h], inv_len[h]), lit);
        _mm256_store_ps(q->tmax, _mm256_and_ps(tmax, lit));
    }
}

void iir_light_sample_delta8_avx2(const iir_light_eval *e, float eps, const iir_light_lanes *in,
                                  iir_light_delta_lanes *out)
{
    sample(e, eps, in, out, 1);
}

void iir_light_sample_delta32_avx2(const iir_light_eval *e, float eps, const iir_light_lanes in[4],
                                   iir_light_delta_lanes out[4])
{
    sample(e, eps, in, out, 4);
}

#endif

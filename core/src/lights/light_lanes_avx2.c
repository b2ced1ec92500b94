/* light_lanes_avx2.c -- a delta light (point, cosine or glTF spot, sun) arriving at 8 receivers
 * at once with AVX2 and FMA (light.h: iir_light_sample_delta8_avx2): iir_light_sample_li's
 * formulas lane by lane, with the receiver's cosine and the shadow segment the renderer tests.
 * Built with -mavx2 -mfma (CMakeLists) and called only where the CPU has them. */
#include "iir/light.h"

#include <math.h>

#if defined(__x86_64__)
#include <immintrin.h>

typedef struct v3 {
    __m256 x, y, z;
} v3;

static inline __m256 dot(v3 a, v3 b)
{
    return _mm256_fmadd_ps(a.z, b.z, _mm256_fmadd_ps(a.y, b.y, _mm256_mul_ps(a.x, b.x)));
}
static inline v3 splat(iir_vec3 a)
{
    return (v3){_mm256_set1_ps(a.x), _mm256_set1_ps(a.y), _mm256_set1_ps(a.z)};
}
static inline v3 sub(v3 a, v3 b)
{
    return (v3){_mm256_sub_ps(a.x, b.x), _mm256_sub_ps(a.y, b.y), _mm256_sub_ps(a.z, b.z)};
}
static inline v3 scale(v3 a, __m256 k)
{
    return (v3){_mm256_mul_ps(a.x, k), _mm256_mul_ps(a.y, k), _mm256_mul_ps(a.z, k)};
}
static inline v3 madd(v3 a, v3 b, __m256 k) /* a + b k */
{
    return (v3){_mm256_fmadd_ps(b.x, k, a.x), _mm256_fmadd_ps(b.y, k, a.y),
                _mm256_fmadd_ps(b.z, k, a.z)};
}
static inline __m256 gt(__m256 a, __m256 b)
{
    return _mm256_cmp_ps(a, b, _CMP_GT_OQ);
}

/* The cosine spot's falloff over disk radius rho: 1 inside R_in, smoothstep down to 0 at R. */
static __m256 cosine_falloff(const iir_light_eval *e, __m256 rho)
{
    __m256 R = _mm256_set1_ps(e->R), one = _mm256_set1_ps(1.f);
    __m256 t = _mm256_div_ps(_mm256_sub_ps(R, rho), _mm256_set1_ps(e->R - e->R_in));
    __m256 smooth = _mm256_mul_ps(_mm256_mul_ps(t, t),
                                  _mm256_fnmadd_ps(_mm256_set1_ps(2.f), t, _mm256_set1_ps(3.f)));
    __m256 inner = _mm256_cmp_ps(rho, _mm256_set1_ps(e->R_in), _CMP_LE_OQ);
    __m256 f = _mm256_blendv_ps(smooth, one, inner);
    return _mm256_and_ps(f, _mm256_cmp_ps(rho, R, _CMP_LT_OQ));
}

/* I(w) / I0 of a spot toward unit w (iir_light_eval_intensity's profile), 0 behind it. */
static __m256 spot_profile(const iir_light_eval *e, v3 w)
{
    __m256 cos_theta = dot(w, splat(e->frame.f)), zero = _mm256_setzero_ps();
    __m256 k;
    if (e->light->profile == IIR_SPOT_GLTF) {
        __m256 t = _mm256_mul_ps(_mm256_sub_ps(cos_theta, _mm256_set1_ps(e->cos_outer)),
                                 _mm256_set1_ps(e->t_scale));
        t = _mm256_min_ps(_mm256_max_ps(t, zero), _mm256_set1_ps(1.f));
        k = _mm256_mul_ps(t, t);
    } else {
        __m256 sx = dot(w, splat(e->frame.r)), sy = dot(w, splat(e->frame.u));
        __m256 rho = _mm256_sqrt_ps(_mm256_fmadd_ps(sy, sy, _mm256_mul_ps(sx, sx)));
        k = _mm256_mul_ps(cos_theta, cosine_falloff(e, rho));
    }
    return _mm256_and_ps(k, gt(cos_theta, zero));
}

static void store3(float *x, float *y, float *z, v3 a, __m256 mask)
{
    _mm256_store_ps(x, _mm256_and_ps(a.x, mask));
    _mm256_store_ps(y, _mm256_and_ps(a.y, mask));
    _mm256_store_ps(z, _mm256_and_ps(a.z, mask));
}

void iir_light_sample_delta8_avx2(const iir_light_eval *e, float eps, const iir_light_lanes *in,
                                  iir_light_delta_lanes *out)
{
    const iir_light *l = e->light;
    v3 x = {_mm256_load_ps(in->px), _mm256_load_ps(in->py), _mm256_load_ps(in->pz)};
    v3 n = {_mm256_load_ps(in->nx), _mm256_load_ps(in->ny), _mm256_load_ps(in->nz)};
    __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.f), veps = _mm256_set1_ps(eps);
    v3 o = madd(x, n, veps); /* the receiver's end, on the lit side (lanes facing away are out) */
    if (l->type == IIR_LIGHT_SUN) {
        v3 wi = splat(iir_neg(iir_normalize(l->direction)));
        __m256 cos_x = dot(n, wi), lit = gt(cos_x, zero);
        store3(out->wx, out->wy, out->wz, wi, lit);
        store3(out->Ex, out->Ey, out->Ez, scale(splat(l->intensity), cos_x), lit);
        store3(out->ox, out->oy, out->oz, o, lit);
        store3(out->dx, out->dy, out->dz, wi, lit);
        _mm256_store_ps(out->tmax, _mm256_and_ps(_mm256_set1_ps(INFINITY), lit));
        return;
    }
    v3 p = splat(l->position), d = sub(p, x);
    __m256 dist2 = dot(d, d), dist = _mm256_sqrt_ps(dist2);
    v3 wi = scale(d, _mm256_div_ps(one, dist));
    __m256 k = l->type == IIR_LIGHT_SPOT ? spot_profile(e, scale(wi, _mm256_set1_ps(-1.f))) : one;
    __m256 cos_x = dot(n, wi);
    __m256 lit = _mm256_and_ps(_mm256_and_ps(gt(dist2, zero), gt(cos_x, zero)), gt(k, zero));
    __m256 Li = _mm256_mul_ps(k, _mm256_div_ps(one, dist2));
    store3(out->wx, out->wy, out->wz, wi, lit);
    store3(out->Ex, out->Ey, out->Ez, scale(splat(l->intensity), _mm256_mul_ps(Li, cos_x)), lit);
    /* the segment stops eps short of the light, which lies on no surface */
    v3 s = sub(p, o);
    __m256 len = _mm256_sqrt_ps(dot(s, s)), tmax = _mm256_sub_ps(len, veps);
    lit = _mm256_and_ps(lit, gt(tmax, zero));
    store3(out->ox, out->oy, out->oz, o, lit);
    store3(out->dx, out->dy, out->dz, scale(s, _mm256_div_ps(one, len)), lit);
    _mm256_store_ps(out->tmax, _mm256_and_ps(tmax, lit));
}

#endif

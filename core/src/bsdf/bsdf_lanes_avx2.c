/* bsdf_lanes_avx2.c -- glTF's metallic-roughness BRDF (bsdf.h) for 8 lanes with AVX2 and FMA: the
 * same terms as bsdf.c's f_local, each cosine a dot product with the lane's shading normal instead
 * of a coordinate in its tangent frame (the model is isotropic). Built with -mavx2 -mfma and called
 * only where the CPU has them (isa.h). */
#include "iir/bsdf.h"

#if defined(__x86_64__)
#include <immintrin.h>

static __m256 dot8(__m256 ax, __m256 ay, __m256 az, __m256 bx, __m256 by, __m256 bz)
{
    return _mm256_fmadd_ps(ax, bx, _mm256_fmadd_ps(ay, by, _mm256_mul_ps(az, bz)));
}

/* sqrt(cos^2 + alpha^2 sin^2) of a direction at cosine c (iir_ggx_root), sin^2 = 1 - c^2. */
static __m256 ggx_root8(__m256 c, __m256 a2)
{
    __m256 c2 = _mm256_mul_ps(c, c);
    __m256 s2 = _mm256_max_ps(_mm256_setzero_ps(), _mm256_sub_ps(_mm256_set1_ps(1.f), c2));
    return _mm256_sqrt_ps(_mm256_fmadd_ps(a2, s2, c2));
}

/* One channel: (1 - F) c / pi + F D V with F = f0 + (1 - f0) m5. */
static __m256 channel(__m256 f0, __m256 c, __m256 m5, __m256 DV)
{
    __m256 one = _mm256_set1_ps(1.f);
    __m256 F = _mm256_fmadd_ps(_mm256_sub_ps(one, f0), m5, f0);
    __m256 diffuse =
        _mm256_mul_ps(_mm256_mul_ps(_mm256_sub_ps(one, F), c), _mm256_set1_ps(IIR_INV_PI));
    return _mm256_fmadd_ps(F, DV, diffuse);
}

/* D V of the lanes (0 where the lobe is a delta or n.wh <= 0): GGX's D at n.wh (nh, and s2 the
 * squared sine, |n x wh|^2: 1 - nh^2 cancels near the peak of a sharp lobe) and the
 * height-correlated Smith V at cos_o, cos_i. */
static __m256 specular_DV(__m256 alpha, __m256 nh, __m256 s2, __m256 cos_o, __m256 cos_i)
{
    __m256 zero = _mm256_setzero_ps();
    __m256 a2 = _mm256_mul_ps(alpha, alpha);
    __m256 c2 = _mm256_mul_ps(nh, nh);
    __m256 d = _mm256_fmadd_ps(a2, c2, s2);
    __m256 D = _mm256_div_ps(a2, _mm256_mul_ps(_mm256_set1_ps(IIR_PI), _mm256_mul_ps(d, d)));
    __m256 V = _mm256_div_ps(
        _mm256_set1_ps(0.5f),
        _mm256_fmadd_ps(cos_i, ggx_root8(cos_o, a2), _mm256_mul_ps(cos_o, ggx_root8(cos_i, a2))));
    __m256 lobe =
        _mm256_and_ps(_mm256_cmp_ps(alpha, _mm256_set1_ps(IIR_BSDF_DELTA_ALPHA), _CMP_GE_OQ),
                      _mm256_cmp_ps(nh, zero, _CMP_GT_OQ));
    return _mm256_and_ps(lobe, _mm256_mul_ps(D, V));
}

void iir_bsdf_f8_avx2(const iir_bsdf_lanes *L, const float *wx, const float *wy, const float *wz,
                      float *fx, float *fy, float *fz)
{
    __m256 zero = _mm256_setzero_ps(), one = _mm256_set1_ps(1.f);
    __m256 nx = _mm256_load_ps(L->nx), ny = _mm256_load_ps(L->ny), nz = _mm256_load_ps(L->nz);
    __m256 ox = _mm256_load_ps(L->wox), oy = _mm256_load_ps(L->woy), oz = _mm256_load_ps(L->woz);
    __m256 ix = _mm256_loadu_ps(wx), iy = _mm256_loadu_ps(wy), iz = _mm256_loadu_ps(wz);
    __m256 cos_o = dot8(nx, ny, nz, ox, oy, oz), cos_i = dot8(nx, ny, nz, ix, iy, iz);
    __m256 valid = _mm256_and_ps(_mm256_cmp_ps(cos_o, zero, _CMP_GT_OQ),
                                 _mm256_cmp_ps(cos_i, zero, _CMP_GT_OQ));
    /* wh = (wo + wi) / |wo + wi|; |v.h| as the mean of wo.wh and wi.wh, as f_local takes it */
    __m256 hx = _mm256_add_ps(ox, ix), hy = _mm256_add_ps(oy, iy), hz = _mm256_add_ps(oz, iz);
    __m256 inv = _mm256_div_ps(
        one, _mm256_sqrt_ps(_mm256_max_ps(dot8(hx, hy, hz, hx, hy, hz), _mm256_set1_ps(1e-30f))));
    hx = _mm256_mul_ps(hx, inv), hy = _mm256_mul_ps(hy, inv), hz = _mm256_mul_ps(hz, inv);
    __m256 vh = _mm256_mul_ps(_mm256_set1_ps(0.5f), _mm256_add_ps(dot8(ox, oy, oz, hx, hy, hz),
                                                                  dot8(ix, iy, iz, hx, hy, hz)));
    vh = _mm256_min_ps(one, _mm256_max_ps(zero, _mm256_andnot_ps(_mm256_set1_ps(-0.f), vh)));
    __m256 m = _mm256_sub_ps(one, vh), m2 = _mm256_mul_ps(m, m);
    __m256 m5 = _mm256_mul_ps(_mm256_mul_ps(m2, m2), m);
    __m256 sx = _mm256_fmsub_ps(ny, hz, _mm256_mul_ps(nz, hy));
    __m256 sy = _mm256_fmsub_ps(nz, hx, _mm256_mul_ps(nx, hz));
    __m256 sz = _mm256_fmsub_ps(nx, hy, _mm256_mul_ps(ny, hx));
    __m256 DV = specular_DV(_mm256_load_ps(L->alpha), dot8(nx, ny, nz, hx, hy, hz),
                            dot8(sx, sy, sz, sx, sy, sz), cos_o, cos_i);
    __m256 r = channel(_mm256_load_ps(L->f0x), _mm256_load_ps(L->cx), m5, DV);
    __m256 g = channel(_mm256_load_ps(L->f0y), _mm256_load_ps(L->cy), m5, DV);
    __m256 b = channel(_mm256_load_ps(L->f0z), _mm256_load_ps(L->cz), m5, DV);
    _mm256_storeu_ps(fx, _mm256_and_ps(valid, r));
    _mm256_storeu_ps(fy, _mm256_and_ps(valid, g));
    _mm256_storeu_ps(fz, _mm256_and_ps(valid, b));
}

#endif

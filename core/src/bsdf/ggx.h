/* ggx.h -- the isotropic GGX (Trowbridge-Reitz) microfacet distribution in a local frame with the
 * normal along +z: D, Smith's G1, the height-correlated visibility V, and sampling the
 * visible normals with its pdf. Not Fresnel, not the lobes' mix (bsdf.c). Internal to libiircore;
 * inline, no state.
 *
 * The trigonometry is taken from the local coordinates (cos^2 = z^2, sin^2 = x^2 + y^2) rather
 * than as 1 - cos^2, which keeps the narrow lobes of small alpha accurate in float. There is no
 * invert_ for the visible-normal warp: nothing needs one yet. */
#ifndef IIR_GGX_H
#define IIR_GGX_H

#include "iir/vecmath.h"
#include "sampling.h"

static inline float iir_ggx_cos2_theta(iir_vec3 w)
{
    return w.z * w.z;
}
static inline float iir_ggx_sin2_theta(iir_vec3 w)
{
    return w.x * w.x + w.y * w.y;
}

/* D(wh) = alpha^2 / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2), its denominator written as
 * sin^2 + alpha^2 cos^2 (the same number). 0 below the horizon. */
static inline float iir_ggx_D(iir_vec3 wh, float alpha)
{
    if (wh.z <= 0.f) return 0.f;
    float alpha2 = iir_sqr(alpha);
    float d = iir_ggx_sin2_theta(wh) + alpha2 * iir_ggx_cos2_theta(wh);
    return alpha2 / (IIR_PI * iir_sqr(d));
}

/* sqrt((n.w)^2 (1 - alpha^2) + alpha^2) = sqrt(cos^2 + alpha^2 sin^2) = n.w sqrt(1 + alpha^2
 * tan^2): the root in Smith's Lambda(w) = (sqrt(1 + alpha^2 tan^2) - 1) / 2, shared by G1 and V. */
static inline float iir_ggx_root(iir_vec3 w, float alpha)
{
    return sqrtf(iir_ggx_cos2_theta(w) + iir_sqr(alpha) * iir_ggx_sin2_theta(w));
}

/* G1(w) = 1 / (1 + Lambda(w)) = 2 n.w / (n.w + sqrt((n.w)^2 (1 - alpha^2) + alpha^2)). */
static inline float iir_ggx_G1(iir_vec3 w, float alpha)
{
    float cos_theta = fabsf(w.z);
    return 2.f * cos_theta / (cos_theta + iir_ggx_root(w, alpha));
}

/* V = G2 / (4 |n.wi| |n.wo|) with the height-correlated G2 = 1 / (1 + Lambda(wo) + Lambda(wi)):
 * V = 0.5 / (n.wi root(wo) + n.wo root(wi)), glTF's V_GGX. Symmetric in wo and wi. */
static inline float iir_ggx_V(iir_vec3 wo, iir_vec3 wi, float alpha)
{
    float cos_o = fabsf(wo.z), cos_i = fabsf(wi.z);
    return 0.5f / (cos_i * iir_ggx_root(wo, alpha) + cos_o * iir_ggx_root(wi, alpha));
}

/* A normal wh of the distribution of normals visible from w (w.z > 0), density D_w(wh) below:
 * Heitz 2018, "Sampling the GGX Distribution of Visible Normals" (JCGT 7(4)), with the uniform
 * disk point from the concentric map. */
static inline iir_vec3 iir_ggx_sample_visible(iir_vec3 w, float alpha, iir_vec2 u)
{
    /* stretch w to the hemisphere configuration (alpha = 1) */
    iir_vec3 wv = iir_normalize(iir_v3(alpha * w.x, alpha * w.y, w.z));
    /* an orthonormal basis (T1, T2, wv) */
    float len2 = iir_sqr(wv.x) + iir_sqr(wv.y);
    iir_vec3 T1 =
        len2 > 0.f ? iir_scale(iir_v3(-wv.y, wv.x, 0.f), 1.f / sqrtf(len2)) : iir_v3(1.f, 0.f, 0.f);
    iir_vec3 T2 = iir_cross(wv, T1);
    /* a uniform point on the disk, warped to the projected visible half of it */
    iir_vec2 p = iir_sample_uniform_disk_concentric(u);
    float s = 0.5f * (1.f + wv.z);
    p.y = (1.f - s) * iir_safe_sqrt(1.f - iir_sqr(p.x)) + s * p.y;
    /* lifted onto the hemisphere, then unstretched */
    float pz = iir_safe_sqrt(1.f - iir_sqr(p.x) - iir_sqr(p.y));
    iir_vec3 nh = iir_add(iir_add(iir_scale(T1, p.x), iir_scale(T2, p.y)), iir_scale(wv, pz));
    return iir_normalize(iir_v3(alpha * nh.x, alpha * nh.y, fmaxf(1e-6f, nh.z)));
}

/* D_w(wh) = G1(w) max(0, w.wh) D(wh) / (n.w): the density of iir_ggx_sample_visible over the
 * normals' solid angle. */
static inline float iir_ggx_visible_pdf(iir_vec3 w, iir_vec3 wh, float alpha)
{
    float cos_theta = fabsf(w.z);
    if (cos_theta == 0.f) return 0.f;
    return iir_ggx_G1(w, alpha) * fmaxf(0.f, iir_dot(w, wh)) * iir_ggx_D(wh, alpha) / cos_theta;
}

#endif

/* specular.h -- the optics of the two specular materials (iir_material_kind): mirror reflection,
 * Snell refraction with total internal reflection, the dielectric Fresnel reflectance, and the
 * split of a ray at glass into its two weighted branches. Shared by pt and whitted; not how
 * either method follows the branches. Internal to libiircore; inline, no state.
 *
 * Directions are the ray's own (V travels towards the surface, as in R = V - 2 (V.N) N). Glass
 * works on basic radiance L / n^2, which refraction leaves unchanged: a branch's weight is then
 * F (reflected) or 1 - F (refracted), never more than 1, and with the camera and lights outside a
 * closed glass object this is the same image as full radiance (the n^2 factors cancel). */
#ifndef IIR_SPECULAR_H
#define IIR_SPECULAR_H

#include <stdbool.h>

#include "iir/vecmath.h"

/* Mirror direction of V about unit normal N (either side): R = V - 2 (V.N) N. */
static inline iir_vec3 iir_reflect(iir_vec3 V, iir_vec3 N)
{
    return iir_sub(V, iir_scale(N, 2.f * iir_dot(V, N)));
}

/* Refraction of unit V through unit N facing against it (V.N <= 0), eta = n1 / n2 (from the side
 * V comes from to the other). Snell: sin(theta_t) = eta sin(theta_i); T = eta V + (eta cos_i -
 * cos_t) N. False (T untouched) on total internal reflection, sin(theta_t) > 1. */
static inline bool iir_refract(iir_vec3 V, iir_vec3 N, float eta, iir_vec3 *T)
{
    float cos_i = -iir_dot(V, N);
    float sin2_t = eta * eta * fmaxf(0.f, 1.f - cos_i * cos_i);
    if (sin2_t > 1.f) return false;
    float cos_t = sqrtf(1.f - sin2_t);
    *T = iir_normalize(iir_add(iir_scale(V, eta), iir_scale(N, eta * cos_i - cos_t)));
    return true;
}

/* Fresnel reflectance of unpolarised light at a smooth interface from index n1 to n2, cos_i the
 * cosine of incidence (>= 0): the mean of the s and p reflectances; 1 past the critical angle. */
static inline float iir_fresnel_dielectric(float cos_i, float n1, float n2)
{
    float sin2_t = (n1 / n2) * (n1 / n2) * fmaxf(0.f, 1.f - cos_i * cos_i);
    if (sin2_t >= 1.f) return 1.f;
    float cos_t = sqrtf(1.f - sin2_t);
    float r_s = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    float r_p = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    return 0.5f * (r_s * r_s + r_p * r_p);
}

/* A ray meeting glass: the reflected branch (direction wr, weight F) and, unless the ray is past
 * the critical angle (has_t false), the refracted branch (direction wt, weight 1 - F, to be tinted
 * by the material's `specular`). */
typedef struct iir_glass_split {
    iir_vec3 wr, wt;
    float F;       /* Fresnel reflectance; 1 on total internal reflection */
    bool has_t;    /* the refracted branch exists */
    bool entering; /* V comes from outside: V.n < 0 for the winding normal n */
} iir_glass_split;

/* Splits unit V at glass of index ior whose unit winding normal n points out of the glass (the
 * side V comes from is decided by n alone: V.n < 0 is entering, from air of index 1). */
static inline iir_glass_split iir_glass_at(iir_vec3 V, iir_vec3 n, float ior)
{
    iir_glass_split g;
    g.entering = iir_dot(V, n) < 0.f;
    iir_vec3 N = g.entering ? n : iir_neg(n); /* facing against V */
    float n1 = g.entering ? 1.f : ior, n2 = g.entering ? ior : 1.f;
    g.wr = iir_reflect(V, N);
    g.has_t = iir_refract(V, N, n1 / n2, &g.wt);
    g.F = g.has_t ? iir_fresnel_dielectric(-iir_dot(V, N), n1, n2) : 1.f;
    if (!g.has_t) g.wt = iir_v3s(0.f);
    return g;
}

#endif

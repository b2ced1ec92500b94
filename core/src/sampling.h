/* sampling.h -- warping uniform numbers to the shapes the renderer samples (disk, hemisphere,
 * sphere, triangle), each with its pdf. Internal to libiircore; inline, no state. */
#ifndef IIR_SAMPLING_H
#define IIR_SAMPLING_H

#include "iir/vecmath.h"

/* Shirley-Chiu concentric map of [0,1)^2 onto the unit disk (area-preserving). */
static inline iir_vec2 iir_sample_uniform_disk_concentric(iir_vec2 u)
{
    float a = 2.f * u.x - 1.f, b = 2.f * u.y - 1.f;
    if (a == 0.f && b == 0.f) return iir_v2(0.f, 0.f);
    float r, phi;
    if (fabsf(a) > fabsf(b)) {
        r = a;
        phi = (IIR_PI / 4.f) * (b / a);
    } else {
        r = b;
        phi = (IIR_PI / 2.f) - (IIR_PI / 4.f) * (a / b);
    }
    return iir_v2(r * cosf(phi), r * sinf(phi));
}

/* Cosine-weighted direction about +z: pdf = cos(theta) / pi. */
static inline iir_vec3 iir_sample_cosine_hemisphere(iir_vec2 u)
{
    iir_vec2 d = iir_sample_uniform_disk_concentric(u);
    float z = iir_safe_sqrt(1.f - d.x * d.x - d.y * d.y);
    return iir_v3(d.x, d.y, z);
}
static inline float iir_cosine_hemisphere_pdf(float cos_theta)
{
    return cos_theta * IIR_INV_PI;
}

/* Uniform direction on the unit sphere: pdf = 1 / (4 pi). */
static inline iir_vec3 iir_sample_uniform_sphere(iir_vec2 u)
{
    float z = 1.f - 2.f * u.x;
    float r = iir_safe_sqrt(1.f - z * z);
    float phi = 2.f * IIR_PI * u.y;
    return iir_v3(r * cosf(phi), r * sinf(phi), z);
}

/* Uniform barycentrics (b0, b1) on a triangle; b2 = 1 - b0 - b1. pdf = 1 / area. */
static inline iir_vec2 iir_sample_uniform_triangle(iir_vec2 u)
{
    float su0 = sqrtf(u.x);
    return iir_v2(1.f - su0, u.y * su0);
}

#endif

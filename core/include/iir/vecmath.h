/* vecmath.h -- small inline vector math shared by everything: vec2/vec3, frames, constants.
 * No allocation, no state. Written so call sites read like the equations they implement. */
#ifndef IIR_VECMATH_H
#define IIR_VECMATH_H

#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#ifdef __cplusplus
extern "C" {
#endif

#define IIR_PI 3.14159265358979323846f
#define IIR_INV_PI 0.31830988618379067154f
#define IIR_INV_2PI 0.15915494309189533577f
#define IIR_INV_4PI 0.07957747154594766788f

typedef struct iir_vec2 {
    float x, y;
} iir_vec2;

typedef struct iir_vec3 {
    float x, y, z;
} iir_vec3;

/* An orthonormal frame: r (right), u (up), f (forward). Spot lights use it as (r, u, f). */
typedef struct iir_frame {
    iir_vec3 r, u, f;
} iir_frame;

static inline float iir_sqr(float a)
{
    return a * a;
}
/* A float's bits and back (IEEE 754 binary32). */
static inline uint32_t iir_float_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}
static inline float iir_bits_float(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}
static inline float iir_safe_sqrt(float a)
{
    return sqrtf(a > 0.f ? a : 0.f);
}
static inline float iir_clampf(float a, float lo, float hi)
{
    return a < lo ? lo : (a > hi ? hi : a);
}
static inline float iir_radians(float deg)
{
    return deg * (IIR_PI / 180.f);
}
static inline float iir_degrees(float rad)
{
    return rad * (180.f / IIR_PI);
}

static inline iir_vec2 iir_v2(float x, float y)
{
    iir_vec2 v = {x, y};
    return v;
}
static inline iir_vec3 iir_v3(float x, float y, float z)
{
    iir_vec3 v = {x, y, z};
    return v;
}
static inline iir_vec3 iir_v3s(float s)
{
    return iir_v3(s, s, s);
}
static inline iir_vec3 iir_add(iir_vec3 a, iir_vec3 b)
{
    return iir_v3(a.x + b.x, a.y + b.y, a.z + b.z);
}
static inline iir_vec3 iir_sub(iir_vec3 a, iir_vec3 b)
{
    return iir_v3(a.x - b.x, a.y - b.y, a.z - b.z);
}
static inline iir_vec3 iir_mul(iir_vec3 a, iir_vec3 b)
{
    return iir_v3(a.x * b.x, a.y * b.y, a.z * b.z);
}
static inline iir_vec3 iir_scale(iir_vec3 a, float s)
{
    return iir_v3(a.x * s, a.y * s, a.z * s);
}
static inline iir_vec3 iir_neg(iir_vec3 a)
{
    return iir_v3(-a.x, -a.y, -a.z);
}
/* a + b * s */
static inline iir_vec3 iir_madd(iir_vec3 a, iir_vec3 b, float s)
{
    return iir_v3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s);
}
static inline float iir_dot(iir_vec3 a, iir_vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
static inline iir_vec3 iir_cross(iir_vec3 a, iir_vec3 b)
{
    return iir_v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float iir_length(iir_vec3 a)
{
    return sqrtf(iir_dot(a, a));
}
static inline float iir_length_sq(iir_vec3 a)
{
    return iir_dot(a, a);
}
static inline iir_vec3 iir_normalize(iir_vec3 a)
{
    float l = iir_length(a);
    return l > 0.f ? iir_scale(a, 1.f / l) : a;
}
static inline float iir_max_comp(iir_vec3 a)
{
    return fmaxf(a.x, fmaxf(a.y, a.z));
}
static inline float iir_luminance(iir_vec3 c)
{
    return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z;
}
static inline bool iir_is_finite3(iir_vec3 a)
{
    return isfinite(a.x) && isfinite(a.y) && isfinite(a.z);
}
static inline bool iir_is_black(iir_vec3 a)
{
    return a.x == 0.f && a.y == 0.f && a.z == 0.f;
}

/* Builds a frame whose f is `forward` (unit length) and whose u is as close to `up_hint` as
 * possible. Falls back to another hint when forward and up_hint are parallel (Duff et al. style
 * basis). */
static inline iir_frame iir_frame_from_forward(iir_vec3 forward, iir_vec3 up_hint)
{
    iir_frame fr;
    fr.f = iir_normalize(forward);
    iir_vec3 r = iir_cross(up_hint, fr.f);
    if (iir_length_sq(r) < 1e-10f)
        r = iir_cross(fabsf(fr.f.x) < 0.9f ? iir_v3(1, 0, 0) : iir_v3(0, 0, 1), fr.f);
    fr.r = iir_normalize(r);
    fr.u = iir_cross(fr.f, fr.r);
    return fr;
}

/* Frame about a normal n (as f), without a preferred up: branchless Duff et al. 2017. */
static inline iir_frame iir_frame_from_normal(iir_vec3 n)
{
    float sign = copysignf(1.f, n.z);
    float a = -1.f / (sign + n.z);
    float b = n.x * n.y * a;
    iir_frame fr;
    fr.r = iir_v3(1.f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    fr.u = iir_v3(b, sign + n.y * n.y * a, -n.y);
    fr.f = n;
    return fr;
}

static inline iir_vec3 iir_frame_to_world(const iir_frame *fr, iir_vec3 l)
{
    return iir_add(iir_add(iir_scale(fr->r, l.x), iir_scale(fr->u, l.y)), iir_scale(fr->f, l.z));
}
static inline iir_vec3 iir_frame_to_local(const iir_frame *fr, iir_vec3 w)
{
    return iir_v3(iir_dot(w, fr->r), iir_dot(w, fr->u), iir_dot(w, fr->f));
}

#ifdef __cplusplus
}
#endif
#endif

/* area_shape.c -- an area light's emitter inside its bounding rectangle (light.h, iir_area_shape):
 * checking a shape, its area, sampling a point uniformly on it and testing whether a point lies on
 * it. All in light-local q coordinates; not the world-space ray test (area_hit.c) nor the light's
 * radiometry (light.c, lightset.c). A shape has at most 64 triangles, so every call walks them:
 * no table to keep in step with the triangles, and the struct stays plain. */
#include "iir/light.h"

#include <math.h>
#include <stddef.h>

#include "sampling.h"

#define MIN_TRIANGLE_AREA 1e-7f /* of the unit rectangle: below it a triangle is degenerate */
#define OVERLAP_EPS 1e-6f       /* q units: triangles that share an edge touch, never overlap */

/* Twice the signed area of triangle t. */
static float cross2(const iir_vec2 t[3])
{
    return (t[1].x - t[0].x) * (t[2].y - t[0].y) - (t[1].y - t[0].y) * (t[2].x - t[0].x);
}

static float tri_area(const iir_vec2 t[3])
{
    return 0.5f * fabsf(cross2(t));
}

/* ---- checking ---- */

static bool corner_ok(iir_vec2 p)
{
    return isfinite(p.x) && isfinite(p.y) && fabsf(p.x) <= 0.5f && fabsf(p.y) <= 0.5f;
}

/* The extent of triangle t along axis n. */
static void project(const iir_vec2 t[3], iir_vec2 n, float *lo, float *hi)
{
    *lo = INFINITY, *hi = -INFINITY;
    for (int k = 0; k < 3; k++) {
        float x = t[k].x * n.x + t[k].y * n.y;
        *lo = fminf(*lo, x), *hi = fmaxf(*hi, x);
    }
}

/* True when a's edges separate it from b (by more than touching). */
static bool separated_by_edges_of(const iir_vec2 a[3], const iir_vec2 b[3])
{
    for (int k = 0; k < 3; k++) {
        iir_vec2 e = iir_v2(a[(k + 1) % 3].x - a[k].x, a[(k + 1) % 3].y - a[k].y);
        float len = sqrtf(e.x * e.x + e.y * e.y);
        if (!(len > 0.f)) continue;
        iir_vec2 n = iir_v2(-e.y / len, e.x / len);
        float alo, ahi, blo, bhi;
        project(a, n, &alo, &ahi);
        project(b, n, &blo, &bhi);
        if (ahi <= blo + OVERLAP_EPS || bhi <= alo + OVERLAP_EPS) return true;
    }
    return false;
}

/* Whether the interiors of triangles a and b overlap (separating axis test). */
static bool overlap(const iir_vec2 a[3], const iir_vec2 b[3])
{
    return !separated_by_edges_of(a, b) && !separated_by_edges_of(b, a);
}

const char *iir_area_shape_check(const iir_area_shape *s)
{
    if (s->num_triangles > IIR_AREA_MAX_TRIANGLES)
        return "has more than 64 triangles (IIR_AREA_MAX_TRIANGLES)";
    double sum = 0.0;
    for (uint32_t i = 0; i < s->num_triangles; i++) {
        for (int k = 0; k < 3; k++)
            if (!corner_ok(s->tri[i][k]))
                return "has a corner that is not finite or lies outside [-1/2, 1/2]^2";
        if (!(tri_area(s->tri[i]) >= MIN_TRIANGLE_AREA)) return "has a degenerate triangle";
        sum += tri_area(s->tri[i]);
    }
    if (sum > 1.0 + 1e-4) return "has overlapping triangles (they cover more than the rectangle)";
    for (uint32_t i = 0; i < s->num_triangles; i++)
        for (uint32_t j = i + 1; j < s->num_triangles; j++)
            if (overlap(s->tri[i], s->tri[j])) return "has overlapping triangles";
    return NULL;
}

/* ---- area, sampling, containment ---- */

float iir_area_shape_fraction(const iir_area_shape *s)
{
    if (s->num_triangles == 0) return 1.f;
    float sum = 0.f;
    for (uint32_t i = 0; i < s->num_triangles; i++) sum += tri_area(s->tri[i]);
    return sum;
}

float iir_area_light_area(const iir_light *l)
{
    return l->size.x * l->size.y * iir_area_shape_fraction(&l->shape);
}

iir_vec2 iir_area_light_sample_q(const iir_light *l, iir_vec2 u)
{
    const iir_area_shape *s = &l->shape;
    if (s->num_triangles == 0) return iir_v2(u.x - 0.5f, u.y - 0.5f);
    /* the triangle whose slice of the area CDF holds u.x; u.x rescaled inside the slice */
    float target = u.x * iir_area_shape_fraction(s), below = 0.f;
    uint32_t i = 0;
    float a = tri_area(s->tri[0]);
    while (i + 1 < s->num_triangles && below + a <= target) {
        below += a;
        a = tri_area(s->tri[++i]);
    }
    float ux = iir_clampf((target - below) / a, 0.f, 0x1.fffffep-1f);
    iir_vec2 b = iir_sample_uniform_triangle(iir_v2(ux, u.y));
    const iir_vec2 *t = s->tri[i];
    float b2 = 1.f - b.x - b.y;
    return iir_v2(b.x * t[0].x + b.y * t[1].x + b2 * t[2].x,
                  b.x * t[0].y + b.y * t[1].y + b2 * t[2].y);
}

/* Whether q lies in triangle t (either winding; edges included, to a float's rounding). */
static bool in_triangle(const iir_vec2 t[3], iir_vec2 q)
{
    float d[3];
    for (int k = 0; k < 3; k++) {
        iir_vec2 a = t[k], b = t[(k + 1) % 3];
        d[k] = (b.x - a.x) * (q.y - a.y) - (b.y - a.y) * (q.x - a.x);
    }
    const float eps = -1e-7f;
    return (d[0] >= eps && d[1] >= eps && d[2] >= eps) ||
           (d[0] <= -eps && d[1] <= -eps && d[2] <= -eps);
}

bool iir_area_light_contains(const iir_light *l, iir_vec2 q)
{
    if (!(fabsf(q.x) <= 0.5f && fabsf(q.y) <= 0.5f)) return false;
    const iir_area_shape *s = &l->shape;
    if (s->num_triangles == 0) return true;
    for (uint32_t i = 0; i < s->num_triangles; i++)
        if (in_triangle(s->tri[i], q)) return true;
    return false;
}

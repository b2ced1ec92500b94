/* scene_area.c -- area lights from the triangles of a material (scene_build.h): fitting a
 * one-sided planar set of triangles (its plane, its smallest bounding rectangle, and, when it is
 * not that rectangle, its shape in the rectangle's light-local coordinates), taking the triangles
 * out of the mesh, and the rule that turns a scene's emissive materials into movable area lights
 * when its sidecar gives no "lights" array. Not the sidecar's syntax (scene_sidecar.c) and not the
 * light's radiometry (lights/). */
#include "scene_build.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_RECT_TRIANGLES 1024 /* a material that forms one rectangle: any count up to this */
#define FLAT_TOLERANCE 1e-4     /* corners off the plane, relative to the larger side */
#define AREA_TOLERANCE 1e-3     /* covered area against the rectangle's, relative */

/* A material's triangles as a rectangle: the plane's unit normal n (the triangles' winding side),
 * the sides' unit directions a, b (b = n x a), the centre, the extents along a and b, the spread
 * of the corners along n, and the area the triangles cover. Double precision throughout. */
typedef struct rect_fit {
    double n[3], a[3], b[3], centre[3];
    double w, h, thickness, area;
} rect_fit;

static void sub3(const iir_vec3 p, const iir_vec3 q, double out[3])
{
    out[0] = (double)p.x - q.x, out[1] = (double)p.y - q.y, out[2] = (double)p.z - q.z;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double a[3], const double b[3], double out[3])
{
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

static bool normalize3(double v[3])
{
    double len = sqrt(dot3(v, v));
    if (!(len > 0.0)) return false;
    for (int k = 0; k < 3; k++) v[k] /= len;
    return true;
}

static bool uses_material(const iir_scene_builder *b, uint32_t t, const char *name)
{
    return strcmp(b->materials[b->tri_materials[t]].name, name) == 0;
}

static uint32_t count_triangles(const iir_scene_builder *b, const char *name)
{
    uint32_t n = 0;
    for (uint32_t t = 0; t < b->num_triangles; t++) n += uses_material(b, t, name);
    return n;
}

/* The corners of material `name`'s n triangles, 3 per triangle in winding order (malloc'd; NULL
 * when out of memory). */
static iir_vec3 *material_corners(const iir_scene_builder *b, const char *name, uint32_t n)
{
    iir_vec3 *c = malloc(sizeof(iir_vec3) * 3 * (size_t)n), *at = c;
    for (uint32_t t = 0; c && t < b->num_triangles; t++) {
        if (!uses_material(b, t, name)) continue;
        for (int k = 0; k < 3; k++) *at++ = b->positions[b->indices[3 * (size_t)t + (size_t)k]];
    }
    return c;
}

/* Twice the vector area of the triangle with corners c[0..2], (c1 - c0) x (c2 - c0). */
static void tri_cross(const iir_vec3 *c, double out[3])
{
    double e1[3], e2[3];
    sub3(c[1], c[0], e1);
    sub3(c[2], c[0], e2);
    cross3(e1, e2, out);
}

/* The n triangles' covered area and mean winding normal; false when they face several ways (a
 * triangle's normal more than about 1 degree off the mean). */
static bool fit_plane(const iir_vec3 *c, uint32_t n, rect_fit *f)
{
    double sum[3] = {0, 0, 0}, x[3];
    for (uint32_t t = 0; t < n; t++) {
        tri_cross(c + 3 * t, x);
        for (int k = 0; k < 3; k++) sum[k] += x[k];
        f->area += 0.5 * sqrt(dot3(x, x));
    }
    memcpy(f->n, sum, sizeof sum);
    if (!normalize3(f->n)) return false;
    for (uint32_t t = 0; t < n; t++) {
        tri_cross(c + 3 * t, x);
        double len = sqrt(dot3(x, x));
        if (len > 0.0 && dot3(x, f->n) < 0.9998 * len) return false;
    }
    return true;
}

/* The extents of the m corners, relative to c[0], along three unit axes: lo and hi per axis. */
static void extents(const iir_vec3 *c, uint32_t m, const double *axes[3], double lo[3],
                    double hi[3])
{
    for (int k = 0; k < 3; k++) lo[k] = INFINITY, hi[k] = -INFINITY;
    for (uint32_t v = 0; v < m; v++) {
        double d[3];
        sub3(c[v], c[0], d);
        for (int k = 0; k < 3; k++) {
            double x = dot3(d, axes[k]);
            lo[k] = fmin(lo[k], x), hi[k] = fmax(hi[k], x);
        }
    }
}

/* The box of the corners along side a (unit, in the plane), b = n x a and n, into f when its
 * area in the plane is below *best. */
static void try_side(const iir_vec3 *c, uint32_t m, double a[3], rect_fit *f, double *best)
{
    double b[3], lo[3], hi[3];
    cross3(f->n, a, b);
    const double *axes[3] = {a, b, f->n};
    extents(c, m, axes, lo, hi);
    double area = (hi[0] - lo[0]) * (hi[1] - lo[1]);
    if (!(area < *best)) return;
    *best = area;
    memcpy(f->a, a, sizeof f->a);
    memcpy(f->b, b, sizeof f->b);
    f->w = hi[0] - lo[0], f->h = hi[1] - lo[1], f->thickness = hi[2] - lo[2];
    double o[3] = {c[0].x, c[0].y, c[0].z};
    for (int k = 0; k < 3; k++)
        f->centre[k] = o[k] + 0.5 * ((lo[0] + hi[0]) * a[k] + (lo[1] + hi[1]) * b[k] +
                                     (lo[2] + hi[2]) * f->n[k]);
}

/* The smallest rectangle around the n triangles with a side along one of their edges (the
 * smallest bounding rectangle of a convex outline has a side on it). */
static void fit_rectangle(const iir_vec3 *c, uint32_t n, rect_fit *f)
{
    double best = INFINITY;
    for (uint32_t v = 0; v < 3 * n; v++) {
        double a[3];
        sub3(c[v % 3 == 2 ? v - 2 : v + 1], c[v], a); /* edge v -> its successor */
        double along = dot3(a, f->n);
        for (int k = 0; k < 3; k++) a[k] -= along * f->n[k];
        if (normalize3(a)) try_side(c, 3 * n, a, f, &best);
    }
}

/* The light from the rectangle: centre, normal, and as up the side more along y (a wall light's
 * vertical side; a ceiling panel's side more along z), pointing to +y (+z); size.x is the other
 * side's length (along r = up x f), size.y up's. */
static void rect_to_light(const rect_fit *f, iir_light *l)
{
    double ka = fabs(f->a[1]) - fabs(f->b[1]);
    if (fabs(ka) < 1e-6) ka = fabs(f->a[2]) - fabs(f->b[2]);
    bool a_up = ka > 0.0;
    const double *up = a_up ? f->a : f->b;
    double sign = (fabs(up[1]) > 1e-6 ? up[1] : up[2]) < 0.0 ? -1.0 : 1.0;
    l->position = iir_v3((float)f->centre[0], (float)f->centre[1], (float)f->centre[2]);
    l->direction = iir_v3((float)f->n[0], (float)f->n[1], (float)f->n[2]);
    l->up = iir_v3((float)(sign * up[0]), (float)(sign * up[1]), (float)(sign * up[2]));
    l->size = a_up ? iir_v2((float)f->h, (float)f->w) : iir_v2((float)f->w, (float)f->h);
}

/* Removes material `name`'s triangles from the builder (the rest keep their order). */
static void remove_triangles(iir_scene_builder *b, const char *name)
{
    uint32_t kept = 0;
    for (uint32_t t = 0; t < b->num_triangles; t++) {
        if (uses_material(b, t, name)) continue;
        memmove(&b->indices[3 * (size_t)kept], &b->indices[3 * (size_t)t], 3 * sizeof(uint32_t));
        b->tri_materials[kept++] = b->tri_materials[t];
    }
    b->num_triangles = kept;
}

/* ======================== the shape ======================== */

/* The light-local point q of world point c on light l (frame fr), clamped into the rectangle
 * (rounding puts corners a hair outside). */
static iir_vec2 light_local(const iir_light *l, const iir_frame *fr, iir_vec3 c)
{
    iir_vec3 d = iir_sub(c, l->position);
    float x = iir_dot(d, fr->r) / l->size.x, y = iir_dot(d, fr->u) / l->size.y;
    return iir_v2(iir_clampf(x, -0.5f, 0.5f), iir_clampf(y, -0.5f, 0.5f));
}

/* The n triangles (corners c) as l's shape, leaving out those too thin to carry area; false when
 * more than IIR_AREA_MAX_TRIANGLES are left. */
static bool make_shape(const iir_vec3 *c, uint32_t n, iir_light *l)
{
    iir_frame fr = iir_spot_frame(l);
    iir_area_shape *s = &l->shape;
    memset(s, 0, sizeof *s);
    for (uint32_t t = 0; t < n; t++) {
        iir_vec2 q[3];
        for (int k = 0; k < 3; k++) q[k] = light_local(l, &fr, c[3 * t + (uint32_t)k]);
        float area2 = (q[1].x - q[0].x) * (q[2].y - q[0].y) - (q[1].y - q[0].y) * (q[2].x - q[0].x);
        if (!(fabsf(area2) >= 2e-7f)) continue;
        if (s->num_triangles == IIR_AREA_MAX_TRIANGLES) return false;
        memcpy(s->tri[s->num_triangles++], q, sizeof q);
    }
    return true;
}

/* ======================== fitting a material ======================== */

/* Why the n triangles with corners c make no area light (into fit->why), or "" when they fill l's
 * pose, size and shape. */
static void fit_corners(const iir_vec3 *c, uint32_t n, iir_light *l, iir_area_fit *fit)
{
    rect_fit f;
    memset(&f, 0, sizeof f);
    const char *why = NULL;
    if (!fit_plane(c, n, &f))
        why = "has triangles facing different ways (two-sided or mixed facing)";
    if (!why) fit_rectangle(c, n, &f);
    fit->area = f.area, fit->w = f.w, fit->h = f.h;
    if (!why && !(f.thickness <= FLAT_TOLERANCE * fmax(f.w, f.h))) why = "is not flat";
    bool rect = !why && fabs(f.area - f.w * f.h) <= AREA_TOLERANCE * f.w * f.h;
    if (!why && !rect && f.area > f.w * f.h) why = "has overlapping triangles";
    if (why) {
        snprintf(fit->why, sizeof fit->why, "%s", why);
        return;
    }
    rect_to_light(&f, l);
    memset(&l->shape, 0, sizeof l->shape);
    if (rect) return;
    const char *bad = NULL;
    if (!make_shape(c, n, l))
        snprintf(fit->why, sizeof fit->why,
                 "has %u triangles and is not one rectangle: a shaped area light has at most %d", n,
                 IIR_AREA_MAX_TRIANGLES);
    else if ((bad = iir_area_shape_check(&l->shape)))
        snprintf(fit->why, sizeof fit->why, "%s", bad);
}

iir_status iir_builder_fit_area_light(const iir_scene_builder *b, const char *name, iir_light *l,
                                      iir_area_fit *fit)
{
    memset(fit, 0, sizeof *fit);
    uint32_t n = fit->triangles = count_triangles(b, name);
    if (n == 0) snprintf(fit->why, sizeof fit->why, "has no triangles");
    if (n > MAX_RECT_TRIANGLES)
        snprintf(fit->why, sizeof fit->why, "has %u triangles, more than %d", n,
                 MAX_RECT_TRIANGLES);
    if (fit->why[0]) return IIR_ERR_INVALID;
    iir_vec3 *c = material_corners(b, name, n);
    if (!c) {
        snprintf(fit->why, sizeof fit->why, "is too large for the memory left");
        return IIR_ERR_NOMEM;
    }
    iir_light tmp = *l;
    fit_corners(c, n, &tmp, fit);
    free(c);
    if (fit->why[0]) return IIR_ERR_INVALID;
    l->position = tmp.position, l->direction = tmp.direction, l->up = tmp.up;
    l->size = tmp.size, l->shape = tmp.shape;
    return IIR_OK;
}

void iir_builder_take_emitter(iir_scene_builder *b, const char *name)
{
    remove_triangles(b, name);
    for (uint32_t k = 0; k < b->num_materials; k++)
        if (strcmp(b->materials[k].name, name) == 0) b->materials[k].emission = iir_v3s(0.f);
}

/* ======================== emissive materials become lights ======================== */

static bool light_named(const iir_scene_builder *b, const char *name)
{
    for (uint32_t i = 0; i < b->num_lights; i++)
        if (strcmp(b->lights[i].name, name) == 0) return true;
    return false;
}

/* The material's name, or "NAME-2", "NAME-3"... when a light already has it. */
static void unique_light_name(const iir_scene_builder *b, const char *material, char *out, size_t n)
{
    snprintf(out, n, "%s", material);
    for (int k = 2; light_named(b, out) && k < 1000; k++)
        snprintf(out, n, "%.*s-%d", (int)(n - 8), material, k);
}

/* Whether material i is the first of its name (a name counts once: the sidecar's rule). */
static bool first_of_name(const iir_scene_builder *b, uint32_t i)
{
    return iir_builder_find_material(b, b->materials[i].name) == (int64_t)i;
}

/* Whether light l (its pose from material `name`'s n triangles) is one the scene can take; else
 * fills *why. */
static bool light_ok(const iir_scene_builder *b, const iir_light *l, uint32_t n, char *why,
                     size_t size)
{
    iir_error e;
    if (n == b->num_triangles)
        snprintf(why, size, "is all that is left of the scene's geometry");
    else if (iir_light_validate(l, &e) != IIR_OK)
        snprintf(why, size, "makes no valid light (%.100s)", e.msg);
    else
        return true;
    return false;
}

/* The note on material `name` that became light l. */
static void note_converted(iir_scene_builder *b, const char *name, const iir_light *l)
{
    char what[64] = "a rectangle";
    if (l->shape.num_triangles)
        snprintf(what, sizeof what, "a shape of %u triangles", l->shape.num_triangles);
    iir_builder_note(b, "material", name,
                     "emits light: became the movable area light '%s' (%s, %g x %g); a sidecar "
                     "with a \"lights\" array keeps it static",
                     l->name, what, (double)l->size.x, (double)l->size.y);
}

/* Emissive material i as a light, or a note saying why it stays emissive triangles. */
static iir_status convert_emitter(iir_scene_builder *b, uint32_t i, iir_error *err)
{
    char name[64];
    snprintf(name, sizeof name, "%s", b->materials[i].name);
    uint32_t n = count_triangles(b, name);
    if (n == 0) return IIR_OK;
    iir_light l;
    memset(&l, 0, sizeof l);
    l.type = IIR_LIGHT_AREA;
    l.intensity = b->materials[i].emission;
    unique_light_name(b, name, l.name, sizeof l.name);
    iir_area_fit fit;
    iir_status st = iir_builder_fit_area_light(b, name, &l, &fit);
    if (st == IIR_ERR_NOMEM) return iir_fail(err, st, "%s: out of memory", b->source);
    if (b->materials[i].emission_tex.texture) {
        st = IIR_ERR_UNSUPPORTED; /* an area light's radiance is uniform or an emission_map */
        snprintf(fit.why, sizeof fit.why, "has an emission texture");
    }
    if (st != IIR_OK || !light_ok(b, &l, n, fit.why, sizeof fit.why)) {
        iir_builder_note(b, "material", name,
                         "emits light: stays static emissive triangles, not a movable area "
                         "light: it %s",
                         fit.why);
        return IIR_OK;
    }
    st = iir_builder_add_light(b, &l, err);
    if (st != IIR_OK) return st;
    iir_builder_take_emitter(b, name);
    note_converted(b, name, &l);
    return IIR_OK;
}

iir_status iir_builder_emitters_to_lights(iir_scene_builder *b, iir_error *err)
{
    for (uint32_t i = 0; i < b->num_materials; i++) {
        if (iir_is_black(b->materials[i].emission) || !first_of_name(b, i)) continue;
        iir_status st = convert_emitter(b, i, err);
        if (st != IIR_OK) return st;
    }
    return IIR_OK;
}

/* lightset.c -- the light arriving at a point (light.h, after pbrt's Light::SampleLi): one light's
 * sample for a receiving point -- direction, distance, radiance, pdf -- and the one rule for the
 * shadow segment that tests it; and the lights next-event estimation chooses from: delta lights
 * (point, spots, suns), area lights (rectangles or shapes in them) and emissive triangles, picked
 * in proportion to their flux (luminance; a sun's is what crosses its disk), and the pdf of a BSDF
 * ray that meets one. Not the lights' own radiometry (light.c) nor the ray-rectangle test
 * (area_hit.c) or the shape (area_shape.c). */
#include "iir/light.h"
#include "surface.h"

#include <math.h>
#include <stdlib.h>

#include "iir/scene.h"
#include "sampling.h"

/* ======================== one light arriving at a point ======================== */

/* ---- the shadow segment ---- */

/* Whether n is a normal (not the zero vector of an end on no surface). */
static bool is_normal(iir_vec3 n)
{
    return iir_length_sq(n) > 0.f;
}

iir_vec3 iir_light_ctx_origin(const iir_light_ctx *ctx, iir_vec3 w)
{
    if (!is_normal(ctx->n)) return iir_madd(ctx->p, w, ctx->eps);
    iir_vec3 side = iir_dot(ctx->n, w) < 0.f ? iir_neg(ctx->n) : ctx->n;
    return iir_madd(ctx->p, side, ctx->eps);
}

iir_light_segment iir_light_shadow(iir_vec3 o, const iir_light_sample *ls, float eps)
{
    iir_light_segment seg = {o, ls->wi, INFINITY};
    if (isinf(ls->dist)) return seg;
    iir_vec3 d = iir_sub(iir_madd(ls->p_light, ls->n_light, eps), o);
    float len = iir_length(d), tmax = is_normal(ls->n_light) ? len : len - eps;
    seg.tmax = 0.f;
    if (!(tmax > 0.f)) return seg;
    seg.dir = iir_scale(d, 1.f / len);
    seg.tmax = tmax;
    return seg;
}

/* ---- one light ---- */

/* A sun: parallel light from -direction at no finite distance; Li is its irradiance E (a delta in
 * direction, so f Li cos is the estimate). */
static iir_light_sample sample_sun(const iir_light *l)
{
    iir_light_sample ls = {0};
    ls.wi = iir_neg(iir_normalize(l->direction));
    ls.dist = INFINITY;
    ls.Li = l->intensity;
    ls.pdf = 1.f;
    ls.is_delta = true;
    return ls;
}

/* A point or spot: I(-wi) / d^2 from its position. */
static iir_light_sample sample_point(const iir_light_eval *e, iir_vec3 x)
{
    iir_light_sample ls = {0};
    iir_vec3 d = iir_sub(e->light->position, x);
    float dist2 = iir_length_sq(d);
    if (!(dist2 > 0.f)) return ls;
    ls.dist = sqrtf(dist2);
    ls.wi = iir_scale(d, 1.f / ls.dist);
    ls.Li = iir_scale(iir_light_eval_intensity(e, iir_neg(ls.wi)), 1.f / dist2);
    ls.pdf = 1.f;
    ls.is_delta = true;
    ls.p_light = e->light->position;
    return ls;
}

/* An area light: a point uniform by area on its emitter; one-sided, so x must be in front. */
static iir_light_sample sample_area(const iir_light_eval *e, iir_vec3 x, iir_vec2 u)
{
    iir_light_sample ls = {0};
    const iir_light *l = e->light;
    iir_vec2 q = iir_area_light_sample_q(l, u);
    ls.p_light = iir_area_light_point(l, &e->frame, q);
    iir_vec3 d = iir_sub(ls.p_light, x);
    float dist2 = iir_length_sq(d);
    if (!(dist2 > 0.f)) return ls;
    ls.dist = sqrtf(dist2);
    ls.wi = iir_scale(d, 1.f / ls.dist);
    float cos_l = -iir_dot(e->frame.f, ls.wi);
    if (cos_l <= 0.f) return ls;
    ls.Li = iir_area_light_radiance(l, q);
    ls.pdf = dist2 / (cos_l * e->area);
    ls.n_light = e->frame.f;
    return ls;
}

iir_light_sample iir_light_sample_li(const iir_light_eval *e, const iir_light_ctx *ctx, iir_vec2 u)
{
    iir_light_sample ls;
    switch (e->light->type) {
    case IIR_LIGHT_SUN:
        ls = sample_sun(e->light);
        break;
    case IIR_LIGHT_AREA:
        ls = sample_area(e, ctx->p, u);
        break;
    default:
        ls = sample_point(e, ctx->p);
    }
    if (ls.pdf > 0.f) ls.shadow = iir_light_shadow(iir_light_ctx_origin(ctx, ls.wi), &ls, ctx->eps);
    return ls;
}

float iir_area_light_pdf(const iir_light *l, iir_vec3 wi, float dist)
{
    float cos_l = -iir_dot(iir_spot_frame(l).f, wi);
    return cos_l > 0.f ? dist * dist / (cos_l * iir_area_light_area(l)) : 0.f;
}

/* ======================== the light set ======================== */

struct iir_lightset {
    const iir_scene *scene;
    uint32_t num_punctual; /* the lights given, delta and area lights alike */
    iir_light *punctual;
    iir_light_eval *eval; /* punctual[i] prepared */
    bool has_area_light;  /* one of them is an area light */
    uint32_t num_entries; /* the lights given first, then emissive triangles */
    uint32_t *tri_of;     /* entry -> triangle (entries >= num_punctual) */
    float *cdf;           /* num_entries + 1, cdf[0] = 0, cdf[n] = 1 */
    uint32_t *entry_of;   /* triangle -> entry, UINT32_MAX if not emissive */
};

/* Triangle t's power for picking it (its emission factor: an emission texture scales it down). */
static float triangle_power(const iir_scene *s, uint32_t t)
{
    iir_vec3 Le = s->material_list[s->materials[t]].emission;
    return IIR_PI * s->areas[t] * iir_luminance(Le);
}

static uint32_t count_emissive(const iir_scene *s)
{
    uint32_t n = 0;
    for (uint32_t t = 0; t < s->num_triangles; t++) n += triangle_power(s, t) > 0.f;
    return n;
}

static void build_cdf(iir_lightset *set)
{
    const iir_scene *s = set->scene;
    double total = 0.0;
    set->cdf[0] = 0.f;
    for (uint32_t e = 0; e < set->num_entries; e++) {
        double w = e < set->num_punctual ? iir_luminance(iir_light_flux(&set->punctual[e]))
                                         : triangle_power(s, set->tri_of[e]);
        total += w;
        set->cdf[e + 1] = (float)total;
    }
    for (uint32_t e = 1; e <= set->num_entries; e++)
        set->cdf[e] = total > 0.0 ? (float)(set->cdf[e] / total) : 0.f;
    if (set->num_entries > 0 && total > 0.0) set->cdf[set->num_entries] = 1.f;
}

iir_lightset *iir_lightset_create(const iir_scene *scene, const iir_light *lights,
                                  uint32_t num_lights)
{
    iir_lightset *set = calloc(1, sizeof *set);
    if (!set) return NULL;
    set->scene = scene;
    set->num_punctual = num_lights;
    set->num_entries = num_lights + count_emissive(scene);
    set->punctual = malloc(sizeof(iir_light) * (num_lights ? num_lights : 1));
    set->eval = malloc(sizeof(iir_light_eval) * (num_lights ? num_lights : 1));
    set->tri_of = calloc(set->num_entries + 1, sizeof(uint32_t));
    set->cdf = calloc(set->num_entries + 1, sizeof(float));
    set->entry_of = malloc(sizeof(uint32_t) * (scene->num_triangles + 1));
    if (!set->punctual || !set->eval || !set->tri_of || !set->cdf || !set->entry_of) {
        iir_lightset_destroy(set);
        return NULL;
    }
    for (uint32_t i = 0; i < num_lights; i++) {
        set->punctual[i] = lights[i];
        set->eval[i] = iir_light_prepare(&set->punctual[i]);
        set->has_area_light |= lights[i].type == IIR_LIGHT_AREA;
    }
    uint32_t e = num_lights;
    for (uint32_t t = 0; t < scene->num_triangles; t++) {
        set->entry_of[t] = UINT32_MAX;
        if (triangle_power(scene, t) > 0.f) {
            set->entry_of[t] = e;
            set->tri_of[e++] = t;
        }
    }
    build_cdf(set);
    return set;
}

void iir_lightset_destroy(iir_lightset *set)
{
    if (!set) return;
    free(set->punctual);
    free(set->eval);
    free(set->tri_of);
    free(set->cdf);
    free(set->entry_of);
    free(set);
}

bool iir_lightset_empty(const iir_lightset *set)
{
    return set->num_entries == 0 || set->cdf[set->num_entries] <= 0.f;
}

bool iir_lightset_has_area_lights(const iir_lightset *set)
{
    return set->num_entries > set->num_punctual || set->has_area_light;
}

uint32_t iir_lightset_num_lights(const iir_lightset *set)
{
    return set->num_punctual;
}

static float entry_pmf(const iir_lightset *set, uint32_t e)
{
    return set->cdf[e + 1] - set->cdf[e];
}

/* Largest e with cdf[e] <= u, skipping zero-width entries. */
static uint32_t pick_entry(const iir_lightset *set, float u)
{
    uint32_t lo = 0, hi = set->num_entries;
    while (hi - lo > 1) {
        uint32_t mid = (lo + hi) / 2;
        if (set->cdf[mid] <= u)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* ---- meeting a light ---- */

iir_emitter_hit iir_lightset_hit_light(const iir_lightset *set, uint32_t i, iir_vec3 o, iir_vec3 d,
                                       float tmax)
{
    iir_emitter_hit h = {INFINITY, {0.f, 0.f, 0.f}, 0.f};
    if (i >= set->num_punctual || set->punctual[i].type != IIR_LIGHT_AREA) return h;
    const iir_light *l = &set->punctual[i];
    float t = iir_area_light_hit(l, o, d, tmax);
    if (isinf(t)) return h;
    h.t = t;
    h.Le = iir_area_light_radiance_at(l, &set->eval[i].frame, iir_madd(o, d, t));
    h.pdf = entry_pmf(set, i) * iir_area_light_pdf(l, d, t);
    return h;
}

/* ---- sampling the set ---- */

/* The light arriving at x from a point uniform by area on emissive triangle t, chosen with
 * probability pmf (its shadow segment left to the caller). */
static iir_light_sample sample_triangle(const iir_scene *s, uint32_t t, iir_vec3 x, float pmf,
                                        iir_vec2 u)
{
    iir_light_sample ls = {0};
    const uint32_t *idx = &s->indices[3 * t];
    iir_vec2 b = iir_sample_uniform_triangle(u);
    ls.p_light =
        iir_add(iir_add(iir_scale(s->positions[idx[0]], b.x), iir_scale(s->positions[idx[1]], b.y)),
                iir_scale(s->positions[idx[2]], 1.f - b.x - b.y));
    iir_vec3 d = iir_sub(ls.p_light, x);
    float dist2 = iir_length_sq(d);
    if (dist2 <= 0.f) return ls;
    ls.dist = sqrtf(dist2);
    ls.wi = iir_scale(d, 1.f / ls.dist);
    float cos_l = -iir_dot(s->normals[t], ls.wi); /* one-sided emission along the normal */
    if (cos_l <= 0.f) return ls;
    ls.Li = iir_surface_emission_at(s, t, b.y, 1.f - b.x - b.y);
    ls.pdf = pmf * dist2 / (cos_l * s->areas[t]);
    ls.n_light = s->normals[t];
    return ls;
}

iir_light_sample iir_lightset_sample_li(const iir_lightset *set, const iir_light_ctx *ctx,
                                        float u_pick, iir_vec2 u)
{
    iir_light_sample none = {0};
    if (iir_lightset_empty(set)) return none;
    uint32_t e = pick_entry(set, u_pick);
    float pmf = entry_pmf(set, e);
    if (pmf <= 0.f) return none;
    if (e < set->num_punctual) {
        iir_light_sample ls = iir_light_sample_li(&set->eval[e], ctx, u);
        ls.pdf *= pmf;
        return ls;
    }
    iir_light_sample ls = sample_triangle(set->scene, set->tri_of[e], ctx->p, pmf, u);
    if (ls.pdf > 0.f) ls.shadow = iir_light_shadow(iir_light_ctx_origin(ctx, ls.wi), &ls, ctx->eps);
    return ls;
}

float iir_lightset_pdf_area(const iir_lightset *set, uint32_t prim, iir_vec3 wi, float dist)
{
    const iir_scene *s = set->scene;
    if (prim >= s->num_triangles || set->entry_of[prim] == UINT32_MAX) return 0.f;
    float cos_l = -iir_dot(s->normals[prim], wi);
    if (cos_l <= 0.f) return 0.f;
    return entry_pmf(set, set->entry_of[prim]) * dist * dist / (cos_l * s->areas[prim]);
}

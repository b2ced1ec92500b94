/* hier_light.c -- the hierarchical method's direct light (hier_light.h): the lights' points for a
 * frame, and the voxel-shadowed irradiance they give a point (each asked of its light with
 * iir_light_sample_li). */
#include "hier_light.h"

#include <math.h>
#include <stdlib.h>

static bool grow_points(hier_lights *hl, uint32_t need)
{
    if (need <= hl->cap) return true;
    hier_point *p = realloc(hl->pts, sizeof *p * need);
    if (!p) return false;
    hl->pts = p;
    hl->cap = need;
    return true;
}

/* The grid of nx x ny cells an area light's K points sit at the centres of: as near square cells
 * on its rectangle as nx ny <= K allows. */
static void area_grid(const iir_light *l, int samples, int *nx, int *ny)
{
    float aspect = l->size.x / l->size.y;
    int x = (int)lroundf(sqrtf((float)samples * aspect));
    x = x < 1 ? 1 : x > samples ? samples : x;
    *nx = x;
    *ny = samples / x;
}

/* At most K points of area light l: the centres of a grid of cells over u in [0, 1)^2, mapped onto
 * its emitter by iir_light_sample_li (iir_area_light_sample_q: the rectangle's cells, or strata of
 * its shape), each dA = A / (nx ny) of it. Cell centres rather than a low-discrepancy set: the
 * points are as symmetric as the emitter, so a symmetric emitter lights a symmetric receiver
 * symmetrically. */
static void area_points(hier_lights *hl, const iir_light *l, uint32_t li, int samples)
{
    int nx, ny;
    area_grid(l, samples, &nx, &ny);
    float dA = iir_area_light_area(l) / (float)(nx * ny);
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            hier_point *p = &hl->pts[hl->num_pts++];
            p->u = iir_v2(((float)i + 0.5f) / (float)nx, ((float)j + 0.5f) / (float)ny);
            p->weight = 1.f / (float)(nx * ny);
            p->dA_over_pi = dA / (float)M_PI;
            p->light = li;
        }
}

bool hier_lights_prepare(hier_lights *hl, const iir_light *lights, uint32_t num_lights, int samples)
{
    hl->lights = lights;
    hl->num_lights = num_lights;
    hl->num_pts = 0;
    uint32_t need = 0;
    for (uint32_t i = 0; i < num_lights; i++)
        need += iir_light_is_delta(&lights[i]) ? 1u : (uint32_t)samples;
    if (!grow_points(hl, need)) return false;
    if (num_lights > hl->eval_cap) {
        iir_light_eval *e = realloc(hl->eval, sizeof *e * num_lights);
        if (!e) return false;
        hl->eval = e;
        hl->eval_cap = num_lights;
    }
    for (uint32_t i = 0; i < num_lights; i++) {
        const iir_light *l = &lights[i];
        hl->eval[i] = iir_light_prepare(l);
        if (!iir_light_is_delta(l)) {
            area_points(hl, l, i, samples);
            continue;
        }
        hier_point p = {{0.f, 0.f}, 1.f, 0.f, i};
        hl->pts[hl->num_pts++] = p;
    }
    return true;
}

void hier_lights_free(hier_lights *hl)
{
    free(hl->pts);
    free(hl->eval);
    hl->pts = NULL;
    hl->eval = NULL;
    hl->num_pts = hl->cap = hl->eval_cap = 0;
}

/* Whether shadow segment seg (a sun's cut at the scene's diameter) is blocked. */
static bool blocked(const hier_lights *hl, const iir_light_segment *seg)
{
    if (hl->vis == HIER_VIS_NONE || !hl->grid || !(seg->tmax > 0.f)) return false;
    float len = isinf(seg->tmax) ? 2.f * hl->scene_radius : seg->tmax;
    if (hl->vis == HIER_VIS_VOXELS)
        return iir_voxels_occluded(hl->grid, seg->org, iir_madd(seg->org, seg->dir, len), 0.f, 0.f);
    for (int i = 0; i < hl->vis_points; i++) {
        float t = len * ((float)i + 0.5f) / (float)hl->vis_points;
        if (iir_voxels_marked_at(hl->grid, iir_madd(seg->org, seg->dir, t))) return true;
    }
    return false;
}

/* Irradiance from point pt at x (normal n), unshadowed: Li cos / pdf, an area sample's as from a
 * disk of area dA (d^2 / (d^2 + dA / pi) of it: bounded where x comes close). */
static iir_vec3 unshadowed(const hier_point *pt, const iir_light_sample *ls, iir_vec3 n)
{
    float cos_x = iir_dot(n, ls->wi);
    if (ls->pdf <= 0.f || cos_x <= 0.f) return iir_v3s(0.f);
    float k = cos_x * pt->weight / ls->pdf;
    if (pt->dA_over_pi > 0.f) k *= ls->dist * ls->dist / (ls->dist * ls->dist + pt->dA_over_pi);
    return iir_scale(ls->Li, k);
}

/* The light of every point at x (normal n), each point's irradiance through the BSDF b toward wo
 * when b is given. */
static iir_vec3 direct(const hier_lights *hl, iir_vec3 x, iir_vec3 n, const iir_bsdf *b,
                       iir_vec3 wo, uint64_t *evals)
{
    iir_vec3 E = iir_v3s(0.f);
    iir_light_ctx ctx = {x, n, hl->offset};
    for (uint32_t k = 0; k < hl->num_pts; k++) {
        const hier_point *pt = &hl->pts[k];
        iir_light_sample ls = iir_light_sample_li(&hl->eval[pt->light], &ctx, pt->u);
        iir_vec3 e = unshadowed(pt, &ls, n);
        if (iir_is_black(e) || blocked(hl, &ls.shadow)) continue;
        E = iir_add(E, b ? iir_mul(e, iir_bsdf_f(b, wo, ls.wi)) : e);
    }
    *evals += hl->num_pts;
    return E;
}

iir_vec3 hier_direct(const hier_lights *hl, iir_vec3 x, iir_vec3 n, uint64_t *evals)
{
    return direct(hl, x, n, NULL, iir_v3s(0.f), evals);
}

iir_vec3 hier_direct_bsdf(const hier_lights *hl, iir_vec3 x, const iir_bsdf *b, iir_vec3 wo,
                          uint64_t *evals)
{
    return direct(hl, x, b->frame.f, b, wo, evals);
}

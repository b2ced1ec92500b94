/* hier_light.c -- the hierarchical method's direct light (hier_light.h): the lights' points for a
 * frame, and the voxel-shadowed irradiance they give a point. */
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
 * its emitter (iir_area_light_sample_q: the rectangle's cells, or strata of its shape), each
 * dA = A / (nx ny) of it. Cell centres rather than a low-discrepancy set: the points are as
 * symmetric as the emitter, so a symmetric emitter lights a symmetric receiver symmetrically. */
static void area_points(hier_lights *hl, const iir_light *l, uint32_t li, int samples)
{
    iir_frame fr = iir_spot_frame(l);
    int nx, ny;
    area_grid(l, samples, &nx, &ny);
    float dA = iir_area_light_area(l) / (float)(nx * ny);
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            iir_vec2 u = iir_v2(((float)i + 0.5f) / (float)nx, ((float)j + 0.5f) / (float)ny);
            hier_point *p = &hl->pts[hl->num_pts++];
            iir_vec2 q = iir_area_light_sample_q(l, u);
            p->p = iir_area_light_point(l, &fr, q);
            p->f = fr.f;
            p->L_dA = iir_scale(iir_area_light_radiance(l, q), dA);
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
        need += lights[i].type == IIR_LIGHT_AREA ? (uint32_t)samples : 1u;
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
        if (l->type == IIR_LIGHT_AREA) {
            area_points(hl, l, i, samples);
            continue;
        }
        hier_point *p = &hl->pts[hl->num_pts++];
        p->p = l->type == IIR_LIGHT_SUN ? iir_normalize(l->direction) : l->position;
        p->light = i;
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

/* Whether the segment from x' (x moved off its surface) to light point y, less the last `skip` of
 * it, is blocked. */
static bool blocked(const hier_lights *hl, iir_vec3 x, iir_vec3 y, float skip)
{
    if (hl->vis == HIER_VIS_NONE || !hl->grid) return false;
    if (hl->vis == HIER_VIS_VOXELS) return iir_voxels_occluded(hl->grid, x, y, 0.f, skip);
    iir_vec3 d = iir_sub(y, x);
    float len = iir_length(d), span = len - skip;
    for (int i = 0; span > 0.f && i < hl->vis_points; i++) {
        float t = span * ((float)i + 0.5f) / (float)hl->vis_points;
        if (iir_voxels_marked_at(hl->grid, iir_madd(x, d, t / len))) return true;
    }
    return false;
}

/* Irradiance from point pt at x (normal n), unshadowed; the shadow segment ends at *to, less its
 * last *skip: an area light's point moved off its emitter along the normal (the emitter usually
 * lies on a surface, whose cells are marked), a delta light's position less a cell's diagonal. */
static iir_vec3 unshadowed(const hier_lights *hl, const hier_point *pt, iir_vec3 x, iir_vec3 n,
                           iir_vec3 *to, float *skip)
{
    const iir_light *l = &hl->lights[pt->light];
    *skip = 0.f;
    if (l->type == IIR_LIGHT_SUN) {
        float c = -iir_dot(n, pt->p);
        *to = iir_madd(x, pt->p, -2.f * hl->scene_radius);
        return c > 0.f ? iir_scale(l->intensity, c) : iir_v3s(0.f);
    }
    iir_vec3 w = iir_sub(x, pt->p); /* from the light to the receiver */
    float d2 = iir_dot(w, w), cos_x = -iir_dot(n, w);
    *to = pt->p;
    *skip = hl->offset;
    if (!(d2 > 0.f) || cos_x <= 0.f) return iir_v3s(0.f);
    float d = sqrtf(d2);
    if (l->type == IIR_LIGHT_AREA) {
        float cos_l = iir_dot(pt->f, w) / d;
        if (cos_l <= 0.f) return iir_v3s(0.f);
        *to = iir_madd(pt->p, pt->f, hl->offset);
        *skip = 0.f;
        return iir_scale(pt->L_dA, cos_l * (cos_x / d) / (d2 + pt->dA_over_pi));
    }
    iir_vec3 I = iir_light_eval_intensity(&hl->eval[pt->light], iir_scale(w, 1.f / d));
    return iir_scale(I, cos_x / (d * d2));
}

iir_vec3 hier_direct(const hier_lights *hl, iir_vec3 x, iir_vec3 n, uint64_t *evals)
{
    iir_vec3 E = iir_v3s(0.f);
    iir_vec3 from = iir_madd(x, n, hl->offset);
    for (uint32_t k = 0; k < hl->num_pts; k++) {
        iir_vec3 to;
        float skip;
        iir_vec3 e = unshadowed(hl, &hl->pts[k], x, n, &to, &skip);
        if (iir_is_black(e) || blocked(hl, from, to, skip)) continue;
        E = iir_add(E, e);
    }
    *evals += hl->num_pts;
    return E;
}

/* whitted_tree.c -- the Whitted ray tree (Whitted 1980) of the methods whitted and hybrid, and
 * its parameters: a ray tree from each pixel centre, local shading with shadow rays to every light
 * at diffuse surfaces, perfect mirror reflection and glass refraction (specular.h: Snell, total
 * internal reflection, Fresnel weights) at specular ones, a tree depth limit and adaptive
 * tree-depth control. No indirect diffuse light: an optional ambient term (default 0) stands in for
 * it, as in Whitted's model. Not the optics (specular.h), not path tracing (pt.c) and not the
 * methods (whitted.c, hybrid.c).
 *
 * The tree. A ray that hits a surface returns its emission (one-sided, as pt's), the light of the
 * rectangular area lights it meets before the surface (they are not in the BVH), and:
 *   diffuse: (rho / pi) sum over lights of Li cos / pdf (a shadow ray each; delta lights once,
 *            area lights and the scene's emissive triangles with area_samples points each) plus
 *            ambient rho (local shading), and the caller's diffuse hook (hybrid: radiosity);
 *   mirror:  specular * L(R), R = V - 2 (V.N) N;
 *   glass:   F L(R) + (1 - F) tint L(T), T by Snell's law, only R past the critical angle.
 * A branch's weight is the product of the factors (F, 1 - F, tint, specular) on the way from the
 * camera; it is followed only while its depth (specular bounces) is at most max_depth and, the
 * adaptive control, its weight's largest channel is at least min_weight. A branch cut by the
 * weight would add at most weight x (the radiance it would find), so the image changes by at most
 * min_weight times the scene's largest radiance per cut branch; every cut is counted
 * (the methods' branches_cut counter: each saves its ray and the tree under it).
 *
 * Glass casts shadows (shadow rays stop at it): light through glass onto a diffuse surface, a
 * caustic, is not in Whitted's model. Frames are deterministic (area samples draw from a stream
 * hashed from the seed and the pixel), rendered by OpenMP over 16 x 16 tiles with no allocation
 * per pixel; a frame is final (no refinement). */
#include <math.h>
#include <omp.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "iir/rng.h"
#include "iir/timer.h"
#include "specular.h"
#include "surface.h"
#include "whitted_tree.h"

enum { TILE = 16 };

/* ---- parameters ---- */

static const iir_param ROWS[] = {
    {"max_depth", IIR_PARAM_INT, offsetof(whitted_params, max_depth), 8, 0, 64, 0, NULL, "bounces",
     "the ray tree's depth limit: specular bounces along a branch", IIR_PARAM_LIVE},
    {"min_weight", IIR_PARAM_FLOAT, offsetof(whitted_params, min_weight), 0.01, 0, 1, 0, NULL, "",
     "adaptive depth: a branch whose weight (largest channel) falls below this stops; 0 = full "
     "tree",
     IIR_PARAM_LIVE},
    {"area_samples", IIR_PARAM_INT, offsetof(whitted_params, area_samples), 4, 1, 4096, 1024, NULL,
     "points", "points per area light for its direct light", IIR_PARAM_LIVE},
    {"ambient", IIR_PARAM_FLOAT, offsetof(whitted_params, ambient), 0, 0, 1e6, 0, NULL, "",
     "ambient radiance (W/sr/m^2) times albedo at diffuse surfaces, Whitted's stand-in for "
     "indirect light",
     IIR_PARAM_LIVE},
};
const iir_param_table whitted_param_table = {"whitted: ray tree", ROWS,
                                             sizeof ROWS / sizeof ROWS[0], NULL};

/* ---- state ---- */

struct whitted_tree {
    const iir_scene *scene;
    const iir_rt *rt;
    iir_lightset *emitters; /* the scene's emissive triangles alone (no lights) */
    bool has_emitters;
    const whitted_frame *f;  /* during a render */
    const iir_light *lights; /* the view's, during a render */
    uint32_t num_lights;
    iir_light_eval eval[64]; /* the first 64 lights, prepared; the rest prepared per call */
    iir_camera_frame cam;
    float eps;
};

/* One pixel's tree: the state, its random stream (area samples), its counters. */
typedef struct tracer {
    const whitted_tree *w;
    iir_rng rng;
    iir_raystats *st;
    uint64_t cut; /* branches the adaptive control stopped */
} tracer;

/* ---- local shading ---- */

/* Light i of the view, prepared. */
static iir_light_eval light_eval(const whitted_tree *w, uint32_t i)
{
    return i < 64 ? w->eval[i] : iir_light_prepare(&w->lights[i]);
}

/* The light a surface point is shaded with, towards wo. */
typedef struct shading {
    const iir_surface *sf;
    iir_bsdf bsdf;
    iir_vec3 wo;
} shading;

/* f Li |cos| / pdf of sample ls at the point, or 0 when it arrives from below the surface or its
 * shadow segment is blocked. */
static iir_vec3 arriving(const tracer *t, const shading *sh, const iir_light_sample *ls)
{
    if (ls->pdf <= 0.f || iir_is_black(ls->Li)) return iir_v3s(0.f);
    iir_vec3 f_cos = iir_surface_f_cos(sh->sf, &sh->bsdf, sh->wo, ls->wi);
    if (iir_is_black(f_cos)) return iir_v3s(0.f);
    iir_ray r = iir_segment_ray(&ls->shadow);
    if (r.tfar > 0.f && iir_rt_occluded(t->w->rt, &r, t->st, IIR_RAYS_SHADOW)) return iir_v3s(0.f);
    return iir_scale(iir_mul(f_cos, ls->Li), 1.f / ls->pdf);
}

/* Mean of f Li cos / pdf over the samples of light e (area_samples points of an area light, or of
 * the scene's emissive triangles when e is NULL; a delta light's one), a shadow ray each. */
static iir_vec3 light_at(tracer *t, const shading *sh, const iir_light_eval *e)
{
    iir_light_ctx ctx = iir_surface_light_ctx(sh->sf, t->w->eps);
    if (e && iir_light_is_delta(e->light)) {
        iir_light_sample ls = iir_light_sample_li(e, &ctx, iir_v2(0.f, 0.f));
        return arriving(t, sh, &ls);
    }
    int n = t->w->f->p->area_samples;
    iir_vec3 sum = iir_v3s(0.f);
    for (int k = 0; k < n; k++) {
        iir_vec2 u = iir_rng_uniform2(&t->rng);
        iir_light_sample ls =
            e ? iir_light_sample_li(e, &ctx, u)
              : iir_lightset_sample_li(t->w->emitters, &ctx, iir_rng_uniform(&t->rng), u);
        sum = iir_add(sum, arriving(t, sh, &ls));
    }
    return iir_scale(sum, 1.f / (float)n);
}

/* Direct light reflected by rough sf towards wo by its full BSDF (the classic local model), plus
 * the ambient term on its diffuse albedo and the caller's diffuse hook. */
static iir_vec3 diffuse(tracer *t, const iir_surface *sf, const iir_hit *hit, iir_vec3 wo)
{
    const whitted_tree *w = t->w;
    shading sh = {sf, iir_surface_bsdf(sf), wo};
    iir_vec3 L = w->f->extra ? w->f->extra(w->f->extra_ctx, hit, sf->albedo) : iir_v3s(0.f);
    L = iir_madd(L, sf->albedo, w->f->p->ambient);
    for (uint32_t i = 0; w->f->local_direct && i < w->num_lights; i++) {
        iir_light_eval e = light_eval(w, i);
        L = iir_add(L, light_at(t, &sh, &e));
    }
    if (w->f->local_direct && w->has_emitters) L = iir_add(L, light_at(t, &sh, NULL));
    return L;
}

/* The radiance of the view's area lights that the ray meets from the front before t_max. */
static iir_vec3 area_lights_seen(const whitted_tree *w, const iir_ray *ray, float t_max)
{
    iir_vec3 L = iir_v3s(0.f);
    for (uint32_t i = 0; i < w->num_lights; i++) {
        const iir_light *l = &w->lights[i];
        if (iir_light_is_delta(l)) continue;
        float t = iir_area_light_hit(l, ray->org, ray->dir, t_max);
        if (isinf(t)) continue;
        iir_light_eval e = light_eval(w, i);
        L = iir_add(L, iir_area_light_radiance_at(l, &e.frame, iir_madd(ray->org, ray->dir, t)));
    }
    return L;
}

/* ---- the tree ---- */

static iir_vec3 trace(tracer *t, iir_ray ray, int depth, iir_vec3 weight);

/* The branch leaving sf along wi with the given weight, or 0 when the depth limit or the adaptive
 * control stops it (the latter counted). */
static iir_vec3 branch(tracer *t, const iir_surface *sf, iir_vec3 wi, int depth, iir_vec3 weight)
{
    if (depth >= t->w->f->p->max_depth || iir_is_black(weight)) return iir_v3s(0.f);
    if (iir_max_comp(weight) < t->w->f->p->min_weight) {
        t->cut++;
        return iir_v3s(0.f);
    }
    iir_vec3 side = iir_dot(wi, sf->n) < 0.f ? iir_neg(sf->n) : sf->n;
    iir_ray ray = iir_make_ray(iir_madd(sf->p, side, t->w->eps), wi, 0.f, INFINITY);
    return trace(t, ray, depth + 1, weight);
}

/* What a specular surface passes on: the mirror's reflection, glass's two Fresnel branches. */
static iir_vec3 specular(tracer *t, const iir_surface *sf, iir_vec3 V, int depth, iir_vec3 weight)
{
    if (sf->kind == IIR_MATERIAL_MIRROR)
        return iir_mul(sf->specular,
                       branch(t, sf, iir_reflect(V, sf->n), depth, iir_mul(weight, sf->specular)));
    iir_glass_split g = iir_glass_at(V, sf->n, sf->ior);
    iir_vec3 L = iir_scale(branch(t, sf, g.wr, depth, iir_scale(weight, g.F)), g.F);
    if (!g.has_t) return L;
    iir_vec3 kt = iir_scale(sf->specular, 1.f - g.F);
    return iir_add(L, iir_mul(kt, branch(t, sf, g.wt, depth, iir_mul(weight, kt))));
}

/* A metal_rough surface smoother than IIR_MIRROR_ROUGHNESS also reflects like a mirror of
 * reflectance F(n.wo) (Schlick, the BSDF's f0) besides its local shading: Whitted's recursion for
 * the near-mirrors (a chrome ball of roughness 0.05) that the local model alone would show as a
 * highlight on black. */
static iir_vec3 smooth_reflection(tracer *t, const iir_surface *sf, iir_vec3 V, int depth,
                                  iir_vec3 weight)
{
    iir_vec3 wi, F;
    if (!iir_surface_mirror_reflection(sf, V, &wi, &F)) return iir_v3s(0.f);
    return iir_mul(F, branch(t, sf, wi, depth, iir_mul(weight, F)));
}

/* Radiance along ray, a branch `depth` specular bounces from the camera with weight `weight`. */
static iir_vec3 trace(tracer *t, iir_ray ray, int depth, iir_vec3 weight)
{
    const whitted_tree *w = t->w;
    iir_hit hit;
    iir_ray_kind kind = depth == 0 ? IIR_RAYS_CAMERA : IIR_RAYS_BOUNCE;
    bool found = iir_rt_intersect(w->rt, &ray, &hit, t->st, kind);
    iir_vec3 L = area_lights_seen(w, &ray, found ? hit.t : INFINITY);
    if (!found) return L;
    iir_vec3 wo = iir_neg(ray.dir);
    /* a camera ray reads textures over its pixel's footprint (a ray cone) */
    float spread = 2.f * w->cam.tan_half_y / (float)w->cam.height;
    iir_surface sf = depth == 0 ? iir_surface_at_cone(w->scene, &hit, wo, spread * hit.t)
                                : iir_surface_at(w->scene, &hit, wo);
    L = iir_add(L, iir_surface_Le(&sf, wo));
    if (iir_surface_is_rough(&sf)) {
        L = iir_add(L, diffuse(t, &sf, &hit, wo));
        return iir_add(L, smooth_reflection(t, &sf, ray.dir, depth, weight));
    }
    return iir_add(L, specular(t, &sf, ray.dir, depth, weight));
}

/* ---- pixels and tiles ---- */

static bool render_tile(const whitted_tree *w, int tile, iir_image *out, iir_raystats *st,
                        uint64_t *cut)
{
    const iir_camera_frame *cam = &w->cam;
    int tiles_x = (cam->width + TILE - 1) / TILE;
    int x0 = (tile % tiles_x) * TILE, y0 = (tile / tiles_x) * TILE;
    int x1 = x0 + TILE < cam->width ? x0 + TILE : cam->width;
    int y1 = y0 + TILE < cam->height ? y0 + TILE : cam->height;
    for (int y = y0; y < y1; y++) {
        if (y > y0 && w->f->stop && w->f->stop(w->f->stop_ctx)) return false;
        for (int x = x0; x < x1; x++) {
            tracer t = {w, iir_rng_make(w->f->seed, iir_hash3((uint64_t)x, (uint64_t)y, 0)), st, 0};
            iir_vec3 dir = iir_camera_dir(cam, (float)x + 0.5f, (float)y + 0.5f);
            iir_vec3 L = trace(&t, iir_make_ray(cam->origin, dir, 0.f, INFINITY), 0, iir_v3s(1.f));
            *iir_image_at(out, x, y) = iir_is_finite3(L) ? L : iir_v3s(0.f);
            *cut += t.cut;
        }
    }
    return true;
}

static iir_status render_tiles(const whitted_tree *w, iir_image *out, iir_frame_stats *stats,
                               iir_error *err)
{
    int tiles = ((w->cam.width + TILE - 1) / TILE) * ((w->cam.height + TILE - 1) / TILE);
    iir_raystats total = {0};
    uint64_t cut_total = 0;
    bool stopped = false;
#pragma omp parallel
    {
        iir_raystats local = {0};
        uint64_t cut = 0;
#pragma omp for schedule(dynamic, 1)
        for (int k = 0; k < tiles; k++) {
            if ((w->f->stop && w->f->stop(w->f->stop_ctx)) ||
                !render_tile(w, k, out, &local, &cut)) {
#pragma omp atomic write
                stopped = true;
            }
        }
#pragma omp critical(iir_whitted_rays)
        {
            iir_raystats_add(&total, &local);
            cut_total += cut;
        }
    }
    stats->rays = total;
    stats->counter[WHITTED_BRANCHES_CUT] = (double)cut_total;
    if (stopped) return iir_fail(err, IIR_ERR_INTERRUPTED, "whitted: frame stopped early");
    return IIR_OK;
}

/* ---- the tree's life ---- */

whitted_tree *whitted_tree_create(const iir_scene *scene, const iir_rt *rt)
{
    whitted_tree *w = calloc(1, sizeof *w);
    if (w) w->emitters = iir_lightset_create(scene, NULL, 0);
    if (!w || !w->emitters) {
        free(w);
        return NULL;
    }
    w->scene = scene;
    w->rt = rt;
    w->has_emitters = !iir_lightset_empty(w->emitters);
    return w;
}

void whitted_tree_destroy(whitted_tree *w)
{
    if (!w) return;
    iir_lightset_destroy(w->emitters);
    free(w);
}

iir_status whitted_tree_render(whitted_tree *w, const whitted_frame *f, const iir_view *view,
                               iir_image *out, iir_frame_stats *stats, iir_error *err)
{
    w->f = f;
    w->lights = view->lights;
    w->num_lights = view->num_lights;
    for (uint32_t i = 0; i < view->num_lights && i < 64; i++)
        w->eval[i] = iir_light_prepare(&view->lights[i]);
    w->cam = iir_camera_setup(&view->camera, out->width, out->height);
    w->eps = iir_rt_epsilon(w->rt);
    iir_status st = render_tiles(w, out, stats, err);
    w->lights = NULL, w->f = NULL;
    return st;
}

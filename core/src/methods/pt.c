/* pt.c -- the reference path tracer (method "pt"): next-event estimation with MIS for area
 * lights (emissive triangles and rectangular area lights), mirrors and glass as delta BSDFs
 * (specular.h: no next-event estimation there, emission found through them counts fully; a
 * specular bounce counts as a bounce), Russian roulette, a maximum bounce count, deterministic
 * seeds, OpenMP over tiles, and progressive refinement (more samples into the same frame).
 * Parameters: spp and bounces (below), seed, jitter, refine_passes: render + refines of spp samples
 * each are converged once the image holds refine_passes samples per pixel, or one frame's spp when
 * that is more (pt_converged_spp); a refine call still adds its samples after that, so a caller can
 * reach any count.
 *
 * Bounces count reflections: a light path light -> x_k -> ... -> x_1 -> camera has k of them, so
 * bounces = 1 is direct light only and bounces = 2 adds one diffuse bounce. Emitters seen directly
 * (k = 0) always count. Sample s of pixel (x, y) draws from the stream hash(x, y, s) of the seed,
 * so an image depends on the seed and the sample count only, not on threads or tile order.
 *
 * A rectangular area light (IIR_LIGHT_AREA) is not in the BVH: every ray also tests the view's
 * area lights (iir_lightset_hit_light) up to its surface, or to infinity when it hits none, adds
 * the emission of each one it meets from the front and goes on through them (they cast no
 * shadow). */
#include <omp.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "iir/method.h"
#include "iir/rng.h"
#include "iir/scene.h"
#include "method_internal.h"
#include "sampling.h"
#include "specular.h"
#include "surface.h"
#include "iir/timer.h"

enum { TILE = 16, RR_START = 3 };

typedef struct pt_options {
    iir_method_common common;
    int spp;     /* samples per pixel per render or refine call */
    int bounces; /* 1 = direct only, 2 = one diffuse bounce */
} pt_options;

static const iir_param PT_ROWS[] = {
    {"spp", IIR_PARAM_INT, offsetof(pt_options, spp), 1, 1, 1 << 20, 64, NULL, "samples",
     "samples per pixel per frame and per refinement pass", IIR_PARAM_LIVE},
};
static const iir_param_table PT_TABLE = {"pt: path tracing", PT_ROWS,
                                         sizeof PT_ROWS / sizeof PT_ROWS[0], NULL};

typedef struct pt_state {
    const iir_scene *scene;
    const iir_rt *rt;
    pt_options params;
    iir_lightset *lights;
    bool has_area_lights; /* emissive triangles or area lights: BSDF rays can find light */
    bool has_area_light;  /* a rectangular area light among the view's lights */
    bool has_blend;       /* a material with alphaMode BLEND: stochastic transparency */
    iir_camera_frame cam;
    float spread;   /* a camera ray's cone angle: the pixel's height over the focal length */
    iir_image *sum; /* sum of samples; the frame is sum / spp_done */
    uint64_t spp_done;
    iir_stop_fn stop; /* a live session's: polled per tile */
    void *stop_ctx;
} pt_state;

/* Samples per pixel of a converged frame: refine_passes of them, rounded up to whole passes of
 * spp (so at least one frame's spp). */
static uint64_t pt_converged_spp(const pt_options *o)
{
    uint64_t spp = (uint64_t)o->spp, want = (uint64_t)o->common.refine_passes;
    return (want + spp - 1) / spp * spp;
}

static uint64_t pt_converged_at(const void *opts)
{
    return pt_converged_spp(opts);
}

static float power_heuristic(float pdf_a, float pdf_b)
{
    float a2 = pdf_a * pdf_a, b2 = pdf_b * pdf_b;
    return a2 + b2 > 0.f ? a2 / (a2 + b2) : 0.f;
}

/* ---- the estimator ---- */

/* Direct light at sf by sampling one light: f Li |cos| / pdf, MIS-weighted against the BSDF.
 * Light arriving from below the geometric surface counts for nothing, whatever the shading normal
 * says (no light leaks through a normal-mapped or smooth-shaded surface). */
static iir_vec3 estimate_direct(const pt_state *pt, const iir_surface *sf, const iir_bsdf *bsdf,
                                iir_vec3 wo, iir_rng *rng, iir_raystats *st)
{
    float u_pick = iir_rng_uniform(rng);
    iir_light_ctx ctx = iir_surface_light_ctx(sf, iir_rt_epsilon(pt->rt));
    iir_light_sample ls = iir_lightset_sample_li(pt->lights, &ctx, u_pick, iir_rng_uniform2(rng));
    if (ls.pdf <= 0.f || iir_is_black(ls.Li)) return iir_v3s(0.f);
    iir_vec3 f_cos = iir_surface_f_cos(sf, bsdf, wo, ls.wi);
    if (iir_is_black(f_cos)) return iir_v3s(0.f);

    iir_ray shadow = iir_segment_ray(&ls.shadow);
    bool blocked = pt->has_blend ? iir_rt_occluded_blend(pt->rt, &shadow, iir_rng_u32(rng), st,
                                                         IIR_RAYS_SHADOW)
                                 : iir_rt_occluded(pt->rt, &shadow, st, IIR_RAYS_SHADOW);
    if (blocked) return iir_v3s(0.f);

    float w = ls.is_delta ? 1.f : power_heuristic(ls.pdf, iir_bsdf_pdf(bsdf, wo, ls.wi));
    return iir_scale(iir_mul(f_cos, ls.Li), w / ls.pdf);
}

/* The emission of the area lights that the ray meets from the front before t_max, times beta,
 * MIS-weighted against light sampling unless the ray is the camera's (pdf_bsdf 0). */
static iir_vec3 area_lights_seen(const pt_state *pt, const iir_ray *ray, float t_max,
                                 float pdf_bsdf, iir_vec3 beta)
{
    iir_vec3 L = iir_v3s(0.f);
    if (!pt->has_area_light) return L;
    uint32_t n = iir_lightset_num_lights(pt->lights);
    for (uint32_t i = 0; i < n; i++) {
        iir_emitter_hit h = iir_lightset_hit_light(pt->lights, i, ray->org, ray->dir, t_max);
        if (isinf(h.t)) continue;
        float w = pdf_bsdf > 0.f ? power_heuristic(pdf_bsdf, h.pdf) : 1.f;
        L = iir_add(L, iir_scale(iir_mul(beta, h.Le), w));
    }
    return L;
}

/* Russian roulette once paths are long enough to matter: false when the path ends (killed, or
 * its throughput is black); a survivor's beta is divided by its survival probability. */
static bool russian_roulette(int vertex, iir_vec3 *beta, iir_rng *rng)
{
    if (vertex >= RR_START) {
        float q = fmaxf(0.05f, 1.f - iir_max_comp(*beta));
        if (iir_rng_uniform(rng) < q) return false;
        *beta = iir_scale(*beta, 1.f / (1.f - q));
    }
    return !iir_is_black(*beta);
}

/* A delta BSDF's bounce of the ray travelling along V at sf (mirror or glass, specular.h): the
 * new direction *wi and the throughput factor f cos / pdf (the mirror's reflectance; glass picks
 * reflection with probability F, so its weight is 1 reflected and the tint refracted). */
static iir_vec3 sample_specular(const iir_surface *sf, iir_vec3 V, float u, iir_vec3 *wi)
{
    if (sf->kind == IIR_MATERIAL_MIRROR) {
        *wi = iir_reflect(V, sf->n);
        return sf->specular;
    }
    iir_glass_split g = iir_glass_at(V, sf->n, sf->ior);
    bool reflect = !g.has_t || u < g.F;
    *wi = reflect ? g.wr : g.wt;
    return reflect ? iir_v3s(1.f) : sf->specular;
}

/* A ray leaving sf along wi, lifted off the surface on wi's side (refraction leaves through the
 * back). */
static iir_ray leave(const iir_surface *sf, iir_vec3 wi, float eps)
{
    iir_vec3 side = iir_dot(wi, sf->n) < 0.f ? iir_neg(sf->n) : sf->n;
    return iir_make_ray(iir_madd(sf->p, side, eps), wi, 0.f, INFINITY);
}

static iir_vec3 Li(const pt_state *pt, iir_ray ray, iir_rng *rng, iir_raystats *st)
{
    const int max_bounces = pt->params.bounces;
    iir_vec3 L = iir_v3s(0.f), beta = iir_v3s(1.f);
    float pdf_bsdf = 0.f; /* pdf of the direction that led here; 0 for the camera ray */

    for (int vertex = 1;; vertex++) {
        iir_hit hit;
        iir_ray_kind kind = vertex == 1 ? IIR_RAYS_CAMERA : IIR_RAYS_BOUNCE;
        bool found = pt->has_blend
                         ? iir_rt_intersect_blend(pt->rt, &ray, iir_rng_u32(rng), &hit, st, kind)
                         : iir_rt_intersect(pt->rt, &ray, &hit, st, kind);
        L = iir_add(L, area_lights_seen(pt, &ray, found ? hit.t : INFINITY, pdf_bsdf, beta));
        if (!found) break;
        iir_vec3 wo = iir_neg(ray.dir);
        /* the camera ray reads textures over its pixel's footprint, later ones their finest level
         */
        iir_surface sf = vertex == 1 ? iir_surface_at_cone(pt->scene, &hit, wo, pt->spread * hit.t)
                                     : iir_surface_at(pt->scene, &hit, wo);

        /* Emission found by BSDF sampling, MIS-weighted against light sampling. */
        iir_vec3 Le = iir_surface_Le(&sf, wo);
        if (!iir_is_black(Le)) {
            float w = 1.f;
            if (pdf_bsdf > 0.f)
                w = power_heuristic(pdf_bsdf,
                                    iir_lightset_pdf_area(pt->lights, hit.prim, ray.dir, hit.t));
            L = iir_add(L, iir_scale(iir_mul(beta, Le), w));
        }
        if (vertex > max_bounces) break;

        /* A mirror or glass: no next-event estimation (a delta BSDF never meets a sampled light);
           what the bounce finds counts fully (pdf_bsdf 0: no MIS). */
        if (!iir_surface_is_rough(&sf)) {
            iir_vec3 wi;
            beta = iir_mul(beta, sample_specular(&sf, ray.dir, iir_rng_uniform(rng), &wi));
            pdf_bsdf = 0.f;
            if (!russian_roulette(vertex, &beta, rng)) break;
            ray = leave(&sf, wi, iir_rt_epsilon(pt->rt));
            continue;
        }

        /* Next-event estimation: a light path with `vertex` reflections. */
        iir_bsdf bsdf = iir_surface_bsdf(&sf);
        L = iir_add(L, iir_mul(beta, estimate_direct(pt, &sf, &bsdf, wo, rng, st)));
        if (vertex == max_bounces && !pt->has_area_lights) break;

        /* Continue in a direction sampled from the BSDF (the lobe picked by uc when it has two),
           above the geometric surface only. */
        float uc = sf.kind == IIR_MATERIAL_METAL_ROUGH ? iir_rng_uniform(rng) : 0.f;
        iir_bsdf_sample bs;
        if (!iir_bsdf_sample_f(&bsdf, wo, uc, iir_rng_uniform2(rng), &bs)) break;
        iir_vec3 f_cos = iir_surface_f_cos_sampled(&sf, &bs);
        if (iir_is_black(f_cos) || !(bs.pdf > 0.f)) break;
        beta = iir_mul(beta, iir_scale(f_cos, 1.f / bs.pdf));
        pdf_bsdf = bs.flags & IIR_BSDF_SPECULAR ? 0.f : bs.pdf;

        if (!russian_roulette(vertex, &beta, rng)) break;
        ray = iir_make_ray(iir_surface_offset(&sf, iir_rt_epsilon(pt->rt)), bs.wi, 0.f, INFINITY);
    }
    return L;
}

/* ---- pixels and tiles ---- */

/* Adds spp samples to the tile's pixels; false when the stop hook, asked before every row after
 * the first (a row of a 16-pixel tile at 64 samples is milliseconds; a whole tile can be a tenth
 * of a second), said stop. */
static bool render_tile(pt_state *pt, int tile, int spp, iir_raystats *st)
{
    const iir_camera_frame *cam = &pt->cam;
    int tiles_x = (cam->width + TILE - 1) / TILE;
    int x0 = (tile % tiles_x) * TILE, y0 = (tile / tiles_x) * TILE;
    int x1 = x0 + TILE < cam->width ? x0 + TILE : cam->width;
    int y1 = y0 + TILE < cam->height ? y0 + TILE : cam->height;
    for (int y = y0; y < y1; y++) {
        if (y > y0 && pt->stop && pt->stop(pt->stop_ctx)) return false;
        for (int x = x0; x < x1; x++) {
            iir_vec3 sum = iir_v3s(0.f);
            for (uint64_t s = pt->spp_done; s < pt->spp_done + (uint64_t)spp; s++) {
                iir_rng rng =
                    iir_rng_make(pt->params.common.seed, iir_hash3((uint64_t)x, (uint64_t)y, s));
                iir_vec2 j = iir_rng_uniform2(&rng);
                if (!pt->params.common.jitter) j = iir_v2(0.5f, 0.5f);
                iir_vec3 dir = iir_camera_dir(cam, (float)x + j.x, (float)y + j.y);
                iir_vec3 L = Li(pt, iir_make_ray(cam->origin, dir, 0.f, INFINITY), &rng, st);
                if (iir_is_finite3(L)) sum = iir_add(sum, L);
            }
            iir_vec3 *acc = iir_image_at(pt->sum, x, y);
            *acc = iir_add(*acc, sum);
        }
    }
    return true;
}

/* Adds spp samples to every pixel's sum; once the stop hook says stop, the tiles not begun are
 * skipped, the sum is forgotten (spp_done 0: refine must start over) and IIR_ERR_INTERRUPTED. */
static iir_status accumulate(pt_state *pt, int spp, iir_frame_stats *stats, iir_error *err)
{
    double t0 = iir_now_ms();
    int tiles = ((pt->cam.width + TILE - 1) / TILE) * ((pt->cam.height + TILE - 1) / TILE);
    iir_raystats total = {0};
    bool stopped = false;
#pragma omp parallel
    {
        iir_raystats local = {0};
#pragma omp for schedule(dynamic, 1)
        for (int t = 0; t < tiles; t++) {
            if ((pt->stop && pt->stop(pt->stop_ctx)) || !render_tile(pt, t, spp, &local)) {
#pragma omp atomic write
                stopped = true;
            }
        }
#pragma omp critical(iir_pt_rays)
        iir_raystats_add(&total, &local);
    }
    stats->rays = total;
    if (stopped) {
        pt->spp_done = 0;
        return iir_fail(err, IIR_ERR_INTERRUPTED, "pt: frame stopped early");
    }
    pt->spp_done += (uint64_t)spp;
    stats->rays = total;
    stats->phase_ms[IIR_PHASE_TRACE] = iir_now_ms() - t0;
    stats->total_ms = stats->phase_ms[IIR_PHASE_TRACE];
    stats->samples_per_pixel = pt->spp_done;
    stats->converged = pt->spp_done >= pt_converged_spp(&pt->params);
    return IIR_OK;
}

static void resolve(const pt_state *pt, iir_image *out)
{
    float inv = 1.f / (float)pt->spp_done;
    size_t n = (size_t)out->width * (size_t)out->height;
    for (size_t i = 0; i < n; i++) out->pixels[i] = iir_scale(pt->sum->pixels[i], inv);
}

/* ---- the method interface ---- */

static iir_status pt_create(const iir_scene *scene, const iir_rt *rt, const void *opts,
                            const iir_stop *stop, void **state, iir_error *err)
{
    (void)stop; /* allocations only: nothing here takes long enough to poll */
    pt_state *pt = calloc(1, sizeof *pt);
    if (!pt) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating the path tracer");
    pt->scene = scene;
    pt->has_blend = iir_scene_has_blend(scene);
    pt->rt = rt;
    pt->params = *(const pt_options *)opts;
    *state = pt;
    return IIR_OK;
}

static void pt_destroy(void *state)
{
    pt_state *pt = state;
    if (!pt) return;
    iir_lightset_destroy(pt->lights);
    iir_image_destroy(pt->sum);
    free(pt);
}

static iir_status pt_render(void *state, const iir_view *view, iir_image *out,
                            iir_frame_stats *stats, iir_error *err)
{
    pt_state *pt = state;
    iir_status st = iir_view_validate(view, err);
    if (st != IIR_OK) return st;
    iir_lightset_destroy(pt->lights);
    pt->lights = iir_lightset_create(pt->scene, view->lights, view->num_lights);
    if (!pt->sum || pt->sum->width != out->width || pt->sum->height != out->height) {
        iir_image_destroy(pt->sum);
        pt->sum = iir_image_create(out->width, out->height);
    }
    if (!pt->lights || !pt->sum) return iir_fail(err, IIR_ERR_NOMEM, "out of memory in pt");
    pt->has_area_lights = iir_lightset_has_area_lights(pt->lights);
    pt->has_area_light = false;
    for (uint32_t i = 0; i < view->num_lights; i++)
        pt->has_area_light |= !iir_light_is_delta(&view->lights[i]);
    pt->cam = iir_camera_setup(&view->camera, out->width, out->height);
    pt->spread = 2.f * pt->cam.tan_half_y / (float)pt->cam.height;
    iir_image_clear(pt->sum);
    pt->spp_done = 0;
    st = accumulate(pt, pt->params.spp, stats, err);
    if (st == IIR_OK) resolve(pt, out);
    return st;
}

static iir_status pt_refine(void *state, iir_image *out, iir_frame_stats *stats, iir_error *err)
{
    pt_state *pt = state;
    if (!pt->sum || pt->spp_done == 0)
        return iir_fail(err, IIR_ERR_INVALID, "pt: refine called before any frame was rendered");
    if (out->width != pt->sum->width || out->height != pt->sum->height)
        return iir_fail(err, IIR_ERR_INVALID, "pt: refine needs a %dx%d image, got %dx%d",
                        pt->sum->width, pt->sum->height, out->width, out->height);
    iir_status st = accumulate(pt, pt->params.spp, stats, err);
    if (st == IIR_OK) resolve(pt, out);
    return st;
}

static void pt_set_stop(void *state, iir_stop_fn fn, void *ctx)
{
    pt_state *pt = state;
    pt->stop = fn;
    pt->stop_ctx = ctx;
}

static void pt_update(void *state, const void *opts)
{
    ((pt_state *)state)->params = *(const pt_options *)opts;
}

static uint64_t pt_memory(const void *opts, int width, int height)
{
    (void)opts;
    return (uint64_t)width * (uint64_t)height * sizeof(iir_vec3); /* the sum image */
}

/* Mirrors and glass at too few bounces: a camera path spends iir_material_specular_depth bounces
 * on one before it reaches a rough surface, which then shows only the bounces left (Li ends the
 * path after `bounces` of them); with none left the material is black. One warning for each such
 * material, with the bounces that show the direct light through it and the image's own diffuse
 * bounces there. */
static uint32_t pt_dropped_by_params(const iir_scene *scene, const void *opts, iir_dropped *out,
                                     uint32_t max)
{
    const pt_options *o = opts;
    uint32_t n = 0;
    for (uint32_t i = 0; i < scene->num_materials; i++) {
        const iir_material *m = &scene->material_list[i];
        int depth = iir_material_specular_depth(m);
        if (!depth || o->bounces > depth) continue;
        bool glass = depth > 1;
        char more[64] = ""; /* the image's own diffuse bounces there, when it has any */
        if (o->bounces > 1)
            snprintf(more, sizeof more, ", %d as the rest of the image", depth + o->bounces);
        iir_dropped_add(out, max, &n, "pt", "material", m->name,
                        "is %s: at bounces %d pt's paths end %s it, so it shows black; bounces %d "
                        "shows the direct light %s it%s",
                        glass ? "glass" : "a mirror", o->bounces, glass ? "inside" : "on",
                        depth + 1, glass ? "through" : "in", more);
    }
    return n;
}

const iir_method_ops iir_method_pt = {
    .name = "pt",
    .summary = "path tracer: the reference (next-event estimation, Russian roulette)",
    .tables = {{&PT_TABLE, 0},
               {&iir_bounces_table, offsetof(pt_options, bounces)},
               {&iir_common_table, offsetof(pt_options, common)}},
    .opts_size = sizeof(pt_options),
    .create = pt_create,
    .destroy = pt_destroy,
    .render = pt_render,
    .refine = pt_refine,
    .vpls = NULL,
    .set_stop = pt_set_stop,
    .update = pt_update,
    .memory = pt_memory,
    .converged_at = pt_converged_at,
    .dropped_by_params = pt_dropped_by_params,
    .phases = {IIR_PHASE_TRACE, IIR_PHASE_COUNT},
};

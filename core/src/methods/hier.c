/* hier.c -- hierarchical image-space shading (Nichols, Shopf & Wyman 2009, with Nichols & Wyman's
 * multiresolution splatting), method "hier": all light is shaded in image space on hierarchies of
 * the G-buffer, coarse where it is smooth, with cheap visibility:
 *  - direct light from every light of the view, an area light as K point samples, shadowed by a
 *    coarse voxel grid of the scene (3DDA, or a few probes along the ray) -- hier_light.h -- on a
 *    quadtree refined at depth and normal discontinuities and where the light at neighbouring
 *    corners differs (light_split), so cone edges, shadow edges and the spot's pool end at pixel
 *    resolution -- render/light_tree.h;
 *  - one-bounce indirect light gathered from the lights' reflective shadow maps without
 *    visibility, as rsm does (rsm_map.h), on the multiresolution hierarchy (multires.h: coarse
 *    where the surface is smooth, per pixel at discontinuities).
 * Its failures are the chart's: shadows that stop at voxel resolution (light leaks through thin
 * walls and under contacts, stair-stepped penumbrae a cell wide), RSM's leaks in the bounced light
 * and its gather pattern's streaks, which the coarse texels turn into blotches.
 *
 * The voxel grid is built once, when the method is created (the scene is static); the maps and the
 * direct light's tree every frame; the bounce hierarchy when the G-buffer changes. The renderer
 * (render.h) gives the G-buffer and the light of emissive triangles (with its exact shadow rays);
 * an area light seen by the camera is added here. No refinement: a frame is what the method
 * gives. */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>

#include "hier_light.h"
#include "iir/method.h"
#include "iir/multires.h"
#include "iir/timer.h"
#include "iir/vplsets.h"
#include "method_internal.h"
#include "../render/light_tree.h"
#include "../render/render_internal.h"
#include "rsm_map.h"

/* ---- parameters ---- */

typedef struct hier_options {
    iir_method_common common;
    float clamp;
    iir_rsm_options rsm;
    iir_mr_params mr;
    int samples;   /* K points per area light */
    int voxel_res; /* cells along the scene's longest side */
    hier_visibility vis;
    int vis_points;
} hier_options;

static const char *const VIS_CHOICES[] = {"voxels", "points", "none", NULL};

static const iir_param HIER_ROWS[] = {
    {"area_samples", IIR_PARAM_INT, offsetof(hier_options, samples), 64, 1, 4096, 1024, NULL,
     "points", "points per area light for its direct light", IIR_PARAM_LIVE},
    {"voxel_res", IIR_PARAM_INT, offsetof(hier_options, voxel_res), 128, 4, 1024, 512, NULL,
     "cells", "voxel grid cells along the scene's longest side (built once per scene)",
     IIR_PARAM_RESTART},
    {"hier_visibility", IIR_PARAM_ENUM, offsetof(hier_options, vis), HIER_VIS_VOXELS, 0, 2, 0,
     VIS_CHOICES, "",
     "direct light's shadows: voxels (3DDA through the grid), points (probe the grid at "
     "vis_points points along the ray) or none",
     IIR_PARAM_LIVE},
    {"vis_points", IIR_PARAM_INT, offsetof(hier_options, vis_points), 4, 1, 64, 0, NULL, "points",
     "hier_visibility points: probes per shadow ray", IIR_PARAM_LIVE},
};
static const iir_param_table HIER_TABLE = {"hier: direct light and voxel visibility", HIER_ROWS,
                                           sizeof HIER_ROWS / sizeof HIER_ROWS[0], NULL};

/* ---- state ---- */

typedef struct hier_state {
    const iir_scene *scene;
    const iir_rt *rt;
    hier_options o;
    iir_renderer *renderer;
    iir_voxels *grid;
    iir_multires *mr;
    uint64_t gb_serial; /* G-buffers rendered: the hierarchy's key */
    hier_lights lights;
    light_tree tree; /* the direct light */
    rsm_map maps[IIR_VPLSETS_MAX_LIGHTS];
    uint32_t num_maps;
    rsm_pattern pattern;
    iir_vec3 *E; /* per pixel: the demodulated bounce light (the direct light: tree.D) */
    size_t E_cap;
    iir_stop_fn stop;
    void *stop_ctx;
} hier_state;

/* ---- shading ---- */

/* Demodulated bounce light at receiver q from the lights' maps; adds the gather samples to
 * *evals. */
static iir_vec3 bounce_point(const hier_state *s, const rsm_receiver *q, uint64_t *evals)
{
    iir_vec3 E = iir_v3s(0.f);
    for (uint32_t l = 0; l < s->num_maps; l++)
        E = iir_add(E, rsm_gather_map(&s->pattern, &s->maps[l], q));
    *evals += (uint64_t)s->num_maps * (uint64_t)s->pattern.m;
    return E;
}

/* multires.h's callback: every sample evaluates everything (no interleaving). */
static uint64_t shade_samples(void *ctx, int item, int m, uint32_t cls, iir_mr_samples *src,
                              int count, iir_vec3 *E, iir_raystats *st)
{
    (void)item, (void)m, (void)cls, (void)st;
    const hier_state *s = ctx;
    const iir_mr_sample *smp = iir_mr_samples_read(src);
    uint64_t evals = 0;
    for (int i = 0; i < count; i++) {
        rsm_receiver q = rsm_receiver_at(smp[i].position, smp[i].normal);
        E[i] = bounce_point(s, &q, &evals);
    }
    return evals;
}

/* The pixels at discontinuities (level 0; the hierarchy marks the glossy ones too, as their light
 * depends on the view): evaluated here, per pixel, a glossy one by its full BSDF. */
static uint64_t shade_pixels(hier_state *s, const iir_gbuffer *gb, const uint8_t *levels)
{
    const int n = gb->width * gb->height;
    uint64_t evals = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : evals)
    for (int p = 0; p < n; p++) {
        if (levels[p] != 0) continue;
        rsm_receiver q = rsm_receiver_pixel(gb, (size_t)p);
        s->E[p] = isfinite(gb->depth[p]) ? bounce_point(s, &q, &evals) : iir_v3s(0.f);
    }
    return evals;
}

/* The direct light of the glossy pixels, evaluated per pixel by their full BSDF over the tree's
 * (which interpolates irradiance), demodulated as their bounce light is (iir_gb_demod). */
static uint64_t glossy_direct(hier_state *s, const iir_gbuffer *gb)
{
    const int n = gb->width * gb->height;
    uint64_t evals = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : evals)
    for (int p = 0; p < n; p++) {
        if (!isfinite(gb->depth[p]) || !iir_gb_glossy(gb, (size_t)p, IIR_RECEIVER_GLOSSY)) continue;
        rsm_receiver q = rsm_receiver_pixel(gb, (size_t)p);
        iir_vec3 L = hier_direct_bsdf(&s->lights, q.x, &q.bsdf, q.wo, &evals);
        s->tree.D[p] = iir_mul(L, q.demod_pi);
    }
    return evals;
}

/* Adds every pixel's light to out: its demodulated direct and bounce light times the
 * demodulation (iir_gb_demod: the albedo where diffuse), over pi, times what its specular chain
 * passes on. */
static void compose(const hier_state *s, const iir_gbuffer *gb, iir_image *out)
{
    const size_t n = (size_t)gb->width * gb->height;
#pragma omp parallel for schedule(static)
    for (size_t p = 0; p < n; p++) {
        iir_vec3 demod = gb->any_pbr ? iir_gb_demod(gb, p, IIR_RECEIVER_GLOSSY) : gb->albedo[p];
        iir_vec3 L = iir_mul(demod, iir_add(s->tree.D[p], s->E[p]));
        if (gb->any_chain) L = iir_mul(L, gb->through[p]);
        out->pixels[p] = iir_madd(out->pixels[p], L, 1.f / (float)M_PI);
    }
}

/* The light tree's points: the lights' irradiance at their G-buffer samples (light_tree_eval_fn).
 */
static uint64_t tree_points(void *ctx, const uint32_t *px, int n, iir_vec3 *D, iir_raystats *st)
{
    (void)st; /* hier's shadows are voxel walks, not rays */
    const hier_state *s = ctx;
    const iir_gbuffer *gb = iir_renderer_gbuffer(s->renderer);
    uint64_t evals = 0;
    for (int i = 0; i < n; i++)
        D[px[i]] = hier_direct(&s->lights, gb->position[px[i]], gb->normal[px[i]], &evals);
    return evals;
}

/* Fills s->E (bounce light) for every pixel -- the hierarchy's levels, then the level-0 pixels --
 * and s->tree.D (direct light) on the tree refined from that hierarchy where the light changes;
 * times them as the indirect and direct phases. */
static iir_status shade(hier_state *s, const iir_gbuffer *gb, iir_frame_stats *stats,
                        iir_error *err)
{
    size_t n = (size_t)gb->width * (size_t)gb->height;
    if (n > s->E_cap) {
        iir_vec3 *E = realloc(s->E, sizeof *E * n);
        if (!E) return iir_fail(err, IIR_ERR_NOMEM, "hier: out of memory for the frame");
        s->E = E, s->E_cap = n;
    }
    uint64_t evals = 0;
    double t0 = iir_now_ms();
    iir_status st = iir_multires_build(s->mr, gb, s->gb_serial, &s->o.mr, 1, err);
    if (st != IIR_OK) return st;
    if (iir_multires_shade(s->mr, shade_samples, s, 1u, s->E, s->stop, s->stop_ctx, &stats->rays,
                           &evals))
        return iir_fail(err, IIR_ERR_INTERRUPTED, "frame stopped early");
    evals += shade_pixels(s, gb, iir_multires_levels(s->mr));
    double t = iir_now_ms();
    stats->phase_ms[IIR_PHASE_INDIRECT] = t - t0;
    const iir_stop stop = {s->stop, s->stop_ctx};
    light_tree_input in = {gb, s->mr, tree_points, s, s->o.mr.mr_levels, s->o.mr.light_split};
    st = light_tree_shade(&s->tree, &in, &stop, &evals, &stats->rays, err);
    if (st == IIR_OK && gb->any_pbr) evals += glossy_direct(s, gb);
    stats->phase_ms[IIR_PHASE_DIRECT] = iir_now_ms() - t;
    stats->vpl_evals = evals;
    return st;
}

/* ---- the frame ---- */

static iir_status render_maps(hier_state *s, const iir_view *view, iir_frame_stats *stats,
                              iir_error *err)
{
    const iir_stop stop = {s->stop, s->stop_ctx};
    iir_status st = rsm_maps_render(s->maps, &s->num_maps, s->o.rsm.res, view->lights,
                                    view->num_lights, s->scene, s->rt, "hier", &stop, stats, err);
    return st;
}

/* Area lights seen by the camera: their radiance where a camera ray meets one from the front
 * before the G-buffer's surface. */
static void add_seen_area_lights(const iir_view *view, const iir_gbuffer *gb, iir_image *out)
{
    iir_camera_frame cf = iir_camera_setup(&view->camera, gb->width, gb->height);
    for (uint32_t i = 0; i < view->num_lights; i++) {
        const iir_light *l = &view->lights[i];
        if (iir_light_is_delta(l)) continue;
        iir_frame fr = iir_spot_frame(l);
#pragma omp parallel for schedule(dynamic, 4)
        for (int y = 0; y < gb->height; y++)
            for (int x = 0; x < gb->width; x++) {
                size_t p = (size_t)y * gb->width + x;
                iir_vec3 d = iir_camera_dir(&cf, (float)x + 0.5f, (float)y + 0.5f);
                float t = iir_area_light_hit(l, view->camera.position, d, gb->camera_t[p]);
                if (!isinf(t))
                    out->pixels[p] = iir_add(
                        out->pixels[p],
                        iir_area_light_radiance_at(l, &fr, iir_madd(view->camera.position, d, t)));
            }
    }
}

static iir_status hier_render(void *state, const iir_view *view, iir_image *out,
                              iir_frame_stats *stats, iir_error *err)
{
    hier_state *s = state;
    iir_status st = iir_view_validate(view, err);
    if (st != IIR_OK) return st;
    double t0 = iir_now_ms();
    st = render_maps(s, view, stats, err);
    if (st == IIR_OK &&
        !hier_lights_prepare(&s->lights, view->lights, view->num_lights, s->o.samples))
        st = iir_fail(err, IIR_ERR_NOMEM, "hier: out of memory for the light points");
    if (st != IIR_OK) return st;
    double t1 = iir_now_ms();
    iir_indirect_params ind = iir_indirect_params_default();
    ind.visibility = IIR_VIS_RAYS, ind.interleave = 1; /* no lights, no VPLs: G-buffer, emitters */
    iir_render_timing rt;
    iir_render_input in = {.camera = &view->camera,
                           .seed = iir_frame_direct_seed(s->o.common.seed)};
    st = iir_renderer_frame(s->renderer, &in, &ind, out, &rt, &stats->rays, err);
    if (st != IIR_OK) return st;
    s->gb_serial += !rt.gbuffer_cached;
    const iir_gbuffer *gb = iir_renderer_gbuffer(s->renderer);
    st = shade(s, gb, stats, err);
    if (st != IIR_OK) return st;
    compose(s, gb, out);
    add_seen_area_lights(view, gb, out);
    stats->phase_ms[IIR_PHASE_GBUFFER] = rt.gbuffer_ms;
    stats->phase_ms[IIR_PHASE_DIRECT] += rt.direct_ms; /* the emitters the camera sees */
    stats->phase_ms[IIR_PHASE_MAPS] = t1 - t0;
    stats->total_ms = iir_now_ms() - t0;
    return IIR_OK;
}

/* ---- the method interface ---- */

static void hier_destroy(void *state)
{
    hier_state *s = state;
    if (!s) return;
    for (uint32_t l = 0; l < IIR_VPLSETS_MAX_LIGHTS; l++) rsm_map_free(&s->maps[l]);
    rsm_pattern_free(&s->pattern);
    hier_lights_free(&s->lights);
    light_tree_free(&s->tree);
    iir_multires_destroy(s->mr);
    iir_voxels_destroy(s->grid);
    iir_renderer_destroy(s->renderer);
    free(s->E);
    free(s);
}

/* The lights' visibility settings from the options. */
static void apply(hier_state *s, const hier_options *o)
{
    s->o = *o;
    s->lights.grid = s->grid;
    s->lights.vis = o->vis;
    s->lights.vis_points = o->vis_points;
    s->lights.offset = sqrtf(3.f) * iir_voxels_cell_size(s->grid);
    iir_vec3 e = iir_sub(s->scene->bounds_max, s->scene->bounds_min);
    s->lights.scene_radius = 0.5f * iir_length(e);
}

static iir_status hier_create(const iir_scene *scene, const iir_rt *rt, const void *opts,
                              const iir_stop *stop, void **state, iir_error *err)
{
    const hier_options *o = opts;
    hier_state *s = calloc(1, sizeof *s);
    if (!s) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating hier");
    s->scene = scene;
    s->rt = rt;
    iir_status st = iir_voxels_build(scene, o->voxel_res, stop, &s->grid, err);
    s->renderer = iir_renderer_create(scene, rt);
    if (s->renderer) iir_renderer_follow_specular(s->renderer, IIR_VPL_SPECULAR_DEPTH);
    s->mr = iir_multires_create();
    if (st == IIR_OK &&
        (!s->renderer || !s->mr ||
         !rsm_pattern_build(&s->pattern, &o->rsm, iir_clamp_g_max(scene, o->clamp))))
        st = iir_fail(err, IIR_ERR_NOMEM, "out of memory creating hier");
    if (st != IIR_OK) {
        hier_destroy(s);
        return st;
    }
    apply(s, o);
    *state = s;
    return IIR_OK;
}

static void hier_update(void *state, const void *opts)
{
    hier_state *s = state;
    const hier_options *o = opts;
    if (rsm_pattern_build(&s->pattern, &o->rsm, iir_clamp_g_max(s->scene, o->clamp)))
        apply(s, o); /* out of memory: the old parameters stay, with their pattern */
}

static void hier_set_stop(void *state, iir_stop_fn fn, void *ctx)
{
    hier_state *s = state;
    s->stop = fn;
    s->stop_ctx = ctx;
    iir_renderer_set_stop(s->renderer, fn, ctx);
}

/* The renderer's G-buffer and scratch, the hierarchy (about a third of a level-0 copy), E, the
 * direct light's tree, one light's map, the voxel grid (for a cube: the worst case). */
static uint64_t hier_memory(const void *opts, int width, int height)
{
    const hier_options *o = opts;
    uint64_t px = (uint64_t)width * (uint64_t)height;
    uint64_t texels = (uint64_t)o->rsm.res * (uint64_t)o->rsm.res;
    return iir_renderer_memory(width, height) + px * (48 + 12) + light_tree_memory(width, height) +
           texels * sizeof(iir_vpl) + iir_voxels_memory(iir_v3s(1.f), o->voxel_res) +
           (uint64_t)o->rsm.samples * 12;
}

/* The maps come from the lights only: emitters' indirect light is left out. */
static uint32_t hier_dropped(const iir_scene *scene, const iir_light *lights, uint32_t num_lights,
                             iir_dropped *out, uint32_t max)
{
    return rsm_maps_dropped("hier", scene, lights, num_lights, out, max);
}

const iir_method_ops iir_method_hier = {
    .name = "hier",
    .summary = "hierarchical image-space shading: direct light with voxel shadows and RSM bounce "
               "light on a multiresolution G-buffer",
    .tables = {{&HIER_TABLE, 0},
               {&iir_rsm_table, offsetof(hier_options, rsm)},
               {&iir_multires_table, offsetof(hier_options, mr)},
               {&iir_clamp_table, offsetof(hier_options, clamp)},
               {&iir_common_table, offsetof(hier_options, common)}},
    .opts_size = sizeof(hier_options),
    .create = hier_create,
    .destroy = hier_destroy,
    .render = hier_render,
    .set_stop = hier_set_stop,
    .update = hier_update,
    .memory = hier_memory,
    .dropped = hier_dropped,
    .full_surfaces = true,
    .phases = {IIR_PHASE_MAPS, IIR_PHASE_GBUFFER, IIR_PHASE_INDIRECT, IIR_PHASE_DIRECT,
               IIR_PHASE_COUNT},
};

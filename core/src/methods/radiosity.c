/* radiosity.c -- patch radiosity (Cohen & Greenberg 1985; Cohen & Wallace 1993), method
 * "radiosity", and its parameter table (shared with hybrid.c): the scene meshed into patches
 * (radiosity/mesh.c), hemicube form factors computed once per scene and cached on disk
 * (radiosity/hemicube.c, ffcache.c), and per frame the lights' direct light shot onto the patches
 * and the system re-solved (radiosity/solution.c, solve.c). The solution is displayed by Gouraud
 * interpolation through the G-buffer. Not the solution itself.
 *
 * The equation, per patch i (B radiosity, W/m^2): B_i = E_i + rho_i sum_j F_ij B_j, with
 *     E_i = pi Le_i + rho_i Ed_i,
 * Le_i the patch material's emitted radiance and Ed_i the irradiance from the view's lights (the
 * mean over light_samples points of the patch, one shadow ray each). A moving light changes only
 * Ed, so a frame re-shoots direct light and re-solves with the cached F.
 *
 * Display. Per patch an irradiance H_i is averaged to the vertices (area-weighted over the patches
 * around a vertex) and interpolated over each patch (barycentrics of the pixel's point in its
 * sub-triangle); a pixel shows L = rho_x H(x) / pi plus:
 *  - direct = pixels (default): the renderer's exact direct light and emission per pixel (shadow
 *    rays, crisp shadows), and H_i = sum_j F_ij (B_j - pi Le_j), the light of one bounce or more;
 *  - direct = patches: the G-buffer's emission only, and H_i = Ed_i + sum_j F_ij B_j, all light at
 *    patch resolution (area lights seen directly by the camera are then not drawn).
 *
 * Solvers: gauss (dense, refused above RAD_GAUSS_MAX patches), gauss_seidel (iterations sweeps
 * or relative change below tolerance; from the last frame's B, so a moving light costs few sweeps),
 * progressive (a frame shoots shoot_batch patches, each refine call another batch, converged when
 * the unshot power is below tolerance times the emitted; the ambient term is displayed with the
 * partial solution). */
#include <math.h>
#include <omp.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "../radiosity/radiosity.h"
#include "iir/method.h"
#include "iir/timer.h"
#include "method_internal.h"

/* ---- parameters ---- */

typedef struct rad_options {
    iir_method_common common;
    rad_params r;
} rad_options;

static const char *const SOLVER_CHOICES[] = {"gauss", "gauss_seidel", "progressive", NULL};
static const char *const DIRECT_CHOICES[] = {"patches", "pixels", NULL};

static const iir_param ROWS[] = {
    {"patch_area", IIR_PARAM_FLOAT, offsetof(rad_params, patch_area), 0.002, 1e-6, 1, 0, NULL, "",
     "largest patch area, as a fraction of the scene bounding box's surface area",
     IIR_PARAM_RESTART},
    {"hemicube_res", IIR_PARAM_INT, offsetof(rad_params, hemicube_res), 32, 4, 512, 0, NULL,
     "cells", "hemicube top face resolution (sides res x res/2; even)", IIR_PARAM_RESTART},
    {"solver", IIR_PARAM_ENUM, offsetof(rad_params, solver), RAD_GAUSS_SEIDEL, 0, 2, 0,
     SOLVER_CHOICES, "",
     "gauss (dense, at most 3000 patches), gauss_seidel or progressive (shooting, refines)",
     IIR_PARAM_LIVE},
    {"iterations", IIR_PARAM_INT, offsetof(rad_params, iterations), 100, 1, 100000, 0, NULL,
     "sweeps", "gauss_seidel: most sweeps per solve", IIR_PARAM_LIVE},
    {"tolerance", IIR_PARAM_FLOAT, offsetof(rad_params, tolerance), 1e-4, 1e-9, 1, 0, NULL, "",
     "gauss_seidel: stop when a sweep changes B by less than this times max B; progressive: "
     "converged when unshot power is below this times the emitted",
     IIR_PARAM_LIVE},
    {"shoot_batch", IIR_PARAM_INT, offsetof(rad_params, shoot_batch), 128, 1, 1000000, 0, NULL,
     "shots", "progressive: patches shot per frame and per refinement pass", IIR_PARAM_LIVE},
    {"light_samples", IIR_PARAM_INT, offsetof(rad_params, light_samples), 4, 1, 256, 0, NULL,
     "rays", "direct light shot onto each patch: points (shadow rays) per patch and light",
     IIR_PARAM_LIVE},
    {"direct", IIR_PARAM_ENUM, offsetof(rad_params, direct), RAD_DIRECT_PIXELS, 0, 1, 0,
     DIRECT_CHOICES, "",
     "direct light per pixel with shadow rays (pixels, crisp) or from the patches (patches)",
     IIR_PARAM_LIVE},
};

static iir_status check_opts(const void *opts, const iir_params *given, const iir_param **bad,
                             iir_error *err)
{
    (void)given;
    const rad_params *o = opts;
    if (o->hemicube_res % 2 == 0) return IIR_OK;
    if (bad) *bad = &ROWS[1];
    return iir_fail(err, IIR_ERR_INVALID, "hemicube_res must be even (got %d)", o->hemicube_res);
}

const iir_param_table rad_param_table = {"radiosity: patches, form factors, solver", ROWS,
                                         sizeof ROWS / sizeof ROWS[0], check_opts};

/* ---- state ---- */

typedef struct rad_state {
    rad_options o;
    rad_solution sol;
    iir_renderer *renderer;
    uint64_t passes;
    iir_vec3 *direct; /* the last frame's renderer output (direct light), for refinement */
    size_t direct_cap;
    bool have_frame;
} rad_state;

/* ---- display ---- */

/* Barycentrics (u, v) of x in scene triangle t (p = (1-u-v) p0 + u p1 + v p2). */
static void tri_barycentrics(const iir_scene *sc, uint32_t t, iir_vec3 x, float *u, float *v)
{
    iir_vec3 p0 = sc->positions[sc->indices[3 * t]];
    iir_vec3 e1 = iir_sub(sc->positions[sc->indices[3 * t + 1]], p0);
    iir_vec3 e2 = iir_sub(sc->positions[sc->indices[3 * t + 2]], p0), d = iir_sub(x, p0);
    float d00 = iir_dot(e1, e1), d01 = iir_dot(e1, e2), d11 = iir_dot(e2, e2);
    float d20 = iir_dot(d, e1), d21 = iir_dot(d, e2), den = d00 * d11 - d01 * d01;
    *u = den != 0.f ? (d11 * d20 - d01 * d21) / den : 0.f;
    *v = den != 0.f ? (d00 * d21 - d01 * d20) / den : 0.f;
}

/* out = base + rho_x H(x) / pi per pixel; base is the renderer's frame (pixels) or the G-buffer's
 * emission (patches). IIR_ERR_INTERRUPTED when the gather was stopped. */
static iir_status shade(rad_state *s, iir_image *out, iir_error *err)
{
    const iir_gbuffer *gb = iir_renderer_gbuffer(s->renderer);
    const bool pixels = s->o.r.direct == RAD_DIRECT_PIXELS;
    const int n = gb->width * gb->height;
    iir_status st = rad_solution_gather(&s->sol, !pixels, err);
    if (st != IIR_OK) return st;
#pragma omp parallel for schedule(dynamic, 256)
    for (int q = 0; q < n; q++) {
        iir_vec3 L = pixels ? s->direct[q] : gb->emission[q];
        if (isfinite(gb->depth[q]) && gb->prim[q] != IIR_NO_HIT) {
            float u, v;
            tri_barycentrics(s->sol.scene, gb->prim[q], gb->position[q], &u, &v);
            L = iir_madd(L, iir_mul(gb->albedo[q], rad_solution_H(&s->sol, gb->prim[q], u, v)),
                         IIR_INV_PI);
        }
        out->pixels[q] = L;
    }
    return IIR_OK;
}

/* ---- the frame ---- */

/* The renderer's direct light (no VPLs) into out, kept for refinement passes. */
static iir_status render_direct(rad_state *s, const iir_view *view, iir_image *out,
                                iir_frame_stats *stats, iir_error *err)
{
    iir_indirect_params ind = iir_indirect_params_default();
    ind.visibility = IIR_VIS_RAYS, ind.interleave = 1; /* no VPLs: direct light only */
    iir_render_timing rt;
    iir_render_input in = {.camera = &view->camera,
                           .lights = view->lights,
                           .num_lights = view->num_lights,
                           .seed = iir_frame_direct_seed(s->o.common.seed)};
    iir_raystats rays = stats->rays;
    iir_status st = iir_renderer_frame(s->renderer, &in, &ind, out, &rt, &rays, err);
    if (st != IIR_OK) return st;
    iir_render_timing_to_stats(&rt, stats);
    stats->rays = rays;
    size_t n = (size_t)out->width * (size_t)out->height;
    if (n > s->direct_cap) {
        iir_vec3 *d = realloc(s->direct, n * sizeof *d);
        if (!d) return iir_fail(err, IIR_ERR_NOMEM, "radiosity: out of memory for the frame");
        s->direct = d, s->direct_cap = n;
    }
    memcpy(s->direct, out->pixels, n * sizeof *s->direct);
    return IIR_OK;
}

static iir_status rad_render(void *state, const iir_view *view, iir_image *out,
                             iir_frame_stats *stats, iir_error *err)
{
    rad_state *s = state;
    s->have_frame = false;
    s->passes = 0;
    iir_status st = iir_view_validate(view, err);
    if (st != IIR_OK) return st;
    double t0 = iir_now_ms(), solve_ms;
    st = rad_solution_update(&s->sol, view->lights, view->num_lights, &stats->rays, &solve_ms, err);
    if (st == IIR_OK) st = render_direct(s, view, out, stats, err);
    if (st != IIR_OK) return st;
    double t1 = iir_now_ms();
    st = shade(s, out, err);
    if (st != IIR_OK) return st;
    stats->phase_ms[IIR_PHASE_SOLVE] = solve_ms;
    stats->phase_ms[IIR_PHASE_DISPLAY] = iir_now_ms() - t1;
    stats->total_ms = iir_now_ms() - t0;
    stats->converged = s->sol.converged;
    stats->whole_sweeps = true;
    s->have_frame = true;
    return IIR_OK;
}

/* Progressive: shoots another batch and redisplays; other solvers are converged at once. */
static iir_status rad_refine(void *state, iir_image *out, iir_frame_stats *stats, iir_error *err)
{
    rad_state *s = state;
    if (!s->have_frame) return iir_fail(err, IIR_ERR_INVALID, "radiosity: no frame to refine");
    memset(stats, 0, sizeof *stats);
    double t0 = iir_now_ms();
    bool shot;
    iir_status st = rad_solution_refine(&s->sol, &shot, err);
    if (st != IIR_OK) return st; /* its whole shots stand, uncounted: the next pass shows them */
    s->passes += shot;
    /* converged: counts as the still's refine_passes, so iird render stops here */
    if (s->sol.converged && s->passes < (uint64_t)s->o.common.refine_passes)
        s->passes = (uint64_t)s->o.common.refine_passes;
    double t1 = iir_now_ms();
    st = shade(s, out, err);
    if (st != IIR_OK) return st;
    stats->phase_ms[IIR_PHASE_SOLVE] = t1 - t0;
    stats->phase_ms[IIR_PHASE_DISPLAY] = iir_now_ms() - t1;
    stats->total_ms = iir_now_ms() - t0;
    stats->samples_per_pixel = s->passes;
    stats->converged = s->sol.converged;
    stats->whole_sweeps = true;
    return IIR_OK;
}

/* ---- the method interface ---- */

static void rad_destroy(void *state)
{
    rad_state *s = state;
    if (!s) return;
    iir_renderer_destroy(s->renderer);
    rad_solution_free(&s->sol);
    free(s->direct);
    free(s);
}

static iir_status rad_create(const iir_scene *scene, const iir_rt *rt, const void *opts,
                             const iir_stop *stop, void **state, iir_error *err)
{
    rad_state *s = calloc(1, sizeof *s);
    if (!s) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating radiosity");
    s->o = *(const rad_options *)opts;
    s->renderer = iir_renderer_create(scene, rt);
    if (!s->renderer) {
        free(s);
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating radiosity");
    }
    iir_status st = rad_solution_init(&s->sol, scene, rt, &s->o.r, s->o.common.seed, stop, err);
    if (st != IIR_OK) {
        iir_renderer_destroy(s->renderer);
        free(s);
        return st;
    }
    *state = s;
    return IIR_OK;
}

/* Live parameters: a new solver, tolerance or light sampling re-solves at the next frame. */
static void rad_update(void *state, const void *opts)
{
    rad_state *s = state;
    const rad_options *o = opts;
    if (rad_solution_set_params(&s->sol, &o->r, o->common.seed)) s->o = *o; /* else the old */
}

static void rad_set_stop(void *state, iir_stop_fn fn, void *ctx)
{
    rad_state *s = state;
    iir_renderer_set_stop(s->renderer, fn, ctx);
    rad_solution_set_stop(&s->sol, fn, ctx);
}

/* The frame's part of rad_memory: G-buffer and scratch as the VPL renderer's, the direct copy. */
static uint64_t frame_bytes(int width, int height)
{
    return iir_renderer_memory(width, height) + (uint64_t)width * (uint64_t)height * 12;
}

/* The solution, and the frame: G-buffer and scratch as the VPL renderer's, plus the direct-light
 * copy. */
static uint64_t rad_memory(const void *opts, int width, int height)
{
    const rad_options *o = opts;
    return rad_solution_memory(&o->r) + frame_bytes(width, height);
}

static uint64_t rad_memory_on(const void *opts, const iir_scene *scene, const iir_rt *rt, int width,
                              int height)
{
    const rad_options *o = opts;
    return rad_solution_estimate(&o->r, scene, rt, omp_get_max_threads()) +
           frame_bytes(width, height);
}

static uint64_t rad_held(const void *state, int width, int height)
{
    const rad_state *s = state;
    return rad_solution_bytes(&s->sol, omp_get_max_threads()) + frame_bytes(width, height);
}

/* Radiosity renders every light and the emitters' light; mirrors and glass have no diffuse part,
 * so their patches are black. */
static uint32_t rad_dropped(const iir_scene *scene, const iir_light *lights, uint32_t num_lights,
                            iir_dropped *out, uint32_t max)
{
    (void)lights, (void)num_lights;
    uint32_t n = 0;
    for (uint32_t i = 0; i < scene->num_materials; i++) {
        const iir_material *m = &scene->material_list[i];
        if (iir_material_is_glossy(m))
            iir_dropped_add(out, max, &n, "radiosity", "material", m->name,
                            "is glossy (a metal, or roughness below 0.6): radiosity's patches are "
                            "diffuse only, its highlights left out; hybrid, pt and whitted render "
                            "them");
        else if (m->kind == IIR_MATERIAL_MIRROR || m->kind == IIR_MATERIAL_GLASS)
            iir_dropped_add(out, max, &n, "radiosity", "material", m->name,
                            "is a %s: radiosity's patches are diffuse only, so it is black; use "
                            "hybrid, pt or whitted",
                            m->kind == IIR_MATERIAL_GLASS ? "dielectric (glass)" : "mirror");
    }
    return n;
}

/* Progressive: refine_passes batches; the other solvers' first frame is converged (0). */
static uint64_t rad_converged_at(const void *opts)
{
    const rad_options *o = opts;
    return o->r.solver == RAD_PROGRESSIVE ? (uint64_t)o->common.refine_passes : 0;
}

const iir_method_ops iir_method_radiosity = {
    .name = "radiosity",
    .summary = "patch radiosity: hemicube form factors (cached on disk), Gauss-Seidel or "
               "progressive solve, Gouraud display",
    .tables = {{&rad_param_table, offsetof(rad_options, r)},
               {&iir_common_table, offsetof(rad_options, common)}},
    .opts_size = sizeof(rad_options),
    .create = rad_create,
    .destroy = rad_destroy,
    .render = rad_render,
    .refine = rad_refine,
    .set_stop = rad_set_stop,
    .update = rad_update,
    .memory = rad_memory,
    .memory_on = rad_memory_on,
    .held = rad_held,
    .converged_at = rad_converged_at,
    .dropped = rad_dropped,
    /* measured against a multi-bounce pt: 8 bounces (the Cornell box's walls keep ~5% past) */
    .reference_bounces = 8,
    .phases = {IIR_PHASE_SOLVE, IIR_PHASE_GBUFFER, IIR_PHASE_DIRECT, IIR_PHASE_DISPLAY,
               IIR_PHASE_COUNT},
};

/* hybrid.c -- the two-pass method "hybrid" (Wallace, Cohen & Greenberg 1987; Sillion & Puech
 * 1989): radiosity for the diffuse part, Whitted ray tracing for the specular part. Pass one is
 * radiosity's view-independent solution (radiosity/solution.c, with the radiosity method's
 * parameters); pass two is the Whitted tree (whitted_tree.c, with whitted's parameters) from
 * every pixel, whose eye rays and mirror and glass branches that land on a diffuse surface x add
 * the solution's light there, rho_x H(x) / pi, Gouraud-interpolated over x's patch. So mirrors
 * show the radiosity-lit room. Not the solution or the tree.
 *
 * direct = pixels (default): x's direct light is the tree's local shading (shadow rays, crisp
 * shadows) and H the light of one bounce or more; direct = patches: no shadow rays, H holds all of
 * x's light at patch resolution. Progressive refinement shoots another batch per refine call and
 * traces the frame again. */
#include <omp.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "../radiosity/radiosity.h"
#include "iir/method.h"
#include "iir/timer.h"
#include "method_internal.h"
#include "whitted_tree.h"

typedef struct hybrid_options {
    iir_method_common common;
    whitted_params w;
    rad_params r;
} hybrid_options;

typedef struct hybrid_state {
    hybrid_options o;
    rad_solution sol;
    whitted_tree *tree;
    iir_camera camera; /* the last frame's, for refinement (its lights are the solution's) */
    bool have_frame;
    uint64_t passes;
    iir_stop_fn stop;
    void *stop_ctx;
} hybrid_state;

/* The diffuse hook: rho_x H(x) / pi from the radiosity solution. */
static iir_vec3 radiosity_at(const void *ctx, const iir_hit *hit, iir_vec3 albedo)
{
    const rad_solution *sol = ctx;
    iir_vec3 H = rad_solution_H(sol, hit->prim, hit->u, hit->v);
    return iir_scale(iir_mul(albedo, H), IIR_INV_PI);
}

/* Gathers the solution for display and traces the frame's trees. */
static iir_status trace(hybrid_state *s, const iir_view *view, iir_image *out,
                        iir_frame_stats *stats, iir_error *err)
{
    const bool pixels = s->o.r.direct == RAD_DIRECT_PIXELS;
    double t0 = iir_now_ms();
    iir_status st = rad_solution_gather(&s->sol, !pixels, err);
    if (st != IIR_OK) return st;
    double t1 = iir_now_ms();
    whitted_frame f = {.p = &s->o.w,
                       .seed = s->o.common.seed,
                       .local_direct = pixels,
                       .extra = radiosity_at,
                       .extra_ctx = &s->sol,
                       .stop = s->stop,
                       .stop_ctx = s->stop_ctx};
    st = whitted_tree_render(s->tree, &f, view, out, stats, err);
    stats->phase_ms[IIR_PHASE_GATHER] = t1 - t0;
    stats->phase_ms[IIR_PHASE_TRACE] = iir_now_ms() - t1;
    return st;
}

static iir_status hybrid_render(void *state, const iir_view *view, iir_image *out,
                                iir_frame_stats *stats, iir_error *err)
{
    hybrid_state *s = state;
    s->have_frame = false;
    s->passes = 0;
    iir_status st = iir_view_validate(view, err);
    if (st != IIR_OK) return st;
    double t0 = iir_now_ms(), solve_ms;
    iir_raystats shoot = {0};
    st = rad_solution_update(&s->sol, view->lights, view->num_lights, &shoot, &solve_ms, err);
    if (st == IIR_OK) st = trace(s, view, out, stats, err);
    if (st != IIR_OK) return st;
    iir_raystats_add(&stats->rays, &shoot);
    stats->phase_ms[IIR_PHASE_SOLVE] = solve_ms;
    stats->total_ms = iir_now_ms() - t0;
    stats->samples_per_pixel = 1;
    stats->converged = s->sol.converged;
    stats->whole_sweeps = true;
    s->camera = view->camera;
    s->have_frame = true;
    return IIR_OK;
}

/* Progressive: shoots another batch and traces again; other solvers are converged at once. */
static iir_status hybrid_refine(void *state, iir_image *out, iir_frame_stats *stats, iir_error *err)
{
    hybrid_state *s = state;
    if (!s->have_frame) return iir_fail(err, IIR_ERR_INVALID, "hybrid: no frame to refine");
    memset(stats, 0, sizeof *stats);
    double t0 = iir_now_ms();
    bool shot;
    iir_status rs = rad_solution_refine(&s->sol, &shot, err);
    if (rs != IIR_OK) return rs; /* its whole shots stand, uncounted: the next pass shows them */
    stats->phase_ms[IIR_PHASE_SOLVE] = iir_now_ms() - t0;
    if (shot) {
        s->passes++;
        iir_view view = {s->sol.lights, s->sol.num_lights, s->camera};
        iir_status st = trace(s, &view, out, stats, err);
        if (st != IIR_OK) return st;
    }
    /* converged: counts as the still's refine_passes, so iird render stops here */
    if (s->sol.converged && s->passes < (uint64_t)s->o.common.refine_passes)
        s->passes = (uint64_t)s->o.common.refine_passes;
    stats->total_ms = iir_now_ms() - t0;
    stats->samples_per_pixel = s->passes;
    stats->converged = s->sol.converged;
    stats->whole_sweeps = true; /* every pass is a whole image: the browser shows each */
    return IIR_OK;
}

static void hybrid_destroy(void *state)
{
    hybrid_state *s = state;
    if (!s) return;
    whitted_tree_destroy(s->tree);
    rad_solution_free(&s->sol);
    free(s);
}

static iir_status hybrid_create(const iir_scene *scene, const iir_rt *rt, const void *opts,
                                const iir_stop *stop, void **state, iir_error *err)
{
    hybrid_state *s = calloc(1, sizeof *s);
    if (s) s->tree = whitted_tree_create(scene, rt);
    if (!s || !s->tree) {
        free(s);
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating the hybrid method");
    }
    s->o = *(const hybrid_options *)opts;
    iir_status st = rad_solution_init(&s->sol, scene, rt, &s->o.r, s->o.common.seed, stop, err);
    if (st != IIR_OK) {
        whitted_tree_destroy(s->tree);
        free(s);
        return st;
    }
    *state = s;
    return IIR_OK;
}

/* Live parameters: the tree's at the next frame; a new solver or light sampling re-solves. */
static void hybrid_update(void *state, const void *opts)
{
    hybrid_state *s = state;
    const hybrid_options *o = opts;
    if (rad_solution_set_params(&s->sol, &o->r, o->common.seed)) s->o = *o; /* else the old */
}

static void hybrid_set_stop(void *state, iir_stop_fn fn, void *ctx)
{
    hybrid_state *s = state;
    s->stop = fn, s->stop_ctx = ctx;
    rad_solution_set_stop(&s->sol, fn, ctx);
}

static uint64_t hybrid_memory(const void *opts, int width, int height)
{
    (void)width, (void)height; /* the trees live on the stack; the frame is the caller's */
    return rad_solution_memory(&((const hybrid_options *)opts)->r) + sizeof(hybrid_state);
}

static uint64_t hybrid_memory_on(const void *opts, const iir_scene *scene, const iir_rt *rt,
                                 int width, int height)
{
    (void)width, (void)height;
    const hybrid_options *o = opts;
    return rad_solution_estimate(&o->r, scene, rt, omp_get_max_threads()) + sizeof(hybrid_state);
}

static uint64_t hybrid_held(const void *state, int width, int height)
{
    (void)width, (void)height;
    const hybrid_state *s = state;
    return rad_solution_bytes(&s->sol, omp_get_max_threads()) + sizeof(hybrid_state);
}

static uint64_t hybrid_converged_at(const void *opts)
{
    const hybrid_options *o = opts;
    return o->r.solver == RAD_PROGRESSIVE ? (uint64_t)o->common.refine_passes : 0;
}

const iir_method_ops iir_method_hybrid = {
    .name = "hybrid",
    .summary = "two-pass: radiosity for the diffuse part, Whitted ray trees for mirrors and glass",
    .tables = {{&whitted_param_table, offsetof(hybrid_options, w)},
               {&rad_param_table, offsetof(hybrid_options, r)},
               {&iir_common_table, offsetof(hybrid_options, common)}},
    .opts_size = sizeof(hybrid_options),
    .create = hybrid_create,
    .destroy = hybrid_destroy,
    .render = hybrid_render,
    .refine = hybrid_refine,
    .set_stop = hybrid_set_stop,
    .update = hybrid_update,
    .memory = hybrid_memory,
    .memory_on = hybrid_memory_on,
    .held = hybrid_held,
    .converged_at = hybrid_converged_at,
    /* measured against a multi-bounce pt: 8 bounces (the Cornell box's walls keep ~5% past) */
    .reference_bounces = 8,
    .phases = {IIR_PHASE_SOLVE, IIR_PHASE_GATHER, IIR_PHASE_TRACE, IIR_PHASE_COUNT},
    .counters = WHITTED_COUNTERS,
};

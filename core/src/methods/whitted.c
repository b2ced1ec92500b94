/* whitted.c -- Whitted ray tracing (method "whitted"; Whitted 1980): the ray tree of
 * whitted_tree.c from each pixel centre, with local shading at diffuse surfaces and nothing for
 * indirect diffuse light but the ambient term. Not the tree itself. */
#include <stddef.h>
#include <stdlib.h>

#include "iir/method.h"
#include "iir/timer.h"
#include "method_internal.h"
#include "whitted_tree.h"

typedef struct whitted_options {
    iir_method_common common;
    whitted_params w;
} whitted_options;

typedef struct whitted_state {
    whitted_tree *tree;
    whitted_options o;
    iir_stop_fn stop;
    void *stop_ctx;
} whitted_state;

static iir_status whitted_create(const iir_scene *scene, const iir_rt *rt, const void *opts,
                                 const iir_stop *stop, void **state, iir_error *err)
{
    (void)stop; /* allocations only: nothing here takes long enough to poll */
    whitted_state *s = calloc(1, sizeof *s);
    if (s) s->tree = whitted_tree_create(scene, rt);
    if (!s || !s->tree) {
        free(s);
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating the Whitted ray tracer");
    }
    s->o = *(const whitted_options *)opts;
    *state = s;
    return IIR_OK;
}

static void whitted_destroy(void *state)
{
    whitted_state *s = state;
    if (!s) return;
    whitted_tree_destroy(s->tree);
    free(s);
}

static iir_status whitted_render(void *state, const iir_view *view, iir_image *out,
                                 iir_frame_stats *stats, iir_error *err)
{
    whitted_state *s = state;
    iir_status st = iir_view_validate(view, err);
    if (st != IIR_OK) return st;
    double t0 = iir_now_ms();
    whitted_frame f = {.p = &s->o.w,
                       .seed = s->o.common.seed,
                       .local_direct = true,
                       .stop = s->stop,
                       .stop_ctx = s->stop_ctx};
    st = whitted_tree_render(s->tree, &f, view, out, stats, err);
    stats->phase_ms[IIR_PHASE_TRACE] = iir_now_ms() - t0;
    stats->total_ms = stats->phase_ms[IIR_PHASE_TRACE];
    stats->samples_per_pixel = 1;
    stats->converged = true;
    return st;
}

static void whitted_set_stop(void *state, iir_stop_fn fn, void *ctx)
{
    whitted_state *s = state;
    s->stop = fn;
    s->stop_ctx = ctx;
}

static void whitted_update(void *state, const void *opts)
{
    ((whitted_state *)state)->o = *(const whitted_options *)opts;
}

static uint64_t whitted_memory(const void *opts, int width, int height)
{
    (void)opts, (void)width, (void)height;
    return sizeof(whitted_state) +
           64 * 256; /* the tree: 64 lights prepared; it lives on the stack */
}

const iir_method_ops iir_method_whitted = {
    .name = "whitted",
    .summary = "Whitted ray tracing: mirror and glass ray trees with adaptive depth, direct light",
    .tables = {{&whitted_param_table, offsetof(whitted_options, w)},
               {&iir_common_table, offsetof(whitted_options, common)}},
    .opts_size = sizeof(whitted_options),
    .create = whitted_create,
    .destroy = whitted_destroy,
    .render = whitted_render,
    .set_stop = whitted_set_stop,
    .update = whitted_update,
    .memory = whitted_memory,
    /* measured against a multi-bounce pt: 8 bounces (the Cornell box's walls keep ~5% past) */
    .reference_bounces = 8,
    .phases = {IIR_PHASE_TRACE, IIR_PHASE_COUNT},
    .counters = WHITTED_COUNTERS,
};

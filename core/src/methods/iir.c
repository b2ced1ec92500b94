/* iir.c -- incremental instant radiosity, method "iir" (Laine et al. 2007): the VPL set lives
 * across frames. Each frame runs the incremental step (core/src/incremental.c) for the first spot
 * light of the view, renders shadow maps only for the VPLs born this frame (a map lives as long as
 * its VPL: the scene is static), and shades with the shared VPL renderer. One bounce by
 * construction. Uses params vpls, kmin, kmax, weights, regen_threshold, seed, visibility, sm_res,
 * sm_bias, interleave, clamp. Direct light comes from every light of the view. */
#include <stdlib.h>

#include "iir/method.h"
#include "iir/rng.h"
#include "iir/scene.h"
#include "iir/shadowmap.h"
#include "method_internal.h"
#include "timer.h"

typedef struct iir_state {
    const iir_scene *scene;
    const iir_rt *rt;
    iir_params params;
    iir_renderer *renderer;
    iir_incr *incr;
    uint32_t frame;
} iir_state;

static iir_incr_params incr_params(const iir_params *p)
{
    iir_incr_params ip = iir_incr_params_default();
    ip.target = (uint32_t)p->vpls;
    ip.k_min = (uint32_t)p->kmin;
    ip.k_max = (uint32_t)p->kmax;
    ip.weights = p->weights;
    ip.regen_threshold = p->regen_threshold;
    ip.seed = p->seed;
    return ip;
}

static iir_status iir_m_create(const iir_scene *scene, const iir_rt *rt, const iir_params *params,
                               void **state, iir_error *err)
{
    iir_state *s = calloc(1, sizeof *s);
    if (!s) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating iir");
    s->scene = scene;
    s->rt = rt;
    s->params = *params;
    iir_incr_params ip = incr_params(params);
    iir_status st = iir_incr_create(scene, rt, &ip, &s->incr, err);
    s->renderer = st == IIR_OK ? iir_renderer_create(scene, rt) : NULL;
    if (st == IIR_OK && !s->renderer)
        st = iir_fail(err, IIR_ERR_NOMEM, "out of memory creating iir's renderer");
    if (st != IIR_OK) {
        iir_incr_destroy(s->incr);
        free(s);
        return st;
    }
    *state = s;
    return IIR_OK;
}

static void iir_m_destroy(void *state)
{
    iir_state *s = state;
    if (!s) return;
    iir_renderer_destroy(s->renderer);
    iir_incr_destroy(s->incr);
    free(s);
}

static const iir_light *first_spot(const iir_view *view)
{
    for (uint32_t i = 0; i < view->num_lights; i++)
        if (view->lights[i].type == IIR_LIGHT_SPOT) return &view->lights[i];
    return NULL;
}

static void fill_counts(const iir_incr_stats *is, uint32_t maps, iir_vpl_counts *c)
{
    c->count = is->count;
    c->valid = is->valid;
    c->invalidated = is->invalidated;
    c->deleted = is->deleted;
    c->inserted = is->inserted;
    c->null_samples = is->null_samples;
    c->regenerated = is->regenerated;
    c->shadowmaps = maps;
}

static iir_status iir_m_render(void *state, const iir_view *view, iir_image *out,
                               iir_frame_stats *stats, iir_error *err)
{
    iir_state *s = state;
    iir_status st = iir_view_validate(view, err);
    if (st != IIR_OK) return st;
    const iir_light *spot = first_spot(view);
    if (!spot)
        return iir_fail(err, IIR_ERR_UNSUPPORTED,
                        "iir needs a spot light (its VPL domain is the spot's disk); this view has "
                        "%u light(s) and no spot",
                        view->num_lights);
    double t0 = iir_now_ms();
    iir_incr_stats is;
    st = iir_incr_update(s->incr, spot, &is, err);
    if (st != IIR_OK) return st;
    iir_raystats_add(&stats->rays, &is.rays);
    double t1 = iir_now_ms();
    uint32_t n = 0, maps = 0;
    iir_vpl *vpls = iir_incr_vpls(s->incr, &n);
    if (s->params.visibility == IIR_VIS_SHADOWMAP)
        maps = iir_smaps_build(vpls, n, s->rt, s->params.sm_res, &stats->rays);
    double t2 = iir_now_ms();
    iir_indirect_params ind = iir_params_indirect(&s->params);
    iir_render_timing rt;
    st = iir_renderer_frame(s->renderer, &view->camera, view->lights, view->num_lights, vpls, n,
                            &ind, iir_hash3(s->params.seed, s->frame, 2), out, &rt, &stats->rays,
                            err);
    stats->phase_ms[IIR_PHASE_VPLS] = t1 - t0;
    stats->phase_ms[IIR_PHASE_SHADOWMAPS] = t2 - t1;
    iir_render_timing_to_stats(&rt, stats);
    stats->total_ms = iir_now_ms() - t0;
    fill_counts(&is, maps, &stats->vpl);
    s->frame++;
    return st;
}

static const iir_vpl *iir_m_vpls(const void *state, uint32_t *n)
{
    const iir_state *s = state;
    return iir_incr_vpls(s->incr, n);
}

const iir_method_ops iir_method_iir = {
    .name = "iir",
    .summary = "incremental instant radiosity: VPLs kept across frames, few replaced per frame",
    .create = iir_m_create,
    .destroy = iir_m_destroy,
    .render = iir_m_render,
    .refine = NULL,
    .vpls = iir_m_vpls,
};

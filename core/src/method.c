/* method.c -- the registry of methods and the dispatch of the method interface; parameters and
 * their ranges. Not any method's algorithm. */
#include <stdlib.h>
#include <string.h>

#include "iir/rng.h"
#include "iir/scene.h"
#include "method_internal.h"

static const iir_method_ops *const registry[] = {&iir_method_pt, &iir_method_ir, &iir_method_iir};
enum { NUM_METHODS = sizeof registry / sizeof registry[0] };

struct iir_method {
    const iir_method_ops *ops;
    void *state;
};

iir_params iir_params_default(void)
{
    iir_indirect_params ind = iir_indirect_params_default();
    iir_incr_params inc = iir_incr_params_default();
    iir_params p = {
        .spp = 16,
        .bounces = 2,
        .seed = 1,
        .jitter = true,
        /* 4 sweeps of the default 4x4 interleave: every pixel sees 4 independent VPL sets (the
           VPL noise halves against one set) through 64 jittered points (edges within ~1/64 of
           their contrast); ~5 s at 512x384 on two cores, after which more passes barely show */
        .refine_passes = 64,
        .vpls = (int)inc.target,
        .kmin = (int)inc.k_min,
        .kmax = (int)inc.k_max,
        .weights = inc.weights,
        .regen_threshold = inc.regen_threshold,
        .visibility = ind.visibility,
        .sm_res = 128,
        .sm_bias = ind.sm_bias,
        .interleave = ind.interleave,
        .clamp = ind.clamp,
        .ir_fresh = true,
    };
    return p;
}

static iir_status check_int(int v, int lo, int hi, const char *name, iir_error *err)
{
    if (v < lo || v > hi)
        return iir_fail(err, IIR_ERR_INVALID, "%s %d is outside [%d, %d]", name, v, lo, hi);
    return IIR_OK;
}

static iir_status check_float(float v, float lo, float hi, const char *name, iir_error *err)
{
    if (!(v >= lo && v <= hi))
        return iir_fail(err, IIR_ERR_INVALID, "%s %g is outside [%g, %g]", name, (double)v,
                        (double)lo, (double)hi);
    return IIR_OK;
}

iir_status iir_params_validate(const iir_params *p, iir_error *err)
{
    iir_status st = check_int(p->spp, 1, 1 << 20, "spp", err);
    if (st == IIR_OK) st = check_int(p->bounces, 1, 1000, "bounces", err);
    if (st == IIR_OK)
        st = check_int(p->refine_passes, 1, IIR_REFINE_MAX_PASSES, "refine_passes", err);
    if (st == IIR_OK) st = check_int(p->vpls, 1, 16384, "vpls", err);
    if (st == IIR_OK) st = check_int(p->kmax, 0, p->vpls, "kmax", err);
    if (st == IIR_OK) st = check_int(p->kmin, 0, p->kmax, "kmin", err);
    if (st == IIR_OK) st = check_int(p->sm_res, 8, 2048, "sm_res", err);
    if (st == IIR_OK) st = check_int(p->interleave, 1, 8, "interleave", err);
    if (st == IIR_OK) st = check_float(p->regen_threshold, 1e-6f, 1.f, "regen_threshold", err);
    if (st == IIR_OK) st = check_float(p->clamp, 0.f, 1e12f, "clamp", err);
    if (st == IIR_OK) st = check_float(p->sm_bias, 0.f, 1.f, "sm_bias", err);
    if (st == IIR_OK && p->weights != IIR_WEIGHTS_UNIFORM && p->weights != IIR_WEIGHTS_VORONOI)
        st = iir_fail(err, IIR_ERR_INVALID, "weights must be uniform or voronoi");
    if (st == IIR_OK && p->visibility != IIR_VIS_SHADOWMAP && p->visibility != IIR_VIS_RAYS)
        st = iir_fail(err, IIR_ERR_INVALID, "visibility must be shadowmap or rays");
    return st;
}

iir_indirect_params iir_params_indirect(const iir_params *p)
{
    iir_indirect_params ind = iir_indirect_params_default();
    ind.visibility = p->visibility;
    ind.interleave = p->interleave;
    ind.clamp = p->clamp;
    ind.sm_bias = p->sm_bias;
    return ind;
}

void iir_render_timing_to_stats(const iir_render_timing *t, iir_frame_stats *stats)
{
    stats->phase_ms[IIR_PHASE_GBUFFER] = t->gbuffer_ms;
    stats->phase_ms[IIR_PHASE_DIRECT] = t->direct_ms;
    stats->phase_ms[IIR_PHASE_INDIRECT] = t->indirect_ms;
    stats->phase_ms[IIR_PHASE_FILTER] = t->filter_ms;
}

iir_refine_params iir_params_refine(const iir_params *p)
{
    iir_refine_params r = {
        .interleave = p->interleave,
        .max_passes = p->refine_passes,
        .jitter = p->jitter,
        .clamp = p->clamp,
        .seed = iir_hash3(p->seed, 0x4ef1, 0),
    };
    return r;
}

void iir_refine_to_stats(const iir_refine_stats *rs, iir_frame_stats *stats)
{
    iir_render_timing_to_stats(&rs->timing, stats);
    stats->phase_ms[IIR_PHASE_VPLS] = rs->vpls_ms;
    stats->total_ms = rs->total_ms;
    stats->rays = rs->rays;
    stats->samples_per_pixel = rs->passes;
    stats->converged = rs->converged;
    stats->vpl.count = rs->num_vpls;
}

iir_status iir_view_validate(const iir_view *view, iir_error *err)
{
    iir_status st = iir_camera_validate(&view->camera, err);
    for (uint32_t i = 0; st == IIR_OK && i < view->num_lights; i++)
        st = iir_light_validate(&view->lights[i], err);
    return st;
}

const char *iir_phase_name(iir_phase phase)
{
    static const char *names[IIR_PHASE_COUNT] = {"trace",  "vpls",     "shadowmaps", "gbuffer",
                                                 "direct", "indirect", "filter"};
    return phase < IIR_PHASE_COUNT ? names[phase] : "unknown";
}

const char *const *iir_method_names(void)
{
    static const char *names[NUM_METHODS + 1];
    for (int i = 0; i < NUM_METHODS; i++) names[i] = registry[i]->name;
    names[NUM_METHODS] = NULL;
    return names;
}

static const iir_method_ops *find_ops(const char *name)
{
    for (int i = 0; i < NUM_METHODS; i++)
        if (strcmp(registry[i]->name, name) == 0) return registry[i];
    return NULL;
}

static iir_status unknown_method(const char *name, iir_error *err)
{
    char list[256] = "";
    for (int i = 0; i < NUM_METHODS; i++) {
        if (i) strncat(list, ", ", sizeof list - strlen(list) - 1);
        strncat(list, registry[i]->name, sizeof list - strlen(list) - 1);
    }
    return iir_fail(err, IIR_ERR_INVALID, "unknown method '%s' (known: %s)", name, list);
}

iir_status iir_method_create(const char *name, const iir_scene *scene, const iir_rt *rt,
                             const iir_params *params, iir_method **out, iir_error *err)
{
    *out = NULL;
    const iir_method_ops *ops = find_ops(name);
    if (!ops) return unknown_method(name, err);
    iir_status st = iir_params_validate(params, err);
    if (st != IIR_OK) return st;
    iir_method *m = calloc(1, sizeof *m);
    if (!m) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating method '%s'", name);
    m->ops = ops;
    st = ops->create(scene, rt, params, &m->state, err);
    if (st != IIR_OK) {
        free(m);
        return st;
    }
    *out = m;
    return IIR_OK;
}

void iir_method_destroy(iir_method *m)
{
    if (!m) return;
    m->ops->destroy(m->state);
    free(m);
}

const char *iir_method_name(const iir_method *m)
{
    return m->ops->name;
}

iir_status iir_method_render(iir_method *m, const iir_view *view, iir_image *out,
                             iir_frame_stats *stats, iir_error *err)
{
    memset(stats, 0, sizeof *stats);
    return m->ops->render(m->state, view, out, stats, err);
}

const iir_vpl *iir_method_vpls(const iir_method *m, uint32_t *n)
{
    *n = 0;
    return m->ops->vpls ? m->ops->vpls(m->state, n) : NULL;
}

void iir_method_set_stop(iir_method *m, iir_stop_fn fn, void *ctx)
{
    if (m && m->ops->set_stop) m->ops->set_stop(m->state, fn, ctx);
}

bool iir_method_can_refine(const iir_method *m)
{
    return m->ops->refine != NULL;
}

iir_status iir_method_refine(iir_method *m, iir_image *out, iir_frame_stats *stats, iir_error *err)
{
    if (!m->ops->refine)
        return iir_fail(err, IIR_ERR_UNSUPPORTED, "method '%s' cannot refine a frame",
                        m->ops->name);
    memset(stats, 0, sizeof *stats);
    return m->ops->refine(m->state, out, stats, err);
}

bool iir_method_domain(iir_method *m, iir_domain *out)
{
    memset(out, 0, sizeof *out);
    return m->ops->domain ? m->ops->domain(m->state, out) : false;
}

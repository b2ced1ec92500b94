/* method.c -- the registry of methods and the dispatch of the method interface; the options every
 * method has; finding, checking and binding the methods' parameters (params.h); giving a live
 * method new parameters. Not any method's algorithm or parameters. */
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "iir/rng.h"
#include "iir/scene.h"
#include "method_internal.h"

static const iir_method_ops *const registry[] = {
    &iir_method_pt,        &iir_method_ir,      &iir_method_iir,
    &iir_method_rsm,       &iir_method_ism,     &iir_method_hier,
    &iir_method_radiosity, &iir_method_whitted, &iir_method_hybrid};
enum { NUM_METHODS = sizeof registry / sizeof registry[0] };

struct iir_method {
    const iir_method_ops *ops;
    void *state;
    void *opts; /* the method's options struct, bound from params */
    iir_params params;
    const iir_scene *scene;
    const iir_rt *rt;
    iir_stop_fn stop_fn; /* kept for a state created anew by iir_method_set_params */
    void *stop_ctx;
};

/* ======================== the options every method has ======================== */

static const iir_param COMMON_ROWS[] = {
    /* at most 2^53 - 1: every integer up to it is exact in a double (and in JSON readers) */
    {"seed", IIR_PARAM_U64, offsetof(iir_method_common, seed), 1, 0, 9007199254740991.0, 0, NULL,
     "", "random seed: the same seed gives the same images", IIR_PARAM_RESTART},
    /* 4 sweeps of the default 4x4 interleave: every pixel sees 4 independent VPL sets (the VPL
       noise halves against one set) through 64 jittered points (edges within ~1/64 of their
       contrast); ~5 s at 512x384 on two cores, after which more passes barely show */
    {"refine_passes", IIR_PARAM_INT, offsetof(iir_method_common, refine_passes), 64, 1,
     IIR_REFINE_MAX_PASSES, 0, NULL, "passes",
     "a converged frame (a still) has this many refinement passes (pt: samples per pixel, "
     "rounded up to whole frames of spp)",
     IIR_PARAM_LIVE},
    {"jitter", IIR_PARAM_BOOL, offsetof(iir_method_common, jitter), 1, 0, 1, 0, NULL, "",
     "pt and refinement: box-filter each pixel (true) or trace its centre (false)", IIR_PARAM_LIVE},
};
const iir_param_table iir_common_table = {"every method", COMMON_ROWS,
                                          sizeof COMMON_ROWS / sizeof COMMON_ROWS[0], NULL};

/* Light bounces, one int wherever a method keeps it (pt, ir, iir). */
static const iir_param BOUNCES_ROWS[] = {
    {"bounces", IIR_PARAM_INT, 0, 2, 1, 1000, 8, NULL, "",
     "light bounces: 1 = direct only, 2 = one diffuse bounce", IIR_PARAM_LIVE},
};
const iir_param_table iir_bounces_table = {"light bounces (pt, ir, iir)", BOUNCES_ROWS, 1, NULL};

void iir_render_timing_to_stats(const iir_render_timing *t, iir_frame_stats *stats)
{
    stats->phase_ms[IIR_PHASE_GBUFFER] = t->gbuffer_ms;
    stats->phase_ms[IIR_PHASE_DIRECT] = t->direct_ms;
    stats->phase_ms[IIR_PHASE_INDIRECT] = t->indirect_ms;
    stats->phase_ms[IIR_PHASE_FILTER] = t->filter_ms;
    stats->vpl_evals = t->vpl_evals;
    stats->vpl_reused = t->vpl_reused;
}

iir_refine_params iir_refine_params_of(const iir_method_common *c, const iir_indirect_params *v,
                                       int bounces)
{
    iir_refine_params r = {
        .interleave = v->interleave,
        .max_passes = c->refine_passes,
        .jitter = c->jitter,
        .clamp = v->clamp,
        .clamp_comp = v->clamp_comp != IIR_CLAMP_COMP_OFF,
        .bounces = bounces,
        .area_samples = v->area_samples,
        .seed = iir_hash3(c->seed, 0x4ef1, 0),
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
    stats->whole_sweeps = rs->whole_sweeps;
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
    static const char *names[IIR_PHASE_COUNT] = {"trace",    "vpls",   "shadowmaps", "maps",
                                                 "solve",    "gather", "gbuffer",    "direct",
                                                 "indirect", "filter", "display"};
    return phase < IIR_PHASE_COUNT ? names[phase] : "unknown";
}

const char *const *iir_method_names(void)
{
    static const char *names[NUM_METHODS + 1];
    for (int i = 0; i < NUM_METHODS; i++) names[i] = registry[i]->name;
    names[NUM_METHODS] = NULL;
    return names;
}

static const iir_method_ops *find_ops(const char *name);

int iir_method_phases(const char *name, const iir_phase **out)
{
    const iir_method_ops *ops = find_ops(name);
    *out = ops ? ops->phases : NULL;
    int n = 0;
    while (ops && ops->phases[n] != IIR_PHASE_COUNT) n++;
    return n;
}

int iir_method_counters(const char *name, const iir_counter **out)
{
    const iir_method_ops *ops = find_ops(name);
    *out = ops ? ops->counters : NULL;
    int n = 0;
    while (ops && n < IIR_MAX_COUNTERS && ops->counters[n].name) n++;
    return n;
}

int iir_method_counter_index(const char *name, const char *counter)
{
    const iir_counter *c;
    int n = iir_method_counters(name, &c);
    for (int i = 0; i < n; i++)
        if (!strcmp(c[i].name, counter)) return i;
    return -1;
}

static const iir_method_ops *find_ops(const char *name)
{
    if (!name) return NULL;
    for (int i = 0; i < NUM_METHODS; i++)
        if (strcmp(registry[i]->name, name) == 0) return registry[i];
    return NULL;
}

const iir_method_ops *iir_method_ops_of(const char *name)
{
    return find_ops(name);
}

const char *iir_method_summary(const char *name)
{
    const iir_method_ops *ops = find_ops(name);
    return ops ? ops->summary : "";
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

/* ======================== parameters ======================== */

const iir_param_table *const *iir_method_tables(const char *name)
{
    static const iir_param_table *lists[NUM_METHODS][IIR_METHOD_MAX_TABLES + 1];
    for (int m = 0; m < NUM_METHODS; m++) {
        if (strcmp(registry[m]->name, name) != 0) continue;
        for (int t = 0; t < IIR_METHOD_MAX_TABLES; t++) lists[m][t] = registry[m]->tables[t].table;
        return lists[m];
    }
    return NULL;
}

const iir_param_table *const *iir_method_all_tables(void)
{
    static const iir_param_table *all[NUM_METHODS * IIR_METHOD_MAX_TABLES + 1];
    int n = 0;
    for (int m = 0; m < NUM_METHODS; m++)
        for (int t = 0; t < IIR_METHOD_MAX_TABLES && registry[m]->tables[t].table; t++) {
            const iir_param_table *tab = registry[m]->tables[t].table;
            bool seen = false;
            for (int k = 0; k < n; k++) seen = seen || all[k] == tab;
            if (!seen) all[n++] = tab;
        }
    all[n] = NULL;
    return all;
}

static const iir_param *ops_find_param(const iir_method_ops *ops, const char *name)
{
    for (int t = 0; t < IIR_METHOD_MAX_TABLES && ops->tables[t].table; t++) {
        const iir_param *row = iir_param_table_find(ops->tables[t].table, name);
        if (row) return row;
    }
    return NULL;
}

const iir_param *iir_method_find_param(const char *method, const char *name)
{
    const iir_method_ops *ops = find_ops(method);
    return ops ? ops_find_param(ops, name) : NULL;
}

const iir_param *iir_method_any_param(const char *name)
{
    for (int m = 0; m < NUM_METHODS; m++) {
        const iir_param *row = ops_find_param(registry[m], name);
        if (row) return row;
    }
    return NULL;
}

static iir_status unknown_param(const char *name, iir_error *err)
{
    return iir_fail(err, IIR_ERR_INVALID, "%s is not a parameter of any method", name);
}

iir_status iir_method_param_set(iir_params *p, const char *name, double value, iir_error *err)
{
    const iir_param *row = iir_method_any_param(name);
    if (!row) return unknown_param(name, err);
    iir_params one = iir_params_default();
    one.count = 1;
    one.v[0].name = row->name;
    one.v[0].value = value;
    iir_status st = iir_method_params_check(&one, false, NULL, err);
    return st == IIR_OK ? iir_params_set(p, row, value, err) : st;
}

iir_status iir_method_params_check(const iir_params *p, bool live, const iir_param **bad,
                                   iir_error *err)
{
    for (uint32_t k = 0; k < p->count; k++) {
        const char *name = p->v[k].name;
        if (!iir_method_any_param(name)) return unknown_param(name, err);
        for (int m = 0; m < NUM_METHODS; m++) {
            const iir_param *row = ops_find_param(registry[m], name);
            iir_status st = row ? iir_param_check(row, p->v[k].value, live, err) : IIR_OK;
            if (st != IIR_OK) return bad ? (*bad = row, st) : st;
        }
    }
    return IIR_OK;
}

double iir_method_param_value(const iir_param *row, const iir_params *p)
{
    double v = row->def;
    iir_params_get(p, row->name, &v);
    return v;
}

/* Binds p into a new options struct of ops (malloc'ed); NULL with err on bad values. */
static void *bind_opts(const iir_method_ops *ops, const iir_params *p, const iir_params *given,
                       const iir_param **bad, iir_error *err)
{
    void *opts = calloc(1, ops->opts_size);
    if (!opts) return iir_fail(err, IIR_ERR_NOMEM, "out of memory"), NULL;
    iir_status st = IIR_OK;
    for (int t = 0; st == IIR_OK && t < IIR_METHOD_MAX_TABLES && ops->tables[t].table; t++)
        st = iir_params_bind(ops->tables[t].table, p, given, (char *)opts + ops->tables[t].offset,
                             bad, err);
    if (st != IIR_OK) free(opts), opts = NULL;
    return opts;
}

void *iir_method_bind_opts(const iir_method_ops *ops, const iir_params *p)
{
    iir_error err;
    return bind_opts(ops, p, NULL, NULL, &err);
}

iir_status iir_method_params_validate(const char *name, const iir_params *p,
                                      const iir_params *given, const iir_param **bad,
                                      iir_error *err)
{
    const iir_method_ops *ops = find_ops(name);
    if (!ops) return unknown_method(name, err);
    void *opts = bind_opts(ops, p, given, bad, err);
    free(opts);
    return opts ? IIR_OK : err->status;
}

uint64_t iir_method_converged_at(const char *name, const iir_params *p)
{
    const iir_method_ops *ops = find_ops(name);
    if (!ops || !ops->refine) return 0;
    iir_error err;
    void *opts = bind_opts(ops, p, NULL, NULL, &err);
    uint64_t at = 0;
    if (opts && ops->converged_at)
        at = ops->converged_at(opts);
    else if (opts)
        at = (uint64_t)iir_method_param_value(
            iir_param_table_find(&iir_common_table, "refine_passes"), p);
    free(opts);
    return at;
}

uint64_t iir_method_memory(const char *name, const iir_params *p, int width, int height)
{
    const iir_method_ops *ops = find_ops(name);
    iir_error err;
    void *opts = ops ? bind_opts(ops, p, NULL, NULL, &err) : NULL;
    uint64_t bytes = opts && ops->memory ? ops->memory(opts, width, height) : 0;
    free(opts);
    return bytes;
}

uint64_t iir_method_memory_on(const char *name, const iir_scene *scene, const iir_rt *rt,
                              const iir_params *p, int width, int height)
{
    const iir_method_ops *ops = find_ops(name);
    if (!ops || !ops->memory_on) return iir_method_memory(name, p, width, height);
    iir_error err;
    void *opts = bind_opts(ops, p, NULL, NULL, &err);
    uint64_t bytes = opts ? ops->memory_on(opts, scene, rt, width, height) : 0;
    free(opts);
    return bytes;
}

uint64_t iir_method_memory_held(const iir_method *m, int width, int height)
{
    if (!m->ops->held) return m->ops->memory ? m->ops->memory(m->opts, width, height) : 0;
    return m->ops->held(m->state, width, height);
}

/* ======================== the interface ======================== */

iir_status iir_method_supports(const char *name, const iir_light *lights, uint32_t num_lights,
                               iir_error *err)
{
    const iir_method_ops *ops = find_ops(name);
    if (!ops) return unknown_method(name, err);
    return ops->supports ? ops->supports(lights, num_lights, err) : IIR_OK;
}

iir_status iir_method_create_stoppable(const char *name, const iir_scene *scene, const iir_rt *rt,
                                       const iir_params *params, iir_stop_fn stop, void *ctx,
                                       iir_method **out, iir_error *err)
{
    *out = NULL;
    const iir_method_ops *ops = find_ops(name);
    if (!ops) return unknown_method(name, err);
    iir_method *m = calloc(1, sizeof *m);
    if (!m) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating method '%s'", name);
    m->ops = ops;
    m->params = *params;
    m->scene = scene;
    m->rt = rt;
    m->stop_fn = stop;
    m->stop_ctx = ctx;
    m->opts = bind_opts(ops, params, NULL, NULL, err);
    const iir_stop hook = {stop, ctx};
    iir_status st = m->opts ? ops->create(scene, rt, m->opts, &hook, &m->state, err) : err->status;
    if (st != IIR_OK) {
        free(m->opts);
        free(m);
        return st;
    }
    if (ops->set_stop) ops->set_stop(m->state, stop, ctx);
    *out = m;
    return IIR_OK;
}

iir_status iir_method_create(const char *name, const iir_scene *scene, const iir_rt *rt,
                             const iir_params *params, iir_method **out, iir_error *err)
{
    return iir_method_create_stoppable(name, scene, rt, params, NULL, NULL, out, err);
}

const iir_params *iir_method_params(const iir_method *m)
{
    return &m->params;
}

/* Whether opts a and b of m differ only in IIR_PARAM_LIVE rows. */
static bool only_live_changes(const iir_method_ops *ops, const void *a, const void *b)
{
    for (int t = 0; t < IIR_METHOD_MAX_TABLES && ops->tables[t].table; t++) {
        const iir_param_table *tab = ops->tables[t].table;
        size_t off = ops->tables[t].offset;
        for (int i = 0; i < tab->count; i++) {
            const iir_param *row = &tab->rows[i];
            if (row->effect != IIR_PARAM_LIVE && iir_param_read(row, (const char *)a + off) !=
                                                     iir_param_read(row, (const char *)b + off))
                return false;
        }
    }
    return true;
}

iir_status iir_method_set_params(iir_method *m, const iir_params *p, bool *restarted,
                                 iir_error *err)
{
    bool dummy;
    if (!restarted) restarted = &dummy;
    *restarted = false;
    void *opts = bind_opts(m->ops, p, NULL, NULL, err);
    if (!opts) return err->status;
    if (m->ops->update && only_live_changes(m->ops, m->opts, opts)) {
        m->ops->update(m->state, opts);
    } else {
        void *state = NULL;
        const iir_stop hook = {m->stop_fn, m->stop_ctx};
        iir_status st = m->ops->create(m->scene, m->rt, opts, &hook, &state, err);
        if (st != IIR_OK) return free(opts), st;
        m->ops->destroy(m->state);
        m->state = state;
        if (m->ops->set_stop) m->ops->set_stop(m->state, m->stop_fn, m->stop_ctx);
        *restarted = true;
    }
    free(m->opts);
    m->opts = opts;
    m->params = *p;
    return IIR_OK;
}

void iir_method_destroy(iir_method *m)
{
    if (!m) return;
    m->ops->destroy(m->state);
    free(m->opts);
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
    stats->whole_sweeps = true;
    return m->ops->render(m->state, view, out, stats, err);
}

const iir_vpl *iir_method_vpls(const iir_method *m, uint32_t *n)
{
    *n = 0;
    return m->ops->vpls ? m->ops->vpls(m->state, n) : NULL;
}

void iir_method_set_stop(iir_method *m, iir_stop_fn fn, void *ctx)
{
    if (!m) return;
    m->stop_fn = fn;
    m->stop_ctx = ctx;
    if (m->ops->set_stop) m->ops->set_stop(m->state, fn, ctx);
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
    stats->whole_sweeps = true; /* the VPL methods' refine_to_stats says otherwise */
    return m->ops->refine(m->state, out, stats, err);
}

bool iir_method_domain(iir_method *m, iir_domain *out)
{
    memset(out, 0, sizeof *out);
    return m->ops->domain ? m->ops->domain(m->state, out) : false;
}

int iir_method_reference_bounces(const char *name, const iir_params *p)
{
    const iir_param *row = iir_method_find_param(name, "bounces");
    if (row) return (int)iir_method_param_value(row, p);
    const iir_method_ops *ops = find_ops(name);
    return ops && ops->reference_bounces > 0 ? ops->reference_bounces : 2;
}

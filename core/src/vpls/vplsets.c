/* vplsets.c -- several lights' VPL sets side by side (vplsets.h): the budget split by the flux
 * each light's own set estimated, the sets' lifetimes as lights come, go and switch, and the
 * gathered array the renderer shades. Each set is an incremental step of its own (incremental.c);
 * nothing here looks inside one. */
#include "iir/vplsets.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "iir/lineage.h"
#include "iir/rng.h"
#include "iir/scene.h"

enum { MAXL = IIR_VPLSETS_MAX_LIGHTS };

struct iir_vplsets {
    const iir_scene *scene;
    const iir_rt *rt;
    iir_incr_params p; /* the totals */
    uint32_t n;        /* lights of the last update */
    iir_incr *set[MAXL];
    iir_incr_params sp[MAXL]; /* each set's parameters in force (target 0: off) */
    double flux[MAXL];        /* each set's last estimate of its flux into the scene */
    uint32_t total;           /* the N the targets in force were split from */
    iir_vpl *all;             /* the gathered array */
    uint32_t all_cap;
    int bounces;            /* > 2: each set's parents carry descendants (lineage.h) */
    iir_lineage *lin[MAXL]; /* set i's descendants, while bounces > 2 */
};

iir_status iir_vplsets_create(const iir_scene *scene, const iir_rt *rt, const iir_incr_params *p,
                              iir_vplsets **out, iir_error *err)
{
    *out = NULL;
    iir_status st = iir_incr_params_validate(p, err);
    if (st != IIR_OK) return st;
    iir_vplsets *g = calloc(1, sizeof *g);
    if (!g) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating the VPL sets");
    g->scene = scene, g->rt = rt, g->p = *p, g->bounces = 2;
    *out = g;
    return IIR_OK;
}

static void drop_set(iir_vplsets *g, uint32_t i)
{
    iir_incr_destroy(g->set[i]);
    iir_lineage_destroy(g->lin[i]);
    g->set[i] = NULL;
    g->lin[i] = NULL;
    g->sp[i].target = 0;
    g->flux[i] = 0.0;
}

void iir_vplsets_destroy(iir_vplsets *g)
{
    if (!g) return;
    for (uint32_t i = 0; i < MAXL; i++) iir_incr_destroy(g->set[i]), iir_lineage_destroy(g->lin[i]);
    free(g->all);
    free(g);
}

iir_status iir_vplsets_set_params(iir_vplsets *g, const iir_incr_params *p, iir_error *err)
{
    iir_status st = iir_incr_params_validate(p, err);
    if (st == IIR_OK) g->p = *p;
    return st;
}

void iir_vplsets_set_bounces(iir_vplsets *g, int bounces)
{
    g->bounces = bounces;
}

iir_incr_params iir_vplsets_get_params(const iir_vplsets *g)
{
    return g->p;
}

uint32_t iir_vplsets_lights(const iir_vplsets *g)
{
    return g->n;
}

iir_incr *iir_vplsets_set(iir_vplsets *g, uint32_t i)
{
    return i < g->n ? g->set[i] : NULL;
}

iir_vpl *iir_vplsets_descendants(iir_vplsets *g, uint32_t i, uint32_t *n)
{
    *n = 0;
    return i < g->n && g->set[i] && g->lin[i] ? iir_lineage_vpls(g->lin[i], n) : NULL;
}

uint32_t iir_vplsets_target(const iir_vplsets *g, uint32_t i)
{
    return i < g->n && g->set[i] ? g->sp[i].target : 0;
}

/* ---- shares ---- */

static bool is_on(const iir_light *l)
{
    return !iir_is_black(l->intensity);
}

/* Light i's flux for its share: its set's estimate, or its emitted flux before it has a set. */
static double share_flux(const iir_vplsets *g, const iir_light *l, uint32_t i)
{
    if (!is_on(l)) return 0.0;
    return g->set[i] ? g->flux[i] : (double)iir_luminance(iir_light_flux(l));
}

/* Targets for the lights that are on: a floor each, the rest of N by share (largest remainders,
 * ties to the lower index). */
static void split_targets(const iir_vplsets *g, const iir_light *lights, uint32_t n,
                          uint32_t *target)
{
    double F[MAXL], sum = 0.0, rem[MAXL];
    uint32_t on = 0, N = g->p.target;
    for (uint32_t i = 0; i < n; i++) F[i] = share_flux(g, &lights[i], i), sum += F[i];
    for (uint32_t i = 0; i < n; i++) on += is_on(&lights[i]);
    if (on == 0) return (void)memset(target, 0, n * sizeof *target);
    uint32_t floor_each = N / on < IIR_VPLSETS_MIN_TARGET ? N / on : IIR_VPLSETS_MIN_TARGET;
    if (floor_each == 0) floor_each = 1;
    uint32_t rest = N > floor_each * on ? N - floor_each * on : 0, given = 0;
    for (uint32_t i = 0; i < n; i++) {
        bool lit = is_on(&lights[i]);
        double share = !lit ? 0.0 : sum > 0.0 ? F[i] / sum : 1.0 / on;
        double exact = share * rest;
        target[i] = lit ? floor_each + (uint32_t)exact : 0;
        rem[i] = lit ? exact - floor(exact) : -1.0;
        given += lit ? (uint32_t)exact : 0;
    }
    for (; given < rest; given++) { /* largest remainders */
        uint32_t best = 0;
        for (uint32_t i = 1; i < n; i++)
            if (rem[i] > rem[best]) best = i;
        target[best]++;
        rem[best] = -1.0;
    }
}

/* Whether the new targets may replace the old: some light came, went or switched, or some target
 * moved by more than max(2, 1/16 of the old). Otherwise the old ones stay (they sum to N too). */
static bool targets_moved(const iir_vplsets *g, const uint32_t *target, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++) {
        uint32_t old = g->set[i] ? g->sp[i].target : 0, t = target[i];
        uint32_t slack = old / 16 > 2 ? old / 16 : 2;
        if (!old != !t || (t > old ? t - old : old - t) > slack) return true;
    }
    return g->p.target != g->total;
}

/* Light i's parameters for target t: the totals' per-frame budgets scaled by t / N. */
static iir_incr_params set_params(const iir_vplsets *g, uint32_t i, uint32_t t)
{
    iir_incr_params q = g->p;
    double share = (double)t / g->p.target;
    q.target = t;
    q.seed = i ? iir_hash3(g->p.seed, i, 0x5e75) : g->p.seed; /* light 0: the totals' seed */
    q.k_max = (uint32_t)fmax(1.0, round(g->p.k_max * share));
    q.k_min = (uint32_t)round(g->p.k_min * share);
    if (q.k_min > q.k_max) q.k_min = q.k_max;
    return q;
}

/* ---- one frame ---- */

static void add_stats(iir_incr_stats *sum, const iir_incr_stats *s)
{
    iir_vpl_counts *a = &sum->vpl;
    const iir_vpl_counts *b = &s->vpl;
    a->count += b->count, a->valid += b->valid, a->invalidated += b->invalidated;
    a->deleted += b->deleted, a->inserted += b->inserted, a->null_samples += b->null_samples;
    a->regenerated |= b->regenerated;
    a->descendants += b->descendants;
    sum->initial |= s->initial;
    for (int k = 0; k < IIR_INCR_PHASE_COUNT; k++) sum->phase_ms[k] += s->phase_ms[k];
    sum->total_ms += s->total_ms;
    iir_raystats_add(&sum->rays, &s->rays);
    sum->flux_in += s->flux_in;
}

/* Drops set i (a light gone or off), counting its VPLs as deleted. */
static void retire(iir_vplsets *g, uint32_t i, iir_incr_stats *sum)
{
    uint32_t n = 0;
    if (g->set[i]) iir_incr_vpls(g->set[i], &n);
    sum->vpl.deleted += n;
    drop_set(g, i);
}

static iir_status check_lights(const iir_light *lights, uint32_t n, iir_error *err)
{
    if (n > MAXL)
        return iir_fail(err, IIR_ERR_INVALID, "%u lights: at most %u keep VPL sets", n, MAXL);
    for (uint32_t i = 0; i < n; i++) {
        iir_status st = iir_light_validate(&lights[i], err);
        if (st != IIR_OK) return st;
    }
    return IIR_OK;
}

/* Light i's set for this frame: created, or given its new parameters. */
static iir_status prepare_set(iir_vplsets *g, uint32_t i, uint32_t t, iir_error *err)
{
    iir_incr_params q = set_params(g, i, t);
    if (g->set[i] && !memcmp(&q, &g->sp[i], sizeof q)) return IIR_OK;
    iir_status st = g->set[i] ? iir_incr_set_params(g->set[i], &q, err)
                              : iir_incr_create(g->scene, g->rt, &q, &g->set[i], err);
    if (st == IIR_OK) g->sp[i] = q;
    return st;
}

/* Set i's descendants after its update (lineage.h), with their rays and count in s; none (and
 * their maps released) while bounces <= 2. */
static iir_status update_lineage(iir_vplsets *g, uint32_t i, iir_incr_stats *s, iir_error *err)
{
    if (g->bounces <= 2) {
        iir_lineage_destroy(g->lin[i]);
        g->lin[i] = NULL;
        return IIR_OK;
    }
    if (!g->lin[i] && !(g->lin[i] = iir_lineage_create(g->scene, g->rt)))
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for the VPLs' descendants");
    uint32_t n = 0;
    const iir_vpl *v = iir_incr_vpls(g->set[i], &n);
    iir_lineage_stats ls;
    iir_status st =
        iir_lineage_update(g->lin[i], v, n, g->bounces, g->sp[i].seed, &s->rays, &ls, err);
    s->vpl.descendants = ls.count;
    return st;
}

iir_status iir_vplsets_update(iir_vplsets *g, const iir_light *lights, uint32_t n,
                              iir_incr_stats *out, iir_error *err)
{
    iir_status st = check_lights(lights, n, err);
    if (st != IIR_OK) return st;
    iir_incr_stats sum;
    memset(&sum, 0, sizeof sum);
    for (uint32_t i = n; i < g->n; i++) retire(g, i, &sum);
    g->n = n;
    uint32_t target[MAXL];
    split_targets(g, lights, n, target);
    bool moved = targets_moved(g, target, n);
    for (uint32_t i = 0; i < n && !moved; i++) target[i] = g->sp[i].target;
    g->total = g->p.target;
    for (uint32_t i = 0; i < n && st == IIR_OK; i++) {
        if (!target[i]) {
            retire(g, i, &sum);
            continue;
        }
        st = prepare_set(g, i, target[i], err);
        iir_incr_stats s;
        if (st == IIR_OK) st = iir_incr_update(g->set[i], &lights[i], &s, err);
        if (st == IIR_OK) st = update_lineage(g, i, &s, err);
        if (st != IIR_OK) break;
        g->flux[i] = s.flux_in;
        add_stats(&sum, &s);
    }
    if (out) *out = sum;
    return st;
}

static uint32_t set_descendants(iir_vplsets *g, uint32_t k)
{
    uint32_t m = 0;
    iir_vplsets_descendants(g, k, &m);
    return m;
}

const iir_vpl *iir_vplsets_gather(iir_vplsets *g, uint32_t *n)
{
    uint32_t total = 0, k, m;
    for (k = 0; k < g->n; k++)
        if (g->set[k]) total += (iir_incr_vpls(g->set[k], &m), m) + set_descendants(g, k);
    *n = 0;
    if (total > g->all_cap) {
        iir_vpl *a = realloc(g->all, total * sizeof *a);
        if (!a) return NULL;
        g->all = a, g->all_cap = total;
    }
    for (k = 0; k < g->n; k++) {
        if (!g->set[k]) continue;
        const iir_vpl *v = iir_incr_vpls(g->set[k], &m);
        for (uint32_t j = 0; j < m; j++) {
            g->all[*n] = v[j];
            g->all[(*n)++].id = v[j].id * g->n + k;
        }
        v = iir_vplsets_descendants(g, k, &m);
        for (uint32_t j = 0; j < m; j++) {
            g->all[*n] = v[j];
            g->all[(*n)++].id = v[j].id * g->n + k;
        }
    }
    return total ? g->all : NULL;
}

/* controller.c -- the frame-time controller (controller.h): the ladder, the cost model, the move
 * rule and the evidence that a cut bought time. Not how a method applies a setting, nor which of
 * its frames are interactive (iir.c). */
#include <math.h>
#include <stdlib.h>

#include "iir/controller.h"

enum {
    STEPS_PER_OCTAVE = 8, /* main rungs: N grows by 2^(1/8) */
    DOWN_FRAMES = 2,      /* frames wanting a cheaper setting before taking it */
    PATIENCE_MIN = 4,     /* frames wanting a dearer setting before taking it */
    PATIENCE_MAX = 128,
    HOLD_FRAMES = 4,    /* frames a new setting is held */
    UNDO_WINDOW = 30,   /* a move undoing the last one within this many frames doubles patience */
    QUIET_FRAMES = 100, /* frames without an undo that halve patience again */
    MAX_CLIMB = STEPS_PER_OCTAVE,
    SM_COARSEST = 2,     /* maps down to a quarter of the configured resolution (and the floor) */
    EVIDENCE_FRAMES = 6, /* frames at a setting under check before it is judged */
    SETTLE_MAX = 8,      /* frames after a move a growing set's frames are left out, at most */
    BEFORE_MIN = 3,      /* frames at the current setting before a cut, the last ones (which
                            wanted it: the conditions it answers) to judge it by */
    AT_MAX = 16,         /* frame times kept of the current setting */
    BUSY_MIN = 60,       /* frames without cuts after one bought no time, doubling ... */
    BUSY_MAX = 480       /* ... up to this */
};

static const double ALPHA = 0.2;      /* the model's running means */
static const double FIT = 0.97;       /* a rung fits when predicted within 97% of the target */
static const double OVER = 1.08;      /* the current rung is too dear above 108% */
static const double MAPS_HIGH = 0.30; /* maps coarser when they would take more of the target */
static const double MAPS_LOW = 0.15;  /* and finer again when the finer ones would take less */
static const double GROWN = 0.9;      /* no climbing while the set holds less of its N */
static const double CHECKED = 0.15; /* cuts promising at least this share of a frame are checked */
static const double BOUGHT = 0.4;   /* and kept when they saved this share of their promise */
static const double NEAR = 0.05;    /* unreachable: the best rung this near the cheapest */

/* The model's units (controller.h), each a running mean; `have_*` says it was measured. */
typedef struct cost_model {
    double rest_ms, eval_ms, texel_ms, tap_ms, step_ms; /* rest, a, b, c, d */
    double pixels, maps;                                /* P, maps per frame */
    bool have_rest, have_eval, have_texel, have_tap, have_step;
} cost_model;

typedef struct rung {
    int vpls, interleave;
} rung;

/* A cut being checked against the clock (controller.h, "The evidence"): first its own frames
 * against the ones that wanted it; when those say it bought nothing, the old setting's frames
 * again, right after (the same conditions), against the cut's. */
typedef enum check_phase { CHECK_NONE, CHECK_CUT, CHECK_BACK } check_phase;

typedef struct cut_check {
    check_phase phase;
    int rung, shift;         /* the setting before the cut */
    int cut_rung, cut_shift; /* the cut's */
    double before_ms;        /* the median frame before the cut */
    double cut_ms;           /* the median frame of the cut */
    double promised;         /* the share of a frame the model said the cut saves */
} cut_check;

struct iir_ctl {
    iir_ctl_config cfg;
    rung rung[IIR_CTL_MAX_RUNGS];
    int rungs, cur; /* the ladder, and the current rung */
    int sm_shift;   /* the maps' resolution: cfg.sm_res >> sm_shift */
    cost_model m;
    double mean_ms;
    bool have_mean;
    double prev_vpls;     /* the last sample's set size: growth is not a rate of maps */
    double at_ms[AT_MAX]; /* the latest frame times at the current setting (ring) ... */
    int at_n;             /* ... how many since the last move (its first frame left out) */
    int since_move;       /* samples since the last move */
    cut_check check;      /* the last cut, while it is judged */
    uint64_t busy_until;  /* no cuts before this frame: the last one bought no time */
    int busy_hold;        /* the next such hold, in frames */
    uint32_t undone;      /* cuts undone */
    int want_streak;      /* consecutive frames wanting a dearer (+) or cheaper (-) setting */
    int held;             /* frames left holding the current setting */
    int patience;         /* frames wanting a dearer setting before taking it */
    int last_dir;         /* direction of the last move (+1 dearer, -1 cheaper, 0 none) */
    uint64_t frame;       /* measured frames */
    uint64_t last_move, last_undo;
    uint32_t moves;
};

/* ---- the ladder ---- */

static int clampi(int v, int lo, int hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

static void add_rung(iir_ctl *c, int vpls, int n)
{
    if (c->rungs == IIR_CTL_MAX_RUNGS) return;
    if (c->rungs > 0 && c->rung[c->rungs - 1].vpls == vpls && c->rung[c->rungs - 1].interleave == n)
        return;
    c->rung[c->rungs++] = (rung){vpls, n};
}

/* The main rungs from the floor N_min up to N_max, then N_max with narrower interleaves; none
 * below the floor, so none with a wider interleave (controller.h). */
static void build_ladder(iir_ctl *c)
{
    const iir_ctl_config *g = &c->cfg;
    int n_min = g->vpls_max < g->vpls_min ? g->vpls_max : g->vpls_min;
    c->rungs = 0;
    for (int k = 0;; k++) {
        int vpls = (int)lround(n_min * exp2((double)k / STEPS_PER_OCTAVE));
        if (vpls >= g->vpls_max) break;
        add_rung(c, vpls, g->interleave);
    }
    add_rung(c, g->vpls_max, g->interleave);
    for (int n = g->interleave - 1; n >= 1 && n >= g->interleave - 2; n--)
        add_rung(c, g->vpls_max, n);
}

/* The main rung (the configured interleave) whose N is nearest vpls. */
static int nearest_rung(const iir_ctl *c, int vpls)
{
    int best = 0;
    double best_d = INFINITY;
    for (int i = 0; i < c->rungs; i++) {
        if (c->rung[i].interleave != c->cfg.interleave) continue;
        double d = fabs(log((double)c->rung[i].vpls / vpls));
        if (d < best_d) best = i, best_d = d;
    }
    return best;
}

/* The maps' floor: sm_res_min, or the configured resolution when that is coarser. */
static int sm_floor(const iir_ctl *c)
{
    return c->cfg.sm_res < c->cfg.sm_res_min ? c->cfg.sm_res : c->cfg.sm_res_min;
}

/* The maps' resolution at shift k: the configured one halved k times, not below the floor. */
static int sm_res_at(const iir_ctl *c, int k)
{
    int r = c->cfg.sm_res >> k;
    return r < sm_floor(c) ? sm_floor(c) : r;
}

/* The coarsest shift that still coarsens the maps (at most SM_COARSEST). */
static int coarsest_shift(const iir_ctl *c)
{
    int k = 0;
    while (k < SM_COARSEST && sm_res_at(c, k + 1) < sm_res_at(c, k)) k++;
    return k;
}

static iir_ctl_setting setting_of(const iir_ctl *c, int rung, int shift)
{
    iir_ctl_setting s = {c->rung[rung].vpls, c->rung[rung].interleave, sm_res_at(c, shift)};
    return s;
}

static iir_status check_config(const iir_ctl_config *g, iir_error *err)
{
    if (!(g->target_ms > 0.0) || !isfinite(g->target_ms))
        return iir_fail(err, IIR_ERR_INVALID, "controller: target %g ms must be finite and > 0",
                        g->target_ms);
    if (g->vpls_max < 1 || g->vpls_max > 16384)
        return iir_fail(err, IIR_ERR_INVALID, "controller: vpls_max %d is outside [1, 16384]",
                        g->vpls_max);
    if (g->vpls_min < 1 || g->vpls_min > 16384)
        return iir_fail(err, IIR_ERR_INVALID, "controller: vpls_min %d is outside [1, 16384]",
                        g->vpls_min);
    if (g->interleave < 1 || g->interleave > 8)
        return iir_fail(err, IIR_ERR_INVALID, "controller: interleave %d is outside [1, 8]",
                        g->interleave);
    if (g->sm_res < 8 || g->sm_res > 2048)
        return iir_fail(err, IIR_ERR_INVALID, "controller: sm_res %d is outside [8, 2048]",
                        g->sm_res);
    if (g->sm_res_min < 8 || g->sm_res_min > 2048)
        return iir_fail(err, IIR_ERR_INVALID, "controller: sm_res_min %d is outside [8, 2048]",
                        g->sm_res_min);
    return IIR_OK;
}

iir_status iir_ctl_create(const iir_ctl_config *cfg, int start_vpls, iir_ctl **out, iir_error *err)
{
    *out = NULL;
    iir_status st = check_config(cfg, err);
    if (st != IIR_OK) return st;
    iir_ctl *c = calloc(1, sizeof *c);
    if (!c) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating the frame-time controller");
    c->cfg = *cfg;
    build_ladder(c);
    c->cur = nearest_rung(c, start_vpls > 0 ? start_vpls : 1);
    c->patience = PATIENCE_MIN;
    c->busy_hold = BUSY_MIN;
    *out = c;
    return IIR_OK;
}

void iir_ctl_destroy(iir_ctl *c)
{
    free(c);
}

static bool same_config(const iir_ctl_config *a, const iir_ctl_config *b)
{
    return a->target_ms == b->target_ms && a->vpls_max == b->vpls_max &&
           a->vpls_min == b->vpls_min && a->interleave == b->interleave && a->sm_res == b->sm_res &&
           a->sm_res_min == b->sm_res_min;
}

iir_status iir_ctl_configure(iir_ctl *c, const iir_ctl_config *cfg, iir_error *err)
{
    iir_status st = check_config(cfg, err);
    if (st != IIR_OK) return st;
    if (same_config(&c->cfg, cfg)) return IIR_OK; /* another parameter changed: nothing here */
    int vpls = c->rung[c->cur].vpls;
    c->cfg = *cfg;
    build_ladder(c);
    c->cur = nearest_rung(c, vpls);
    c->sm_shift = c->sm_shift < coarsest_shift(c) ? c->sm_shift : coarsest_shift(c);
    c->want_streak = 0;
    c->check.phase = CHECK_NONE; /* a new ladder: the frames before are no evidence */
    c->at_n = 0;
    c->busy_until = 0;
    return IIR_OK;
}

/* ---- the model ---- */

static void mean_in(double *m, bool *have, double x)
{
    if (!isfinite(x) || x < 0.0) return;
    *m = *have ? *m + ALPHA * (x - *m) : x;
    *have = true;
}

/* The maps a frame built to replace VPLs, not to grow the set towards a raised N (those are paid
 * once): maps times the inserted VPLs that did not add to the set's size. */
static double replacement_maps(const iir_ctl_sample *s, double prev_vpls)
{
    double growth = s->vpls > prev_vpls ? s->vpls - prev_vpls : 0.0;
    if (!(s->inserted > 0.0) || growth <= 0.0) return s->maps;
    double kept = s->inserted > growth ? (s->inserted - growth) / s->inserted : 0.0;
    return s->maps * kept;
}

static void measure(cost_model *m, const iir_ctl_sample *s, double prev_vpls)
{
    double n2 = (double)s->setting.interleave * s->setting.interleave;
    double res2 = (double)s->setting.sm_res * s->setting.sm_res;
    double rest = s->total_ms - s->step_ms - s->shadowmap_ms - s->indirect_ms - s->filter_ms;
    mean_in(&m->rest_ms, &m->have_rest, rest > 0.0 ? rest : 0.0);
    if (s->vpl_evals > 0.0 && s->vpls > 0.0) {
        double P = s->vpl_evals * n2 / s->vpls;
        m->pixels = m->have_eval ? m->pixels + ALPHA * (P - m->pixels) : P;
        mean_in(&m->eval_ms, &m->have_eval, s->indirect_ms / s->vpl_evals);
    }
    if (s->maps > 0.0) mean_in(&m->texel_ms, &m->have_texel, s->shadowmap_ms / (s->maps * res2));
    mean_in(&m->tap_ms, &m->have_tap, s->filter_ms / n2);
    if (s->regenerated) return; /* a whole new set: its maps and step are no rate per frame */
    m->maps += ALPHA * (replacement_maps(s, prev_vpls) - m->maps);
    if (s->vpls > 0.0) mean_in(&m->step_ms, &m->have_step, s->step_ms / s->vpls);
}

/* The maps' share of a frame at resolution res. */
static double maps_ms(const cost_model *m, int res)
{
    return m->have_texel ? m->texel_ms * m->maps * (double)res * res : 0.0;
}

double iir_ctl_predict(const iir_ctl *c, const iir_ctl_setting *s)
{
    const cost_model *m = &c->m;
    if (!m->have_rest) return 0.0;
    double N = s->vpls, n2 = (double)s->interleave * s->interleave;
    double t = m->rest_ms + maps_ms(m, s->sm_res);
    if (m->have_eval) t += m->eval_ms * m->pixels * N / n2;
    if (m->have_tap) t += m->tap_ms * n2;
    if (m->have_step) t += m->step_ms * N;
    return t;
}

/* ---- the rule ---- */

static double predict_at(const iir_ctl *c, int rung, int shift)
{
    iir_ctl_setting s = setting_of(c, rung, shift);
    return iir_ctl_predict(c, &s);
}

/* The maps' resolution wanted: one step coarser when the current maps take more than MAPS_HIGH
 * of the target, one finer when those would take less than MAPS_LOW. */
static int wanted_shift(const iir_ctl *c)
{
    double T = c->cfg.target_ms;
    int k = c->sm_shift;
    if (k < coarsest_shift(c) && maps_ms(&c->m, sm_res_at(c, k)) > MAPS_HIGH * T) return k + 1;
    if (k > 0 && maps_ms(&c->m, sm_res_at(c, k - 1)) < MAPS_LOW * T) return k - 1;
    return k;
}

/* The rung wanted with maps at shift k: the current one while its prediction is within OVER of
 * the target and the next is not within FIT (or the set is still growing to its N); else the
 * highest within FIT, at most MAX_CLIMB above the current; when none is (the target is out of
 * reach), the highest predicted within NEAR of the cheapest: no quality is given for a few per
 * cent of a frame that still misses the target. */
static int wanted_rung(const iir_ctl *c, int k, bool growing)
{
    double T = c->cfg.target_ms;
    bool over = predict_at(c, c->cur, k) > OVER * T;
    bool room = !growing && c->cur + 1 < c->rungs && predict_at(c, c->cur + 1, k) <= FIT * T;
    if (!over && !room) return c->cur;
    int top = over ? c->cur : clampi(c->cur + MAX_CLIMB, 0, c->rungs - 1);
    double cheapest = INFINITY;
    for (int i = top; i >= 0; i--) {
        double t = predict_at(c, i, k);
        if (t <= FIT * T) return i;
        if (t < cheapest) cheapest = t;
    }
    for (int i = top; i > 0; i--)
        if (predict_at(c, i, k) <= (1.0 + NEAR) * cheapest) return i;
    return 0;
}

static void move_to(iir_ctl *c, int rung, int shift, int dir)
{
    if (c->last_dir && dir != c->last_dir && c->frame - c->last_move <= UNDO_WINDOW) {
        c->patience = c->patience * 2 > PATIENCE_MAX ? PATIENCE_MAX : c->patience * 2;
        c->last_undo = c->frame;
    }
    c->cur = rung;
    c->sm_shift = shift;
    c->last_dir = dir;
    c->last_move = c->frame;
    c->held = HOLD_FRAMES;
    c->want_streak = 0;
    c->moves++;
    c->at_n = 0;
    c->since_move = 0;
}

/* ---- the evidence ---- */

/* The median of the last k frame times kept at the current setting (fewer when fewer are kept; 0
 * when none). */
static double at_median(const iir_ctl *c, int k)
{
    int n = c->at_n < AT_MAX ? c->at_n : AT_MAX;
    n = n < k ? n : k;
    double v[AT_MAX] = {0};
    for (int i = 0; i < n; i++) {
        double x = c->at_ms[(c->at_n - 1 - i) % AT_MAX];
        int j = i;
        for (; j > 0 && v[j - 1] > x; j--) v[j] = v[j - 1];
        v[j] = x;
    }
    if (n == 0) return 0.0;
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/* A frame's time at the current setting, kept unless it is the first after a move (the set still
 * shrinks to its N, the maps change) or its set is still growing to its N, up to SETTLE_MAX frames
 * after the move (a set that grows no further is as grown as it gets). */
static void note_time(iir_ctl *c, const iir_ctl_sample *s)
{
    bool growing = s->vpls < GROWN * s->setting.vpls && c->since_move < SETTLE_MAX;
    if (c->since_move++ > 0 && !growing) c->at_ms[c->at_n++ % AT_MAX] = s->total_ms;
}

/* Before a cut from the current setting to (rung, shift) (taken only with BEFORE_MIN frames at
 * the current setting to compare with): checked when it promises CHECKED of a frame or more. */
static void start_check(iir_ctl *c, int rung, int shift)
{
    double was = predict_at(c, c->cur, c->sm_shift), will = predict_at(c, rung, shift);
    double promised = was > 0.0 ? 1.0 - will / was : 0.0;
    c->check = (cut_check){.phase = promised >= CHECKED ? CHECK_CUT : CHECK_NONE,
                           .rung = c->cur,
                           .shift = c->sm_shift,
                           .cut_rung = rung,
                           .cut_shift = shift,
                           .before_ms = at_median(c, BEFORE_MIN),
                           .promised = promised};
}

/* Whether frames at `slow_ms` against frames at `fast_ms` show the saving the cut promised. */
static bool bought(const iir_ctl *c, double fast_ms, double slow_ms)
{
    return slow_ms > 0.0 && 1.0 - fast_ms / slow_ms >= BOUGHT * c->check.promised;
}

/* The cut under check, once the setting in force has EVIDENCE_FRAMES frames. The cut's frames
 * against the ones before it: kept when they show BOUGHT of its promise; else the old setting
 * again. Its frames against the cut's: the cut again when they show it (the conditions had
 * changed), else the machine is busy -- the old setting stays and no cut is taken for busy_hold
 * frames (which doubles; a cut that bought its time sets it back to BUSY_MIN). Returns true when
 * the setting changed. */
static bool judge_cut(iir_ctl *c)
{
    cut_check *k = &c->check;
    if (k->phase == CHECK_NONE || c->at_n < EVIDENCE_FRAMES) return false;
    double now = at_median(c, EVIDENCE_FRAMES);
    if (k->phase == CHECK_CUT && !bought(c, now, k->before_ms)) {
        k->phase = CHECK_BACK;
        k->cut_ms = now;
        move_to(c, k->rung, k->shift, +1);
        c->last_dir = 0; /* not the model's undo: patience stays */
        return true;
    }
    bool back = k->phase == CHECK_BACK;
    k->phase = CHECK_NONE;
    if (!back) {
        c->busy_hold = BUSY_MIN;
        return false;
    }
    if (bought(c, k->cut_ms, now)) {
        move_to(c, k->cut_rung, k->cut_shift, -1);
        c->busy_hold = BUSY_MIN;
        return true;
    }
    c->busy_until = c->frame + (uint64_t)c->busy_hold;
    c->busy_hold = c->busy_hold * 2 > BUSY_MAX ? BUSY_MAX : c->busy_hold * 2;
    c->undone++;
    return false;
}

bool iir_ctl_update(iir_ctl *c, const iir_ctl_sample *s)
{
    if (!(s->total_ms > 0.0) || !isfinite(s->total_ms)) return false;
    c->frame++;
    measure(&c->m, s, c->prev_vpls);
    c->prev_vpls = s->vpls;
    mean_in(&c->mean_ms, &c->have_mean, s->total_ms);
    note_time(c, s);
    if (c->frame - c->last_undo > QUIET_FRAMES && c->patience > PATIENCE_MIN) {
        c->patience /= 2;
        c->last_undo = c->frame;
    }
    if (judge_cut(c)) return true;
    if (c->held > 0) return c->held--, false;
    if (c->check.phase != CHECK_NONE) return false; /* one cut judged at a time */
    bool growing = s->vpls < GROWN * s->setting.vpls;
    int k = wanted_shift(c), want = wanted_rung(c, k, growing);
    int dir = 0;
    if (want != c->cur || k != c->sm_shift)
        dir = predict_at(c, want, k) > predict_at(c, c->cur, c->sm_shift) ? 1 : -1;
    if (dir < 0 && (c->frame < c->busy_until || c->at_n < BEFORE_MIN))
        dir = 0; /* the last cut bought nothing, or this one could not be judged: hold */
    if (dir == 0 || (c->want_streak != 0 && (dir > 0) != (c->want_streak > 0))) c->want_streak = 0;
    c->want_streak += dir;
    if ((dir < 0 && -c->want_streak >= DOWN_FRAMES) || (dir > 0 && c->want_streak >= c->patience)) {
        if (dir < 0) start_check(c, want, k);
        move_to(c, want, k, dir);
        return true;
    }
    return false;
}

/* ---- reading it ---- */

iir_ctl_setting iir_ctl_current(const iir_ctl *c)
{
    return setting_of(c, c->cur, c->sm_shift);
}

iir_ctl_setting iir_ctl_rung(const iir_ctl *c, int i)
{
    return setting_of(c, clampi(i, 0, c->rungs - 1), c->sm_shift);
}

void iir_ctl_get_report(const iir_ctl *c, iir_ctl_report *out)
{
    out->setting = iir_ctl_current(c);
    out->rung = c->cur;
    out->rungs = c->rungs;
    out->target_ms = c->cfg.target_ms;
    out->predicted_ms = iir_ctl_predict(c, &out->setting);
    out->mean_ms = c->have_mean ? c->mean_ms : 0.0;
    out->frames = c->frame;
    out->reachable = !c->m.have_rest;
    for (int i = 0; i < c->rungs && !out->reachable; i++)
        out->reachable = predict_at(c, i, coarsest_shift(c)) <= c->cfg.target_ms;
    out->busy = c->frame < c->busy_until && c->mean_ms > OVER * c->cfg.target_ms;
    out->floor = setting_of(c, 0, coarsest_shift(c));
    out->moves = c->moves;
    out->undone = c->undone;
}

/* iir.c -- incremental instant radiosity, method "iir" (Laine et al. 2007): the VPL set lives
 * across frames. Each frame runs the incremental step (core/src/vpls/incremental.c) for every light
 * of the view, each on its own domain with its share of the budget (vplsets.h), renders shadow maps
 * only for the VPLs born this frame (a map lives as long as its VPL: the scene is static), and
 * shades with the shared VPL renderer. With bounces > 2 every kept VPL carries the rest of its
 * light path (lineage.h, through vplsets.h), whose VPLs get their maps at their birth too. With
 * insert_ms > 0 the step's k_max is set each frame to what the budget buys at the running cost of
 * a new VPL with its maps ("the insertion budget" below). Parameters: the incremental step's
 * (table below), light bounces (method.c), the VPL shading's (vpl_options.c), the ISMs'
 * (ism_options.c: with visibility=ism a VPL's map is an imperfect one, also built at its birth)
 * and every method's. Direct light comes from every light of the view.
 *
 * Refinement (refine.h; refine_passes, jitter, interleave, clamp): sweep 0 shades the live
 * set, sweep s >= 1 a fresh set sampled as a regeneration would (iir_incr_sample_set, stream
 * (frame, s)) into a buffer of this file, so the live set is exactly as before when frames resume.
 * The domain (iir_method_domain) of the light a user moves (the first spot, else the first light)
 * is drawn from its set's triangulation on demand into buffers of this file that grow with the set
 * and are reused; site ids are that set's own. */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "iir/method.h"
#include "iir/ism.h"
#include "iir/lineage.h"
#include "iir/refine.h"
#include "iir/rng.h"
#include "iir/scene.h"
#include "iir/shadowmap.h"
#include "domain_draw.h"
#include "iir/light_domain.h"
#include "iir/vplsets.h"
#include "method_internal.h"
#include "iir/timer.h"

/* ---- parameters ---- */

typedef struct iir_options {
    iir_method_common common;
    iir_indirect_params vpl; /* bounces: the method's own `bounces` */
    iir_ism_options ism;
    int vpls;              /* N: the VPL set's size */
    int kmin, kmax;        /* replacements per frame */
    iir_weights weights;   /* uniform, Voronoi or surface-aware cell areas */
    float regen_threshold; /* regenerate when more than this fraction dies */
    int bounces;           /* 2: the kept set alone; more: its VPLs carry descendants */
    float insert_ms;       /* > 0: time a frame for new VPLs and their maps (kmax caps, 0 none) */
    bool refill;           /* every VPL removed is replaced in its frame (insert_ms 0 only) */
    iir_ctl_options ctl;   /* target_fps > 0: the controller sets vpls, interleave and sm_res */
} iir_options;

static const char *const WEIGHTS_CHOICES[] = {"uniform", "voronoi", "surface", NULL};

static const iir_param IIR_ROWS[] = {
    {"vpls", IIR_PARAM_INT, offsetof(iir_options, vpls), 256, 1, 16384, 4096, NULL, "VPLs",
     "the VPL set's size N", IIR_PARAM_RESTART},
    {"kmin", IIR_PARAM_INT, offsetof(iir_options, kmin), 4, 0, 16384, 4096, NULL, "VPLs",
     "VPLs replaced per frame at least (the crowded ones)", IIR_PARAM_LIVE},
    {"kmax", IIR_PARAM_INT, offsetof(iir_options, kmax), 8, 0, 16384, 4096, NULL, "VPLs",
     "VPLs inserted per frame at most (with insert_ms: the cap, 0 = none)", IIR_PARAM_LIVE},
    {"insert_ms", IIR_PARAM_FLOAT, offsetof(iir_options, insert_ms), 0, 0, 1000, 0, NULL, "ms",
     "time per frame for new VPLs and their shadow maps: as many as fit at their measured cost "
     "(frames then depend on the machine's speed); 0 = kmax a frame",
     IIR_PARAM_LIVE},
    {"weights", IIR_PARAM_ENUM, offsetof(iir_options, weights), IIR_WEIGHTS_SURFACE, 0, 2, 0,
     WEIGHTS_CHOICES, "",
     "VPL flux by Voronoi cell area (surface: less the cell's reach over other surfaces, found by "
     "16 rays a VPL) or uniform (the paper's)",
     IIR_PARAM_LIVE},
    {"regen_threshold", IIR_PARAM_FLOAT, offsetof(iir_options, regen_threshold), 0.5, 1e-6, 1, 0,
     NULL, "", "regenerate the whole set when more than this fraction of it dies", IIR_PARAM_LIVE},
    {"refill", IIR_PARAM_BOOL, offsetof(iir_options, refill), 1, 0, 1, 0, NULL, "",
     "replace every VPL removed in its own frame, beyond kmax when more died (their shadow maps at "
     "a quarter of sm_res, rendered again at full in later frames within kmax); false: kmax a "
     "frame",
     IIR_PARAM_LIVE},
};

/* bounces >= 2; kmax 0 only with insert_ms; kmin <= kmax (when > 0) <= vpls, blaming the one the
 * user gave (kmin, then kmax, when both or neither). */
static iir_status iir_check(const void *opts, const iir_params *given, const iir_param **bad,
                            iir_error *err)
{
    const iir_options *o = opts;
    if (o->bounces < 2) {
        *bad = iir_method_any_param("bounces");
        return iir_fail(err, IIR_ERR_INVALID,
                        "bounces: iir keeps VPLs for indirect light, at least one bounce (2); "
                        "for direct light alone use pt or ir with bounces 1");
    }
    if (o->kmax == 0 && o->insert_ms <= 0.f) {
        *bad = &IIR_ROWS[2];
        return iir_fail(err, IIR_ERR_INVALID,
                        "kmax: 0 (no cap) needs insert_ms, the time budget that then decides how "
                        "many VPLs a frame inserts");
    }
    if (o->kmax > 0 && o->kmin > o->kmax) {
        *bad = &IIR_ROWS[iir_params_has(given, "kmin") || !iir_params_has(given, "kmax") ? 1 : 2];
        return iir_fail(err, IIR_ERR_INVALID, "%s: kmin %d must not exceed kmax %d", (*bad)->name,
                        o->kmin, o->kmax);
    }
    if (o->kmax > o->vpls) {
        *bad = &IIR_ROWS[iir_params_has(given, "kmax") || !iir_params_has(given, "vpls") ? 2 : 0];
        return iir_fail(err, IIR_ERR_INVALID, "%s: kmax %d must not exceed vpls %d", (*bad)->name,
                        o->kmax, o->vpls);
    }
    return IIR_OK;
}

static const iir_param_table IIR_TABLE = {"iir: the incremental step", IIR_ROWS,
                                          sizeof IIR_ROWS / sizeof IIR_ROWS[0], iir_check};

typedef struct iir_state {
    const iir_scene *scene;
    const iir_rt *rt;
    iir_options asked;  /* the parameters given */
    iir_options params; /* the ones in use: asked, with the controller's setting when it is on */
    iir_ctl *ctl;       /* target_fps > 0: the frame-time controller; else NULL */
    bool restore;       /* target_fps just went to 0: the next frame brings back the asked set */
    bool maps_all;      /* this frame renders every missing map at sm_res (restoring the set) */
    bool remap;         /* the maps were dropped (another visibility): the next frame is maps_all */
    iir_renderer *renderer;
    iir_vplsets *sets;
    iir_ism_points *ism; /* visibility=ism: the scene's point set, made on first use */
    uint32_t frame;
    iir_refine *refine;
    iir_light lights[IIR_VPLSETS_MAX_LIGHTS]; /* the lights of the frame being refined */
    uint32_t num_lights, drawn;               /* their number; the light whose domain is drawn */
    iir_camera camera;                        /* that frame's camera ... */
    bool have_view;                           /* ... once a frame was rendered */
    iir_vpl *fresh;                           /* [fresh_cap]: refinement's fresh sets */
    uint32_t fresh_n, fresh_cap;
    uint32_t refine_frame; /* the frame being refined: the fresh sets' stream */
    iir_domain_draw dom;
    double insert_cost_ms; /* insert_ms: a running mean of one new VPL's cost with its maps */
    iir_stop_fn stop;      /* a live session's: frames and passes end early when it says so */
    void *stop_ctx;
} iir_state;

static void iir_m_destroy(void *state)
{
    iir_state *s = state;
    if (!s) return;
    iir_renderer_destroy(s->renderer);
    iir_refine_destroy(s->refine);
    iir_vplsets_destroy(s->sets);
    iir_ctl_destroy(s->ctl);
    iir_ism_points_destroy(s->ism);
    free(s->fresh);
    iir_domain_draw_free(&s->dom);
    free(s);
}

/* The step's parameters with k_max VPLs inserted a frame at most (k_min no more than that). */
/* ---- the insertion budget (insert_ms) ---- */

/* VPLs the step may insert this frame: kmax (insert_ms 0), else as many as insert_ms buys at the
 * measured cost of one with its maps, kmax (when > 0) and N the caps; at least one. Before the
 * first measurement: kmax, or 8 without a cap. */
static uint32_t insert_limit(const iir_state *s)
{
    const iir_options *o = &s->params;
    if (o->insert_ms <= 0.f) return (uint32_t)o->kmax;
    double n = s->insert_cost_ms > 0.0 ? floor(o->insert_ms / s->insert_cost_ms)
               : o->kmax > 0           ? o->kmax
                                       : 8;
    if (o->kmax > 0 && n > o->kmax) n = o->kmax;
    if (n > o->vpls) n = o->vpls;
    return n < 1.0 ? 1u : (uint32_t)n;
}

/* One frame's cost of a new VPL into the running mean (weight 1/4: a few frames follow a change of
 * scene or view): the step's insertion time plus the new maps' time, per VPL inserted. The maps
 * counted are at most what the inserted VPLs bring (each itself and its descendants, 1 +
 * descendants / count; null samples none): a frame also builds the maps an interrupted frame left,
 * which are not this frame's cost. */
static void measure_insert_cost(iir_state *s, const iir_incr_stats *is, uint32_t maps,
                                double maps_ms)
{
    const iir_vpl_counts *v = &is->vpl;
    if (v->inserted == 0) return;
    double brought = v->inserted * (1.0 + (v->count ? (double)v->descendants / v->count : 0.0));
    double own = maps > brought ? brought : (double)maps;
    double c = (is->phase_ms[IIR_INCR_INSERT] + (maps ? maps_ms / maps * own : 0.0)) / v->inserted;
    s->insert_cost_ms = s->insert_cost_ms > 0.0 ? 0.75 * s->insert_cost_ms + 0.25 * c : c;
}

/* The step's parameters with k_max VPLs inserted a frame at most and k_min replaced at least (no
 * more than k_max). */
static iir_incr_params incr_params(const iir_options *p, uint32_t k_max, uint32_t k_min)
{
    iir_incr_params ip = iir_incr_params_default();
    ip.target = (uint32_t)p->vpls;
    ip.k_max = k_max;
    ip.k_min = k_min < k_max ? k_min : k_max;
    ip.weights = p->weights;
    ip.regen_threshold = p->regen_threshold;
    ip.seed = p->common.seed;
    ip.refill = p->refill && p->insert_ms <= 0.f;
    return ip;
}

/* VPLs in the sets (every light's), null samples included. */
static uint32_t set_count(iir_state *s)
{
    uint32_t count = 0;
    for (uint32_t k = 0; k < iir_vplsets_lights(s->sets); k++) {
        iir_incr *set = iir_vplsets_set(s->sets, k);
        uint32_t n = 0;
        if (set) iir_incr_vpls(set, &n);
        count += n;
    }
    return count;
}

enum { GROW_FRAMES = 4 }; /* the controller's new N: reached in about this many frames */

/* The step's budgets for the next update (the sets keep their VPLs). With insert_ms: k_max what
 * the budget buys, k_min kmin while the set is full and 0 while it is short of N (the budget goes
 * to refilling it, not to churn; the churn resumes once it is full). With the frame-time controller
 * and a set short of its N: kmax plus a quarter of the shortfall, so that a raised N is reached in
 * GROW_FRAMES frames (the controller does not climb further meanwhile). Right after the controller
 * was turned off (restore): the whole shortfall, so the user's N is back in this frame. */
static void apply_insert_limit(iir_state *s)
{
    bool restore = s->restore;
    s->restore = false;
    s->maps_all = restore || s->remap;
    s->remap = false;
    if (s->params.insert_ms <= 0.f && !s->ctl && !restore) return;
    uint32_t count = set_count(s), N = (uint32_t)s->params.vpls;
    bool short_of_n = count < N;
    uint32_t k_max = insert_limit(s), k_min = (uint32_t)s->params.kmin;
    if (s->params.insert_ms > 0.f && short_of_n) k_min = 0;
    if (restore && short_of_n) {
        k_max += N - count;
        k_min = 0;
    } else if (s->params.insert_ms <= 0.f && short_of_n) {
        k_max += (N - count + GROW_FRAMES - 1) / GROW_FRAMES;
    }
    if (k_max > N) k_max = N;
    iir_incr_params ip = incr_params(&s->params, k_max, k_min);
    iir_error err;
    iir_vplsets_set_params(s->sets, &ip, &err); /* valid by construction */
}

/* ---- the frame-time controller (target_fps; controller.h) ---- */

/* The options in use: the asked ones, with the controller's vpls, interleave and sm_res when it is
 * on (kmin and kmax no more than its N). */
static iir_options controlled(const iir_state *s)
{
    iir_options o = s->asked;
    if (!s->ctl) return o;
    iir_ctl_setting c = iir_ctl_current(s->ctl);
    o.vpls = c.vpls;
    o.vpl.interleave = c.interleave;
    o.vpl.sm_res = c.sm_res;
    if (o.kmax > o.vpls) o.kmax = o.vpls;
    if (o.kmin > o.vpls) o.kmin = o.vpls;
    return o;
}

/* Whether the view differs from the last rendered frame's: a light (of the first
 * IIR_VPLSETS_MAX_LIGHTS) or the camera moved. Only such frames are interactive ones, the
 * controller's samples; a method's first frame (a whole set, the G-buffer) and a re-render of the
 * same view (a parameter change, a new image size) are not. */
static bool view_moved(const iir_state *s, const iir_view *view, uint32_t nl)
{
    return s->have_view &&
           (s->num_lights != nl || memcmp(s->lights, view->lights, nl * sizeof *s->lights) ||
            memcmp(&s->camera, &view->camera, sizeof s->camera));
}

/* After a finished frame: its measurement to the controller when it is interactive, and the next
 * setting in use. The sets keep their VPLs under a new N (they grow by insertions, shrink by
 * deletions of the crowded ones); maps of a new resolution are for new VPLs only (maps_of). */
static void control(iir_state *s, bool interactive, iir_frame_stats *stats)
{
    if (!s->ctl) return;
    iir_ctl_sample m = iir_ctl_sample_of(stats, iir_ctl_current(s->ctl));
    if (interactive && iir_ctl_update(s->ctl, &m)) {
        s->params = controlled(s);
        iir_incr_params ip = incr_params(&s->params, insert_limit(s), (uint32_t)s->params.kmin);
        iir_error err;
        iir_vplsets_set_params(s->sets, &ip, &err); /* valid by construction */
    }
    stats->controlled = true;
    iir_ctl_get_report(s->ctl, &stats->ctl);
}

static iir_status iir_m_create(const iir_scene *scene, const iir_rt *rt, const void *opts,
                               const iir_stop *stop, void **state, iir_error *err)
{
    (void)stop; /* allocations only: nothing here takes long enough to poll */
    const iir_options *params = opts;
    iir_state *s = calloc(1, sizeof *s);
    if (!s) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating iir");
    s->scene = scene;
    s->rt = rt;
    s->asked = *params;
    iir_status st = iir_ctl_follow(&s->ctl, &params->ctl, &params->vpl, params->vpls, err);
    s->params = controlled(s);
    iir_incr_params ip = incr_params(&s->params, insert_limit(s), (uint32_t)s->params.kmin);
    if (st == IIR_OK) st = iir_vplsets_create(scene, rt, &ip, &s->sets, err);
    if (st == IIR_OK) iir_vplsets_set_bounces(s->sets, s->params.bounces);
    s->renderer = st == IIR_OK ? iir_renderer_create(scene, rt) : NULL;
    s->refine = st == IIR_OK ? iir_refine_create() : NULL;
    if (st == IIR_OK && (!s->renderer || !s->refine))
        st = iir_fail(err, IIR_ERR_NOMEM, "out of memory creating iir's renderer");
    if (st == IIR_OK) iir_renderer_follow_specular(s->renderer, IIR_VPL_SPECULAR_DEPTH);
    if (st != IIR_OK) {
        iir_m_destroy(s);
        return st;
    }
    *state = s;
    return IIR_OK;
}

/* The light whose domain is drawn: the one a user moves (iir_lights_moved). */
static uint32_t drawn_light(const iir_light *lights, uint32_t n)
{
    return n > 0 ? iir_lights_moved(lights, n) : 0;
}

static iir_status iir_m_supports(const iir_light *lights, uint32_t num_lights, iir_error *err)
{
    (void)lights;
    if (num_lights > 0) return IIR_OK;
    return iir_fail(err, IIR_ERR_UNSUPPORTED,
                    "iir needs a light (spot, point, sun or area light) to keep VPLs for; the "
                    "scene has none (static emissive triangles have no VPL domain: an emissive "
                    "material becomes a movable area light when the scene's sidecar gives no "
                    "\"lights\" array, docs/scene-format.md section 3)");
}

/* Every light keeps VPLs (up to IIR_VPLSETS_MAX_LIGHTS); the emitters' indirect light is left out
 * (their direct light is rendered). Without lights iir renders nothing (supports). */
static uint32_t iir_m_dropped(const iir_scene *scene, const iir_light *lights, uint32_t num_lights,
                              iir_dropped *out, uint32_t max)
{
    uint32_t n = 0;
    for (uint32_t i = IIR_VPLSETS_MAX_LIGHTS; i < num_lights; i++)
        iir_dropped_add(out, max, &n, "iir", "light", lights[i].name,
                        "light %u: its indirect light is left out, as iir keeps VPLs for %u lights "
                        "at most (its direct light is rendered)",
                        i + 1, IIR_VPLSETS_MAX_LIGHTS);
    if (num_lights == 0) return 0;
    return n + iir_dropped_emitters(scene, "iir", n < max ? out + n : NULL, n < max ? max - n : 0);
}

static void fill_counts(const iir_incr_stats *is, uint32_t maps, iir_vpl_counts *c)
{
    *c = is->vpl;
    c->shadowmaps = maps;
}

/* The maps (exact or ISMs) of v[0..n) that have none, of light k's set; *built = how many. With
 * refill (and not after a regeneration, whose maps are all new) beyond kmax at full resolution
 * the rest are coarse and rendered again later within kmax (iir_smaps_build_budget). */
static iir_status maps_of(iir_state *s, uint32_t k, iir_vpl *v, uint32_t n, int res,
                          bool regenerated, iir_raystats *rays, uint32_t *built, iir_error *err)
{
    *built = 0;
    if (!n) return IIR_OK;
    if (s->params.vpl.visibility == IIR_VIS_SHADOWMAP) {
        const iir_options *o = &s->params;
        *built = o->refill && o->insert_ms <= 0.f && !regenerated && !s->maps_all
                     ? iir_smaps_build_budget(v, n, s->rt, res, (uint32_t)o->kmax, rays, s->stop,
                                              s->stop_ctx)
                     : iir_smaps_build_missing(v, n, s->rt, res, rays, s->stop, s->stop_ctx);
        return IIR_OK;
    }
    return iir_ism_maps_build(&s->ism, s->scene, s->rt, &s->params.ism, s->params.common.seed, k, v,
                              n, s->stop, s->stop_ctx, built, err);
}

/* Shadow maps (exact or ISMs, as visibility says) for every set's new VPLs, on the sets' own
 * arrays (where maps live), until the stop hook says stop; *maps = how many were built. Fails
 * only when ISM's point set cannot be made. */
/* A descendant's shadow map (bounces > 2): half the set's resolution, at least 8. Later bounces
 * carry a fraction of the light and their shadows blur in the sum; on the Cornell orbit at 4
 * bounces the half maps cut the frame by a quarter (the maps and the lookups' cache misses) and
 * leave relMSE and flicker unchanged to 3 digits (docs/experiments.md). */
static int descendant_res(int sm_res)
{
    return sm_res / 2 >= 8 ? sm_res / 2 : sm_res;
}

static iir_status build_maps(iir_state *s, const iir_incr_stats *is, iir_raystats *rays,
                             uint32_t *maps, iir_error *err)
{
    iir_visibility vis = s->params.vpl.visibility;
    iir_status st = IIR_OK;
    *maps = 0;
    for (uint32_t k = 0; vis != IIR_VIS_RAYS && st == IIR_OK && k < iir_vplsets_lights(s->sets);
         k++) {
        iir_incr *set = iir_vplsets_set(s->sets, k);
        uint32_t n = 0, nd = 0, built = 0;
        iir_vpl *v = set ? iir_incr_vpls(set, &n) : NULL;
        iir_vpl *d = iir_vplsets_descendants(s->sets, k, &nd);
        bool regen = is->initial || is->vpl.regenerated;
        int res = s->params.vpl.sm_res;
        st = maps_of(s, k, v, n, res, regen, rays, &built, err);
        *maps += built;
        if (st == IIR_OK) st = maps_of(s, k, d, nd, descendant_res(res), regen, rays, &built, err);
        *maps += built;
    }
    return st;
}

/* A frame's VPL step (run beside its direct light: iir_render_side) and maps: what they did. */
typedef struct frame_step {
    iir_state *s;
    const iir_view *view;
    uint32_t nl;
    bool updated, done; /* the step ran (the frame counts); and the maps too */
    iir_incr_stats is;
    uint32_t maps;
    double step_ms, maps_ms;
    iir_raystats rays;
} frame_step;

/* The side's run, beside the direct light: the VPL sets follow the lights. */
static iir_status step(void *ctx, iir_error *err)
{
    frame_step *f = ctx;
    double t0 = iir_now_ms();
    iir_status st = iir_vplsets_update(f->s->sets, f->view->lights, f->nl, &f->is, err);
    if (st != IIR_OK) return st;
    f->updated = true;
    iir_raystats_add(&f->rays, &f->is.rays);
    f->step_ms = iir_now_ms() - t0;
    return IIR_OK;
}

/* The side's VPLs, after the direct light: the maps of new VPLs built (on every thread), and the
 * VPLs gathered for the renderer. */
static iir_status maps(void *ctx, const iir_vpl **vpls, uint32_t *n, iir_error *err)
{
    frame_step *f = ctx;
    iir_state *s = f->s;
    double t0 = iir_now_ms();
    iir_status st = build_maps(s, &f->is, &f->rays, &f->maps, err);
    if (st != IIR_OK) return st;
    if (s->stop && s->stop(s->stop_ctx)) /* the maps not built are built by the next frame */
        return iir_fail(err, IIR_ERR_INTERRUPTED, "frame stopped early");
    f->maps_ms = iir_now_ms() - t0;
    measure_insert_cost(s, &f->is, f->maps, f->maps_ms);
    *vpls = iir_vplsets_gather(s->sets, n);
    f->done = true;
    return IIR_OK;
}

/* The frame: the VPL step beside the direct light (step), then the new VPLs' maps (maps), the
 * indirect light of the VPLs and the filter. */
static iir_status iir_m_render(void *state, const iir_view *view, iir_image *out,
                               iir_frame_stats *stats, iir_error *err)
{
    iir_state *s = state;
    iir_refine_end(s->refine);
    s->dom.valid = false;
    iir_status st = iir_view_validate(view, err);
    if (st != IIR_OK) return st;
    if (view->num_lights == 0)
        return iir_fail(
            err, IIR_ERR_UNSUPPORTED,
            "iir needs a light (spot, point, sun or area light) to keep VPLs for; this view has "
            "none");
    double t0 = iir_now_ms();
    uint32_t nl =
        view->num_lights < IIR_VPLSETS_MAX_LIGHTS ? view->num_lights : IIR_VPLSETS_MAX_LIGHTS;
    bool interactive = view_moved(s, view, nl);
    apply_insert_limit(s);
    frame_step f = {.s = s, .view = view, .nl = nl};
    iir_render_side side = {step, maps, &f};
    iir_indirect_params ind = s->params.vpl;
    ind.bounces = s->params.bounces;
    iir_render_timing rt;
    iir_render_input in = {.camera = &view->camera,
                           .lights = view->lights,
                           .num_lights = view->num_lights,
                           .seed = iir_frame_direct_seed(s->params.common.seed),
                           .side = &side};
    st = iir_renderer_frame(s->renderer, &in, &ind, out, &rt, &stats->rays, err);
    iir_raystats_add(&stats->rays, &f.rays);
    if (!f.updated) return st; /* the step did not run, or failed: the frame did not happen */
    if (!f.done) return s->frame++, st; /* the maps not built are built by the next frame */
    iir_refine_params rp =
        iir_refine_params_of(&s->params.common, &s->params.vpl, s->params.bounces);
    if (st == IIR_OK)
        st = iir_refine_begin(s->refine, &view->camera, view->lights, view->num_lights, out->width,
                              out->height, &rp, err);
    memcpy(s->lights, view->lights, nl * sizeof *s->lights);
    s->num_lights = nl;
    s->camera = view->camera;
    s->have_view = true;
    s->drawn = drawn_light(view->lights, nl);
    s->refine_frame = s->frame;
    stats->phase_ms[IIR_PHASE_VPLS] = f.step_ms;
    stats->phase_ms[IIR_PHASE_SHADOWMAPS] = f.maps_ms;
    iir_render_timing_to_stats(&rt, stats);
    stats->total_ms = iir_now_ms() - t0;
    fill_counts(&f.is, f.maps, &stats->vpl);
    if (st == IIR_OK) control(s, interactive, stats);
    s->frame++;
    return st;
}

static const iir_vpl *iir_m_vpls(const void *state, uint32_t *n)
{
    const iir_state *s = state;
    return iir_vplsets_gather(s->sets, n);
}

/* ---- refinement ---- */

/* Room in the fresh buffer for every set's target and their descendants. */
static iir_status fresh_room(iir_state *s, iir_error *err)
{
    uint32_t need = 0, per = s->params.bounces > 2 ? (uint32_t)s->params.bounces - 1 : 1;
    for (uint32_t k = 0; k < s->num_lights; k++) need += iir_vplsets_target(s->sets, k) * per;
    if (need <= s->fresh_cap) return IIR_OK;
    iir_vpl *f = realloc(s->fresh, need * sizeof *f);
    if (!f) return iir_fail(err, IIR_ERR_NOMEM, "out of memory for %u fresh VPLs", need);
    s->fresh = f, s->fresh_cap = need;
    return IIR_OK;
}

/* Appends the descendants of the fresh set out[0..m) after it (at most cap VPLs in all), traced
 * from refinement's stream as the kept sets' are from the seed; returns how many. */
static uint32_t fresh_descendants(iir_state *s, uint32_t k, uint64_t stream, iir_vpl *out,
                                  uint32_t m, uint32_t cap, iir_raystats *st)
{
    uint32_t added = 0;
    uint64_t seed = iir_hash3(s->params.common.seed, stream, k);
    for (uint32_t j = 0; s->params.bounces > 2 && j < m; j++)
        added += iir_lineage_trace(s->scene, s->rt, &out[j], s->params.bounces, seed, out[j].birth,
                                   out + m + added, cap - m - added, st);
    return added;
}

/* Sweep 0: the live sets; sweep s: for every light a fresh set sampled as a regeneration would,
 * ids spread as the gathered array spreads them. */
static iir_status refine_vpls(void *ctx, uint32_t sweep, const iir_vpl **vpls, uint32_t *n,
                              iir_raystats *st, iir_error *err)
{
    iir_state *s = ctx;
    if (sweep == 0) {
        *vpls = iir_vplsets_gather(s->sets, n);
        return IIR_OK;
    }
    uint64_t stream = ((uint64_t)s->refine_frame << 32) | sweep;
    iir_status status = fresh_room(s, err);
    s->fresh_n = 0;
    for (uint32_t k = 0; k < s->num_lights && status == IIR_OK; k++) {
        iir_incr *set = iir_vplsets_set(s->sets, k);
        if (!set) continue;
        uint32_t m = 0;
        iir_vpl *out = s->fresh + s->fresh_n;
        status = iir_incr_sample_set(set, &s->lights[k], stream, out, s->fresh_cap - s->fresh_n, &m,
                                     st, err);
        m += fresh_descendants(s, k, stream, out, m, s->fresh_cap - s->fresh_n, st);
        for (uint32_t j = 0; j < m; j++) out[j].id = out[j].id * s->num_lights + k;
        s->fresh_n += m;
    }
    *vpls = s->fresh;
    *n = s->fresh_n;
    return status;
}

static iir_status iir_m_refine(void *state, iir_image *out, iir_frame_stats *stats, iir_error *err)
{
    iir_state *s = state;
    iir_refine_stats rs;
    iir_status st = iir_refine_pass(s->refine, s->renderer, refine_vpls, s, out, &rs, err);
    iir_refine_to_stats(&rs, stats);
    return st;
}

/* ---- the domain, for drawing ---- */

/* The domain of the light a user moves (drawn_light), with its own set's ids (domain_draw.h). */
static bool build_domain(iir_state *s, iir_domain_draw *b)
{
    iir_incr *set = iir_vplsets_set(s->sets, s->drawn);
    iir_light_domain d;
    iir_error err;
    if (!set || iir_light_domain_make(&s->lights[s->drawn], &d, &err) != IIR_OK) return false;
    const char *map = d.map == IIR_MAP_SPHERE ? "sphere (equal-area)" : iir_domain_map_name(d.map);
    return iir_domain_draw_build(b, set, map);
}

static bool iir_m_domain(void *state, iir_domain *out)
{
    iir_state *s = state;
    if (!s->dom.valid) s->dom.valid = build_domain(s, &s->dom);
    if (s->dom.valid) *out = s->dom.d;
    return s->dom.valid;
}

static void iir_m_set_stop(void *state, iir_stop_fn fn, void *ctx)
{
    iir_state *s = state;
    s->stop = fn;
    s->stop_ctx = ctx;
    iir_renderer_set_stop(s->renderer, fn, ctx);
}

/* Drops every map but those of resolution keep (0: every one), so the next frame builds them anew
 * (exact maps and ISMs may share a res). */
static void release_maps(iir_state *s, int keep)
{
    for (uint32_t k = 0; k < iir_vplsets_lights(s->sets); k++) {
        iir_incr *set = iir_vplsets_set(s->sets, k);
        uint32_t n = 0;
        iir_vpl *v = set ? iir_incr_vpls(set, &n) : NULL;
        for (uint32_t i = 0; i < n; i++)
            if (v[i].smap.res != keep) iir_smap_release(&v[i].smap);
        v = iir_vplsets_descendants(s->sets, k, &n);
        for (uint32_t i = 0; i < n; i++)
            if (v[i].smap.res != keep) iir_smap_release(&v[i].smap);
    }
}

/* Only IIR_PARAM_LIVE rows changed: the step's budgets, weights and threshold go to the step; a
 * change of visibility to or from ism drops the maps of the other kind. target_fps going to 0
 * brings the asked settings back at once: the next frame fills the set to vpls (restore) and
 * rebuilds the maps the controller made coarser. */
static void iir_m_update(void *state, const void *opts)
{
    iir_state *s = state;
    iir_visibility was = s->params.vpl.visibility;
    bool controlled_before = s->ctl != NULL;
    s->asked = *(const iir_options *)opts;
    iir_error err;
    if (iir_ctl_follow(&s->ctl, &s->asked.ctl, &s->asked.vpl, s->params.vpls, &err) != IIR_OK) {
        iir_ctl_destroy(s->ctl); /* out of memory: the fixed settings */
        s->ctl = NULL;
    }
    s->params = controlled(s);
    if (controlled_before && !s->ctl) {
        s->restore = true;
        if (s->params.vpl.visibility == IIR_VIS_SHADOWMAP) release_maps(s, s->params.vpl.sm_res);
    }
    if (was != s->params.vpl.visibility &&
        (was == IIR_VIS_ISM || s->params.vpl.visibility == IIR_VIS_ISM)) {
        release_maps(s, 0);
        s->remap = true;
    }
    iir_incr_params ip = incr_params(&s->params, insert_limit(s), (uint32_t)s->params.kmin);
    iir_vplsets_set_params(s->sets, &ip, &err); /* valid once bound (N: the sets follow it) */
    iir_vplsets_set_bounces(s->sets, s->params.bounces); /* new: descendants traced anew */
}

/* The set, the step's triangulation, graph and surface weights' pattern, refinement's fresh sets.
 */
static uint64_t iir_m_memory(const void *opts, int width, int height)
{
    const iir_options *o = opts;
    uint64_t N = (uint64_t)iir_ctl_vpls_bound(&o->ctl, o->vpls);
    uint64_t n = N * (uint64_t)(o->bounces > 2 ? o->bounces - 1 : 1);
    return iir_vpl_memory(&o->vpl, (uint32_t)n, width, height) +
           iir_gv_memory(&o->vpl, (uint32_t)n, width, height) + n * sizeof(iir_vpl) +
           iir_incr_memory((uint32_t)n) + iir_ism_memory(&o->ism, o->vpl.visibility, (uint32_t)n);
}

const iir_method_ops iir_method_iir = {
    .full_surfaces = true,
    .name = "iir",
    .summary = "incremental instant radiosity: VPLs kept across frames, few replaced per frame",
    .tables = {{&iir_bounces_table, offsetof(iir_options, bounces)}, /* bound before iir_check */
               {&IIR_TABLE, 0},
               {&iir_vis_table, offsetof(iir_options, vpl)},
               {&iir_vpl_table, offsetof(iir_options, vpl)},
               {&iir_ism_table, offsetof(iir_options, ism)},
               {&iir_clamp_table, offsetof(iir_options, vpl.clamp)},
               {&iir_shading_table, offsetof(iir_options, vpl.shading)},
               {&iir_clamp_comp_table, offsetof(iir_options, vpl)}, /* after shading */
               {&iir_multires_table, offsetof(iir_options, vpl.mr)},
               {&iir_ctl_table, offsetof(iir_options, ctl)},
               {&iir_common_table, offsetof(iir_options, common)}},
    .opts_size = sizeof(iir_options),
    .create = iir_m_create,
    .destroy = iir_m_destroy,
    .render = iir_m_render,
    .refine = iir_m_refine,
    .vpls = iir_m_vpls,
    .domain = iir_m_domain,
    .set_stop = iir_m_set_stop,
    .update = iir_m_update,
    .supports = iir_m_supports,
    .memory = iir_m_memory,
    .dropped = iir_m_dropped,
    .phases = IIR_VPL_PHASES,
};

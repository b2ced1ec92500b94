/* ir.c -- instant radiosity (Keller 1997), method "ir": every frame, N light paths leave the
 * lights (chosen by flux), and every diffuse vertex of a path becomes a VPL carrying the flux it
 * reflects; paths end by Russian roulette or after `bounces - 1` VPL vertices (so bounces = 2 is
 * one-bounce indirect light, like iir). All VPLs are new each frame, so all their shadow maps are
 * rendered each frame: this is the baseline the incremental method must beat.
 * Parameters: its own table below, the VPL shading's (vpl_options.c), the ISMs' (ism_options.c,
 * for visibility=ism: an imperfect shadow map per VPL instead) and every method's.
 *
 * The first two dimensions of path i (the point on the spot's disk, the point light's sphere or
 * the sun's disk of origins: iir_light_sample_emission) are the Halton point i in bases 2 and 3,
 * rotated by a per-frame offset (Cranley-Patterson): the same offset every frame when same_random
 * is set, a new one every frame otherwise. Later dimensions come from PCG streams.
 *
 * Refinement (refine.h; refine_passes, jitter, interleave, clamp): sweep 0 shades the frame's
 * own paths, sweep s >= 1 a second list of N paths traced with the frame seed hashed with s (new
 * random numbers, same count), so the frame's list and the frame counter stay untouched.
 */
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "../vpls/light_path.h"
#include "../vpls/vpl_lobe.h"
#include "iir/method.h"
#include "iir/ism.h"
#include "iir/refine.h"
#include "iir/rng.h"
#include "iir/scene.h"
#include "iir/shadowmap.h"
#include "method_internal.h"
#include "sampling.h"
#include "surface.h"
#include "iir/timer.h"

/* A list of VPLs from N light paths; grows, never shrinks. */
typedef struct vpl_list {
    iir_vpl *v;
    uint32_t n, cap;
    uint32_t escaped; /* paths that left no VPL */
    uint32_t next_id; /* the id of the next VPL */
} vpl_list;

/* ---- parameters ---- */

typedef iir_ir_options ir_options; /* method_internal.h: the ism method binds it too */

static const iir_param IR_ROWS[] = {
    {"vpls", IIR_PARAM_INT, offsetof(ir_options, vpls), 256, 1, 16384, 4096, NULL, "paths",
     "light paths per frame (each diffuse vertex a VPL)", IIR_PARAM_RESTART},
    {"same_random", IIR_PARAM_BOOL, offsetof(ir_options, same_random), 0, 0, 1, 0, NULL, "",
     "the same random numbers every frame (default: fresh ones)", IIR_PARAM_RESTART},
};
static const iir_param_table IR_TABLE = {"ir: light paths", IR_ROWS,
                                         sizeof IR_ROWS / sizeof IR_ROWS[0], NULL};

typedef struct ir_state {
    const iir_scene *scene;
    const iir_rt *rt;
    ir_options params;
    iir_renderer *renderer;
    vpl_list live;          /* the frame's VPLs (with shadow maps) */
    iir_ism_points *ism;    /* visibility=ism: the scene's point set, made on first use */
    vpl_list fresh;         /* refinement: the current sweep's VPLs (no maps) */
    uint64_t seed_rendered; /* the frame seed of the last frame */
    uint32_t frame;
    float *light_pmf; /* per view light, rebuilt each frame; grows with the light count */
    uint32_t pmf_cap;
    iir_refine *refine;
    iir_stop_fn stop; /* a live session's: frames and passes end early when it says so */
    void *stop_ctx;
} ir_state;

/* ---- light paths ---- */

static bool push_vpl(vpl_list *l, const iir_vpl *v)
{
    if (l->n == l->cap) {
        uint32_t cap = l->cap ? 2 * l->cap : 256;
        iir_vpl *grown = realloc(l->v, sizeof(iir_vpl) * cap);
        if (!grown) return false;
        l->v = grown;
        l->cap = cap;
    }
    l->v[l->n++] = *v;
    return true;
}

static void clear_list(vpl_list *l)
{
    for (uint32_t i = 0; i < l->n; i++) iir_smap_release(&l->v[i].smap);
    l->n = 0;
    l->escaped = 0;
}

/* Each light's share of the total flux (luminance), computed once per frame: a smooth-edged
 * spot's flux is a numeric integral. pmf[i] = 0 for all lights when none emits. */
static void light_pmf(const iir_light *lights, uint32_t num_lights, float *pmf)
{
    float total = 0.f;
    for (uint32_t i = 0; i < num_lights; i++) {
        pmf[i] = iir_luminance(iir_light_flux(&lights[i]));
        total += pmf[i];
    }
    for (uint32_t i = 0; i < num_lights; i++) pmf[i] = total > 0.f ? pmf[i] / total : 0.f;
}

/* Chooses a light with probability pmf[i]; returns its index and pmf. */
static uint32_t pick_light(const float *pmf, uint32_t n, float u, float *p)
{
    float acc = 0.f;
    for (uint32_t i = 0; i < n; i++) {
        acc += pmf[i];
        if (u < acc || i + 1 == n) {
            *p = pmf[i];
            return i;
        }
    }
    *p = 0.f;
    return 0;
}

static iir_vec2 halton2(uint32_t i, iir_vec2 shift)
{
    float a = iir_radical_inverse(2, i) + shift.x, b = iir_radical_inverse(3, i) + shift.y;
    return iir_v2(a - floorf(a), b - floorf(b));
}

/* One light path: a VPL at each reflecting vertex, appended to l; false when out of memory. */
static bool trace_path(ir_state *ir, vpl_list *l, const iir_light *light, iir_vec3 beta, iir_vec2 u,
                       iir_rng *rng, iir_raystats *st)
{
    iir_light_ray lr = iir_light_sample_emission(light, u);
    iir_ray ray = iir_make_ray(lr.origin, lr.dir, 0.f, INFINITY);
    beta = iir_mul(beta, lr.beta); /* flux arriving at the next vertex */
    float eps = iir_rt_epsilon(ir->rt);
    for (int vertex = 1; vertex < ir->params.bounces; vertex++) {
        iir_hit hit;
        if (iir_is_black(beta) || !iir_rt_intersect(ir->rt, &ray, &hit, st, IIR_RAYS_VPL)) break;
        iir_surface sf = iir_surface_at(ir->scene, &hit, iir_neg(ray.dir));
        if (!iir_is_black(sf.Le)) break; /* emitters absorb light paths */
        iir_vpl v = {.id = l->next_id++,
                     .position = sf.p,
                     .wi = iir_neg(ray.dir),
                     .birth = ir->frame,
                     .generation = (uint8_t)(vertex - 1 < 255 ? vertex - 1 : 255)};
        v.lobe = iir_vpl_lobe_at(&sf, &v.albedo);
        v.flux = iir_mul(beta, v.albedo);
        iir_vpl_set_normal(&v, sf.ns);
        if (!push_vpl(l, &v)) return false;
        iir_light_step step;
        if (!iir_light_path_continue(&v, eps, rng, &step)) break;
        ray = step.ray;
        beta = iir_mul(v.flux, step.weight);
    }
    return true;
}

/* Replaces l by the VPLs of N light paths from `lights`, all randomness from frame_seed. */
static iir_status generate_vpls(ir_state *ir, vpl_list *l, const iir_light *lights,
                                uint32_t num_lights, uint64_t frame_seed, iir_raystats *st,
                                iir_error *err)
{
    clear_list(l);
    if (num_lights == 0) return IIR_OK;
    if (num_lights > ir->pmf_cap) {
        float *grown = realloc(ir->light_pmf, sizeof(float) * num_lights);
        if (!grown) return iir_fail(err, IIR_ERR_NOMEM, "ir: out of memory for the lights");
        ir->light_pmf = grown;
        ir->pmf_cap = num_lights;
    }
    light_pmf(lights, num_lights, ir->light_pmf);
    iir_rng shift_rng = iir_rng_make(frame_seed, UINT64_MAX);
    iir_vec2 shift = iir_rng_uniform2(&shift_rng);
    uint32_t n = (uint32_t)ir->params.vpls;
    for (uint32_t i = 0; i < n; i++) {
        iir_rng rng = iir_rng_make(frame_seed, i);
        float pmf;
        uint32_t k = pick_light(ir->light_pmf, num_lights, iir_rng_uniform(&rng), &pmf);
        const iir_light *light = &lights[k];
        if (pmf <= 0.f) continue;
        uint32_t before = l->n;
        if (!trace_path(ir, l, light, iir_v3s(1.f / ((float)n * pmf)), halton2(i, shift), &rng, st))
            return iir_fail(err, IIR_ERR_NOMEM, "ir: out of memory for VPLs");
        l->escaped += l->n == before;
    }
    return IIR_OK;
}

/* ---- the method interface ---- */

static iir_status ir_create(const iir_scene *scene, const iir_rt *rt, const void *opts,
                            const iir_stop *stop, void **state, iir_error *err)
{
    (void)stop; /* allocations only: nothing here takes long enough to poll */
    ir_state *ir = calloc(1, sizeof *ir);
    if (!ir) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating ir");
    ir->scene = scene;
    ir->rt = rt;
    ir->params = *(const ir_options *)opts;
    ir->renderer = iir_renderer_create(scene, rt);
    ir->refine = iir_refine_create();
    if (!ir->renderer || !ir->refine) {
        iir_renderer_destroy(ir->renderer);
        iir_refine_destroy(ir->refine);
        free(ir);
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating ir's renderer");
    }
    iir_renderer_follow_specular(ir->renderer, IIR_VPL_SPECULAR_DEPTH);
    *state = ir;
    return IIR_OK;
}

static void ir_destroy(void *state)
{
    ir_state *ir = state;
    if (!ir) return;
    clear_list(&ir->live);
    clear_list(&ir->fresh);
    iir_ism_points_destroy(ir->ism);
    free(ir->live.v);
    free(ir->fresh.v);
    free(ir->light_pmf);
    iir_renderer_destroy(ir->renderer);
    iir_refine_destroy(ir->refine);
    free(ir);
}

static void fill_counts(const ir_state *ir, uint32_t maps, iir_vpl_counts *c)
{
    c->count = ir->live.n;
    c->valid = 0;
    c->inserted = ir->live.n;
    c->null_samples = ir->live.escaped;
    c->regenerated = 1;
    c->shadowmaps = maps;
}

static iir_status ir_render(void *state, const iir_view *view, iir_image *out,
                            iir_frame_stats *stats, iir_error *err)
{
    ir_state *ir = state;
    iir_refine_end(ir->refine);
    iir_status st = iir_view_validate(view, err);
    if (st != IIR_OK) return st;
    double t0 = iir_now_ms();
    uint64_t seed = ir->params.common.seed;
    ir->seed_rendered =
        ir->params.same_random ? iir_hash3(seed, 0, 0x1f) : iir_hash3(seed, ir->frame, 0x1f);
    st = generate_vpls(ir, &ir->live, view->lights, view->num_lights, ir->seed_rendered,
                       &stats->rays, err);
    if (st != IIR_OK) return st;
    double t1 = iir_now_ms();
    uint32_t maps = 0;
    if (ir->params.vpl.visibility == IIR_VIS_SHADOWMAP)
        maps = iir_smaps_build_until(ir->live.v, ir->live.n, ir->rt, ir->params.vpl.sm_res,
                                     &stats->rays, ir->stop, ir->stop_ctx);
    else if (ir->params.vpl.visibility == IIR_VIS_ISM)
        st = iir_ism_maps_build(&ir->ism, ir->scene, ir->rt, &ir->params.ism, seed, 0, ir->live.v,
                                ir->live.n, ir->stop, ir->stop_ctx, &maps, err);
    if (st != IIR_OK) return ir->frame++, st;
    if (ir->stop && ir->stop(ir->stop_ctx))
        return ir->frame++, iir_fail(err, IIR_ERR_INTERRUPTED, "frame stopped early");
    double t2 = iir_now_ms();
    iir_indirect_params ind = ir->params.vpl;
    ind.bounces = ir->params.bounces;
    iir_render_timing rt;
    iir_render_input in = {.camera = &view->camera,
                           .lights = view->lights,
                           .num_lights = view->num_lights,
                           .vpls = ir->live.v,
                           .num_vpls = ir->live.n,
                           .seed = iir_frame_direct_seed(seed)};
    st = iir_renderer_frame(ir->renderer, &in, &ind, out, &rt, &stats->rays, err);
    iir_refine_params rp =
        iir_refine_params_of(&ir->params.common, &ir->params.vpl, ir->params.bounces);
    if (st == IIR_OK)
        st = iir_refine_begin(ir->refine, &view->camera, view->lights, view->num_lights, out->width,
                              out->height, &rp, err);
    stats->phase_ms[IIR_PHASE_VPLS] = t1 - t0;
    stats->phase_ms[IIR_PHASE_SHADOWMAPS] = t2 - t1;
    iir_render_timing_to_stats(&rt, stats);
    stats->total_ms = iir_now_ms() - t0;
    fill_counts(ir, maps, &stats->vpl);
    ir->frame++;
    return st;
}

static const iir_vpl *ir_vpls(const void *state, uint32_t *n)
{
    const ir_state *ir = state;
    *n = ir->live.n;
    return ir->live.v;
}

/* ---- refinement ---- */

/* Sweep 0: the frame's paths; sweep s: N new paths from the frame seed hashed with s. */
static iir_status refine_vpls(void *ctx, uint32_t sweep, const iir_vpl **vpls, uint32_t *n,
                              iir_raystats *st, iir_error *err)
{
    ir_state *ir = ctx;
    vpl_list *l = &ir->live;
    if (sweep > 0) {
        uint32_t num_lights;
        const iir_light *lights = iir_refine_lights(ir->refine, &num_lights);
        l = &ir->fresh;
        l->next_id = 0;
        iir_status s = generate_vpls(ir, l, lights, num_lights,
                                     iir_hash3(ir->seed_rendered, sweep, 0x3e), st, err);
        if (s != IIR_OK) return s;
    }
    *vpls = l->v;
    *n = l->n;
    return IIR_OK;
}

static iir_status ir_refine(void *state, iir_image *out, iir_frame_stats *stats, iir_error *err)
{
    ir_state *ir = state;
    iir_refine_stats rs;
    iir_status st = iir_refine_pass(ir->refine, ir->renderer, refine_vpls, ir, out, &rs, err);
    iir_refine_to_stats(&rs, stats);
    return st;
}

static void ir_set_stop(void *state, iir_stop_fn fn, void *ctx)
{
    ir_state *ir = state;
    ir->stop = fn;
    ir->stop_ctx = ctx;
    iir_renderer_set_stop(ir->renderer, fn, ctx);
}

static void ir_update(void *state, const void *opts)
{
    ((ir_state *)state)->params = *(const ir_options *)opts;
}

/* About one VPL per path and bounce (Russian roulette ends many sooner). */
static uint64_t ir_memory(const void *opts, int width, int height)
{
    const ir_options *o = opts;
    uint32_t n = (uint32_t)o->vpls * (uint32_t)(o->bounces > 1 ? o->bounces - 1 : 0);
    return iir_vpl_memory(&o->vpl, n, width, height) +
           iir_ism_memory(&o->ism, o->vpl.visibility, n);
}

/* ir's light paths leave the punctual lights only: emitters' indirect light is left out. */
static uint32_t ir_dropped(const iir_scene *scene, const iir_light *lights, uint32_t num_lights,
                           iir_dropped *out, uint32_t max)
{
    (void)lights, (void)num_lights;
    return iir_dropped_emitters(scene, "ir", out, max);
}

const iir_method_ops iir_method_ir = {
    .full_surfaces = true,
    .name = "ir",
    .summary = "instant radiosity: VPLs from light paths, regenerated every frame",
    .tables = {{&iir_bounces_table, offsetof(ir_options, bounces)}, /* first, as iir's */
               {&IR_TABLE, 0},
               {&iir_vis_table, offsetof(ir_options, vpl)},
               {&iir_vpl_table, offsetof(ir_options, vpl)},
               {&iir_ism_table, offsetof(ir_options, ism)},
               {&iir_clamp_table, offsetof(ir_options, vpl.clamp)},
               {&iir_shading_table, offsetof(ir_options, vpl.shading)},
               {&iir_clamp_comp_table, offsetof(ir_options, vpl)}, /* after shading */
               {&iir_multires_table, offsetof(ir_options, vpl.mr)},
               {&iir_common_table, offsetof(ir_options, common)}},
    .opts_size = sizeof(ir_options),
    .create = ir_create,
    .destroy = ir_destroy,
    .render = ir_render,
    .refine = ir_refine,
    .vpls = ir_vpls,
    .domain = NULL,
    .set_stop = ir_set_stop,
    .update = ir_update,
    .memory = ir_memory,
    .dropped = ir_dropped,
    .phases = IIR_VPL_PHASES,
};

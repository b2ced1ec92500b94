/* render.c -- the VPL renderer object (create/destroy, scratch ownership), its parameters and the
 * order of one frame's (and one refinement pass's) phases; not the phases themselves
 * (render_gbuffer.c, render_direct.c, render_indirect.c, render_filter.c). */
#include <stdlib.h>
#include <string.h>

#include "gv_columns.h"
#include "render_internal.h"
#include "iir/timer.h"

/* ---- parameters ---- */

iir_status iir_indirect_params_validate(const iir_indirect_params *p, iir_error *err)
{
    if (p->visibility != IIR_VIS_SHADOWMAP && p->visibility != IIR_VIS_RAYS &&
        p->visibility != IIR_VIS_ISM)
        return iir_fail(err, IIR_ERR_INVALID,
                        "indirect visibility %d is not shadowmap, rays or ism", (int)p->visibility);
    if (p->interleave < 1 || p->interleave > IIR_MAX_INTERLEAVE)
        return iir_fail(err, IIR_ERR_INVALID, "indirect interleave %d is outside [1, %d]",
                        p->interleave, IIR_MAX_INTERLEAVE);
    if (!(p->clamp >= 0.f) || isinf(p->clamp))
        return iir_fail(err, IIR_ERR_INVALID, "indirect clamp %g must be finite and >= 0",
                        (double)p->clamp);
    if (!(p->sm_bias >= 0.f && p->sm_bias <= 1.f))
        return iir_fail(err, IIR_ERR_INVALID, "indirect sm_bias %g is outside [0, 1]",
                        (double)p->sm_bias);
    if (p->clamp_comp < IIR_CLAMP_COMP_OFF || p->clamp_comp > IIR_CLAMP_COMP_INTERLEAVED)
        return iir_fail(err, IIR_ERR_INVALID,
                        "indirect clamp_comp %d is not off, full or interleaved",
                        (int)p->clamp_comp);
    if (p->clamp_comp != IIR_CLAMP_COMP_OFF && p->shading == IIR_SHADING_MULTIRES)
        return iir_fail(err, IIR_ERR_INVALID,
                        "clamp compensation needs shading full (multires has no per-pixel "
                        "indirect light to add it to)");
    if (p->area_samples < 1 || p->area_samples > IIR_MAX_AREA_SAMPLES)
        return iir_fail(err, IIR_ERR_INVALID, "indirect area_samples %d is outside [1, %d]",
                        p->area_samples, IIR_MAX_AREA_SAMPLES);
    if (p->shading != IIR_SHADING_FULL && p->shading != IIR_SHADING_MULTIRES)
        return iir_fail(err, IIR_ERR_INVALID, "indirect shading %d is neither full nor multires",
                        (int)p->shading);
    if (p->shading == IIR_SHADING_MULTIRES)
        return iir_mr_params_validate(&p->mr, p->interleave, err);
    return IIR_OK;
}

/* ---- the renderer ---- */

iir_renderer *iir_renderer_create(const iir_scene *scene, const iir_rt *rt)
{
    iir_renderer *r = calloc(1, sizeof *r);
    if (!r) return NULL;
    r->scene = scene;
    r->rt = rt;
    r->eps = iir_rt_epsilon(rt);
    r->diag2 = iir_length_sq(iir_sub(scene->bounds_max, scene->bounds_min));
    r->isa = iir_isa_default();
    iir_lightset *set = iir_lightset_create(scene, NULL, 0);
    if (!set) {
        free(r);
        return NULL;
    }
    if (iir_lightset_has_area_lights(set))
        r->area_lights = set;
    else
        iir_lightset_destroy(set);
    return r;
}

iir_isa iir_renderer_set_isa(iir_renderer *r, iir_isa isa)
{
    if (iir_isa_supported(isa)) r->isa = isa;
    return r->isa;
}

void iir_renderer_destroy(iir_renderer *r)
{
    if (!r) return;
    iir_lightset_destroy(r->area_lights);
    iir_lightset_destroy(r->comp_lights);
    iir_multires_destroy(r->mr);
    light_tree_free(&r->dtree);
    iir_gbuffer_free(&r->gb);
    free(r->raw);
    free(r->rows);
    free(r->near_fine);
    free(r->fmask);
    free(r->vpl);
    iir_gv_free(r->gv);
    iir_gv_free(r->gv_mr);
    free(r);
}

const iir_gbuffer *iir_renderer_gbuffer(const iir_renderer *r)
{
    return &r->gb;
}

void iir_renderer_follow_specular(iir_renderer *r, int depth)
{
    if (r->specular_depth != depth) r->gb_valid = false;
    r->specular_depth = depth < 0 ? 0 : depth;
}

/* ---- one frame ---- */

static bool same_camera(const iir_camera *a, const iir_camera *b)
{
    return a->position.x == b->position.x && a->position.y == b->position.y &&
           a->position.z == b->position.z && a->target.x == b->target.x &&
           a->target.y == b->target.y && a->target.z == b->target.z && a->up.x == b->up.x &&
           a->up.y == b->up.y && a->up.z == b->up.z && a->fov_y == b->fov_y;
}

static iir_status check_inputs(const iir_camera *cam, const iir_light *lights, uint32_t num_lights,
                               const iir_indirect_params *p, const iir_image *out, iir_error *err)
{
    if (out->width < 1 || out->height < 1 || out->width > IIR_IMAGE_MAX_DIM ||
        out->height > IIR_IMAGE_MAX_DIM)
        return iir_fail(err, IIR_ERR_INVALID, "frame size %dx%d is outside [1, %d]", out->width,
                        out->height, IIR_IMAGE_MAX_DIM);
    iir_status s = iir_camera_validate(cam, err);
    for (uint32_t i = 0; s == IIR_OK && i < num_lights; i++)
        s = iir_light_validate(&lights[i], err);
    return s == IIR_OK ? iir_indirect_params_validate(p, err) : s;
}

uint64_t iir_renderer_memory(int width, int height)
{
    const iir_gbuffer *g = NULL;
    uint64_t gbuffer =
        7 * sizeof *g->position + sizeof *g->mr + 2 * sizeof *g->depth + sizeof *g->prim;
    uint64_t scratch = sizeof(iir_vec3) + sizeof(iir_filter_row) + sizeof(uint32_t);
    uint64_t px = (uint64_t)width * (uint64_t)height;
    return px * (gbuffer + scratch) + (uint64_t)iir_tile_count(width, height, IIR_RENDER_TILE);
}

/* Sizes the G-buffer and the per-pixel scratch for a w x h frame (only when the size changed). On
 * failure everything is freed (width 0), so the next frame tries again. */
static iir_status resize(iir_renderer *r, int w, int h, iir_error *err)
{
    if (r->gb.width == w && r->gb.height == h) return IIR_OK;
    r->gb_valid = false;
    free(r->raw);
    free(r->rows);
    free(r->near_fine);
    free(r->fmask);
    r->raw = malloc(sizeof(iir_vec3) * (size_t)w * (size_t)h);
    r->rows = malloc(sizeof(iir_filter_row) * (size_t)w * (size_t)h);
    r->near_fine = malloc((size_t)iir_tile_count(w, h, IIR_RENDER_TILE));
    r->near_fine_gen = 0;
    r->bg_serial = 0;
    r->fmask = malloc(sizeof(uint32_t) * (size_t)w * (size_t)h);
    r->fmask_serial = 0;
    iir_status s = iir_gbuffer_resize(&r->gb, w, h, err);
    if (s == IIR_OK && (!r->raw || !r->rows || !r->near_fine || !r->fmask)) {
        iir_gbuffer_free(&r->gb);
        s = iir_fail(err, IIR_ERR_NOMEM, "out of memory for a %dx%d frame", w, h);
    }
    return s;
}

/* Renders the G-buffer unless the camera and size are those of the last one. */
static iir_status gbuffer_phase(iir_renderer *r, const iir_camera *cam, int w, int h,
                                iir_render_timing *t, iir_raystats *st, iir_error *err)
{
    double t0 = iir_now_ms();
    iir_status s = resize(r, w, h, err);
    if (s != IIR_OK) return s;
    t->gbuffer_cached = r->gb_valid && same_camera(cam, &r->gb_camera);
    if (!t->gbuffer_cached) {
        iir_camera_frame cf = iir_camera_setup(cam, w, h);
        const iir_stop stop = {r->stop, r->stop_ctx};
        r->gb_serial++;
        if (!iir_gbuffer_render(&r->gb, r->scene, r->rt, &cf, iir_v2(0.5f, 0.5f), r->specular_depth,
                                &stop, st)) {
            r->gb_valid = false;
            return iir_fail(err, IIR_ERR_INTERRUPTED, "frame stopped early");
        }
        r->gb_camera = *cam;
        r->gb_shift = iir_v2(0.f, 0.f);
        r->gb_valid = true;
    }
    t->gbuffer_ms = iir_now_ms() - t0;
    return IIR_OK;
}

void iir_side_go(iir_side_run *sr)
{
    double t0 = iir_now_ms();
    sr->status = sr->side->run(sr->side->ctx, &sr->err);
    sr->ms = iir_now_ms() - t0;
#pragma omp atomic write
    sr->failed = sr->status != IIR_OK;
}

bool iir_side_failed(const iir_side_run *sr)
{
    bool failed;
#pragma omp atomic read
    failed = sr->failed;
    return failed;
}

/* After the direct light: the side's status (its error into err), then its VPLs and their
 * subsets. */
static iir_status side_vpls(iir_renderer *r, const iir_side_run *sr, const iir_indirect_params *p,
                            iir_error *err)
{
    if (sr->status != IIR_OK) {
        if (err) *err = sr->err;
        return sr->status;
    }
    const iir_vpl *vpls = NULL;
    uint32_t n = 0;
    iir_status s = sr->side->vpls(sr->side->ctx, &vpls, &n, err);
    return s == IIR_OK ? iir_render_subsets(r, vpls, n, p, false, err) : s;
}

/* The shading phases on the current G-buffer, timed into tm, rays added to rays: direct light
 * (with the side beside it, then its VPLs' subsets), indirect light from the VPL subsets and the
 * clamp's compensation (timed as indirect), then the filter into job->out. Returns the side's
 * error, or IIR_ERR_INTERRUPTED when a phase stopped early at r->stop's request (out is then
 * incomplete). */
static iir_status shade(iir_renderer *r, const iir_shade_job *job, iir_side_run *side,
                        iir_render_timing *tm, iir_raystats *rays, iir_error *err)
{
    double t0 = iir_now_ms();
    bool stopped = iir_render_direct(r, job, side->side ? side : NULL, rays);
    double direct_ms = iir_now_ms() - t0;
    if (side->side) {
        iir_status s = side_vpls(r, side, job->p, err);
        if (s != IIR_OK) return s;
    }
    double t1 = iir_now_ms();
    if (!stopped && r->level)
        stopped =
            iir_render_indirect_coarse(r, job->p, true, rays, &tm->vpl_evals, &tm->vpl_reused);
    else if (!stopped)
        stopped =
            iir_render_indirect(r, job->p, job->shift, true, rays, &tm->vpl_evals, &tm->vpl_reused);
    if (!stopped && r->comp_lights) stopped = iir_render_compensate(r, job, rays);
    double t2 = iir_now_ms();
    if (!stopped) iir_render_filter(r, job->p, job->out);
    tm->side_ms = side->ms;
    tm->direct_ms = direct_ms > side->ms ? direct_ms - side->ms : 0.0;
    tm->indirect_ms = t2 - t1;
    tm->filter_ms = iir_now_ms() - t2;
    return stopped ? iir_fail(err, IIR_ERR_INTERRUPTED, "frame stopped early") : IIR_OK;
}

/* Multires: builds (or keeps) the hierarchy of the current G-buffer and sets r->level; full
 * shading clears it. Timed into t->indirect_ms (shade adds the shading to it). */
static iir_status multires_phase(iir_renderer *r, const iir_indirect_params *p,
                                 iir_render_timing *t, iir_error *err)
{
    r->level = NULL;
    if (p->shading != IIR_SHADING_MULTIRES) return IIR_OK;
    double t0 = iir_now_ms();
    if (!r->mr && !(r->mr = iir_multires_create()))
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for the multires hierarchy");
    iir_status s = iir_multires_build(r->mr, &r->gb, r->gb_serial, &p->mr, p->interleave, err);
    if (s == IIR_OK) r->level = iir_multires_levels(r->mr);
    t->indirect_ms = iir_now_ms() - t0;
    return s;
}

/* Clamp compensation samples the frame's lights at the points its rays hit: their light set,
 * rebuilt every frame (lights move), or none when compensation is off. */
static iir_status compensation_phase(iir_renderer *r, const iir_render_input *in,
                                     const iir_indirect_params *p, iir_error *err)
{
    iir_lightset_destroy(r->comp_lights);
    r->comp_lights = NULL;
    if (p->clamp_comp == IIR_CLAMP_COMP_OFF || p->clamp <= 0.f) return IIR_OK;
    r->comp_lights = iir_lightset_create(r->scene, in->lights, in->num_lights);
    return r->comp_lights
               ? IIR_OK
               : iir_fail(err, IIR_ERR_NOMEM, "out of memory for the clamp compensation");
}

static bool stop_requested(const iir_renderer *r)
{
    return r->stop && r->stop(r->stop_ctx);
}

iir_status iir_renderer_frame(iir_renderer *r, const iir_render_input *in,
                              const iir_indirect_params *p, iir_image *out, iir_render_timing *t,
                              iir_raystats *st, iir_error *err)
{
    iir_render_timing tm = {0};
    iir_raystats rays = {0};
    iir_status s = check_inputs(in->camera, in->lights, in->num_lights, p, out, err);
    iir_side_run side = {.side = in->side};
    if (s == IIR_OK && !in->side) s = iir_render_subsets(r, in->vpls, in->num_vpls, p, false, err);
    if (s == IIR_OK) s = gbuffer_phase(r, in->camera, out->width, out->height, &tm, &rays, err);
    if (s == IIR_OK) s = multires_phase(r, p, &tm, err);
    if (s == IIR_OK) s = compensation_phase(r, in, p, err);
    iir_shade_job job = {
        .lights = in->lights, .num_lights = in->num_lights, .p = p, .seed = in->seed, .out = out};
    if (s == IIR_OK && stop_requested(r))
        s = iir_fail(err, IIR_ERR_INTERRUPTED, "frame stopped early");
    double mr_ms = tm.indirect_ms;
    if (s == IIR_OK) {
        s = shade(r, &job, &side, &tm, &rays, err);
        tm.indirect_ms += mr_ms; /* the hierarchy's build (0 when kept) */
    }
    if (t) *t = tm;
    if (st) iir_raystats_add(st, &rays);
    return s;
}

/* ---- one refinement pass ---- */

static iir_status check_pass(const iir_pass_params *p, iir_error *err)
{
    if (p->interleave < 1 || p->interleave > IIR_MAX_INTERLEAVE)
        return iir_fail(err, IIR_ERR_INVALID, "pass interleave %d is outside [1, %d]",
                        p->interleave, IIR_MAX_INTERLEAVE);
    uint32_t n2 = (uint32_t)(p->interleave * p->interleave);
    if (p->shift >= n2)
        return iir_fail(err, IIR_ERR_INVALID, "pass shift %u is outside [0, %u)", p->shift, n2);
    if (!(p->jitter.x >= 0.f && p->jitter.x <= 1.f && p->jitter.y >= 0.f && p->jitter.y <= 1.f))
        return iir_fail(err, IIR_ERR_INVALID, "pass jitter (%g, %g) is outside [0, 1]^2",
                        (double)p->jitter.x, (double)p->jitter.y);
    return IIR_OK;
}

/* The G-buffer of a pass: the cached pixel-centre one when the jitter is the centre, else one
 * rendered through the jittered points, which is not kept for frames (gb_valid is cleared). */
static iir_status pass_gbuffer(iir_renderer *r, const iir_camera *cam, iir_vec2 jitter, int w,
                               int h, iir_render_timing *t, iir_raystats *st, iir_error *err)
{
    if (jitter.x == 0.5f && jitter.y == 0.5f) return gbuffer_phase(r, cam, w, h, t, st, err);
    double t0 = iir_now_ms();
    iir_status s = resize(r, w, h, err);
    if (s != IIR_OK) return s;
    iir_camera_frame cf = iir_camera_setup(cam, w, h);
    const iir_stop stop = {r->stop, r->stop_ctx};
    r->gb_serial++;
    r->gb_valid = false;
    if (!iir_gbuffer_render(&r->gb, r->scene, r->rt, &cf, jitter, r->specular_depth, &stop, st))
        return iir_fail(err, IIR_ERR_INTERRUPTED, "refinement pass stopped early");
    r->gb_camera = *cam; /* the area lights' camera rays go through the same jittered points */
    r->gb_shift = iir_v2(jitter.x - 0.5f, jitter.y - 0.5f);
    t->gbuffer_ms = iir_now_ms() - t0;
    return IIR_OK;
}

void iir_renderer_set_stop(iir_renderer *r, iir_stop_fn fn, void *ctx)
{
    r->stop = fn;
    r->stop_ctx = ctx;
}

iir_status iir_renderer_pass(iir_renderer *r, const iir_render_input *in, const iir_pass_params *p,
                             iir_image *out, iir_render_timing *t, iir_raystats *st, iir_error *err)
{
    iir_render_timing tm = {0};
    iir_raystats rays = {0};
    iir_indirect_params ind = iir_indirect_params_default();
    r->level = NULL; /* passes are full resolution: exact */
    ind.shading = IIR_SHADING_FULL;
    ind.visibility = IIR_VIS_RAYS;
    ind.interleave = p->interleave;
    ind.unfiltered = true;
    ind.clamp = p->clamp;
    ind.clamp_comp = p->clamp_comp ? IIR_CLAMP_COMP_FULL : IIR_CLAMP_COMP_OFF;
    ind.bounces = p->bounces;
    if (p->area_samples > 0) ind.area_samples = p->area_samples;
    iir_status s = check_pass(p, err);
    if (s == IIR_OK) s = check_inputs(in->camera, in->lights, in->num_lights, &ind, out, err);
    if (s == IIR_OK) s = iir_render_subsets(r, in->vpls, in->num_vpls, &ind, true, err);
    if (s == IIR_OK)
        s = pass_gbuffer(r, in->camera, p->jitter, out->width, out->height, &tm, &rays, err);
    if (s == IIR_OK) s = compensation_phase(r, in, &ind, err);
    iir_shade_job job = {.lights = in->lights,
                         .num_lights = in->num_lights,
                         .p = &ind,
                         .shift = p->shift,
                         .seed = in->seed,
                         .out = out};
    iir_side_run none = {0};
    if (s == IIR_OK && !stop_requested(r))
        s = shade(r, &job, &none, &tm, &rays, err);
    else if (s == IIR_OK)
        s = IIR_ERR_INTERRUPTED;
    if (s == IIR_ERR_INTERRUPTED) s = iir_fail(err, s, "refinement pass stopped early");
    if (t) *t = tm;
    if (st) iir_raystats_add(st, &rays);
    return s;
}

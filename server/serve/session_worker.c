/* session_worker.c -- a session's render worker: renders the newest state, encodes the JPEG,
 * publishes the frame and wakes the service thread; refines the frame while nothing changes;
 * loads scenes and encodes snapshots. Not messages (session_msg.c) or writing (session.c).
 *
 * The loop holds the session's lock only to look at the state and to publish; every step below
 * that says "_locked" is entered and left with the lock held and drops it for the slow part.
 * Priorities: stop, scene load, a new state (unless held back by an unsent frame that already
 * replaced another: at most one frame ahead of what was sent), a snapshot, refinement (after
 * IIRD_REFINE_IDLE_MS without input, until converged), then sleep on the condition variable. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>
#include <string.h>
#include <time.h>

#include <libwebsockets.h>
#include <omp.h>

#include "budget.h"
#include "iir/timer.h"
#include "session_internal.h"

/* ======================== small helpers ======================== */

/* Wakes the service thread to write (the lock is held): the only lws call a worker makes. */
static void notify_locked(iird_session *s)
{
    s->wake_service = true;
    lws_cancel_service(s->env->lws);
}

static iird_err err_code(iir_status st)
{
    switch (st) {
    case IIR_ERR_UNSUPPORTED:
        return IIRD_E_UNSUPPORTED;
    case IIR_ERR_INVALID:
        return IIRD_E_BAD_FIELD;
    default:
        return IIRD_E_INTERNAL;
    }
}

/* Queues an error reply for a failure on the worker (unlocked) and wakes the service thread. */
static void worker_error(iird_session *s, iird_err code, int64_t seq, const char *what,
                         const iir_error *err)
{
    iird_proto_error e = {.seq = seq};
    iird_proto_fail(&e, code, NULL, "%s: %s", what, err->msg);
    iird_queue_error(s, &e);
    pthread_mutex_lock(&s->lock);
    notify_locked(s);
    pthread_mutex_unlock(&s->lock);
}

static void wait_ms_locked(iird_session *s, double ms)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    double ns = (double)ts.tv_nsec + ms * 1e6;
    ts.tv_sec += (time_t)(ns / 1e9);
    ts.tv_nsec = (long)fmod(ns, 1e9);
    pthread_cond_timedwait(&s->wake, &s->lock, &ts);
}

void iird_worker_free(worker_state *w)
{
    iir_method_destroy(w->method);
    w->method = NULL;
    iir_image_destroy(w->img);
    iir_jpeg_encoder_destroy(w->enc);
    iird_buf_free(&w->back);
    free(w->job_lights);
    free(w->last_lights);
    free(w->vpl_px);
    free(w->vpl_flags);
}

/* ======================== the method and its inputs ======================== */

/* Same picture as the last frame: only the encoding (quality, exposure) or the stream changed. */
static bool same_view(const worker_state *w, const render_job *j)
{
    const render_job *a = &w->last;
    return w->have_frame && a->num_lights == j->num_lights &&
           !memcmp(a->lights, j->lights, j->num_lights * sizeof *j->lights) &&
           !memcmp(&a->camera, &j->camera, sizeof a->camera) &&
           a->settings.width == j->settings.width && a->settings.height == j->settings.height &&
           !strcmp(a->settings.method, j->settings.method) &&
           iir_params_equal(&a->settings.params, &j->settings.params);
}

/* Whether the method being created (w.creating) is no longer the one the session asks for: a
 * scene switch is waiting, or the newest method, parameters or scene differ from the job's. New
 * input that only moves lights or the camera lets the creation finish (it would start over
 * otherwise, and never finish while a light is dragged). Takes the lock briefly. */
static bool creation_obsolete(iird_session *s)
{
    const worker_state *w = &s->w;
    pthread_mutex_lock(&s->lock);
    bool gone = s->scene_pending || s->scene != w->creating ||
                strcmp(s->settings.method, w->last.settings.method) != 0 ||
                !iir_params_equal(&s->settings.params, &w->last.settings.params);
    pthread_mutex_unlock(&s->lock);
    return gone;
}

/* The method's stop hook (called from its threads without the lock, per tile and every few
 * milliseconds of a creation): new input or the session closing ends the frame or pass under way
 * within a tile, so input never waits for a whole frame and a closing session frees its worker at
 * once; a creation ends when the session closes or asks for another method (creation_obsolete).
 * w.last is the job being created, rendered or refined. It is also where the session hands the
 * cores to another whose turn it is (scheduler.h). */
static bool should_stop(void *ctx)
{
    iird_session *s = ctx;
    if (atomic_load_explicit(&s->stop, memory_order_relaxed)) return true;
    iird_sched_yield(s->env->sched, &s->sched); /* the cores may go to another session first */
    if (atomic_load_explicit(&s->version, memory_order_relaxed) == s->w.last.version) return false;
    if (s->w.creating) return creation_obsolete(s);
    return s->w.refining ||
           iird_sched_used_ms(s->env->sched, &s->sched) - s->w.started_ms > s->w.patience_ms;
}

/* A method the budget refused: the session goes back to the settings its method has (those of a new
 * session when it has none), answered with a `state` reply, and the job's request gets the refusal
 * (lock held). Newer settings than the job's are left alone: their own turn checks them. */
static void refuse_settings_locked(iird_session *s, const render_job *j, iird_proto_error *pe)
{
    worker_state *w = &s->w;
    const iird_settings *now = &s->settings;
    if (!strcmp(now->method, j->settings.method) &&
        iir_params_equal(&now->params, &j->settings.params) && now->width == j->settings.width &&
        now->height == j->settings.height) {
        s->settings = w->method ? w->method_settings : s->env->defaults;
        iird_proto_error ignore;
        (void)iird_budget_reserve(s->env->budget, &s->reserved, iird_session_estimate(&s->settings),
                                  &ignore); /* less than before: fits */
        s->version++;
        s->generation++;
        iird_state_view v = iird_state_view_locked(s);
        char *json = iird_json_state(&v, j->seq);
        iird_queue_text_locked(s, json, false);
        free(json);
    }
    char *json = iird_json_error(pe);
    iird_metrics_error(s->env->metrics, pe->code);
    iird_queue_text_locked(s, json, false);
    free(json);
    notify_locked(s);
}

/* Reserves what the job's method will hold by its real counts on scene sc (radiosity: the scene's
 * patches and sampled form-factor rows; iir_method_memory_on) beyond what the session reserved
 * from its parameters, before anything is built. False when that passes the session's or the
 * daemon's budget: the request is refused as a `params` message would be (the session's settings
 * go back to its method's), nothing is built and the old method stays. */
static bool reserve_real_size(iird_session *s, const render_job *j, const iird_scene_entry *sc)
{
    worker_state *w = &s->w;
    const iird_settings *st = &j->settings;
    uint64_t real =
        iir_method_memory_on(st->method, sc->scene, sc->rt, &st->params, st->width, st->height);
    uint64_t param = iir_method_memory(st->method, &st->params, st->width, st->height);
    uint64_t extra = real > param ? real - param : 0;
    iird_budget *b = s->env->budget;
    iird_proto_error pe = {.seq = j->seq};
    pthread_mutex_lock(&s->lock);
    bool ok = !b || s->reserved + extra <= b->session_max;
    if (!ok)
        iird_proto_fail(&pe, IIRD_E_OUT_OF_RANGE, "params",
                        "params: %s on scene %s would hold about %.0f MiB (counted on the scene), "
                        "over the session's memory budget of %.0f MiB (--max-session-memory); "
                        "a larger patch_area or a smaller hemicube_res fits",
                        st->method, sc->name, (double)(s->reserved + extra) / 1048576.0,
                        (double)b->session_max / 1048576.0);
    else
        ok = iird_budget_reserve(b, &w->extra_held, extra, &pe);
    if (!ok) refuse_settings_locked(s, j, &pe);
    pthread_mutex_unlock(&s->lock);
    return ok;
}

/* The session's method for the job: kept when only parameters changed (its VPLs too, when every
 * change is IIR_PARAM_LIVE), created anew for another method or scene; its size on the scene is
 * reserved first (reserve_real_size). */
static iir_status ensure_method(iird_session *s, const render_job *j, const iird_scene_entry *sc,
                                iir_error *err)
{
    worker_state *w = &s->w;
    const iird_settings *st = &j->settings;
    bool same = w->method && w->method_scene == sc && !strcmp(w->method_name, st->method);
    if (same && iir_params_equal(iir_method_params(w->method), &st->params)) return IIR_OK;
    if (!reserve_real_size(s, j, sc))
        return iir_fail(err, IIR_ERR_INTERRUPTED, "refused: over the memory budget"); /* said */
    w->have_frame = false;
    w->creating = sc; /* the stop hook's creation rule, until this returns */
    if (same) {
        iir_status rc = iir_method_set_params(w->method, &st->params, NULL, err);
        w->creating = NULL;
        if (rc == IIR_OK) w->method_settings = *st;
        return rc;
    }
    iir_method_destroy(w->method);
    w->method = NULL;
    iir_status rc = iir_method_create_stoppable(st->method, sc->scene, sc->rt, &st->params,
                                                should_stop, s, &w->method, err);
    w->creating = NULL;
    if (rc != IIR_OK) return rc;
    w->method_settings = *st;
    snprintf(w->method_name, sizeof w->method_name, "%s", st->method);
    w->method_scene = sc;
    return IIR_OK;
}

static iir_status ensure_image(worker_state *w, int width, int height, iir_error *err)
{
    if (w->img && w->img->width == width && w->img->height == height) return IIR_OK;
    iir_image_destroy(w->img);
    w->img = iir_image_create(width, height);
    w->have_frame = false;
    return w->img ? IIR_OK
                  : iir_fail(err, IIR_ERR_NOMEM, "out of memory for a %dx%d frame", width, height);
}

/* The view: the job's lights (every light of the session, in the scene's order; one switched off
 * black) and camera. */
static void build_view(const render_job *j, iir_view *view)
{
    view->lights = j->lights;
    view->num_lights = j->num_lights;
    view->camera = j->camera;
}

/* The session's lights as rendered, copied into the worker's job buffer for job j (lock held).
 * False when out of memory for them. */
static bool take_lights_locked(iird_session *s, render_job *j)
{
    worker_state *w = &s->w;
    uint32_t n = s->lights.n;
    if (n > w->job_cap) {
        iir_light *l = realloc(w->job_lights, n * sizeof *l);
        if (!l) return false;
        w->job_lights = l;
        w->job_cap = n;
    }
    memcpy(w->job_lights, iird_lights_shown(&s->lights), n * sizeof *w->job_lights);
    j->lights = w->job_lights;
    j->num_lights = n;
    return true;
}

/* j becomes the last job; its lights' buffer becomes last's and last's old one the next job's. */
static void keep_job(worker_state *w, const render_job *j)
{
    iir_light *spare = w->last_lights;
    uint32_t spare_cap = w->last_cap;
    w->last = *j;
    w->last_lights = w->job_lights;
    w->last_cap = w->job_cap;
    w->job_lights = spare;
    w->job_cap = spare_cap;
}

/* ======================== the domain message ======================== */

static bool reserve_vpls(worker_state *w, uint32_t n)
{
    if (n <= w->vpl_cap) return true;
    float(*px)[2] = realloc(w->vpl_px, n * sizeof *px);
    if (px) w->vpl_px = px;
    uint8_t *fl = realloc(w->vpl_flags, n);
    if (fl) w->vpl_flags = fl;
    if (!px || !fl) return false;
    w->vpl_cap = n;
    return true;
}

/* Pixel position of VPL v on the image, or (-1, -1) where no dot belongs: a null sample (no
 * surface point: it sits at the light, or for a sun outside the scene), a VPL that carries no
 * light (on a black, mirror or glass surface), one behind the camera or outside the frame, one
 * whose surface faces away from the camera (seen from outside a room: the back of the wall it lies
 * on) or that something hides from the camera. */
static void project(const iir_camera_frame *cf, const iir_rt *rt, const iir_vpl *v, float out[2])
{
    out[0] = out[1] = -1.f;
    iir_vec3 p = v->position, d = iir_sub(p, cf->origin);
    if (v->null_sample || iir_is_black(v->flux) || !(iir_dot(v->normal, d) < 0.f)) return;
    float z = iir_dot(d, cf->basis.f), dist = iir_length(d);
    if (z <= 1e-6f * dist) return;
    float sx = iir_dot(d, cf->basis.r) / (z * cf->tan_half_y * cf->aspect);
    float sy = iir_dot(d, cf->basis.u) / (z * cf->tan_half_y);
    float x = 0.5f * (sx + 1.f) * (float)cf->width, y = 0.5f * (1.f - sy) * (float)cf->height;
    if (!(x >= 0.f && x < (float)cf->width && y >= 0.f && y < (float)cf->height)) return;
    float eps = iir_rt_epsilon(rt);
    iir_ray ray = iir_make_ray(cf->origin, iir_scale(d, 1.f / dist), 0.f, dist - 4.f * eps);
    iir_raystats rs = {{0}};
    if (ray.tfar > 0.f && iir_rt_occluded(rt, &ray, &rs, IIR_RAYS_CAMERA)) return;
    out[0] = x;
    out[1] = y;
}

/* The domain JSON of the frame just rendered, or NULL for methods without VPLs. */
static char *domain_json(worker_state *w, const render_job *j, const iird_scene_entry *sc,
                         uint32_t frame)
{
    uint32_t n = 0;
    const iir_vpl *v = iir_method_vpls(w->method, &n);
    if (!v || n == 0 || !reserve_vpls(w, n)) return NULL;
    iir_domain dom;
    bool has_dom = iir_method_domain(w->method, &dom);
    bool by_site = has_dom && dom.num_sites == n;
    uint32_t newest = 0;
    for (uint32_t i = 0; i < n; i++) newest = v[i].birth > newest ? v[i].birth : newest;
    iir_camera_frame cf = iir_camera_setup(&j->camera, j->settings.width, j->settings.height);
    for (uint32_t i = 0; i < n; i++) {
        project(&cf, sc->rt, &v[i], w->vpl_px[i]);
        bool fresh = by_site ? (dom.sites[i].flags & IIR_SITE_NEW) != 0 : v[i].birth == newest;
        w->vpl_flags[i] =
            (uint8_t)((fresh ? 1 : 0) | (v[i].null_sample ? 2 : 0) | (v[i].generation > 0 ? 4 : 0));
    }
    return iird_json_domain(frame, (const float(*)[2])w->vpl_px, w->vpl_flags, n,
                            has_dom ? &dom : NULL);
}

/* ======================== memory ======================== */

/* Bytes this session holds, estimated (docs/architecture.md, "Memory per session"). */
uint64_t iird_session_estimate(const iird_settings *st)
{
    uint64_t px = (uint64_t)st->width * (uint64_t)st->height;
    uint64_t jpeg = px * 3 + 2048 + IIRD_FRAME_HEADER_BYTES;        /* tjBufSize's bound */
    uint64_t bytes = sizeof(iird_session) + IIRD_MAX_MESSAGE_BYTES; /* + the receive buffer */
    bytes += px * sizeof(iir_vec3);                                 /* the frame */
    bytes += px * 3 + jpeg;                                         /* encoder: RGB8 + output */
    bytes += 3 * jpeg; /* back, slot and sending buffers */
    return bytes + iir_method_memory(st->method, &st->params, st->width, st->height);
}

/* ======================== publishing ======================== */

typedef struct frame_info {
    uint32_t id, pass;
    bool converged;
    bool reencoded; /* the last frame's image again, only its encoding changed */
    iir_frame_stats stats;
    double encode_ms;
} frame_info;

/* Encodes the worker's image behind a frame header into the back buffer; the JPEG's size in
 * *size. */
static iir_status encode_frame(worker_state *w, const render_job *j, frame_info *f, size_t *size,
                               iir_error *err)
{
    const uint8_t *jpeg = NULL;
    double t0 = iir_now_ms();
    iir_status st = iir_jpeg_encode(w->enc, w->img, j->settings.exposure, j->settings.quality,
                                    &jpeg, size, err);
    if (st != IIR_OK) return st;
    if (!iird_buf_reserve(&w->back, IIRD_FRAME_HEADER_BYTES + *size))
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for a frame of %zu bytes", *size);
    f->encode_ms = iir_now_ms() - t0;
    iird_frame_header h = {.kind = 1,
                           .frame_id = f->id,
                           .seq = j->seq == IIRD_NO_SEQ ? 0xFFFFFFFFu : (uint32_t)j->seq,
                           .width = (uint16_t)w->img->width,
                           .height = (uint16_t)w->img->height,
                           .render_ms = (float)f->stats.total_ms,
                           .encode_ms = (float)f->encode_ms,
                           .pass = f->pass,
                           .flags = (f->converged ? 1u : 0u) | (f->pass > 0 ? 2u : 0u) |
                                    (f->reencoded ? 4u : 0u),
                           .payload_bytes = (uint32_t)*size,
                           .generation = j->generation};
    unsigned char *out = w->back.buf + LWS_PRE;
    iird_frame_header_write(&h, out);
    memcpy(out + IIRD_FRAME_HEADER_BYTES, jpeg, *size);
    return IIR_OK;
}

/* Swaps the back buffer into the slot, replacing (and counting as dropped) an unsent frame, and
 * wakes the service thread (the lock is held). */
static void fill_slot_locked(iird_session *s, const render_job *j, frame_info *f, size_t size)
{
    worker_state *w = &s->w;
    frame_slot *slot = &s->slot;
    if (slot->full) {
        s->dropped++;
        atomic_fetch_add(&s->env->metrics->frames_dropped, 1);
        free(slot->domain);
    }
    byte_buf mine = w->back;
    w->back = slot->data;
    slot->data = mine;
    slot->len = IIRD_FRAME_HEADER_BYTES + size;
    slot->full = true;
    slot->id = f->id;
    slot->pass = f->pass;
    slot->converged = f->converged;
    slot->reencoded = f->reencoded;
    slot->seq = j->seq;
    slot->input_ms = j->input_ms;
    slot->encode_ms = f->encode_ms;
    slot->jpeg_bytes = size;
    snprintf(slot->method, sizeof slot->method, "%s", j->settings.method);
    slot->stats = f->stats;
    slot->domain = NULL; /* send_domain attaches it */
    w->last_id = f->id;
    notify_locked(s);
}

/* Encodes and publishes the worker's image. Called unlocked. */
static void publish(iird_session *s, const render_job *j, frame_info *f)
{
    size_t size = 0;
    iir_error err = {0};
    if (encode_frame(&s->w, j, f, &size, &err) != IIR_OK) {
        worker_error(s, IIRD_E_INTERNAL, j->seq, "encoding the frame", &err);
        return;
    }
    atomic_store(&s->memory_bytes, iird_session_estimate(&j->settings));
    pthread_mutex_lock(&s->lock);
    fill_slot_locked(s, j, f, size);
    pthread_mutex_unlock(&s->lock);
}

/* ======================== the steps ======================== */

/* The VPL counts of a refinement or re-encoded frame: the set of the frame it shows again,
 * unchanged (every VPL of it valid, none inserted or removed), whatever sets refinement passes
 * drew: what the stats mean stays the same from a frame to its refinement. */
static iir_vpl_counts refined_vpl(const iir_vpl_counts *frame)
{
    return (iir_vpl_counts){.count = frame->count,
                            .valid = frame->count,
                            .null_samples = frame->null_samples,
                            .descendants = frame->descendants};
}

static iir_status render_frame(iird_session *s, const render_job *j, const iird_scene_entry *sc,
                               frame_info *f, iir_error *err)
{
    worker_state *w = &s->w;
    iir_view view;
    build_view(j, &view);
    iir_status st = ensure_method(s, j, sc, err);
    if (st == IIR_OK) st = ensure_image(w, j->settings.width, j->settings.height, err);
    w->refining = false;
    w->started_ms = iird_sched_used_ms(s->env->sched, &s->sched);
    double typical = 3.0 * w->last_stats.total_ms;
    w->patience_ms = typical < IIRD_FRAME_PATIENCE_MS       ? IIRD_FRAME_PATIENCE_MS
                     : typical > IIRD_FRAME_PATIENCE_MAX_MS ? IIRD_FRAME_PATIENCE_MAX_MS
                                                            : typical;
    if (st == IIR_OK) st = iir_method_render(w->method, &view, w->img, &f->stats, err);
    w->have_frame = st == IIR_OK;
    w->pass = 0;
    /* a frame converged at once (whitted, radiosity, hybrid) is final: not refined */
    f->converged = w->converged = f->stats.converged;
    if (st != IIR_OK) return st;
    f->id = ++w->next_id;
    return IIR_OK;
}

/* Sends frame id's domain message after the frame: with it while it waits in the slot, else at
 * once. Built after the frame is published, so it adds nothing to the frame's latency (building
 * the JSON of a few hundred Voronoi cells takes milliseconds). */
static void send_domain(iird_session *s, uint32_t id, char *json)
{
    if (!json) return;
    pthread_mutex_lock(&s->lock);
    if (s->slot.full && s->slot.id == id && !s->slot.domain) {
        s->slot.domain = json;
        json = NULL;
    } else {
        iird_queue_text_locked(s, json, true);
    }
    notify_locked(s);
    pthread_mutex_unlock(&s->lock);
    free(json);
}

/* Building a domain message costs ~4 ms (cells from CGAL, a few thousand JSON numbers): while
 * frames stream it goes out at most every IIRD_DOMAIN_MIN_MS, and the newest frame's once they
 * pause, so the drawing always ends on the frame shown. */
static void send_stale_domain(iird_session *s, const iird_scene_entry *sc)
{
    worker_state *w = &s->w;
    w->domain_stale = false;
    w->domain_ms = iir_now_ms();
    send_domain(s, w->domain_for, domain_json(w, &w->last, sc, w->domain_for));
}

/* A new state: render it (or only re-encode when just the encoding changed) and publish. */
static void render_locked(iird_session *s)
{
    worker_state *w = &s->w;
    render_job j = {.version = s->version,
                    .generation = s->generation,
                    .camera = s->camera,
                    .settings = s->settings,
                    .seq = s->seq,
                    .input_ms = s->input_ms};
    const iird_scene_entry *sc = s->scene;
    uint32_t num_lights = s->lights.n;
    bool have_lights = take_lights_locked(s, &j);
    pthread_mutex_unlock(&s->lock);

    frame_info f = {0};
    iir_error err = {0};
    iir_status st = IIR_OK;
    if (!have_lights) { /* reported, and not tried again until the next input */
        w->last.version = j.version;
        w->have_frame = false;
        iir_fail(&err, IIR_ERR_NOMEM, "out of memory for %u lights", num_lights);
        worker_error(s, IIRD_E_INTERNAL, j.seq, "rendering the frame", &err);
        pthread_mutex_lock(&s->lock);
        return;
    }
    bool rendered = !same_view(w, &j);
    keep_job(w, &j); /* before rendering: the stop hook compares the input version with it */
    j.lights = w->last_lights;
    omp_set_num_threads(iird_sched_enter(s->env->sched, &s->sched)); /* the frame, its JPEG */
    if (!rendered) { /* quality, exposure, refine or domain changed: no render, no VPL step */
        f = (frame_info){
            .id = ++w->next_id, .pass = w->pass, .converged = w->converged, .reencoded = true};
        f.stats.samples_per_pixel = w->last_stats.samples_per_pixel;
        f.stats.converged = w->last_stats.converged;
        f.stats.whole_sweeps = true;
        f.stats.vpl = refined_vpl(&w->frame_vpl);
    } else {
        st = render_frame(s, &j, sc, &f, &err);
        w->last_stats = f.stats;
        w->frame_vpl = f.stats.vpl;
    }
    if (st == IIR_OK) publish(s, &j, &f);
    iird_sched_leave(s->env->sched, &s->sched);
    if (st != IIR_OK &&
        st != IIR_ERR_INTERRUPTED) /* stopped by newer input (rendered next) or closing */
        worker_error(s, err_code(st), j.seq, "rendering the frame", &err);
    if (st == IIR_OK && rendered && j.settings.domain) {
        w->domain_stale = true;
        w->domain_for = f.id;
        if (iir_now_ms() - w->domain_ms >= IIRD_DOMAIN_MIN_MS) send_stale_domain(s, sc);
    }
    pthread_mutex_lock(&s->lock);
}

/* The domain of the newest interactive frame that has none yet, once the frames pause (the
 * method still holds that frame's VPLs: refinement does not touch them). */
static void domain_locked(iird_session *s)
{
    const iird_scene_entry *sc = s->scene;
    pthread_mutex_unlock(&s->lock);
    send_stale_domain(s, sc);
    pthread_mutex_lock(&s->lock);
}

/* A VPL method's refined frame is worth showing only after whole sweeps of its n x n subsets:
 * in between, pixels have seen different numbers of subsets and the image shows the n x n
 * pattern (refine.h). pt's passes are whole samples per pixel: every one is shown. */
/* One more refinement pass over the last frame, published as pass k > 0 after whole sweeps. */
static void refine_locked(iird_session *s)
{
    worker_state *w = &s->w;
    render_job j = w->last;
    pthread_mutex_unlock(&s->lock);
    frame_info f = {0};
    iir_error err = {0};
    w->refining = true;
    /* the pass, its JPEG: background work, which any session's frame goes before */
    omp_set_num_threads(iird_sched_enter_background(s->env->sched, &s->sched));
    iir_status st = iir_method_refine(w->method, w->img, &f.stats, &err);
    if (st == IIR_OK) {
        f.stats.vpl = refined_vpl(&w->frame_vpl);
        f.pass = ++w->pass;
        f.converged = w->converged = f.stats.converged;
        w->last_stats = f.stats;
        if (f.converged || f.stats.whole_sweeps) {
            f.id = ++w->next_id;
            publish(s, &j, &f);
        }
    }
    iird_sched_leave(s->env->sched, &s->sched);
    if (st == IIR_ERR_INTERRUPTED) {
        /* New input (or closing) stopped the pass: nothing of it is published, and w->img is
         * unspecified, so the next job renders afresh (no re-encode, no snapshot of it). */
        w->have_frame = false;
    } else if (st != IIR_OK) {
        w->converged = true; /* do not try again until the next frame */
        worker_error(s, err_code(st), j.seq, "refining the frame", &err);
    }
    pthread_mutex_lock(&s->lock);
}

/* Refinement is due (or due in *wait_ms) for the last frame (the lock is held). */
static bool refine_due_locked(const iird_session *s, double *wait_ms)
{
    const worker_state *w = &s->w;
    if (!w->have_frame || w->converged || !s->settings.refine || !w->method ||
        !iir_method_can_refine(w->method))
        return false;
    *wait_ms = IIRD_REFINE_IDLE_MS - (iir_now_ms() - s->input_ms);
    return true;
}

/* The image as a PNG or EXR file's bytes after LWS_PRE + the frame header's room, encoded in
 * memory; NULL with err filled on failure. */
static unsigned char *snapshot_bytes(const iir_image *img, bool exr, float exposure, size_t *size,
                                     iir_error *err)
{
    uint8_t *file = NULL;
    iir_status st = exr ? iir_image_encode_exr(img, &file, size, err)
                        : iir_image_encode_png(img, exposure, &file, size, err);
    if (st != IIR_OK) return NULL;
    unsigned char *buf = malloc(LWS_PRE + IIRD_FRAME_HEADER_BYTES + *size);
    if (buf)
        memcpy(buf + LWS_PRE + IIRD_FRAME_HEADER_BYTES, file, *size);
    else
        iir_fail(err, IIR_ERR_NOMEM, "out of memory for a %zu-byte snapshot", *size);
    free(file);
    return buf;
}

/* The snapshot reply and its binary kind-2 message. */
static void snapshot_locked(iird_session *s)
{
    worker_state *w = &s->w;
    bool exr = s->snapshot_exr;
    int64_t seq = s->snapshot_seq;
    s->snapshot_pending = false;
    pthread_mutex_unlock(&s->lock);
    iir_error err = {0};
    size_t size = 0;
    double t0 = iir_now_ms();
    unsigned char *buf = w->have_frame
                             ? snapshot_bytes(w->img, exr, w->last.settings.exposure, &size, &err)
                             : (iir_fail(&err, IIR_ERR_INVALID, "no frame yet"), NULL);
    pthread_mutex_lock(&s->lock);
    iird_proto_error pe = {.seq = seq};
    bool fits = buf && iird_budget_reserve(s->env->budget, &s->snapshot_held,
                                           IIRD_FRAME_HEADER_BYTES + size, &pe);
    if (!fits) s->snapshot_busy = false;
    pthread_mutex_unlock(&s->lock);
    if (!buf) {
        worker_error(s, IIRD_E_INTERNAL, seq, "snapshot", &err);
        pthread_mutex_lock(&s->lock);
        return;
    }
    if (!fits) {
        free(buf);
        iird_proto_fail(&pe, IIRD_E_BUSY, "snapshot", "snapshot: %s", pe.message);
        iird_queue_error(s, &pe);
        pthread_mutex_lock(&s->lock);
        notify_locked(s);
        return;
    }
    iird_frame_header h = {.kind = 2,
                           .frame_id = w->last_id,
                           .seq = seq == IIRD_NO_SEQ ? 0xFFFFFFFFu : (uint32_t)seq,
                           .width = (uint16_t)w->img->width,
                           .height = (uint16_t)w->img->height,
                           .encode_ms = (float)(iir_now_ms() - t0),
                           .pass = w->pass,
                           .flags = (w->converged ? 1u : 0u) | (w->pass > 0 ? 2u : 0u),
                           .payload_bytes = (uint32_t)size,
                           .generation = w->last.generation};
    iird_frame_header_write(&h, buf + LWS_PRE);
    char *json = iird_json_snapshot(seq, exr ? "exr" : "png", w->last_id, w->pass, size,
                                    w->img->width, w->img->height);
    pthread_mutex_lock(&s->lock);
    iird_queue_snapshot_locked(s, json, buf, IIRD_FRAME_HEADER_BYTES + size);
    notify_locked(s);
    free(json);
}

/* A scene switch while recording: the recording so far goes to the client as a `record` reply
 * (its script names the old scene) and a new one starts on the new scene, its first keys the reset
 * lights, the new scene's camera and the exposure, so no script mixes scenes and no reset is lost.
 * Lock held, after the swap. */
static void record_scene_switch_locked(iird_session *s)
{
    if (!s->rec) return;
    iird_proto_error pe = {.seq = IIRD_NO_SEQ};
    iird_session_record_end_locked(s, (iir_now_ms() - s->rec_start_ms) / 1e3);
    char *json = iird_json_record_part(s->rec, IIRD_NO_SEQ, true);
    int fps = iird_recording_fps(s->rec);
    iird_queue_text_locked(s, json, false);
    free(json);
    iird_recording_destroy(s->rec);
    s->rec = iird_session_record_start_locked(s, fps, &pe);
    /* the switch resets the camera to the new scene's right after this: start from that one */
    if (s->rec && !iird_recording_add_camera(s->rec, 0.0, &s->scene->scene->camera, &pe))
        iird_recording_destroy(s->rec), s->rec = NULL;
}

/* Whether the session's method renders scene `name`'s lights L; else its unsupported error is
 * queued, naming the methods that would (unlocked). */
static bool scene_supported(iird_session *s, const char *name, const iird_lights *L, int64_t seq)
{
    iir_error err = {0};
    pthread_mutex_lock(&s->lock);
    char method[sizeof s->settings.method];
    memcpy(method, s->settings.method, sizeof method);
    pthread_mutex_unlock(&s->lock);
    if (iir_method_supports(method, L->v, L->n, &err) == IIR_OK) return true;
    char what[300], alt[96];
    iird_session_alternatives(L->v, L->n, method, alt, sizeof alt);
    snprintf(err.msg + strlen(err.msg), sizeof err.msg - strlen(err.msg), "%s", alt);
    snprintf(what, sizeof what, "scene %s with method %s", name, method);
    worker_error(s, IIRD_E_UNSUPPORTED, seq, what, &err);
    return false;
}

/* Scene e and its lights *L become the session's, with e's camera, answered by `state`; *L gets
 * the old lights and the old scene is returned, both for the caller to free (lock held). */
static const iird_scene_entry *swap_scene_locked(iird_session *s, const iird_scene_entry *e,
                                                 iird_lights *L, int64_t seq)
{
    const iird_scene_entry *old = s->scene;
    iird_lights gone = s->lights;
    s->scene = e;
    s->lights = *L;
    *L = gone;
    record_scene_switch_locked(s);
    s->camera = e->scene->camera;
    s->generation++;
    /* a light or camera message that came after the switch was asked (it moved the old scene's)
       is still the newest input: frames answer its seq */
    if (seq != IIRD_NO_SEQ && s->version == s->scene_version) s->seq = seq;
    s->version++;
    s->input_ms = iir_now_ms();
    iird_state_view v = iird_state_view_locked(s);
    char *json = iird_json_state(&v, seq);
    iird_queue_text_locked(s, json, false);
    free(json);
    notify_locked(s);
    return old;
}

/* Loads the requested scene (seconds for a large one, without the lock), then swaps it in and
 * resets the lights and camera to the scene's own. */
static void load_scene_locked(iird_session *s)
{
    char name[sizeof s->scene_name];
    memcpy(name, s->scene_name, sizeof name);
    int64_t seq = s->scene_seq;
    s->scene_pending = false;
    pthread_mutex_unlock(&s->lock);

    const iird_scene_entry *e = NULL;
    iir_error err = {0};
    iird_lights L;
    char what[160];
    snprintf(what, sizeof what, "scene %s", name);
    if (iird_scene_cache_acquire(s->env->scenes, name, &e, &err) != IIR_OK) {
        worker_error(s, IIRD_E_SCENE_ERROR, seq, what, &err);
        pthread_mutex_lock(&s->lock);
        return;
    }
    bool ok = iird_lights_init(&L, e->scene);
    if (!ok) worker_error(s, IIRD_E_INTERNAL, seq, what, &(iir_error){.msg = "out of memory"});
    if (!ok || !scene_supported(s, name, &L, seq)) { /* keep the old scene */
        iird_lights_free(&L);
        iird_scene_cache_release(s->env->scenes, e);
        pthread_mutex_lock(&s->lock);
        return;
    }
    iir_method_destroy(s->w.method); /* it renders the old scene */
    s->w.method = NULL;
    s->w.have_frame = false;
    pthread_mutex_lock(&s->lock);
    const iird_scene_entry *old = swap_scene_locked(s, e, &L, seq);
    pthread_mutex_unlock(&s->lock);
    iird_lights_free(&L);
    iird_scene_cache_release(s->env->scenes, old);
    pthread_mutex_lock(&s->lock);
}

/* A frame is waiting that already replaced another: render no further ahead (lock held). */
static bool held_back_locked(const iird_session *s)
{
    return s->slot.full && s->w.last_id - s->sent_id >= 2;
}

void *iird_session_worker(void *arg)
{
    iird_session *s = arg;
    /* a lower priority for this thread and the OpenMP threads it starts (they inherit it), so the
       service thread answers /healthz and input promptly while many sessions render; failing is
       harmless (the worker renders at the daemon's priority) */
    (void)setpriority(PRIO_PROCESS, (id_t)syscall(SYS_gettid), IIRD_WORKER_NICE);
    pthread_mutex_lock(&s->lock);
    while (!s->stop) {
        double wait = 0;
        bool fresh = s->version != s->w.last.version;
        if (!s->ready)
            pthread_cond_wait(&s->wake, &s->lock);
        else if (s->scene_pending)
            load_scene_locked(s);
        else if (fresh && !held_back_locked(s))
            render_locked(s);
        else if (s->snapshot_pending && (s->w.have_frame || !fresh))
            snapshot_locked(s);
        else if (held_back_locked(s) || fresh)
            pthread_cond_wait(&s->wake, &s->lock);
        else if (s->w.domain_stale && s->w.have_frame && s->settings.domain)
            domain_locked(s);
        else if (refine_due_locked(s, &wait) && wait <= 0)
            refine_locked(s);
        else if (wait > 0)
            wait_ms_locked(s, wait);
        else
            pthread_cond_wait(&s->wake, &s->lock);
    }
    iird_budget_release(s->env->budget, &s->w.extra_held);
    s->worker_done = true;
    notify_locked(s); /* the service thread reaps finished sessions */
    pthread_mutex_unlock(&s->lock);
    return NULL;
}

/* session.c -- a session's life (create, stop, destroy), its output queue and frame slot, and
 * writing them to the client one message per writable callback. Client messages are
 * session_msg.c's, the render worker session_worker.c's. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <libwebsockets.h>

#include "budget.h"
#include "iir/timer.h"
#include "protocol/recording.h"
#include "session_internal.h"

/* ======================== buffers ======================== */

bool iird_buf_reserve(byte_buf *b, size_t n)
{
    if (b->buf && n <= b->cap) return true;
    size_t cap = n + n / 4 + 4096;
    unsigned char *p = realloc(b->buf, LWS_PRE + cap);
    if (!p) return false;
    b->buf = p;
    b->cap = cap;
    return true;
}

void iird_buf_free(byte_buf *b)
{
    free(b->buf);
    b->buf = NULL;
    b->cap = 0;
}

/* ======================== life ======================== */

/* False when out of memory for the scene's lights. */
static bool init_state(iird_session *s, const iird_session_env *env)
{
    s->scene = env->startup;
    iird_scene_cache_ref(env->scenes, s->scene);
    if (!iird_lights_init(&s->lights, s->scene->scene)) return false;
    s->camera = s->scene->scene->camera;
    s->settings = env->defaults;
    s->version = 1;
    s->seq = IIRD_NO_SEQ;
    s->input_ms = iir_now_ms();
    s->tokens = IIRD_RATE_BURST;
    s->tokens_ms = s->input_ms;
    s->rate_error_ms = -1e9;
    return true;
}

iird_session *iird_session_create(const iird_session_env *env, uint32_t id, iir_error *err)
{
    iird_session *s = calloc(1, sizeof *s);
    if (!s) return iir_fail(err, IIR_ERR_NOMEM, "out of memory for a session"), NULL;
    s->env = env;
    s->id = id;
    iird_proto_error pe = {.seq = IIRD_NO_SEQ};
    if (!iird_budget_reserve(env->budget, &s->reserved, iird_session_estimate(&env->defaults),
                             &pe)) {
        iir_fail(err, IIR_ERR_NOMEM, "%s", pe.message);
        free(s);
        return NULL;
    }
    pthread_mutex_init(&s->lock, NULL);
    pthread_condattr_t attr; /* timed waits on the monotonic clock, as iir_now_ms */
    pthread_condattr_init(&attr);
    pthread_condattr_setclock(&attr, CLOCK_MONOTONIC);
    pthread_cond_init(&s->wake, &attr);
    pthread_condattr_destroy(&attr);
    bool lights = init_state(s, env);
    iird_sched_add(env->sched, &s->sched);
    s->sched_added = true;
    s->w.enc = iir_jpeg_encoder_create();
    if (!s->w.enc || !lights) {
        iir_fail(err, IIR_ERR_NOMEM, "out of memory for %s",
                 lights ? "a JPEG encoder" : "the scene's lights");
        iird_session_destroy(s);
        return NULL;
    }
    int rc = pthread_create(&s->thread, NULL, iird_session_worker, s);
    if (rc != 0) {
        iir_fail(err, IIR_ERR_INTERNAL, "cannot start a render worker: %s", strerror(rc));
        iird_session_destroy(s);
        return NULL;
    }
    s->thread_started = true;
    return s;
}

void iird_session_request_stop(iird_session *s)
{
    pthread_mutex_lock(&s->lock);
    s->stop = true;
    pthread_cond_broadcast(&s->wake);
    pthread_mutex_unlock(&s->lock);
    if (s->sched_added) iird_sched_cancel(s->env->sched, &s->sched); /* its waits end */
}

bool iird_session_worker_done(iird_session *s)
{
    pthread_mutex_lock(&s->lock);
    bool done = s->worker_done || !s->thread_started;
    pthread_mutex_unlock(&s->lock);
    return done;
}

static void free_output(iird_session *s)
{
    for (int i = 0; i < s->q_count; i++) free(s->queue[(s->q_head + i) % IIRD_QUEUE_CAP].buf);
    s->q_count = 0;
    iird_buf_free(&s->slot.data);
    free(s->slot.domain);
    s->slot.domain = NULL;
    iird_buf_free(&s->sending);
}

void iird_session_destroy(iird_session *s)
{
    if (!s) return;
    if (s->thread_started) {
        iird_session_request_stop(s);
        pthread_join(s->thread, NULL);
    }
    if (s->sched_added) iird_sched_remove(s->env->sched, &s->sched);
    free_output(s);
    free(s->rx);
    iird_recording_destroy(s->rec);
    iird_worker_free(&s->w); /* the method before the scene it renders */
    iird_lights_free(&s->lights);
    iird_scene_cache_release(s->env->scenes, s->scene);
    iird_budget_release(s->env->budget, &s->reserved);
    iird_budget_release(s->env->budget, &s->snapshot_held);
    pthread_cond_destroy(&s->wake);
    pthread_mutex_destroy(&s->lock);
    free(s);
}

uint32_t iird_session_id(const iird_session *s)
{
    return s->id;
}

bool iird_session_greeted(const iird_session *s)
{
    return s->hello_ok;
}

double iird_session_render_seconds(iird_session *s)
{
    return s->sched_added ? iird_sched_used_ms(s->env->sched, &s->sched) / 1e3 : 0.0;
}

uint64_t iird_session_memory(iird_session *s)
{
    return atomic_load(&s->memory_bytes);
}

/* ======================== the output queue ======================== */

/* Replies are never dropped: a client that lets more of them wait than the caps allow is closed
 * (IIRD_CLOSE_NOT_READING). Stats and domain messages are (the oldest first), as frames are. */

static out_msg *q_at(iird_session *s, int i)
{
    return &s->queue[(s->q_head + i) % IIRD_QUEUE_CAP];
}

/* Counts m in (sign 1) or out of (-1) the queue's figures. A snapshot's file is not counted in the
 * bytes (it is one per session, held in the memory budget). */
static void q_account(iird_session *s, const out_msg *m, int sign)
{
    if (m->droppable)
        s->q_droppable += sign;
    else if (!(m->binary && m->snapshot))
        s->q_reply_bytes = sign > 0 ? s->q_reply_bytes + m->len : s->q_reply_bytes - m->len;
}

/* Drops the oldest stats or domain message; false when none is queued (the lock is held). */
static bool drop_oldest_droppable(iird_session *s)
{
    for (int i = 0; i < s->q_count; i++) {
        out_msg *m = q_at(s, i);
        if (!m->droppable) continue;
        q_account(s, m, -1);
        free(m->buf);
        for (int k = i; k + 1 < s->q_count; k++) *q_at(s, k) = *q_at(s, k + 1);
        s->q_count--;
        return true;
    }
    return false;
}

/* The client does not read its replies: nothing more is queued and the service thread closes the
 * session with IIRD_CLOSE_NOT_READING (the lock is held). */
static void overflow_locked(iird_session *s)
{
    fprintf(stderr,
            "iird serve: session %u: closed (%d): the client does not read its replies (%d "
            "messages, %zu bytes waiting)\n",
            s->id, IIRD_CLOSE_NOT_READING, s->q_count, s->q_reply_bytes);
    s->overflow = true;
    s->close_status = IIRD_CLOSE_NOT_READING;
    s->wake_service = true;
    if (s->env->lws) lws_cancel_service(s->env->lws);
}

/* Whether one more message m fits; makes room by dropping stats or domain messages (the lock is
 * held). A reply that does not fit overflows the session. */
static bool make_room_locked(iird_session *s, const out_msg *m)
{
    if (m->droppable && s->q_droppable >= IIRD_QUEUE_DROPPABLE) drop_oldest_droppable(s);
    if (s->q_count == IIRD_QUEUE_CAP && !drop_oldest_droppable(s)) {
        if (!m->droppable) overflow_locked(s);
        return false;
    }
    if (!m->droppable && s->q_reply_bytes >= IIRD_QUEUE_MAX_BYTES) {
        overflow_locked(s);
        return false;
    }
    return true;
}

void iird_queue_locked(iird_session *s, out_msg msg)
{
    if (s->overflow || !make_room_locked(s, &msg)) {
        free(msg.buf);
        return;
    }
    *q_at(s, s->q_count) = msg;
    s->q_count++;
    q_account(s, &msg, 1);
}

void iird_queue_text_locked(iird_session *s, const char *text, bool droppable)
{
    if (!text) return; /* out of memory building it: nothing to send */
    size_t len = strlen(text);
    out_msg m = {malloc(LWS_PRE + len), len, false, droppable, false};
    if (!m.buf) return;
    memcpy(m.buf + LWS_PRE, text, len);
    iird_queue_locked(s, m);
}

void iird_queue_snapshot_locked(iird_session *s, const char *json, unsigned char *buf, size_t len)
{
    const unsigned char *tail = s->q_count > 0 ? q_at(s, s->q_count - 1)->buf : NULL;
    iird_queue_text_locked(s, json, false);
    out_msg *text = s->q_count > 0 ? q_at(s, s->q_count - 1) : NULL;
    if (text && text->buf != tail) text->snapshot = true; /* queued: the reply's text */
    iird_queue_locked(s, (out_msg){buf, len, true, false, true});
}

void iird_queue_error(iird_session *s, const iird_proto_error *e)
{
    char *json = iird_json_error(e);
    iird_metrics_error(s->env->metrics, e->code);
    pthread_mutex_lock(&s->lock);
    iird_queue_text_locked(s, json, false);
    pthread_mutex_unlock(&s->lock);
    free(json);
}

iird_recording *iird_session_record_start_locked(iird_session *s, int fps, iird_proto_error *err)
{
    char folder[4096];
    iird_scene_cache_folder(s->env->scenes, s->scene, folder, sizeof folder);
    iird_recording *r = iird_recording_create(fps, s->scene->name, folder);
    if (!r) return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory"), NULL;
    s->rec_start_ms = iir_now_ms();
    bool ok = iird_session_record_lights_locked(s, r, 0.0, err) &&
              iird_recording_add_camera(r, 0.0, &s->camera, err) &&
              iird_recording_add_exposure(r, 0.0, s->settings.exposure, err);
    if (!ok) iird_recording_destroy(r), r = NULL;
    return r;
}

void iird_session_record_end_locked(iird_session *s, double t)
{
    iird_recording_set_size(s->rec, s->settings.width, s->settings.height);
    iird_recording_end(s->rec, t);
}

bool iird_session_record_lights_locked(iird_session *s, iird_recording *r, double t,
                                       iird_proto_error *err)
{
    return iird_recording_add_lights(r, t, iird_lights_shown(&s->lights), s->lights.n, err);
}

iird_state_view iird_state_view_locked(const iird_session *s)
{
    const iird_lights *L = &s->lights;
    iird_state_view v = {.scene = s->scene->name,
                         .light = &L->v[L->moved],
                         .camera = &s->camera,
                         .settings = &s->settings,
                         .generation = s->generation,
                         .default_light = L->made_up,
                         .scene_data = s->scene->scene,
                         .lights = L->v,
                         .on = L->on,
                         .num_lights = L->n};
    return v;
}

bool iird_session_take_wake(iird_session *s)
{
    pthread_mutex_lock(&s->lock);
    bool wake = s->wake_service;
    s->wake_service = false;
    pthread_mutex_unlock(&s->lock);
    return wake;
}

void iird_session_close(iird_session *s, int status)
{
    pthread_mutex_lock(&s->lock);
    if (!s->close_status) s->close_status = status;
    pthread_mutex_unlock(&s->lock);
}

void iird_session_close_error(iird_session *s, int status, const iird_proto_error *e)
{
    iird_queue_error(s, e);
    iird_session_close(s, status);
}

/* ======================== writing ======================== */

static double fps_after_send(iird_session *s, double now)
{
    s->sent_ms[s->sent_count % IIRD_FPS_WINDOW] = now;
    s->sent_count++;
    unsigned n = s->sent_count < IIRD_FPS_WINDOW ? s->sent_count : IIRD_FPS_WINDOW, recent = 0;
    for (unsigned i = 0; i < n; i++) recent += now - s->sent_ms[i] <= 1000.0;
    return recent;
}

/* Moves the slot's frame into s->sending and *f (the lock is held). */
static void take_frame_locked(iird_session *s, frame_slot *f)
{
    byte_buf data = s->slot.data;
    *f = s->slot;
    s->slot.data = s->sending;
    s->sending = data;
    s->slot.domain = NULL;
    s->slot.full = false;
    s->sent_id = f->id;
    pthread_cond_broadcast(&s->wake); /* a worker held back by an unsent frame may go on */
}

static bool write_bytes(iird_session *s, struct lws *wsi, unsigned char *payload, size_t len,
                        bool binary)
{
    int n = lws_write(wsi, payload, len, binary ? LWS_WRITE_BINARY : LWS_WRITE_TEXT);
    if (n < (int)len) return false;
    atomic_fetch_add(&s->env->metrics->bytes_sent, len);
    return true;
}

/* Writes the frame, then queues its stats and domain (the lock is not held). */
static bool write_frame(iird_session *s, struct lws *wsi, frame_slot *f)
{
    if (!write_bytes(s, wsi, s->sending.buf + LWS_PRE, f->len, true)) {
        free(f->domain);
        return false;
    }
    double now = iir_now_ms();
    iird_metrics_frame_sent(s->env->metrics, f->method, &f->stats);
    pthread_mutex_lock(&s->lock);
    uint64_t dropped = s->dropped;
    pthread_mutex_unlock(&s->lock);
    iird_stats_view v = {.frame = f->id,
                         .seq = f->seq,
                         .method = f->method,
                         .pass = f->pass,
                         .converged = f->converged,
                         .reencoded = f->reencoded,
                         .stats = &f->stats,
                         .encode_ms = f->encode_ms,
                         .latency_ms = now - f->input_ms,
                         .fps = fps_after_send(s, now),
                         .bytes = f->jpeg_bytes,
                         .dropped = dropped,
                         .memory_bytes = iird_session_memory(s)};
    char *stats = iird_json_stats(&v);
    pthread_mutex_lock(&s->lock);
    iird_queue_text_locked(s, stats, true);
    iird_queue_text_locked(s, f->domain, true);
    pthread_mutex_unlock(&s->lock);
    free(stats);
    free(f->domain);
    return true;
}

static bool more_locked(const iird_session *s)
{
    return s->q_count > 0 || s->slot.full || s->close_status;
}

bool iird_session_overflowed(iird_session *s)
{
    pthread_mutex_lock(&s->lock);
    bool overflow = s->overflow;
    pthread_mutex_unlock(&s->lock);
    return overflow;
}

void iird_session_close_not_reading(struct lws *wsi)
{
    static const char why[] = "the client does not read: too many replies waiting";
    lws_close_reason(wsi, (enum lws_close_status)IIRD_CLOSE_NOT_READING, (unsigned char *)why,
                     sizeof why - 1);
}

iird_write_result iird_session_write(iird_session *s, struct lws *wsi)
{
    if (iird_session_overflowed(s)) { /* nothing queued goes: close now, even while choked */
        iird_session_close_not_reading(wsi);
        return IIRD_WRITE_CLOSE;
    }
    if (lws_send_pipe_choked(wsi)) return IIRD_WRITE_MORE;
    bool ok = true;
    pthread_mutex_lock(&s->lock);
    if (s->q_count > 0) {
        out_msg m = s->queue[s->q_head];
        s->q_head = (s->q_head + 1) % IIRD_QUEUE_CAP;
        s->q_count--;
        q_account(s, &m, -1);
        pthread_mutex_unlock(&s->lock);
        ok = write_bytes(s, wsi, m.buf + LWS_PRE, m.len, m.binary);
        free(m.buf);
        if (m.snapshot && m.binary) { /* the snapshot is out: the next may be asked for */
            pthread_mutex_lock(&s->lock);
            iird_budget_release(s->env->budget, &s->snapshot_held);
            s->snapshot_busy = false;
            pthread_mutex_unlock(&s->lock);
        }
    } else if (s->close_status) { /* after the replies, before any further frame */
        int status = s->close_status;
        pthread_mutex_unlock(&s->lock);
        lws_close_reason(wsi, (enum lws_close_status)status, NULL, 0);
        return IIRD_WRITE_CLOSE;
    } else if (s->slot.full) {
        frame_slot f;
        take_frame_locked(s, &f);
        pthread_mutex_unlock(&s->lock);
        ok = write_frame(s, wsi, &f);
    } else {
        pthread_mutex_unlock(&s->lock);
        return IIRD_WRITE_IDLE;
    }
    if (!ok) return IIRD_WRITE_CLOSE;
    pthread_mutex_lock(&s->lock);
    bool more = more_locked(s);
    pthread_mutex_unlock(&s->lock);
    return more ? IIRD_WRITE_MORE : IIRD_WRITE_IDLE;
}

void iird_session_alternatives(const iir_light *lights, uint32_t num_lights, const char *except,
                               char *out, size_t n)
{
    const char *ok[16];
    int k = 0;
    iir_error err;
    for (const char *const *m = iir_method_names(); *m && k < 16; m++)
        if (strcmp(*m, except) && iir_method_supports(*m, lights, num_lights, &err) == IIR_OK)
            ok[k++] = *m;
    size_t used = (size_t)snprintf(out, n, "%s", k ? " -- try " : "");
    for (int i = 0; i < k && used < n; i++)
        used += (size_t)snprintf(out + used, n - used, "%s%s",
                                 i == 0       ? ""
                                 : i == k - 1 ? " or "
                                              : ", ",
                                 ok[i]);
}

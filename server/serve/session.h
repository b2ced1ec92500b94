/* session.h -- one WebSocket client of `iird serve`: its state (lights, camera, settings, scene),
 * its render worker, and what it sends back. Not the lws context or the HTTP side (server.c).
 *
 * DESIGN. Two threads touch a session.
 *  - The service thread (the one running lws_service) feeds it client messages
 *    (iird_session_receive), which are parsed, validated and applied all or nothing to the state,
 *    and writes its output one message per writable callback (iird_session_write).
 *  - The session's render worker (a pthread) renders the newest state, encodes a JPEG, and
 *    publishes the frame into a one-frame slot, replacing an unsent one (input is latest-wins and
 *    so is output: a slow client gets fewer frames, never a queue). It then asks the service
 *    thread to write by calling lws_cancel_service; it calls no other lws function. It renders at
 *    most one frame ahead of what was sent. When nothing changes it refines the frame
 *    progressively up to convergence, then sleeps on a condition variable (no CPU).
 * The session's mutex guards the state, the output queue and the frame slot; neither thread holds
 * it during a render, an encode, or a write. A session whose client left is stopped without
 * blocking (iird_session_request_stop) and freed once its worker has finished (server.c reaps it).
 */
#ifndef IIRD_SESSION_H
#define IIRD_SESSION_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "prometheus.h"
#include "protocol/protocol.h"
#include "scene_cache.h"

struct lws;
struct lws_context;

/* What every session shares; read-only while sessions exist. */
typedef struct iird_session_env {
    struct lws_context *lws; /* woken with lws_cancel_service by the workers */
    iird_scene_cache *scenes;
    iird_metrics *metrics;
    iird_limits limits;
    iird_settings defaults;          /* the state of a new session */
    const iird_scene_entry *startup; /* the scene a new session shows (pinned) */
    const char *token;               /* NULL: hello needs no token */
    struct iird_budget *budget;      /* memory reservations (budget.h); NULL: no limits */
    struct iird_sched *sched;        /* who renders when (scheduler.h) */
    struct iird_saves *saves;        /* named saves' limits (scene_save.h); NULL: none */
} iird_session_env;

typedef struct iird_session iird_session;

/* Bytes a session with these settings will allocate: the frame, the JPEG encoder and three frame
 * buffers, the receive buffer, and its method's own estimate (iir_method_memory). What the memory
 * budget reserves and /metrics reports. */
uint64_t iird_session_estimate(const iird_settings *st);

/* A new session on the startup scene with the default settings, its worker started (waiting for
 * hello). NULL with err filled when out of memory, when the default settings do not fit the
 * daemon's memory budget beside the other sessions, or when the thread cannot start. */
iird_session *iird_session_create(const iird_session_env *env, uint32_t id, iir_error *err);

/* The client's address as server.c counts it (per-address limits); service thread. */
void iird_session_set_address(iird_session *s, const char *addr);

/* Asks the worker to stop after its current step; does not block. */
void iird_session_request_stop(iird_session *s);
/* True once the worker has returned (joining will not block). */
bool iird_session_worker_done(iird_session *s);
/* Stops the worker, joins it and frees everything. Blocks for at most the current render step.
 * NULL is ignored. */
void iird_session_destroy(iird_session *s);

uint32_t iird_session_id(const iird_session *s);
/* True once the client's hello was accepted (service thread only). */
bool iird_session_greeted(const iird_session *s);
/* Estimated bytes the session holds (images, method, encoder, frames; docs/architecture.md). */
uint64_t iird_session_memory(iird_session *s);
/* Render time the session has used so far, in seconds (its turns on the cores, scheduler.h). */
double iird_session_render_seconds(iird_session *s);

/* ---- service thread only ---- */

/* One received piece of a WebSocket message; final marks its last piece. Complete messages are
 * handled at once: replies go to the output queue, state changes to the worker. */
void iird_session_receive(iird_session *s, const void *data, size_t len, bool final, bool binary);

/* True (once) after the worker queued output: the caller then asks lws for a writable callback. */
bool iird_session_take_wake(iird_session *s);

/* Queues a close with this WebSocket status after the pending output (shutdown: 1001). */
void iird_session_close(iird_session *s, int status);
/* Queues the error e (counted in the metrics), then a close with this status. */
void iird_session_close_error(iird_session *s, int status, const iird_proto_error *e);

typedef enum iird_write_result {
    IIRD_WRITE_IDLE, /* nothing more to send now */
    IIRD_WRITE_MORE, /* more is waiting: ask for another writable callback */
    IIRD_WRITE_CLOSE /* close the connection now (the close reason is set) */
} iird_write_result;

/* Writes at most one message to wsi: queued replies first, then a pending close (returns
 * IIRD_WRITE_CLOSE with the reason set), then the newest frame (its stats and domain are queued
 * behind it). Nothing while lws_send_pipe_choked. On a write error returns IIRD_WRITE_CLOSE; a
 * session that overflowed (below) returns it at once, choked or not. */
iird_write_result iird_session_write(iird_session *s, struct lws *wsi);

/* True once the client let more replies wait than the output queue's caps allow (it does not
 * read): replies are never dropped, so the session must be closed (any thread). */
bool iird_session_overflowed(iird_session *s);
/* Sets wsi's close reason for such a client: 1008 (policy violation) with a text. */
void iird_session_close_not_reading(struct lws *wsi);

#endif

/* session_internal.h -- the session's struct, shared by its files: session.c (life, output
 * queue, frame slot), session_msg.c (client messages, service thread), session_worker.c (the
 * render worker). Not part of the session's interface (session.h). */
#ifndef IIRD_SESSION_INTERNAL_H
#define IIRD_SESSION_INTERNAL_H

#include <pthread.h>
#include <stdatomic.h>

#include "iir/image.h"
#include "iir/method.h"
#include "scheduler.h"
#include "session.h"
#include "session_lights.h"

enum {
    IIRD_QUEUE_CAP = 1024,          /* queued messages at most: more replies waiting than this (a
                                       client that does not read) closes the session */
    IIRD_QUEUE_DROPPABLE = 32,      /* stats and domain messages waiting at most: the oldest go */
    IIRD_QUEUE_MAX_BYTES = 4 << 20, /* reply bytes waiting at most (a snapshot's file aside) */
    IIRD_CLOSE_NOT_READING = 1008,  /* policy violation: the client does not read its replies */
    IIRD_REFINE_IDLE_MS = 250,      /* no input for this long before refinement starts */
    IIRD_RATE_PER_S = 250,          /* token bucket refill */
    IIRD_RATE_BURST = 500,          /* token bucket size */
    IIRD_FPS_WINDOW = 128,          /* send times kept for the fps figure */
    IIRD_DOMAIN_MIN_MS = 100,       /* domain messages at most this often while frames stream */
    IIRD_FRAME_PATIENCE_MS = 250,   /* newer input stops a frame only after it ran this long, or 3x
                                       the last frame's time (at most IIRD_FRAME_PATIENCE_MAX_MS), so
                                       a drag still shows frames on a loaded machine; refinement
                                       stops at once */
    IIRD_FRAME_PATIENCE_MAX_MS = 1000,
    IIRD_WORKER_NICE =
        5, /* render workers (and their OpenMP threads) yield to the service thread */
};

/* One queued outgoing message: LWS_PRE bytes of headroom, then len bytes. */
typedef struct out_msg {
    unsigned char *buf;
    size_t len;
    bool binary;
    bool droppable; /* stats and domain: the only messages ever dropped (latest-wins) */
    bool snapshot;  /* a snapshot's reply or its binary part: not counted in the byte cap */
} out_msg;

/* A growable byte buffer with LWS_PRE headroom in front of the data. */
typedef struct byte_buf {
    unsigned char *buf;
    size_t cap; /* bytes after the headroom */
} byte_buf;

/* The newest published frame and what its stats message needs. */
typedef struct frame_slot {
    byte_buf data; /* header + JPEG after the headroom */
    size_t len;
    bool full;
    uint32_t id, pass;
    bool converged;
    bool reencoded;  /* the last image again, only its encoding changed: not rendered */
    int64_t seq;     /* of the newest input the frame shows, IIRD_NO_SEQ: none yet */
    double input_ms; /* when that input was received */
    double encode_ms;
    size_t jpeg_bytes;
    char method[16];
    iir_frame_stats stats;
    char *domain; /* JSON, or NULL */
} frame_slot;

/* A copy of the state the worker renders (taken under the lock). */
typedef struct render_job {
    uint64_t version;
    uint32_t generation;
    const iir_light *lights; /* [num_lights] as rendered (iird_lights_shown), in a worker buffer */
    uint32_t num_lights;
    iir_camera camera;
    iird_settings settings;
    int64_t seq;
    double input_ms;
} render_job;

/* Worker-only state. */
typedef struct worker_state {
    iir_method *method;
    char method_name[16];
    const iird_scene_entry *method_scene;
    bool refining;       /* the method call under way is a refinement pass (the stop hook) */
    uint64_t extra_held; /* bytes reserved in env->budget beyond the session's `reserved`: what
                            the method's real counts on its scene add to the estimate from its
                            parameters (reserve_real_size; the worker's own) */
    iird_settings method_settings;    /* the settings `method` was made with (a refused switch
                                         goes back to them) */
    const iird_scene_entry *creating; /* the method is being created (or re-created by new
                                         parameters) for this scene, for job `last` (the stop
                                         hook's creation rule); NULL otherwise */
    double started_ms;  /* the session's render time (scheduler.h) when the call under way
                           started: patience counts its turns on the cores, not its waits */
    double patience_ms; /* how long newer input lets the frame under way run (see should_stop) */
    iir_image *img;
    iir_jpeg_encoder *enc;
    byte_buf back; /* the frame being built; swapped with the slot's on publish */
    iir_light *job_lights, *last_lights; /* the next job's lights and last's (swapped) */
    uint32_t job_cap, last_cap;
    render_job last; /* the last job rendered (version 0: none); its lights are last_lights */
    iir_frame_stats last_stats;
    iir_vpl_counts frame_vpl; /* the VPL set of the last interactive frame (refinement keeps it) */
    bool have_frame;          /* img holds last's frame */
    uint32_t pass;            /* refinement passes on it */
    bool converged;
    uint32_t next_id, last_id;
    float (*vpl_px)[2];
    uint8_t *vpl_flags;
    uint32_t vpl_cap;
    double domain_ms;    /* when the last domain message was built */
    bool domain_stale;   /* the newest interactive frame's domain is not sent yet */
    uint32_t domain_for; /* that frame's id */
} worker_state;

struct iird_session {
    const iird_session_env *env;
    uint32_t id;
    char addr[64]; /* the client's address (server.c), for the per-address save rate */
    pthread_t thread;
    bool thread_started;
    pthread_mutex_t lock;
    pthread_cond_t wake; /* the worker waits on it; signalled on input, stop and sent frames */

    /* ---- guarded by lock ---- */
    const iird_scene_entry *scene; /* written by the worker (scene loads), read by both */
    iird_lights lights;            /* the scene's, moved and switched by `light` messages */
    iir_camera camera;
    iird_settings settings;
    _Atomic uint64_t version; /* bumped by every applied input; also read without the lock by
                                 refinement's stop hook */
    int64_t seq;              /* newest input's seq (IIRD_NO_SEQ: none) */
    uint32_t generation; /* bumped by every accepted params and scene switch (frames carry it) */
    double input_ms;     /* when it was received */
    bool ready;          /* hello received: the worker may render */
    atomic_bool stop;    /* read without the lock by refinement's stop hook */
    bool worker_done;
    bool scene_pending;
    char scene_name[130];
    int64_t scene_seq;
    uint64_t scene_version; /* `version` when it was asked: a frame after the switch answers the
                               newest input, which is the switch's only if none came since */
    bool snapshot_pending, snapshot_exr;
    bool snapshot_busy;     /* one requested and not yet written out (at most one per session) */
    uint64_t snapshot_held; /* its bytes, reserved in env->budget while queued */
    int64_t snapshot_seq;
    out_msg queue[IIRD_QUEUE_CAP]; /* a ring: replies are never dropped; stats and domain are */
    int q_head, q_count;
    int q_droppable;      /* stats and domain messages in the queue */
    size_t q_reply_bytes; /* bytes of the queued replies (snapshot files aside) */
    bool overflow;        /* more replies waiting than the caps allow: the session is closed with
                             IIRD_CLOSE_NOT_READING and nothing more is queued */
    frame_slot slot;
    uint32_t sent_id;  /* id of the last frame handed to lws */
    bool wake_service; /* the worker queued output since the service thread last looked */
    uint64_t dropped;
    int close_status; /* 0: none; else close with it once the queue is empty */

    iird_sched_entity sched; /* its place in env->sched (worker: enter/leave; threads: yield) */
    bool sched_added;

    _Atomic uint64_t memory_bytes;
    uint64_t reserved; /* bytes held in env->budget (service thread; destroy) */

    /* ---- service thread only ---- */
    bool hello_ok;
    char *rx;
    size_t rx_len;
    bool rx_too_large;
    double tokens, tokens_ms, rate_error_ms;
    iird_recording *rec;
    double rec_start_ms;
    byte_buf sending; /* the frame being written (taken from the slot) */
    double sent_ms[IIRD_FPS_WINDOW];
    unsigned sent_count;

    worker_state w;
};

/* ---- session.c ---- */
bool iird_buf_reserve(byte_buf *b, size_t n);
void iird_buf_free(byte_buf *b);
/* Queues a copy of text (with the lock held). */
void iird_queue_text_locked(iird_session *s, const char *text, bool droppable);
/* Queues msg, taking ownership of buf (with the lock held). Replies are never dropped: one that
 * does not fit overflows the session (it is closed); stats and domain messages may be. */
void iird_queue_locked(iird_session *s, out_msg msg);
/* Queues a snapshot's reply (a copy of json) and its binary message (buf, LWS_PRE headroom, len
 * bytes; taken), marked as the snapshot's two parts (with the lock held). */
void iird_queue_snapshot_locked(iird_session *s, const char *json, unsigned char *buf, size_t len);
/* Queues an error reply (locks); counts it in the metrics. */
void iird_queue_error(iird_session *s, const iird_proto_error *e);
/* The session's state as the protocol's JSON builders read it (lock held). */
iird_state_view iird_state_view_locked(const iird_session *s);
/* A new recording of the session's scene (naming the folder that finds it) whose first keys
 * (t = 0) are the current lights, camera and exposure; NULL with err filled on out-of-memory.
 * Lock held. */
iird_recording *iird_session_record_start_locked(iird_session *s, int fps, iird_proto_error *err);
/* Ends s->rec at t seconds since its start, naming the session's frame size now (the size a
 * replay renders at). Lock held. */
void iird_session_record_end_locked(iird_session *s, double t);
/* Adds the session's lights as rendered to recording r at t seconds; false with err filled as the
 * recording's add functions do (r is then unchanged). Lock held. */
bool iird_session_record_lights_locked(iird_session *s, iird_recording *r, double t,
                                       iird_proto_error *err);

/* " -- try ir or pt": the methods that can render these lights, other than `except`, as the end of
 * an `unsupported` message ("" when none can). */
void iird_session_alternatives(const iir_light *lights, uint32_t num_lights, const char *except,
                               char *out, size_t n);

/* ---- session_msg.c ---- */
void iird_session_handle(iird_session *s, const char *text, size_t len);

/* ---- session_worker.c ---- */
void *iird_session_worker(void *arg);
void iird_worker_free(worker_state *w);

#endif

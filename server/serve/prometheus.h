/* prometheus.h -- the daemon's counters and the frame-time histogram, and the two texts built from
 * them: GET /metrics (Prometheus text format 0.0.4, names in docs/protocol.md) and GET /healthz
 * (JSON). Not the per-frame `stats` message (protocol.h) and not who calls what (server.c).
 *
 * Threads: every counter is a C11 atomic, so render workers (frames dropped) and the service
 * thread (everything else) update them without a lock. The texts are built on the service thread.
 */
#ifndef IIRD_METRICS_H
#define IIRD_METRICS_H

#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>

#include "iir/method.h"
#include "protocol/protocol.h"
#include "scheduler.h"

/* Upper bounds of the frame-time histogram buckets in seconds, +Inf implied after the last. */
#define IIRD_FRAME_BUCKETS 9
/* Methods the per-method totals have room for (iir_method_names' order). */
#define IIRD_METRICS_METHODS 16

typedef struct iird_metrics {
    double start_ms; /* iir_now_ms() at start, for the uptime */
    atomic_int sessions;
    atomic_uint_fast64_t sessions_total;
    atomic_uint_fast64_t frames_sent, frames_dropped, bytes_sent, messages;
    atomic_uint_fast64_t errors[IIRD_E_COUNT];
    atomic_uint_fast64_t frame_buckets[IIRD_FRAME_BUCKETS + 1]; /* per bucket, not cumulative */
    atomic_uint_fast64_t frame_us_sum;                          /* sum of render times, us */
    /* per method (iir_method_names' order): the time of each phase it declares, us, and its
     * IIR_COUNTER_EVENTS counters, over the frames sent */
    atomic_uint_fast64_t phase_us[IIRD_METRICS_METHODS][IIR_PHASE_COUNT];
    atomic_uint_fast64_t counter[IIRD_METRICS_METHODS][IIR_MAX_COUNTERS];
    /* the form-factor cache's folder (iir/ffcache.h), read at each /metrics (service thread) */
    char ffcache_dir[1024];
    uint64_t ffcache_max;
    int ffcache_watch;          /* inotify on the folder's deletions, -1 until it exists */
    uint64_t ffcache_evictions; /* cache files deleted from the folder since start */
} iird_metrics;

/* One open session as the memory gauge reports it. */
typedef struct iird_metrics_session {
    uint32_t session;
    uint64_t bytes;
    double render_s; /* render time it has used (scheduler.h) */
} iird_metrics_session;

/* Zeroes m; takes the form-factor cache's folder and cap from the environment (after
 * --cache-max set it). */
void iird_metrics_init(iird_metrics *m);

/* Counts one sent frame of method `method` and its stats (render time, phases, counters). */
void iird_metrics_frame_sent(iird_metrics *m, const char *method, const iir_frame_stats *st);
void iird_metrics_error(iird_metrics *m, iird_err code);

/* The /metrics text: malloc'd, NUL-terminated; NULL only when out of memory. Counts the cache
 * folder's deletions since the last call first (service thread). */
char *iird_metrics_prometheus(iird_metrics *m, const iird_metrics_session *sessions,
                              size_t num_sessions, const iird_sched_stats *sched,
                              size_t scenes_loaded, uint64_t scene_bytes);

/* The /healthz and /livez JSON: {"status":STATUS,"sessions":N,"uptime_s":S} (STATUS "ok", "full",
 * "draining" or "alive"); malloc'd, NULL when out of memory. */
char *iird_metrics_healthz(const iird_metrics *m, const char *status);

#endif

/* prometheus.c -- the daemon's counters and the /metrics and /healthz texts, and the form-factor
 * cache folder's size and deletions (inotify); not the stats message. */
#include "prometheus.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/inotify.h>
#include <unistd.h>

#include "iir/ffcache.h"
#include "iir/timer.h"

static const double frame_bucket_s[IIRD_FRAME_BUCKETS] = {0.005, 0.01, 0.025, 0.05, 0.1,
                                                          0.25,  0.5,  1.0,   2.5};

/* ---- the form-factor cache ---- */

/* A cache file's name: 16 hex digits and ".ff" (what a trim evicts). */
static bool is_cache_file(const char *name)
{
    return strlen(name) == 19 && strspn(name, "0123456789abcdefABCDEF") == 16 &&
           !strcmp(name + 16, ".ff");
}

/* Counts the cache files deleted since the last look (the watch starts once the folder exists;
 * a full kernel queue loses some: the count is then low). */
static void count_evictions(iird_metrics *m)
{
    if (m->ffcache_watch < 0 && m->ffcache_dir[0]) {
        int fd = inotify_init1(IN_NONBLOCK | IN_CLOEXEC);
        if (fd >= 0 && inotify_add_watch(fd, m->ffcache_dir, IN_DELETE) < 0) close(fd), fd = -1;
        m->ffcache_watch = fd;
        return;
    }
    char buf[8192] __attribute__((aligned(__alignof__(struct inotify_event))));
    ssize_t len;
    while (m->ffcache_watch >= 0 && (len = read(m->ffcache_watch, buf, sizeof buf)) > 0)
        for (char *p = buf; p < buf + len;) {
            const struct inotify_event *e = (const struct inotify_event *)p;
            if ((e->mask & IN_DELETE) && e->len && is_cache_file(e->name)) m->ffcache_evictions++;
            if (e->mask & IN_IGNORED) close(m->ffcache_watch), m->ffcache_watch = -1;
            p += sizeof *e + e->len;
        }
}

void iird_metrics_init(iird_metrics *m)
{
    memset(m, 0, sizeof *m);
    m->start_ms = iir_now_ms();
    atomic_init(&m->sessions, 0);
    iir_ffcache_config(m->ffcache_dir, sizeof m->ffcache_dir, &m->ffcache_max);
    m->ffcache_watch = -1;
    count_evictions(m); /* starts the watch when the folder exists */
}

/* Index of method `name` among iir_method_names, or -1. */
static int method_index(const char *name)
{
    const char *const *names = iir_method_names();
    for (int i = 0; names[i] && i < IIRD_METRICS_METHODS; i++)
        if (name && !strcmp(names[i], name)) return i;
    return -1;
}

static uint_fast64_t micros(double ms)
{
    return (uint_fast64_t)(ms > 0 ? ms * 1e3 : 0);
}

/* Adds the frame's declared phases and event counters to method `method`'s totals. */
static void add_method_totals(iird_metrics *m, const char *method, const iir_frame_stats *st)
{
    int k = method_index(method);
    if (k < 0) return;
    const iir_phase *ph;
    int n = iir_method_phases(method, &ph);
    for (int i = 0; i < n; i++)
        atomic_fetch_add(&m->phase_us[k][ph[i]], micros(st->phase_ms[ph[i]]));
    const iir_counter *c;
    n = iir_method_counters(method, &c);
    for (int i = 0; i < n; i++)
        if (c[i].kind == IIR_COUNTER_EVENTS)
            atomic_fetch_add(&m->counter[k][i], (uint_fast64_t)st->counter[i]);
}

void iird_metrics_frame_sent(iird_metrics *m, const char *method, const iir_frame_stats *st)
{
    double render_ms = st->total_ms;
    add_method_totals(m, method, st);
    double s = render_ms / 1e3;
    int b = 0;
    while (b < IIRD_FRAME_BUCKETS && s > frame_bucket_s[b]) b++;
    atomic_fetch_add(&m->frame_buckets[b], 1);
    atomic_fetch_add(&m->frame_us_sum, micros(render_ms));
    atomic_fetch_add(&m->frames_sent, 1);
}

void iird_metrics_error(iird_metrics *m, iird_err code)
{
    if ((int)code >= 0 && code < IIRD_E_COUNT) atomic_fetch_add(&m->errors[code], 1);
}

static unsigned long long load(const atomic_uint_fast64_t *v)
{
    return (unsigned long long)atomic_load(v);
}

static void metric_head(FILE *f, const char *name, const char *type, const char *help)
{
    fprintf(f, "# HELP %s %s\n# TYPE %s %s\n", name, help, name, type);
}

static void section_sessions(FILE *f, const iird_metrics *m, const iird_metrics_session *sessions,
                             size_t n)
{
    metric_head(f, "iird_sessions", "gauge", "Open WebSocket sessions.");
    fprintf(f, "iird_sessions %d\n", atomic_load(&m->sessions));
    metric_head(f, "iird_sessions_total", "counter", "Sessions ever opened.");
    fprintf(f, "iird_sessions_total %llu\n", load(&m->sessions_total));
    metric_head(f, "iird_session_memory_bytes", "gauge",
                "Estimated memory of each open session (images, method, encoder, frames).");
    for (size_t i = 0; i < n; i++)
        fprintf(f, "iird_session_memory_bytes{session=\"%u\"} %llu\n", sessions[i].session,
                (unsigned long long)sessions[i].bytes);
    metric_head(f, "iird_session_render_seconds_total", "counter",
                "Render time each open session has used (its turns on the cores).");
    for (size_t i = 0; i < n; i++)
        fprintf(f, "iird_session_render_seconds_total{session=\"%u\"} %.6f\n", sessions[i].session,
                sessions[i].render_s);
}

static void section_sched(FILE *f, const iird_sched_stats *st)
{
    metric_head(f, "iird_render_slots", "gauge", "Sessions that may render at once.");
    fprintf(f, "iird_render_slots %d\n", st->slots);
    metric_head(f, "iird_sessions_rendering", "gauge", "Sessions rendering now.");
    fprintf(f, "iird_sessions_rendering %d\n", st->running);
    metric_head(f, "iird_sessions_waiting", "gauge", "Sessions waiting for their turn to render.");
    fprintf(f, "iird_sessions_waiting %d\n", st->waiting);
    metric_head(f, "iird_render_handovers_total", "counter",
                "Turns on the cores ended for another session (slice over or preempted).");
    fprintf(f, "iird_render_handovers_total %llu\n", (unsigned long long)st->handovers);
    metric_head(f, "iird_render_wait_seconds_total", "counter",
                "Time sessions waited for their turn to render.");
    fprintf(f, "iird_render_wait_seconds_total %.6f\n", st->wait_ms / 1e3);
}

static void section_frames(FILE *f, const iird_metrics *m)
{
    metric_head(f, "iird_frames_sent_total", "counter", "Frames sent.");
    fprintf(f, "iird_frames_sent_total %llu\n", load(&m->frames_sent));
    metric_head(f, "iird_frames_dropped_total", "counter", "Frames replaced before sending.");
    fprintf(f, "iird_frames_dropped_total %llu\n", load(&m->frames_dropped));
    metric_head(f, "iird_frame_seconds", "histogram", "Render time of sent frames.");
    unsigned long long cum = 0;
    for (int b = 0; b < IIRD_FRAME_BUCKETS; b++) {
        cum += load(&m->frame_buckets[b]);
        fprintf(f, "iird_frame_seconds_bucket{le=\"%g\"} %llu\n", frame_bucket_s[b], cum);
    }
    cum += load(&m->frame_buckets[IIRD_FRAME_BUCKETS]);
    fprintf(f, "iird_frame_seconds_bucket{le=\"+Inf\"} %llu\n", cum);
    fprintf(f, "iird_frame_seconds_sum %.6f\n", (double)load(&m->frame_us_sum) / 1e6);
    fprintf(f, "iird_frame_seconds_count %llu\n", cum);
}

/* Every method's declared phases and event counters, summed over the frames sent (a method no
 * frame used shows zeros: the series exist from the start). */
static void section_methods(FILE *f, const iird_metrics *m)
{
    const char *const *names = iir_method_names();
    metric_head(f, "iird_phase_seconds_total", "counter",
                "Render time of sent frames by method and the phases it declares.");
    for (int k = 0; names[k] && k < IIRD_METRICS_METHODS; k++) {
        const iir_phase *ph;
        int n = iir_method_phases(names[k], &ph);
        for (int i = 0; i < n; i++)
            fprintf(f, "iird_phase_seconds_total{method=\"%s\",phase=\"%s\"} %.6f\n", names[k],
                    iir_phase_name(ph[i]), (double)load(&m->phase_us[k][ph[i]]) / 1e6);
    }
    metric_head(f, "iird_method_events_total", "counter",
                "The event counters methods declare (iir_counter), summed over the frames sent.");
    for (int k = 0; names[k] && k < IIRD_METRICS_METHODS; k++) {
        const iir_counter *c;
        int n = iir_method_counters(names[k], &c);
        for (int i = 0; i < n; i++)
            if (c[i].kind == IIR_COUNTER_EVENTS)
                fprintf(f, "iird_method_events_total{method=\"%s\",counter=\"%s\"} %llu\n",
                        names[k], c[i].name, load(&m->counter[k][i]));
    }
}

static void section_traffic(FILE *f, const iird_metrics *m)
{
    metric_head(f, "iird_bytes_sent_total", "counter", "WebSocket payload bytes sent.");
    fprintf(f, "iird_bytes_sent_total %llu\n", load(&m->bytes_sent));
    metric_head(f, "iird_messages_total", "counter", "Client messages received.");
    fprintf(f, "iird_messages_total %llu\n", load(&m->messages));
    metric_head(f, "iird_errors_total", "counter", "Error replies by code.");
    for (int c = 0; c < IIRD_E_COUNT; c++)
        fprintf(f, "iird_errors_total{code=\"%s\"} %llu\n", iird_err_name((iird_err)c),
                load(&m->errors[c]));
}

/* The process's resident set from /proc/self/statm (its second field, in pages); left out where
 * there is no /proc. */
static void section_process(FILE *f)
{
    unsigned long long size = 0, resident = 0;
    FILE *statm = fopen("/proc/self/statm", "r");
    int n = statm ? fscanf(statm, "%llu %llu", &size, &resident) : 0;
    if (statm) fclose(statm);
    long page = sysconf(_SC_PAGESIZE);
    if (n != 2 || page <= 0) return;
    metric_head(f, "process_resident_memory_bytes", "gauge", "Resident memory size in bytes.");
    fprintf(f, "process_resident_memory_bytes %llu\n", resident * (unsigned long long)page);
}

static void section_ffcache(FILE *f, iird_metrics *m)
{
    count_evictions(m);
    uint64_t bytes = 0, files = 0;
    if (m->ffcache_dir[0]) iir_ffcache_usage(m->ffcache_dir, &bytes, &files);
    metric_head(f, "iird_ffcache_bytes", "gauge", "Bytes of the form-factor cache's files.");
    fprintf(f, "iird_ffcache_bytes %llu\n", (unsigned long long)bytes);
    metric_head(f, "iird_ffcache_files", "gauge", "Files in the form-factor cache.");
    fprintf(f, "iird_ffcache_files %llu\n", (unsigned long long)files);
    metric_head(f, "iird_ffcache_max_bytes", "gauge",
                "The form-factor cache's cap (--cache-max): least recently used files go.");
    fprintf(f, "iird_ffcache_max_bytes %llu\n", (unsigned long long)m->ffcache_max);
    metric_head(
        f, "iird_ffcache_evictions_total", "counter",
        "Form-factor cache files deleted from the folder since start (evicted by the cap).");
    fprintf(f, "iird_ffcache_evictions_total %llu\n", (unsigned long long)m->ffcache_evictions);
}

char *iird_metrics_prometheus(iird_metrics *m, const iird_metrics_session *sessions,
                              size_t num_sessions, const iird_sched_stats *sched,
                              size_t scenes_loaded, uint64_t scene_bytes)
{
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    if (!f) return NULL;
    section_sessions(f, m, sessions, num_sessions);
    section_sched(f, sched);
    section_frames(f, m);
    section_methods(f, m);
    section_traffic(f, m);
    metric_head(f, "iird_scenes_loaded", "gauge", "Scenes in memory.");
    fprintf(f, "iird_scenes_loaded %zu\n", scenes_loaded);
    metric_head(f, "iird_scene_bytes", "gauge",
                "Bytes the scenes in memory hold: geometry, materials, decoded textures.");
    fprintf(f, "iird_scene_bytes %llu\n", (unsigned long long)scene_bytes);
    section_ffcache(f, m);
    metric_head(f, "iird_uptime_seconds", "gauge", "Seconds since start.");
    fprintf(f, "iird_uptime_seconds %.3f\n", (iir_now_ms() - m->start_ms) / 1e3);
    section_process(f);
    if (fclose(f) != 0) {
        free(text);
        return NULL;
    }
    return text;
}

char *iird_metrics_healthz(const iird_metrics *m, const char *status)
{
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    if (!f) return NULL;
    fprintf(f, "{\"status\":\"%s\",\"sessions\":%d,\"uptime_s\":%.3f}\n", status,
            atomic_load(&m->sessions), (iir_now_ms() - m->start_ms) / 1e3);
    if (fclose(f) != 0) {
        free(text);
        return NULL;
    }
    return text;
}

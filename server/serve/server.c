/* server.c -- the libwebsockets daemon of `iird serve`: context, protocols and mounts, the
 * handshake checks, the WebSocket protocol callback that drives sessions, /healthz and /metrics,
 * signals and shutdown. Not the per-client logic (session*.c).
 *
 * THREADS. The main thread runs lws_service and is the only thread that calls lws (except
 * lws_cancel_service). Each session has a render worker (session_worker.c) that publishes frames
 * and wakes the main thread with lws_cancel_service; the protocol callback then, on
 * LWS_CALLBACK_EVENT_WAIT_CANCELLED, only asks for writable callbacks for the sessions that have
 * output, and on LWS_CALLBACK_SERVER_WRITEABLE writes one message and asks again if more is
 * waiting. SIGINT, SIGTERM, SIGHUP and SIGQUIT (and the ignored ones: signal_set) are blocked in
 * every thread and taken by a small signal thread (sigwait), which sets the stop flag and wakes
 * the service loop the same way.
 * A session whose client left is told to stop and parked on the `closing` list; it is freed when
 * its worker has returned (it wakes the service thread once more on its way out), so a client
 * that vanishes mid-render never blocks the service thread. Until then it keeps its slot: it
 * counts against --max-sessions and --max-sessions-per-address and in the sessions and memory
 * gauges, since its worker may still be rendering. */
#include "server.h"

#include <arpa/inet.h>
#include <errno.h>
#include <limits.h>
#include <malloc.h>
#include <netdb.h>
#include <pthread.h>
#include <signal.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <libwebsockets.h>

#include <omp.h>

#include "iir/timer.h"
#include "prometheus.h"
#include "scene_cache.h"
#include "scene_save.h"
#include "scheduler.h"
#include "session.h"

/* Why a connection was refused a session (it gets one busy error, then close 1013). */
typedef enum busy_reason { NOT_BUSY, BUSY_SERVER, BUSY_ADDRESS, BUSY_DRAINING } busy_reason;

enum { ADDR_BYTES = 64 };

/* Per WebSocket connection (lws allocates and zeroes it). */
typedef struct conn {
    struct lws *wsi;
    iird_session *session; /* NULL for a refused (busy) connection and after close */
    busy_reason busy;
    bool linked;
    bool failing;          /* lws (or we) started closing it: nothing more is written */
    char addr[ADDR_BYTES]; /* the peer's IP address, for --max-sessions-per-address */
    bool local;            /* a direct peer on the loopback address (not via --trust-proxy) */
    struct conn *next;
} conn;

/* Per HTTP request to /healthz or /metrics. */
typedef struct http_req {
    unsigned char *body; /* LWS_PRE headroom, then len bytes */
    size_t len;
} http_req;

/* A session whose client left, until its worker has returned: it still holds its slot. */
typedef struct closing {
    iird_session *session;
    char addr[ADDR_BYTES];
    struct closing *next;
} closing;

typedef struct server {
    const iird_server_config *cfg;
    struct lws_context *ctx;
    pthread_mutex_t ctx_lock; /* guards ctx against the signal thread while it is made or freed */
    iird_metrics metrics;
    iird_scene_cache *scenes;
    const iird_scene_entry *startup;
    iird_session_env env;
    iird_sched *sched;
    iird_saves *saves; /* named saves' limits; service thread */
    conn *conns;       /* every open WebSocket connection */
    closing *closing;
    int active; /* sessions whose worker has not returned: open ones and closing ones */
    uint32_t next_id;
    atomic_int stop;
    atomic_int draining;          /* set by the signal thread at the first SIGTERM */
    double drain_until;           /* ms: the drain's end (0 until the service loop sees it) */
    int port;                     /* the listening port (cfg->port may be 0) */
    lws_sorted_usec_list_t tick;  /* bounds each lws_service wait during shutdown */
    lws_sorted_usec_list_t sweep; /* looks for connections lws is failing (sweep_cb) */
    lws_sorted_usec_list_t idle;  /* hands free memory back once the last session is gone */
    bool sweeping;
    char web_dir[PATH_MAX];
} server;

static server *server_of(struct lws *wsi)
{
    return lws_context_user(lws_get_context(wsi));
}

/* ======================== the handshake ======================== */

static bool same_origin(const char *a, const char *b)
{
    size_t la = strlen(a), lb = strlen(b);
    while (la && a[la - 1] == '/') la--;
    while (lb && b[lb - 1] == '/') lb--;
    return la == lb && !strncasecmp(a, b, la);
}

/* One of the server's own origins: SCHEME://H:PORT for H = 127.0.0.1, localhost, [::1] and the
 * bound address (SCHEME://H alone when PORT is the scheme's default). Never derived from the
 * request's Host header, which a DNS-rebinding page controls. */
static bool own_origin(const server *srv, const char *origin)
{
    const iird_server_config *cfg = srv->cfg;
    const char *scheme = cfg->tls_cert ? "https" : "http";
    bool v6 = strchr(cfg->host, ':') != NULL,
         default_port = srv->port == (cfg->tls_cert ? 443 : 80);
    char bound[80], own[128];
    snprintf(bound, sizeof bound, "%s%s%s", v6 ? "[" : "", cfg->host, v6 ? "]" : "");
    const char *hosts[] = {"127.0.0.1", "localhost", "[::1]", bound};
    for (size_t i = 0; i < sizeof hosts / sizeof *hosts; i++) {
        snprintf(own, sizeof own, "%s://%s:%d", scheme, hosts[i], srv->port);
        if (same_origin(origin, own)) return true;
        snprintf(own, sizeof own, "%s://%s", scheme, hosts[i]);
        if (default_port && same_origin(origin, own)) return true;
    }
    return false;
}

/* docs/protocol.md, Transport: the server's own origins and the --origin list; anything else
 * (`null` included) is refused. A request without Origin (not a browser) passes. */
static bool origin_allowed(server *srv, struct lws *wsi)
{
    char origin[512] = "";
    if (lws_hdr_total_length(wsi, WSI_TOKEN_ORIGIN) <= 0) return true;
    if (lws_hdr_copy(wsi, origin, sizeof origin, WSI_TOKEN_ORIGIN) <= 0) return false;
    const iird_server_config *cfg = srv->cfg;
    if (own_origin(srv, origin)) return true;
    for (int i = 0; i < cfg->num_origins; i++)
        if (same_origin(origin, cfg->origins[i])) return true;
    return false;
}

/* Answers a refused handshake with a plain HTTP/1.1 status (lws_return_http_status would say
 * HTTP/1.0 here: the request's version is only parsed for requests that stay HTTP). */
static int refuse(struct lws *wsi, int status, const char *reason, const char *body)
{
    unsigned char buf[LWS_PRE + 512];
    int n = snprintf((char *)buf + LWS_PRE, sizeof buf - LWS_PRE,
                     "HTTP/1.1 %d %s\r\ncontent-type: text/plain\r\ncontent-length: %zu\r\n"
                     "connection: close\r\n\r\n%s",
                     status, reason, strlen(body), body);
    if (n > 0 && n < (int)(sizeof buf - LWS_PRE))
        (void)lws_write(wsi, buf + LWS_PRE, (size_t)n, LWS_WRITE_HTTP);
    return 1;
}

/* Refuses a WebSocket handshake: not /ws (404) or a foreign origin (403). Returns nonzero to
 * refuse. */
static int filter_handshake(server *srv, struct lws *wsi)
{
    char uri[256] = "";
    lws_hdr_copy(wsi, uri, sizeof uri, WSI_TOKEN_GET_URI);
    char *q = strchr(uri, '?');
    if (q) *q = '\0';
    if (strcmp(uri, "/ws") != 0)
        return refuse(wsi, 404, "Not Found", "the WebSocket endpoint is /ws\n");
    if (!origin_allowed(srv, wsi))
        return refuse(wsi, 403, "Forbidden", "this origin may not open a session\n");
    return 0;
}

/* ======================== sessions ======================== */

static void link_conn(server *srv, conn *c, struct lws *wsi)
{
    c->wsi = wsi;
    c->next = srv->conns;
    c->linked = true;
    srv->conns = c;
}

static void unlink_conn(server *srv, conn *c)
{
    for (conn **p = &srv->conns; *p; p = &(*p)->next)
        if (*p == c) {
            *p = c->next;
            break;
        }
    c->linked = false;
}

/* Sessions held by peer address addr, closing ones (worker still running) included. */
static int sessions_from(const server *srv, const char *addr)
{
    int n = 0;
    for (const conn *c = srv->conns; c; c = c->next) n += c->session && !strcmp(c->addr, addr);
    for (const closing *z = srv->closing; z; z = z->next) n += !strcmp(z->addr, addr);
    return n;
}

/* Arms (or re-arms) the idle timer: LWS_CALLBACK_TIMER after --idle-timeout without a message. */
static void arm_idle(const server *srv, struct lws *wsi)
{
    if (srv->cfg->idle_timeout_s > 0)
        lws_set_timer_usecs(wsi, (lws_usec_t)srv->cfg->idle_timeout_s * LWS_USEC_PER_SEC);
}

static void refuse_busy(conn *c, busy_reason why)
{
    c->busy = why;
    lws_callback_on_writable(c->wsi);
}

/* Whether addr (as lws_get_peer_simple writes it) is on the loopback network: 127.0.0.0/8, ::1,
 * or IPv4-mapped 127.x. */
static bool is_loopback(const char *addr)
{
    if (!strncasecmp(addr, "::ffff:", 7)) addr += 7;
    return !strncmp(addr, "127.", 4) || !strcmp(addr, "::1") || !strcmp(addr, "0:0:0:0:0:0:0:1");
}

/* The client's address: the peer's, or behind the trusted balancer (--trust-proxy) the last entry
 * of X-Forwarded-For (the one the balancer appended; earlier ones are the client's own word).
 * *local: a direct loopback peer, never one that came through the balancer (whatever its
 * header says), so that --max-sessions-per-address's default spares this machine's own tabs. */
static void client_address(const server *srv, struct lws *wsi, char addr[ADDR_BYTES], bool *local)
{
    lws_get_peer_simple(wsi, addr, ADDR_BYTES);
    const char *proxy = srv->cfg->trust_proxy;
    bool proxied = proxy && !strcmp(addr, proxy);
    *local = !proxied && is_loopback(addr);
    char xff[512];
    if (!proxied || lws_hdr_copy(wsi, xff, sizeof xff, WSI_TOKEN_X_FORWARDED_FOR) <= 0) return;
    const char *last = strrchr(xff, ',');
    last = last ? last + 1 : xff;
    while (*last == ' ') last++;
    size_t n = strcspn(last, " ");
    if (n > 0 && n < ADDR_BYTES) memcpy(addr, last, n), addr[n] = '\0';
}

static void start_sweep(server *srv);

/* Messages go out in one send of up to this many bytes (the protocol's tx_packet_size), into a
 * socket send buffer that takes them whole (a new TCP socket starts at 16 KB, tcp_wmem; setting it
 * fixes it, doubled by the kernel, giving up autotuning past that). With the default (the rx
 * buffer's 16 KB) a welcome (~33 KB: every method's parameter table) went out in three sends, the
 * rest buffered by libwebsockets, which then closed a connection that failed the protocol (RSV
 * bits, a reserved opcode) without its close frame (1002): test_serve_hostile2's FramingTest. */
enum { SEND_BUFFER_BYTES = 1 << 20 };

static void size_send_buffer(struct lws *wsi)
{
    int fd = (int)lws_get_socket_fd(wsi), bytes = SEND_BUFFER_BYTES;
    if (fd >= 0) (void)setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &bytes, sizeof bytes); /* a hint */
}

static void on_established(server *srv, conn *c, struct lws *wsi)
{
    link_conn(srv, c, wsi);
    size_send_buffer(wsi);
    start_sweep(srv);
    client_address(srv, wsi, c->addr, &c->local);
    if (atomic_load(&srv->draining)) return refuse_busy(c, BUSY_DRAINING);
    if (srv->active >= srv->cfg->max_sessions) return refuse_busy(c, BUSY_SERVER);
    bool limited = !(c->local && srv->cfg->loopback_unlimited);
    if (limited && sessions_from(srv, c->addr) >= srv->cfg->max_sessions_per_address)
        return refuse_busy(c, BUSY_ADDRESS);
    iir_error err = {0};
    c->session = iird_session_create(&srv->env, ++srv->next_id, &err);
    if (!c->session) {
        fprintf(stderr, "iird serve: %s\n", err.msg);
        return refuse_busy(c, BUSY_SERVER);
    }
    iird_session_set_address(c->session, c->addr);
    srv->active++;
    /* A client that never says hello must not hold a session slot: lws closes it after this. */
    lws_set_timeout(wsi, PENDING_TIMEOUT_USER_OK, IIRD_HELLO_TIMEOUT_S);
    arm_idle(srv, wsi);
    atomic_fetch_add(&srv->metrics.sessions, 1);
    atomic_fetch_add(&srv->metrics.sessions_total, 1);
}

/* A session's worker has returned: free it and give its slot back. */
static void release_session(server *srv, iird_session *s)
{
    iird_session_destroy(s);
    srv->active--;
    atomic_fetch_sub(&srv->metrics.sessions, 1);
}

/* The client left: stop the worker without waiting; the session keeps its slot until the worker
 * has returned (reap_closing). */
static void on_closed(server *srv, conn *c)
{
    if (c->linked) unlink_conn(srv, c);
    if (!c->session) return;
    closing *z = malloc(sizeof *z);
    iird_session_request_stop(c->session);
    if (z) {
        z->session = c->session;
        memcpy(z->addr, c->addr, sizeof z->addr);
        z->next = srv->closing;
        srv->closing = z;
    } else {
        release_session(srv, c->session); /* out of memory: wait for the worker here */
    }
    c->session = NULL;
}

#if defined(__SANITIZE_ADDRESS__)
#define IIRD_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define IIRD_ASAN 1
#endif
#endif
#ifdef IIRD_ASAN
/* From <sanitizer/allocator_interface.h>, which GCC 12 does not ship. */
void __sanitizer_purge_allocator(void);
#endif

static bool stopping(server *srv)
{
    return atomic_load(&srv->stop) || atomic_load(&srv->draining);
}

/* IDLE_RELEASE_MS after the last session went, if none came since: give the allocator's free
 * memory (a session's shadow maps were allocated on its worker) back to the system, so an idle
 * daemon's RSS returns to its start. glibc keeps it in per-thread arenas until malloc_trim; ASan's
 * allocator ignores malloc_trim and keeps freed blocks in its quarantine and size-class regions
 * until its purge (~50 ms of this thread after a radiosity session: hence on a timer, not in the
 * closing's own callback, and never while the daemon stops). */
enum { IDLE_RELEASE_MS = 100 };

static void idle_cb(lws_sorted_usec_list_t *sul)
{
    server *srv = lws_container_of(sul, server, idle);
    if (srv->active || srv->closing || stopping(srv)) return;
#ifdef IIRD_ASAN
    __sanitizer_purge_allocator();
#else
    malloc_trim(0);
#endif
}

static void reap_closing(server *srv, bool wait)
{
    bool freed = false;
    for (closing **p = &srv->closing; *p;) {
        closing *z = *p;
        if (wait || iird_session_worker_done(z->session)) {
            *p = z->next;
            release_session(srv, z->session);
            free(z);
            freed = true;
        } else {
            p = &z->next;
        }
    }
    if (freed && !srv->closing && srv->active == 0 && !stopping(srv)) {
        lws_sul_cancel(&srv->idle);
        lws_sul_schedule(srv->ctx, 0, &srv->idle, idle_cb, IDLE_RELEASE_MS * LWS_US_PER_MS);
    }
}

/* No client message for --idle-timeout: an idle_timeout error, then close 4000. A client that
 * does not read either is dropped a few seconds later by lws. */
static void on_idle(server *srv, conn *c)
{
    if (!c->session) return;
    iird_proto_error e = {.seq = IIRD_NO_SEQ};
    iird_proto_fail(&e, IIRD_E_IDLE_TIMEOUT, NULL,
                    "closing the session: no message from the client for %d s (--idle-timeout)",
                    srv->cfg->idle_timeout_s);
    iird_session_close_error(c->session, IIRD_CLOSE_IDLE, &e);
    lws_set_timeout(c->wsi, PENDING_TIMEOUT_USER_OK, 5);
    lws_callback_on_writable(c->wsi);
}

/* A client that does not read its replies: its close reason now, sent (after what the socket
 * already holds) at the next writable callback; a client that reads nothing for
 * IIRD_NOT_READING_GRACE_S more is dropped without it. */
static void check_overflow(conn *c)
{
    if (c->failing || !c->session || !iird_session_overflowed(c->session)) return;
    c->failing = true;
    iird_session_close_not_reading(c->wsi);
    lws_set_timeout(c->wsi, PENDING_TIMEOUT_USER_OK, IIRD_NOT_READING_GRACE_S);
    lws_callback_on_writable(c->wsi);
}

/* A worker (or the signal thread) woke the loop: ask for writable callbacks where output waits. */
static void on_wake(server *srv)
{
    for (conn *c = srv->conns; c; c = c->next) {
        if (c->session && iird_session_take_wake(c->session)) lws_callback_on_writable(c->wsi);
        check_overflow(c);
    }
    reap_closing(srv, false);
}

/* RFC 6455 fails a connection on a frame with RSV bits or a reserved opcode. libwebsockets 4.1
 * sends its close frame (1002) and stops reading, but then waits up to 5 s for the client's
 * answer while still handing us writable callbacks. Such a connection has a close payload we did
 * not set: it gets no further message and is closed at its next writable callback, which this
 * asks for every 200 ms (a session with output asks sooner). */
static bool lws_failing(conn *c, struct lws *wsi)
{
    if (!c->failing && lws_get_close_length(wsi) > 0) c->failing = true;
    return c->failing;
}

static void sweep_cb(lws_sorted_usec_list_t *sul)
{
    server *srv = lws_container_of(sul, server, sweep);
    srv->sweeping = false;
    for (conn *c = srv->conns; c; c = c->next)
        if (lws_failing(c, c->wsi)) lws_callback_on_writable(c->wsi);
    start_sweep(srv);
}

static void start_sweep(server *srv)
{
    if (srv->sweeping || !srv->conns) return;
    srv->sweeping = true;
    lws_sul_schedule(srv->ctx, 0, &srv->sweep, sweep_cb, 200 * LWS_US_PER_MS);
}

/* A refused connection gets one busy error, then close 1013 (try again later). */
static int write_busy(server *srv, conn *c, struct lws *wsi)
{
    iird_proto_error e = {.seq = IIRD_NO_SEQ};
    if (c->busy == BUSY_DRAINING)
        iird_proto_fail(&e, IIRD_E_BUSY, NULL,
                        "the server is shutting down (draining its sessions): connect again to "
                        "reach another");
    else if (c->busy == BUSY_ADDRESS)
        iird_proto_fail(&e, IIRD_E_BUSY, NULL,
                        "this address has its maximum of %d sessions open "
                        "(--max-sessions-per-address)",
                        srv->cfg->max_sessions_per_address);
    else
        iird_proto_fail(&e, IIRD_E_BUSY, NULL, "the server has its maximum of %d sessions open",
                        srv->cfg->max_sessions);
    iird_metrics_error(&srv->metrics, IIRD_E_BUSY);
    char *json = iird_json_error(&e);
    size_t len = json ? strlen(json) : 0;
    unsigned char *buf = malloc(LWS_PRE + len);
    if (buf && json) {
        memcpy(buf + LWS_PRE, json, len);
        if (lws_write(wsi, buf + LWS_PRE, len, LWS_WRITE_TEXT) == (int)len)
            atomic_fetch_add(&srv->metrics.bytes_sent, len);
    }
    free(buf);
    free(json);
    lws_close_reason(wsi, (enum lws_close_status)1013, NULL, 0); /* try again later */
    return -1;
}

static int on_writable(server *srv, conn *c, struct lws *wsi)
{
    if (lws_failing(c, wsi)) return -1; /* its close reason is set: nothing more, close now */
    if (c->busy) return write_busy(srv, c, wsi);
    if (!c->session) return 0;
    switch (iird_session_write(c->session, wsi)) {
    case IIRD_WRITE_CLOSE:
        return -1;
    case IIRD_WRITE_MORE:
        lws_callback_on_writable(wsi);
        break;
    case IIRD_WRITE_IDLE:
        break;
    }
    return 0;
}

static int ws_callback(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in,
                       size_t len)
{
    server *srv = server_of(wsi);
    conn *c = user;
    switch (reason) {
    case LWS_CALLBACK_FILTER_PROTOCOL_CONNECTION:
        return filter_handshake(srv, wsi);
    case LWS_CALLBACK_ESTABLISHED:
        on_established(srv, c, wsi);
        break;
    case LWS_CALLBACK_RECEIVE:
        if (!c->session || lws_failing(c, wsi)) break; /* closing: nothing more is taken */
        iird_session_receive(c->session, in, len, lws_is_final_fragment(wsi),
                             lws_frame_is_binary(wsi));
        check_overflow(c);
        if (c->failing) break;
        if (iird_session_greeted(c->session)) lws_set_timeout(wsi, NO_PENDING_TIMEOUT, 0);
        arm_idle(srv, wsi);
        lws_callback_on_writable(wsi);
        break;
    case LWS_CALLBACK_TIMER:
        on_idle(srv, c);
        break;
    case LWS_CALLBACK_SERVER_WRITEABLE:
        return on_writable(srv, c, wsi);
    case LWS_CALLBACK_CLOSED:
        on_closed(srv, c);
        break;
    case LWS_CALLBACK_EVENT_WAIT_CANCELLED:
        if (srv) on_wake(srv);
        break;
    default:
        break;
    }
    return lws_callback_http_dummy(wsi, reason, user, in, len);
}

/* ======================== /healthz and /metrics ======================== */

static iird_metrics_session session_metrics(iird_session *s)
{
    return (iird_metrics_session){iird_session_id(s), iird_session_memory(s),
                                  iird_session_render_seconds(s)};
}

static char *metrics_text(server *srv)
{
    iird_metrics_session mem[256];
    size_t n = 0;
    for (conn *c = srv->conns; c && n < sizeof mem / sizeof *mem; c = c->next)
        if (c->session) mem[n++] = session_metrics(c->session);
    for (closing *z = srv->closing; z && n < sizeof mem / sizeof *mem; z = z->next)
        mem[n++] = session_metrics(z->session);
    iird_sched_stats sched = iird_sched_get_stats(srv->sched);
    uint64_t scene_bytes;
    size_t loaded = iird_scene_cache_loaded(srv->scenes, &scene_bytes);
    return iird_metrics_prometheus(&srv->metrics, mem, n, &sched, loaded, scene_bytes);
}

/* What /healthz says to a balancer: "draining" after SIGTERM and "full" at --max-sessions (503:
 * send no new session here), else "ok"; /livez (for systemd and liveness probes) is always 200
 * "alive" while the process serves. */
static const char *health(const server *srv, bool live, int *status)
{
    *status = HTTP_STATUS_OK;
    if (live) return "alive";
    *status = HTTP_STATUS_SERVICE_UNAVAILABLE;
    if (atomic_load(&srv->draining)) return "draining";
    if (srv->active >= srv->cfg->max_sessions) return "full";
    *status = HTTP_STATUS_OK;
    return "ok";
}

/* Builds the body and sends the headers; the body follows on HTTP_WRITEABLE. Only the exact
 * paths /healthz, /livez and /metrics: anything below them is 404. */
static int http_start(server *srv, struct lws *wsi, http_req *r, const char *path)
{
    bool metrics = !strcmp(path, "/metrics"), live = !strcmp(path, "/livez");
    if (!metrics && !live && strcmp(path, "/healthz") != 0)
        return lws_return_http_status(wsi, HTTP_STATUS_NOT_FOUND, NULL), -1;
    int status = HTTP_STATUS_OK;
    const char *word = metrics ? NULL : health(srv, live, &status);
    char *text = metrics ? metrics_text(srv) : iird_metrics_healthz(&srv->metrics, word);
    if (!text) return lws_return_http_status(wsi, HTTP_STATUS_INTERNAL_SERVER_ERROR, NULL), -1;
    r->len = strlen(text);
    r->body = malloc(LWS_PRE + r->len);
    if (r->body) memcpy(r->body + LWS_PRE, text, r->len);
    free(text);
    if (!r->body) return -1;
    unsigned char hdr[LWS_PRE + 512], *start = hdr + LWS_PRE, *p = start, *end = hdr + sizeof hdr;
    const char *type = metrics ? "text/plain; version=0.0.4" : "application/json";
    if (lws_add_http_common_headers(wsi, (unsigned)status, type, r->len, &p, end) ||
        lws_add_http_header_by_token(wsi, WSI_TOKEN_HTTP_CACHE_CONTROL, (unsigned char *)"no-store",
                                     8, &p, end) ||
        lws_finalize_write_http_header(wsi, start, &p, end))
        return -1;
    lws_callback_on_writable(wsi);
    return 0;
}

static int http_body(struct lws *wsi, http_req *r)
{
    if (!r->body) return 0;
    int n = lws_write(wsi, r->body + LWS_PRE, r->len, LWS_WRITE_HTTP_FINAL);
    free(r->body);
    r->body = NULL;
    if (n < (int)r->len) return -1;
    return lws_http_transaction_completed(wsi) ? -1 : 0;
}

static int http_callback(struct lws *wsi, enum lws_callback_reasons reason, void *user, void *in,
                         size_t len)
{
    http_req *r = user;
    char path[16] = ""; /* longer than "/healthz", "/metrics": a path that does not fit is 404 */
    switch (reason) {
    case LWS_CALLBACK_HTTP:
        if (lws_hdr_copy(wsi, path, sizeof path, WSI_TOKEN_GET_URI) <= 0) path[0] = '\0';
        return http_start(server_of(wsi), wsi, r, path);
    case LWS_CALLBACK_HTTP_WRITEABLE:
        return http_body(wsi, r);
    case LWS_CALLBACK_CLOSED_HTTP:
        free(r->body);
        r->body = NULL;
        break;
    default:
        break;
    }
    return lws_callback_http_dummy(wsi, reason, user, in, len);
}

/* ======================== context ======================== */

/* The first protocol is the one lws gives WebSocket clients that name no subprotocol. */
static const struct lws_protocols protocols[] = {
    {"iird", ws_callback, sizeof(conn), 16384, 0, NULL, SEND_BUFFER_BYTES},
    {"http", http_callback, sizeof(http_req), 0, 0, NULL, 0},
    {NULL, NULL, 0, 0, 0, NULL, 0}};

enum { MOUNTS = 4 };

static void make_mounts(const server *srv, struct lws_http_mount m[MOUNTS])
{
    static const char *const callbacks[] = {"/healthz", "/livez", "/metrics"};
    memset(m, 0, MOUNTS * sizeof *m);
    for (int i = 0; i < 3; i++) {
        m[i].mountpoint = callbacks[i];
        m[i].protocol = "http";
        m[i].origin_protocol = LWSMPRO_CALLBACK;
        m[i].mount_next = &m[i + 1];
    }
    m[3].mountpoint = "/";
    m[3].origin = srv->web_dir;
    m[3].def = "index.html";
    m[3].origin_protocol = LWSMPRO_FILE;
    for (int i = 0; i < MOUNTS; i++) m[i].mountpoint_len = (unsigned char)strlen(m[i].mountpoint);
}

static struct lws_context *create_context(server *srv, const struct lws_http_mount *mounts)
{
    const iird_server_config *cfg = srv->cfg;
    struct lws_context_creation_info info;
    memset(&info, 0, sizeof info);
    info.port = cfg->port;
    info.iface = cfg->host;
    info.protocols = protocols;
    info.mounts = mounts;
    info.user = srv;
    info.vhost_name = "default";
    if (!strchr(cfg->host, ':')) info.options |= LWS_SERVER_OPTION_DISABLE_IPV6;
    if (cfg->tls_cert) {
        info.options |= LWS_SERVER_OPTION_DO_SSL_GLOBAL_INIT;
        info.ssl_cert_filepath = cfg->tls_cert;
        info.ssl_private_key_filepath = cfg->tls_key;
        /* HTTP/1.1 only: the handshake refusals (refuse()) and one message per writable callback
         * assume one connection per client, not h2 streams */
        info.alpn = "http/1.1";
    }
    lws_set_log_level(cfg->verbose ? LLL_ERR | LLL_WARN | LLL_NOTICE : LLL_ERR, NULL);
    return lws_create_context(&info);
}

/* ======================== signals ======================== */

typedef struct signal_thread {
    pthread_t thread;
    server *srv;
    atomic_int quit;
} signal_thread;

/* The signals the signal thread takes: SIGINT, SIGTERM, SIGHUP and SIGQUIT stop the server
 * cleanly; the others are ignored, since their default would end the daemon and nothing here
 * uses them: SIGUSR1/2, the timer signals (SIGALRM, SIGVTALRM, SIGPROF), SIGIO, SIGPWR,
 * SIGSTKFLT and the real-time signals. (SIGPIPE and SIGXFSZ are ignored in every thread: a failed
 * write returns its error. Faults, SIGXCPU, SIGKILL and SIGSTOP keep their defaults.) */
static void signal_set(sigset_t *set)
{
    static const int taken[] = {SIGINT,  SIGTERM,   SIGHUP,  SIGQUIT, SIGUSR1, SIGUSR2,
                                SIGALRM, SIGVTALRM, SIGPROF, SIGIO,   SIGPWR};
    sigemptyset(set);
    for (size_t i = 0; i < sizeof taken / sizeof *taken; i++) sigaddset(set, taken[i]);
#ifdef SIGSTKFLT
    sigaddset(set, SIGSTKFLT);
#endif
    for (int sig = SIGRTMIN; sig <= SIGRTMAX; sig++) sigaddset(set, sig);
}

static bool stop_signal(int sig)
{
    return sig == SIGINT || sig == SIGTERM || sig == SIGHUP || sig == SIGQUIT;
}

static void *signal_main(void *arg)
{
    signal_thread *st = arg;
    sigset_t set;
    signal_set(&set);
    for (;;) {
        int sig = 0;
        sigwait(&set, &sig);
        if (atomic_load(&st->quit)) return NULL;
        if (!stop_signal(sig)) continue;
        bool drain = sig == SIGTERM && st->srv->cfg->drain_seconds > 0;
        if (!drain || atomic_exchange(&st->srv->draining, 1)) atomic_store(&st->srv->stop, 1);
        pthread_mutex_lock(&st->srv->ctx_lock);
        if (st->srv->ctx) lws_cancel_service(st->srv->ctx);
        pthread_mutex_unlock(&st->srv->ctx_lock);
    }
}

/* ======================== start and stop ======================== */

static int start(server *srv, iir_error *err)
{
    srv->scenes = iird_scene_cache_create(srv->cfg->scenes_dir, srv->cfg->scenes_follow_links);
    if (!srv->scenes) return iir_fail(err, IIR_ERR_NOMEM, "out of memory"), 1;
    iird_scene_cache_set_budget(srv->scenes, srv->cfg->budget);
    iir_status st = iird_scene_cache_acquire(srv->scenes, srv->cfg->scene, &srv->startup, err);
    if (st != IIR_OK) { /* its whole reason, paths and all, is logged already */
        snprintf(err->msg, sizeof err->msg, "the startup scene cannot be loaded (above)");
        return iir_status_exit_code(st);
    }
    iird_scene_cache_set_startup(srv->scenes, srv->startup);
    iird_metrics_init(&srv->metrics);
    int threads = omp_get_max_threads();
    int slots = srv->cfg->render_slots ? srv->cfg->render_slots : threads > 1 ? 2 : 1;
    srv->sched = iird_sched_create(slots, threads, IIRD_SCHED_SLICE_MS);
    if (!srv->sched) return iir_fail(err, IIR_ERR_NOMEM, "out of memory"), 1;
    srv->saves = iird_saves_create(iird_scene_cache_dir(srv->scenes), srv->cfg->max_saved_scenes,
                                   srv->cfg->save_rate);
    if (!srv->saves) return iir_fail(err, IIR_ERR_NOMEM, "out of memory"), 1;
    srv->env = (iird_session_env){.scenes = srv->scenes,
                                  .metrics = &srv->metrics,
                                  .limits = srv->cfg->limits,
                                  .defaults = srv->cfg->defaults,
                                  .startup = srv->startup,
                                  .token = srv->cfg->token,
                                  .budget = srv->cfg->budget,
                                  .sched = srv->sched,
                                  .saves = srv->saves};
    return 0;
}

static void tick_cb(lws_sorted_usec_list_t *sul)
{
    (void)sul;
}

/* Services until no WebSocket is left or until the deadline (ms). lws_service alone would wait
 * for its next timer (up to ~20 s when a client does not read): a 20 ms tick bounds each wait. */
static void service_until(server *srv, double until)
{
    while (srv->conns && iir_now_ms() < until) {
        lws_sul_schedule(srv->ctx, 0, &srv->tick, tick_cb, 20 * LWS_US_PER_MS);
        if (lws_service(srv->ctx, 0) < 0) break;
    }
    lws_sul_cancel(&srv->tick);
}

/* Closes every session with 1001 (going away) and services ~0.6 s so the close frames go out;
 * then drops the connections still open (clients that do not read) and services ~0.3 s more;
 * whatever is left goes with the context. Joins every worker before the context goes. */
static void shut_down(server *srv)
{
    for (conn *c = srv->conns; c; c = c->next)
        if (c->session) {
            iird_session_request_stop(c->session);
            iird_session_close(c->session, LWS_CLOSE_STATUS_GOINGAWAY);
            lws_callback_on_writable(c->wsi);
        }
    service_until(srv, iir_now_ms() + 600.0);
    for (conn *c = srv->conns; c; c = c->next) lws_set_timeout(c->wsi, 1, LWS_TO_KILL_ASYNC);
    service_until(srv, iir_now_ms() + 300.0);
    for (conn *c = srv->conns; c; c = c->next) {
        if (c->session) release_session(srv, c->session);
        c->session = NULL;
    }
    reap_closing(srv, true);
}

/* Whether a drain (the first SIGTERM) is over: every session gone, or --drain-seconds passed.
 * While it lasts, a 100 ms tick bounds each lws_service wait so that the deadline is seen. */
static bool drained(server *srv)
{
    if (!atomic_load(&srv->draining)) return false;
    double now = iir_now_ms();
    if (srv->active == 0) return true; /* nothing to drain: stop now, quietly */
    if (srv->drain_until == 0.0) {
        srv->drain_until = now + 1e3 * srv->cfg->drain_seconds;
        fprintf(stderr,
                "iird serve: SIGTERM: draining %d session%s for up to %d s (/healthz: draining; "
                "SIGTERM again to stop now)\n",
                srv->active, srv->active == 1 ? "" : "s", srv->cfg->drain_seconds);
    }
    if (now >= srv->drain_until) return true;
    lws_sul_schedule(srv->ctx, 0, &srv->tick, tick_cb, 100 * LWS_US_PER_MS);
    return false;
}

static void print_url(const server *srv)
{
    const iird_server_config *cfg = srv->cfg;
    int port = srv->port;
    bool v6 = strchr(cfg->host, ':') != NULL;
    const char *name = srv->startup->name;
    printf("iird: serving %s://%s%s%s:%d/ (%s)\n", cfg->tls_cert ? "https" : "http", v6 ? "[" : "",
           cfg->host, v6 ? "]" : "", port, strcmp(name, "builtin") ? name : "Cornell box");
    fflush(stdout);
}

/* Binds host:port once and lets go, before libwebsockets tries: a port in use or an address this
 * machine does not have gets the system's own reason (and lws is never half-started). 0 when it
 * can bind; otherwise the errno (EAI_* failures of the name give EADDRNOTAVAIL). */
static int probe_listen(const char *host, int port)
{
    char service[16];
    snprintf(service, sizeof service, "%d", port);
    struct addrinfo hints = {.ai_family = AF_UNSPEC,
                             .ai_socktype = SOCK_STREAM,
                             .ai_flags = AI_PASSIVE | AI_NUMERICSERV},
                    *ai = NULL;
    if (getaddrinfo(host, service, &hints, &ai) != 0 || !ai) return EADDRNOTAVAIL;
    int fd = socket(ai->ai_family, ai->ai_socktype, ai->ai_protocol), one = 1, rc = 0;
    if (fd < 0) rc = errno;
    if (!rc) setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
    if (!rc && bind(fd, ai->ai_addr, ai->ai_addrlen) != 0) rc = errno;
    if (fd >= 0) close(fd);
    freeaddrinfo(ai);
    return rc;
}

static int serve(server *srv)
{
    int bind_err = probe_listen(srv->cfg->host, srv->cfg->port);
    if (bind_err) {
        fprintf(stderr, "iird serve: cannot listen on %s port %d: %s\n", srv->cfg->host,
                srv->cfg->port, strerror(bind_err));
        return 1;
    }
    struct lws_http_mount mounts[MOUNTS];
    make_mounts(srv, mounts);
    struct lws_context *ctx = create_context(srv, mounts);
    pthread_mutex_lock(&srv->ctx_lock);
    srv->ctx = ctx;
    pthread_mutex_unlock(&srv->ctx_lock);
    if (!srv->ctx) {
        fprintf(stderr,
                "iird serve: cannot listen on %s port %d (in use, or a bad address or TLS "
                "file?)\n",
                srv->cfg->host, srv->cfg->port);
        return 1;
    }
    srv->env.lws = srv->ctx;
    struct lws_vhost *vh = lws_get_vhost_by_name(srv->ctx, "default");
    srv->port = vh ? lws_get_vhost_listen_port(vh) : srv->cfg->port;
    print_url(srv);
    while (!atomic_load(&srv->stop) && !drained(srv))
        if (lws_service(srv->ctx, 0) < 0) break;
    shut_down(srv);
    lws_sul_cancel(&srv->sweep);
    lws_sul_cancel(&srv->idle);
    pthread_mutex_lock(&srv->ctx_lock);
    srv->ctx = NULL;
    pthread_mutex_unlock(&srv->ctx_lock);
    lws_context_destroy(ctx);
    return 0;
}

static void finish(server *srv)
{
    if (srv->scenes) {
        iird_scene_cache_release(srv->scenes, srv->startup);
        iird_scene_cache_destroy(srv->scenes);
    }
    iird_sched_destroy(srv->sched);
    iird_saves_destroy(srv->saves);
}

int iird_server_run(const iird_server_config *cfg)
{
    /* Before any thread exists (Embree, OpenMP, workers): they all inherit the blocked mask. */
    sigset_t set;
    signal_set(&set);
    pthread_sigmask(SIG_BLOCK, &set, NULL);
    signal(SIGPIPE, SIG_IGN);
    signal(SIGXFSZ, SIG_IGN);

    server *srv = calloc(1, sizeof *srv);
    if (!srv) return fprintf(stderr, "iird serve: out of memory\n"), 1;
    srv->cfg = cfg;
    pthread_mutex_init(&srv->ctx_lock, NULL);
    if (!realpath(cfg->web_dir, srv->web_dir)) snprintf(srv->web_dir, PATH_MAX, "%s", cfg->web_dir);
    signal_thread sig = {.srv = srv};
    pthread_create(&sig.thread, NULL, signal_main, &sig);

    iir_error err = {0};
    int rc = start(srv, &err);
    if (rc != 0)
        fprintf(stderr, "iird serve: %s\n", err.msg);
    else if (!atomic_load(&srv->stop))
        rc = serve(srv);
    finish(srv);

    atomic_store(&sig.quit, 1);
    pthread_kill(sig.thread, SIGTERM);
    pthread_join(sig.thread, NULL);
    pthread_mutex_destroy(&srv->ctx_lock);
    free(srv);
    return rc;
}

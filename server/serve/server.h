/* server.h -- `iird serve`'s libwebsockets daemon: the context and its one service thread, the
 * HTTP side (the web client's files, /healthz, /metrics), the WebSocket endpoint /ws and its
 * sessions, the handshake checks (origin, session limits), idle sessions and the shutdown on
 * SIGINT/SIGTERM/SIGHUP/SIGQUIT.
 * Not the per-client logic (session.h) and not option parsing (cmd_serve.c). */
#ifndef IIRD_SERVER_H
#define IIRD_SERVER_H

#include <stdbool.h>

#include "protocol/protocol.h"

enum {
    IIRD_MAX_ORIGINS = 16,
    IIRD_HELLO_TIMEOUT_S = 10,    /* a WebSocket without an accepted hello by then is closed */
    IIRD_CLOSE_IDLE = 4000,       /* WebSocket close status after --idle-timeout */
    IIRD_NOT_READING_GRACE_S = 5, /* a client closed for not reading is dropped this long after */
};

typedef struct iird_server_config {
    const char *host;         /* IP address to bind, "127.0.0.1" unless told otherwise */
    int port;                 /* 0: any free port (printed) */
    const char *scene;        /* startup scene: NULL/"builtin", a name, a folder or a file */
    const char *scenes_dir;   /* where client scene names are looked up */
    bool scenes_follow_links; /* names may lead outside scenes_dir through symbolic links */
    const char *web_dir;      /* the web client's folder (must exist) */
    int max_sessions;
    int max_sessions_per_address; /* sessions one peer address may hold at once */
    bool loopback_unlimited;      /* the default limit: a client on the loopback address (this
                                     machine's own tabs, not one behind --trust-proxy) is held
                                     only by max_sessions; false when the option was given */
    int render_slots;   /* sessions rendering at once (scheduler.h); 0: 2, or 1 on one core */
    int idle_timeout_s; /* close a session after this long without a client message;
                           0: never */
    iird_limits limits;
    const char *origins[IIRD_MAX_ORIGINS]; /* allowed Origin headers besides the server's own */
    int num_origins;
    const char *token;              /* NULL: no token */
    const char *tls_cert, *tls_key; /* both or neither */
    iird_settings defaults;         /* the state of a new session */
    struct iird_budget *budget;     /* memory limits and reservations (budget.h); NULL: none */
    bool verbose;                   /* libwebsockets notices on stderr */
    int drain_seconds;       /* after SIGTERM: keep serving the open sessions this long (or until
                                they leave) while /healthz says draining; 0: stop at once */
    const char *trust_proxy; /* NULL, or a balancer's address: connections from it are counted
                                (per-address limits, logs) by the last X-Forwarded-For entry */
    int max_saved_scenes;    /* saved scenes the scenes directory may hold (scene_save.h) */
    int save_rate;           /* named saves per client address per minute (and burst) */
} iird_server_config;

/* Loads the startup scene, starts listening, prints "iird: serving URL (scene)" on stdout, and
 * serves until SIGINT, SIGTERM, SIGHUP or SIGQUIT (SIGUSR1 and SIGUSR2 are ignored). The first
 * SIGTERM with drain_seconds > 0 drains first: new sessions are refused (busy), /healthz answers
 * 503 "draining", and the open sessions are served until they leave or drain_seconds pass (another
 * SIGTERM, or any other of those signals, ends it at once). Then it closes every session (about a
 * second of service at most, whatever the clients do), stops every worker and frees everything.
 * Returns the process exit code (0 after a signal; 1, 2 or 3 when start-up fails, with the reason
 * on stderr). */
int iird_server_run(const iird_server_config *cfg);

#endif

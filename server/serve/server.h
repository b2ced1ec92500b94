/* server.h -- `iird serve`'s libwebsockets daemon: the context and its one service thread, the
 * HTTP side (the web client's files, /healthz, /metrics), the WebSocket endpoint /ws and its
 * sessions, the handshake checks (origin, session limit) and the shutdown on SIGINT/SIGTERM.
 * Not the per-client logic (session.h) and not option parsing (cmd_serve.c). */
#ifndef IIRD_SERVER_H
#define IIRD_SERVER_H

#include <stdbool.h>

#include "protocol/protocol.h"

enum {
    IIRD_MAX_ORIGINS = 16,
    IIRD_HELLO_TIMEOUT_S = 10, /* a WebSocket without an accepted hello by then is closed */
};

typedef struct iird_server_config {
    const char *host;       /* IP address to bind, "127.0.0.1" unless told otherwise */
    int port;               /* 0: any free port (printed) */
    const char *scene;      /* startup scene: NULL/"builtin", a name, a folder or a file */
    const char *scenes_dir; /* where client scene names are looked up */
    const char *web_dir;    /* the web client's folder (must exist) */
    int max_sessions;
    iird_limits limits;
    const char *origins[IIRD_MAX_ORIGINS]; /* allowed Origin headers; none: see protocol.md */
    int num_origins;
    const char *token;              /* NULL: no token */
    const char *tls_cert, *tls_key; /* both or neither */
    iird_settings defaults;         /* the state of a new session */
    bool verbose;                   /* libwebsockets notices on stderr */
} iird_server_config;

/* Loads the startup scene, starts listening, prints "iird: serving URL (scene)" on stdout, and
 * serves until SIGINT or SIGTERM; then stops every worker, closes every session and frees
 * everything. Returns the process exit code (0 after a signal; 1, 2 or 3 when start-up fails,
 * with the reason on stderr). */
int iird_server_run(const iird_server_config *cfg);

#endif

/* cmd_serve.c -- `iird serve`: options, checks and the server's configuration; the daemon itself
 * is server.c's. */
#include <arpa/inet.h>
#include <getopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <openssl/err.h>
#include <openssl/pem.h>
#include <openssl/x509.h>

#include "cli.h"
#include "commands.h"
#include "budget.h"
#include "scene_save.h"
#include "server.h"
#include "session.h"
#include "session.h"

typedef struct serve_opts {
    iird_server_config cfg;
    iird_budget budget; /* limits from the options; cfg.budget points here */
    const char *scene_arg, *web_opt, *method;
    bool size_given;
} serve_opts;

static void serve_usage(FILE *f)
{
    fprintf(
        f,
        "usage: iird serve [SCENE] [options]\n"
        "\n"
        "Serves the web client and live frames over WebSockets (docs/protocol.md) until\n"
        "Ctrl-C or SIGTERM (which drains first: --drain-seconds). Prints\n"
        "'iird: serving URL (scene)' on stdout once listening. GET /healthz answers 200 ok,\n"
        "or 503 full (at --max-sessions) or draining; GET /livez always 200.\n"
        "SCENE (or --scene) is what new sessions show: a name in the scenes directory, a\n"
        "folder or a file; without it, the built-in Cornell box.\n"
        "\n"
        "  --host ADDR          IP address to bind (default 127.0.0.1; 0.0.0.0 = every one)\n"
        "  --port N             TCP port (default 8080; 0 = any free port)\n"
        "  --scene NAME|PATH    the startup scene\n"
        "  --scenes DIR         where clients' scene names are looked up (default ./scenes)\n"
        "  --scenes-follow-links  let scene names lead outside --scenes through symbolic\n"
        "                       links (by default such scenes are neither listed nor loaded)\n"
        "  --allow-save         clients may save their lights and camera as a new scene in\n"
        "                       the scenes directory (save with a name; never over a scene)\n"
        "  --max-saved-scenes N  saved scenes the scenes directory may hold (default 200)\n"
        "  --save-rate N        saves one client address may make a minute (default 12)\n"
        "  --web DIR            the web client's folder (default $IIR_WEB, ./web, the source's)\n"
        "  --max-sessions N     open WebSocket sessions at most (default 8)\n"
        "  --max-sessions-per-address N  sessions one client address may hold (default\n"
        "                       max(1, max-sessions / 4))\n"
        "  --idle-timeout S     close a session after S seconds without a client message\n"
        "                       (default 1800; 0 = never)\n"
        "  --max-size WxH       largest frame a client may ask for (default 1920x1080)\n"
        "  --render-slots N     sessions that render at once; the others wait their turn,\n"
        "                       the cores shared fairly (default 2; 1 on a 1-core machine)\n"
        "  --max-memory SIZE    memory all sessions together may take, by their estimates\n"
        "                       (e.g. 8G; default half of the physical memory)\n"
        "  --max-session-memory SIZE  memory one session may take (default 2G, at most\n"
        "                       --max-memory); params beyond either budget are refused\n"
        "  --origin URL         another allowed browser origin, repeatable (the server's\n"
        "                       own, http(s)://127.0.0.1|localhost|[::1]|HOST:PORT, always are)\n"
        "  --token T            clients must send this token in hello\n"
        "  --tls-cert F --tls-key F  serve https/wss with this PEM certificate and key\n"
        "  --method NAME        a new session's method: %s (default iir)\n"
        "  --size WxH           a new session's frame size (default 512x384)\n"
        "  --drain-seconds S    after SIGTERM keep serving the open sessions up to S seconds\n"
        "                       (until they leave) while /healthz answers 503 draining and\n"
        "                       new sessions are refused; a second SIGTERM or Ctrl-C stops\n"
        "                       at once (default 10; 0 = stop at once)\n"
        "  --trust-proxy ADDR   a load balancer's address: its connections count as the\n"
        "                       client in the last X-Forwarded-For entry (per-address\n"
        "                       limits, logs); see deploy/haproxy.cfg\n"
        "  --verbose            libwebsockets notices on stderr\n" IIRD_CACHE_MAX_HELP
        "  -h, --help           this text\n"
        "\n"
        "Exit codes: 0 stopped by a signal, 1 cannot listen, 2 bad input, 3 file error,\n"
        "64 usage.\n"
        "\n"
        "The parameters below set a new session's defaults, which are otherwise each\n"
        "parameter's one default (as for every command; welcome in docs/protocol.md);\n"
        "clients change them with params.\n",
        iird_method_choices());
}

enum {
    OPT_HOST = 1,
    OPT_PORT,
    OPT_SCENE,
    OPT_SCENES,
    OPT_WEB,
    OPT_MAX_SESSIONS,
    OPT_MAX_SIZE,
    OPT_ORIGIN,
    OPT_TOKEN,
    OPT_TLS_CERT,
    OPT_TLS_KEY,
    OPT_METHOD,
    OPT_SIZE,
    OPT_VERBOSE,
    OPT_MAX_SESSIONS_PER_ADDRESS,
    OPT_IDLE_TIMEOUT,
    OPT_MAX_MEMORY,
    OPT_MAX_SESSION_MEMORY,
    OPT_RENDER_SLOTS,
    OPT_ALLOW_SAVE,
    OPT_DRAIN_SECONDS,
    OPT_TRUST_PROXY,
    OPT_MAX_SAVED_SCENES,
    OPT_SAVE_RATE,
    OPT_CACHE_MAX,
    OPT_SCENES_FOLLOW_LINKS,
};

static iir_status parse_host(const char *arg, const char **out, iir_error *err)
{
    unsigned char addr[16];
    if (!strcmp(arg, "localhost")) arg = "127.0.0.1";
    if (inet_pton(AF_INET, arg, addr) != 1 && inet_pton(AF_INET6, arg, addr) != 1)
        return iir_fail(err, IIR_ERR_INVALID,
                        "--host '%s' is not an IP address (e.g. 127.0.0.1, 0.0.0.0, ::1)", arg);
    *out = arg;
    return IIR_OK;
}

static iir_status parse_int_opt(const char *arg, const char *what, long lo, long hi, int *out,
                                iir_error *err)
{
    long v = 0;
    iir_status st = iird_parse_int(arg, what, lo, hi, &v, err);
    if (st == IIR_OK) *out = (int)v;
    return st;
}

static iir_status parse_option(void *ctx, int c, const char *arg, iir_error *err)
{
    serve_opts *o = ctx;
    iird_server_config *cfg = &o->cfg;
    switch (c) {
    case OPT_HOST:
        return parse_host(arg, &cfg->host, err);
    case OPT_PORT:
        return parse_int_opt(arg, "--port", 0, 65535, &cfg->port, err);
    case OPT_SCENE:
        return o->scene_arg = arg, IIR_OK;
    case OPT_SCENES:
        return cfg->scenes_dir = arg, IIR_OK;
    case OPT_WEB:
        return o->web_opt = arg, IIR_OK;
    case OPT_MAX_SESSIONS:
        return parse_int_opt(arg, "--max-sessions", 1, 1024, &cfg->max_sessions, err);
    case OPT_MAX_SESSIONS_PER_ADDRESS:
        return parse_int_opt(arg, "--max-sessions-per-address", 1, 1024,
                             &cfg->max_sessions_per_address, err);
    case OPT_RENDER_SLOTS:
        return parse_int_opt(arg, "--render-slots", 1, 64, &cfg->render_slots, err);
    case OPT_DRAIN_SECONDS:
        return parse_int_opt(arg, "--drain-seconds", 0, 3600, &cfg->drain_seconds, err);
    case OPT_TRUST_PROXY:
        return parse_host(arg, &cfg->trust_proxy, err);
    case OPT_ALLOW_SAVE:
        return cfg->limits.allow_save = true, IIR_OK;
    case OPT_MAX_SAVED_SCENES:
        return parse_int_opt(arg, "--max-saved-scenes", 0, 1000000, &cfg->max_saved_scenes, err);
    case OPT_SAVE_RATE:
        return parse_int_opt(arg, "--save-rate", 1, 100000, &cfg->save_rate, err);
    case OPT_CACHE_MAX:
        return iird_set_cache_max(arg, err);
    case OPT_SCENES_FOLLOW_LINKS:
        return cfg->scenes_follow_links = true, IIR_OK;
    case OPT_IDLE_TIMEOUT:
        return parse_int_opt(arg, "--idle-timeout", 0, 7 * 86400, &cfg->idle_timeout_s, err);
    case OPT_MAX_SIZE:
        return iird_parse_size(arg, 4096, &cfg->limits.max_width, &cfg->limits.max_height, err);
    case OPT_ORIGIN:
        if (cfg->num_origins == IIRD_MAX_ORIGINS)
            return iir_fail(err, IIR_ERR_INVALID, "--origin: at most %d origins", IIRD_MAX_ORIGINS);
        return cfg->origins[cfg->num_origins++] = arg, IIR_OK;
    case OPT_TOKEN:
        if (!*arg || strlen(arg) > 256)
            return iir_fail(err, IIR_ERR_INVALID, "--token must have 1 to 256 bytes");
        return cfg->token = arg, IIR_OK;
    case OPT_TLS_CERT:
        return cfg->tls_cert = arg, IIR_OK;
    case OPT_TLS_KEY:
        return cfg->tls_key = arg, IIR_OK;
    case OPT_METHOD:
        return o->method = arg, IIR_OK;
    case OPT_SIZE:
        o->size_given = true;
        return iird_parse_size(arg, 4096, &cfg->defaults.width, &cfg->defaults.height, err);
    case OPT_VERBOSE:
        return cfg->verbose = true, IIR_OK;
    case OPT_MAX_MEMORY:
    case OPT_MAX_SESSION_MEMORY: {
        uint64_t *to = c == OPT_MAX_MEMORY ? &o->budget.total_max : &o->budget.session_max;
        const char *name = c == OPT_MAX_MEMORY ? "--max-memory" : "--max-session-memory";
        if (!iird_parse_bytes(arg, to) || *to < (16u << 20))
            return iir_fail(err, IIR_ERR_INVALID,
                            "%s '%s' is not a size of at least 16M (bytes, or with K, M, G, T)",
                            name, arg);
        return IIR_OK;
    }
    }
    return IIR_OK;
}

static bool is_dir(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISDIR(sb.st_mode);
}

/* --web if given, else $IIR_WEB, else ./web, else the source tree's. */
static const char *web_dir(const char *option)
{
    if (option) return option;
    const char *env = getenv("IIR_WEB");
    if (env && *env) return env;
    if (is_dir("web")) return "web";
    return IIR_SOURCE_DIR "/web";
}

static bool known_method(const char *name)
{
    for (const char *const *m = iir_method_names(); *m; m++)
        if (!strcmp(*m, name)) return true;
    return false;
}

/* An encrypted key would make OpenSSL prompt on the terminal: refuse it instead. */
static int no_passphrase(char *buf, int size, int rwflag, void *user)
{
    (void)buf, (void)size, (void)rwflag, (void)user;
    return 0;
}

/* The first certificate of --tls-cert and the key of --tls-key parse as PEM and belong together,
 * as libwebsockets will load them: IIR_ERR_INVALID naming the option otherwise, before any
 * listening (lws would only fail to create its vhost). The files are known to be readable. */
static iir_status check_tls_pair(const char *cert_path, const char *key_path, iir_error *err)
{
    iir_status st = IIR_OK;
    FILE *f = fopen(cert_path, "rb");
    X509 *cert = f ? PEM_read_X509(f, NULL, no_passphrase, NULL) : NULL;
    if (f) fclose(f);
    f = fopen(key_path, "rb");
    EVP_PKEY *key = f ? PEM_read_PrivateKey(f, NULL, no_passphrase, NULL) : NULL;
    if (f) fclose(f);
    if (!cert)
        st = iir_fail(err, IIR_ERR_INVALID, "--tls-cert %s holds no PEM certificate", cert_path);
    else if (!key)
        st = iir_fail(err, IIR_ERR_INVALID,
                      "--tls-key %s holds no PEM private key (or one with a passphrase)", key_path);
    else if (X509_check_private_key(cert, key) != 1)
        st = iir_fail(err, IIR_ERR_INVALID, "--tls-key %s is not the key of --tls-cert %s",
                      key_path, cert_path);
    X509_free(cert);
    EVP_PKEY_free(key);
    ERR_clear_error();
    return st;
}

static iir_status check_files(const iird_server_config *cfg, iir_error *err)
{
    if (!is_dir(cfg->web_dir))
        return iir_fail(err, IIR_ERR_IO,
                        "the web client's folder %s does not exist (give --web DIR or set "
                        "IIR_WEB)",
                        cfg->web_dir);
    const char *files[2] = {cfg->tls_cert, cfg->tls_key};
    for (int i = 0; i < 2; i++) {
        FILE *f = files[i] ? fopen(files[i], "rb") : NULL;
        if (files[i] && !f)
            return iir_fail(err, IIR_ERR_IO, "%s %s cannot be read", i ? "--tls-key" : "--tls-cert",
                            files[i]);
        if (f) fclose(f);
    }
    return cfg->tls_cert ? check_tls_pair(cfg->tls_cert, cfg->tls_key, err) : IIR_OK;
}

/* The budgets' defaults, and a new session's settings must fit them (a daemon whose every session
 * would be refused is refused itself). */
static iir_status check_budget(serve_opts *o, iir_error *err)
{
    iird_budget *b = &o->budget;
    if (!b->total_max) b->total_max = iird_budget_default_total();
    if (!b->session_max) b->session_max = b->total_max < (2ull << 30) ? b->total_max : 2ull << 30;
    if (b->session_max > b->total_max)
        return iir_fail(err, IIR_ERR_INVALID, "--max-session-memory is more than --max-memory");
    uint64_t need = iird_session_estimate(&o->cfg.defaults), held = 0;
    iird_proto_error pe;
    if (!iird_budget_reserve(b, &held, need, &pe))
        return iir_fail(err, IIR_ERR_INVALID, "a new session's settings do not fit: %s",
                        pe.message + sizeof "params: " - 1);
    iird_budget_release(b, &held);
    o->cfg.budget = b;
    return check_files(&o->cfg, err);
}

/* Cross-option checks once everything is parsed. */
static iir_status check(serve_opts *o, iir_error *err)
{
    iird_server_config *cfg = &o->cfg;
    iird_settings *d = &cfg->defaults;
    if (o->method) {
        if (!known_method(o->method))
            return iir_fail(err, IIR_ERR_INVALID, "--method %s is not a method (pt, ir, iir)",
                            o->method);
        snprintf(d->method, sizeof d->method, "%s", o->method);
    }
    if (d->width > cfg->limits.max_width || d->height > cfg->limits.max_height)
        return iir_fail(err, IIR_ERR_INVALID, "--size %dx%d is larger than --max-size %dx%d",
                        d->width, d->height, cfg->limits.max_width, cfg->limits.max_height);
    if (d->width < 16 || d->height < 16)
        return iir_fail(err, IIR_ERR_INVALID, "--size: each side must be at least 16");
    iir_status st = iir_method_params_validate(d->method, &d->params, NULL, NULL, err);
    return st == IIR_OK ? check_budget(o, err) : st;
}

int iird_cmd_serve(int argc, char **argv)
{
    static const struct option longopts[] = {
        {"host", required_argument, 0, OPT_HOST},
        {"port", required_argument, 0, OPT_PORT},
        {"scene", required_argument, 0, OPT_SCENE},
        {"scenes", required_argument, 0, OPT_SCENES},
        {"scenes-follow-links", no_argument, 0, OPT_SCENES_FOLLOW_LINKS},
        {"web", required_argument, 0, OPT_WEB},
        {"max-sessions", required_argument, 0, OPT_MAX_SESSIONS},
        {"max-sessions-per-address", required_argument, 0, OPT_MAX_SESSIONS_PER_ADDRESS},
        {"idle-timeout", required_argument, 0, OPT_IDLE_TIMEOUT},
        {"max-size", required_argument, 0, OPT_MAX_SIZE},
        {"origin", required_argument, 0, OPT_ORIGIN},
        {"token", required_argument, 0, OPT_TOKEN},
        {"tls-cert", required_argument, 0, OPT_TLS_CERT},
        {"tls-key", required_argument, 0, OPT_TLS_KEY},
        {"method", required_argument, 0, OPT_METHOD},
        {"size", required_argument, 0, OPT_SIZE},
        {"verbose", no_argument, 0, OPT_VERBOSE},
        {"max-memory", required_argument, 0, OPT_MAX_MEMORY},
        {"max-session-memory", required_argument, 0, OPT_MAX_SESSION_MEMORY},
        {"render-slots", required_argument, 0, OPT_RENDER_SLOTS},
        {"allow-save", no_argument, 0, OPT_ALLOW_SAVE},
        {"drain-seconds", required_argument, 0, OPT_DRAIN_SECONDS},
        {"trust-proxy", required_argument, 0, OPT_TRUST_PROXY},
        {"max-saved-scenes", required_argument, 0, OPT_MAX_SAVED_SCENES},
        {"save-rate", required_argument, 0, OPT_SAVE_RATE},
        {"cache-max", required_argument, 0, OPT_CACHE_MAX},
        {"help", no_argument, 0, 'h'},
        {0, 0, 0, 0}};
    static const iird_command cmd = {"serve", longopts, serve_usage, parse_option, NULL};
    serve_opts o = {.cfg = {.host = "127.0.0.1",
                            .port = 8080,
                            .max_sessions = 8,
                            .idle_timeout_s = 1800,
                            .drain_seconds = 10,
                            .max_saved_scenes = IIRD_SAVED_DEFAULT,
                            .save_rate = IIRD_SAVE_RATE_DEFAULT,
                            .limits = iird_limits_default(),
                            .defaults = iird_settings_default()}};
    const char *positional = NULL;
    int rc = iird_parse_command(&cmd, argc, argv, &o, &o.cfg.defaults.params, &positional);
    if (rc >= 0) return rc;
    if (positional && o.scene_arg) {
        fprintf(stderr, "iird serve: give the scene once (SCENE or --scene)\n");
        return IIRD_EXIT_USAGE;
    }
    if (!o.cfg.tls_cert != !o.cfg.tls_key) {
        fprintf(stderr, "iird serve: %s needs %s too (give both or neither)\n",
                o.cfg.tls_cert ? "--tls-cert" : "--tls-key",
                o.cfg.tls_cert ? "--tls-key" : "--tls-cert");
        return IIRD_EXIT_USAGE;
    }
    if (o.cfg.max_sessions_per_address == 0) { /* not given: for strangers, not this machine */
        o.cfg.max_sessions_per_address = o.cfg.max_sessions / 4 > 1 ? o.cfg.max_sessions / 4 : 1;
        o.cfg.loopback_unlimited = true;
    }
    o.cfg.scene = o.scene_arg ? o.scene_arg : positional;
    o.cfg.scenes_dir = iird_scenes_dir(o.cfg.scenes_dir);
    o.cfg.web_dir = web_dir(o.web_opt);
    iir_error err = {0};
    if (check(&o, &err) != IIR_OK) return iird_report("serve", &err);
    return iird_server_run(&o.cfg);
}

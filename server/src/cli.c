/* cli.c -- argument parsing helpers, scene lookup and loading, error reporting and interrupt
 * handling shared by the iird subcommands. */
#include "cli.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>

iir_status iird_parse_size(const char *text, int max_dim, int *w, int *h, iir_error *err)
{
    char *end = NULL;
    errno = 0;
    long a = strtol(text, &end, 10);
    if (end == text || *end != 'x' || errno)
        return iir_fail(err, IIR_ERR_INVALID, "--size '%s' is not WIDTHxHEIGHT (e.g. 512x384)",
                        text);
    const char *rest = end + 1;
    long b = strtol(rest, &end, 10);
    if (end == rest || *end || errno)
        return iir_fail(err, IIR_ERR_INVALID, "--size '%s' is not WIDTHxHEIGHT (e.g. 512x384)",
                        text);
    if (a < 1 || b < 1 || a > max_dim || b > max_dim)
        return iir_fail(err, IIR_ERR_INVALID, "--size %ldx%ld: each side must be in [1, %d]", a, b,
                        max_dim);
    *w = (int)a;
    *h = (int)b;
    return IIR_OK;
}

iir_status iird_parse_int(const char *text, const char *what, long lo, long hi, long *out,
                          iir_error *err)
{
    char *end = NULL;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (end == text || *end || errno)
        return iir_fail(err, IIR_ERR_INVALID, "%s '%s' is not an integer", what, text);
    if (v < lo || v > hi)
        return iir_fail(err, IIR_ERR_INVALID, "%s %ld is outside [%ld, %ld]", what, v, lo, hi);
    *out = v;
    return IIR_OK;
}

iir_status iird_parse_u64(const char *text, const char *what, uint64_t *out, iir_error *err)
{
    char *end = NULL;
    errno = 0;
    unsigned long long v = strtoull(text, &end, 10);
    if (end == text || *end || errno || text[0] == '-')
        return iir_fail(err, IIR_ERR_INVALID, "%s '%s' is not a non-negative integer", what, text);
    *out = (uint64_t)v;
    return IIR_OK;
}

iir_status iird_parse_float(const char *text, const char *what, float lo, float hi, float *out,
                            iir_error *err)
{
    char *end = NULL;
    errno = 0;
    float v = strtof(text, &end);
    if (end == text || *end || errno || !isfinite(v))
        return iir_fail(err, IIR_ERR_INVALID, "%s '%s' is not a finite number", what, text);
    if (v < lo || v > hi)
        return iir_fail(err, IIR_ERR_INVALID, "%s %g is outside [%g, %g]", what, (double)v,
                        (double)lo, (double)hi);
    *out = v;
    return IIR_OK;
}

static bool is_dir(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 && S_ISDIR(sb.st_mode);
}

iir_status iird_check_output(const char *path, iir_error *err)
{
    const char *dot = strrchr(path, '.'), *slash = strrchr(path, '/');
    if (!dot || (slash && dot < slash) ||
        (strcasecmp(dot, ".png") && strcasecmp(dot, ".exr") && strcasecmp(dot, ".pfm")))
        return iir_fail(err, IIR_ERR_INVALID, "--out %s: the name must end in .png, .exr or .pfm",
                        path);
    char dir[4096];
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - path) : 1, slash ? path : ".");
    if (slash == path) snprintf(dir, sizeof dir, "/");
    if (!is_dir(dir))
        return iir_fail(err, IIR_ERR_IO, "--out %s: directory '%s' does not exist", path, dir);
    return IIR_OK;
}

const char *iird_scenes_dir(const char *option)
{
    if (option) return option;
    const char *env = getenv("IIR_SCENES");
    if (env && *env) return env;
    if (is_dir("scenes")) return "scenes";
    return IIR_SOURCE_DIR "/scenes";
}

iir_status iird_load_scene(const char *arg, const char *scenes_dir, iir_scene **scene, iir_rt **rt,
                           iir_error *err)
{
    *scene = NULL;
    *rt = NULL;
    if (!arg || strcmp(arg, "builtin") == 0) {
        *scene = iir_scene_create_cornell_box();
        if (!*scene) return iir_fail(err, IIR_ERR_NOMEM, "out of memory building the Cornell box");
    } else {
        char path[4096];
        iir_status st = iir_scene_resolve(arg, scenes_dir, path, sizeof path, err);
        if (st == IIR_OK) st = iir_scene_load(path, scene, err);
        if (st != IIR_OK) return st;
    }
    iir_status st = iir_rt_create(*scene, rt, err);
    if (st != IIR_OK) {
        iir_scene_destroy(*scene);
        *scene = NULL;
    }
    return st;
}

int iird_report(const char *cmd, const iir_error *err)
{
    fprintf(stderr, "iird %s: %s\n", cmd, err->msg);
    return iir_status_exit_code(err->status);
}

/* ---- interrupts ---- */

static volatile sig_atomic_t interrupted;

static void on_signal(int sig)
{
    (void)sig;
    interrupted = 1;
}

void iird_catch_interrupts(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

bool iird_interrupted(void)
{
    return interrupted != 0;
}

double iird_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

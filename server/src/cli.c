/* cli.c -- argument parsing helpers, scene lookup and loading, error reporting and interrupt
 * handling shared by the iird subcommands. */
#include "cli.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <omp.h>
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

const char IIRD_METHOD_HELP[] =
    "method parameters (each method reads the ones it uses; see docs/cli.md):\n"
    "  --spp N              pt: samples per pixel (default 16)\n"
    "  --bounces B          pt, ir: 1 = direct only, 2 = one diffuse bounce (default 2)\n"
    "  --seed S             random seed (default 1); same seed, same image\n"
    "  --vpls N             ir: light paths; iir: VPL set size (default 256)\n"
    "  --kmin K, --kmax K   iir: VPLs replaced per frame (default 4, 8)\n"
    "  --weights W          iir: uniform | voronoi (default voronoi)\n"
    "  --regen-threshold F  iir: regenerate all when more than F of the VPLs die (default 0.5)\n"
    "  --visibility V       ir, iir: shadowmap | rays (default shadowmap)\n"
    "  --sm-res R           shadow-map resolution (default 128)\n"
    "  --sm-bias B          shadow-map bias (see docs/cli.md)\n"
    "  --interleave N       N x N interleaved VPL subsets + filter; 1 = full (default 4)\n"
    "  --clamp C            bound G at C / D^2, D the scene diagonal; 0 = no clamp\n"
    "  --ir-same-random     ir: the same random numbers every frame (default: fresh)\n"
    "  --threads N          OpenMP threads (default: all cores)\n";

static iir_status parse_int_into(const char *arg, const char *what, long lo, long hi, int *out,
                                 iir_error *err)
{
    long v;
    iir_status st = iird_parse_int(arg, what, lo, hi, &v, err);
    if (st == IIR_OK) *out = (int)v;
    return st;
}

static iir_status parse_choice(const char *arg, const char *what, const char *a, const char *b,
                               int *out, iir_error *err)
{
    if (!strcmp(arg, a))
        *out = 0;
    else if (!strcmp(arg, b))
        *out = 1;
    else
        return iir_fail(err, IIR_ERR_INVALID, "%s '%s' must be %s or %s", what, arg, a, b);
    return IIR_OK;
}

static iir_status parse_threads(const char *arg, iir_error *err)
{
    int n = 0;
    iir_status st = parse_int_into(arg, "--threads", 1, 1024, &n, err);
    if (st == IIR_OK) omp_set_num_threads(n);
    return st;
}

bool iird_method_option(int c, const char *arg, iir_params *p, iir_status *st, iir_error *err)
{
    int choice = 0;
    switch (c) {
    case IIRD_OPT_SPP:
        *st = parse_int_into(arg, "--spp", 1, 1 << 20, &p->spp, err);
        break;
    case IIRD_OPT_BOUNCES:
        *st = parse_int_into(arg, "--bounces", 1, 1000, &p->bounces, err);
        break;
    case IIRD_OPT_SEED:
        *st = iird_parse_u64(arg, "--seed", &p->seed, err);
        break;
    case IIRD_OPT_VPLS:
        *st = parse_int_into(arg, "--vpls", 1, 16384, &p->vpls, err);
        break;
    case IIRD_OPT_KMIN:
        *st = parse_int_into(arg, "--kmin", 0, 16384, &p->kmin, err);
        break;
    case IIRD_OPT_KMAX:
        *st = parse_int_into(arg, "--kmax", 0, 16384, &p->kmax, err);
        break;
    case IIRD_OPT_REGEN:
        *st = iird_parse_float(arg, "--regen-threshold", 1e-6f, 1.f, &p->regen_threshold, err);
        break;
    case IIRD_OPT_WEIGHTS:
        *st = parse_choice(arg, "--weights", "uniform", "voronoi", &choice, err);
        p->weights = choice ? IIR_WEIGHTS_VORONOI : IIR_WEIGHTS_UNIFORM;
        break;
    case IIRD_OPT_VISIBILITY:
        *st = parse_choice(arg, "--visibility", "shadowmap", "rays", &choice, err);
        p->visibility = choice ? IIR_VIS_RAYS : IIR_VIS_SHADOWMAP;
        break;
    case IIRD_OPT_SM_RES:
        *st = parse_int_into(arg, "--sm-res", 8, 2048, &p->sm_res, err);
        break;
    case IIRD_OPT_SM_BIAS:
        *st = iird_parse_float(arg, "--sm-bias", 0.f, 1.f, &p->sm_bias, err);
        break;
    case IIRD_OPT_INTERLEAVE:
        *st = parse_int_into(arg, "--interleave", 1, 8, &p->interleave, err);
        break;
    case IIRD_OPT_CLAMP:
        *st = iird_parse_float(arg, "--clamp", 0.f, 1e12f, &p->clamp, err);
        break;
    case IIRD_OPT_IR_SAME:
        p->ir_fresh = false, *st = IIR_OK;
        break;
    case IIRD_OPT_THREADS:
        *st = parse_threads(arg, err);
        break;
    default:
        return false;
    }
    return true;
}

int iird_parse_command(const iird_command *cmd, int argc, char **argv, void *ctx,
                       iir_params *params, const char **scene)
{
    int c;
    iir_error err = {0};
    optind = 1;
    while ((c = getopt_long(argc, argv, "h", cmd->options, NULL)) != -1) {
        iir_status st = IIR_OK;
        if (c == 'h') return cmd->usage(stdout), 0;
        if (c == '?') return cmd->usage(stderr), IIRD_EXIT_USAGE;
        if (!iird_method_option(c, optarg, params, &st, &err))
            st = cmd->option(ctx, c, optarg, &err);
        if (st != IIR_OK) return iird_report(cmd->name, &err);
    }
    if (optind < argc) *scene = argv[optind++];
    if (optind < argc) {
        fprintf(stderr, "iird %s: unexpected argument '%s'\n", cmd->name, argv[optind]);
        return IIRD_EXIT_USAGE;
    }
    return -1;
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

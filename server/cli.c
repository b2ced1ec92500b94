/* cli.c -- argument parsing helpers, scene lookup and loading, animation scripts named by a
 * scene, error reporting and interrupt handling shared by the iird subcommands. */
#include "cli.h"

#include "iir/refine.h"

#include <ctype.h>
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

#include <cjson/cJSON.h>

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
    "  --refine-passes P    refinement converges after P passes (ir, iir: one VPL subset per\n"
    "                       pixel each; pt: P x spp samples) (default 64)\n"
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
    case IIRD_OPT_REFINE_PASSES:
        *st = parse_int_into(arg, "--refine-passes", 1, IIR_REFINE_MAX_PASSES, &p->refine_passes,
                             err);
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

/* ---- animation scripts named by a scene ---- */

static bool is_bare_name(const char *s)
{
    if (!*s || strstr(s, "..")) return false;
    for (; *s; s++)
        if (!isalnum((unsigned char)*s) && *s != '_' && *s != '-' && *s != '.') return false;
    return true;
}

static bool ends_with(const char *s, const char *suffix)
{
    size_t a = strlen(s), b = strlen(suffix);
    return a >= b && strcmp(s + a - b, suffix) == 0;
}

/* The text of a small file (at most 1 MiB), NUL-terminated, malloc'ed; NULL if unreadable. */
static char *read_small_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    enum { MAX = 1 << 20 };
    char *buf = malloc(MAX + 1);
    size_t n = buf ? fread(buf, 1, MAX, f) : 0;
    fclose(f);
    if (buf) buf[n] = '\0';
    return buf;
}

/* The "paths" object of the scene's sidecar (a new cJSON tree, or NULL when it names none), the
 * sidecar's path and its folder. The built-in box borrows the shipped box's sidecar. */
static cJSON *scene_paths(const iir_scene *scene, const char *scenes_dir, char *sidecar, char *dir,
                          size_t n)
{
    cJSON *paths = NULL;
    if (scene->paths_json) {
        snprintf(sidecar, n, "%s", scene->source);
        paths = cJSON_Parse(scene->paths_json);
    } else if (!scene->source[0]) {
        snprintf(sidecar, n, "%s/%s/%s.scene.json", scenes_dir, scene->name, scene->name);
        char *text = read_small_file(sidecar);
        cJSON *root = text ? cJSON_Parse(text) : NULL;
        paths = root ? cJSON_DetachItemFromObjectCaseSensitive(root, "paths") : NULL;
        cJSON_Delete(root);
        free(text);
    }
    const char *slash = strrchr(sidecar, '/');
    snprintf(dir, n, "%.*s", slash ? (int)(slash - sidecar) : 1, slash ? sidecar : ".");
    return cJSON_IsObject(paths) ? paths : (cJSON_Delete(paths), NULL);
}

static iir_status unknown_path(const iir_scene *scene, const char *arg, const cJSON *paths,
                               iir_error *err)
{
    char names[512] = "";
    size_t used = 0;
    for (const cJSON *it = paths ? paths->child : NULL; it && used < sizeof names; it = it->next)
        used += (size_t)snprintf(names + used, sizeof names - used, "%s%s", used ? ", " : "",
                                 it->string);
    return iir_fail(
        err, IIR_ERR_INVALID, "--anim %s: no such file, and scene '%s' names no path '%s' (%s%s)",
        arg, scene->name, arg, used ? "its paths: " : "its sidecar lists no \"paths\"", names);
}

iir_status iird_resolve_anim(const iir_scene *scene, const char *scenes_dir, const char *arg,
                             iir_anim **out, char *label, size_t n, iir_error *err)
{
    struct stat sb;
    *out = NULL;
    if (stat(arg, &sb) == 0 || strchr(arg, '/') || ends_with(arg, ".json") || !is_bare_name(arg)) {
        snprintf(label, n, "%s", arg);
        return iir_anim_load(arg, out, err);
    }
    char sidecar[4096], dir[4096], path[8192];
    cJSON *paths = scene_paths(scene, scenes_dir, sidecar, dir, sizeof sidecar);
    const cJSON *item = paths ? cJSON_GetObjectItemCaseSensitive(paths, arg) : NULL;
    iir_status st = IIR_OK;
    if (!item) {
        st = unknown_path(scene, arg, paths, err);
    } else if (cJSON_IsString(item)) {
        const char *rel = item->valuestring;
        snprintf(path, sizeof path, "%s/%s", dir, rel);
        snprintf(label, n, "%s", path);
        st = rel[0] == '/' || strstr(rel, "..")
                 ? iir_fail(err, IIR_ERR_INVALID,
                            "%s: paths.%s: '%s' must be a path inside the sidecar's folder (no "
                            "'..', not absolute)",
                            sidecar, arg, rel)
                 : iir_anim_load(path, out, err);
    } else if (cJSON_IsObject(item)) {
        char *text = cJSON_PrintUnformatted(item);
        snprintf(label, n, "%s: paths.%s", sidecar, arg);
        st = text ? iir_anim_parse(text, label, out, err)
                  : iir_fail(err, IIR_ERR_NOMEM, "out of memory");
        cJSON_free(text);
    } else {
        st = iir_fail(err, IIR_ERR_FORMAT,
                      "%s: paths.%s: must be a script file name or a script object", sidecar, arg);
    }
    cJSON_Delete(paths);
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

/* cli.c -- argument parsing helpers, the scenes folder, animation scripts named by a scene, error
 * reporting and interrupt handling shared by the iird subcommands; not loading scenes
 * (iir_scene_open). */
#include "cli.h"

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
#include <unistd.h>

#include <cjson/cJSON.h>

#include "iir/ffcache.h"
#include "serve/budget.h" /* iird_parse_bytes: one syntax for every size option */

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

iir_status iird_parse_segment(const char *text, int *index, int *count, iir_error *err)
{
    const char *slash = strchr(text, '/');
    char *end = NULL;
    long i = slash && slash > text && isdigit((unsigned char)text[0]) ? strtol(text, &end, 10) : -1;
    long n = end == slash && isdigit((unsigned char)slash[1]) ? strtol(slash + 1, &end, 10) : -1;
    if (i < 0 || n < 1 || n > 100000 || i >= n || *end)
        return iir_fail(err, IIR_ERR_INVALID,
                        "--segment '%s' must be I/N with 0 <= I < N <= 100000 (the I-th of N "
                        "shares, from 0)",
                        text);
    *index = (int)i;
    *count = (int)n;
    return IIR_OK;
}

void iird_segment_range(int index, int count, int total, int *first, int *end)
{
    *first = (int)((long long)index * total / count);
    *end = (int)((long long)(index + 1) * total / count);
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

/* ======================== method parameters ======================== */

enum { OPT_PARAM_BASE = 2000, OPT_THREADS = 1999, MAX_OPTIONS = 128 };

/* Every distinct parameter name of every method's tables, in table order; NULL-terminated. */
static const iir_param *const *all_params(void)
{
    static const iir_param *rows[MAX_OPTIONS];
    if (rows[0]) return rows;
    int n = 0;
    for (const iir_param_table *const *t = iir_method_all_tables(); *t; t++)
        for (int i = 0; i < (*t)->count && n < MAX_OPTIONS - 1; i++) {
            bool seen = false;
            for (int k = 0; k < n; k++) seen = seen || !strcmp(rows[k]->name, (*t)->rows[i].name);
            if (!seen) rows[n++] = &(*t)->rows[i];
        }
    return rows;
}

/* The command's options, then one per parameter, then --threads. */
static const struct option *build_longopts(const iird_command *cmd)
{
    static struct option opts[MAX_OPTIONS * 2];
    static char names[MAX_OPTIONS][40];
    int n = 0;
    for (const struct option *o = cmd->options; o->name && n < MAX_OPTIONS; o++) opts[n++] = *o;
    const iir_param *const *rows = all_params();
    for (int i = 0; rows[i]; i++) {
        iir_param_option_name(rows[i], names[i], sizeof names[i]);
        bool flag = rows[i]->type == IIR_PARAM_BOOL;
        opts[n++] = (struct option){names[i], flag ? optional_argument : required_argument, 0,
                                    OPT_PARAM_BASE + i};
    }
    opts[n++] = (struct option){"threads", required_argument, 0, OPT_THREADS};
    opts[n] = (struct option){0, 0, 0, 0};
    return opts;
}

const iir_param *iird_param_by_option(const char *name)
{
    char key[40];
    snprintf(key, sizeof key, "%s", name);
    for (char *c = key; *c; c++)
        if (*c == '-') *c = '_';
    return iir_method_any_param(key);
}

iir_status iird_parse_param(const char *name, const char *text, iir_params *p, iir_error *err)
{
    const iir_param *row = iird_param_by_option(name);
    if (!row) return iir_fail(err, IIR_ERR_INVALID, "--%s is not a parameter of any method", name);
    double v = 0.0;
    iir_status st = iir_param_parse(row, text, &v, err);
    if (st == IIR_OK) st = iir_method_param_set(p, row->name, v, err);
    if (st != IIR_OK) { /* every message starts with the parameter's name: spell it as an option */
        char opt[48] = "--";
        iir_param_option_name(row, opt + 2, sizeof opt - 2);
        iir_param_reword(err, row, opt);
    }
    return st;
}

static iir_status parse_threads(const char *arg, iir_error *err)
{
    long n = 0;
    iir_status st = iird_parse_int(arg, "--threads", 1, 1024, &n, err);
    if (st == IIR_OK) omp_set_num_threads((int)n);
    return st;
}

/* The next method of a comma-separated list into buf; NULL at the end. */
static const char *next_method(const char *list, char *buf, size_t n)
{
    if (!list || !*list) return NULL;
    const char *comma = strchr(list, ',');
    size_t len = comma ? (size_t)(comma - list) : strlen(list);
    snprintf(buf, n, "%.*s", (int)len, list);
    return comma ? comma + 1 : list + len;
}

/* Whether some method of the list declares name; its names into have (for the message). */
static bool declared_by(const char *methods, const char *name, char *have, size_t n)
{
    char m[32];
    bool found = false;
    have[0] = '\0';
    for (const char *rest = methods; (rest = next_method(rest, m, sizeof m));) {
        found = found || iir_method_find_param(m, name);
        size_t used = strlen(have);
        snprintf(have + used, n - used, "%s%s", used ? ", " : "", m);
    }
    return found;
}

iir_status iird_check_params_for(const char *methods, const iir_params *p, iir_error *err)
{
    char have[128], opt[40];
    for (uint32_t k = 0; methods && k < p->count; k++) {
        if (declared_by(methods, p->v[k].name, have, sizeof have)) continue;
        iir_param_option_name(iir_method_any_param(p->v[k].name), opt, sizeof opt);
        return iir_fail(err, IIR_ERR_INVALID,
                        "--%s is not a parameter of %s (--help lists the parameters)", opt, have);
    }
    return IIR_OK;
}

iir_status iird_check_memory(const char *method, const iir_params *p, int width, int height,
                             iir_error *err)
{
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    double have = pages > 0 && size > 0 ? (double)pages * (double)size : 0.0;
    double need = (double)iir_method_memory(method, p, width, height);
    if (have <= 0.0 || need <= 0.9 * have) return IIR_OK;
    return iir_fail(err, IIR_ERR_INVALID,
                    "%s with these parameters would need about %.0f MiB for %dx%d, more than 90%% "
                    "of this machine's %.0f MiB: ask for fewer VPLs, smaller shadow maps or a "
                    "smaller image",
                    method, need / 1048576.0, width, height, have / 1048576.0);
}

/* ---- help ---- */

/* "N", "F", "shadowmap|rays", "[=BOOL]": what an option takes. */
static void metavar(const iir_param *row, char *buf, size_t n)
{
    switch (row->type) {
    case IIR_PARAM_ENUM:
        buf[0] = '\0';
        for (int i = 0; row->choices[i]; i++) {
            size_t used = strlen(buf);
            snprintf(buf + used, n - used, "%s%s", i ? "|" : "", row->choices[i]);
        }
        break;
    case IIR_PARAM_BOOL:
        snprintf(buf, n, "[=BOOL]");
        break;
    case IIR_PARAM_FLOAT:
        snprintf(buf, n, "F");
        break;
    default:
        snprintf(buf, n, "N");
    }
}

static void print_row(FILE *f, const iir_param *row)
{
    char opt[40], var[64], def[32], lo[32], hi[32], left[128];
    iir_param_option_name(row, opt, sizeof opt);
    metavar(row, var, sizeof var);
    iir_param_format(row, row->def, def, sizeof def);
    snprintf(left, sizeof left, "--%s%s%s", opt, row->type == IIR_PARAM_BOOL ? "" : " ", var);
    fprintf(f, "  %-26s %s\n", left, row->help);
    if (row->type == IIR_PARAM_INT || row->type == IIR_PARAM_U64 || row->type == IIR_PARAM_FLOAT) {
        iir_param_format(row, row->lo, lo, sizeof lo);
        iir_param_format(row, row->hi, hi, sizeof hi);
        fprintf(f, "  %-26s (default %s%s%s, [%s, %s])\n", "", def, row->unit[0] ? " " : "",
                row->unit, lo, hi);
    } else {
        fprintf(f, "  %-26s (default %s)\n", "", def);
    }
}

/* Whether table t belongs to one of the methods (NULL = any). */
static bool table_of(const iir_param_table *t, const char *methods)
{
    char m[32];
    if (!methods) return true;
    for (const char *rest = methods; (rest = next_method(rest, m, sizeof m));) {
        const iir_param_table *const *ts = iir_method_tables(m);
        for (int i = 0; ts && ts[i]; i++)
            if (ts[i] == t) return true;
    }
    return false;
}

void iird_print_params(FILE *f, const char *methods)
{
    fprintf(f, "\nparameters%s%s (docs/cli.md; booleans as --name or --name=false):\n",
            methods ? " of " : " of every method", methods ? methods : "");
    for (const iir_param_table *const *t = iir_method_all_tables(); *t; t++) {
        if (!table_of(*t, methods)) continue;
        fprintf(f, " %s:\n", (*t)->title);
        for (int i = 0; i < (*t)->count; i++) print_row(f, &(*t)->rows[i]);
    }
    fprintf(f, "  --threads N                OpenMP threads (default: all cores)\n");
}

/* The "live session" cell: the most a live session may ask for, where that is less. */
static void live_cell(const iir_param *r, char *buf, size_t n)
{
    char v[32];
    buf[0] = '\0';
    if (r->live_hi > 0.0) {
        iir_param_format(r, r->live_hi, v, sizeof v);
        snprintf(buf, n, "at most %s", v);
    }
}

void iird_settings_text(const char *method, const iir_params *p, char *buf, size_t n)
{
    const iir_param_table *const *t = iir_method_tables(method);
    size_t used = 0;
    buf[0] = '\0';
    for (int k = 0; t && t[k]; k++)
        for (int i = 0; i < t[k]->count && used < n; i++) {
            const iir_param *row = &t[k]->rows[i];
            char opt[40], v[32];
            iir_param_option_name(row, opt, sizeof opt);
            iir_param_format(row, iir_method_param_value(row, p), v, sizeof v);
            used += (size_t)snprintf(buf + used, n - used, "%s%s %s", used ? ", " : "", opt, v);
        }
}

void iird_print_params_markdown(FILE *f)
{
    for (const iir_param_table *const *t = iir_method_all_tables(); *t; t++) {
        fprintf(f, "\n#### %s\n\n", (*t)->title);
        fprintf(f, "| option | values | default | live session | on change | meaning |\n");
        fprintf(f, "|---|---|---|---|---|---|\n");
        for (int i = 0; i < (*t)->count; i++) {
            const iir_param *r = &(*t)->rows[i];
            char opt[40], values[96], def[32], lo[32], hi[32], live[80];
            iir_param_option_name(r, opt, sizeof opt);
            iir_param_format(r, r->def, def, sizeof def);
            iir_param_format(r, r->lo, lo, sizeof lo);
            iir_param_format(r, r->hi, hi, sizeof hi);
            live_cell(r, live, sizeof live);
            if (r->type == IIR_PARAM_ENUM) {
                values[0] = '\0';
                for (int k = 0; r->choices[k]; k++)
                    snprintf(values + strlen(values), sizeof values - strlen(values), "%s%s",
                             k ? ", " : "", r->choices[k]);
            } else if (r->type == IIR_PARAM_BOOL) {
                snprintf(values, sizeof values, "true, false");
            } else {
                snprintf(values, sizeof values, "%s %s..%s%s%s", iir_param_type_name(r->type), lo,
                         hi, r->unit[0] ? " " : "", r->unit);
            }
            fprintf(f, "| `--%s` | %s | %s | %s | %s | %s |\n", opt, values, def, live,
                    r->effect == IIR_PARAM_LIVE ? "kept" : "restart", r->help);
        }
    }
}

/* ---- parsing ---- */

/* A parameter option that failed its check against the first method declaring it (rows of one
 * name may differ in unit: ir's vpls are "paths", iir's "VPLs"), kept until the methods are
 * known. */
typedef struct param_error {
    const iir_param *row; /* NULL: none */
    const char *text;
    iir_error err;
} param_error;

/* pe's error again, against the row of the first method of the list that declares the parameter
 * and refuses the value (its own unit and range), spelt as an option; pe's own error when none
 * does (another method of the list refused it). */
static iir_status param_error_for(const char *methods, param_error *pe, iir_error *err)
{
    char m[32];
    *err = pe->err;
    for (const char *rest = methods; (rest = next_method(rest, m, sizeof m));) {
        const iir_param *row = iir_method_find_param(m, pe->row->name);
        double v = 0.0;
        iir_error e = {0};
        if (!row || (iir_param_parse(row, pe->text, &v, &e) == IIR_OK &&
                     iir_param_check(row, v, false, &e) == IIR_OK))
            continue;
        char opt[48] = "--";
        iir_param_option_name(row, opt + 2, sizeof opt - 2);
        iir_param_reword(&e, row, opt);
        *err = e;
        break;
    }
    return err->status;
}

int iird_parse_command(const iird_command *cmd, int argc, char **argv, void *ctx,
                       iir_params *params, const char **scene)
{
    const struct option *longopts = build_longopts(cmd);
    const iir_param *const *rows = all_params();
    int c;
    bool help = false;
    iir_error err = {0};
    param_error pe = {0};
    optind = 1;
    while ((c = getopt_long(argc, argv, "h", longopts, NULL)) != -1) {
        iir_status st = IIR_OK;
        if (c == 'h') help = true;
        if (c == '?') return cmd->usage(stderr), IIRD_EXIT_USAGE;
        if (c >= OPT_PARAM_BASE) {
            const char *text = optarg ? optarg : "true";
            st = iird_parse_param(rows[c - OPT_PARAM_BASE]->name, text, params, &err);
            if (st != IIR_OK && !pe.row) /* worded once --method is known (it may come later) */
                pe = (param_error){rows[c - OPT_PARAM_BASE], text, err};
            continue;
        }
        if (c == OPT_THREADS)
            st = parse_threads(optarg, &err);
        else if (c != 'h')
            st = cmd->option(ctx, c, optarg, &err);
        if (st != IIR_OK) return iird_report(cmd->name, pe.row ? &pe.err : &err);
    }
    const char *methods = cmd->methods ? cmd->methods(ctx) : NULL;
    if (pe.row && !help) {
        param_error_for(methods, &pe, &err);
        return iird_report(cmd->name, &err);
    }
    if (help) return cmd->usage(stdout), iird_print_params(stdout, methods), 0;
    if (optind < argc) *scene = argv[optind++];
    if (optind < argc) {
        fprintf(stderr, "iird %s: unexpected argument '%s'\n", cmd->name, argv[optind]);
        return IIRD_EXIT_USAGE;
    }
    if (iird_check_params_for(methods, params, &err) != IIR_OK) return iird_report(cmd->name, &err);
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
    return iird_prepare_parent(path, "--out", err);
}

iir_status iird_set_cache_max(const char *arg, iir_error *err)
{
    uint64_t bytes = 0;
    char text[32];
    if (!iird_parse_bytes(arg, &bytes) || bytes < (1u << 20))
        return iir_fail(err, IIR_ERR_INVALID,
                        "--cache-max '%s' is not a size of at least 1M (bytes, or with K, M, G, T)",
                        arg);
    snprintf(text, sizeof text, "%llu", (unsigned long long)bytes);
    setenv(IIR_FFCACHE_MAX_ENV, text, 1); /* read by the cache's saves (iir/ffcache.h) */
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

/* ARG names a script file rather than a path of the scene's sidecar. */
static bool anim_is_file(const char *arg)
{
    struct stat sb;
    return stat(arg, &sb) == 0 || strchr(arg, '/') || ends_with(arg, ".json") || !is_bare_name(arg);
}

/* The script's scenes folder when it is one (else a warning when the scene needs it: not the
 * built-in box), copied into o->scenes_buf. */
static const char *script_scenes(const char *cmd, const iir_anim *a, iird_anim_origin *o)
{
    const char *dir = iir_anim_scenes_dir(a);
    if (!dir[0]) return NULL;
    if (is_dir(dir)) return snprintf(o->scenes_buf, sizeof o->scenes_buf, "%s", dir), o->scenes_buf;
    if (o->scene && strcmp(o->scene, "builtin"))
        fprintf(stderr,
                "iird %s: warning: the script's scenes folder %s is not a folder here; looking "
                "'%s' up in %s (give --scenes DIR)\n",
                cmd, dir, o->scene, iird_scenes_dir(NULL));
    return NULL;
}

void iird_anim_origin_read(const char *cmd, const char *scene_arg, const char *scenes_arg,
                           const char *anim_arg, iird_anim_origin *o)
{
    *o = (iird_anim_origin){.scene = scene_arg};
    iir_anim *a = NULL;
    iir_error err = {0};
    if (anim_arg && anim_is_file(anim_arg) && iir_anim_load(anim_arg, &a, &err) == IIR_OK) {
        snprintf(o->scene_buf, sizeof o->scene_buf, "%s", iir_anim_scene(a));
        if (!scene_arg && o->scene_buf[0]) o->scene = o->scene_buf;
        if (!scenes_arg) o->scenes_dir = script_scenes(cmd, a, o);
        iir_anim_size(a, &o->width, &o->height);
    }
    iir_anim_destroy(a);
    if (!o->scenes_dir) o->scenes_dir = iird_scenes_dir(scenes_arg);
}

/* The scene opened from arg is the one called name: the argument itself, its last path
 * component, or the loaded scene's short name. */
static bool same_scene(const char *name, const char *arg, const iir_scene *scene)
{
    if (!arg) return !strcmp(name, "builtin");
    size_t len = strlen(arg);
    while (len > 1 && arg[len - 1] == '/') len--;
    size_t start = len;
    while (start > 0 && arg[start - 1] != '/') start--;
    bool base = strlen(name) == len - start && !strncmp(arg + start, name, len - start);
    return base || !strcmp(name, arg) || !strcmp(name, scene->name);
}

void iird_warn_anim_scene(const char *cmd, const iir_anim *anim, const char *scene_arg,
                          const iir_scene *scene)
{
    const char *named = iir_anim_scene(anim);
    if (!named[0] || same_scene(named, scene_arg, scene)) return;
    fprintf(stderr,
            "iird %s: warning: the script was made on scene '%s'; rendering it on '%s' (give "
            "SCENE %s to render it there)\n",
            cmd, named, scene_arg ? scene_arg : "builtin", named);
}

iir_status iird_resolve_anim(const iir_scene *scene, const char *scenes_dir, const char *arg,
                             iir_anim **out, char *label, size_t n, iir_error *err)
{
    *out = NULL;
    if (anim_is_file(arg)) {
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

/* ---- output folders ---- */

/* mkdir -p dir, then a probe file created and removed in it; `value` is what the user gave. */
static iir_status prepare_dir(const char *dir, const char *option, const char *value,
                              iir_error *err)
{
    char buf[4096];
    if (!*dir) return iir_fail(err, IIR_ERR_IO, "%s '%s': an empty folder name", option, value);
    if (snprintf(buf, sizeof buf, "%s", dir) >= (int)sizeof buf)
        return iir_fail(err, IIR_ERR_IO, "%s %s: the name is too long", option, value);
    for (char *p = buf + 1; *p; p++) {
        if (*p != '/' || p[-1] == '/') continue;
        *p = '\0';
        int e = mkdir(buf, 0777) == 0 ? 0 : errno;
        *p = '/';
        if (e && e != EEXIST)
            return iir_fail(err, IIR_ERR_IO, "%s %s: cannot create %.*s: %s", option, value,
                            (int)(p - buf), buf, strerror(e));
    }
    if (mkdir(buf, 0777) != 0 && errno != EEXIST)
        return iir_fail(err, IIR_ERR_IO, "%s %s: cannot create %s: %s", option, value, dir,
                        strerror(errno));
    if (!is_dir(dir))
        return iir_fail(err, IIR_ERR_IO, "%s %s: %s exists and is not a folder", option, value,
                        dir);
    char probe[4200];
    snprintf(probe, sizeof probe, "%s/.iird-probe-XXXXXX", dir);
    int fd = mkstemp(probe);
    if (fd < 0)
        return iir_fail(err, IIR_ERR_IO, "%s %s: cannot write into %s: %s", option, value, dir,
                        strerror(errno));
    close(fd);
    unlink(probe);
    return IIR_OK;
}

iir_status iird_prepare_dir(const char *dir, const char *option, iir_error *err)
{
    return prepare_dir(dir, option, dir, err);
}

iir_status iird_prepare_parent(const char *path, const char *option, iir_error *err)
{
    const char *slash = strrchr(path, '/');
    char dir[4096];
    if (!slash)
        snprintf(dir, sizeof dir, ".");
    else if (slash == path)
        snprintf(dir, sizeof dir, "/");
    else
        snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    return prepare_dir(dir, option, path, err);
}

const char *iird_method_choices(void)
{
    static char buf[256];
    size_t n = 0;
    buf[0] = '\0';
    for (const char *const *m = iir_method_names(); *m && n < sizeof buf; m++)
        n += (size_t)snprintf(buf + n, sizeof buf - n, "%s%s", n ? " | " : "", *m);
    return buf;
}

/* bench_out.c -- what `iird bench` leaves behind: DIR/frames.csv (one row per run and frame),
 * DIR/summary.json (per run statistics, the machine, the command line, the iir/ir ratios), the
 * summary on stdout, and the charts drawn by tools/plot_bench.py. Columns and keys are documented
 * in docs/cli.md; not the measuring itself (bench.c). */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "bench.h"
#include "iir/isa.h"
#include "cli.h"

/* ---- per-run statistics ---- */

typedef struct run_summary {
    double mean_ms, median_ms, p95_ms, fps, phase[IIR_PHASE_COUNT];
    double counter[IIR_MAX_COUNTERS]; /* per frame: the method's counters (a share's mean) */
    double rmse, relmse, flicker;     /* means over the frames that have them; NAN if none */
    double rays[IIR_RAY_KIND_COUNT], rays_total;  /* per frame */
    double inserted, deleted, invalidated, smaps; /* per frame */
    double vpl_evals;                             /* per frame: pixel-VPL pairs shaded */
    double vpl_reused; /* per frame: of those, pairs kept VPLs' columns held */
    int regenerations, scored;
    double rss_peak_mb, method_mb;
    double min_lum; /* darkest frame's mean luminance: a black frame shows as 0 */
} run_summary;

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* Median and nearest-rank 95th percentile of the frame times of frames 1.. (sorted in tmp). */
static void percentiles(const iird_bench *b, int r, double *tmp, run_summary *s)
{
    int n = b->frames - 1;
    for (int i = 1; i < b->frames; i++)
        tmp[i - 1] = b->rows[(size_t)r * b->frames + i].stats.total_ms;
    qsort(tmp, (size_t)n, sizeof *tmp, cmp_double);
    s->median_ms = n % 2 ? tmp[n / 2] : 0.5 * (tmp[n / 2 - 1] + tmp[n / 2]);
    int k = (int)ceil(0.95 * n) - 1;
    s->p95_ms = tmp[k < 0 ? 0 : k];
}

/* Timing, rays and VPL churn over frames 1.. (frame 0 is every method's cold start); errors over
 * the reference frames. */
static run_summary summarise(const iird_bench *b, int r, double *tmp)
{
    run_summary s = {.min_lum = INFINITY};
    double n = b->frames - 1, err[3] = {0};
    int n_err = 0, n_fl = 0;
    for (int i = 0; i < b->frames; i++) {
        const iird_bench_row *row = &b->rows[(size_t)r * b->frames + i];
        const iir_frame_stats *st = &row->stats;
        s.rss_peak_mb = fmax(s.rss_peak_mb, row->rss_mb);
        s.min_lum = fmin(s.min_lum, row->mean_lum);
        if (!isnan(row->relmse)) err[0] += row->rmse, err[1] += row->relmse, n_err++;
        if (!isnan(row->flicker)) err[2] += row->flicker, n_fl++;
        if (i == 0) continue;
        s.mean_ms += st->total_ms / n;
        for (int p = 0; p < IIR_PHASE_COUNT; p++) s.phase[p] += st->phase_ms[p] / n;
        for (int c = 0; c < IIR_MAX_COUNTERS; c++) s.counter[c] += st->counter[c] / n;
        for (int k = 0; k < IIR_RAY_KIND_COUNT; k++) s.rays[k] += (double)st->rays.n[k] / n;
        s.inserted += st->vpl.inserted / n;
        s.deleted += st->vpl.deleted / n;
        s.invalidated += st->vpl.invalidated / n;
        s.smaps += st->vpl.shadowmaps / n;
        s.vpl_evals += (double)st->vpl_evals / n;
        s.vpl_reused += (double)st->vpl_reused / n;
        s.regenerations += (int)st->vpl.regenerated;
        s.method_mb += row->method_mb / n;
    }
    for (int k = 0; k < IIR_RAY_KIND_COUNT; k++) s.rays_total += s.rays[k];
    percentiles(b, r, tmp, &s);
    s.fps = 1000.0 / s.mean_ms;
    s.rmse = n_err ? err[0] / n_err : NAN;
    s.relmse = n_err ? err[1] / n_err : NAN;
    s.flicker = n_fl ? err[2] / n_fl : NAN;
    s.scored = n_err;
    return s;
}

static iir_status summarise_all(const iird_bench *b, run_summary *s, iir_error *err)
{
    double *tmp = malloc(sizeof(double) * (size_t)b->frames);
    if (!tmp) return iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    for (int r = 0; r < b->num_runs; r++) s[r] = summarise(b, r, tmp);
    free(tmp);
    return IIR_OK;
}

/* The ir run an iir run is compared with: the same setting, else ir's only run. -1 if none. */
static int partner(const iird_bench *b, int r)
{
    int only = -1, n = 0;
    for (int q = 0; q < b->num_runs; q++) {
        if (strcmp(b->runs[q].method, "ir")) continue;
        if (!strcmp(b->runs[q].setting, b->runs[r].setting)) return q;
        only = q, n++;
    }
    return n == 1 ? only : -1;
}

/* ---- frames.csv ---- */

/* The columns a run's method may fill: the phases and counters some run's method declares (a row
 * leaves those of its method's undeclared empty). */
typedef struct csv_columns {
    bool phase[IIR_PHASE_COUNT];
    const char *counter[4 * IIR_MAX_COUNTERS]; /* names, first seen first */
    int num_counters;
} csv_columns;

static csv_columns columns_of(const iird_bench *b)
{
    csv_columns c;
    memset(&c, 0, sizeof c);
    for (int r = 0; r < b->num_runs; r++) {
        const iir_phase *ph;
        const iir_counter *ct;
        int np = iir_method_phases(b->runs[r].method, &ph);
        for (int i = 0; i < np; i++) c.phase[ph[i]] = true;
        int nc = iir_method_counters(b->runs[r].method, &ct);
        for (int i = 0; i < nc; i++) {
            int k = 0;
            while (k < c.num_counters && strcmp(c.counter[k], ct[i].name)) k++;
            if (k == c.num_counters && k < (int)(sizeof c.counter / sizeof c.counter[0]))
                c.counter[c.num_counters++] = ct[i].name;
        }
    }
    return c;
}

static bool declares_phase(const char *method, iir_phase p)
{
    const iir_phase *ph;
    int n = iir_method_phases(method, &ph);
    for (int i = 0; i < n; i++)
        if (ph[i] == p) return true;
    return false;
}

static void csv_header(FILE *f, const csv_columns *cols)
{
    fprintf(f, "method,setting,frame,total_ms");
    for (int p = 0; p < IIR_PHASE_COUNT; p++)
        if (cols->phase[p]) fprintf(f, ",%s_ms", iir_phase_name((iir_phase)p));
    for (int k = 0; k < IIR_RAY_KIND_COUNT; k++)
        fprintf(f, ",rays_%s", iir_ray_kind_name((iir_ray_kind)k));
    fprintf(f, ",vpls,vpls_valid,vpls_invalidated,vpls_deleted,vpls_inserted,vpls_null,"
               "regenerated,shadowmaps,vpls_desc,vpl_evals,vpl_reused");
    for (int k = 0; k < cols->num_counters; k++) fprintf(f, ",%s", cols->counter[k]);
    fprintf(f, ",ctl_target_ms,ctl_vpls,ctl_interleave,ctl_sm_res,rss_mb,method_mb,mean_lum,rmse,"
               "relmse,flicker\n");
}

/* A row's phase times and counters in cols' columns: empty where its method has none. */
static void csv_declared(FILE *f, const csv_columns *cols, const char *method,
                         const iir_frame_stats *s, bool counters)
{
    if (!counters) {
        for (int p = 0; p < IIR_PHASE_COUNT; p++) {
            if (!cols->phase[p]) continue;
            if (declares_phase(method, (iir_phase)p))
                fprintf(f, ",%.4f", s->phase_ms[p]);
            else
                fputc(',', f);
        }
        return;
    }
    for (int k = 0; k < cols->num_counters; k++) {
        int i = iir_method_counter_index(method, cols->counter[k]);
        if (i >= 0)
            fprintf(f, ",%.6g", s->counter[i]);
        else
            fputc(',', f);
    }
}

static void csv_number(FILE *f, double v, const char *end)
{
    if (isnan(v))
        fputs(end, f);
    else
        fprintf(f, "%.6g%s", v, end);
}

static void csv_row(FILE *f, const csv_columns *cols, const iird_bench_run *run, int frame,
                    const iird_bench_row *r)
{
    const iir_frame_stats *s = &r->stats;
    const iir_vpl_counts *c = &s->vpl;
    fprintf(f, "%s,%s,%d,%.4f", run->method, run->setting, frame, s->total_ms);
    csv_declared(f, cols, run->method, s, false);
    for (int k = 0; k < IIR_RAY_KIND_COUNT; k++)
        fprintf(f, ",%llu", (unsigned long long)s->rays.n[k]);
    fprintf(f, ",%u,%u,%u,%u,%u,%u,%u,%u,%u,%llu,%llu", c->count, c->valid, c->invalidated,
            c->deleted, c->inserted, c->null_samples, c->regenerated, c->shadowmaps, c->descendants,
            (unsigned long long)s->vpl_evals, (unsigned long long)s->vpl_reused);
    csv_declared(f, cols, run->method, s, true);
    const iir_ctl_report *k = &s->ctl; /* zero without target_fps */
    fprintf(f, ",%.3f,%d,%d,%d,%.2f,%.3f,%.6g,", k->target_ms, k->setting.vpls,
            k->setting.interleave, k->setting.sm_res, r->rss_mb, r->method_mb, r->mean_lum);
    csv_number(f, r->rmse, ",");
    csv_number(f, r->relmse, ",");
    csv_number(f, r->flicker, "\n");
}

iir_status iird_bench_write_csv(const iird_bench *b, iir_error *err)
{
    if (!b->o->out_dir) return IIR_OK;
    char path[4200];
    snprintf(path, sizeof path, "%s/frames.csv", b->o->out_dir);
    FILE *f = fopen(path, "w");
    if (!f) return iir_fail(err, IIR_ERR_IO, "cannot write %s", path);
    csv_columns cols = columns_of(b);
    csv_header(f, &cols);
    for (int r = 0; r < b->num_runs; r++)
        for (int i = 0; i < b->frames; i++)
            csv_row(f, &cols, &b->runs[r], b->first + i, &b->rows[(size_t)r * b->frames + i]);
    if (fclose(f) != 0) return iir_fail(err, IIR_ERR_IO, "cannot write %s", path);
    return IIR_OK;
}

/* ---- summary.json ---- */

/* A number, or null where it is not finite (JSON has no NaN). */
static void add_num(cJSON *o, const char *key, double v)
{
    cJSON_AddItemToObject(o, key, isfinite(v) ? cJSON_CreateNumber(v) : cJSON_CreateNull());
}

static void cpu_model(char *buf, size_t n)
{
    FILE *f = fopen("/proc/cpuinfo", "r");
    char line[512];
    snprintf(buf, n, "unknown");
    while (f && fgets(line, sizeof line, f)) {
        char *colon = strchr(line, ':');
        if (strncmp(line, "model name", 10) || !colon) continue;
        snprintf(buf, n, "%s", colon + 2);
        buf[strcspn(buf, "\n")] = '\0';
        break;
    }
    if (f) fclose(f);
}

static cJSON *machine_json(void)
{
    char model[256];
    cpu_model(model, sizeof model);
    cJSON *m = cJSON_CreateObject();
    cJSON_AddNumberToObject(m, "nproc", (double)sysconf(_SC_NPROCESSORS_ONLN));
    cJSON_AddNumberToObject(m, "omp_threads", omp_get_max_threads());
    cJSON_AddStringToObject(m, "cpu_model", model);
    cJSON_AddStringToObject(m, "isa", iir_isa_name(iir_isa_default()));
    return m;
}

static cJSON *run_json(const iird_bench_run *run, const run_summary *s)
{
    cJSON *o = cJSON_CreateObject(), *ph = cJSON_CreateObject(), *rays = cJSON_CreateObject();
    cJSON *churn = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "method", run->method);
    cJSON_AddStringToObject(o, "setting", run->setting);
    add_num(o, "mean_ms", s->mean_ms);
    add_num(o, "median_ms", s->median_ms);
    add_num(o, "p95_ms", s->p95_ms);
    add_num(o, "fps", s->fps);
    const iir_phase *phases;
    int np = iir_method_phases(run->method, &phases);
    for (int p = 0; p < np; p++) add_num(ph, iir_phase_name(phases[p]), s->phase[phases[p]]);
    cJSON_AddItemToObject(o, "phase_ms", ph);
    const iir_counter *ct;
    int nc = iir_method_counters(run->method, &ct);
    cJSON *counters = cJSON_AddObjectToObject(o, "counters_per_frame");
    for (int c = 0; c < nc && counters; c++) add_num(counters, ct[c].name, s->counter[c]);
    add_num(o, "rmse", s->rmse);
    add_num(o, "relmse", s->relmse);
    add_num(o, "flicker", s->flicker);
    cJSON_AddNumberToObject(o, "scored_frames", s->scored);
    for (int k = 0; k < IIR_RAY_KIND_COUNT; k++)
        if (s->rays[k] > 0) add_num(rays, iir_ray_kind_name((iir_ray_kind)k), s->rays[k]);
    add_num(rays, "total", s->rays_total);
    cJSON_AddItemToObject(o, "rays_per_frame", rays);
    add_num(churn, "inserted", s->inserted);
    add_num(churn, "deleted", s->deleted);
    add_num(churn, "invalidated", s->invalidated);
    add_num(churn, "shadowmaps", s->smaps);
    cJSON_AddItemToObject(o, "vpl_churn_per_frame", churn);
    cJSON_AddNumberToObject(o, "regenerations", s->regenerations);
    add_num(o, "vpl_evals_per_frame", s->vpl_evals);
    add_num(o, "vpl_reused_per_frame", s->vpl_reused);
    add_num(o, "rss_peak_mb", s->rss_peak_mb);
    add_num(o, "method_mb", s->method_mb);
    add_num(o, "min_mean_lum", s->min_lum);
    return o;
}

static cJSON *ratios_json(const iird_bench *b, const run_summary *s)
{
    cJSON *a = cJSON_CreateArray();
    for (int r = 0; r < b->num_runs; r++) {
        int q = strcmp(b->runs[r].method, "iir") ? -1 : partner(b, r);
        if (q < 0) continue;
        cJSON *o = cJSON_CreateObject();
        cJSON_AddStringToObject(o, "iir", b->runs[r].setting);
        cJSON_AddStringToObject(o, "ir", b->runs[q].setting);
        add_num(o, "fps", s[r].fps / s[q].fps);
        add_num(o, "relmse", s[r].relmse / s[q].relmse);
        add_num(o, "rmse", s[r].rmse / s[q].rmse);
        add_num(o, "flicker", s[r].flicker / s[q].flicker);
        cJSON_AddItemToArray(a, o);
    }
    return a;
}

static cJSON *command_json(const iird_bench_opts *o)
{
    char cmd[4096] = "iird";
    size_t used = strlen(cmd);
    for (int i = 0; i < o->argc && used < sizeof cmd; i++)
        used += (size_t)snprintf(cmd + used, sizeof cmd - used, " %s", o->argv[i]);
    return cJSON_CreateString(cmd);
}

static cJSON *run_info_json(const iird_bench *b)
{
    char hash[32], date[64];
    time_t now = time(NULL);
    struct tm tm;
    strftime(date, sizeof date, "%Y-%m-%dT%H:%M:%SZ", gmtime_r(&now, &tm));
    snprintf(hash, sizeof hash, "%016llx", (unsigned long long)b->scene_hash);
    cJSON *o = cJSON_CreateObject(), *refs = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "version", IIR_VERSION);
    cJSON_AddStringToObject(o, "date", date);
    cJSON_AddItemToObject(o, "command", command_json(b->o));
    cJSON_AddItemToObject(o, "machine", machine_json());
    cJSON_AddStringToObject(o, "scene", b->scene->name);
    cJSON_AddStringToObject(o, "scene_hash", hash);
    cJSON_AddStringToObject(o, "path", b->path_label);
    cJSON_AddNumberToObject(o, "path_frames", b->path_frames);
    cJSON_AddNumberToObject(o, "first_frame", b->first);
    cJSON_AddNumberToObject(o, "frames", b->frames);
    cJSON_AddNumberToObject(o, "width", b->o->width);
    cJSON_AddNumberToObject(o, "height", b->o->height);
    cJSON_AddStringToObject(o, "timing", "means over the frames after the first of the range");
    cJSON_AddNumberToObject(refs, "spp", b->o->ref_spp);
    cJSON_AddNumberToObject(refs, "every", b->o->ref_every);
    cJSON_AddBoolToObject(refs, "antialiased", b->o->ref_aa);
    cJSON_AddNumberToObject(refs, "needed", b->refs_total);
    cJSON_AddNumberToObject(refs, "from_cache", b->refs_cached);
    add_num(refs, "seconds", b->refs_s);
    cJSON_AddStringToObject(refs, "cache", b->cache_dir);
    cJSON_AddItemToObject(o, "references", refs);
    add_num(o, "wall_seconds", b->wall_s);
    return o;
}

iir_status iird_bench_write_json(const iird_bench *b, iir_error *err)
{
    if (!b->o->out_dir) return IIR_OK;
    run_summary s[IIRD_BENCH_MAX_RUNS];
    iir_status st = summarise_all(b, s, err);
    if (st != IIR_OK) return st;
    cJSON *root = run_info_json(b), *runs = cJSON_CreateArray();
    for (int r = 0; r < b->num_runs; r++) cJSON_AddItemToArray(runs, run_json(&b->runs[r], &s[r]));
    cJSON_AddItemToObject(root, "runs", runs);
    cJSON_AddItemToObject(root, "ratios", ratios_json(b, s));
    char *text = cJSON_Print(root), path[4200];
    cJSON_Delete(root);
    snprintf(path, sizeof path, "%s/summary.json", b->o->out_dir);
    FILE *f = text ? fopen(path, "w") : NULL;
    bool ok = f && fputs(text, f) >= 0 && fputc('\n', f) != EOF;
    if (f && fclose(f) != 0) ok = false;
    cJSON_free(text);
    return ok ? IIR_OK : iir_fail(err, IIR_ERR_IO, "cannot write %s", path);
}

/* ---- the printed summary ---- */

static void print_ratios(const iird_bench *b, const run_summary *s, FILE *f)
{
    for (int r = 0; r < b->num_runs; r++) {
        int q = strcmp(b->runs[r].method, "iir") ? -1 : partner(b, r);
        if (q < 0) continue;
        char which[200] = "";
        if (strcmp(b->runs[r].setting, "default") || strcmp(b->runs[q].setting, "default"))
            snprintf(which, sizeof which, " [%s vs %s]", b->runs[r].setting, b->runs[q].setting);
        fprintf(f, "iir/ir%s: frame rate x%.2f, relMSE x%.2f, RMSE x%.2f, flicker x%.2f\n", which,
                s[r].fps / s[q].fps, s[r].relmse / s[q].relmse, s[r].rmse / s[q].rmse,
                s[r].flicker / s[q].flicker);
    }
}

/* Where method `m`'s error stops falling along a sweep of vpls alone (settings "vpls=N"): the
 * smallest N whose relMSE is within 10% of the sweep's best, with at least three Ns measured; 0
 * when there is no such sweep. The frame-time controller's ctl_vpls_max (docs/cli.md). */
static int error_knee(const iird_bench *b, const run_summary *s, const char *m)
{
    const iir_param *row = iir_method_find_param(m, "vpls");
    double best = INFINITY;
    int n = 0, knee = 0;
    for (int r = 0; row && r < b->num_runs; r++) {
        const char *set = b->runs[r].setting;
        if (strcmp(b->runs[r].method, m) || strncmp(set, "vpls=", 5) || strchr(set, ';') ||
            !isfinite(s[r].relmse))
            continue;
        best = fmin(best, s[r].relmse);
        n++;
    }
    for (int r = 0; n >= 3 && r < b->num_runs; r++) {
        const char *set = b->runs[r].setting;
        if (strcmp(b->runs[r].method, m) || strncmp(set, "vpls=", 5) || strchr(set, ';') ||
            !(s[r].relmse <= 1.1 * best))
            continue;
        int v = (int)iir_method_param_value(row, &b->runs[r].params);
        if (!knee || v < knee) knee = v;
    }
    return knee;
}

static void print_knees(const iird_bench *b, const run_summary *s, FILE *f)
{
    for (int r = 0; r < b->num_runs; r++) {
        bool first = true;
        for (int q = 0; q < r; q++) first = first && strcmp(b->runs[q].method, b->runs[r].method);
        int knee = first ? error_knee(b, s, b->runs[r].method) : 0;
        if (knee)
            fprintf(f,
                    "%s: relMSE within 10%% of the sweep's best from vpls %d on (iir's "
                    "--ctl-vpls-max for --target-fps)\n",
                    b->runs[r].method, knee);
    }
}

/* The parameters each method read, from its first run (the setting column gives swept values). */
static void print_settings(const iird_bench *b, FILE *f)
{
    for (int r = 0; r < b->num_runs; r++) {
        bool first = true;
        for (int q = 0; q < r; q++) first = first && strcmp(b->runs[q].method, b->runs[r].method);
        if (!first) continue;
        char text[1024];
        iird_settings_text(b->runs[r].method, &b->runs[r].params, text, sizeof text);
        fprintf(f, "%s settings: %s%s\n", b->runs[r].method, text,
                strcmp(b->runs[r].setting, "default") ? " (swept values: the setting column)" : "");
    }
}

/* A summary row's phase and counter columns (cols'), "-" where its method has none. */
static void summary_declared(FILE *f, const csv_columns *cols, const char *method,
                             const run_summary *s)
{
    for (int p = 0; p < IIR_PHASE_COUNT; p++) {
        if (!cols->phase[p]) continue;
        if (declares_phase(method, (iir_phase)p))
            fprintf(f, " %10.2f", s->phase[p]);
        else
            fprintf(f, " %10s", "-");
    }
    for (int k = 0; k < cols->num_counters; k++) {
        int i = iir_method_counter_index(method, cols->counter[k]);
        if (i >= 0)
            fprintf(f, " %12.6g", s->counter[i]);
        else
            fprintf(f, " %12s", "-");
    }
}

void iird_bench_summary(const iird_bench *b, FILE *f)
{
    run_summary s[IIRD_BENCH_MAX_RUNS];
    if (summarise_all(b, s, NULL) != IIR_OK) return;
    fprintf(f, "scene %s, path %s, %dx%d, %d frames (%d:%d; timing over all but the first)\n",
            b->scene->name, b->path_label, b->o->width, b->o->height, b->frames, b->first,
            b->first + b->frames);
    if (b->o->ref_spp > 0)
        fprintf(f, "references: %d at %d spp, %d from the cache%s%s (%.1f s)\n", b->refs_total,
                b->o->ref_spp, b->refs_cached, b->cache_dir[0] ? " in " : "", b->cache_dir,
                b->refs_s);
    fprintf(f, "%-9s %-16s %9s %9s %7s %9s %9s %9s", "method", "setting", "ms/frame", "p95 ms",
            "fps", "rmse", "relmse", "flicker");
    csv_columns cols = columns_of(b);
    for (int p = 0; p < IIR_PHASE_COUNT; p++)
        if (cols.phase[p]) fprintf(f, " %10s", iir_phase_name((iir_phase)p));
    for (int k = 0; k < cols.num_counters; k++) fprintf(f, " %12s", cols.counter[k]);
    fputc('\n', f);
    for (int r = 0; r < b->num_runs; r++) {
        fprintf(f, "%-9s %-16s %9.2f %9.2f %7.2f %9.5f %9.5f %9.5f", b->runs[r].method,
                b->runs[r].setting, s[r].mean_ms, s[r].p95_ms, s[r].fps, s[r].rmse, s[r].relmse,
                s[r].flicker);
        summary_declared(f, &cols, b->runs[r].method, &s[r]);
        fputc('\n', f);
    }
    print_ratios(b, s, f);
    print_knees(b, s, f);
    print_settings(b, f);
    fprintf(f, "shading kernels: %s (IIR_ISA caps them: scalar, sse2, avx2)\n",
            iir_isa_name(iir_isa_default()));
}

/* ---- charts ---- */

/* Appends s to buf in single quotes for /bin/sh. */
static void shell_quote(char *buf, size_t n, const char *s)
{
    size_t used = strlen(buf);
    used += (size_t)snprintf(buf + used, n - used, " '");
    for (; *s && used + 5 < n; s++)
        used += *s == '\'' ? (size_t)snprintf(buf + used, n - used, "'\\''")
                           : (size_t)snprintf(buf + used, n - used, "%c", *s);
    snprintf(buf + used, n - used, "'");
}

static const char *plot_script(void)
{
    static const char *const where[] = {"tools/plot_bench.py",
                                        IIR_SOURCE_DIR "/tools/plot_bench.py"};
    for (size_t i = 0; i < sizeof where / sizeof where[0]; i++)
        if (access(where[i], R_OK) == 0) return where[i];
    return NULL;
}

/* The first Python that has matplotlib: python3 on PATH, else Debian's. NULL if none. */
static const char *python_with_matplotlib(void)
{
    static const char *const cand[] = {"python3", "/usr/bin/python3"};
    char cmd[128];
    for (size_t i = 0; i < sizeof cand / sizeof cand[0]; i++) {
        snprintf(cmd, sizeof cmd, "%s -c 'import matplotlib' >/dev/null 2>&1", cand[i]);
        if (system(cmd) == 0) return cand[i];
    }
    return NULL;
}

bool iird_bench_charts(const iird_bench *b, FILE *f)
{
    if (!b->o->out_dir || b->o->no_charts) return true;
    const char *script = plot_script(), *python = script ? python_with_matplotlib() : NULL;
    if (!script) {
        fprintf(f, "charts: tools/plot_bench.py not found; skipped\n");
        return true;
    }
    if (!python) {
        fprintf(f,
                "charts: no python3 with matplotlib (apt-get install python3-matplotlib); then"
                " run: python3 %s %s\n",
                script, b->o->out_dir);
        return true;
    }
    char cmd[8400];
    snprintf(cmd, sizeof cmd, "%s", python);
    shell_quote(cmd, sizeof cmd, script);
    shell_quote(cmd, sizeof cmd, b->o->out_dir);
    fflush(f);
    int rc = system(cmd);
    if (rc != 0) fprintf(stderr, "iird bench: warning: %s failed (status %d)\n", script, rc);
    return rc == 0;
}

/* bench.c -- running one `iird bench`: the scene and its light path (a script checked against the
 * scene's lights), the runs (each method once per setting of the --sweep values it uses), and one
 * run over the path with its scores and memory. Not option parsing (cmd_bench.c), references
 * (bench_refs.c) or outputs (bench_out.c). */
#include "bench.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "animview.h"
#include "cli.h"
#include "iir/timer.h"
#include "iir/metrics.h"
#include "iir/vpl.h"
#include "orbit.h"

/* The bounce count of a method's references (iir_method_reference_bounces): its bounces
 * parameter, a multi-bounce method's own count, or one bounce (2: iir is one bounce by
 * construction). */
static int ref_bounces(const iird_bench_run *r)
{
    return iir_method_reference_bounces(r->method, &r->params);
}

static iir_status refset_for(iird_bench *b, int bounces, int *out, iir_error *err)
{
    for (int i = 0; i < b->num_refsets; i++)
        if (b->refsets[i].bounces == bounces) return *out = i, IIR_OK;
    if (b->num_refsets == IIRD_BENCH_MAX_REFSETS)
        return iir_fail(err, IIR_ERR_INVALID, "--sweep bounces: at most %d bounce counts",
                        IIRD_BENCH_MAX_REFSETS);
    iird_bench_refset *rs = &b->refsets[b->num_refsets];
    rs->bounces = bounces;
    rs->img = calloc((size_t)b->frames, sizeof(iir_image *));
    if (!rs->img) return iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    *out = b->num_refsets++;
    return IIR_OK;
}

/* ---- set-up ---- */

/* Applies value v of every sweep the method uses (idx[i] for sweep used[i]) to run r. */
static iir_status apply_setting(iird_bench_run *r, const iird_bench_opts *o, const int *used,
                                const int *idx, int nu, iir_error *err)
{
    size_t len = 0;
    snprintf(r->setting, sizeof r->setting, "default");
    for (int i = 0; i < nu; i++) {
        const iird_bench_sweep *s = &o->sweeps[used[i]];
        iir_status st = iird_parse_param(s->name, s->values[idx[i]], &r->params, err);
        if (st != IIR_OK) return st; /* values were checked when parsed */
        len += (size_t)snprintf(r->setting + len, sizeof r->setting - len, "%s%s=%s", i ? ";" : "",
                                s->name, s->values[idx[i]]);
        if (len >= sizeof r->setting) len = sizeof r->setting - 1;
    }
    iir_error perr = {0};
    if (iir_method_params_validate(r->method, &r->params, NULL, NULL, &perr) != IIR_OK ||
        iird_check_memory(r->method, &r->params, o->width, o->height, &perr) != IIR_OK)
        return iir_fail(err, IIR_ERR_INVALID, "--sweep: %s with %s: %s", r->method, r->setting,
                        perr.msg);
    return IIR_OK;
}

/* Adds one run per combination of the sweep values `method` uses (one "default" run if none). */
static iir_status add_runs(iird_bench *b, const char *method, iir_error *err)
{
    const iird_bench_opts *o = b->o;
    int used[IIRD_BENCH_MAX_SWEEPS], nu = 0, total = 1;
    for (int s = 0; s < o->num_sweeps; s++)
        if (iir_method_find_param(method, o->sweeps[s].row->name))
            used[nu++] = s, total *= o->sweeps[s].num_values;
    for (int k = 0; k < total; k++) {
        if (b->num_runs == IIRD_BENCH_MAX_RUNS)
            return iir_fail(err, IIR_ERR_INVALID, "--methods x --sweep: more than %d runs",
                            IIRD_BENCH_MAX_RUNS);
        iird_bench_run *r = &b->runs[b->num_runs++];
        int idx[IIRD_BENCH_MAX_SWEEPS], rest = k;
        for (int i = nu - 1; i >= 0; i--) { /* the first sweep varies slowest */
            idx[i] = rest % o->sweeps[used[i]].num_values;
            rest /= o->sweeps[used[i]].num_values;
        }
        snprintf(r->method, sizeof r->method, "%s", method);
        r->params = o->params;
        /* pt runs shade like their references */
        iir_status st = iir_params_set(&r->params, iir_method_any_param("jitter"), o->ref_aa, err);
        if (st == IIR_OK) st = apply_setting(r, o, used, idx, nu, err);
        if (st == IIR_OK) st = refset_for(b, ref_bounces(r), &r->refset, err);
        if (st != IIR_OK) return st;
    }
    return IIR_OK;
}

static iir_status parse_methods(iird_bench *b, const char *list, iir_error *err)
{
    char buf[256];
    int n = 0;
    snprintf(buf, sizeof buf, "%s", list);
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok;
         tok = strtok_r(NULL, ",", &save)) {
        if (++n > IIRD_BENCH_MAX_METHODS)
            return iir_fail(err, IIR_ERR_INVALID, "--methods: at most %d methods",
                            IIRD_BENCH_MAX_METHODS);
        iir_method *m = NULL; /* an unknown name fails here, before any work */
        iir_status st = iir_method_create(tok, b->scene, b->rt, &b->o->params, &m, err);
        iir_method_destroy(m);
        if (st == IIR_OK) st = add_runs(b, tok, err);
        if (st != IIR_OK) return st;
    }
    if (n == 0) return iir_fail(err, IIR_ERR_INVALID, "--methods is empty");
    return IIR_OK;
}

/* The frame range: --frames N (at most N of a script's frames) or A:B (must fit the script). */
static iir_status set_range(iird_bench *b, iir_error *err)
{
    const iird_bench_opts *o = b->o;
    b->path_frames = b->anim ? iir_anim_frame_count(b->anim) : o->frames;
    b->first = o->first;
    b->frames = o->frames - o->first;
    if (b->anim && !o->frames_given) b->frames = b->path_frames;
    if (b->anim && !o->range_given && b->frames > b->path_frames) b->frames = b->path_frames;
    if (o->range_given && o->frames > b->path_frames)
        return iir_fail(err, IIR_ERR_INVALID, "--frames %d:%d: the path has %d frames (0:%d)",
                        o->first, o->frames, b->path_frames, b->path_frames);
    if (b->frames < 2)
        return iir_fail(err, IIR_ERR_INVALID, "%s: %d frame(s); bench needs at least 2",
                        b->path_label, b->frames);
    return IIR_OK;
}

iir_status iird_bench_setup(iird_bench *b, const iird_bench_opts *o, iir_error *err)
{
    b->o = o;
    snprintf(b->path_label, sizeof b->path_label, "built-in orbit");
    iir_status st = IIR_OK;
    iird_anim_origin origin; /* its size aside: a bench's size is the experiment's (--size) */
    iird_anim_origin_read("bench", o->scene, o->scenes_dir, o->anim, &origin);
    const char *scene = origin.scene, *scenes = origin.scenes_dir;
    if (st == IIR_OK) st = iir_scene_open(scene, scenes, &b->scene, &b->rt, err);
    if (st == IIR_OK) iird_note_camera("bench", b->scene);
    if (st == IIR_OK) b->spot = iird_moved_light(b->scene);
    if (st == IIR_OK && o->anim)
        st = iird_resolve_anim(b->scene, scenes, o->anim, &b->anim, b->path_label,
                               sizeof b->path_label, err);
    if (st == IIR_OK && b->anim) iird_warn_anim_scene("bench", b->anim, scene, b->scene);
    if (st == IIR_OK) st = set_range(b, err);
    if (st == IIR_OK) st = parse_methods(b, o->methods, err);
    if (st != IIR_OK) return st;
    iird_warn_dropped("bench", o->methods, &o->params, b->scene, b->scene->lights,
                      b->scene->num_lights);
    b->scene_hash = iird_bench_scene_hash(b->scene);
    b->lights = malloc(sizeof(iir_light) * (b->scene->num_lights + 1)); /* + a made-up spot */
    b->rows = calloc((size_t)b->frames * (size_t)b->num_runs, sizeof(iird_bench_row));
    if (!b->lights || !b->rows) return iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    if (!b->anim) return IIR_OK;
    iir_view v = iird_anim_view(b->anim, b->scene, b->spot, b->lights, 0);
    return iir_anim_check_lights(b->anim, v.lights, v.num_lights, b->spot, err);
}

iir_view iird_bench_view(iird_bench *b, int i)
{
    int f = b->first + i;
    if (b->anim) return iird_anim_view(b->anim, b->scene, b->spot, b->lights, f);
    uint32_t n = b->scene->num_lights;
    if (n) memcpy(b->lights, b->scene->lights, sizeof(iir_light) * n);
    iir_light base;
    iir_scene_moved_light(b->scene, &base); /* the made-up spot when b->spot == n */
    b->lights[b->spot] = iird_orbit_light(b->scene, b->rt, &base, f, b->path_frames);
    iir_view v = {b->lights, b->spot == n ? n + 1 : n, b->scene->camera};
    return v;
}

/* ---- what the rest will take ---- */

/* Mean ms per frame of run r after its first (cold) frame. */
static double run_ms(const iird_bench *b, int r)
{
    double sum = 0;
    for (int i = 1; i < b->frames; i++) sum += b->rows[(size_t)r * b->frames + i].stats.total_ms;
    return sum / (b->frames - 1);
}

static double estimate_ms(const iird_bench *b, int q, int current, double current_ms)
{
    const iird_bench_run *run = &b->runs[q];
    for (int p = current - 1; p >= 0; p--)
        if (!strcmp(b->runs[p].method, run->method)) return run_ms(b, p);
    const iir_param *spp = iir_method_find_param(run->method, "spp");
    if (!strcmp(run->method, "pt") && spp && b->refs_rendered > 0 && b->o->ref_spp > 0)
        return b->refs_render_ms / b->refs_rendered * iir_method_param_value(spp, &run->params) /
               b->o->ref_spp;
    return current_ms;
}

double iird_bench_after_s(const iird_bench *b, int current, double current_ms)
{
    if (current_ms < 0) return -1;
    double ms = 0;
    for (int q = current + 1; q < b->num_runs; q++)
        ms += b->frames * estimate_ms(b, q, current, current_ms);
    return ms / 1e3;
}

bool iird_bench_is_ref_frame(const iird_bench *b, int i)
{
    return b->o->ref_spp > 0 && (i % b->o->ref_every == 0 || i % b->o->ref_every == 1);
}

/* ---- one run over the path ---- */

static void score(const iird_bench *b, const iird_bench_run *run, int i, const iir_image *img,
                  const iir_image *prev, iird_bench_row *row)
{
    iir_image **refs = b->refsets[run->refset].img;
    row->rmse = row->relmse = row->flicker = NAN;
    if (!refs[i]) return;
    row->rmse = iir_metric_rmse(img, refs[i]);
    row->relmse = iir_metric_relmse(img, refs[i]);
    if (i > 0 && refs[i - 1] && prev)
        row->flicker = iir_metric_flicker(img, prev, refs[i], refs[i - 1]);
}

/* Resident set size now, from /proc/self/statm (0 where unavailable). */
static double rss_mb(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    long pages = 0, resident = 0;
    if (f && fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
    if (f) fclose(f);
    return (double)resident * (double)sysconf(_SC_PAGESIZE) / (1024.0 * 1024.0);
}

/* The method's own VPL memory: the VPLs and their shadow-map texels. */
static double method_mb(const iir_method *m)
{
    uint32_t n = 0;
    const iir_vpl *v = iir_method_vpls(m, &n);
    double bytes = (double)n * sizeof(iir_vpl);
    for (uint32_t i = 0; i < n; i++)
        bytes += (double)v[i].smap.res * v[i].smap.res * sizeof *v[i].smap.depth;
    return bytes / (1024.0 * 1024.0);
}

/* Mean Rec. 709 luminance over the pixels. */
static double mean_luminance(const iir_image *img)
{
    double sum = 0;
    size_t n = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < n; i++) {
        const iir_vec3 c = img->pixels[i];
        sum += 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    }
    return sum / (double)n;
}

/* Writes img as OUT/<name>_<frame>.pfm when images are asked for. */
static iir_status save_image(const iird_bench *b, const iird_bench_run *run, int i,
                             const iir_image *img, iir_error *err)
{
    if (!b->o->save_images || !b->o->out_dir) return IIR_OK;
    char path[4096];
    bool plain = !strcmp(run->setting, "default");
    snprintf(path, sizeof path, "%s/%s%s%s_%05d.pfm", b->o->out_dir, run->method, plain ? "" : "_",
             plain ? "" : run->setting, b->first + i);
    return iir_image_write(img, path, 0.f, err);
}

iir_status iird_bench_run_one(iird_bench *b, int r, iir_error *err)
{
    const iird_bench_run *run = &b->runs[r];
    iir_method *method = NULL;
    iir_image *img = iir_image_create(b->o->width, b->o->height);
    iir_image *prev = iir_image_create(b->o->width, b->o->height);
    iir_status st =
        img && prev ? iir_method_create(run->method, b->scene, b->rt, &run->params, &method, err)
                    : iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    char label[128];
    snprintf(label, sizeof label, "%-4s %-14s", run->method, run->setting);
    iird_progress bar;
    iird_progress_start(&bar, label, b->frames);
    for (int i = 0; st == IIR_OK && i < b->frames; i++) {
        iird_bench_row *row = &b->rows[(size_t)r * b->frames + i];
        iir_view v = iird_bench_view(b, i);
        st = iir_method_render(method, &v, img, &row->stats, err);
        if (st == IIR_OK) score(b, run, i, img, i > 0 ? prev : NULL, row);
        row->rss_mb = rss_mb();
        row->method_mb = st == IIR_OK ? method_mb(method) : 0;
        row->mean_lum = mean_luminance(img);
        if (st == IIR_OK && b->refsets[run->refset].img[i]) st = save_image(b, run, i, img, err);
        iir_image_copy(prev, img);
        double rate = iird_progress_rate(&bar, i + 1, iir_now_ms());
        iird_progress_set_after(&bar, "bench", iird_bench_after_s(b, r, rate * 1e3));
        iird_progress_update(&bar, i + 1);
        if (iird_interrupted()) st = iir_fail(err, IIR_ERR_INTERRUPTED, "interrupted");
    }
    iird_progress_finish(&bar);
    iir_method_destroy(method);
    iir_image_destroy(img);
    iir_image_destroy(prev);
    return st;
}

void iird_bench_warn_black(iird_bench *b)
{
    for (int r = 0; r < b->num_runs; r++) {
        int black = 0, first = -1;
        for (int i = 0; i < b->frames; i++)
            if (b->rows[(size_t)r * b->frames + i].mean_lum <= 0.0 && black++ == 0) first = i;
        if (black == 0) continue;
        char what[160];
        snprintf(what, sizeof what, "%s %s: %d of %d frames (first: frame %d) are",
                 b->runs[r].method, b->runs[r].setting, black, b->frames, b->first + first);
        iir_view v = iird_bench_view(b, first);
        iird_warn_black("bench", what, b->scene, b->rt, &v);
    }
}

void iird_bench_free(iird_bench *b)
{
    for (int s = 0; s < b->num_refsets; s++) {
        for (int i = 0; b->refsets[s].img && i < b->frames; i++)
            iir_image_destroy(b->refsets[s].img[i]);
        free(b->refsets[s].img);
    }
    free(b->rows);
    free(b->lights);
    iir_anim_destroy(b->anim);
    iir_rt_destroy(b->rt);
    iir_scene_destroy(b->scene);
}

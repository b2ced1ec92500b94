/* bench.c -- running one `iird bench`: the path, the references, the methods, the CSV and the
 * summary. Not option parsing (cmd_bench.c). */
#include "bench.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "iir/metrics.h"
#include "orbit.h"

/* ---- set-up ---- */

static iir_status parse_methods(iird_bench *b, const char *list, iir_error *err)
{
    char buf[256];
    snprintf(buf, sizeof buf, "%s", list);
    for (char *save = NULL, *tok = strtok_r(buf, ",", &save); tok;
         tok = strtok_r(NULL, ",", &save)) {
        if (b->num_methods == IIRD_BENCH_MAX_METHODS)
            return iir_fail(err, IIR_ERR_INVALID, "--methods: at most %d methods",
                            IIRD_BENCH_MAX_METHODS);
        snprintf(b->names[b->num_methods++], sizeof b->names[0], "%s", tok);
    }
    if (b->num_methods == 0) return iir_fail(err, IIR_ERR_INVALID, "--methods is empty");
    return IIR_OK;
}

static iir_status find_spot(iird_bench *b, iir_error *err)
{
    for (uint32_t i = 0; i < b->scene->num_lights; i++)
        if (b->scene->lights[i].type == IIR_LIGHT_SPOT) {
            b->spot = i;
            return IIR_OK;
        }
    return iir_fail(err, IIR_ERR_INVALID, "scene '%s' has no spot light to move", b->scene->name);
}

iir_status iird_bench_setup(iird_bench *b, const iird_bench_opts *o, iir_error *err)
{
    b->o = o;
    iir_status st = parse_methods(b, o->methods, err);
    if (st == IIR_OK) st = iir_params_validate(&o->params, err);
    if (st == IIR_OK)
        st = iird_load_scene(o->scene, iird_scenes_dir(o->scenes_dir), &b->scene, &b->rt, err);
    if (st == IIR_OK) st = find_spot(b, err);
    if (st == IIR_OK && o->anim_path) st = iir_anim_load(o->anim_path, &b->anim, err);
    if (st != IIR_OK) return st;
    b->frames = o->frames;
    if (b->anim) {
        int n = iir_anim_frame_count(b->anim);
        b->frames = o->frames_given && o->frames < n ? o->frames : n;
        if (b->frames < 2)
            return iir_fail(err, IIR_ERR_INVALID, "%s: %d frame(s); bench needs at least 2",
                            o->anim_path, b->frames);
    }
    b->lights = malloc(sizeof(iir_light) * b->scene->num_lights);
    b->refs = calloc((size_t)b->frames, sizeof(iir_image *));
    b->rows = calloc((size_t)b->frames * (size_t)b->num_methods, sizeof(iird_bench_row));
    if (!b->lights || !b->refs || !b->rows) return iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    return IIR_OK;
}

/* The lights and camera of frame f: from the script, or the built-in orbit. */
static iir_view view_at(iird_bench *b, int f)
{
    const iir_light *base = &b->scene->lights[b->spot];
    memcpy(b->lights, b->scene->lights, sizeof(iir_light) * b->scene->num_lights);
    iir_view v = {b->lights, b->scene->num_lights, b->scene->camera};
    if (b->anim) {
        double t = iir_anim_frame_time(b->anim, f);
        b->lights[b->spot] = iir_anim_light(b->anim, base, t);
        v.camera = iir_anim_camera(b->anim, &b->scene->camera, t);
    } else {
        b->lights[b->spot] = iird_orbit_light(b->scene, b->rt, base, f, b->frames);
    }
    return v;
}

static bool is_ref_frame(const iird_bench *b, int f)
{
    return b->o->ref_spp > 0 && (f % b->o->ref_every == 0 || f % b->o->ref_every == 1);
}

/* ---- references ---- */

/* Writes img as OUT/<name>_<frame>.pfm when images are asked for. */
static iir_status save_image(const iird_bench *b, const char *name, int f, const iir_image *img,
                             iir_error *err)
{
    if (!b->o->save_images || !b->o->out_dir) return IIR_OK;
    char path[4096];
    snprintf(path, sizeof path, "%s/%s_%05d.pfm", b->o->out_dir, name, f);
    return iir_image_write(img, path, 0.f, err);
}

iir_status iird_bench_references(iird_bench *b, iir_error *err)
{
    if (b->o->ref_spp == 0) return IIR_OK;
    iir_params p = b->o->params;
    p.spp = b->o->ref_spp;
    p.bounces = 2; /* one bounce, like iir */
    p.jitter = b->o->ref_aa;
    iir_method *pt = NULL;
    iir_status st = iir_method_create("pt", b->scene, b->rt, &p, &pt, err);
    int total = 0, done = 0;
    for (int f = 0; f < b->frames; f++) total += is_ref_frame(b, f);
    iird_progress bar;
    iird_progress_start(&bar, "references", total);
    for (int f = 0; st == IIR_OK && f < b->frames; f++) {
        if (!is_ref_frame(b, f)) continue;
        if (iird_interrupted()) st = iir_fail(err, IIR_ERR_INTERRUPTED, "interrupted");
        b->refs[f] = iir_image_create(b->o->width, b->o->height);
        iir_view v = view_at(b, f);
        iir_frame_stats fs;
        if (st == IIR_OK) st = iir_method_render(pt, &v, b->refs[f], &fs, err);
        if (st == IIR_OK) st = save_image(b, "ref", f, b->refs[f], err);
        iird_progress_update(&bar, ++done);
    }
    iird_progress_finish(&bar);
    iir_method_destroy(pt);
    return st;
}

/* ---- one method over the path ---- */

static void score(const iird_bench *b, int f, const iir_image *img, const iir_image *prev,
                  iird_bench_row *row)
{
    row->rmse = row->relmse = row->flicker = NAN;
    if (!b->refs[f]) return;
    row->rmse = iir_metric_rmse(img, b->refs[f]);
    row->relmse = iir_metric_relmse(img, b->refs[f]);
    if (f > 0 && b->refs[f - 1] && prev)
        row->flicker = iir_metric_flicker(img, prev, b->refs[f], b->refs[f - 1]);
}

iir_status iird_bench_method(iird_bench *b, int m, iir_error *err)
{
    iir_method *method = NULL;
    iir_image *img = iir_image_create(b->o->width, b->o->height);
    iir_image *prev = iir_image_create(b->o->width, b->o->height);
    iir_status st =
        img && prev ? iir_method_create(b->names[m], b->scene, b->rt, &b->o->params, &method, err)
                    : iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    char label[64];
    snprintf(label, sizeof label, "%-10s", b->names[m]);
    iird_progress bar;
    iird_progress_start(&bar, label, b->frames);
    for (int f = 0; st == IIR_OK && f < b->frames; f++) {
        iird_bench_row *row = &b->rows[(size_t)m * b->frames + f];
        iir_view v = view_at(b, f);
        st = iir_method_render(method, &v, img, &row->stats, err);
        if (st == IIR_OK) score(b, f, img, f > 0 ? prev : NULL, row);
        if (st == IIR_OK && b->refs[f]) st = save_image(b, b->names[m], f, img, err);
        iir_image_copy(prev, img);
        iird_progress_update(&bar, f + 1);
        if (iird_interrupted()) st = iir_fail(err, IIR_ERR_INTERRUPTED, "interrupted");
    }
    iird_progress_finish(&bar);
    iir_method_destroy(method);
    iir_image_destroy(img);
    iir_image_destroy(prev);
    return st;
}

/* ---- output ---- */

static void csv_header(FILE *f)
{
    fprintf(f, "method,setting,frame,total_ms");
    for (int p = 0; p < IIR_PHASE_COUNT; p++) fprintf(f, ",%s_ms", iir_phase_name((iir_phase)p));
    for (int k = 0; k < IIR_RAY_KIND_COUNT; k++)
        fprintf(f, ",rays_%s", iir_ray_kind_name((iir_ray_kind)k));
    fprintf(f, ",vpls,vpls_valid,vpls_invalidated,vpls_deleted,vpls_inserted,vpls_null,"
               "regenerated,shadowmaps,rmse,relmse,flicker\n");
}

static void csv_row(FILE *f, const char *method, const char *setting, int frame,
                    const iird_bench_row *r)
{
    const iir_frame_stats *s = &r->stats;
    const iir_vpl_counts *c = &s->vpl;
    fprintf(f, "%s,%s,%d,%.4f", method, setting, frame, s->total_ms);
    for (int p = 0; p < IIR_PHASE_COUNT; p++) fprintf(f, ",%.4f", s->phase_ms[p]);
    for (int k = 0; k < IIR_RAY_KIND_COUNT; k++)
        fprintf(f, ",%llu", (unsigned long long)s->rays.n[k]);
    fprintf(f, ",%u,%u,%u,%u,%u,%u,%u,%u", c->count, c->valid, c->invalidated, c->deleted,
            c->inserted, c->null_samples, c->regenerated, c->shadowmaps);
    fprintf(f, isnan(r->rmse) ? ",," : ",%.6g,", r->rmse);
    fprintf(f, isnan(r->relmse) ? "," : "%.6g,", r->relmse);
    fprintf(f, isnan(r->flicker) ? "\n" : "%.6g\n", r->flicker);
}

static void setting_of(const iir_params *p, char *buf, size_t n)
{
    snprintf(buf, n, "N=%d;k=%d-%d;vis=%s;sm=%d;il=%d;clamp=%g", p->vpls, p->kmin, p->kmax,
             p->visibility == IIR_VIS_RAYS ? "rays" : "shadowmap", p->sm_res, p->interleave,
             (double)p->clamp);
}

iir_status iird_bench_write_csv(const iird_bench *b, iir_error *err)
{
    if (!b->o->out_dir) return IIR_OK;
    char path[4096], setting[128];
    snprintf(path, sizeof path, "%s/frames.csv", b->o->out_dir);
    FILE *f = fopen(path, "w");
    if (!f) return iir_fail(err, IIR_ERR_IO, "cannot write %s", path);
    setting_of(&b->o->params, setting, sizeof setting);
    csv_header(f);
    for (int m = 0; m < b->num_methods; m++)
        for (int fr = 0; fr < b->frames; fr++)
            csv_row(f, b->names[m], setting, fr, &b->rows[(size_t)m * b->frames + fr]);
    if (fclose(f) != 0) return iir_fail(err, IIR_ERR_IO, "cannot write %s", path);
    return IIR_OK;
}

typedef struct method_summary {
    double ms, fps, phase[IIR_PHASE_COUNT], rmse, relmse, flicker;
} method_summary;

static double mean_finite(double sum, int n)
{
    return n > 0 ? sum / n : NAN;
}

/* Timing over frames 1.. (frame 0 is the cold start of every method); errors over reference frames.
 */
static method_summary summarise(const iird_bench *b, int m)
{
    method_summary s = {0};
    double rmse = 0, rel = 0, fl = 0;
    int n_err = 0, n_fl = 0, n = b->frames - 1;
    for (int f = 1; f < b->frames; f++) {
        const iird_bench_row *r = &b->rows[(size_t)m * b->frames + f];
        s.ms += r->stats.total_ms / n;
        for (int p = 0; p < IIR_PHASE_COUNT; p++) s.phase[p] += r->stats.phase_ms[p] / n;
    }
    for (int f = 0; f < b->frames; f++) {
        const iird_bench_row *r = &b->rows[(size_t)m * b->frames + f];
        if (!isnan(r->relmse)) rmse += r->rmse, rel += r->relmse, n_err++;
        if (!isnan(r->flicker)) fl += r->flicker, n_fl++;
    }
    s.fps = 1000.0 / s.ms;
    s.rmse = mean_finite(rmse, n_err);
    s.relmse = mean_finite(rel, n_err);
    s.flicker = mean_finite(fl, n_fl);
    return s;
}

static int method_index(const iird_bench *b, const char *name)
{
    for (int m = 0; m < b->num_methods; m++)
        if (!strcmp(b->names[m], name)) return m;
    return -1;
}

void iird_bench_summary(const iird_bench *b, FILE *f)
{
    method_summary s[IIRD_BENCH_MAX_METHODS];
    fprintf(f,
            "scene %s, path %s, %dx%d, %d frames (timing over frames 1..%d), references %d spp\n",
            b->scene->name, b->o->anim_path ? b->o->anim_path : "built-in orbit", b->o->width,
            b->o->height, b->frames, b->frames - 1, b->o->ref_spp);
    fprintf(f, "%-8s %9s %7s %9s %9s %9s", "method", "ms/frame", "fps", "rmse", "relmse",
            "flicker");
    for (int p = 0; p < IIR_PHASE_COUNT; p++) fprintf(f, " %10s", iir_phase_name((iir_phase)p));
    fputc('\n', f);
    for (int m = 0; m < b->num_methods; m++) {
        s[m] = summarise(b, m);
        fprintf(f, "%-8s %9.2f %7.2f %9.5f %9.5f %9.5f", b->names[m], s[m].ms, s[m].fps, s[m].rmse,
                s[m].relmse, s[m].flicker);
        for (int p = 0; p < IIR_PHASE_COUNT; p++) fprintf(f, " %10.2f", s[m].phase[p]);
        fputc('\n', f);
    }
    int i = method_index(b, "iir"), r = method_index(b, "ir");
    if (i >= 0 && r >= 0)
        fprintf(f, "iir/ir: frame rate x%.2f, relMSE x%.2f, RMSE x%.2f, flicker x%.2f\n",
                s[i].fps / s[r].fps, s[i].relmse / s[r].relmse, s[i].rmse / s[r].rmse,
                s[i].flicker / s[r].flicker);
}

void iird_bench_free(iird_bench *b)
{
    for (int f = 0; b->refs && f < b->frames; f++) iir_image_destroy(b->refs[f]);
    free(b->refs);
    free(b->rows);
    free(b->lights);
    iir_anim_destroy(b->anim);
    iir_rt_destroy(b->rt);
    iir_scene_destroy(b->scene);
}

/* render_log.c -- DIR/render.json of `iird render --anim` (see render_log.h): settings and the
 * resume check, per-frame and per-run entries, totals, atomic writes. */
#include "render_log.h"

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "protocol/protocol.h"

struct iird_render_log {
    char path[4096], tmp[4200];
    cJSON *settings;  /* this run's, owned */
    cJSON *old_runs;  /* runs of the earlier render.json (an array, maybe empty), owned */
    cJSON **by_frame; /* script_frames entries, owned, NULL where a frame has none */
    int frames, kept;
    char scene_source[1024], script_label[4096];
    const iird_render_run *run;        /* the current run; NULL for a loaded or merged log */
    int seg, segs, seg_first, seg_end; /* --segment I/N and its frames (segs 0: none) */
};

/* ---- settings ---- */

/* Rounds to 1e-4, enough for milliseconds in a log and much shorter to print. */
static double r4(double x)
{
    return round(x * 1e4) / 1e4;
}

/* The shortest decimal that reads back as the same float: 0.005, not 0.00499999988824129. */
static double float_value(float v)
{
    char buf[32];
    for (int prec = 6; prec < 9; prec++) {
        snprintf(buf, sizeof buf, "%.*g", prec, (double)v);
        if (strtof(buf, NULL) == v) return strtod(buf, NULL);
    }
    return v;
}

static cJSON *settings_json(const iird_render_setup *s)
{
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "scene", s->scene_name);
    cJSON *script = cJSON_AddObjectToObject(o, "script");
    char hash[32];
    snprintf(hash, sizeof hash, "%016llx", (unsigned long long)s->script_hash);
    cJSON_AddNumberToObject(script, "frames", s->script_frames);
    cJSON_AddNumberToObject(script, "fps", s->fps);
    cJSON_AddStringToObject(script, "hash", hash);
    cJSON_AddStringToObject(o, "method", s->method);
    cJSON *size = cJSON_AddArrayToObject(o, "size");
    cJSON_AddItemToArray(size, cJSON_CreateNumber(s->width));
    cJSON_AddItemToArray(size, cJSON_CreateNumber(s->height));
    cJSON_AddStringToObject(o, "format", s->format);
    cJSON_AddNumberToObject(o, "exposure", float_value(s->exposure));
    cJSON_AddItemToObject(o, "params", iird_json_method_params(s->method, s->params));
    return o;
}

/* The command-line spelling of a settings key, for messages. */
static const char *option_name(const char *key, char *buf, size_t n)
{
    if (!strcmp(key, "scene")) return "SCENE";
    if (!strcmp(key, "script")) return "--anim (the script's frames)";
    snprintf(buf, n, "--%s", key);
    for (char *c = buf; *c; c++)
        if (*c == '_') *c = '-';
    return buf;
}

static iir_status differs(const char *path, const char *key, const cJSON *was, const cJSON *now,
                          iir_error *err)
{
    char opt[64];
    char *a = was ? cJSON_PrintUnformatted(was) : NULL, *b = cJSON_PrintUnformatted(now);
    iir_status st =
        iir_fail(err, IIR_ERR_INVALID,
                 "%s differs from the earlier run recorded in %s (%.120s there, "
                 "%.120s now): resume with the same settings, or render into "
                 "another --out directory",
                 option_name(key, opt, sizeof opt), path, a ? a : "nothing", b ? b : "?");
    cJSON_free(a);
    cJSON_free(b);
    return st;
}

/* Every setting of `now` must equal the one in `was`; the params one by one. */
static iir_status check_settings(const char *path, const cJSON *was, const cJSON *now,
                                 iir_error *err)
{
    for (const cJSON *it = now->child; it; it = it->next) {
        const cJSON *old = cJSON_GetObjectItemCaseSensitive(was, it->string);
        if (!strcmp(it->string, "params") && cJSON_IsObject(old)) {
            iir_status st = check_settings(path, old, it, err);
            if (st != IIR_OK) return st;
        } else if (!old || !cJSON_Compare(old, it, true)) {
            return differs(path, it->string, old, it, err);
        }
    }
    return IIR_OK;
}

/* ---- reading an earlier log ---- */

/* The whole file, NUL-terminated, malloc'ed; NULL with errno set when unreadable. */
static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    char *buf = NULL;
    long n = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
    if (n >= 0 && fseek(f, 0, SEEK_SET) == 0 && (buf = malloc((size_t)n + 1)) &&
        fread(buf, 1, (size_t)n, f) == (size_t)n) {
        buf[n] = '\0';
    } else {
        free(buf), buf = NULL;
        errno = errno ? errno : EIO;
    }
    fclose(f);
    return buf;
}

/* Moves the earlier file's frame entries into l->by_frame, checking each names a frame of the
 * script and has a total_ms. */
static iir_status adopt_frames(iird_render_log *l, cJSON *frames, iir_error *err)
{
    int i = 0;
    for (cJSON *e; (e = cJSON_DetachItemFromArray(frames, 0)); i++) {
        const cJSON *f = cJSON_GetObjectItemCaseSensitive(e, "frame");
        double v = cJSON_IsNumber(f) ? f->valuedouble : -1;
        if (v < 0 || v >= l->frames || v != floor(v) ||
            !cJSON_IsNumber(cJSON_GetObjectItemCaseSensitive(e, "total_ms"))) {
            cJSON_Delete(e);
            return iir_fail(err, IIR_ERR_FORMAT,
                            "%s: frames[%d]: needs a \"frame\" in [0, %d) and a \"total_ms\"",
                            l->path, i, l->frames);
        }
        if (!l->by_frame[(int)v]) l->kept++;
        cJSON_Delete(l->by_frame[(int)v]);
        l->by_frame[(int)v] = e;
    }
    return IIR_OK;
}

/* Reads an existing render.json: checks its settings and keeps its frames and runs. */
static iir_status resume_from(iird_render_log *l, iir_error *err)
{
    errno = 0;
    char *text = read_text(l->path);
    if (!text && errno == ENOENT) return IIR_OK;
    if (!text) return iir_fail(err, IIR_ERR_IO, "cannot read %s: %s", l->path, strerror(errno));
    cJSON *root = cJSON_Parse(text);
    free(text);
    cJSON *settings = cJSON_GetObjectItemCaseSensitive(root, "settings");
    cJSON *frames = cJSON_GetObjectItemCaseSensitive(root, "frames");
    cJSON *runs = cJSON_GetObjectItemCaseSensitive(root, "runs");
    iir_status st = IIR_OK;
    if (!cJSON_IsObject(settings) || !cJSON_IsArray(frames) || !cJSON_IsArray(runs))
        st = iir_fail(err, IIR_ERR_FORMAT,
                      "%s is not a render log of iird render --anim (no settings, frames and "
                      "runs); move it away or use another --out directory",
                      l->path);
    if (st == IIR_OK) st = check_settings(l->path, settings, l->settings, err);
    if (st == IIR_OK) st = adopt_frames(l, frames, err);
    if (st == IIR_OK) {
        cJSON_Delete(l->old_runs);
        l->old_runs = cJSON_DetachItemViaPointer(root, runs);
    }
    cJSON_Delete(root);
    return st;
}

iir_status iird_render_log_open(const char *dir, const iird_render_setup *setup,
                                const iird_render_run *run, iird_render_log **out, iir_error *err)
{
    *out = NULL;
    iird_render_log *l = calloc(1, sizeof *l);
    if (!l) return iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    snprintf(l->path, sizeof l->path, "%s/%s", dir,
             setup->log_name ? setup->log_name : "render.json");
    snprintf(l->tmp, sizeof l->tmp, "%s.part", l->path);
    l->seg = setup->segment, l->segs = setup->segments;
    l->seg_first = setup->segment_first, l->seg_end = setup->segment_end;
    snprintf(l->scene_source, sizeof l->scene_source, "%s", setup->scene_source);
    snprintf(l->script_label, sizeof l->script_label, "%s", setup->script_label);
    l->frames = setup->script_frames;
    l->run = run;
    l->settings = settings_json(setup);
    l->old_runs = cJSON_CreateArray();
    l->by_frame = calloc((size_t)l->frames, sizeof(cJSON *));
    iir_status st = l->settings && l->old_runs && l->by_frame
                        ? resume_from(l, err)
                        : iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    if (st != IIR_OK) {
        iird_render_log_destroy(l);
        return st;
    }
    *out = l;
    return IIR_OK;
}

int iird_render_log_kept(const iird_render_log *l)
{
    return l->kept;
}

int iird_render_log_count(const iird_render_log *l)
{
    int n = 0;
    for (int f = 0; f < l->frames; f++) n += l->by_frame[f] != NULL;
    return n;
}

/* ---- entries ---- */

void iird_render_log_frame(iird_render_log *l, int f, double time_s, const char *file,
                           float exposure, const iir_frame_stats *fs, double write_ms)
{
    cJSON *e = cJSON_CreateObject();
    cJSON_AddNumberToObject(e, "frame", f);
    cJSON_AddNumberToObject(e, "time_s", time_s);
    cJSON_AddStringToObject(e, "file", file);
    cJSON_AddNumberToObject(e, "exposure", float_value(exposure));
    cJSON_AddNumberToObject(e, "total_ms", r4(fs->total_ms));
    cJSON_AddNumberToObject(e, "write_ms", r4(write_ms));
    const char *method = cJSON_GetStringValue(cJSON_GetObjectItem(l->settings, "method"));
    cJSON_AddItemToObject(e, "phase_ms", iird_json_phases(method ? method : "", fs, 1e4));
    cJSON_AddItemToObject(e, "counters", iird_json_counters(method ? method : "", fs));
    cJSON_AddItemToObject(e, "rays", iird_json_rays(&fs->rays));
    cJSON_AddItemToObject(e, "vpls", iird_json_vpl_counts(&fs->vpl));
    cJSON_AddNumberToObject(e, "vpl_evals", (double)fs->vpl_evals);
    cJSON_AddNumberToObject(e, "vpl_reused", (double)fs->vpl_reused);
    cJSON_AddNumberToObject(e, "spp", (double)fs->samples_per_pixel);
    if (fs->controlled) cJSON_AddItemToObject(e, "ctl", iird_json_ctl(fs));
    cJSON_Delete(l->by_frame[f]);
    l->by_frame[f] = e;
}

static cJSON *run_json(const iird_render_run *r)
{
    cJSON *o = cJSON_CreateObject();
    cJSON *range = cJSON_AddArrayToObject(o, "frames");
    cJSON_AddItemToArray(range, cJSON_CreateNumber(r->first));
    cJSON_AddItemToArray(range, cJSON_CreateNumber(r->end));
    cJSON_AddNumberToObject(o, "done", r->done);
    cJSON_AddStringToObject(o, "status", r->status);
    cJSON *w = cJSON_AddObjectToObject(o, "warmup");
    cJSON_AddNumberToObject(w, "frames", r->warmup_frames);
    if (r->warmup_frames > 0) {
        cJSON *size = cJSON_AddArrayToObject(w, "size");
        cJSON_AddItemToArray(size, cJSON_CreateNumber(r->warmup_width));
        cJSON_AddItemToArray(size, cJSON_CreateNumber(r->warmup_height));
        cJSON_AddNumberToObject(w, "ms", r4(r->warmup_ms));
        cJSON_AddStringToObject(w, "note",
                                "frames 0..first-1 were rendered, unwritten and small, to carry "
                                "the method's state (the VPL set) up to the first frame");
    }
    cJSON_AddNumberToObject(o, "wall_ms", r4(r->wall_ms));
    cJSON_AddNumberToObject(o, "threads", r->threads);
    if (r->video) cJSON_AddStringToObject(o, "video", r->video);
    return o;
}

/* Sums over every frame entry, earlier runs' included. */
static cJSON *totals_json(const iird_render_log *l)
{
    double ms = 0, rays[IIR_RAY_KIND_COUNT] = {0};
    int n = 0, regen = 0, first_missing = -1;
    for (int f = 0; f < l->frames; f++) {
        const cJSON *e = l->by_frame[f];
        if (!e) {
            if (first_missing < 0) first_missing = f;
            continue;
        }
        n++;
        ms += cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(e, "total_ms"));
        const cJSON *r = cJSON_GetObjectItemCaseSensitive(e, "rays");
        for (int k = 0; k < IIR_RAY_KIND_COUNT; k++) {
            const cJSON *v =
                cJSON_GetObjectItemCaseSensitive(r, iir_ray_kind_name((iir_ray_kind)k));
            rays[k] += cJSON_IsNumber(v) ? v->valuedouble : 0;
        }
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(e, "vpls");
        regen += cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(v, "regenerated")) > 0;
    }
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "frames", n);
    cJSON_AddNumberToObject(o, "missing", l->frames - n);
    if (first_missing >= 0) cJSON_AddNumberToObject(o, "first_missing", first_missing);
    cJSON_AddNumberToObject(o, "total_ms", r4(ms));
    cJSON_AddNumberToObject(o, "mean_ms", n ? r4(ms / n) : 0);
    cJSON_AddNumberToObject(o, "fps", ms > 0 ? r4(1000.0 * n / ms) : 0);
    cJSON *ro = cJSON_AddObjectToObject(o, "rays");
    for (int k = 0; k < IIR_RAY_KIND_COUNT; k++)
        cJSON_AddNumberToObject(ro, iir_ray_kind_name((iir_ray_kind)k), rays[k]);
    cJSON_AddNumberToObject(o, "regenerations", regen);
    return o;
}

/* ---- writing ---- */

static cJSON *document(const iird_render_log *l)
{
    cJSON *root = cJSON_CreateObject();
    cJSON_AddStringToObject(root, "generator", "iird " IIR_VERSION " render --anim");
    cJSON_AddItemReferenceToObject(root, "settings", l->settings);
    cJSON_AddStringToObject(root, "scene_source", l->scene_source);
    cJSON_AddStringToObject(root, "script", l->script_label);
    if (l->segs) {
        cJSON *seg = cJSON_AddObjectToObject(root, "segment");
        cJSON_AddNumberToObject(seg, "index", l->seg);
        cJSON_AddNumberToObject(seg, "of", l->segs);
        cJSON *range = cJSON_AddArrayToObject(seg, "frames");
        cJSON_AddItemToArray(range, cJSON_CreateNumber(l->seg_first));
        cJSON_AddItemToArray(range, cJSON_CreateNumber(l->seg_end));
    }
    cJSON *runs = cJSON_AddArrayToObject(root, "runs");
    for (cJSON *r = l->old_runs->child; r; r = r->next) cJSON_AddItemReferenceToArray(runs, r);
    if (l->run) cJSON_AddItemToArray(runs, run_json(l->run));
    cJSON *frames = cJSON_AddArrayToObject(root, "frames");
    for (int f = 0; f < l->frames; f++)
        if (l->by_frame[f]) cJSON_AddItemReferenceToArray(frames, l->by_frame[f]);
    cJSON_AddItemToObject(root, "totals", totals_json(l));
    return root;
}

iir_status iird_render_log_write(iird_render_log *l, iir_error *err)
{
    cJSON *root = document(l);
    char *text = root ? cJSON_Print(root) : NULL;
    cJSON_Delete(root);
    if (!text) return iir_fail(err, IIR_ERR_NOMEM, "out of memory writing %s", l->path);
    FILE *f = fopen(l->tmp, "wb");
    size_t n = strlen(text);
    bool ok = f && fwrite(text, 1, n, f) == n && fputc('\n', f) != EOF;
    ok = (f && fclose(f) == 0) && ok;
    cJSON_free(text);
    if (ok && rename(l->tmp, l->path) == 0) return IIR_OK;
    iir_status st = iir_fail(err, IIR_ERR_IO, "cannot write %s: %s", l->path, strerror(errno));
    remove(l->tmp);
    return st;
}

void iird_render_log_destroy(iird_render_log *l)
{
    if (!l) return;
    for (int f = 0; l->by_frame && f < l->frames; f++) cJSON_Delete(l->by_frame[f]);
    free(l->by_frame);
    cJSON_Delete(l->settings);
    cJSON_Delete(l->old_runs);
    free(l);
}

/* ---- merging segments ---- */

/* The segment object of a part file into l (none when absent); false when malformed. */
static bool read_segment(iird_render_log *l, const cJSON *seg)
{
    if (!seg) return true;
    const cJSON *range = cJSON_GetObjectItemCaseSensitive(seg, "frames");
    double i = cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(seg, "index"));
    double n = cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(seg, "of"));
    if (!cJSON_IsArray(range) || cJSON_GetArraySize(range) != 2 || !(n >= 1 && n <= 100000) ||
        !(i >= 0 && i < n))
        return false;
    l->seg = (int)i, l->segs = (int)n;
    l->seg_first = (int)cJSON_GetNumberValue(cJSON_GetArrayItem(range, 0));
    l->seg_end = (int)cJSON_GetNumberValue(cJSON_GetArrayItem(range, 1));
    return l->seg_first >= 0 && l->seg_first < l->seg_end && l->seg_end <= l->frames;
}

static iir_status load_document(iird_render_log *l, cJSON *root, iir_error *err)
{
    cJSON *settings = cJSON_GetObjectItemCaseSensitive(root, "settings");
    cJSON *frames = cJSON_GetObjectItemCaseSensitive(root, "frames");
    cJSON *runs = cJSON_GetObjectItemCaseSensitive(root, "runs");
    const cJSON *script = cJSON_GetObjectItemCaseSensitive(settings, "script");
    double n = cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(script, "frames"));
    if (!cJSON_IsObject(settings) || !cJSON_IsArray(frames) || !cJSON_IsArray(runs) ||
        !(n >= 1 && n <= 1e7))
        return iir_fail(err, IIR_ERR_FORMAT,
                        "%s is not a render log of iird render --anim (no settings, frames and "
                        "runs)",
                        l->path);
    l->frames = (int)n;
    l->settings = cJSON_DetachItemViaPointer(root, settings);
    l->old_runs = cJSON_DetachItemViaPointer(root, runs);
    if (!(l->by_frame = calloc((size_t)l->frames, sizeof(cJSON *))))
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    const char *src = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(root, "scene_source"));
    const char *lab = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(root, "script"));
    snprintf(l->scene_source, sizeof l->scene_source, "%s", src ? src : "");
    snprintf(l->script_label, sizeof l->script_label, "%s", lab ? lab : "");
    if (!read_segment(l, cJSON_GetObjectItemCaseSensitive(root, "segment")))
        return iir_fail(err, IIR_ERR_FORMAT, "%s: a bad \"segment\" (index, of, frames)", l->path);
    iir_status st = adopt_frames(l, frames, err);
    l->kept = 0;
    return st;
}

iir_status iird_render_log_load(const char *path, iird_render_log **out, iir_error *err)
{
    *out = NULL;
    iird_render_log *l = calloc(1, sizeof *l);
    if (!l) return iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    snprintf(l->path, sizeof l->path, "%s", path);
    errno = 0;
    char *text = read_text(path);
    cJSON *root = text ? cJSON_Parse(text) : NULL;
    free(text);
    iir_status st = !text && !root ? iir_fail(err, IIR_ERR_IO, "cannot read %s: %s", path,
                                              strerror(errno ? errno : EIO))
                    : root         ? load_document(l, root, err)
                                   : iir_fail(err, IIR_ERR_FORMAT, "%s is not JSON", path);
    cJSON_Delete(root);
    if (st != IIR_OK) {
        iird_render_log_destroy(l);
        return st;
    }
    *out = l;
    return IIR_OK;
}

void iird_render_log_segment(const iird_render_log *l, int *index, int *segments, int *first,
                             int *end)
{
    *index = l->seg, *segments = l->segs, *first = l->seg_first, *end = l->seg_end;
}

iir_status iird_render_log_absorb(iird_render_log *l, const iird_render_log *part, iir_error *err)
{
    iir_status st = check_settings(part->path, l->settings, part->settings, err);
    if (st == IIR_OK && part->frames != l->frames)
        st = iir_fail(err, IIR_ERR_INVALID, "%s: the script has %d frames there, %d elsewhere",
                      part->path, part->frames, l->frames);
    for (int f = 0; st == IIR_OK && f < l->frames; f++) {
        if (!part->by_frame[f]) continue;
        if (l->by_frame[f])
            return iir_fail(err, IIR_ERR_INVALID,
                            "frame %d is in %s and in another part: the segments overlap", f,
                            part->path);
        l->by_frame[f] = cJSON_Duplicate(part->by_frame[f], true);
    }
    for (const cJSON *r = part->old_runs->child; st == IIR_OK && r; r = r->next)
        cJSON_AddItemToArray(l->old_runs, cJSON_Duplicate(r, true));
    return st;
}

bool iird_render_log_entry(const iird_render_log *l, int f, const char **file, float *exposure)
{
    const cJSON *e = f >= 0 && f < l->frames ? l->by_frame[f] : NULL;
    if (!e) return false;
    *file = cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(e, "file"));
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(e, "exposure");
    *exposure = cJSON_IsNumber(x) ? (float)x->valuedouble : 0.f;
    return *file != NULL;
}

int iird_render_log_frames(const iird_render_log *l)
{
    return l->frames;
}

double iird_render_log_fps(const iird_render_log *l)
{
    const cJSON *script = cJSON_GetObjectItemCaseSensitive(l->settings, "script");
    return cJSON_GetNumberValue(cJSON_GetObjectItemCaseSensitive(script, "fps"));
}

const char *iird_render_log_format(const iird_render_log *l)
{
    return cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(l->settings, "format"));
}

iir_status iird_render_log_save(iird_render_log *l, const char *dir, const char *name,
                                iir_error *err)
{
    snprintf(l->path, sizeof l->path, "%s/%s", dir, name);
    snprintf(l->tmp, sizeof l->tmp, "%s.part", l->path);
    l->segs = 0;
    l->run = NULL;
    return iird_render_log_write(l, err);
}

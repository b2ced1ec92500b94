/* render_merge.c -- `iird render --merge DIR [--video FILE.mp4]`: the segments of one animation
 * render (render --segment I/N, e.g. a Slurm array's tasks writing into one shared directory)
 * checked and merged into DIR/render.json, and optionally their video. Not rendering a segment
 * (cmd_render_anim.c) or the log's format (render_log.c).
 *
 * The checks, each with an error that names the part and says what to re-run: every part file
 * render.part-I-of-N.json has the same N and I = 0..N-1 are all there once; the parts' settings
 * (scene, script and its hash, method, size, format, exposure, every parameter) are equal; their
 * frame ranges tile the script's frames without a gap or an overlap; every frame of a range has
 * its entry and its image file. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "render_anim.h"
#include "render_log.h"
#include "video.h"

enum { MAX_PARTS = 4096 };

typedef struct parts {
    iird_render_log *log[MAX_PARTS]; /* by segment index */
    int n;                           /* N */
    char dir[4096];
} parts;

static void parts_free(parts *p)
{
    for (int i = 0; i < p->n && i < MAX_PARTS; i++) iird_render_log_destroy(p->log[i]);
}

/* Loads one part file into its slot: its name and its own segment must agree, N must be the
 * others'. */
static iir_status load_part(parts *p, const char *name, int i, int n, iir_error *err)
{
    if (n > MAX_PARTS)
        return iir_fail(err, IIR_ERR_INVALID, "%s/%s: more than %d segments", p->dir, name,
                        MAX_PARTS);
    if (p->n && n != p->n)
        return iir_fail(err, IIR_ERR_INVALID,
                        "%s holds parts of %d and of %d segments (%s): one render per "
                        "directory",
                        p->dir, p->n, n, name);
    p->n = n;
    char path[8192];
    snprintf(path, sizeof path, "%s/%s", p->dir, name);
    iird_render_log *l = NULL;
    iir_status st = iird_render_log_load(path, &l, err);
    int si = 0, sn = 0, a = 0, b = 0;
    if (st == IIR_OK) iird_render_log_segment(l, &si, &sn, &a, &b);
    if (st == IIR_OK && (si != i || sn != n))
        st = iir_fail(err, IIR_ERR_FORMAT, "%s says it is segment %d of %d", path, si, sn);
    if (st != IIR_OK) return iird_render_log_destroy(l), st;
    p->log[i] = l;
    return IIR_OK;
}

/* Every render.part-I-of-N.json of the directory. */
static iir_status load_parts(parts *p, iir_error *err)
{
    DIR *d = opendir(p->dir);
    if (!d) return iir_fail(err, IIR_ERR_IO, "--merge %s: not a readable directory", p->dir);
    iir_status st = IIR_OK;
    int found = 0;
    for (struct dirent *e; st == IIR_OK && (e = readdir(d));) {
        int i = -1, n = -1, end = 0;
        if (sscanf(e->d_name, "render.part-%d-of-%d.json%n", &i, &n, &end) != 2 ||
            e->d_name[end] != '\0' || i < 0 || n < 1 || i >= n)
            continue;
        st = load_part(p, e->d_name, i, n, err);
        found++;
    }
    closedir(d);
    if (st == IIR_OK && !found)
        st = iir_fail(err, IIR_ERR_INVALID,
                      "%s has no render.part-I-of-N.json: render the segments into it first "
                      "(iird render --anim ... --out %s --segment I/N)",
                      p->dir, p->dir);
    for (int i = 0; st == IIR_OK && i < p->n; i++)
        if (!p->log[i])
            st = iir_fail(err, IIR_ERR_INVALID,
                          "%s: segment %d of %d is missing (render.part-%d-of-%d.json): run "
                          "iird render ... --segment %d/%d into it",
                          p->dir, i, p->n, i, p->n, i, p->n);
    return st;
}

/* The parts' ranges tile the script's frames in order: part i starts where part i - 1 ended. */
static iir_status check_ranges(const parts *p, iir_error *err)
{
    int next = 0, frames = iird_render_log_frames(p->log[0]);
    for (int i = 0; i < p->n; i++) {
        int si, sn, a, b;
        iird_render_log_segment(p->log[i], &si, &sn, &a, &b);
        if (a != next)
            return iir_fail(err, IIR_ERR_INVALID,
                            "segment %d of %d covers frames %d..%d, but the one before ended at "
                            "%d: the parts come from different renders",
                            i, p->n, a, b - 1, next - 1);
        next = b;
    }
    if (next != frames)
        return iir_fail(err, IIR_ERR_INVALID,
                        "the segments cover frames 0..%d of the script's %d: the parts come from "
                        "different renders",
                        next - 1, frames);
    return IIR_OK;
}

static bool file_exists(const char *dir, const char *name)
{
    char path[8192];
    struct stat sb;
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return stat(path, &sb) == 0 && S_ISREG(sb.st_mode);
}

/* Every frame of each part's range has its entry (in that part) and its image. */
static iir_status check_frames(const parts *p, iir_error *err)
{
    for (int i = 0; i < p->n; i++) {
        int si, sn, a, b;
        iird_render_log_segment(p->log[i], &si, &sn, &a, &b);
        for (int f = a; f < b; f++) {
            const char *file = NULL;
            float exposure;
            if (!iird_render_log_entry(p->log[i], f, &file, &exposure))
                return iir_fail(err, IIR_ERR_INVALID,
                                "segment %d of %d has no frame %d: run it again (iird render "
                                "... --segment %d/%d resumes it)",
                                i, p->n, f, i, p->n);
            if (!file_exists(p->dir, file))
                return iir_fail(err, IIR_ERR_IO,
                                "%s/%s (frame %d, segment %d of %d) is missing: run the segment "
                                "again",
                                p->dir, file, f, i, p->n);
        }
    }
    return IIR_OK;
}

/* Part 0 absorbs the others (settings checked there), then is saved as render.json. */
static iir_status merge_logs(parts *p, iir_error *err)
{
    iir_status st = IIR_OK;
    for (int i = 1; st == IIR_OK && i < p->n; i++)
        st = iird_render_log_absorb(p->log[0], p->log[i], err);
    if (st == IIR_OK) st = iird_render_log_save(p->log[0], p->dir, "render.json", err);
    return st;
}

/* The video of the merged frames, read back from their files (PNG: as written, exposure applied;
 * EXR and PFM: with each frame's exposure). */
static iir_status write_video(const parts *p, const char *video, iir_error *err)
{
    const iird_render_log *l = p->log[0];
    int frames = iird_render_log_frames(l);
    iird_video *v = NULL;
    iir_status st = IIR_OK;
    bool png = !strcmp(iird_render_log_format(l), "png");
    for (int f = 0; st == IIR_OK && f < frames; f++) {
        const char *file = NULL;
        float exposure = 0.f;
        iird_render_log_entry(l, f, &file, &exposure);
        char path[8192];
        snprintf(path, sizeof path, "%s/%s", p->dir, file);
        iir_image *img = NULL;
        st = iir_image_read(path, &img, err);
        if (st == IIR_OK && !v)
            st = iird_video_open(video, img->width, img->height, iird_render_log_fps(l), &v, err);
        if (st == IIR_OK) st = iird_video_frame(v, img, png ? 0.f : exposure, err);
        iir_image_destroy(img);
    }
    iir_error cerr = {0};
    iir_status closed = iird_video_close(v, &cerr);
    if (st == IIR_OK && closed != IIR_OK) *err = cerr;
    return st == IIR_OK ? closed : st;
}

int iird_render_merge(const iird_render_opts *o)
{
    parts *p = calloc(1, sizeof *p);
    if (!p) return fprintf(stderr, "iird render: out of memory\n"), 1;
    snprintf(p->dir, sizeof p->dir, "%s", o->merge);
    iir_error err = {0};
    iir_status st = load_parts(p, &err);
    if (st == IIR_OK) st = check_ranges(p, &err);
    if (st == IIR_OK) st = check_frames(p, &err);
    if (st == IIR_OK && o->video) st = iird_prepare_parent(o->video, "--video", &err);
    if (st == IIR_OK) st = merge_logs(p, &err);
    int frames = st == IIR_OK ? iird_render_log_frames(p->log[0]) : 0;
    if (st == IIR_OK && o->video) st = write_video(p, o->video, &err);
    int rc = 0;
    if (st == IIR_OK) {
        printf("merged %d segments of %d frames into %s/render.json\n", p->n, frames, p->dir);
        if (o->video) printf("video %s: %d frames (H.264)\n", o->video, frames);
    } else {
        rc = iird_report("render", &err);
    }
    parts_free(p);
    free(p);
    return rc;
}

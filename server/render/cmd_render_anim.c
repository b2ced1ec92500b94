/* cmd_render_anim.c -- `iird render --anim`: checks an animation script against the scene's
 * lights, renders its frames (every light it animates moved) in order with one method instance
 * (so coherence carries from frame to frame) into DIR/frame_NNNNN.<ext>, logs them in
 * DIR/render.json and optionally pipes them into an MP4. Not option parsing (cmd_render.c),
 * render.json (render_log.c) or the ffmpeg pipe (video.c).
 *
 * Files are named by the frame's index in the script, so `--frames A:B` fills a gap. Every file
 * is written under a .part name and renamed, so an interrupted run leaves whole frames only.
 *
 * Resuming: a method's state (iir's VPL set and its shadow maps, ir's frame counter) is not
 * saved, so a run that starts at frame A > 0 first renders frames 0..A-1 at WARMUP_DIM x
 * WARMUP_DIM pixels without writing them. The methods' cross-frame state does not depend on the
 * image size, so frame A then comes out byte for byte as in one uninterrupted run
 * (tests/cli/test_render_anim.sh checks it); the cost is the VPL work of A frames, not their
 * shading. render.json records the warm-up of every run. */
#define _GNU_SOURCE /* program_invocation_name */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "animview.h"
#include "cli.h"
#include "iir/hash.h"
#include "iir/timer.h"
#include "iir/anim.h"
#include "iir/image.h"
#include "render_anim.h"
#include "render_log.h"
#include "video.h"

enum {
    WARMUP_DIM = 8,        /* warm-up frames are this many pixels square */
    CHECKPOINT_MS = 10000, /* render.json is rewritten at least this often while rendering */
};

/* ---- options ---- */

/* A frame index: digits only, at most 9 of them. */
static bool parse_index(const char *s, size_t n, int *out)
{
    if (n == 0 || n > 9) return false;
    int v = 0;
    for (size_t i = 0; i < n; i++) {
        if (s[i] < '0' || s[i] > '9') return false;
        v = v * 10 + (s[i] - '0');
    }
    *out = v;
    return true;
}

iir_status iird_parse_frame_range(const char *text, int *first, int *end, iir_error *err)
{
    const char *colon = strchr(text, ':');
    int a = 0, b = -1;
    if (!colon || !parse_index(text, (size_t)(colon - text), &a) ||
        (colon[1] && !parse_index(colon + 1, strlen(colon + 1), &b)))
        return iir_fail(err, IIR_ERR_INVALID,
                        "--frames '%s' must be A:B (script frames A to B-1) or A: (A to the end)",
                        text);
    if (b >= 0 && b <= a)
        return iir_fail(err, IIR_ERR_INVALID,
                        "--frames %s: B must be greater than A (the range is A..B-1)", text);
    *first = a;
    *end = b;
    return IIR_OK;
}

static const char *const FORMAT_EXT[] = {"png", "exr", "pfm"};

iir_status iird_parse_format(const char *text, iird_format *format, iir_error *err)
{
    for (int i = 0; i < 3; i++)
        if (!strcmp(text, FORMAT_EXT[i])) {
            *format = (iird_format)i;
            return IIR_OK;
        }
    return iir_fail(err, IIR_ERR_INVALID, "--format '%s' must be png, exr or pfm", text);
}

const char *iird_format_ext(iird_format format)
{
    return FORMAT_EXT[format];
}

/* Ends a progress bar: drawn full after success, left where it stopped otherwise. */
static void end_bar(iird_progress *bar, iir_status st)
{
    if (st == IIR_OK)
        iird_progress_finish(bar);
    else if (bar->enabled)
        fputc('\n', stderr);
}

/* ---- one run ---- */

typedef struct anim_job {
    const iird_render_opts *o; /* &opts */
    iird_render_opts opts;     /* the options, with the default size settled (set_size) */
    iir_scene *scene;
    iir_rt *rt;
    iir_anim *anim;
    char script[4096]; /* what --anim loaded, for messages */
    uint32_t spot; /* the light the light track moves (animview.h: num_lights = the made-up spot) */
    iir_light *lights; /* the current frame's lights */
    int count;         /* frames of the script */
    int first, end;    /* this run: frames [first, end) */
    iir_method *m;
    iir_image *img;
    iird_render_log *log;
    iird_video *video;
    iird_render_run run;
    double start_ms, frames_start_ms, render_ms, last_log_ms;
    int black_frames, first_black; /* frames that came out entirely black */
    iir_frame_stats last;          /* the last frame written (the controller's state) */
    char log_name[64];             /* render.json, or a segment's render.part-I-of-N.json */
} anim_job;

/* The view of script frame f: the scene's camera and lights, every light the script animates
 * moved. */
static iir_view frame_view(const anim_job *j, int f)
{
    return iird_anim_view(j->anim, j->scene, j->spot, j->lights, f);
}

/* h extended by v's three floats. */
static uint64_t hash_vec(uint64_t h, iir_vec3 v)
{
    float f[3] = {v.x, v.y, v.z};
    return iir_hash_bytes(h, f, sizeof f);
}

/* The exposure of frame f: --exposure when given, else the script's (--exposure's default, 0,
 * when it has none). */
static float frame_exposure(const anim_job *j, int f)
{
    if (j->o->exposure_given) return j->o->exposure;
    return iir_anim_exposure(j->anim, j->o->exposure, iir_anim_frame_time(j->anim, f));
}

/* A hash of what the script does at every frame (the lights, the camera and, when it sets the
 * frames' exposure, the exposure), so a resume with an edited script is refused while the same
 * script by another path is not. */
static uint64_t script_hash(anim_job *j)
{
    uint64_t h = iir_hash_bytes(IIR_HASH_BASIS, &j->count, sizeof j->count);
    double fps = iir_anim_fps(j->anim);
    h = iir_hash_bytes(h, &fps, sizeof fps);
    for (int f = 0; f < j->count; f++) {
        iir_view v = frame_view(j, f);
        h = hash_vec(hash_vec(h, v.camera.position), v.camera.target);
        h = iir_hash_bytes(hash_vec(h, v.camera.up), &v.camera.fov_y, sizeof v.camera.fov_y);
        float exposure = frame_exposure(j, f);
        if (!j->o->exposure_given && iir_anim_has_exposure(j->anim))
            h = iir_hash_bytes(h, &exposure, sizeof exposure);
        for (uint32_t i = 0; i < v.num_lights; i++) h = iir_light_hash(h, &v.lights[i]);
    }
    return h;
}

/* The frame range against the script's length. */
static iir_status set_range(anim_job *j, iir_error *err)
{
    const iird_render_opts *o = j->o;
    j->count = iir_anim_frame_count(j->anim);
    j->first = o->first;
    j->end = o->end < 0 ? j->count : o->end;
    if (o->segments) { /* the I-th of N contiguous shares of the script */
        iird_segment_range(o->segment, o->segments, j->count, &j->first, &j->end);
        snprintf(j->log_name, sizeof j->log_name, "render.part-%d-of-%d.json", o->segment,
                 o->segments);
        if (j->first == j->end)
            return iir_fail(err, IIR_ERR_INVALID,
                            "--segment %s: the script %s has only %d frames, fewer than %d "
                            "segments",
                            o->segment_arg, j->script, j->count, o->segments);
        return IIR_OK;
    }
    if (j->first >= j->count || j->end > j->count)
        return iir_fail(err, IIR_ERR_INVALID,
                        "--frames %s: the script %s has %d frames (0:%d at most)", o->frames_arg,
                        j->script, j->count, j->count);
    return IIR_OK;
}

/* The light the light track moves, as a session moves it (animview.h), and the lights array;
 * then the script's light tracks against the scene's lights. */
static iir_status set_lights(anim_job *j, iir_error *err)
{
    j->spot = iird_moved_light(j->scene);
    if (!(j->lights = malloc(sizeof(iir_light) * (j->scene->num_lights + 1))))
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    iir_view v = iird_anim_view(j->anim, j->scene, j->spot, j->lights, 0);
    return iir_anim_check_lights(j->anim, v.lights, v.num_lights, j->spot, err);
}

/* Without --size: the script's size (a recording's: the session's frame size); else the pixels of
 * a 512x512 still's height, as wide as the scene camera's aspect asks (16:9 for a scene that gives
 * none), at most 1280 wide; even, for the video. */
static void set_size(anim_job *j, const iird_anim_origin *origin)
{
    enum { HEIGHT = 512, MAX_WIDTH = 1280 };
    if (j->opts.size_given) return;
    if (origin->width) {
        j->opts.width = origin->width;
        j->opts.height = origin->height;
        return;
    }
    double a = j->scene->aspect > 0.f ? j->scene->aspect : 16.0 / 9.0;
    long w = 2 * lround(HEIGHT * a / 2), h = HEIGHT;
    if (w > MAX_WIDTH) w = MAX_WIDTH, h = 2 * lround(MAX_WIDTH / a / 2);
    j->opts.width = w > 2 ? (int)w : 2;
    j->opts.height = h > 2 ? (int)h : 2;
}

/* Scene (and the size that follows it), script, range, then the output folders (made only once
 * the rest is accepted): everything that can be refused before any work. */
static iir_status load(anim_job *j, iir_error *err)
{
    const iird_render_opts *o = j->o;
    iir_status st = iir_method_params_validate(o->method, &o->params, NULL, NULL, err);
    if (st == IIR_OK && o->video && o->size_given)
        st = iird_video_check(o->video, o->width, o->height, err);
    iird_anim_origin origin;
    iird_anim_origin_read("render", o->scene, o->scenes_dir, o->anim, &origin);
    const char *scene = origin.scene, *scenes = origin.scenes_dir;
    if (st == IIR_OK) st = iir_scene_open(scene, scenes, &j->scene, &j->rt, err);
    if (st == IIR_OK) set_size(j, &origin);
    if (st == IIR_OK) st = iird_check_memory(o->method, &o->params, o->width, o->height, err);
    if (st == IIR_OK && o->video && !o->size_given)
        st = iird_video_check(o->video, o->width, o->height, err);
    if (st == IIR_OK)
        st = iird_resolve_anim(j->scene, scenes, o->anim, &j->anim, j->script, sizeof j->script,
                               err);
    if (st == IIR_OK) iird_warn_anim_scene("render", j->anim, scene, j->scene);
    if (st == IIR_OK) iird_note_camera("render", j->scene);
    if (st == IIR_OK) st = set_range(j, err);
    if (st == IIR_OK) st = set_lights(j, err);
    if (st == IIR_OK) st = iird_prepare_dir(o->out, "--out", err);
    if (st == IIR_OK && o->video) st = iird_prepare_parent(o->video, "--video", err);
    if (st == IIR_OK)
        iird_warn_dropped("render", o->method, &o->params, j->scene, j->scene->lights,
                          j->scene->num_lights);
    return st;
}

/* Method, render.json (which may refuse a resume), image, video. */
static iir_status prepare(anim_job *j, iir_error *err)
{
    const iird_render_opts *o = j->o;
    iird_render_setup setup = {.scene_name = j->scene->name,
                               .scene_source = j->scene->source,
                               .script_label = j->script,
                               .script_frames = j->count,
                               .fps = iir_anim_fps(j->anim),
                               .script_hash = script_hash(j),
                               .method = o->method,
                               .format = iird_format_ext(o->format),
                               .width = o->width,
                               .height = o->height,
                               .exposure = frame_exposure(j, 0),
                               .params = &o->params,
                               .log_name = j->log_name,
                               .segment = o->segment,
                               .segments = o->segments,
                               .segment_first = j->first,
                               .segment_end = j->end};
    j->run = (iird_render_run){.first = j->first,
                               .end = j->end,
                               .status = "running",
                               .video = o->video,
                               .threads = omp_get_max_threads()};
    iir_status st = iir_method_create(o->method, j->scene, j->rt, &o->params, &j->m, err);
    if (st == IIR_OK) st = iird_render_log_open(o->out, &setup, &j->run, &j->log, err);
    if (st == IIR_OK && !(j->img = iir_image_create(o->width, o->height)))
        st = iir_fail(err, IIR_ERR_NOMEM, "out of memory for a %dx%d frame", o->width, o->height);
    if (st == IIR_OK && o->video)
        st = iird_video_open(o->video, o->width, o->height, iir_anim_fps(j->anim), &j->video, err);
    return st;
}

/* A segment run again (a farm's failed task) starts at its first frame its part file lacks (the
 * frames before it are warmed up as for --frames); *done when it has every frame already. */
static void resume_segment(anim_job *j, bool *done)
{
    const char *file;
    float exposure;
    int f = j->first;
    while (j->o->segments && f < j->end && iird_render_log_entry(j->log, f, &file, &exposure)) f++;
    if (f > j->first)
        fprintf(stderr, "iird render: %s has frames %d..%d already: going on from frame %d\n",
                j->log_name, j->first, f - 1, f);
    j->run.first = j->first = f;
    *done = f == j->end;
}

/* Frames 0..first-1, small and unwritten, so the method's state reaches frame `first` as in an
 * uninterrupted run (see the top of this file). */
static iir_status warm_up(anim_job *j, iir_error *err)
{
    if (j->first == 0) return IIR_OK;
    double t0 = iir_now_ms();
    iir_image *small = iir_image_create(WARMUP_DIM, WARMUP_DIM);
    if (!small) return iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    iird_progress bar;
    iird_progress_start(&bar, "warm-up", j->first);
    iir_status st = IIR_OK;
    for (int f = 0; st == IIR_OK && f < j->first; f++) {
        iir_view v = frame_view(j, f);
        iir_frame_stats fs = {0};
        st = iir_method_render(j->m, &v, small, &fs, err);
        iird_progress_update(&bar, f + 1);
        if (st == IIR_OK && iird_interrupted())
            st = iir_fail(err, IIR_ERR_INTERRUPTED, "interrupted during the warm-up");
    }
    end_bar(&bar, st);
    iir_image_destroy(small);
    j->run.warmup_frames = j->first;
    j->run.warmup_width = j->run.warmup_height = WARMUP_DIM;
    j->run.warmup_ms = iir_now_ms() - t0;
    return st;
}

static iir_status write_image(const iir_image *img, iird_format format, const char *path,
                              float exposure, iir_error *err)
{
    switch (format) {
    case IIRD_FORMAT_EXR:
        return iir_image_write_exr(img, path, err);
    case IIRD_FORMAT_PFM:
        return iir_image_write_pfm(img, path, err);
    default:
        return iir_image_write_png(img, path, exposure, err);
    }
}

/* Writes frame f under a temporary name and renames it, then sends it to the video and logs it.
 */
static iir_status write_frame(anim_job *j, int f, const iir_frame_stats *fs, iir_error *err)
{
    const iird_render_opts *o = j->o;
    char name[64], path[4200], part[4300];
    snprintf(name, sizeof name, "frame_%05d.%s", f, iird_format_ext(o->format));
    snprintf(path, sizeof path, "%s/%s", o->out, name);
    snprintf(part, sizeof part, "%s.part", path);
    double t0 = iir_now_ms();
    float exposure = frame_exposure(j, f);
    iir_status st = write_image(j->img, o->format, part, exposure, err);
    if (st == IIR_OK && rename(part, path) != 0)
        st = iir_fail(err, IIR_ERR_IO, "cannot rename %s to %s: %s", part, name, strerror(errno));
    if (st != IIR_OK) {
        remove(part);
        return st;
    }
    double write_ms = iir_now_ms() - t0;
    if (iird_image_black(j->img) && j->black_frames++ == 0) j->first_black = f;
    iird_render_log_frame(j->log, f, iir_anim_frame_time(j->anim, f), name, exposure, fs, write_ms);
    j->run.done++;
    j->render_ms += fs->total_ms;
    j->last = *fs;
    return j->video ? iird_video_frame(j->video, j->img, exposure, err) : IIR_OK;
}

/* Keeps render.json current during long runs, so even a killed run leaves a useful log. */
static iir_status checkpoint(anim_job *j, iir_error *err)
{
    double now = iir_now_ms();
    if (now - j->last_log_ms < CHECKPOINT_MS) return IIR_OK;
    j->last_log_ms = now;
    j->run.wall_ms = now - j->start_ms;
    return iird_render_log_write(j->log, err);
}

/* Frames first..end-1. A Ctrl-C during a frame lets that frame finish and be written. */
static iir_status render_frames(anim_job *j, iir_error *err)
{
    iird_progress bar;
    iird_progress_start(&bar, "render", j->end - j->first);
    iir_status st = IIR_OK;
    j->frames_start_ms = j->last_log_ms = iir_now_ms();
    for (int f = j->first; st == IIR_OK && f < j->end; f++) {
        iir_view v = frame_view(j, f);
        iir_frame_stats fs = {0};
        st = iir_method_render(j->m, &v, j->img, &fs, err);
        if (st == IIR_OK) st = write_frame(j, f, &fs, err);
        if (st == IIR_OK) st = checkpoint(j, err);
        iird_progress_update(&bar, f + 1 - j->first);
        if (st == IIR_OK && iird_interrupted() && f + 1 < j->end)
            st = iir_fail(err, IIR_ERR_INTERRUPTED, "interrupted");
    }
    end_bar(&bar, st);
    return st;
}

/* ---- reporting ---- */

/* Appends s to buf, single-quoted for a POSIX shell when it holds anything but safe characters.
 */
static void append_arg(char *buf, size_t n, const char *s)
{
    size_t used = strlen(buf);
    bool safe = *s != '\0';
    for (const char *p = s; *p; p++)
        if (!strchr("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_@%+=:,./-", *p))
            safe = false;
    if (used + 1 < n) buf[used++] = ' ', buf[used] = '\0';
    if (safe) {
        snprintf(buf + used, n - used, "%s", s);
        return;
    }
    if (used + 1 < n) buf[used++] = '\'';
    for (const char *p = s; *p && used + 5 < n; p++) {
        if (*p == '\'') {
            memcpy(buf + used, "'\\''", 4), used += 4;
        } else {
            buf[used++] = *p;
        }
    }
    if (used + 1 < n) buf[used++] = '\'';
    buf[used < n ? used : n - 1] = '\0';
}

/* True when arg is, or holds after '=', the value of --frames or --video. */
static bool is_dropped_value(const iird_render_opts *o, const char *arg)
{
    const char *values[2] = {o->frames_arg, o->video};
    uintptr_t a = (uintptr_t)arg, end = a + strlen(arg);
    for (int i = 0; i < 2; i++) {
        uintptr_t v = (uintptr_t)values[i];
        if (values[i] && v >= a && v <= end) return true;
    }
    return false;
}

/* The command line that renders frames from..end-1 with the same settings: this one without its
 * --frames and --video, plus --frames FROM:END. */
static void resume_command(const anim_job *j, int from, char *buf, size_t n)
{
    const iird_render_opts *o = j->o;
    buf[0] = '\0';
    append_arg(buf, n, program_invocation_name);
    for (int k = 0; k < o->argc; k++) {
        const char *a = o->argv[k];
        bool option_with_value = k + 1 < o->argc && a[0] == '-' && !strchr(a, '=') &&
                                 (o->argv[k + 1] == o->frames_arg || o->argv[k + 1] == o->video);
        if (option_with_value)
            k++;
        else if (!is_dropped_value(o, a))
            append_arg(buf, n, a);
    }
    char range[64];
    snprintf(range, sizeof range, "%d:%d", from, j->end);
    if (!o->segments) { /* a segment resumes where its part file stops: the same command */
        append_arg(buf, n, "--frames");
        append_arg(buf, n, range);
    }
    memmove(buf, buf + 1, strlen(buf)); /* the leading space */
}

/* After a stop with work left: what was kept and how to go on. */
static void report_stop(const anim_job *j, iir_status st, const iir_error *err)
{
    const iird_render_opts *o = j->o;
    int total = j->end - j->first, next = j->first + j->run.done;
    char cmd[8192];
    resume_command(j, next, cmd, sizeof cmd);
    if (st == IIR_ERR_INTERRUPTED)
        fprintf(stderr, "iird render: interrupted after %d of %d frames; resume with: %s\n",
                j->run.done, total, cmd);
    else
        fprintf(stderr,
                "iird render: %s\niird render: %d of %d frames were written; resume with: %s\n",
                err->msg, j->run.done, total, cmd);
    if (!o->video || j->run.done == 0) return;
    fprintf(stderr, "iird render: the video %s holds frames %d..%d only", o->video, j->first,
            next - 1);
    if (o->format == IIRD_FORMAT_PNG)
        fprintf(stderr,
                "; once every frame is rendered, encode them all with: ffmpeg -framerate %g -i "
                "%s/frame_%%05d.png -c:v libx264 -pix_fmt yuv420p %s",
                iir_anim_fps(j->anim), o->out, o->video);
    fputc('\n', stderr);
}

/* After the frames: how many came out entirely black, and why the first may have. */
static void warn_black(anim_job *j)
{
    if (j->black_frames == 0) return;
    char what[96];
    if (j->black_frames == j->run.done)
        snprintf(what, sizeof what, "all %d frames are", j->black_frames);
    else
        snprintf(what, sizeof what, "%d of %d frames (first: frame %d) are", j->black_frames,
                 j->run.done, j->first_black);
    iir_view v = frame_view(j, j->first_black);
    iird_warn_black("render", what, j->scene, j->rt, &v);
}

static void print_summary(const anim_job *j, int video_frames)
{
    const iird_render_opts *o = j->o;
    int n = j->run.done;
    double mean = n ? j->render_ms / n : 0;
    double wall = n ? (iir_now_ms() - j->frames_start_ms) / n : 0;
    printf("wrote %d frames (%d..%d of %d) to %s: %s, %dx%d %s, method %s; %.2f ms/frame "
           "rendering (%.1f fps), %.2f ms/frame with writing (%.1f fps), %.1f s",
           n, j->first, j->end - 1, j->count, o->out, j->scene->name, o->width, o->height,
           iird_format_ext(o->format), o->method, mean, mean > 0 ? 1000 / mean : 0, wall,
           wall > 0 ? 1000 / wall : 0, j->run.wall_ms / 1e3);
    if (j->run.warmup_frames)
        printf(" (warm-up of frames 0..%d: %.1f s)", j->first - 1, j->run.warmup_ms / 1e3);
    printf("\n%s: %d of %d frames%s\n", j->log_name, iird_render_log_count(j->log), j->count,
           iird_render_log_kept(j->log) ? " (earlier runs' frames kept)" : "");
    if (o->video)
        printf("video %s: %d frames at %g fps (H.264)\n", o->video, video_frames,
               iir_anim_fps(j->anim));
    const iir_ctl_report *c = &j->last.ctl;
    if (n && j->last.controlled)
        printf("frame-time controller: target %.2f ms, frames %.2f ms (running mean)%s%s; last "
               "setting %d VPLs, interleave %d, sm_res %d after %u changes (%u cuts undone: no "
               "time bought)\n",
               c->target_ms, c->mean_ms, c->reachable ? "" : ", not reachable at the floor",
               c->busy ? ", busy" : "", c->setting.vpls, c->setting.interleave, c->setting.sm_res,
               c->moves, c->undone);
    char settings[1024];
    iird_settings_text(o->method, &o->params, settings, sizeof settings);
    printf("%s settings: %s\n", o->method, settings);
}

/* Closes the video, writes render.json, says what happened; returns the final status. */
static iir_status finish(anim_job *j, iir_status st, iir_error *err)
{
    iir_error verr = {0}, lerr = {0};
    j->run.wall_ms = iir_now_ms() - j->start_ms;
    j->run.status = st == IIR_OK                ? "complete"
                    : st == IIR_ERR_INTERRUPTED ? "interrupted"
                                                : "failed";
    int video_frames = iird_video_frames(j->video);
    iir_status vst = iird_video_close(j->video, &verr);
    j->video = NULL;
    if (vst != IIR_OK && st == IIR_OK) j->run.status = "failed";
    iir_status lst = j->log ? iird_render_log_write(j->log, &lerr) : IIR_OK;
    if (st == IIR_OK && vst == IIR_OK && lst == IIR_OK) print_summary(j, video_frames);
    if (st == IIR_OK) warn_black(j);
    if (st == IIR_OK && vst != IIR_OK)
        st = vst, *err = verr;
    else if (vst != IIR_OK)
        fprintf(stderr, "iird render: %s\n", verr.msg);
    if (st == IIR_OK && lst != IIR_OK)
        st = lst, *err = lerr;
    else if (lst != IIR_OK)
        fprintf(stderr, "iird render: %s\n", lerr.msg);
    return st;
}

static void free_job(anim_job *j)
{
    iird_video_close(j->video, NULL);
    iird_render_log_destroy(j->log);
    iir_image_destroy(j->img);
    iir_method_destroy(j->m);
    free(j->lights);
    iir_anim_destroy(j->anim);
    iir_rt_destroy(j->rt);
    iir_scene_destroy(j->scene);
}

int iird_render_anim(const iird_render_opts *o)
{
    anim_job j = {.opts = *o, .start_ms = iir_now_ms(), .log_name = "render.json"};
    j.o = &j.opts;
    iir_error err = {0};
    iird_catch_interrupts();
    iir_status st = load(&j, &err);
    if (st == IIR_OK) st = prepare(&j, &err);
    bool started = st == IIR_OK, done = false;
    if (st == IIR_OK) resume_segment(&j, &done);
    if (st == IIR_OK && !done) st = warm_up(&j, &err);
    if (st == IIR_OK && !done) st = render_frames(&j, &err);
    if (started) st = finish(&j, st, &err);
    int rc = iir_status_exit_code(st);
    if (started && st != IIR_OK && j.run.done < j.end - j.first)
        report_stop(&j, st, &err);
    else if (st != IIR_OK)
        rc = iird_report("render", &err);
    free_job(&j);
    return rc;
}

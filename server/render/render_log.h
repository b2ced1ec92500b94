/* render_log.h -- DIR/render.json of `iird render --anim`: the settings a resumed run must
 * match, one entry per rendered frame (stats), one per run (range, warm-up, outcome), and
 * totals. A resumed run keeps the earlier frames' entries and adds or replaces its own. Not the
 * rendering (cmd_render_anim.c).
 *
 * Layout (docs/cli.md): {"generator", "settings": {scene, script: {frames, fps, hash}, method,
 * size, format, exposure, params: {every parameter of the method by name}}, "scene_source",
 * "script", ["segment": {index, of, frames: [first, end]}], "runs": [...], "frames": [{frame,
 * time_s, file, exposure, total_ms, write_ms, phase_ms, rays, vpls, spp}], "totals"}. The file is
 * replaced atomically (written to NAME.part, renamed).
 *
 * Segments (`render --segment I/N`, a farm's array task) each write their own
 * render.part-I-of-N.json into the shared directory; `render --merge` loads them, checks and
 * absorbs them into one log, and saves render.json (render_merge.c). */
#ifndef IIRD_RENDER_LOG_H
#define IIRD_RENDER_LOG_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/method.h"
#include "iir/status.h"

/* What identifies a render: a resumed run must match every field but the labels. */
typedef struct iird_render_setup {
    const char *scene_name;
    const char *scene_source; /* label only: the scene file, "" for the built-in box */
    const char *script_label; /* label only: the script file (or sidecar path) as loaded */
    int script_frames;
    double fps;
    uint64_t script_hash; /* of the script's light and camera at every frame */
    const char *method, *format;
    int width, height;
    float exposure;
    const iir_params *params;
    const char *log_name;           /* the file in the directory: NULL for render.json */
    int segment, segments;          /* --segment I/N (segments 0: none) */
    int segment_first, segment_end; /* its frames */
} iird_render_setup;

/* One run of `iird render --anim`; the caller updates it, every write serialises it. */
typedef struct iird_render_run {
    int first, end;    /* --frames range */
    int done;          /* frames written so far */
    int warmup_frames; /* frames 0..first-1 rendered first, not written (0: none) */
    int warmup_width, warmup_height;
    double warmup_ms, wall_ms; /* wall-clock time of the warm-up and of the whole run */
    const char *status;        /* "running", "complete", "interrupted", "failed" */
    const char *video;         /* --video file or NULL */
    int threads;
} iird_render_run;

typedef struct iird_render_log iird_render_log;

/* Starts the log for directory dir. When dir/render.json exists, its settings must equal this
 * run's (else IIR_ERR_INVALID naming the option that differs, e.g. "--vpls", with both values)
 * and its frames and runs are kept; a file that is not such a log is IIR_ERR_FORMAT naming it.
 * `run` (owned by the caller, must outlive the log) is written as the last run. On error *out
 * stays NULL. */
iir_status iird_render_log_open(const char *dir, const iird_render_setup *setup,
                                const iird_render_run *run, iird_render_log **out, iir_error *err);

/* Frames of the earlier render.json that were kept (0 for a new directory). */
int iird_render_log_kept(const iird_render_log *l);
/* Frames that have an entry now, and the script's frame count. */
int iird_render_log_count(const iird_render_log *l);

/* Adds or replaces frame f's entry. file is the image's name inside the directory; exposure the
 * stops its PNG (and video frame) were written with. */
void iird_render_log_frame(iird_render_log *l, int f, double time_s, const char *file,
                           float exposure, const iir_frame_stats *fs, double write_ms);

/* Writes dir/render.json (atomically). IIR_ERR_IO naming the file on failure. */
iir_status iird_render_log_write(iird_render_log *l, iir_error *err);

void iird_render_log_destroy(iird_render_log *l);

/* ---- merging segments (render_merge.c) ---- */

/* Loads a written log (a segment's part file) whole: settings, runs, frames, segment. IIR_ERR_IO
 * when unreadable, IIR_ERR_FORMAT naming the file when it is not such a log. */
iir_status iird_render_log_load(const char *path, iird_render_log **out, iir_error *err);
/* The segment a loaded log was written by (*segments 0: none) and its frame range. */
void iird_render_log_segment(const iird_render_log *l, int *index, int *segments, int *first,
                             int *end);
/* Takes part's frames and runs into l. IIR_ERR_INVALID when its settings differ (naming the
 * option) or it has an entry for a frame l already has; l is then unspecified. */
iir_status iird_render_log_absorb(iird_render_log *l, const iird_render_log *part, iir_error *err);
/* Frame f's entry: its image's file name and exposure; false when the log has no entry for f. */
bool iird_render_log_entry(const iird_render_log *l, int f, const char **file, float *exposure);
/* The script's frame count and fps, the settings' format. */
int iird_render_log_frames(const iird_render_log *l);
double iird_render_log_fps(const iird_render_log *l);
const char *iird_render_log_format(const iird_render_log *l);
/* Writes the log as dir/name (atomically), without a segment and without a current run. */
iir_status iird_render_log_save(iird_render_log *l, const char *dir, const char *name,
                                iir_error *err);

#endif

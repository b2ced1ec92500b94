/* render_log.h -- DIR/render.json of `iird render --anim`: the settings a resumed run must
 * match, one entry per rendered frame (stats), one per run (range, warm-up, outcome), and
 * totals. A resumed run keeps the earlier frames' entries and adds or replaces its own. Not the
 * rendering (cmd_render_anim.c).
 *
 * Layout (docs/cli.md): {"generator", "settings": {scene, script: {frames, fps, hash}, method,
 * size, format, exposure, params: {every parameter of the method by name}}, "scene_source",
 * "script", "runs": [...], "frames": [{frame, time_s, file, total_ms, write_ms, phase_ms, rays,
 * vpls, spp}], "totals"}. The file is replaced atomically (written to render.json.part, renamed).
 */
#ifndef IIRD_RENDER_LOG_H
#define IIRD_RENDER_LOG_H

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

/* Adds or replaces frame f's entry. file is the image's name inside the directory. */
void iird_render_log_frame(iird_render_log *l, int f, double time_s, const char *file,
                           const iir_frame_stats *fs, double write_ms);

/* Writes dir/render.json (atomically). IIR_ERR_IO naming the file on failure. */
iir_status iird_render_log_write(iird_render_log *l, iir_error *err);

void iird_render_log_destroy(iird_render_log *l);

#endif

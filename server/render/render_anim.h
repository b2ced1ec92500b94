/* render_anim.h -- `iird render`'s options, shared by the still render (cmd_render.c) and the
 * animation render `iird render --anim` (cmd_render_anim.c), and the animation render itself.
 * Not render.json (render_log.h) or the video pipe (video.h). */
#ifndef IIRD_RENDER_ANIM_H
#define IIRD_RENDER_ANIM_H

#include <stdbool.h>

#include "iir/method.h"
#include "iir/status.h"

typedef enum iird_format { IIRD_FORMAT_PNG, IIRD_FORMAT_EXR, IIRD_FORMAT_PFM } iird_format;

typedef struct iird_render_opts {
    const char *scene, *scenes_dir, *method; /* method NULL: pt for stills, iir with --anim */
    const char *out;                         /* a file for stills, a directory with --anim */
    int width, height;
    bool size_given;
    float exposure;
    bool exposure_given; /* --exposure given: it wins over an --anim script's exposure */
    iir_params params;
    /* --anim only. frames_arg / format_arg / video are the option values as given: pointers
     * into argv (the resume hint drops --frames and --video by them), NULL when absent. */
    const char *anim, *video, *frames_arg, *format_arg;
    iird_format format;
    int first, end;          /* --frames A:B -> first = A, end = B; end < 0: to the script's end */
    const char *segment_arg; /* --segment I/N as given, or NULL */
    int segment, segments;   /* I and N: frames [I count / N, (I + 1) count / N) */
    const char *merge;       /* --merge DIR, or NULL */
    int argc;                /* the command line, argv[0] = "render", for the resume hint */
    char **argv;
} iird_render_opts;

/* Parses --frames "A:B" (frames A..B-1, 0 <= A < B) or "A:" (A to the end). IIR_ERR_INVALID
 * naming --frames otherwise; the outputs are then unchanged. */
iir_status iird_parse_frame_range(const char *text, int *first, int *end, iir_error *err);

/* Parses --format png|exr|pfm; IIR_ERR_INVALID naming --format otherwise. */
iir_status iird_parse_format(const char *text, iird_format *format, iir_error *err);

/* "png", "exr" or "pfm". */
const char *iird_format_ext(iird_format format);

/* Renders frames [first, end) of the --anim script into the directory o->out, with
 * DIR/render.json and optionally a video; see docs/cli.md. Returns the process exit code after
 * printing what happened (130 after Ctrl-C, with a resume command). */
int iird_render_anim(const iird_render_opts *o);

/* `iird render --merge DIR [--video FILE.mp4]` (render_merge.c): checks that the segments'
 * render.part-I-of-N.json in DIR are all there, agree in their settings and hold every frame of
 * their ranges once, with its image; writes DIR/render.json and optionally the video. Returns the
 * exit code after printing what happened. */
int iird_render_merge(const iird_render_opts *o);

#endif

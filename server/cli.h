/* cli.h -- what the iird subcommands share: argument parsing helpers, the scenes folder and the
 * animation scripts a scene names, and the progress bar. Not any subcommand's logic, and not
 * loading scenes (iir_scene_open in iir/scene.h). */
#ifndef IIRD_CLI_H
#define IIRD_CLI_H

#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>

#include <getopt.h>

#include "iir/anim.h"
#include "iir/method.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "iir/status.h"

/* Exit codes (docs/cli.md): 0 ok, 1 internal, 2 bad input, 3 io, 4 unsupported, 64 usage,
 * 130 interrupted. */
enum { IIRD_EXIT_USAGE = 64 };

/* ---- method parameters: options derived from the methods' tables (method.h, params.h) ----
 *
 * Every row of every method's tables is an option --name (with '-' for '_'): integers, numbers and
 * enums take a value (--sm-res 64, --weights uniform), booleans take none or an attached one
 * (--jitter, --jitter=false). --threads N sets the OpenMP threads. */

/* A subcommand's command line: its options, its --help text, a handler for its own options, and
 * the methods whose parameters it takes. */
typedef struct iird_command {
    const char *name;             /* "render", for messages */
    const struct option *options; /* the command's own, ending with a zero entry */
    void (*usage)(FILE *f);
    /* Applies one of the command's own options to ctx (parameter options never reach it). */
    iir_status (*option)(void *ctx, int c, const char *arg, iir_error *err);
    /* Comma-separated methods whose parameters the command takes, read after parsing; NULL (or
     * a NULL function) = any method's. A parameter that none of them declares is refused, and
     * --help lists only theirs. */
    const char *(*methods)(const void *ctx);
} iird_command;

/* Parses argv: parameter options into *params, the command's own through cmd->option, then at
 * most one positional SCENE into *scene. --help prints cmd->usage and the parameters of the
 * command's methods (so `--method iir --help` lists iir's). Returns -1 to go on, else the exit
 * code (0 after --help, 2 for a bad value, 64 for a usage error) with the reason printed. */
int iird_parse_command(const iird_command *cmd, int argc, char **argv, void *ctx,
                       iir_params *params, const char **scene);

/* The method names joined by " | " in registry order, for usage texts (a static buffer). */
const char *iird_method_choices(void);

/* Prints the parameters of `methods` (comma-separated; NULL = every method), a section per
 * table, as --help shows them. */
void iird_print_params(FILE *f, const char *methods);

/* Prints every table as the Markdown of docs/cli.md's parameter section (`iird params
 * --markdown`; a test compares the two). */
void iird_print_params_markdown(FILE *f);

/* Every parameter method `method` reads, with the value it uses (p's, else the default), as
 * "spp 1, bounces 2, seed 1, refine-passes 64, jitter true": the settings summaries print it. */
void iird_settings_text(const char *method, const iir_params *p, char *buf, size_t n);

/* Refuses (IIR_ERR_INVALID naming the option) a value of p that no method of `methods` declares. */
iir_status iird_check_params_for(const char *methods, const iir_params *p, iir_error *err);

/* Refuses (IIR_ERR_INVALID) a method whose parameters would make it allocate more than 90% of the
 * machine's physical memory for a width x height frame (iir_method_memory), before anything is
 * allocated: "--vpls 16384 --sm-res 2048" names the estimate instead of swapping for minutes. */
iir_status iird_check_memory(const char *method, const iir_params *p, int width, int height,
                             iir_error *err);

/* The parameter an option names, spelled either way ("sm-res" or "sm_res"); NULL for none. */
const iir_param *iird_param_by_option(const char *name);

/* Parses a parameter value as on the command line (NAME without "--", '-' or '_') into p;
 * IIR_ERR_INVALID naming --NAME. For --sweep values. */
iir_status iird_parse_param(const char *name, const char *text, iir_params *p, iir_error *err);

/* Parses "WxH" with 1 <= W, H <= max_dim. */
iir_status iird_parse_size(const char *text, int max_dim, int *w, int *h, iir_error *err);
/* Parses an integer in [lo, hi]; `what` names the option in the error. */
/* Parses --segment "I/N" (0 <= I < N <= 100000): the I-th (from 0) of N contiguous shares of some
 * work (render's frames, bench's references). IIR_ERR_INVALID naming --segment otherwise. */
iir_status iird_parse_segment(const char *text, int *index, int *count, iir_error *err);
/* Share `index` of `count` over total items: [index total / count, (index + 1) total / count),
 * the one rule every --segment follows (render's frames, bench's references). */
void iird_segment_range(int index, int count, int total, int *first, int *end);
iir_status iird_parse_int(const char *text, const char *what, long lo, long hi, long *out,
                          iir_error *err);
iir_status iird_parse_u64(const char *text, const char *what, uint64_t *out, iir_error *err);
iir_status iird_parse_float(const char *text, const char *what, float lo, float hi, float *out,
                            iir_error *err);

/* Checks before any work that an image can be written to path: a .png/.exr/.pfm extension
 * (IIR_ERR_INVALID), and its folder, made if missing, takes a new file (iird_prepare_parent). */
iir_status iird_check_output(const char *path, iir_error *err);

/* The scenes directory: --scenes if given, else $IIR_SCENES, else ./scenes, else the source tree's.
 */
const char *iird_scenes_dir(const char *option);

/* --cache-max SIZE (serve, render, bench): the radiosity form-factor cache's cap, parsed as
 * --max-session-memory is (bytes, or with K, M, G, T; at least 1M) and handed to the cache through
 * the environment ($IIR_CACHE_MAX, iir/ffcache.h) -- before any thread starts. */
#define IIRD_CACHE_MAX_HELP                                                                        \
    "  --cache-max SIZE     the radiosity form-factor cache's cap: least recently used\n"          \
    "                       files go past it (default 512M, or $IIR_CACHE_MAX)\n"
iir_status iird_set_cache_max(const char *arg, iir_error *err);

/* Finds and loads the animation script that --anim ARG names for scene (both iird render and
 * iird bench use it; docs/scene-format.md section 5): an existing file, or any ARG with a '/' or
 * ending in ".json", is loaded as a file; otherwise ARG must be a bare name listed in the scene
 * sidecar's "paths" object, whose value is a script file relative to the sidecar's folder (no
 * "..", not absolute) or an inline script object. The built-in Cornell box uses the paths of the
 * shipped box's sidecar, scenes_dir/cornell_box/cornell_box.scene.json. Writes what was loaded
 * (a file path, or "SIDECAR: paths.NAME") into label (size n). On error *out stays NULL: an
 * unknown name is IIR_ERR_INVALID listing the names the scene has; a missing file IIR_ERR_IO. */
iir_status iird_resolve_anim(const iir_scene *scene, const char *scenes_dir, const char *arg,
                             iir_anim **out, char *label, size_t n, iir_error *err);

/* What an --anim script file says of where and how it was made (recordings from the browser say
 * all of it, docs/animation-format.md section 6), under what the command line gives. */
typedef struct iird_anim_origin {
    const char *scene;      /* SCENE; else the script's "scene"; else NULL (the built-in box) */
    const char *scenes_dir; /* --scenes; else the script's "scenes" when that is a folder here;
                               else iird_scenes_dir(NULL) */
    int width, height;      /* the script's "size"; 0 when it gives none (--size is the caller's) */
    char scene_buf[129], scenes_buf[4096]; /* what scene and scenes_dir may point into */
} iird_anim_origin;

/* Fills *o for `iird CMD [SCENE] [--scenes DIR] --anim ARG` (scene_arg, scenes_arg, anim_arg NULL
 * when not given; ARG a path of a scene's sidecar names no origin). A script folder that is not a
 * folder here is passed over with a warning on stderr (not for the built-in box, which needs
 * none); a script that cannot be read is reported later, by iird_resolve_anim. */
void iird_anim_origin_read(const char *cmd, const char *scene_arg, const char *scenes_arg,
                           const char *anim_arg, iird_anim_origin *o);

/* A warning on stderr ("iird CMD: warning: ...") when the script names a scene other than the one
 * opened (from scene_arg, NULL: builtin); nothing when it names none. */
void iird_warn_anim_scene(const char *cmd, const iir_anim *anim, const char *scene_arg,
                          const iir_scene *scene);

/* ---- what a command tells about the scene it renders (scene_notes.c), on stderr ---- */

/* "iird CMD: camera: ..." when the scene has no camera of its own (the one it was framed with). */
void iird_note_camera(const char *cmd, const iir_scene *scene);

/* "iird CMD: warning: light 'sun': ..." for every light and material that a method of `methods`
 * (comma-separated) does not render (iir_method_dropped), also at the parameters params
 * (iir_method_dropped_by_params: pt's glass at too few bounces); what no method renders once. The
 * scene's notes (iir_dropped.note: an emitter became an area light) say "note:" instead. */
void iird_warn_dropped(const char *cmd, const char *methods, const iir_params *params,
                       const iir_scene *scene, const iir_light *lights, uint32_t num_lights);

/* The scene's own notes and warnings (iir_scene.dropped: what no method renders, and what was made
 * of its emissive materials), "iird WHO: warning: ..." or "iird WHO: note: ...", grouped as
 * iird_warn_dropped does; `serve` logs them when it loads a scene (WHO "serve: scene NAME"). */
void iird_log_scene_notes(const char *who, const iir_scene *scene);

/* Whether every pixel of img is black (no channel above 0). */
bool iird_image_black(const iir_image *img);

/* "iird CMD: warning: WHAT entirely black: REASON" (iir_scene_explain_dark for the view); WHAT
 * ends in its verb: "the image is", "2 of 5 frames (first: frame 3) are". */
void iird_warn_black(const char *cmd, const char *what, const iir_scene *scene, const iir_rt *rt,
                     const iir_view *view);

/* Reports an error to stderr as "iird <cmd>: <message>" and returns its exit code. */
int iird_report(const char *cmd, const iir_error *err);

/* A progress bar on stderr, drawn only when stderr is a terminal. Its ETA is the measured time
 * per unit from the first update with work done (so set-up and a cold first frame do not count)
 * times the units left, plus what iird_progress_set_after says comes after it. */
typedef struct iird_progress {
    bool enabled;
    const char *label;
    double total, start_ms, last_draw_ms;
    double mark_ms, mark_done; /* the first update with work done; -1 before it */
    double after_s;            /* seconds expected after this bar; < 0: nothing shown */
    const char *after_label;   /* what the whole is called ("bench") */
} iird_progress;

void iird_progress_start(iird_progress *p, const char *label, double total);
void iird_progress_update(iird_progress *p, double done);
void iird_progress_finish(iird_progress *p);
/* Shows ", LABEL MM:SS" after the bar's ETA: its ETA plus `seconds` of later work. */
void iird_progress_set_after(iird_progress *p, const char *label, double seconds);
/* Seconds per unit measured so far with `done` units at now_ms (iir_now_ms); < 0 before any. */
double iird_progress_rate(const iird_progress *p, double done, double now_ms);

/* Ctrl-C / SIGTERM: installs a handler that sets a flag long-running commands poll. */
void iird_catch_interrupts(void);
bool iird_interrupted(void);

/* ---- output folders, made and checked before any work ---- */

/* Makes folder dir with its missing parents (mkdir -p), then checks that a file can be created in
 * it by creating and removing a probe file. `option` names the option that gave it ("--out") for
 * messages. Returns IIR_ERR_IO with a message naming the option, the folder and the system's
 * reason when it cannot; folders made before the failure are left. */
iir_status iird_prepare_dir(const char *dir, const char *option, iir_error *err);

/* iird_prepare_dir on the folder of file path ("." when it has no '/'); messages name the file. */
iir_status iird_prepare_parent(const char *path, const char *option, iir_error *err);

#endif

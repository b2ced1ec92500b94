/* cli.h -- what the iird subcommands share: argument parsing helpers, finding and loading a
 * scene, and the progress bar. Not any subcommand's logic. */
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

/* ---- method parameters, shared by every command that renders ---- */

enum iird_method_opt {
    IIRD_OPT_SPP = 1000,
    IIRD_OPT_BOUNCES,
    IIRD_OPT_SEED,
    IIRD_OPT_VPLS,
    IIRD_OPT_KMIN,
    IIRD_OPT_KMAX,
    IIRD_OPT_WEIGHTS,
    IIRD_OPT_REGEN,
    IIRD_OPT_VISIBILITY,
    IIRD_OPT_SM_RES,
    IIRD_OPT_SM_BIAS,
    IIRD_OPT_INTERLEAVE,
    IIRD_OPT_CLAMP,
    IIRD_OPT_IR_SAME,
    IIRD_OPT_THREADS,
    IIRD_OPT_REFINE_PASSES,
};

/* getopt_long entries for the method parameters; put inside a command's option table. */
#define IIRD_METHOD_LONGOPTS                                                                       \
    {"spp", required_argument, 0, IIRD_OPT_SPP},                                                   \
        {"bounces", required_argument, 0, IIRD_OPT_BOUNCES},                                       \
        {"seed", required_argument, 0, IIRD_OPT_SEED},                                             \
        {"vpls", required_argument, 0, IIRD_OPT_VPLS},                                             \
        {"kmin", required_argument, 0, IIRD_OPT_KMIN},                                             \
        {"kmax", required_argument, 0, IIRD_OPT_KMAX},                                             \
        {"weights", required_argument, 0, IIRD_OPT_WEIGHTS},                                       \
        {"regen-threshold", required_argument, 0, IIRD_OPT_REGEN},                                 \
        {"visibility", required_argument, 0, IIRD_OPT_VISIBILITY},                                 \
        {"sm-res", required_argument, 0, IIRD_OPT_SM_RES},                                         \
        {"sm-bias", required_argument, 0, IIRD_OPT_SM_BIAS},                                       \
        {"interleave", required_argument, 0, IIRD_OPT_INTERLEAVE},                                 \
        {"clamp", required_argument, 0, IIRD_OPT_CLAMP},                                           \
        {"ir-same-random", no_argument, 0, IIRD_OPT_IR_SAME},                                      \
        {"refine-passes", required_argument, 0, IIRD_OPT_REFINE_PASSES},                           \
    {                                                                                              \
        "threads", required_argument, 0, IIRD_OPT_THREADS                                          \
    }

/* The --help text for those options. */
extern const char IIRD_METHOD_HELP[];

/* True when c is one of IIRD_METHOD_LONGOPTS; then *st says whether arg was valid. */
bool iird_method_option(int c, const char *arg, iir_params *p, iir_status *st, iir_error *err);

/* A subcommand's command line: its options, its --help text, and a handler for its own options. */
typedef struct iird_command {
    const char *name; /* "render", for messages */
    const struct option *options;
    void (*usage)(FILE *f);
    /* Applies one of the command's own options to ctx (method options never reach it). */
    iir_status (*option)(void *ctx, int c, const char *arg, iir_error *err);
} iird_command;

/* Parses argv: method options into *params, the command's own through cmd->option, then at most
 * one positional SCENE into *scene. Returns -1 to go on, else the exit code (0 after --help, 2 for
 * a bad value, 64 for a usage error) with the reason printed. */
int iird_parse_command(const iird_command *cmd, int argc, char **argv, void *ctx,
                       iir_params *params, const char **scene);

/* Parses "WxH" with 1 <= W, H <= max_dim. */
iir_status iird_parse_size(const char *text, int max_dim, int *w, int *h, iir_error *err);
/* Parses an integer in [lo, hi]; `what` names the option in the error. */
iir_status iird_parse_int(const char *text, const char *what, long lo, long hi, long *out,
                          iir_error *err);
iir_status iird_parse_u64(const char *text, const char *what, uint64_t *out, iir_error *err);
iir_status iird_parse_float(const char *text, const char *what, float lo, float hi, float *out,
                            iir_error *err);

/* Checks before any work that an image can be written to path: a .png/.exr/.pfm extension and an
 * existing directory. */
iir_status iird_check_output(const char *path, iir_error *err);

/* The scenes directory: --scenes if given, else $IIR_SCENES, else ./scenes, else the source tree's.
 */
const char *iird_scenes_dir(const char *option);

/* Loads SCENE (NULL or "builtin" = the built-in Cornell box; else a name, folder or file) and
 * builds its ray tracer. On error both outputs stay NULL. */
iir_status iird_load_scene(const char *arg, const char *scenes_dir, iir_scene **scene, iir_rt **rt,
                           iir_error *err);

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

/* Reports an error to stderr as "iird <cmd>: <message>" and returns its exit code. */
int iird_report(const char *cmd, const iir_error *err);

/* A progress bar on stderr, drawn only when stderr is a terminal. */
typedef struct iird_progress {
    bool enabled;
    const char *label;
    double total, start_ms, last_draw_ms;
} iird_progress;

void iird_progress_start(iird_progress *p, const char *label, double total);
void iird_progress_update(iird_progress *p, double done);
void iird_progress_finish(iird_progress *p);

/* Ctrl-C / SIGTERM: installs a handler that sets a flag long-running commands poll. */
void iird_catch_interrupts(void);
bool iird_interrupted(void);

#endif

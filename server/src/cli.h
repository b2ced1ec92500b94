/* cli.h -- what the iird subcommands share: argument parsing helpers, finding and loading a
 * scene, and the progress bar. Not any subcommand's logic. */
#ifndef IIRD_CLI_H
#define IIRD_CLI_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/rt.h"
#include "iir/scene.h"
#include "iir/status.h"

/* Exit codes (docs/cli.md): 0 ok, 1 internal, 2 bad input, 3 io, 4 unsupported, 64 usage,
 * 130 interrupted. */
enum { IIRD_EXIT_USAGE = 64 };

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

double iird_now_ms(void);

#endif

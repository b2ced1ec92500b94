/* controller.h -- the frame-time controller: picks the VPL count N, the interleave n and the
 * shadow-map resolution of a VPL method's next frame so that its frames take a target time. It
 * decides from measurements only; it does not render, and which method applies its choice (and
 * how) is the method's business (iir.c, parameter target_fps).
 *
 * Its samples are interactive frames only: frames rendered because a light or the camera moved.
 * Refinement passes, idle time and frames that only re-render the same view (a parameter change,
 * a method's first frame, which builds a whole set and the G-buffer) are not frame rates of a
 * drag; the method leaves them out (iir.c). Before its first sample it has no figure (mean_ms 0).
 *
 * The settings form a ladder of (N, n) rungs ordered by cost and quality, above a floor the user
 * sets (N_min = vpls_min, maps of at least sm_res_min: below those the Cornell box is blotchy,
 * docs/experiments.md):
 *  - the main rungs: N from N_min to N_max in steps of 2^(1/8) (about 9%), interleave n -- N_max is
 *    where the scene's error stops falling (the bench's N sweep), so no time goes to VPLs that no
 *    longer help;
 *  - the top: N_max with the interleave n - 1, n - 2 (down to 1): more VPLs per pixel, less filter.
 * No rung has a wider interleave than n: fewer VPLs per pixel than N_min at n is below the floor.
 * Beside the rung, the resolution of the maps built from now on: the configured one, or a half or
 * a quarter of it (not below the floor) when new maps would take more than 30% of the target (a
 * fast light kills many VPLs; their replacements' maps are what a frame cannot afford), back one
 * step when the finer maps would take less than 15%. Maps already built keep their resolution.
 *
 * The model. A frame's time is split by its phases into parts proportional to what they do:
 *     t = rest + a * P * N / n^2 + b * maps * res^2 + c * n^2 + d * N
 * P the pixels shaded (evaluations * n^2 / VPLs in the set), a the time of one pixel-VPL
 * evaluation, b of one shadow-map texel, maps the maps built per frame to replace VPLs (not those
 * that grow the set towards a raised N: paid once), c the filter's per-tap
 * time, d the incremental step's time per VPL; every unit is a running mean (weight 1/5) of the
 * frames measured, so the model follows the machine, the scene and the motion. A rung is predicted
 * from the model at its setting, whatever the set holds at the moment (a growing set's frames still
 * price N correctly).
 *
 * The rule. The current rung stays while its prediction is within 108% of the target and the next
 * rung's is not within 97% (a dead band), or while the set holds less than 90% of its N (it grows
 * by insertions over frames); otherwise the wanted rung is the highest predicted within 97%. When
 * none is (the target is out of reach), the highest predicted within 105% of the cheapest: no
 * quality is given for a few per cent of a frame that misses the target anyway. A
 * cheaper setting is taken after 2 frames that want one, a dearer one after `patience` frames (4,
 * doubling up to 128 whenever a move undoes the move before it within 30 frames, halving again
 * after 100 quiet frames); a dearer move climbs at most 8 rungs (one doubling of N); after any move
 * the setting is held for 4 frames while the model takes in its frames. So a setting never
 * alternates frame to frame, and a noisy frame does not move it.
 *
 * The evidence. A cut the model says saves 15% or more of a frame is checked against the clock,
 * as an A/B/A test: the median of 6 frames at the new setting (the first after a move left out:
 * the set is still shrinking or growing) against the median of the last 3 at the old one (those
 * that wanted the cut). When it saved less than 40% of what the model promised, the old setting
 * runs again for 6 frames, under the same conditions as the cut's: when those are slower by 40% of
 * the promise the cut is taken again (the conditions had changed); else frame time does not
 * depend on the setting -- the machine is busy with other work (other sessions, other programs)
 * or the time goes where the knobs do not reach -- and the controller keeps the old setting and
 * takes no cut for 60 frames, doubling (up to 480) each time the next cut buys nothing again,
 * back to 60 once one does. Meanwhile it reports `busy` (while its frames miss the target). A cut
 * needs 3 frames at the current setting to be judged by; one cut is judged at a time.
 *
 * Single-threaded: one controller per method instance, called by its render thread. */
#ifndef IIR_CONTROLLER_H
#define IIR_CONTROLLER_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/status.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { IIR_CTL_MAX_RUNGS = 128 };

/* One frame's setting. */
typedef struct iir_ctl_setting {
    int vpls;       /* N */
    int interleave; /* n */
    int sm_res;     /* shadow-map resolution of the maps built from now on */
} iir_ctl_setting;

typedef struct iir_ctl_config {
    double target_ms; /* > 0 and finite */
    int vpls_max;     /* N_max, [1, 16384] */
    int vpls_min;     /* the floor: N_min = min(vpls_min, N_max), [1, 16384] */
    int interleave;   /* the main rungs' n, [1, 8] */
    int sm_res;       /* the main rungs' map resolution, [8, 2048] */
    int sm_res_min;   /* the maps' floor: never coarser than min(sm_res_min, sm_res), [8, 2048] */
} iir_ctl_config;

/* What one interactive frame cost and did (a method's frame stats, iir_frame_stats). Interrupted
 * frames, refinement passes and frames of an unchanged view are not measurements. */
typedef struct iir_ctl_sample {
    iir_ctl_setting setting; /* the setting the frame was rendered with */
    double total_ms, step_ms, shadowmap_ms, indirect_ms, filter_ms;
    double vpls;      /* VPLs in the frame's set (null samples included) */
    double vpl_evals; /* pixel-VPL evaluations */
    double maps;      /* shadow maps built */
    double inserted;  /* VPLs inserted: replacements, or growth towards a raised N */
    bool regenerated; /* the set was made anew (its maps are not a rate per frame) */
} iir_ctl_sample;

/* What the controller is doing, for stats, logs and the browser. */
typedef struct iir_ctl_report {
    iir_ctl_setting setting; /* the next frame's */
    int rung, rungs;         /* its place on the ladder, [0, rungs) */
    double target_ms;
    double predicted_ms;   /* the model's time of the setting; 0 before the first measurement */
    double mean_ms;        /* running mean (weight 1/5) of the measured frame times; 0 before the
                              first (no figure rather than a wrong one) */
    uint64_t frames;       /* interactive frames measured */
    bool reachable;        /* false when even the floor is predicted above the target */
    bool busy;             /* a cut bought no time (the machine is too busy to tell): held */
    iir_ctl_setting floor; /* the cheapest setting it may take: N_min, n, the maps' floor */
    uint32_t moves;        /* setting changes so far */
    uint32_t undone;       /* cuts undone because they bought no time */
} iir_ctl_report;

typedef struct iir_ctl iir_ctl;

/* A controller starting at the main rung whose N is nearest `start_vpls`. IIR_ERR_INVALID for a
 * configuration outside the ranges above; IIR_ERR_NOMEM. */
iir_status iir_ctl_create(const iir_ctl_config *cfg, int start_vpls, iir_ctl **out, iir_error *err);
void iir_ctl_destroy(iir_ctl *c);

/* A new target or ladder (a live parameter change): the model's units are kept; the setting moves
 * to the new ladder's rung nearest the current N; a cut under check and a busy hold are forgotten
 * (the frames before are no evidence for the new ladder). The same configuration changes nothing.
 * On error the controller is unchanged. */
iir_status iir_ctl_configure(iir_ctl *c, const iir_ctl_config *cfg, iir_error *err);

/* Takes one interactive frame's measurement into the model, checks the last cut against it and
 * decides the next frame's setting; returns true when it differs from the current one. Samples
 * with a non-finite or non-positive total are ignored. */
bool iir_ctl_update(iir_ctl *c, const iir_ctl_sample *s);

iir_ctl_setting iir_ctl_current(const iir_ctl *c);
void iir_ctl_get_report(const iir_ctl *c, iir_ctl_report *out);
/* The ladder's rung i (0 <= i < rungs), for tests and docs. */
iir_ctl_setting iir_ctl_rung(const iir_ctl *c, int i);
/* The model's time for setting s; 0 before the first measurement. */
double iir_ctl_predict(const iir_ctl *c, const iir_ctl_setting *s);

#ifdef __cplusplus
}
#endif
#endif

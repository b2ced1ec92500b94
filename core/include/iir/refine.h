/* refine.h -- progressive refinement of a VPL method's frame (DESIGN section 6): while the view
 * stays still, passes over the whole image are averaged into an ever better frame, up to a
 * converged flag. Used by ir and iir; not how a method chooses its VPLs (it supplies one set per
 * sweep through a callback) and not the shading of one pass (iir_renderer_pass, render.h).
 *
 * PASSES. Pass i (i = 0, 1, ...) of the last rendered view, n = interleave:
 *   - camera rays through (x, y) + j_i, j_i = ((phi_2(i) + 1/2) mod 1, (phi_3(i) + 1/2) mod 1) (a
 *     Halton sequence rotated so that pass 0 is the pixel centre), or the centre for every pass
 *     without jitter: averaging the passes is a box filter over the pixel (antialiasing);
 *   - direct light as in a frame (area-light samples from the stream hash(seed, i));
 *   - indirect light from sweep s = i / n^2 's VPL set, pixel (x, y) evaluating its subset
 *     ((y mod n) n + (x mod n) + i) mod n^2 with exact visibility and no filter (render.h), so
 *     after a sweep every pixel has seen every VPL of the set exactly once.
 *   Sweep 0 uses the frame's own VPL set; sweep s >= 1 a fresh, independent set of the same size,
 *   which the method makes without disturbing its live set. Every pass has the same weight, so a
 *   frame of k whole sweeps is the all-VPL estimate averaged over k independent VPL sets.
 * CONVERGENCE. After max_passes passes the refinement is converged: further passes do no work and
 *   only copy the average out again.
 * DETERMINISM. A pass depends on the view, the VPL set, the parameters and i only; the average is
 *   summed per pixel in double precision in pass order, so it does not depend on the thread count.
 * MEMORY. The sum (double RGB) and one pass image are allocated at the first pass of a frame size
 *   and kept; the light list is copied at begin and grows only with the light count. No pass
 *   allocates otherwise (the renderer's own scratch follows render.h).
 * THREADS. One thread at a time per iir_refine; a pass is OpenMP-parallel inside. */
#ifndef IIR_REFINE_H
#define IIR_REFINE_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/camera.h"
#include "iir/image.h"
#include "iir/light.h"
#include "iir/render.h"
#include "iir/rt.h"
#include "iir/status.h"
#include "iir/vpl.h"

#ifdef __cplusplus
extern "C" {
#endif

#define IIR_REFINE_MAX_PASSES 4096

typedef struct iir_refine_params {
    int interleave;   /* n: a sweep is n^2 passes, [1, 8] */
    int max_passes;   /* converged after this many passes, [1, IIR_REFINE_MAX_PASSES] */
    bool jitter;      /* jittered camera rays (antialiasing) or pixel centres */
    float clamp;      /* geometry-term bound, as iir_indirect_params.clamp */
    bool clamp_comp;  /* compensate the clamp in every pass (render.h's iir_pass_params) */
    int bounces;      /* as iir_indirect_params.bounces */
    int area_samples; /* as iir_indirect_params.area_samples; 0 = its default */
    uint64_t seed;    /* area-light samples of the passes */
} iir_refine_params;

/* Supplies the VPL set of `sweep` (0: the rendered frame's set; >= 1: a fresh independent set of
 * the same size). *vpls must stay valid until the next call or the next iir_refine_begin. Rays
 * spent are added to *st. On error the pass fails with that status. */
typedef iir_status (*iir_refine_vpls_fn)(void *ctx, uint32_t sweep, const iir_vpl **vpls,
                                         uint32_t *num_vpls, iir_raystats *st, iir_error *err);

typedef struct iir_refine_stats {
    uint32_t passes;          /* passes in the frame after this call */
    bool converged;           /* passes == max_passes */
    bool worked;              /* a pass was rendered (false once converged) */
    uint32_t sweep;           /* the sweep of this pass */
    bool whole_sweeps;        /* passes is a multiple of interleave^2: every subset as often */
    uint32_t num_vpls;        /* size of that sweep's set, null samples included */
    double vpls_ms;           /* in the callback (making a fresh set) */
    double total_ms;          /* the whole call */
    iir_render_timing timing; /* the pass's phases */
    iir_raystats rays;        /* of this call, the callback's included */
} iir_refine_stats;

typedef struct iir_refine iir_refine;

/* An idle refinement (nothing to refine until iir_refine_begin); NULL when out of memory. */
iir_refine *iir_refine_create(void);
void iir_refine_destroy(iir_refine *rf);

/* Starts over for a new frame of width x height: copies the camera and the lights (they need not
 * outlive the call) and forgets every pass. *p must be valid (iir_refine_params_validate).
 * IIR_ERR_NOMEM (the refinement is then idle) when the light list cannot grow. */
iir_status iir_refine_begin(iir_refine *rf, const iir_camera *cam, const iir_light *lights,
                            uint32_t num_lights, int width, int height, const iir_refine_params *p,
                            iir_error *err);

/* Makes it idle (after a frame that failed): the next pass fails with IIR_ERR_INVALID. */
void iir_refine_end(iir_refine *rf);

/* IIR_ERR_INVALID naming the field and its range. */
iir_status iir_refine_params_validate(const iir_refine_params *p, iir_error *err);

/* The lights of the frame being refined (for the callback); NULL with *n = 0 when idle. */
const iir_light *iir_refine_lights(const iir_refine *rf, uint32_t *n);

/* Renders the next pass with renderer r (whose cached G-buffer it may replace, see render.h) and
 * writes the average of all passes so far to out. Once converged it only writes the average
 * (worked = false). *st (may be NULL) is overwritten.
 * Errors: IIR_ERR_INVALID when idle or when out is not the frame's size; the callback's or the
 * renderer's error; IIR_ERR_NOMEM for the buffers. After an error the passes done still stand and
 * out is unspecified. */
iir_status iir_refine_pass(iir_refine *rf, iir_renderer *r, iir_refine_vpls_fn vpls, void *ctx,
                           iir_image *out, iir_refine_stats *st, iir_error *err);

/* The jitter of pass i (see PASSES), in [0, 1)^2. */
iir_vec2 iir_refine_jitter(uint32_t i);

#ifdef __cplusplus
}
#endif
#endif

/* method.h -- the one interface every rendering method implements (DESIGN section 7): create from a
 * scene and parameters, render a frame for a light/camera state into a float image with stats,
 * optionally refine that frame progressively, destroy. Methods share the scene and the ray tracer;
 * each lives in its own file under core/src/methods/. */
#ifndef IIR_METHOD_H
#define IIR_METHOD_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/camera.h"
#include "iir/controller.h"
#include "iir/image.h"
#include "iir/incremental.h"
#include "iir/light.h"
#include "iir/params.h"
#include "iir/render.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "iir/status.h"

#ifdef __cplusplus
extern "C" {
#endif

struct iir_scene;

/* What a frame is rendered from: the scene is fixed, lights and camera move. */
typedef struct iir_view {
    const iir_light *lights; /* punctual lights; emissive triangles come from the scene */
    uint32_t num_lights;
    iir_camera camera;
} iir_view;

/* The phases a frame's time is split into. A method declares the ones it reports, in its
 * pipeline's order (iir_method_phases); the others stay 0 in its stats. */
typedef enum iir_phase {
    IIR_PHASE_TRACE,      /* ray trees or paths per pixel (pt, whitted, hybrid) */
    IIR_PHASE_VPLS,       /* choosing VPLs: the incremental step (iir) or light paths (ir, ism) */
    IIR_PHASE_SHADOWMAPS, /* rendering shadow maps (or ISMs) of new VPLs */
    IIR_PHASE_MAPS,       /* the lights' reflective shadow maps (rsm, hier: and hier's light
                             points) */
    IIR_PHASE_SOLVE,      /* the radiosity solution (radiosity, hybrid): direct light on the patches
                             and the solve, or a refinement's shots */
    IIR_PHASE_GATHER,     /* hybrid: the solution gathered to the display vertices */
    IIR_PHASE_GBUFFER,    /* camera rays (0 when the G-buffer was reused) */
    IIR_PHASE_DIRECT,     /* direct light: shadow rays per light per pixel (hier: on its tree) */
    IIR_PHASE_INDIRECT,   /* bounce light: from the VPLs (ir, iir, ism), the maps' gather (rsm) or
                             the multires hierarchy (hier) */
    IIR_PHASE_FILTER,     /* geometry-aware filter of interleaved sampling */
    IIR_PHASE_DISPLAY,    /* radiosity: the solution's Gouraud lookup through the G-buffer */
    IIR_PHASE_COUNT
} iir_phase;

/* A number a method reports per frame beyond the common stats, declared once in its operations
 * (as its parameters are, in its tables): the protocol's stats message (`counters`), the bench CSV
 * and summary, the render summary line and log, the browser's stats panel and /metrics list
 * whatever the method declares. */
typedef enum iir_counter_kind {
    IIR_COUNTER_EVENTS, /* a count of things that happened this frame: summed (/metrics: a total) */
    IIR_COUNTER_SHARE   /* a fraction of this frame, [0, 1]: averaged, not summed */
} iir_counter_kind;

typedef struct iir_counter {
    const char *name; /* a key: lower case and underscores */
    iir_counter_kind kind;
    const char *help; /* one line: what it counts */
} iir_counter;

enum { IIR_MAX_COUNTERS = 4 }; /* a method declares at most this many */

typedef struct iir_frame_stats {
    double total_ms;
    double phase_ms[IIR_PHASE_COUNT];
    iir_raystats rays;
    uint64_t samples_per_pixel; /* pt: samples accumulated in the image so far; ir, iir: refinement
                                   passes in the image (0 for an interactive frame) */
    bool converged;             /* refinement reached the refine_passes parameter (see refine) */
    bool whole_sweeps;          /* refinement: the passes so far give every interleaved VPL
                                   subset equal weight, so the image shows no subset pattern
                                   (always true for pt and for frames) */
    iir_vpl_counts vpl;  /* VPL bookkeeping (vpl.h), zero for methods without VPLs; refinement:
                            count = the size of the pass's VPL set */
    uint64_t vpl_evals;  /* VPL evaluations: pixel-VPL pairs shaded (multires: texel-VPL pairs
                            too; iir_render_timing), 0 for methods without VPLs */
    uint64_t vpl_reused; /* of those, pairs a kept VPL's column held (iir_render_timing) */
    double counter[IIR_MAX_COUNTERS]; /* the method's own counters (iir_method_counters), in
                                         the order it declares them */
    bool controlled;    /* target_fps set: ctl is the frame-time controller's state after the
                           frame (its setting is the next frame's; controller.h) */
    iir_ctl_report ctl; /* zero when not controlled */
} iir_frame_stats;

const char *iir_phase_name(iir_phase phase);

/* The phases method `name` reports, in its pipeline's order: *out gets them, the return value is
 * how many (0 and *out NULL for an unknown name). */
int iir_method_phases(const char *name, const iir_phase **out);
/* The counters method `name` declares (frame stats' counter[i] is (*out)[i]): how many, 0 for
 * none or an unknown name. */
int iir_method_counters(const char *name, const iir_counter **out);
/* Index of counter `counter` among method `name`'s, or -1. */
int iir_method_counter_index(const char *name, const char *counter);

typedef struct iir_method iir_method;

/* Names of the available methods, NULL-terminated. */
const char *const *iir_method_names(void);
/* One line saying what method `name` is; "" for an unknown name. */
const char *iir_method_summary(const char *name);

/* ---- the methods' parameters (params.h) ---- */

/* The parameter tables of method `name`, NULL-terminated (shared tables such as the VPL shading's
 * appear in every method that uses them); NULL for an unknown name. */
const iir_param_table *const *iir_method_tables(const char *name);
/* Every distinct table of every method, NULL-terminated, in registry order. */
const iir_param_table *const *iir_method_all_tables(void);
/* The row `name` of method `method`'s tables, or NULL when it declares none. */
const iir_param *iir_method_find_param(const char *method, const char *name);
/* The first row `name` of any method's tables, or NULL. Rows of one name agree in type and
 * choices across methods (test_params checks it), so a CLI option or a protocol field means one
 * thing; their ranges and defaults may differ per method. */
const iir_param *iir_method_any_param(const char *name);

/* Sets p[name] after finding its row among all methods' (IIR_ERR_INVALID for a name no method
 * declares or a value no row of that name allows). */
iir_status iir_method_param_set(iir_params *p, const char *name, double value, iir_error *err);
/* Checks every value of p against every row of its name in every method (live: each row's
 * live_hi instead of hi). IIR_ERR_INVALID naming the first bad value (*bad: its row, may be NULL).
 */
iir_status iir_method_params_check(const iir_params *p, bool live, const iir_param **bad,
                                   iir_error *err);
/* Binds p for method `name` as create would -- every range and every table's check -- without
 * creating anything. `given` as in iir_params_bind. IIR_ERR_INVALID (with *bad) otherwise. */
iir_status iir_method_params_validate(const char *name, const iir_params *p,
                                      const iir_params *given, const iir_param **bad,
                                      iir_error *err);
/* The value method `name` uses for parameter row `name`: p's when set, else the row's default. */
double iir_method_param_value(const iir_param *row, const iir_params *p);

/* The samples_per_pixel at which method `name`'s refinement with p converges (iir_method_refine):
 * pt: refine_passes samples rounded up to whole frames of spp; ir, iir: refine_passes passes. A
 * still is a converged frame (iird render). 0 for an unknown name, bad parameters, or a method
 * that cannot refine. */
uint64_t iir_method_converged_at(const char *name, const iir_params *p);

/* The bounce count of the pt reference that method `name` is measured against (iird bench): its
 * `bounces` parameter when it has one; a multi-bounce method's own count (radiosity, whitted: 8);
 * else 2 (one bounce: iir, rsm, ism, hier). 2 for an unknown name. */
int iir_method_reference_bounces(const char *name, const iir_params *p);

/* Bytes method `name` would hold with p for a width x height frame (frame buffers, VPLs and their
 * shadow maps, G-buffer, refinement buffers): an estimate from the parameters alone, so a caller
 * can refuse a request before anything is allocated. 0 for an unknown name. */
uint64_t iir_method_memory(const char *name, const iir_params *p, int width, int height);

/* The same for this scene, from its real counts where the method's size depends on the scene
 * (radiosity and hybrid: the exact patch count and the form factors' non-zeros from a few sampled
 * hemicube rows; milliseconds of work, never the build itself): what a caller checks against a
 * budget before iir_method_create. Equal to iir_method_memory for the other methods. */
uint64_t iir_method_memory_on(const char *name, const struct iir_scene *scene, const iir_rt *rt,
                              const iir_params *p, int width, int height);
/* What a created method holds by its real counts, in the terms of iir_method_memory_on (for
 * methods whose size does not depend on the scene: their estimate). */
uint64_t iir_method_memory_held(const iir_method *m, int width, int height);

/* Whether method `name` can render these lights (iir: its domain is a spot's disk, so it needs a
 * spot light): IIR_OK, or IIR_ERR_UNSUPPORTED saying what is missing, so that a caller can refuse a
 * request before accepting it rather than fail every frame after. IIR_ERR_INVALID for an unknown
 * name. */
iir_status iir_method_supports(const char *name, const iir_light *lights, uint32_t num_lights,
                               iir_error *err);

/* What method `name` does not render of the scene and these lights: first the scene's own notes
 * (lights and materials of the file that no method renders: iir_scene.dropped, method ""), then
 * the method's (method `name`, its ops' `dropped` list: e.g. ir and iir leave out the indirect
 * light of emissive materials, and beyond IIR_VPLSETS_MAX_LIGHTS lights iir the indirect light of
 * the rest). For warnings: the CLI prints them, the
 * daemon can send them. Writes at most max entries into out (NULL when max is 0) and returns how
 * many there are; 0 for an unknown name. */
uint32_t iir_method_dropped(const char *name, const struct iir_scene *scene,
                            const iir_light *lights, uint32_t num_lights, iir_dropped *out,
                            uint32_t max);

/* What method `name` leaves out of the scene because of its parameters p (missing ones: their
 * defaults), as warnings in the terms of iir_method_dropped: pt at too few `bounces` for a mirror
 * or glass (a camera path spends one bounce on a mirror, two crossing glass, before it reaches a
 * rough surface) renders it black, and the warning says the bounces that show it. Writes at most
 * max entries into out (NULL when max is 0) and returns how many there are; 0 for an unknown name
 * or parameters it refuses. */
uint32_t iir_method_dropped_by_params(const char *name, const struct iir_scene *scene,
                                      const iir_params *p, iir_dropped *out, uint32_t max);

/* Creates method `name` over a scene and its ray tracer (both must outlive the method).
 * IIR_ERR_INVALID for an unknown name (the message lists the known ones) or bad parameters. */
iir_status iir_method_create(const char *name, const struct iir_scene *scene, const iir_rt *rt,
                             const iir_params *params, iir_method **out, iir_error *err);
/* The same, polling stop(ctx) as iir_method_set_stop says from the creation's first instruction
 * (meshing, form factors, voxels and point sets check it every few milliseconds of work): once it
 * returns true creation frees what it built and fails with IIR_ERR_INTERRUPTED. A created method
 * keeps the hook for its renders, refinements and set_params. */
iir_status iir_method_create_stoppable(const char *name, const struct iir_scene *scene,
                                       const iir_rt *rt, const iir_params *params, iir_stop_fn stop,
                                       void *ctx, iir_method **out, iir_error *err);
void iir_method_destroy(iir_method *m);
const char *iir_method_name(const iir_method *m);
/* The parameters the method was created with or last given (iir_method_set_params). */
const iir_params *iir_method_params(const iir_method *m);

/* Gives a live method new parameters. When every changed parameter is IIR_PARAM_LIVE (and the
 * method can take them) its state -- VPLs, shadow maps, G-buffer -- is kept and *restarted is
 * false; otherwise the method starts over with the new parameters (*restarted true; may be NULL),
 * its new state created under the method's stop hook. On error (bad parameters, out of memory,
 * IIR_ERR_INTERRUPTED) the method is unchanged. */
iir_status iir_method_set_params(iir_method *m, const iir_params *p, bool *restarted,
                                 iir_error *err);

/* Renders a new frame for `view` into out (its size is the frame size). Stats are overwritten. */
iir_status iir_method_render(iir_method *m, const iir_view *view, iir_image *out,
                             iir_frame_stats *stats, iir_error *err);

/* Optional: the method's current VPLs (null samples included), for overlays and tests; NULL with
 * *n = 0 for methods without VPLs. Valid until the next render or destroy. */
const iir_vpl *iir_method_vpls(const iir_method *m, uint32_t *n);

/* Optional (check iir_method_can_refine): improves the last rendered frame with more work and
 * writes the improved frame to out, which must have the size of that frame. Any render starts
 * over (a new view). IIR_ERR_UNSUPPORTED if the method cannot, IIR_ERR_INVALID if nothing was
 * rendered (or the last render failed).
 *  - pt: `spp` more samples per pixel per call; converged once the image holds refine_passes
 *    samples (rounded up to whole calls: iir_method_converged_at), but it keeps adding samples
 *    when asked.
 *  - ir, iir: one pass of refine.h per call (jittered camera rays, one interleaved VPL subset per
 *    pixel with exact visibility, no filter; after every interleave^2 passes a fresh, independent
 *    VPL set; the live set is left exactly as it was). samples_per_pixel = passes so far. Once
 *    converged (refine_passes passes) a call does no work and only writes the frame again.
 * The caller stops asking when stats->converged. */
bool iir_method_can_refine(const iir_method *m);
iir_status iir_method_refine(iir_method *m, iir_image *out, iir_frame_stats *stats, iir_error *err);

/* Lets render and refine calls end early (a live session's new input, its closing, shutdown):
 * fn(ctx) is polled from the method's threads between phases and per tile of every phase that
 * takes time (pt's samples, shadow-map builds per VPL, direct and indirect light), so a call ends
 * within about a tile of work once it returns true, with IIR_ERR_INTERRUPTED and `out` unspecified.
 * A stopped refine keeps the passes before it; a stopped render leaves no frame to refine (render
 * again), while the VPL set has moved on as for a finished frame (iir: maps not built yet are built
 * by the next frame). Offline callers set no hook, so their frames are never cut short.
 * fn NULL = never stop. */
void iir_method_set_stop(iir_method *m, iir_stop_fn fn, void *ctx);

/* ---- the light's domain, for drawing (optional) ---- */

/* One VPL site in the drawn domain, in the unit disk (a disk's s / R). */
typedef struct iir_domain_site {
    float x, y;
    uint32_t id; /* the VPL's id (iir_method_vpls) */
    uint8_t flags;
} iir_domain_site;

enum {
    IIR_SITE_NEW = 1, /* born in the last frame */
    IIR_SITE_NULL = 2 /* null sample: its ray escaped or hit an emitter */
};

/* The domain of the last frame, drawn into the unit disk: a disk domain scaled to radius 1, a point
 * light's sphere by Lambert's equal-area map about straight down (straight up on the rim; edges and
 * cells the map tears are left out). Sites are in the order (ascending id) of the drawn light's
 * own set (with one light: of iir_method_vpls). */
typedef struct iir_domain {
    uint32_t num_sites;
    const iir_domain_site *sites;
    uint32_t num_edges;
    const uint32_t (*edges)[2];    /* Delaunay edges, indices into sites, first < second */
    uint32_t num_cells;            /* == num_sites; cell k belongs to sites[k] */
    const uint32_t *cell_start;    /* num_cells + 1 entries: cell k is
                                      cell_points[cell_start[k] .. cell_start[k + 1]) */
    const float (*cell_points)[2]; /* Voronoi cells clipped to the unit disk, counter-clockwise,
                                      not closed; arcs drawn as chords (tri.h) */
    uint32_t num_removed;
    const float (*removed)[2]; /* sites removed in the last frame (invalidated or deleted), where
                                  the frame's light saw them: outside the unit disk for sites that
                                  left the cone */
    const char *map; /* "disk", "cap disk", "sphere (equal-area)", "sun disk", "area disk" */
} iir_domain;

/* Fills *out for methods with a disk domain (iir, after a frame); false (and *out zeroed)
 * otherwise or when out of memory. The pointers are owned by the method and valid until the next
 * render or destroy. */
bool iir_method_domain(iir_method *m, iir_domain *out);

#ifdef __cplusplus
}
#endif
#endif

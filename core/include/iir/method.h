/* method.h -- the one interface every rendering method implements (DESIGN section 7): create from a
 * scene and parameters, render a frame for a light/camera state into a float image with stats,
 * optionally refine that frame progressively, destroy. Methods share the scene and the ray tracer;
 * each lives in its own file under core/src/methods/. */
#ifndef IIR_METHOD_H
#define IIR_METHOD_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/camera.h"
#include "iir/image.h"
#include "iir/incremental.h"
#include "iir/light.h"
#include "iir/render.h"
#include "iir/rt.h"
#include "iir/status.h"

#ifdef __cplusplus
extern "C" {
#endif

struct iir_scene;

/* Every parameter any method reads; each method documents which ones it uses. Ranges are checked
 * by iir_params_validate. */
typedef struct iir_params {
    int spp;           /* pt: samples per pixel per render/refine call, [1, 1<<20] */
    int bounces;       /* pt, ir: light bounces: 1 = direct only, 2 = one diffuse bounce, [1, 1000];
                          iir is one bounce by construction */
    uint64_t seed;     /* all randomness derives from it */
    bool jitter;       /* pt and the refinement of ir/iir: box-filter each pixel (true) or shoot
                          through its centre, as interactive frames do (false; for references that
                          compare like with like) */
    int refine_passes; /* progressive refinement is converged after this many passes (ir, iir:
                          refine calls; pt: render + refine calls of `spp` each), [1, 4096] */

    /* VPL methods (ir, iir) */
    int vpls;                  /* N: light paths (ir) or the VPL set's size (iir), [1, 16384] */
    int kmin, kmax;            /* iir: replacements per frame, 0 <= kmin <= kmax <= vpls */
    iir_weights weights;       /* iir: uniform or voronoi cell areas */
    float regen_threshold;     /* iir: regenerate when more than this fraction dies, (0, 1] */
    iir_visibility visibility; /* shadowmap or rays */
    int sm_res;                /* shadow-map resolution, [8, 2048] */
    float sm_bias;             /* shadow-map bias, see shadowmap.h */
    int interleave;            /* n x n VPL subsets with a geometry-aware filter, [1, 8] */
    float clamp;               /* geometry-term bound relative to the scene (render.h); 0 = off */
    bool ir_fresh;             /* ir: fresh random numbers every frame (true) or the same ones */
} iir_params;

iir_params iir_params_default(void);
/* IIR_ERR_INVALID naming the parameter and its allowed range. */
iir_status iir_params_validate(const iir_params *p, iir_error *err);

/* What a frame is rendered from: the scene is fixed, lights and camera move. */
typedef struct iir_view {
    const iir_light *lights; /* punctual lights; emissive triangles come from the scene */
    uint32_t num_lights;
    iir_camera camera;
} iir_view;

typedef enum iir_phase {
    IIR_PHASE_TRACE,      /* path tracing (pt) */
    IIR_PHASE_VPLS,       /* choosing VPLs: the incremental step (iir) or light paths (ir) */
    IIR_PHASE_SHADOWMAPS, /* rendering shadow maps of new VPLs */
    IIR_PHASE_GBUFFER,    /* camera rays (0 when the G-buffer was reused) */
    IIR_PHASE_DIRECT,     /* direct light, one shadow ray per light per pixel */
    IIR_PHASE_INDIRECT,   /* light from the VPLs */
    IIR_PHASE_FILTER,     /* geometry-aware filter of interleaved sampling */
    IIR_PHASE_COUNT
} iir_phase;

/* VPL bookkeeping of one frame (zero for methods without VPLs). */
typedef struct iir_vpl_counts {
    uint32_t count;        /* VPLs in the set, null samples included */
    uint32_t valid;        /* survived validation (iir) */
    uint32_t invalidated;  /* removed by validation (iir) */
    uint32_t deleted;      /* removed along the shortest Delaunay edges (iir) */
    uint32_t inserted;     /* new this frame (iir; all of them for ir) */
    uint32_t null_samples; /* domain points whose rays escaped or hit an emitter */
    uint32_t regenerated;  /* 1 when the whole set was regenerated this frame */
    uint32_t shadowmaps;   /* shadow maps rendered this frame */
} iir_vpl_counts;

typedef struct iir_frame_stats {
    double total_ms;
    double phase_ms[IIR_PHASE_COUNT];
    iir_raystats rays;
    uint64_t samples_per_pixel; /* pt: samples accumulated in the image so far; ir, iir: refinement
                                   passes in the image (0 for an interactive frame) */
    bool converged;             /* refinement reached params.refine_passes (see refine) */
    iir_vpl_counts vpl;         /* refinement: count = the size of the pass's VPL set */
} iir_frame_stats;

const char *iir_phase_name(iir_phase phase);

typedef struct iir_method iir_method;

/* Names of the available methods, NULL-terminated. */
const char *const *iir_method_names(void);

/* Creates method `name` over a scene and its ray tracer (both must outlive the method).
 * IIR_ERR_INVALID for an unknown name (the message lists the known ones) or bad parameters. */
iir_status iir_method_create(const char *name, const struct iir_scene *scene, const iir_rt *rt,
                             const iir_params *params, iir_method **out, iir_error *err);
void iir_method_destroy(iir_method *m);
const char *iir_method_name(const iir_method *m);

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
 *  - pt: `spp` more samples per pixel per call; converged once the image holds refine_passes x spp
 *    samples, but it keeps adding samples when asked (iird render asks for an exact count).
 *  - ir, iir: one pass of refine.h per call (jittered camera rays, one interleaved VPL subset per
 *    pixel with exact visibility, no filter; after every interleave^2 passes a fresh, independent
 *    VPL set; the live set is left exactly as it was). samples_per_pixel = passes so far. Once
 *    converged (refine_passes passes) a call does no work and only writes the frame again.
 * The caller stops asking when stats->converged. */
bool iir_method_can_refine(const iir_method *m);
iir_status iir_method_refine(iir_method *m, iir_image *out, iir_frame_stats *stats, iir_error *err);

/* Optional: lets a refine call end early (a live session's new input): fn(ctx) is polled from the
 * method's threads during refine; once it returns true the call returns IIR_ERR_INTERRUPTED with
 * the passes before it kept and `out` unspecified. Render calls never stop early. A no-op for
 * methods whose refine steps are short (pt). fn NULL = never stop. */
void iir_method_set_stop(iir_method *m, iir_stop_fn fn, void *ctx);

/* ---- the light's domain, for drawing (optional) ---- */

/* One VPL site in the spot's disk, in disk units normalised to radius 1 (s / R). */
typedef struct iir_domain_site {
    float x, y;
    uint32_t id; /* the VPL's id (iir_method_vpls) */
    uint8_t flags;
} iir_domain_site;

enum {
    IIR_SITE_NEW = 1, /* born in the last frame */
    IIR_SITE_NULL = 2 /* null sample: its ray escaped or hit an emitter */
};

/* The domain of the last frame. Sites are in the order (ascending id) of iir_method_vpls. */
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
} iir_domain;

/* Fills *out for methods with a disk domain (iir, after a frame); false (and *out zeroed)
 * otherwise or when out of memory. The pointers are owned by the method and valid until the next
 * render or destroy. */
bool iir_method_domain(iir_method *m, iir_domain *out);

#ifdef __cplusplus
}
#endif
#endif

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
    int spp;       /* pt: samples per pixel per render/refine call, [1, 1<<20] */
    int bounces;   /* pt, ir: light bounces: 1 = direct only, 2 = one diffuse bounce, [1, 1000];
                      iir is one bounce by construction */
    uint64_t seed; /* all randomness derives from it */
    bool jitter;   /* pt: box-filter each pixel (true) or shoot through its centre, as the
                      interactive methods do (false; for references that compare like with like) */

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
    uint64_t samples_per_pixel; /* pt: accumulated in the image so far */
    iir_vpl_counts vpl;
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

/* Optional (check iir_method_can_refine): improves the last rendered frame with more work (for pt,
 * `spp` more samples per pixel) and writes the improved frame to out, which must have the size of
 * that frame. IIR_ERR_UNSUPPORTED if the method cannot, IIR_ERR_INVALID if nothing was rendered. */
bool iir_method_can_refine(const iir_method *m);
iir_status iir_method_refine(iir_method *m, iir_image *out, iir_frame_stats *stats, iir_error *err);

#ifdef __cplusplus
}
#endif
#endif

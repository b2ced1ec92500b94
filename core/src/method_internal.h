/* method_internal.h -- what a method file provides to method.c (its operations and parameter
 * tables) and the option structs and tables that several methods share. Internal. */
#ifndef IIR_METHOD_INTERNAL_H
#define IIR_METHOD_INTERNAL_H

#include <stddef.h>

#include "iir/controller.h"
#include "iir/render.h"
#include "iir/method.h"
#include "iir/refine.h"

/* ---- options every method has (table iir_common_table, method.c) ---- */
typedef struct iir_method_common {
    uint64_t seed;     /* all randomness derives from it */
    int refine_passes; /* progressive refinement is converged after this many passes */
    bool jitter;       /* pt and refinement: box-filter each pixel (true) or shoot through its
                          centre, as interactive frames do (false) */
} iir_method_common;
extern const iir_param_table iir_common_table;
/* `bounces`, one int wherever a method keeps it (pt, ir, iir; method.c). */
extern const iir_param_table iir_bounces_table;

/* ---- the VPL shading: iir_indirect_params and its tables (render.h, render_params.c) ---- */
/* clamp / D^2 (D the scene's bounding-box diagonal), or INFINITY for clamp 0 (rsm.c). */
float iir_clamp_g_max(const struct iir_scene *scene, float clamp);
/* The reflective shadow maps' gather (rsm_map.c; rsm, hier): rsm_map.h's iir_rsm_options. */
extern const iir_param_table iir_rsm_table;

/* ---- the frame-time controller (table iir_ctl_table, methods/ctl_options.c; controller.h) ---- */
typedef struct iir_ctl_options {
    float target_fps; /* 0: off (the fixed vpls, interleave and sm_res) */
    int vpls_max;     /* ctl_vpls_max: the controller's N_max */
    int vpls_min;     /* ctl_vpls_min: its floor N_min (at most N_max) */
    int sm_res_min;   /* ctl_sm_res_min: the coarsest maps it builds (at most sm_res) */
} iir_ctl_options;
extern const iir_param_table iir_ctl_table;
/* Creates, reconfigures or destroys *ctl as o asks (target_fps 0: none), its main rungs at v's
 * interleave and sm_res, a new one starting at start_vpls. On error *ctl is unchanged. */
iir_status iir_ctl_follow(iir_ctl **ctl, const iir_ctl_options *o, const iir_indirect_params *v,
                          int start_vpls, iir_error *err);
/* One finished frame's measurement, rendered with setting `used`, from its stats. */
iir_ctl_sample iir_ctl_sample_of(const iir_frame_stats *fs, iir_ctl_setting used);
/* The most VPLs a method holds with these options: vpls, or the controller's N_max when it is on
 * and larger (memory estimates). */
int iir_ctl_vpls_bound(const iir_ctl_options *o, int vpls);

/* ---- imperfect shadow maps as VPL visibility (table iir_ism_table, ism_options.c) ---- */
typedef struct iir_ism_options {
    int points;         /* the scene's point set, sampled once per method */
    int res;            /* each VPL's map: res x res */
    int points_per_vpl; /* each VPL's subset of the points */
} iir_ism_options;
extern const iir_param_table iir_ism_table;

struct iir_ism_points;
/* The ISMs (ism.h) of the non-null VPLs without one, until stop(ctx) says stop; *pts is the point
 * set the caller keeps, created from scene and seed on first use (the caller frees it with
 * iir_ism_points_destroy). salt tells apart VPL sets whose ids may repeat (iir's per light).
 * *built = maps rendered. IIR_ERR_NOMEM or IIR_ERR_INVALID (a scene without area) when the point
 * set cannot be made. */
iir_status iir_ism_maps_build(struct iir_ism_points **pts, const struct iir_scene *scene,
                              const iir_rt *rt, const iir_ism_options *o, uint64_t seed,
                              uint64_t salt, iir_vpl *vpls, uint32_t n, iir_stop_fn stop, void *ctx,
                              uint32_t *built, iir_error *err);
/* Bytes of n VPLs' ISMs and the point set when visibility is ism, else 0 (iir_vpl_memory counts
 * the exact maps). */
uint64_t iir_ism_memory(const iir_ism_options *o, iir_visibility visibility, uint32_t n);

/* One of a method's tables and where its options struct sits in the method's own. */
typedef struct iir_method_table {
    const iir_param_table *table;
    size_t offset;
} iir_method_table;

enum { IIR_METHOD_MAX_TABLES = 12 };

typedef struct iir_method_ops {
    const char *name;
    const char *summary;
    iir_method_table tables[IIR_METHOD_MAX_TABLES]; /* up to the first NULL table */
    size_t opts_size;                               /* the method's options struct */
    /* opts: the method's options struct, bound from its tables; copy what you keep. stop (never
     * NULL; its fn may be) is polled at least every few milliseconds of the work creation does
     * (meshing, form factors, voxels, point sets): once it says stop, create frees what it built
     * and fails with IIR_ERR_INTERRUPTED. Keep it as the render hook too (set_stop may follow). */
    iir_status (*create)(const struct iir_scene *scene, const iir_rt *rt, const void *opts,
                         const iir_stop *stop, void **state, iir_error *err);
    void (*destroy)(void *state);
    iir_status (*render)(void *state, const iir_view *view, iir_image *out, iir_frame_stats *stats,
                         iir_error *err);
    /* NULL when the method cannot refine. */
    iir_status (*refine)(void *state, iir_image *out, iir_frame_stats *stats, iir_error *err);
    /* NULL when the method has no VPLs. */
    const iir_vpl *(*vpls)(const void *state, uint32_t *n);
    /* NULL when the method has no disk domain; false when it has none now. */
    bool (*domain)(void *state, iir_domain *out);
    /* NULL when the method's refinement cannot stop early. */
    void (*set_stop)(void *state, iir_stop_fn fn, void *ctx);
    /* Takes new options that differ only in IIR_PARAM_LIVE parameters; the next frame uses
     * them. NULL: every change re-creates the method. */
    void (*update)(void *state, const void *opts);
    /* NULL when the method renders any lights; else IIR_ERR_UNSUPPORTED naming what it needs. */
    iir_status (*supports)(const iir_light *lights, uint32_t num_lights, iir_error *err);
    /* Bytes the method holds with opts for a width x height frame, beyond the output image. */
    uint64_t (*memory)(const void *opts, int width, int height);
    /* NULL when memory's estimate does not depend on the scene. Else the same from the scene's
     * real counts (meshing counts, sampled rays: milliseconds, not the build itself), and the
     * bytes a created state holds by its real counts. */
    uint64_t (*memory_on)(const void *opts, const struct iir_scene *scene, const iir_rt *rt,
                          int width, int height);
    uint64_t (*held)(const void *state, int width, int height);
    /* samples_per_pixel at which refinement converges (iir_method_converged_at). NULL: the
     * refine_passes parameter (one pass per refine call). */
    uint64_t (*converged_at)(const void *opts);
    /* pt's bounce count for this method's references (iir_method_reference_bounces): 0 = the
     * method's `bounces` parameter, or 2 (one bounce) without one. */
    int reference_bounces;
    /* Its VPL sum reflects by a glossy pixel's full BSDF (render_indirect.c, full shading) and its
       camera rays follow mirrors and glass (iir_renderer_follow_specular). */
    bool full_surfaces;
    /* The phases the method reports, in pipeline order, ending with IIR_PHASE_COUNT. */
    iir_phase phases[IIR_PHASE_COUNT + 1];
    /* Its own counters (frame stats' counter[i] is counters[i]), up to the first NULL name. */
    iir_counter counters[IIR_MAX_COUNTERS + 1];
    /* NULL when the method renders all of every light it is given (pt). Otherwise appends to out
     * (at most max entries; returns how many there are) what it leaves out of these lights and
     * the scene's emissive materials (iir_method_dropped). */
    uint32_t (*dropped)(const struct iir_scene *scene, const iir_light *lights, uint32_t num_lights,
                        iir_dropped *out, uint32_t max);
    /* NULL when what the method renders does not depend on its options. Otherwise appends, as
     * dropped does, what opts leave out of the scene (pt: mirrors and glass its bounces do not get
     * through; iir_method_dropped_by_params). */
    uint32_t (*dropped_by_params)(const struct iir_scene *scene, const void *opts, iir_dropped *out,
                                  uint32_t max);
} iir_method_ops;

/* The operations of method `name`, or NULL (method.c). */
const iir_method_ops *iir_method_ops_of(const char *name);
/* A new options struct of ops bound from p (malloc'ed: the caller frees it), or NULL when p holds
 * a value the method refuses or on out-of-memory (method.c). */
void *iir_method_bind_opts(const iir_method_ops *ops, const iir_params *p);

/* Appends an entry to out (when *n < max; printf-style `what`) and counts it in *n (dropped.c). */
void iir_dropped_add(iir_dropped *out, uint32_t max, uint32_t *n, const char *method,
                     const char *kind, const char *name, const char *fmt, ...)
    __attribute__((format(printf, 7, 8)));
/* An entry per emissive material of the scene (`method` leaves out its indirect light) and per
 * mirror or glass (a diffuse-only `method` renders it black). Returns how many; writes at most
 * max. */
uint32_t iir_dropped_emitters(const struct iir_scene *scene, const char *method, iir_dropped *out,
                              uint32_t max);

/* The phases of the VPL renderer's methods (ir, iir, ism), ending with IIR_PHASE_COUNT. */
#define IIR_VPL_PHASES                                                                             \
    {                                                                                              \
        IIR_PHASE_VPLS, IIR_PHASE_SHADOWMAPS, IIR_PHASE_GBUFFER, IIR_PHASE_DIRECT,                 \
            IIR_PHASE_INDIRECT, IIR_PHASE_FILTER, IIR_PHASE_COUNT                                  \
    }

extern const iir_method_ops iir_method_pt;
extern const iir_method_ops iir_method_ir;
extern const iir_method_ops iir_method_iir;
extern const iir_method_ops iir_method_ism;

/* ---- instant radiosity's options (ir.c), which the ism method binds too ---- */
typedef struct iir_ir_options {
    iir_method_common common;
    iir_indirect_params vpl; /* bounces: the method's own `bounces` */
    iir_ism_options ism;
    int vpls;         /* N light paths */
    int bounces;      /* 1 = direct only, 2 = one diffuse bounce */
    bool same_random; /* the same random numbers every frame */
} iir_ir_options;
extern const iir_method_ops iir_method_rsm;
extern const iir_method_ops iir_method_hier;
extern const iir_method_ops iir_method_radiosity;
extern const iir_method_ops iir_method_whitted;
extern const iir_method_ops iir_method_hybrid;

/* Shared by the VPL methods: validates the view (camera and lights), IIR_ERR_INVALID otherwise. */
iir_status iir_view_validate(const iir_view *view, iir_error *err);

/* Copies the renderer's phase times into the frame stats. */
void iir_render_timing_to_stats(const iir_render_timing *t, iir_frame_stats *stats);

/* The refine.h settings the options ask for, for VPLs of a method's `bounces`. */
iir_refine_params iir_refine_params_of(const iir_method_common *c, const iir_indirect_params *v,
                                       int bounces);

/* A refinement pass's stats as frame stats (samples_per_pixel = passes, converged, phases). */
void iir_refine_to_stats(const iir_refine_stats *rs, iir_frame_stats *stats);

#endif

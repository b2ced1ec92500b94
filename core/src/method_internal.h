/* method_internal.h -- the table of operations a method file provides to method.c. Internal. */
#ifndef IIR_METHOD_INTERNAL_H
#define IIR_METHOD_INTERNAL_H

#include "iir/method.h"
#include "iir/refine.h"

typedef struct iir_method_ops {
    const char *name;
    const char *summary;
    iir_status (*create)(const struct iir_scene *scene, const iir_rt *rt, const iir_params *params,
                         void **state, iir_error *err);
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
} iir_method_ops;

extern const iir_method_ops iir_method_pt;
extern const iir_method_ops iir_method_ir;
extern const iir_method_ops iir_method_iir;

/* Shared by the VPL methods: validates the view (camera and lights), IIR_ERR_INVALID otherwise. */
iir_status iir_view_validate(const iir_view *view, iir_error *err);

/* The render.h settings a method's parameters ask for. */
iir_indirect_params iir_params_indirect(const iir_params *p);

/* Copies the renderer's phase times into the frame stats. */
void iir_render_timing_to_stats(const iir_render_timing *t, iir_frame_stats *stats);

/* The refine.h settings a method's parameters ask for. */
iir_refine_params iir_params_refine(const iir_params *p);

/* A refinement pass's stats as frame stats (samples_per_pixel = passes, converged, phases). */
void iir_refine_to_stats(const iir_refine_stats *rs, iir_frame_stats *stats);

#endif

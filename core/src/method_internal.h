/* method_internal.h -- the table of operations a method file provides to method.c. Internal. */
#ifndef IIR_METHOD_INTERNAL_H
#define IIR_METHOD_INTERNAL_H

#include "iir/method.h"

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
} iir_method_ops;

extern const iir_method_ops iir_method_pt;

#endif

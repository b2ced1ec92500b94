/* whitted_tree.h -- the Whitted ray tree (Whitted 1980) shared by the methods whitted and hybrid:
 * its parameters (table whitted_param_table), and a frame of trees, one from each pixel centre.
 * Internal to the methods; the model is described at the top of whitted_tree.c.
 *
 * What a diffuse surface returns is the tree's local shading (shadow rays to every light, the
 * ambient term) and, when the caller gives one, a diffuse hook's radiance: hybrid's is the
 * radiosity solution's rho H(x) / pi. */
#ifndef IIR_WHITTED_TREE_H
#define IIR_WHITTED_TREE_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/method.h"
#include "iir/rt.h"
#include "iir/scene.h"

typedef struct whitted_params {
    int max_depth;    /* most specular bounces along a branch */
    float min_weight; /* a branch whose weight falls below this stops (0 = the full tree) */
    int area_samples; /* points per area light (and for the emissive triangles) per shading point */
    float ambient;    /* ambient radiance times albedo added at diffuse surfaces */
} whitted_params;
extern const iir_param_table whitted_param_table;

/* Radiance leaving a rough hit towards the viewer beyond the tree's local shading (hit: the
 * scene triangle and its Embree barycentrics; albedo: the diffuse reflectance there, textured).
 * Called from several threads at once. */
typedef iir_vec3 (*whitted_diffuse_fn)(const void *ctx, const iir_hit *hit, iir_vec3 albedo);

/* A frame's settings. */
typedef struct whitted_frame {
    const whitted_params *p;
    uint64_t seed;            /* area samples draw from a stream hashed from it and the pixel */
    bool local_direct;        /* shadow rays to the lights at diffuse hits (false: the hook's) */
    whitted_diffuse_fn extra; /* NULL: none */
    const void *extra_ctx;
    iir_stop_fn stop; /* NULL: never stops */
    void *stop_ctx;
} whitted_frame;

typedef struct whitted_tree whitted_tree;

/* The counters of the methods that render the tree (whitted, hybrid): frame stats' counter[0]. */
enum { WHITTED_BRANCHES_CUT };
#define WHITTED_COUNTERS                                                                           \
    {                                                                                              \
        {                                                                                          \
            "branches_cut", IIR_COUNTER_EVENTS,                                                    \
                "ray-tree branches the adaptive depth control (min_weight) stopped, each saving "  \
                "its ray "                                                                         \
                "and the tree under it"                                                            \
        }                                                                                          \
    }

/* NULL when out of memory. The scene and rt must outlive it. */
whitted_tree *whitted_tree_create(const iir_scene *scene, const iir_rt *rt);
void whitted_tree_destroy(whitted_tree *w);
/* One tree per pixel of out (OpenMP over tiles): stats->rays and its branches_cut counter; the
 * frame's lights and camera from view (validated by the caller). IIR_ERR_INTERRUPTED when stop said
 * so. */
iir_status whitted_tree_render(whitted_tree *w, const whitted_frame *f, const iir_view *view,
                               iir_image *out, iir_frame_stats *stats, iir_error *err);

#endif

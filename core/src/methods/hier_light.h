/* hier_light.h -- the direct light of the hierarchical method (hier.c) at any point: every light of
 * the view, an area light as K point samples on its emitter, shadowed by the coarse voxel grid
 * (voxels.h) instead of rays. Internal to the hier method.
 *
 * An area light of radiance L and area A becomes K points y_k stratified over its emitter (cell
 * centres of a grid through its area map: iir_area_light_sample_q), each a patch of area dA = A / K
 * facing the light's normal f; a receiver x with normal n gets the irradiance of a disk of area dA
 * (Wallace, Elmquist & Haines 1989), which stays bounded where x comes close:
 *     E_k = L dA max(0, f . w) max(0, -n . w) / (d^2 + dA / pi),   w = (x - y_k) / d.
 * Delta lights give I(w) cos / d^2 (the sun E cos). Visibility V is the voxel grid's: the segment
 * from x moved a cell's diagonal along n (out of its own surface's cells) to the light point, moved
 * as much off its emitter along the light's normal (an area light usually sits on a ceiling), or
 * to a delta light's position with the last cell diagonal skipped; either traversed cell by cell
 * (3DDA) or probed at a few points along it (the cheaper option: thin walls can slip between
 * them), or not tested at all. */
#ifndef IIR_HIER_LIGHT_H
#define IIR_HIER_LIGHT_H

#include <stdint.h>

#include "iir/bsdf.h"
#include "iir/light.h"
#include "iir/voxels.h"

typedef enum hier_visibility {
    HIER_VIS_VOXELS, /* 3DDA through the grid */
    HIER_VIS_POINTS, /* the cells at vis_points points along the segment */
    HIER_VIS_NONE
} hier_visibility;

/* One point of a light: the sample its light is asked for (iir_light_sample_li). */
typedef struct hier_point {
    iir_vec2 u;       /* area sample: its cell's centre in [0, 1)^2; delta lights: unused */
    float weight;     /* area sample: 1 / K; delta lights: 1 */
    float dA_over_pi; /* area sample: dA / pi; delta lights: 0 */
    uint32_t light;   /* index of its light */
} hier_point;

typedef struct hier_lights {
    const iir_light *lights;
    uint32_t num_lights;
    hier_point *pts; /* every light's points, in light order */
    uint32_t num_pts, cap;
    iir_light_eval *eval; /* per light, prepared */
    uint32_t eval_cap;
    const iir_voxels *grid;
    hier_visibility vis;
    int vis_points;
    float offset; /* a cell's diagonal: the shadow segment's offset from both ends */
    float scene_radius;
} hier_lights;

/* The points of the view's lights for this frame: K = samples per area light, one per delta
 * light. false when out of memory (hl then has no points). lights must outlive the frame. */
bool hier_lights_prepare(hier_lights *hl, const iir_light *lights, uint32_t num_lights,
                         int samples);
void hier_lights_free(hier_lights *hl);

/* The direct irradiance at x (normal n, facing the camera) from every point, shadowed as hl->vis
 * says; adds the points evaluated to *evals. Read-only on hl: any thread may call it. */
iir_vec3 hier_direct(const hier_lights *hl, iir_vec3 x, iir_vec3 n, uint64_t *evals);
/* The same reflected by BSDF b toward wo (its normal: the receiver's): radiance, not irradiance
 * (a glossy pixel's, evaluated per pixel). */
iir_vec3 hier_direct_bsdf(const hier_lights *hl, iir_vec3 x, const iir_bsdf *b, iir_vec3 wo,
                          uint64_t *evals);

#endif

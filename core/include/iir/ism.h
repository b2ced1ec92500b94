/* ism.h -- imperfect shadow maps (Ritschel, Grosch, Kim, Seidel, Dachsbacher, Kautz 2008): the
 * scene preprocessed once into a point set, and per VPL a low-resolution paraboloid depth map
 * splatted from the VPL's own subset of the points, its holes filled by pull-push (pullpush.h).
 * Not the exact maps (shadowmap.h) and not lookups: an ISM is an iir_smap in exactly shadowmap.h's
 * layout and parametrisation, so the renderer reads it with the same iir_smap_probe_* lookups.
 *
 * The point set. n samples, uniform over the scene's surface area: sample k picks a triangle by
 * stratified inversion of the area CDF (u_k = (k + xi_k) / n, so triangle t gets n A_t / A points
 * up to one) and a uniform point on it (iir_sample_uniform_triangle). A sample is stored as
 * (triangle, barycentrics), so it follows the scene if meshes were transformed; its world position
 * is derived from them (iir_ism_points_update). The samples are then shuffled (Fisher-Yates), so
 * any run of consecutive samples is a uniform random subset of the surface. Everything derives
 * from the seed.
 *
 * A map. Every texel starts as a hole (INFINITY). Each point x of the VPL's subset -- m = points
 * per VPL consecutive samples starting at hash(key, VPL id) mod n, wrapping -- with local
 * direction w = x - o (o = the VPL's position lifted by eps along its normal, the exact map's
 * origin) in the hemisphere (w . f > 0) lands in the texel holding iir_paraboloid_uv(w / |w|) and
 * keeps the nearest distance there: depth = min |x - o|. Pull-push then fills the holes (the
 * corners outside the paraboloid's disk too). Texels hold distances like the exact map's, but
 * to the nearest point splatted into them rather than along their centre direction, and holes
 * hold averages of their neighbourhood: the map is "imperfect", and lookups add the same bias.
 *
 * Measured on the Cornell box (tests/unit/test_ism.c; 96 VPLs x 1500 receivers with G > 0, against
 * exact occlusion rays, default bias): a 32^2 ISM from 256, 1024 or 4096 points agrees on 71%, 79%
 * and 86% of the pairs (an exact 32^2 map on 90%, 128^2 on 96%). Nearly all of the difference is
 * leaks: a texel behind an occluder that no occluder point reached keeps a farther point, so light
 * passes near contacts and through sparsely hit occluders (half of the occluded pairs at 1024
 * points); only ~5% of the lit pairs are wrongly shadowed, so more bias would only leak more and
 * ISMs use the exact maps' bias (whose slope term grows with the texel). Over many VPLs the leaks
 * average out: frames of ir come within ~10% of the relMSE against pt of exact maps. A map costs
 * about a twentieth of a ray-traced 128^2 one (~30 us on one core) and has 1/16 of its bytes. */
#ifndef IIR_ISM_H
#define IIR_ISM_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "iir/status.h"
#include "iir/vecmath.h"
#include "iir/vpl.h"

#ifdef __cplusplus
extern "C" {
#endif

struct iir_scene;

/* ---- the point set ---- */

/* A point on triangle tri: p = (1 - b1 - b2) v0 + b1 v1 + b2 v2. */
typedef struct iir_ism_sample {
    uint32_t tri;
    float b1, b2;
} iir_ism_sample;

typedef struct iir_ism_points {
    uint32_t n;
    iir_ism_sample *sample; /* [n], in random order */
    iir_vec3 *p;            /* [n], world positions derived from sample */
} iir_ism_points;

/* n area-uniform samples of the scene's triangles (n >= 1) from seed. IIR_ERR_INVALID when the
 * scene has no triangle of positive area, IIR_ERR_NOMEM; *out is then NULL. Free with
 * iir_ism_points_destroy. */
iir_status iir_ism_points_create(const struct iir_scene *scene, uint32_t n, uint64_t seed,
                                 iir_ism_points **out, iir_error *err);
/* Recomputes every world position from its triangle and barycentrics (after the scene's vertices
 * moved; the triangles must be the same). */
void iir_ism_points_update(iir_ism_points *pts, const struct iir_scene *scene);
void iir_ism_points_destroy(iir_ism_points *pts);

/* ---- maps ---- */

typedef struct iir_ism_params {
    int res;                 /* res x res texels, [1, IIR_SMAP_MAX_RES] */
    uint32_t points_per_vpl; /* m, at most the point count (more is clamped) */
    uint64_t key;            /* with the VPL id, where its subset starts */
} iir_ism_params;

/* Floats of per-thread scratch iir_ism_render needs at resolution res (the map in floats, then
 * pull-push's levels). */
size_t iir_ism_scratch_floats(int res);

/* Renders v's ISM into m: (re)allocates m->depth with malloc when it has no texels or another
 * resolution, splats v's subset of pts and fills the holes by pull-push in scratch (at least
 * iir_ism_scratch_floats(p->res) floats). v->frame must be set; eps is the exact map's origin
 * lift (iir_rt_epsilon). Returns false, with the map released, only when allocation fails.
 * Thread-safe for distinct maps and scratch. */
bool iir_ism_render(iir_smap *m, const iir_ism_points *pts, const iir_vpl *v,
                    const iir_ism_params *p, float eps, float *scratch);

/* Splats v's subset of pts into depth (res x res, filled with INFINITY by the caller), keeping the
 * nearest distance per texel: iir_ism_render without pull-push. Returns the points splatted (those
 * in v's hemisphere). */
uint32_t iir_ism_splat(float *depth, const iir_ism_points *pts, const iir_vpl *v,
                       const iir_ism_params *p, float eps);

/* Renders the ISMs of the non-null VPLs whose smap.res != p->res, in parallel over VPLs (OpenMP,
 * scratch allocated once per thread), skipping the maps not yet begun once stop(ctx) returns true
 * (stop may be NULL). Returns how many it rendered; a map whose allocation failed (or a thread
 * whose scratch did) is left not rendered (res 0). */
uint32_t iir_ism_build_until(iir_vpl *vpls, uint32_t n, const iir_ism_points *pts,
                             const iir_ism_params *p, float eps, iir_stop_fn stop, void *ctx);

#ifdef __cplusplus
}
#endif
#endif

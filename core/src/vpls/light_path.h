/* light_path.h -- one continuation step of a light path at a VPL (Keller 1997), shared by ir's
 * paths (methods/ir.c) and iir's descendants (lineage.c): Russian roulette on the VPL's albedo,
 * then a cosine-distributed direction about its normal. Cosine sampling makes the throughput of a
 * diffuse bounce its albedo, so the flux carried on is the VPL's flux over q. Internal; inline. */
#ifndef IIR_LIGHT_PATH_H
#define IIR_LIGHT_PATH_H

#include <math.h>
#include <stdbool.h>

#include "../sampling.h"
#include "iir/rng.h"
#include "iir/rt.h"
#include "iir/vpl.h"

/* Whether the path goes on past v: with probability q = min(1, max rho) (one number of rng; none
 * when q is 0), *ray then leaving v (eps along its normal) in a cosine-distributed direction (two
 * numbers) and *q the probability it went on with. */
static inline bool iir_light_path_continue(const iir_vpl *v, float eps, iir_rng *rng, iir_ray *ray,
                                           float *q)
{
    *q = fminf(1.f, iir_max_comp(v->albedo));
    if (*q <= 0.f || iir_rng_uniform(rng) >= *q) return false;
    iir_vec3 wi =
        iir_frame_to_world(&v->frame, iir_sample_cosine_hemisphere(iir_rng_uniform2(rng)));
    *ray = iir_make_ray(iir_madd(v->position, v->normal, eps), wi, 0.f, INFINITY);
    return true;
}

#endif

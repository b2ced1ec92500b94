/* light_path.h -- one continuation step of a light path at a VPL (Keller 1997), shared by ir's
 * paths (methods/ir.c) and iir's descendants (lineage.c): Russian roulette on the VPL's albedo,
 * then a direction from its lobe -- cosine-distributed about a diffuse VPL's normal, which makes
 * the step's throughput its albedo (the flux carried on is the VPL's flux over q), or sampled from
 * a glossy VPL's BSDF for the direction its light came from (GGX visible normals and the diffuse
 * lobe, bsdf.h), the step carrying f |cos| / pdf of the arriving flux. Internal; inline. */
#ifndef IIR_LIGHT_PATH_H
#define IIR_LIGHT_PATH_H

#include <math.h>
#include <stdbool.h>

#include "../sampling.h"
#include "iir/rng.h"
#include "iir/rt.h"
#include "iir/vpl.h"
#include "vpl_lobe.h"

/* One step on from a VPL: the ray, what it carries relative to the VPL's flux, and for a glossy
 * VPL's non-delta sample what re-weighs it (iir_vpl_lobe_weight): its density times q. */
typedef struct iir_light_step {
    iir_ray ray;
    iir_vec3 weight; /* the flux the ray carries = the VPL's flux times weight */
    float pdf_q;     /* > 0: sampled from a glossy lobe's density (not its delta) */
} iir_light_step;

/* Whether the path goes on past v: with probability q = min(1, max rho) (one number of rng; none
 * when q is 0), *step then leaving v (eps along its normal) by its lobe (a diffuse VPL: two
 * numbers; a glossy one: three, and false when its BSDF's sample fails). */
static inline bool iir_light_path_continue(const iir_vpl *v, float eps, iir_rng *rng,
                                           iir_light_step *step)
{
    float q = fminf(1.f, iir_max_comp(v->albedo));
    if (q <= 0.f || iir_rng_uniform(rng) >= q) return false;
    iir_vec3 o = iir_madd(v->position, v->normal, eps), d;
    step->pdf_q = 0.f;
    if (!v->lobe.glossy) {
        d = iir_frame_to_world(&v->frame, iir_sample_cosine_hemisphere(iir_rng_uniform2(rng)));
        step->weight = iir_v3s(1.f / q);
    } else {
        iir_bsdf b = iir_vpl_lobe_bsdf(v);
        iir_bsdf_sample s;
        float uc = iir_rng_uniform(rng);
        if (!iir_bsdf_sample_f(&b, v->wi, uc, iir_rng_uniform2(rng), &s)) return false;
        d = s.wi;
        iir_vec3 T = iir_scale(s.f, fabsf(iir_dot(v->normal, d)) / (s.pdf * q)); /* a delta's too */
        step->weight = iir_v3(T.x / v->albedo.x, T.y / v->albedo.y, T.z / v->albedo.z);
        if (!(s.flags & IIR_BSDF_SPECULAR)) step->pdf_q = s.pdf * q;
    }
    step->ray = iir_make_ray(o, d, 0.f, INFINITY);
    return true;
}

#endif

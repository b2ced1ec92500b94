/* surface.h -- what shading needs at a ray hit: position, geometric normal facing the viewer,
 * material; and the shadow ray from it to a light sample. Internal to libiircore; inline. */
#ifndef IIR_SURFACE_H
#define IIR_SURFACE_H

#include "iir/light.h"
#include "iir/rt.h"
#include "iir/scene.h"

typedef struct iir_surface {
    iir_vec3 p;  /* hit point from barycentrics (more precise than org + t dir) */
    iir_vec3 n;  /* unit geometric normal in winding order (emission side) */
    iir_vec3 ns; /* n flipped to the side of wo (surfaces reflect on both sides) */
    const iir_material *mat;
} iir_surface;

static inline iir_surface iir_surface_at(const iir_scene *s, const iir_hit *hit, iir_vec3 wo)
{
    const uint32_t *idx = &s->indices[3 * hit->prim];
    iir_vec3 p0 = s->positions[idx[0]], p1 = s->positions[idx[1]], p2 = s->positions[idx[2]];
    iir_surface sf;
    sf.p = iir_add(iir_add(iir_scale(p0, 1.f - hit->u - hit->v), iir_scale(p1, hit->u)),
                   iir_scale(p2, hit->v));
    sf.n = s->normals[hit->prim];
    sf.ns = iir_dot(sf.n, wo) < 0.f ? iir_neg(sf.n) : sf.n;
    sf.mat = &s->material_list[s->materials[hit->prim]];
    return sf;
}

/* Emitted radiance towards wo: one-sided, along the winding normal. */
static inline iir_vec3 iir_surface_Le(const iir_surface *sf, iir_vec3 wo)
{
    return iir_dot(sf->n, wo) > 0.f ? sf->mat->emission : iir_v3s(0.f);
}

/* Origin for a ray leaving the surface on the side of ns. */
static inline iir_vec3 iir_surface_offset(const iir_surface *sf, float eps)
{
    return iir_madd(sf->p, sf->ns, eps);
}

/* The shadow ray from o (the shading point lifted off its surface) to light sample ls taken at p:
 * aimed at the sampled point itself and stopping 2 eps short of it, so that the lift does not
 * carry a grazing ray through the light's own surface just before the point (an emissive triangle
 * is geometry: aimed along ls.wi from o, a ray at 20 degrees above the emitter's plane met the
 * emitter 3 eps early and most such samples counted as shadowed); a sun's goes along wi. */
static inline iir_ray iir_light_sample_ray(iir_vec3 o, iir_vec3 p, const iir_light_sample *ls,
                                           float eps)
{
    if (isinf(ls->dist)) return iir_make_ray(o, ls->wi, 0.f, INFINITY);
    iir_vec3 d = iir_sub(iir_madd(p, ls->wi, ls->dist), o);
    float len = iir_length(d);
    if (!(len > 2.f * eps)) return iir_make_ray(o, ls->wi, 0.f, 0.f);
    return iir_make_ray(o, iir_scale(d, 1.f / len), 0.f, len - 2.f * eps);
}

#endif

/* surface.h -- what shading needs at a ray hit: position, geometric normal facing the viewer,
 * material; where light arrives at it and the shadow ray to a light sample. Internal to libiircore;
 * inline. */
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

/* Where light arrives at sf: its point and normal, for iir_light_sample_li and
 * iir_lightset_sample_li. */
static inline iir_light_ctx iir_surface_light_ctx(const iir_surface *sf, float eps)
{
    iir_light_ctx ctx = {sf->p, sf->ns, eps};
    return ctx;
}

/* A light segment as a ray. */
static inline iir_ray iir_segment_ray(const iir_light_segment *seg)
{
    return iir_make_ray(seg->org, seg->dir, 0.f, seg->tmax);
}

#endif

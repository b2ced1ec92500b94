/* surface.h -- what shading needs at a ray hit: position, geometric and shading normals facing the
 * viewer, texture coordinates and the material evaluated there (textured base colour, metallic,
 * roughness, emission, normal map), its BSDF, and where light arrives at it. The only reader of
 * iir_material's fields outside the material's own module and loaders (material/surface.c).
 * Internal to libiircore. */
#ifndef IIR_SURFACE_H
#define IIR_SURFACE_H

#include <math.h>

#include "iir/bsdf.h"
#include "iir/light.h"
#include "iir/rt.h"
#include "iir/scene.h"

typedef struct iir_surface {
    iir_vec3 p;        /* hit point from barycentrics (more precise than org + t dir) */
    iir_vec3 n;        /* unit geometric normal in winding order (emission side) */
    iir_vec3 ns;       /* n flipped to the side of wo (surfaces reflect on both sides) */
    iir_vec3 sn;       /* shading normal on the side of wo: vertex normals and normal map; ns
                          without them, and never more than ~89 degrees from wo */
    iir_vec2 uv;       /* TEXCOORD_0 at the hit; 0 without texture coordinates */
    iir_vec3 base;     /* base colour: the material's albedo x its base colour texture */
    float metallic;    /* metal_rough: metallic x texture (0 otherwise) */
    float roughness;   /* metal_rough: roughness x texture (1 otherwise) */
    float specular_f0; /* metal_rough: a dielectric's reflectance at normal incidence */
    iir_vec3 albedo;   /* the diffuse reflectance a diffuse-only method uses (base (1 - metallic));
                          0 for a mirror or glass */
    iir_vec3 Le;       /* emitted radiance on the winding side (emission x its texture) */
    iir_vec3 specular; /* mirror: reflectance; glass: transmission tint */
    float ior;         /* glass: index of refraction */
    iir_material_kind kind;
    int specular_depth;      /* iir_material_specular_depth of the material */
    const iir_material *mat; /* for the material's module and hashing only */
} iir_surface;

/* The surface at hit seen from direction wo (unit, pointing away from the surface); textures are
 * read at their finest level (bilinear). */
iir_surface iir_surface_at(const iir_scene *s, const iir_hit *hit, iir_vec3 wo);

/* The same with textures filtered trilinearly over a ray cone of width `width` (world units) at
 * the hit (camera rays: the pixel's spread angle times the distance). */
iir_surface iir_surface_at_cone(const iir_scene *s, const iir_hit *hit, iir_vec3 wo, float width);

/* The BSDF at sf (metal_rough: Lambert + GGX; diffuse: Lambert of albedo). Mirror and glass are
 * delta surfaces that pt and whitted follow with specular.h; their BSDF here is black. */
iir_bsdf iir_surface_bsdf(const iir_surface *sf);

/* Reflected radiance factor f(wo, wi) |cos| for a diffuse-only method's direct light: the full BSDF
 * (glossy part included), zero below the geometric surface on wi's side (no light leaks through).
 */
static inline iir_vec3 iir_surface_f_cos(const iir_surface *sf, const iir_bsdf *b, iir_vec3 wo,
                                         iir_vec3 wi)
{
    if (iir_dot(wi, sf->ns) <= 0.f) return iir_v3s(0.f);
    return iir_scale(iir_bsdf_f(b, wo, wi), fabsf(iir_dot(wi, sf->sn)));
}

/* The same for a direction the BSDF sampled (its f, delta lobes included). */
static inline iir_vec3 iir_surface_f_cos_sampled(const iir_surface *sf, const iir_bsdf_sample *bs)
{
    if (iir_dot(bs->wi, sf->ns) <= 0.f) return iir_v3s(0.f);
    return iir_scale(bs->f, fabsf(iir_dot(bs->wi, sf->sn)));
}

/* A metal_rough surface smoother than IIR_MIRROR_ROUGHNESS as a mirror, met along unit V: the
 * direction *wi it reflects to (about the shading normal) and its reflectance *F there (Schlick's F
 * of its f0). False for other surfaces, or when *wi falls below the surface. Whitted's tree and
 * the VPL methods' specular chains follow it. */
bool iir_surface_mirror_reflection(const iir_surface *sf, iir_vec3 V, iir_vec3 *wi, iir_vec3 *F);

/* Whether sf scatters light diffusely or glossily (a rough surface a gather can stop at). */
static inline bool iir_surface_is_rough(const iir_surface *sf)
{
    return sf->kind == IIR_MATERIAL_DIFFUSE || sf->kind == IIR_MATERIAL_METAL_ROUGH;
}

/* The diffuse albedo and the front-side emitted radiance of triangle prim at barycentrics (u, v)
 * (the weights of its second and third vertex), textures at their finest level: for light
 * sampling and patch reflectances. */
iir_vec3 iir_surface_albedo_at(const iir_scene *s, uint32_t prim, float u, float v);
iir_vec3 iir_surface_emission_at(const iir_scene *s, uint32_t prim, float u, float v);

/* Coverage of triangle prim at barycentrics (u, v): false where its material's alpha cut-out makes
 * a hole (MASK below the cutoff; BLEND below 0.5). True for opaque materials. */
bool iir_surface_covers(const iir_scene *s, uint32_t prim, float u, float v);

/* Whether material m has cut-outs (alpha mode MASK or BLEND). */
static inline bool iir_material_has_cutout(const iir_material *m)
{
    return m->alpha_mode != IIR_ALPHA_OPAQUE;
}

/* Whether triangle prim's material is alphaMode BLEND, and its alpha at (u, v) (base colour
 * alpha x texture alpha): pt's stochastic transparency (iir_rt_intersect_blend). */
bool iir_surface_blends(const iir_scene *s, uint32_t prim);
float iir_surface_alpha(const iir_scene *s, uint32_t prim, float u, float v);

/* Whether any material of the scene is alphaMode BLEND. */
bool iir_scene_has_blend(const iir_scene *s);

/* Whether any material of the scene has cut-outs (the ray tracer filters hits only then). */
bool iir_scene_has_cutouts(const iir_scene *s);

/* Emitted radiance towards wo: one-sided, along the winding normal. */
static inline iir_vec3 iir_surface_Le(const iir_surface *sf, iir_vec3 wo)
{
    return iir_dot(sf->n, wo) > 0.f ? sf->Le : iir_v3s(0.f);
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

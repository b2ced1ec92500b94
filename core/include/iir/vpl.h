/* vpl.h -- virtual point lights: what a VPL is (shared by the incremental step, instant
 * radiosity and the renderer) and its cached visibility, the paraboloid shadow map. Not how VPLs
 * are chosen (incremental.h, methods/ir.c) or shaded (render.h).
 *
 * A VPL is a cosine emitter on a surface: it re-emits the flux `flux` it reflected, with radiant
 * intensity I(w) = flux / pi * max(0, n . w). A pixel at x with albedo rho_x and normal n_x
 * receives from it
 *     L(x) = (rho_x / pi) (flux / pi) max(0, n . w) max(0, -n_x . w) V(x) / d^2,  w = (x - p) / d.
 *
 * The shadow map stores, for directions in the hemisphere about n (paraboloid parametrisation,
 * Heidrich & Seidel 1998), the distance from the VPL to the first surface. The scene is static, so
 * a map is rendered once when its VPL is born and kept until the VPL dies. */
#ifndef IIR_VPL_H
#define IIR_VPL_H

#include <stdbool.h>
#include <stdint.h>
#include <stdlib.h>

#include "iir/rt.h"
#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- the shadow map ---- */

typedef struct iir_smap {
    int res;         /* res x res texels; 0 = not rendered */
    uint16_t *depth; /* per texel, the distance to the first hit over scale as a half float
                        (half.h), +infinity where the ray escaped */
    float scale;     /* a power of two (iir_smap_scale): depth[i] * scale is the distance */
    uint64_t stamp;  /* which rendering the texels are: unique to each (iir_smap_next_stamp); 0 for
                        maps filled by other means, which the renderer never reuses work for */
    bool coarse;     /* rendered below the asked resolution to bound a frame's cost, to be rendered
                        again at it when a frame has room (iir_smaps_build_budget) */
} iir_smap;

/* Frees the map's texels (allocated with malloc by the shadow-map renderer) and marks it not
 * rendered. Whoever removes a VPL calls this. */
static inline void iir_smap_release(iir_smap *m)
{
    free(m->depth);
    m->depth = NULL;
    m->res = 0;
}

/* Paraboloid map of the hemisphere about +z: local direction d (d.z >= 0) <-> texel coordinates
 * in [0, 1)^2: (u, v) = ((d.x / (1 + d.z) + 1) / 2, (d.y / (1 + d.z) + 1) / 2). */
static inline iir_vec2 iir_paraboloid_uv(iir_vec3 d)
{
    float k = 1.f / (1.f + d.z);
    return iir_v2(0.5f * (d.x * k + 1.f), 0.5f * (d.y * k + 1.f));
}
static inline iir_vec3 iir_paraboloid_dir(iir_vec2 uv)
{
    float x = 2.f * uv.x - 1.f, y = 2.f * uv.y - 1.f;
    float r2 = x * x + y * y;
    return iir_scale(iir_v3(2.f * x, 2.f * y, 1.f - r2), 1.f / (1.f + r2));
}

/* ---- the VPL ---- */

/* How a VPL sends its light on: diffuse (its flux over pi, times the cosine), or by the glossy
 * metallic-roughness BSDF of the surface it lies on (iir_bsdf_params_glossy), toward each
 * receiver f(wi, w) pi / albedo times that (render_indirect.c). */
typedef struct iir_vpl_lobe {
    bool glossy;
    float metallic, roughness, f0; /* f0: a dielectric's reflectance at normal incidence */
    iir_vec3 base;                 /* base colour */
} iir_vpl_lobe;

typedef struct iir_vpl {
    uint32_t id;        /* unique within its set for the set's whole life; never reused */
    bool null_sample;   /* the light's ray escaped or hit an emitter: holds its place, no light */
    iir_vec3 position;  /* on the surface */
    iir_vec3 normal;    /* unit, on the side the light arrived from */
    iir_frame frame;    /* iir_frame_from_normal(normal): the shadow map's axes */
    iir_vec3 albedo;    /* rho at the VPL: the diffuse albedo, or for a glossy lobe c_diff + F0
                           (kept off zero), which its lobe divides back out */
    iir_vec3 flux;      /* Phi_i, the flux it re-emits (W, RGB): the flux arriving times albedo */
    iir_vpl_lobe lobe;  /* diffuse unless lobe.glossy */
    iir_vec3 wi;        /* glossy lobe: unit, toward where its light arrived from (kept up to date
                           as the light moves: iir's weighing); unused otherwise */
    iir_vec2 disk;      /* its point in its light's domain (incremental step only) */
    iir_vec2 emit;      /* area light: where on the emitter its birth ray started, in light-local
                           coordinates [-1/2, 1/2]^2 (incremental step only) */
    uint32_t birth;     /* frame number it was created in */
    uint32_t key;       /* interleave key: its subset is render.h's iir_vpl_subset_of; 0 (every
                           set but iir's) for one from the id's hash */
    uint8_t generation; /* 0: lit by the light; k: k diffuse bounces further along its light path
                           (ir's later path vertices, iir's descendants: lineage.h) */
    iir_smap smap;      /* owned by whoever owns the VPL */
} iir_vpl;

/* The interleave key of VPL `id` when it has none of its own: Fibonacci hashing of the id. */
static inline uint32_t iir_id_key(uint32_t id)
{
    return id * 2654435769u;
}

/* A key's interleaving subset among n2: the key scaled onto [0, n2). */
static inline uint32_t iir_key_subset(uint32_t key, uint32_t n2)
{
    return (uint32_t)(((uint64_t)key * n2) >> 32);
}

/* Fills the frame from the normal. */
static inline void iir_vpl_set_normal(iir_vpl *v, iir_vec3 n)
{
    v->normal = n;
    v->frame = iir_frame_from_normal(n);
}

/* ---- a frame's bookkeeping of a VPL set ---- */

/* How a VPL set changed in one frame: what the incremental step reports (iir_incr_stats) and what
 * every method reports in its frame stats (iir_frame_stats; zero for methods without VPLs). The
 * fields marked (iir) are zero for instant radiosity, which draws a new set every frame. */
typedef struct iir_vpl_counts {
    uint32_t count;        /* VPLs in the set after the frame, null samples included */
    uint32_t valid;        /* survived validation, before deletion or a regeneration (iir) */
    uint32_t invalidated;  /* removed by validation, or coincided with an older VPL (iir) */
    uint32_t deleted;      /* removed along the shortest Delaunay edges, or survivors discarded by
                              a regeneration (iir) */
    uint32_t inserted;     /* new this frame (N after a regeneration; all of them for ir) */
    uint32_t null_samples; /* in the set: domain points whose rays escaped or hit an emitter */
    uint32_t regenerated;  /* 1 when the whole set was regenerated this frame */
    uint32_t shadowmaps;   /* shadow maps rendered this frame */
    uint32_t descendants;  /* iir with bounces > 2: VPLs of later bounces carried by the set's
                              (not in count; ir counts every bounce's VPLs in count) */
} iir_vpl_counts;

#ifdef __cplusplus
}
#endif
#endif

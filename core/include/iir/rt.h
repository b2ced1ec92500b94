/* rt.h -- rays through the static scene with Embree 3: building the BVH, closest hit and occlusion
 * for single rays and 8-wide packets, and counting rays by kind. Not shading.
 *
 * Thread safety: an iir_rt is read-only after creation and may be traced from any number of
 * threads. Counting is the caller's: each trace call adds to an iir_raystats the caller owns
 * (keep one per thread and sum them after the parallel loop), so there is no shared counter. */
#ifndef IIR_RT_H
#define IIR_RT_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/status.h"
#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

struct iir_scene;

#define IIR_NO_HIT UINT32_MAX

typedef enum iir_ray_kind {
    IIR_RAYS_CAMERA,     /* primary rays from the camera */
    IIR_RAYS_SHADOW,     /* direct-light occlusion */
    IIR_RAYS_BOUNCE,     /* path continuation / light random walks */
    IIR_RAYS_VPL,        /* VPL creation and validation */
    IIR_RAYS_SHADOWMAP,  /* rendering VPL shadow maps */
    IIR_RAYS_VISIBILITY, /* exact VPL-to-pixel occlusion */
    IIR_RAYS_BENCH,      /* micro-benchmarks */
    IIR_RAY_KIND_COUNT
} iir_ray_kind;

typedef struct iir_raystats {
    uint64_t n[IIR_RAY_KIND_COUNT];
} iir_raystats;

typedef struct iir_ray {
    iir_vec3 org;
    float tnear;
    iir_vec3 dir; /* need not be unit length; t is in units of |dir| */
    float tfar;
} iir_ray;

typedef struct iir_hit {
    float t;
    uint32_t prim; /* triangle index in the scene, IIR_NO_HIT on a miss */
    float u, v;    /* barycentrics of the hit */
} iir_hit;

/* Eight rays in structure-of-arrays layout; lanes with valid[i] == 0 are ignored. */
typedef struct iir_ray8 {
    float ox[8], oy[8], oz[8];
    float dx[8], dy[8], dz[8];
    float tnear[8], tfar[8];
    int valid[8];
} iir_ray8;

/* Lane k of a packet set to the segment (tnear 0, tfar) along dir from org, valid. */
static inline void iir_ray8_set(iir_ray8 *rays, int k, iir_vec3 org, iir_vec3 dir, float tfar)
{
    rays->ox[k] = org.x, rays->oy[k] = org.y, rays->oz[k] = org.z;
    rays->dx[k] = dir.x, rays->dy[k] = dir.y, rays->dz[k] = dir.z;
    rays->tnear[k] = 0.f;
    rays->tfar[k] = tfar;
    rays->valid[k] = 1;
}

typedef struct iir_rt iir_rt;

/* Builds a high-quality BVH over the scene's triangles. The scene must outlive the rt.
 * On error returns a status with Embree's message and leaves *out NULL. */
iir_status iir_rt_create(const struct iir_scene *scene, iir_rt **out, iir_error *err);
void iir_rt_destroy(iir_rt *rt);

static inline iir_ray iir_make_ray(iir_vec3 org, iir_vec3 dir, float tnear, float tfar)
{
    iir_ray r = {org, tnear, dir, tfar};
    return r;
}

/* Closest hit. Returns true on a hit and fills *hit (hit->prim = IIR_NO_HIT otherwise). */
bool iir_rt_intersect(const iir_rt *rt, const iir_ray *ray, iir_hit *hit, iir_raystats *st,
                      iir_ray_kind kind);

/* Any hit in (tnear, tfar). */
bool iir_rt_occluded(const iir_rt *rt, const iir_ray *ray, iir_raystats *st, iir_ray_kind kind);

/* The same with alphaMode BLEND surfaces as stochastic transparency (pt): such a surface lets the
 * ray through with probability 1 - alpha, one coin per (key, triangle) -- a path's rays draw their
 * keys from its random stream. The queries above treat BLEND as a cut-out at alpha 0.5. */
bool iir_rt_intersect_blend(const iir_rt *rt, const iir_ray *ray, uint64_t key, iir_hit *hit,
                            iir_raystats *st, iir_ray_kind kind);
bool iir_rt_occluded_blend(const iir_rt *rt, const iir_ray *ray, uint64_t key, iir_raystats *st,
                           iir_ray_kind kind);

/* Packets: coherent rays (camera tiles, shadow-map texels). hits[i].prim = IIR_NO_HIT for misses
 * and invalid lanes; occluded[i] = false for invalid lanes. */
void iir_rt_intersect8(const iir_rt *rt, const iir_ray8 *rays, iir_hit hits[8], iir_raystats *st,
                       iir_ray_kind kind);
void iir_rt_occluded8(const iir_rt *rt, const iir_ray8 *rays, bool occluded[8], iir_raystats *st,
                      iir_ray_kind kind);
/* Two packets of 8 as one of 16 (hits/occluded[8 h + k]: halves[h] lane k): Embree's 16-wide
 * traversal where the CPU has AVX-512. */
void iir_rt_intersect16(const iir_rt *rt, const iir_ray8 halves[2], iir_hit hits[16],
                        iir_raystats *st, iir_ray_kind kind);
void iir_rt_occluded16(const iir_rt *rt, const iir_ray8 halves[2], bool occluded[16],
                       iir_raystats *st, iir_ray_kind kind);

/* Offset for the origin of a ray leaving a surface, relative to the scene's extent. */
float iir_rt_epsilon(const iir_rt *rt);

const char *iir_ray_kind_name(iir_ray_kind kind);
void iir_raystats_add(iir_raystats *into, const iir_raystats *from);
uint64_t iir_raystats_total(const iir_raystats *st);

#ifdef __cplusplus
}
#endif
#endif

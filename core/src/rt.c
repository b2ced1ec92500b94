/* rt.c -- the Embree 3 device and BVH over the scene's triangles, and every ray query the
 * renderer makes (single rays and 8-wide packets). Not shading, not sampling.
 *
 * One error callback on the device reports Embree failures to stderr; creation checks
 * rtcGetDeviceError once after the build instead of after every call. */
#include "iir/rt.h"

#include <embree3/rtcore.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "iir/rng.h"
#include "iir/scene.h"
#include "surface.h"

struct iir_rt {
    RTCDevice device;
    RTCScene scene;
    float epsilon;
};

static void on_embree_error(void *user, enum RTCError code, const char *msg)
{
    (void)user;
    fprintf(stderr, "iir: embree error %d: %s\n", (int)code, msg ? msg : "");
}

static void fill_buffers(RTCGeometry geom, const iir_scene *s)
{
    float *v = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       3 * sizeof(float), s->num_vertices);
    unsigned *ix = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           3 * sizeof(unsigned), s->num_triangles);
    if (v) memcpy(v, s->positions, sizeof(float) * 3 * s->num_vertices);
    if (ix) memcpy(ix, s->indices, sizeof(unsigned) * 3 * s->num_triangles);
}

/* A query's context: Embree's, and for the stochastic queries (iir_rt_intersect_blend) the key of
 * the ray's coin flips. The filter reads it back from args->context (its first member). */
typedef struct query_ctx {
    struct RTCIntersectContext rtc;
    uint64_t key;
    bool stochastic;
} query_ctx;

static query_ctx plain_ctx(void)
{
    query_ctx c;
    rtcInitIntersectContext(&c.rtc);
    c.key = 0;
    c.stochastic = false;
    return c;
}

/* plain_ctx for a packet of coherent rays. */
static query_ctx coherent_ctx(void)
{
    query_ctx c = plain_ctx();
    c.rtc.flags = RTC_INTERSECT_CONTEXT_FLAG_COHERENT;
    return c;
}

/* Alpha cut-outs (iir_surface_covers): a candidate hit on a hole is rejected, for closest hits
 * and occlusion alike, single rays and packets; under a stochastic query a BLEND surface lets the
 * ray through with probability 1 - alpha, one coin per ray and triangle (iir_surface_alpha).
 * Installed only on scenes that have cut-outs. */
static void cutout_filter(const struct RTCFilterFunctionNArguments *args)
{
    const iir_scene *s = args->geometryUserPtr;
    const query_ctx *q = (const query_ctx *)args->context;
    const unsigned N = args->N;
    /* RTCHitN in C: SoA blocks of N (Ng x, y, z, u, v, primID, ...), as rtcore_ray.h lays out */
    const float *hf = (const float *)args->hit;
    const unsigned *hu = (const unsigned *)args->hit;
    for (unsigned i = 0; i < N; i++) {
        if (!args->valid[i]) continue;
        unsigned prim = hu[5 * N + i];
        float u = hf[3 * N + i], v = hf[4 * N + i];
        if (q->stochastic && iir_surface_blends(s, prim)) {
            float coin = (float)(iir_hash3(q->key, prim, 0xb1e4d) >> 40) * 0x1p-24f;
            if (coin >= iir_surface_alpha(s, prim, u, v)) args->valid[i] = 0;
        } else if (!iir_surface_covers(s, prim, u, v)) {
            args->valid[i] = 0;
        }
    }
}

static void set_cutouts(RTCGeometry geom, const iir_scene *s)
{
    if (!iir_scene_has_cutouts(s)) return;
    rtcSetGeometryUserData(geom, (void *)s);
    rtcSetGeometryIntersectFilterFunction(geom, cutout_filter);
    rtcSetGeometryOccludedFilterFunction(geom, cutout_filter);
}

static float scene_epsilon(const iir_scene *s)
{
    float diag = iir_length(iir_sub(s->bounds_max, s->bounds_min));
    float m = fmaxf(iir_max_comp(iir_v3(fabsf(s->bounds_max.x), fabsf(s->bounds_max.y),
                                        fabsf(s->bounds_max.z))),
                    iir_max_comp(iir_v3(fabsf(s->bounds_min.x), fabsf(s->bounds_min.y),
                                        fabsf(s->bounds_min.z))));
    return fmaxf(1e-5f * diag, 4e-6f * m) + 1e-7f;
}

iir_status iir_rt_create(const iir_scene *s, iir_rt **out, iir_error *err)
{
    *out = NULL;
    if (s->num_triangles == 0)
        return iir_fail(err, IIR_ERR_INVALID, "scene '%s' has no triangles to trace", s->name);
    iir_rt *rt = calloc(1, sizeof *rt);
    if (!rt) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating the ray tracer");
    rt->device = rtcNewDevice(NULL);
    if (!rt->device) {
        free(rt);
        return iir_fail(err, IIR_ERR_INTERNAL, "embree: cannot create a device (error %d)",
                        (int)rtcGetDeviceError(NULL));
    }
    rtcSetDeviceErrorFunction(rt->device, on_embree_error, NULL);
    rt->scene = rtcNewScene(rt->device);
    rtcSetSceneBuildQuality(rt->scene, RTC_BUILD_QUALITY_HIGH);
    RTCGeometry geom = rtcNewGeometry(rt->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    fill_buffers(geom, s);
    set_cutouts(geom, s);
    rtcCommitGeometry(geom);
    rtcAttachGeometry(rt->scene, geom);
    rtcReleaseGeometry(geom);
    rtcCommitScene(rt->scene);
    enum RTCError e = rtcGetDeviceError(rt->device);
    if (e != RTC_ERROR_NONE) {
        iir_rt_destroy(rt);
        return iir_fail(err, IIR_ERR_INTERNAL,
                        "embree: building the BVH for '%s' failed (error %d)", s->name, (int)e);
    }
    rt->epsilon = scene_epsilon(s);
    *out = rt;
    return IIR_OK;
}

void iir_rt_destroy(iir_rt *rt)
{
    if (!rt) return;
    if (rt->scene) rtcReleaseScene(rt->scene);
    if (rt->device) rtcReleaseDevice(rt->device);
    free(rt);
}

float iir_rt_epsilon(const iir_rt *rt)
{
    return rt->epsilon;
}

/* ---- single rays ---- */

static void set_ray(struct RTCRay *r, const iir_ray *ray)
{
    r->org_x = ray->org.x;
    r->org_y = ray->org.y;
    r->org_z = ray->org.z;
    r->tnear = ray->tnear;
    r->dir_x = ray->dir.x;
    r->dir_y = ray->dir.y;
    r->dir_z = ray->dir.z;
    r->time = 0.f;
    r->tfar = ray->tfar;
    r->mask = UINT32_MAX;
    r->id = 0;
    r->flags = 0;
}

static inline void count(iir_raystats *st, iir_ray_kind kind, uint64_t n)
{
    if (st) st->n[kind] += n;
}

static bool intersect(const iir_rt *rt, query_ctx *ctx, const iir_ray *ray, iir_hit *hit,
                      iir_raystats *st, iir_ray_kind kind)
{
    struct RTCRayHit rh;
    set_ray(&rh.ray, ray);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(rt->scene, &ctx->rtc, &rh);
    count(st, kind, 1);
    bool found = rh.hit.geomID != RTC_INVALID_GEOMETRY_ID;
    hit->t = found ? rh.ray.tfar : INFINITY;
    hit->prim = found ? rh.hit.primID : IIR_NO_HIT;
    hit->u = rh.hit.u;
    hit->v = rh.hit.v;
    return found;
}

static bool occluded(const iir_rt *rt, query_ctx *ctx, const iir_ray *ray, iir_raystats *st,
                     iir_ray_kind kind)
{
    struct RTCRay r;
    set_ray(&r, ray);
    rtcOccluded1(rt->scene, &ctx->rtc, &r);
    count(st, kind, 1);
    return r.tfar < 0.f; /* Embree sets tfar to -inf on a hit */
}

bool iir_rt_intersect(const iir_rt *rt, const iir_ray *ray, iir_hit *hit, iir_raystats *st,
                      iir_ray_kind kind)
{
    query_ctx c = plain_ctx();
    return intersect(rt, &c, ray, hit, st, kind);
}

bool iir_rt_occluded(const iir_rt *rt, const iir_ray *ray, iir_raystats *st, iir_ray_kind kind)
{
    query_ctx c = plain_ctx();
    return occluded(rt, &c, ray, st, kind);
}

bool iir_rt_intersect_blend(const iir_rt *rt, const iir_ray *ray, uint64_t key, iir_hit *hit,
                            iir_raystats *st, iir_ray_kind kind)
{
    query_ctx c = plain_ctx();
    c.key = key, c.stochastic = true;
    return intersect(rt, &c, ray, hit, st, kind);
}

bool iir_rt_occluded_blend(const iir_rt *rt, const iir_ray *ray, uint64_t key, iir_raystats *st,
                           iir_ray_kind kind)
{
    query_ctx c = plain_ctx();
    c.key = key, c.stochastic = true;
    return occluded(rt, &c, ray, st, kind);
}

/* ---- packets of 8 ---- */

/* Lanes at .. at + 7 of Embree packet r (RTCRay8 or RTCRay16: the same fields) from p. */
#define SET_LANES(r, p, at, valid)                                                                 \
    for (int k_ = 0; k_ < 8; k_++) {                                                               \
        int i_ = (at) + k_;                                                                        \
        (valid)[i_] = (p)->valid[k_] ? -1 : 0;                                                     \
        (r)->org_x[i_] = (p)->ox[k_], (r)->org_y[i_] = (p)->oy[k_], (r)->org_z[i_] = (p)->oz[k_];  \
        (r)->dir_x[i_] = (p)->dx[k_], (r)->dir_y[i_] = (p)->dy[k_], (r)->dir_z[i_] = (p)->dz[k_];  \
        (r)->tnear[i_] = (p)->tnear[k_], (r)->tfar[i_] = (p)->tfar[k_];                            \
        (r)->time[i_] = 0.f, (r)->mask[i_] = UINT32_MAX;                                           \
        (r)->id[i_] = (unsigned)i_, (r)->flags[i_] = 0;                                            \
    }

static void set_ray8(struct RTCRay8 *r, const iir_ray8 *p, int valid[8])
{
    SET_LANES(r, p, 0, valid);
}

/* Two packets of 8 as Embree's packet of 16 r (RTCRay16, or RTCRayHit16's ray). */
static void set_ray16(struct RTCRay16 *r, const iir_ray8 halves[2], int valid[16])
{
    SET_LANES(r, &halves[0], 0, valid);
    SET_LANES(r, &halves[1], 8, valid);
}

static uint64_t count_valid(const int valid[8])
{
    uint64_t n = 0;
    for (int i = 0; i < 8; i++) n += valid[i] != 0;
    return n;
}

/* hits[0 .. n) from Embree packet rh (RTCRayHit8 or RTCRayHit16: the same fields). */
#define GET_HITS(rh, valid, n, hits)                                                               \
    for (int i_ = 0; i_ < (n); i_++) {                                                             \
        bool found_ = (valid)[i_] && (rh)->hit.geomID[i_] != RTC_INVALID_GEOMETRY_ID;              \
        (hits)[i_].t = found_ ? (rh)->ray.tfar[i_] : INFINITY;                                     \
        (hits)[i_].prim = found_ ? (rh)->hit.primID[i_] : IIR_NO_HIT;                              \
        (hits)[i_].u = (rh)->hit.u[i_];                                                            \
        (hits)[i_].v = (rh)->hit.v[i_];                                                            \
    }

void iir_rt_intersect8(const iir_rt *rt, const iir_ray8 *rays, iir_hit hits[8], iir_raystats *st,
                       iir_ray_kind kind)
{
    query_ctx ctx = coherent_ctx(); /* the filter reads the whole of it */
    struct RTCRayHit8 rh;
    _Alignas(32) int valid[8]; /* rtcIntersect8 wants its mask 32-byte aligned */
    set_ray8(&rh.ray, rays, valid);
    for (int i = 0; i < 8; i++) rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect8(valid, rt->scene, &ctx.rtc, &rh);
    count(st, kind, count_valid(valid));
    GET_HITS(&rh, valid, 8, hits);
}

void iir_rt_intersect16(const iir_rt *rt, const iir_ray8 halves[2], iir_hit hits[16],
                        iir_raystats *st, iir_ray_kind kind)
{
    query_ctx ctx = coherent_ctx();
    struct RTCRayHit16 rh;
    _Alignas(64) int valid[16];
    set_ray16(&rh.ray, halves, valid);
    for (int i = 0; i < 16; i++) rh.hit.geomID[i] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect16(valid, rt->scene, &ctx.rtc, &rh);
    count(st, kind, count_valid(valid) + count_valid(valid + 8));
    GET_HITS(&rh, valid, 16, hits);
}

void iir_rt_occluded8(const iir_rt *rt, const iir_ray8 *rays, bool occluded[8], iir_raystats *st,
                      iir_ray_kind kind)
{
    query_ctx ctx = coherent_ctx(); /* the filter reads the whole of it */
    struct RTCRay8 r;
    _Alignas(32) int valid[8]; /* as rtcOccluded8 wants it */
    set_ray8(&r, rays, valid);
    rtcOccluded8(valid, rt->scene, &ctx.rtc, &r);
    count(st, kind, count_valid(valid));
    for (int i = 0; i < 8; i++) occluded[i] = valid[i] && r.tfar[i] < 0.f;
}

void iir_rt_occluded16(const iir_rt *rt, const iir_ray8 halves[2], bool occluded[16],
                       iir_raystats *st, iir_ray_kind kind)
{
    query_ctx ctx = coherent_ctx();
    struct RTCRay16 r;
    _Alignas(64) int valid[16];
    set_ray16(&r, halves, valid);
    rtcOccluded16(valid, rt->scene, &ctx.rtc, &r);
    count(st, kind, count_valid(valid) + count_valid(valid + 8));
    for (int i = 0; i < 16; i++) occluded[i] = valid[i] && r.tfar[i] < 0.f;
}

/* ---- counters ---- */

const char *iir_ray_kind_name(iir_ray_kind kind)
{
    static const char *names[IIR_RAY_KIND_COUNT] = {"camera",    "shadow",     "bounce", "vpl",
                                                    "shadowmap", "visibility", "bench"};
    return kind < IIR_RAY_KIND_COUNT ? names[kind] : "unknown";
}

void iir_raystats_add(iir_raystats *into, const iir_raystats *from)
{
    for (int k = 0; k < IIR_RAY_KIND_COUNT; k++) into->n[k] += from->n[k];
}

uint64_t iir_raystats_total(const iir_raystats *st)
{
    uint64_t t = 0;
    for (int k = 0; k < IIR_RAY_KIND_COUNT; k++) t += st->n[k];
    return t;
}

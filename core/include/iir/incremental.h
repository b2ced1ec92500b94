/* incremental.h -- the incremental instant radiosity step (DESIGN.md section 5): a set of VPLs for
 * one light that is kept across frames, validated, thinned and refilled on the light's domain
 * (light_domain.h: a cosine or glTF spot's disk, a point light's sphere, the sun's disk), and
 * weighted so that it carries the light's flux. Not shadow maps (shadowmap.h) and not
 * shading (render.h); the caller renders a map for every VPL whose smap.res is 0.
 *
 * The text below says "the disk" and "circle"; on a point light's sphere read the sphere, geodesic
 * lengths and spherical caps, and no edge margin. p is the light's position, or for the sun the
 * point of its plane behind x (iir_domain_origin).
 *
 * ONE FRAME (iir_incr_update), phase by phase, with the choices this implementation makes:
 *   REPROJECT   Every VPL's domain point is recomputed from its world position x for the new
 *               frame (iir_domain_locate, in double precision; for a cosine spot (p; r, u, f):
 *               w = (x - p) / |x - p|, s = (w.r, w.u)). A null sample has no surface; it keeps the
 *               unit world direction w of the ray that escaped (or hit an emitter) -- a point at
 *               infinity -- or, for the sun, the point where that ray left the sun's sphere, and is
 *               reprojected from that (iir_domain_locate_null).
 *   VALIDATE    A VPL stays when (a) it is strictly inside the domain (for a spot: in front of it,
 *               w.f > 0, and |s| < R); (b) it faces the light: normal . (p - x) > 0; (c) the
 *               segment p -> x is unoccluded: one occlusion ray (IIR_RAYS_VPL) from p with
 *               dir = x - p, tnear 0, tfar = 1 - iir_rt_epsilon / |x - p|.
 *               A null sample stays when (a) holds for it and a closest-hit ray from p along w
 *               (iir_domain_null_ray) would again give a null sample (a miss, an emitter, or a
 *               grazing hit); it is dropped when that ray now finds a reflecting surface (the light
 *               moved), so the hole is refilled by a real VPL. Dropped VPLs' maps are released.
 *   REGENERATE  When more than regen_threshold of the previous set died in VALIDATE (invalidated >
 *               regen_threshold * count_prev), when VPLs died this frame and the survivors are
 *               fewer than (1 - regen_threshold) * N (deaths spread over frames that k_max
 *               insertions a frame could not refill) -- N here is the smaller of N and the
 *               largest count since the last regeneration, so a raised N fills gradually --, when
 * the set is empty (always so on the first update), when the light is of another kind than at the
 * last update (another domain), or when the ids run out (see THE SET), the survivors are discarded
 * too (counted as `deleted`) and N new VPLs are made from the Hammersley set
 *               ((i / N + o1) mod 1, (phi_2(i) + o2) mod 1), i < N, Cranley-Patterson rotated by
 *               offsets o drawn from (seed, number of regenerations so far), mapped to the disk by
 *               the concentric map and shrunk by (1 - IIR_INCR_EDGE_MARGIN) (the sphere: the
 *               uniform map). Each gets one closest-hit ray. `regenerated` is 1, except on the
 * first update (`initial` is 1). Such a frame skips DELETE. TRIANGULATE The Delaunay triangulation
 * of all domain points is rebuilt (iir_tri_build or iir_stri_build, ids as vertex info). A VPL
 * whose domain point coincides exactly with an older one's is dropped and counted in `invalidated`
 * (it is not in `valid`). DELETE      While invalidated + deleted < k_min, or count > N: remove the
 * endpoint of the shortest Delaunay edge in the denser neighbourhood (ties: the younger, larger id;
 *               see tri.h), updating the triangulation. Stops at one remaining site. So, with
 *               v = valid: deleted = min(max(k_min - invalidated, v - N, 0), max(v, 1) - 1).
 *   INSERT      While count < N and inserted < k_max (after a regeneration: while count < N; with
 *               `refill`, while inserted < max(k_max, invalidated + deleted): what the frame
 *               removed is replaced in it, so a set at N stays at N; and then, up to k_max
 *               more, while an empty circle is wider than IIR_INCR_HOLE cells -- a hole the
 *               light swept into or uncovered -- a VPL goes there and the most crowded one is
 *               deleted, counted in inserted and deleted): take
 *               the largest empty circle's centre c (tri.h), pull it inside the disk to at most
 *               R (1 - IIR_INCR_EDGE_MARGIN) so that float directions stay strictly inside the
 *               cone, cast one closest-hit ray from p along its direction. A hit on a non-emissive
 *               surface whose normal, flipped to the light's side, faces p becomes a VPL
 *               (position from barycentrics, that normal, the material's albedo, its domain
 *               point the reprojection of that position). A miss, an emitter, a grazing hit, or a
 * hit whose reprojection rounding put outside the cone becomes a null sample (direction w, albedo
 * and flux 0). It joins the triangulation before the next circle is chosen. If its point is not
 * strictly inside the disk or is already taken (only when the domain is saturated), insertion stops
 * for this frame. WEIGH       Phi_i = I * rho_i * A_i * profile(s_i) per RGB channel: I the light's
 * intensity (I0, or the sun's E), profile its flux per unit domain area (iir_domain_profile; for a
 * cosine spot the smooth edge's falloff, so this is Phi_light * rho_i * A_i / (pi R^2) with
 * Phi_light = pi I0 R^2). A_i is the Voronoi cell clipped to the domain (IIR_WEIGHTS_VORONOI; the
 * A_i tile it) or the domain's area / count, count including null samples (IIR_WEIGHTS_UNIFORM).
 * Null samples have flux 0. Recomputed for every VPL every frame.
 *
 * THE SET. iir_incr_vpls returns the VPLs sorted by ascending id. Ids start at 0 and increase by
 * one per VPL ever created for the life of the iir_incr (regenerations included); an id is never
 * reused -- except that after 2^32 - N - k_max VPLs a regeneration restarts them at 0 (every
 * older VPL is gone by then). `birth` is the index of the update that created the VPL (the first
 * update is 0). For a null sample, `position` is the light's position at its birth (the sun: where
 * its ray left the sun's sphere), `normal` (and `frame`) the unit world direction of its ray,
 * `albedo` and `flux` 0; it needs no shadow map. `disk` is the domain point's x and y.
 *
 * STATS. count_prev - invalidated - deleted + inserted == count, on every frame. `valid` is the
 * number that survived VALIDATE (and TRIANGULATE), before DELETE or a regeneration.
 *
 * Deterministic: the same parameters, seed and sequence of lights give bitwise identical sets
 * (Embree and libiirtri answer independently of thread count; ties are broken by id).
 * Threads: an iir_incr is used by one thread at a time; it shares the scene and rt read-only.
 * Memory: buffers are sized for max(N, count) and reused; only a larger N (iir_incr_set_params) or
 * a new cone angle (a new triangulation handle) allocates outside libiirtri's own rebuilds. */
#ifndef IIR_INCREMENTAL_H
#define IIR_INCREMENTAL_H

#include <stdint.h>

#include "iir/light.h"
#include "iir/rt.h"
#include "iir/status.h"
#include "iir/vpl.h"

#ifdef __cplusplus
extern "C" {
#endif

struct iir_scene;
struct iir_tri;
struct iir_stri;

#define IIR_INCR_MAX_TARGET 16384u
/* New samples keep |s| <= R (1 - IIR_INCR_EDGE_MARGIN) so they stay strictly inside the cone when
 * their float world positions are reprojected. */
#define IIR_INCR_EDGE_MARGIN 1e-4
/* With refill, an empty circle wider than this times the radius of a cell of a set of N (sqrt of
 * the domain's area / (pi N)) is a hole: a VPL moves there from the most crowded place. */
#define IIR_INCR_HOLE 2.0

/* A VPL's share of the light's flux: the domain's area over the count (the paper's), its clipped
 * Voronoi cell, or that cell corrected where it reaches over another surface (surface_cells.h). */
typedef enum iir_weights {
    IIR_WEIGHTS_UNIFORM,
    IIR_WEIGHTS_VORONOI,
    IIR_WEIGHTS_SURFACE
} iir_weights;

typedef struct iir_incr_params {
    uint32_t target;       /* N, [1, IIR_INCR_MAX_TARGET], default 256 */
    uint32_t k_min, k_max; /* replacements per frame: k_max in [1, IIR_INCR_MAX_TARGET], k_min in
                              [0, k_max]; defaults 4 and 8 */
    iir_weights weights;   /* default IIR_WEIGHTS_SURFACE */
    float regen_threshold; /* regenerate when more than this fraction dies at once, (0, 1], 0.5 */
    uint64_t seed;         /* scrambles the Hammersley sets; default 1 */
    bool refill;           /* INSERT may exceed k_max to replace what this frame removed; false */
} iir_incr_params;

/* The defaults above. */
iir_incr_params iir_incr_params_default(void);

/* IIR_ERR_INVALID with a message naming the field (target, k_min, k_max, weights,
 * regen_threshold) when a value is out of range. */
iir_status iir_incr_params_validate(const iir_incr_params *p, iir_error *err);

typedef enum iir_incr_phase {
    IIR_INCR_REPROJECT,
    IIR_INCR_VALIDATE,
    IIR_INCR_TRIANGULATE,
    IIR_INCR_DELETE,
    IIR_INCR_INSERT, /* includes the rays of a regeneration */
    IIR_INCR_WEIGH,
    IIR_INCR_PHASE_COUNT
} iir_incr_phase;

/* Short name of a phase ("reproject", "validate", ...); "?" when out of range. */
const char *iir_incr_phase_name(iir_incr_phase phase);

typedef struct iir_incr_stats {
    iir_vpl_counts vpl; /* how the set changed (vpl.h); vpl.shadowmaps stays 0: the step renders
                           no maps. count - invalidated - deleted + inserted = the new count */
    uint32_t initial;   /* 1 on the first update: the set was created from nothing */
    double phase_ms[IIR_INCR_PHASE_COUNT], total_ms;
    iir_raystats rays; /* rays of this update (all IIR_RAYS_VPL) */
    double flux_in;    /* luminance (W) of the flux the light sends onto reflecting surfaces,
                          estimated from the set: sum over VPLs of I A_i profile(s_i), albedo not
                          applied (iir_vplsets splits budgets by it) */
} iir_incr_stats;

typedef struct iir_incr iir_incr;

/* An empty set for the scene traced by rt (both must outlive it); *p is copied. On error
 * (IIR_ERR_INVALID for bad parameters, IIR_ERR_NOMEM) returns the status and leaves *out NULL. */
iir_status iir_incr_create(const struct iir_scene *scene, const iir_rt *rt,
                           const iir_incr_params *p, iir_incr **out, iir_error *err);

/* Releases every VPL's shadow map and frees everything; NULL is a no-op. */
void iir_incr_destroy(iir_incr *inc);

/* One frame for the light's new pose (see ONE FRAME). st may be NULL; it is overwritten.
 * IIR_ERR_INVALID for a light that fails iir_light_validate: nothing changes. A light of another
 * kind than the last update's (another domain) regenerates the set.
 * IIR_ERR_NOMEM / IIR_ERR_INTERNAL (libiirtri failed): the set stays consistent -- every VPL is
 * still owned and valid for this pose -- but this frame's step may be incomplete. */
iir_status iir_incr_update(iir_incr *inc, const iir_light *light, iir_incr_stats *st,
                           iir_error *err);

/* The current set (null samples included, flagged), sorted by ascending id; *n gets its size.
 * Valid until the next update/set_params/destroy. The caller may write the VPLs' `smap` fields
 * (the renderer builds maps for new VPLs) but nothing else; maps are released by this module when
 * their VPL dies. */
iir_vpl *iir_incr_vpls(iir_incr *inc, uint32_t *n);

/* Replaces the parameters; they take effect at the next update (a smaller N deletes down to N in
 * that frame, a larger N fills by k_max per frame, a new seed changes the next regeneration).
 * IIR_ERR_INVALID leaves the old ones; IIR_ERR_NOMEM when a larger N cannot be allocated. */
iir_status iir_incr_set_params(iir_incr *inc, const iir_incr_params *p, iir_error *err);

/* The parameters in force (after set_params: the new ones). */
iir_incr_params iir_incr_get_params(const iir_incr *inc);

/* For drawing the domain: the triangulation of the current disk points (ids = VPL ids) on the
 * disk of radius R of the last update; NULL before the first update. Owned by inc, valid until the
 * next update/destroy; read it only with tri.h's const functions. */
const struct iir_tri *iir_incr_tri(const iir_incr *inc);

/* The same for a point light's sphere (stri.h); NULL before the first update or for a disk. */
const struct iir_stri *iir_incr_stri(const iir_incr *inc);

/* For drawing the domain: the domain points (x y z interleaved, stride 3; z = 0 on a disk; in
 * domain units of the last update's pose, so outside the disk for VPLs that left the cone) of the
 * VPLs the last update removed -- invalidated, then deleted (a regeneration's discarded survivors
 * included); *n gets their number, invalidated + deleted of that update. Valid until the next
 * update/destroy. */
const double *iir_incr_removed(const iir_incr *inc, uint32_t *n);

/* Bytes a step holds for a set of n VPLs besides the VPLs: its triangulation (~200 B a site), the
 * Delaunay graph and the surface-aware weights' counts. */
uint64_t iir_incr_memory(uint32_t n);

/* Updates so far; the VPLs the last update created have birth == iir_incr_updates - 1. */
uint32_t iir_incr_updates(const iir_incr *inc);

/* For progressive refinement: a fresh VPL set independent of the live one, made as a
 * regeneration makes it -- N points of a Hammersley set on the light's domain, rotated by offsets
 * from (seed, stream) (a family of streams apart from the regenerations' own), one closest-hit
 * ray each -- and weighted uniformly, Phi_i = I0 rho_i falloff(|s_i|) pi R^2 / count (the rotated
 * set is uniform on the disk, so this is unbiased). Written to out[0 .. *n) with ids 0 .. *n - 1,
 * birth iir_incr_updates - 1, no shadow maps; *n <= N (a point off the disk is skipped, as in a
 * regeneration). The live set, its triangulation and its counters are not touched; rays are
 * added to *rays (may be NULL). IIR_ERR_INVALID for a bad light or cap < N. */
iir_status iir_incr_sample_set(const iir_incr *inc, const iir_light *light, uint64_t stream,
                               iir_vpl *out, uint32_t cap, uint32_t *n, iir_raystats *rays,
                               iir_error *err);

#ifdef __cplusplus
}
#endif
#endif

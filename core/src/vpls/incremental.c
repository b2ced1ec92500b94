/* incremental.c -- the incremental instant radiosity step: owns a light's VPL set across
 * frames (creation, validation, deletion, insertion, weights, and the VPLs' lifetime including
 * releasing their shadow maps), the points each frame removed (for drawing the domain) and fresh
 * sets sampled apart from the live one (for refinement); not rendering the maps and not shading.
 *
 * Design. The set is an array sorted by ascending id (ids only grow, new VPLs are appended,
 * removals compact in place), so the triangulation's by-id answers (cell areas by ascending id)
 * line up with the array without a map, and a VPL is found by binary search. Next to it lives a
 * double-precision copy of every domain point (what the triangulation gets). The light's domain
 * (light_domain.h: the cosine or glTF spot's disk, the point light's sphere, the sun's disk) maps
 * points to rays and back; domain_sites.h triangulates them, whatever the shape. A frame is the
 * phases of DESIGN section 5 as visible blocks in iir_incr_update: reproject, validate,
 * (regenerate), triangulate, delete, insert, weigh. Every choice the header documents is made here:
 * null samples keep their world direction and are re-cast, new samples stay a margin inside the
 * disk edge, a birth and a validation use the same facing predicate so a still light never
 * invalidates its own VPLs. All buffers are sized for max(N, count) and reused across frames. */
#include "iir/incremental.h"

#include <assert.h>
#include <stdlib.h>
#include <string.h>

#include "iir/light_domain.h"
#include "iir/rng.h"
#include "iir/scene.h"
#include "iir/timer.h"
#include "lights/domain_sites.h"
#include "site_graph.h"
#include "surface.h"
#include "surface_cells.h"
#include "vpl_lobe.h"

struct iir_incr {
    const iir_scene *scene;
    const iir_rt *rt;
    iir_incr_params params;
    iir_sites sites;         /* the domain points of the current set, ids as vertex info */
    iir_vpl *vpls;           /* [count], ascending id */
    double *xy;              /* [3 cap]: vpls[i]'s domain point in double, xy[3i .. 3i + 2] */
    uint32_t *ids;           /* [cap] scratch: ids for the triangulation */
    double *areas;           /* [cap] scratch: clipped cell areas */
    unsigned char *alive;    /* [cap] scratch: VPLs kept by the phase running */
    double *removed;         /* [3 cap]: domain points of the VPLs the last update removed */
    uint32_t num_removed;    /* <= the count before that update <= cap */
    uint32_t count, cap;     /* cap >= max(room(params), count) */
    uint32_t next_id;        /* the id of the next VPL created */
    uint32_t frame;          /* updates so far: the birth of the VPLs made now */
    uint32_t generations;    /* Hammersley sets made so far: the scramble's stream */
    iir_domain_map map;      /* the last update's domain: another one regenerates the set */
    uint32_t reached;        /* the largest count since the last regeneration, at most N */
    iir_site_graph graph;    /* the set's Delaunay neighbours, rebuilt each frame after INSERT */
    iir_surface_cells cells; /* surface-aware weights' buffers */
};

/* The light's pose for one frame: its domain. */
typedef iir_light_domain pose;

/* What one ray from the light found: a VPL-to-be or a null sample. */
typedef struct sample {
    bool null_sample;
    iir_vec3 x, n, albedo; /* VPL: position, normal on the light's side, albedo */
    iir_vpl_lobe lobe;     /* VPL: how it reflects */
    iir_vec3 o, w;         /* the ray's origin and unit direction */
    iir_vec2 q;            /* area light: the origin's light-local point on the emitter */
} sample;

/* ==== parameters ============================================================================= */

iir_incr_params iir_incr_params_default(void)
{
    iir_incr_params p = {
        .target = 256,
        .k_min = 4,
        .k_max = 8,
        .weights = IIR_WEIGHTS_SURFACE,
        .regen_threshold = 0.5f,
        .seed = 1,
    };
    return p;
}

iir_status iir_incr_params_validate(const iir_incr_params *p, iir_error *err)
{
    if (p->target < 1 || p->target > IIR_INCR_MAX_TARGET)
        return iir_fail(err, IIR_ERR_INVALID, "incremental step: target (N) %u is outside [1, %u]",
                        p->target, IIR_INCR_MAX_TARGET);
    if (p->k_max < 1 || p->k_max > IIR_INCR_MAX_TARGET)
        return iir_fail(err, IIR_ERR_INVALID, "incremental step: k_max %u is outside [1, %u]",
                        p->k_max, IIR_INCR_MAX_TARGET);
    if (p->k_min > p->k_max)
        return iir_fail(err, IIR_ERR_INVALID, "incremental step: k_min %u is larger than k_max %u",
                        p->k_min, p->k_max);
    if (p->weights != IIR_WEIGHTS_UNIFORM && p->weights != IIR_WEIGHTS_VORONOI &&
        p->weights != IIR_WEIGHTS_SURFACE)
        return iir_fail(err, IIR_ERR_INVALID,
                        "incremental step: weights %d is not uniform, voronoi or surface",
                        (int)p->weights);
    if (!(p->regen_threshold > 0.f && p->regen_threshold <= 1.f))
        return iir_fail(err, IIR_ERR_INVALID,
                        "incremental step: regen_threshold %g is outside (0, 1]",
                        (double)p->regen_threshold);
    return IIR_OK;
}

const char *iir_incr_phase_name(iir_incr_phase phase)
{
    static const char *const names[IIR_INCR_PHASE_COUNT] = {"reproject", "validate", "triangulate",
                                                            "delete",    "insert",   "weigh"};
    return (unsigned)phase < IIR_INCR_PHASE_COUNT ? names[phase] : "?";
}

/* ==== lifetime =============================================================================== */

/* The VPLs a set of p holds at most within an update: N, and with refill the holes' VPLs before
 * the crowded ones go (phase_holes). */
static uint32_t room(const iir_incr_params *p)
{
    return p->target + (p->refill ? p->k_max : 0);
}

/* Makes room for cap VPLs; on failure the old buffers stay (realloc keeps them). */
static iir_status reserve(iir_incr *inc, uint32_t cap, iir_error *err)
{
    if (cap <= inc->cap) return IIR_OK;
    iir_vpl *v = realloc(inc->vpls, cap * sizeof *v);
    if (v) inc->vpls = v;
    double *xy = realloc(inc->xy, 3 * (size_t)cap * sizeof *xy);
    if (xy) inc->xy = xy;
    uint32_t *ids = realloc(inc->ids, cap * sizeof *ids);
    if (ids) inc->ids = ids;
    double *areas = realloc(inc->areas, cap * sizeof *areas);
    if (areas) inc->areas = areas;
    unsigned char *alive = realloc(inc->alive, cap);
    if (alive) inc->alive = alive;
    double *removed = realloc(inc->removed, 3 * (size_t)cap * sizeof *removed);
    if (removed) inc->removed = removed;
    if (!v || !xy || !ids || !areas || !alive || !removed)
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for %u VPLs", cap);
    inc->cap = cap;
    return IIR_OK;
}

iir_status iir_incr_create(const iir_scene *scene, const iir_rt *rt, const iir_incr_params *p,
                           iir_incr **out, iir_error *err)
{
    *out = NULL;
    iir_status st = iir_incr_params_validate(p, err);
    if (st != IIR_OK) return st;
    iir_incr *inc = calloc(1, sizeof *inc);
    if (!inc) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating the incremental step");
    inc->scene = scene;
    inc->rt = rt;
    inc->params = *p;
    st = reserve(inc, room(p), err);
    if (st != IIR_OK) {
        iir_incr_destroy(inc);
        return st;
    }
    *out = inc;
    return IIR_OK;
}

void iir_incr_destroy(iir_incr *inc)
{
    if (!inc) return;
    for (uint32_t i = 0; i < inc->count; i++) iir_smap_release(&inc->vpls[i].smap);
    iir_sites_free(&inc->sites);
    iir_site_graph_free(&inc->graph);
    iir_surface_cells_free(&inc->cells);
    free(inc->vpls);
    free(inc->xy);
    free(inc->ids);
    free(inc->areas);
    free(inc->alive);
    free(inc->removed);
    free(inc);
}

iir_status iir_incr_set_params(iir_incr *inc, const iir_incr_params *p, iir_error *err)
{
    iir_status st = iir_incr_params_validate(p, err);
    if (st == IIR_OK) st = reserve(inc, room(p), err);
    if (st == IIR_OK) inc->params = *p;
    return st;
}

iir_incr_params iir_incr_get_params(const iir_incr *inc)
{
    return inc->params;
}

iir_vpl *iir_incr_vpls(iir_incr *inc, uint32_t *n)
{
    *n = inc->count;
    return inc->vpls;
}

const struct iir_tri *iir_incr_tri(const iir_incr *inc)
{
    return inc->sites.shape == IIR_DOMAIN_DISK ? inc->sites.tri : NULL;
}

const struct iir_stri *iir_incr_stri(const iir_incr *inc)
{
    return inc->sites.shape == IIR_DOMAIN_SPHERE ? inc->sites.stri : NULL;
}

/* ==== the domain ============================================================================= */

/* v's domain point for this frame's pose (a null sample's from its kept direction or anchor);
 * true when strictly inside. ps is already at v's point of an area light's emitter. */
static bool locate(const pose *ps, const iir_vpl *v, double s[3])
{
    return v->null_sample ? iir_domain_locate_null(ps, v->position, v->normal, s)
                          : iir_domain_locate(ps, v->position, s);
}

/* The pose as v sees it: an area light's domain from v's own point of the emitter (copied to
 * *at), any other light's as it is. */
static const pose *pose_of(const pose *ps, const iir_vpl *v, pose *at)
{
    if (ps->map != IIR_MAP_AREA_DISK) return ps;
    *at = iir_domain_at_emitter(ps, v->emit);
    return at;
}

static void set_disk(iir_vpl *v, const double s[3])
{
    v->disk = iir_v2((float)s[0], (float)s[1]);
}

/* ==== rays =================================================================================== */

/* The surface a closest hit of a ray along unit w found: true when it can hold a VPL (it reflects
 * and faces the light), false for an emitter or a grazing hit (a null sample). */
static bool hit_surface(const iir_incr *inc, const pose *ps, const iir_hit *hit, iir_vec3 w,
                        iir_surface *sf)
{
    *sf = iir_surface_at(inc->scene, hit, iir_neg(w));
    return iir_is_black(sf->Le) && iir_domain_faces(ps, sf->p, sf->ns);
}

/* One closest-hit ray from o along unit w: a VPL on a reflecting surface facing the light, or a
 * null sample (miss, emitter, grazing hit). */
static bool trace_surface(const iir_incr *inc, const pose *ps, iir_vec3 o, iir_vec3 w,
                          iir_raystats *rays, iir_surface *sf)
{
    iir_ray ray = iir_make_ray(o, w, 0.f, INFINITY);
    iir_hit hit;
    if (!iir_rt_intersect(inc->rt, &ray, &hit, rays, IIR_RAYS_VPL)) return false;
    return hit_surface(inc, ps, &hit, w, sf);
}

static sample trace_sample(const iir_incr *inc, const pose *ps, iir_vec3 o, iir_vec3 w,
                           iir_raystats *rays)
{
    sample sm = {.null_sample = true, .o = o, .w = w};
    iir_surface sf;
    if (!trace_surface(inc, ps, o, w, rays, &sf)) return sm;
    sm.null_sample = false;
    sm.x = sf.p;
    sm.n = sf.ns;
    sm.lobe = iir_vpl_lobe_at(&sf, &sm.albedo);
    return sm;
}

/* The ray for domain point s (from the emitter's point q of an area light), traced. */
static sample trace_point(const iir_incr *inc, const pose *ps, const double s[3], iir_vec2 q,
                          iir_raystats *rays)
{
    iir_vec3 o, w;
    pose at = iir_domain_at_emitter(ps, q);
    iir_domain_ray(&at, s, &o, &w);
    sample sm = trace_sample(inc, &at, o, w, rays);
    sm.q = q;
    return sm;
}

/* Whether the segment from the light to x is free (one occlusion ray, stopping short of x). */
static bool unoccluded(const iir_incr *inc, const pose *ps, iir_vec3 x, iir_raystats *rays)
{
    iir_vec3 o = iir_domain_origin(ps, x), d = iir_sub(x, o);
    float len = iir_length(d);
    float tfar = 1.f - iir_rt_epsilon(inc->rt) / len;
    if (!(tfar > 0.f)) return true; /* x is within epsilon of the light: nothing between */
    iir_ray ray = iir_make_ray(o, d, 0.f, tfar);
    return !iir_rt_occluded(inc->rt, &ray, rays, IIR_RAYS_VPL);
}

/* ==== the set ================================================================================ */

/* Index of the VPL with this id (the array is sorted by id); asserts that it exists. */
static uint32_t index_of(const iir_incr *inc, uint32_t id)
{
    return iir_site_index(inc->vpls, inc->count, id);
}

/* Keeps the VPLs with alive[i] set, in order; releases the others' maps and, when `record`,
 * appends their domain points to the removed list. Returns how many went. */
static uint32_t compact(iir_incr *inc, bool record)
{
    uint32_t kept = 0;
    for (uint32_t i = 0; i < inc->count; i++) {
        if (!inc->alive[i]) {
            iir_smap_release(&inc->vpls[i].smap);
            if (record && inc->num_removed < inc->cap)
                memcpy(&inc->removed[3 * inc->num_removed++], &inc->xy[3 * i], 3 * sizeof(double));
            continue;
        }
        inc->vpls[kept] = inc->vpls[i];
        memmove(&inc->xy[3 * kept], &inc->xy[3 * i], 3 * sizeof(double));
        kept++;
    }
    uint32_t gone = inc->count - kept;
    inc->count = kept;
    return gone;
}

/* Writes the VPL for sample sm into *v and its domain point into s (id 0): a VPL at the
 * reprojection of its position, or a null sample at that of its ray (also when the position fell
 * outside the domain). Returns false when even that is not strictly inside. */
static bool make_vpl(const pose *light, const sample *sm, uint32_t birth, iir_vpl *v, double s[3])
{
    memset(v, 0, sizeof *v);
    v->birth = birth;
    v->emit = sm->q;
    pose at;
    const pose *ps = pose_of(light, v, &at);
    if (!sm->null_sample && iir_domain_locate(ps, sm->x, s)) {
        v->position = sm->x;
        v->albedo = sm->albedo;
        v->lobe = sm->lobe;
        v->wi = iir_neg(sm->w);
        iir_vpl_set_normal(v, sm->n);
    } else {
        iir_vec3 dir;
        v->null_sample = true;
        iir_domain_null_pose(ps, sm->o, sm->w, &v->position, &dir);
        iir_vpl_set_normal(v, dir);
        if (!locate(ps, v, s)) return false;
    }
    set_disk(v, s);
    return true;
}

/* Writes the VPL for sample sm into slot `count` (not yet part of the set; see commit); false when
 * its point is not strictly inside the disk (see make_vpl). */
static bool stage(iir_incr *inc, const pose *ps, const sample *sm)
{
    assert(inc->count < inc->cap);
    return make_vpl(ps, sm, inc->frame, &inc->vpls[inc->count], &inc->xy[3 * inc->count]);
}

/* Makes the staged VPL part of the set and gives it the next id. */
static void commit(iir_incr *inc)
{
    inc->vpls[inc->count].id = inc->next_id++;
    inc->count++;
}

/* ==== the phases ============================================================================= */

/* REPROJECT: every domain point from the world position (null samples: the kept ray) for the new
 * frame; alive[i] says whether it is strictly inside the domain. */
static void phase_reproject(iir_incr *inc, const pose *ps)
{
    for (uint32_t i = 0; i < inc->count; i++) {
        iir_vpl *v = &inc->vpls[i];
        double *s = &inc->xy[3 * i];
        pose at;
        inc->alive[i] = locate(pose_of(ps, v, &at), v, s);
        set_disk(v, s);
    }
}

/* VALIDATE: inside the domain (from REPROJECT), facing the light and unoccluded; a null sample
 * stays while its ray would still give a null sample. Returns how many died. */
static uint32_t phase_validate(iir_incr *inc, const pose *light, iir_raystats *rays)
{
    for (uint32_t i = 0; i < inc->count; i++) {
        if (!inc->alive[i]) continue;
        const iir_vpl *v = &inc->vpls[i];
        pose at;
        const pose *ps = pose_of(light, v, &at);
        if (v->null_sample) {
            iir_vec3 o, w;
            iir_domain_null_ray(ps, v->position, v->normal, &o, &w);
            inc->alive[i] = trace_sample(inc, ps, o, w, rays).null_sample;
        } else {
            inc->alive[i] = iir_domain_faces(ps, v->position, v->normal) &&
                            unoccluded(inc, ps, v->position, rays);
        }
    }
    return compact(inc, true);
}

/* A Hammersley point (i / n, phi_2(i)) rotated by offsets o (Cranley-Patterson), in [0, 1)^2. */
static iir_vec2 hammersley(uint32_t i, uint32_t n, const double o[2])
{
    double u0 = (double)i / n + o[0], u1 = (double)iir_radical_inverse(2, i) + o[1];
    u0 -= floor(u0);
    u1 -= floor(u1);
    return iir_v2(fminf((float)u0, 0x1.fffffep-1f), fminf((float)u1, 0x1.fffffep-1f));
}

/* Whether the ids left before uint32_t wraps might not last this frame (after ~2^32 VPLs). */
static bool ids_exhausted(const iir_incr *inc)
{
    return inc->next_id > UINT32_MAX - inc->params.target - inc->params.k_max;
}

/* The traced ray of point i of n of a regeneration's Hammersley set rotated by o: mapped onto the
 * domain by area (a disk's shrunk by the edge margin); from the emitter's stratum k of an area
 * light. */
static sample regen_sample(const iir_incr *inc, const pose *ps, uint32_t i, uint32_t n,
                           const double o[2], uint32_t k, iir_raystats *rays)
{
    double s[3];
    iir_domain_sample(ps, hammersley(i, n, o), IIR_INCR_EDGE_MARGIN, s);
    return trace_point(inc, ps, s, iir_domain_emitter_stratum(ps, k), rays);
}

/* REGENERATE: discards the whole set and makes N new VPLs from a scrambled Hammersley set, one
 * ray each (ids restart at 0 only when they are exhausted). Returns how many were created. */
static uint32_t regenerate(iir_incr *inc, const pose *ps, iir_raystats *rays)
{
    memset(inc->alive, 0, inc->count);
    compact(inc, true);
    if (ids_exhausted(inc)) inc->next_id = 0;
    iir_rng rng = iir_rng_make(inc->params.seed, inc->generations++);
    double o[2] = {iir_rng_uniform(&rng), iir_rng_uniform(&rng)};
    uint32_t n = inc->params.target, made = 0;
    for (uint32_t i = 0; i < n; i++) {
        sample sm = regen_sample(inc, ps, i, n, o, inc->next_id, rays);
        if (!stage(inc, ps, &sm)) continue;
        commit(inc);
        made++;
    }
    return made;
}

static iir_status tri_fail(iir_tri_status ts, const char *what, iir_error *err)
{
    iir_status st = ts == IIR_TRI_NO_MEMORY ? IIR_ERR_NOMEM : IIR_ERR_INTERNAL;
    return iir_fail(err, st, "incremental step: %s failed in the triangulation (%s)", what,
                    iir_tri_status_name(ts));
}

/* TRIANGULATE: rebuilds the triangulation of all domain points (a new handle when the shape or a
 * disk's R changed). VPLs that coincide with an older one are dropped (recorded as removed when
 * `record`: they were in the set before this frame); *dropped gets how many. */
static iir_status phase_triangulate(iir_incr *inc, const pose *ps, bool record, uint32_t *dropped,
                                    iir_error *err)
{
    *dropped = 0;
    if (iir_sites_fit(&inc->sites, ps) != IIR_TRI_OK)
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating the triangulation");
    for (uint32_t i = 0; i < inc->count; i++) inc->ids[i] = inc->vpls[i].id;
    iir_tri_status ts = iir_sites_build(&inc->sites, inc->xy, inc->ids, inc->count);
    if (ts == IIR_TRI_OK) return IIR_OK;
    if (ts != IIR_TRI_DUPLICATE_POINT) return tri_fail(ts, "building", err);
    for (uint32_t i = 0; i < inc->count; i++)
        inc->alive[i] = (unsigned char)iir_sites_has(&inc->sites, inc->vpls[i].id);
    *dropped = compact(inc, record);
    return IIR_OK;
}

/* DELETE: while fewer than k_min replacements so far (`replaced` died already) or above N, remove
 * the denser endpoint of the shortest Delaunay edge (geodesic on the sphere). Returns the status;
 * *deleted gets how many. */
static iir_status phase_delete(iir_incr *inc, uint32_t replaced, uint32_t *deleted, iir_error *err)
{
    const iir_incr_params *p = &inc->params;
    uint32_t n = inc->count;
    memset(inc->alive, 1, inc->count);
    *deleted = 0;
    while (replaced + *deleted < p->k_min || n > p->target) {
        uint32_t id;
        iir_tri_status ts = iir_sites_shortest_edge(&inc->sites, &id);
        if (ts == IIR_TRI_TOO_FEW) break;
        if (ts == IIR_TRI_OK) ts = iir_sites_remove(&inc->sites, id);
        if (ts != IIR_TRI_OK) {
            compact(inc, true);
            return tri_fail(ts, "deleting", err);
        }
        inc->alive[index_of(inc, id)] = 0;
        (*deleted)++;
        n--;
    }
    compact(inc, true);
    return IIR_OK;
}

/* One VPL at the largest empty circle's (cap's) centre, pulled a margin inside a disk's edge, when
 * that circle is wider than r_min: a ray towards it, the VPL or null sample it gives joining the
 * triangulation. *added false when the circle is not wider, the set is empty (only when a
 * regeneration found nothing) or the domain saturated. */
static iir_status insert_one(iir_incr *inc, const pose *ps, double r_min, bool *added,
                             iir_raystats *rays, iir_error *err)
{
    double c[3], s[3], r;
    *added = false;
    iir_tri_status ts = iir_sites_largest_empty(&inc->sites, c, &r);
    if (ts == IIR_TRI_TOO_FEW || !(r > r_min)) return IIR_OK;
    if (ts != IIR_TRI_OK) return tri_fail(ts, "finding the largest empty circle", err);
    iir_domain_pull_inside(ps, c, IIR_INCR_EDGE_MARGIN, s);
    sample sm = trace_point(inc, ps, s, iir_domain_emitter_stratum(ps, inc->next_id), rays);
    if (!stage(inc, ps, &sm)) return IIR_OK; /* only for a cone too narrow for float directions */
    ts = iir_sites_insert(&inc->sites, &inc->xy[3 * inc->count], inc->next_id);
    if (ts == IIR_TRI_DUPLICATE_POINT || ts == IIR_TRI_OUTSIDE) return IIR_OK; /* saturated */
    if (ts != IIR_TRI_OK) return tri_fail(ts, "inserting", err);
    commit(inc);
    *added = true;
    return IIR_OK;
}

/* INSERT: while below N and below `limit` insertions, insert_one at any circle. */
static iir_status phase_insert(iir_incr *inc, const pose *ps, uint32_t limit, uint32_t *inserted,
                               iir_raystats *rays, iir_error *err)
{
    *inserted = 0;
    bool added = true;
    iir_status st = IIR_OK;
    while (st == IIR_OK && added && inc->count < inc->params.target && *inserted < limit) {
        st = insert_one(inc, ps, -1.0, &added, rays, err);
        *inserted += added;
    }
    return st;
}

/* HOLES (refill): while an empty circle is wider than IIR_INCR_HOLE times the radius of a cell of
 * a set of N (the part of the domain the light swept into, or uncovered, faster than the frame's
 * replacements), a VPL there, up to `limit`; then the most crowded ones (the shortest edges') go
 * until the set is back at N. A survivor's cell then stops growing over light its VPL does not
 * see. */
static iir_status phase_holes(iir_incr *inc, const pose *ps, uint32_t limit, uint32_t *inserted,
                              uint32_t *deleted, iir_raystats *rays, iir_error *err)
{
    double r_hole = IIR_INCR_HOLE * sqrt(ps->area / (IIR_PI * (double)inc->params.target));
    *inserted = *deleted = 0;
    bool added = true;
    iir_status st = IIR_OK;
    while (st == IIR_OK && added && *inserted < limit && inc->count < inc->cap) {
        st = insert_one(inc, ps, r_hole, &added, rays, err);
        *inserted += added;
    }
    if (st != IIR_OK || !*inserted) return st;
    return phase_delete(inc, inc->params.k_min, deleted, err); /* only the excess over N */
}

/* Phi = I rho A profile(s): the flux a VPL carries for a cell of area A at domain point s (I is
 * I0 or E, an area light's radiance at the VPL's own point of it; 0 for a null sample). */
static iir_vec3 cell_flux(const pose *ps, const iir_vpl *v, double A, const double s[3])
{
    if (v->null_sample) return iir_v3s(0.f);
    float k = (float)A * iir_domain_profile(ps, s);
    const iir_light *l = ps->light;
    iir_vec3 I = iir_light_emission_at(l, v->emit);
    return iir_scale(iir_mul(I, v->albedo), k);
}

/* A glossy VPL's lobe turns as the light moves: its light now arrives from the light's position
 * (an area light's: the VPL's own point of it; the sun's: along its direction). */
static void aim(const pose *light, iir_vpl *v)
{
    if (v->null_sample || !v->lobe.glossy) return;
    pose at;
    const pose *ps = pose_of(light, v, &at);
    iir_vec3 d = iir_sub(iir_domain_origin(ps, v->position), v->position);
    float len = iir_length(d);
    if (len > 0.f) v->wi = iir_scale(d, 1.f / len);
}

/* The light's ray for point j of the surface cells' pattern (surface_cells.h): an area light's
 * from the emitter's point of a hash of j, not the cell owner's. */
typedef struct cell_ctx {
    const iir_incr *inc;
    const pose *ps;
} cell_ctx;

/* Pattern point j's emitter stratum: a hash of j, independent of the cells. */
static pose cell_pose(const pose *ps, uint32_t j)
{
    return iir_domain_at_stratum(ps, (uint32_t)iir_mix64(0x5ce11ull << 32 | j));
}

static void cell_trace(void *ctx, const double (*s)[3], uint32_t j0, int m, iir_cell_hit *hits,
                       iir_raystats *rays)
{
    _Static_assert(IIR_CELL_BATCH == 16, "one packet of 16");
    const cell_ctx *c = ctx;
    iir_ray8 half[2];
    pose at[IIR_CELL_BATCH];
    iir_vec3 o[IIR_CELL_BATCH], w[IIR_CELL_BATCH];
    memset(half, 0, sizeof half);
    for (int q = 0; q < m; q++) {
        at[q] = cell_pose(c->ps, j0 + (uint32_t)q);
        iir_domain_ray(&at[q], s[q], &o[q], &w[q]);
        iir_ray8_set(&half[q / 8], q % 8, o[q], w[q], INFINITY);
    }
    iir_hit hit[IIR_CELL_BATCH];
    iir_rt_intersect16(c->inc->rt, half, hit, rays, IIR_RAYS_VPL);
    for (int q = 0; q < m; q++) {
        iir_surface sf;
        hits[q] = (iir_cell_hit){.null_sample = true};
        if (hit[q].prim != IIR_NO_HIT && hit_surface(c->inc, &at[q], &hit[q], w[q], &sf))
            hits[q] =
                (iir_cell_hit){.x = sf.p, .n = sf.ns, .dist = iir_length(iir_sub(sf.p, o[q]))};
    }
}

/* WEIGH: Phi_i = I rho_i A_i profile(s_i); A_i the clipped Voronoi cell (surface: corrected where
 * it reaches over another surface, surface_cells.h) or the domain's area / count. *flux_in gets the
 * luminance of sum I A_i profile(s_i) over the VPLs (null samples excluded): the flux the light
 * sends onto reflecting surfaces. */
static iir_status phase_weigh(iir_incr *inc, const pose *ps, double *flux_in, iir_raystats *rays,
                              iir_error *err)
{
    bool voronoi = inc->params.weights != IIR_WEIGHTS_UNIFORM;
    if (voronoi) {
        size_t n = 0;
        iir_tri_status ts = iir_sites_cell_areas(&inc->sites, inc->ids, inc->areas, inc->cap, &n);
        if (ts != IIR_TRI_OK) return tri_fail(ts, "computing cell areas", err);
        assert(n == inc->count);
    }
    if (inc->params.weights == IIR_WEIGHTS_SURFACE) {
        cell_ctx ctx = {inc, ps};
        iir_status st = iir_surface_cells_apply(&inc->cells, ps, inc->vpls, inc->xy, &inc->graph,
                                                cell_trace, &ctx, inc->areas, rays, err);
        if (st != IIR_OK) return st;
    }
    double uniform = ps->area / (inc->count ? inc->count : 1);
    for (uint32_t i = 0; i < inc->count; i++) {
        iir_vpl *v = &inc->vpls[i];
        assert(!voronoi || inc->ids[i] == v->id);
        double A = voronoi ? inc->areas[i] : uniform;
        v->flux = cell_flux(ps, v, A, &inc->xy[3 * i]);
        aim(ps, v);
        if (!v->null_sample) *flux_in += A * iir_domain_profile(ps, &inc->xy[3 * i]);
        assert(iir_is_finite3(v->flux) && v->flux.x >= 0.f && v->flux.y >= 0.f && v->flux.z >= 0.f);
    }
    return IIR_OK;
}

/* ==== one frame ============================================================================== */

static uint32_t count_null_samples(const iir_incr *inc)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < inc->count; i++) n += inc->vpls[i].null_sample;
    return n;
}

/* Adds the time since *t to phase ph and restarts *t. */
static void lap(iir_incr_stats *st, iir_incr_phase ph, double *t)
{
    double now = iir_now_ms();
    st->phase_ms[ph] += now - *t;
    *t = now;
}

iir_status iir_incr_update(iir_incr *inc, const iir_light *light, iir_incr_stats *out,
                           iir_error *err)
{
    pose ps;
    iir_status status = iir_light_domain_make(light, &ps, err);
    if (status != IIR_OK) return status;
    iir_incr_stats st;
    memset(&st, 0, sizeof st);
    iir_vpl_counts *c = &st.vpl;
    const iir_incr_params *p = &inc->params;
    uint32_t count_prev = inc->count, dropped = 0, limit = p->k_max;
    double t0 = iir_now_ms(), t = t0;
    inc->num_removed = 0;

    /* 1. reproject */
    phase_reproject(inc, &ps);
    lap(&st, IIR_INCR_REPROJECT, &t);

    /* 2. validate */
    c->invalidated = phase_validate(inc, &ps, &st.rays);
    c->valid = inc->count;
    lap(&st, IIR_INCR_VALIDATE, &t);

    /* fallback: regenerate when too many died at once, when VPLs are still dying and deaths spread
     * over frames (faster than k_max insertions refill) have left less than 1 - regen_threshold of
     * the target (a raised target alone fills gradually), when nothing is left, or when the ids
     * run out */
    double thr = (double)p->regen_threshold;
    uint32_t full = inc->reached < p->target ? inc->reached : p->target;
    bool dwindled = c->invalidated > 0 && (double)inc->count < (1.0 - thr) * (double)full;
    bool regen = inc->count == 0 || ids_exhausted(inc) || dwindled || ps.map != inc->map ||
                 (double)c->invalidated > thr * count_prev;
    if (regen) {
        st.initial = inc->frame == 0;
        c->regenerated = !st.initial;
        c->deleted = inc->count;
        c->inserted = regenerate(inc, &ps, &st.rays);
        limit = p->target;
        lap(&st, IIR_INCR_INSERT, &t);
    }

    /* 3. triangulate */
    status = phase_triangulate(inc, &ps, !regen, &dropped, err);
    c->invalidated += regen ? 0 : dropped;
    c->valid -= regen ? 0 : dropped;
    c->inserted -= regen ? dropped : 0;
    lap(&st, IIR_INCR_TRIANGULATE, &t);

    /* 4. delete */
    if (status == IIR_OK && !regen) status = phase_delete(inc, c->invalidated, &c->deleted, err);
    if (p->refill && !regen && c->invalidated + c->deleted > limit)
        limit = c->invalidated + c->deleted; /* what this frame removed comes back in it */
    lap(&st, IIR_INCR_DELETE, &t);

    /* 5. insert (with refill: and fill the holes) */
    uint32_t added = 0, moved = 0, trimmed = 0;
    if (status == IIR_OK) status = phase_insert(inc, &ps, limit, &added, &st.rays, err);
    if (status == IIR_OK && p->refill && !regen)
        status = phase_holes(inc, &ps, p->k_max, &moved, &trimmed, &st.rays, err);
    c->inserted += added + moved;
    c->deleted += trimmed;
    lap(&st, IIR_INCR_INSERT, &t);

    /* 6. weigh, and the new VPLs' interleave keys */
    if (status == IIR_OK)
        status = iir_site_graph_build(&inc->graph, &inc->sites, inc->vpls, inc->count, err);
    if (status == IIR_OK) status = phase_weigh(inc, &ps, &st.flux_in, &st.rays, err);
    if (status == IIR_OK) iir_site_keys_assign(inc->vpls, &inc->graph);
    st.flux_in *= iir_luminance(iir_light_mean_emission(light));
    lap(&st, IIR_INCR_WEIGH, &t);

    c->count = inc->count;
    c->null_samples = count_null_samples(inc);
    st.total_ms = iir_now_ms() - t0;
    assert(count_prev - c->invalidated - c->deleted + c->inserted == c->count);
    inc->frame++;
    inc->map = ps.map;
    if (regen || inc->count > inc->reached) inc->reached = inc->count;
    if (out) *out = st;
    return status;
}

/* ==== refinement and drawing ================================================================= */

iir_status iir_incr_sample_set(const iir_incr *inc, const iir_light *light, uint64_t stream,
                               iir_vpl *out, uint32_t cap, uint32_t *n, iir_raystats *rays,
                               iir_error *err)
{
    *n = 0;
    pose ps;
    iir_status status = iir_light_domain_make(light, &ps, err);
    if (status != IIR_OK) return status;
    uint32_t N = inc->params.target, made = 0;
    if (cap < N)
        return iir_fail(err, IIR_ERR_INVALID,
                        "incremental step: a sample set needs room for %u VPLs, got %u", N, cap);
    iir_rng rng = iir_rng_make(iir_hash3(inc->params.seed, 0x5a3b1e, 0), stream);
    double o[2] = {iir_rng_uniform(&rng), iir_rng_uniform(&rng)};
    uint32_t birth = inc->frame ? inc->frame - 1 : 0;
    for (uint32_t i = 0; i < N; i++) {
        sample sm = regen_sample(inc, &ps, i, N, o, (uint32_t)(stream * 7919u) + i, rays);
        double s[3];
        iir_vpl *v = &out[made];
        if (!make_vpl(&ps, &sm, birth, v, s)) continue;
        v->id = made++;
        v->flux = cell_flux(&ps, v, 1.0, s); /* times the cell area once the count is known */
        aim(&ps, v);
    }
    float A = (float)(ps.area / (made ? made : 1));
    for (uint32_t i = 0; i < made; i++) out[i].flux = iir_scale(out[i].flux, A);
    *n = made;
    return IIR_OK;
}

const double *iir_incr_removed(const iir_incr *inc, uint32_t *n)
{
    *n = inc->num_removed;
    return inc->removed;
}

uint64_t iir_incr_memory(uint32_t n)
{
    uint64_t per_site = 200 + 3 * sizeof(double) + 4 * sizeof(uint32_t) + 1 + /* tri, xy, ids.. */
                        14 * sizeof(uint32_t) +                               /* graph */
                        sizeof(int32_t); /* surface weights' counts */
    return per_site * n;
}

uint32_t iir_incr_updates(const iir_incr *inc)
{
    return inc->frame;
}

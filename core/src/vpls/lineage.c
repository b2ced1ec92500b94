/* lineage.c -- the descendants of a kept VPL set (lineage.h): tracing a parent's path, and each
 * frame carrying lineages over by parent id (an open-addressing table of the last frame's
 * lineages), tracing the new ones and releasing the orphans. Not the parents (incremental.c). */
#include "iir/lineage.h"

#include <stdlib.h>
#include <string.h>

#include "iir/rng.h"
#include "iir/scene.h"
#include "../surface.h"
#include "light_path.h"
#include "vpl_lobe.h"

/* One parent's lineage: its descendants are vpls[first .. first + count). The first step leaves
 * the parent along d0 carrying w0 times its flux; a glossy parent's w0 follows its light (pdf_q0 >
 * 0: re-weighed by iir_vpl_lobe_weight each frame; a delta step, pdf_q0 = 0, holds while the
 * parent's wi is wi0 and is traced again when it turns). */
typedef struct lineage {
    uint32_t parent;
    uint32_t first, count;
    iir_vec3 w0, d0, wi0;
    float pdf_q0;
    bool glossy; /* the parent's lobe is */
} lineage;

/* A frame's lineages and their descendants (two of them: the last frame's and the new one). */
typedef struct generation {
    lineage *lin;
    uint32_t num_lin, lin_cap;
    iir_vpl *v;
    iir_vec3 *T; /* each descendant's path throughput past the lineage's first step (w0) */
    uint32_t n, cap;
} generation;

struct iir_lineage {
    const iir_scene *scene;
    const iir_rt *rt;
    generation cur, next;
    uint32_t *table; /* lineage index + 1 by hashed parent id; 0 = empty */
    uint32_t table_cap;
    uint8_t *used; /* per lineage of cur: carried over */
    int bounces;
};

/* ---- one path ---- */

static uint32_t descendant_id(uint32_t parent, int gen)
{
    return (uint32_t)iir_hash3(parent, (uint64_t)gen, 0x11ea9e);
}

/* Traces parent's path, writing at most cap descendants and their throughputs past the first
 * step, which *l gets (w0, d0, pdf_q0, wi0, glossy). */
static uint32_t trace(const iir_scene *scene, const iir_rt *rt, const iir_vpl *parent, int bounces,
                      uint64_t seed, uint32_t birth, iir_vpl *out, iir_vec3 *T, uint32_t cap,
                      lineage *l, iir_raystats *rays)
{
    iir_rng rng = iir_rng_make(iir_hash3(seed, parent->id, 0x11ea9e), 0);
    iir_vec3 throughput = iir_v3s(1.f);
    const iir_vpl *from = parent;
    float eps = iir_rt_epsilon(rt);
    uint32_t n = 0;
    iir_light_step step;
    *l = (lineage){.parent = parent->id, .wi0 = parent->wi, .glossy = parent->lobe.glossy};
    for (int gen = 1; gen <= bounces - 2 && n < cap; gen++) {
        if (!iir_light_path_continue(from, eps, &rng, &step)) break;
        if (gen == 1) l->w0 = step.weight, l->d0 = step.ray.dir, l->pdf_q0 = step.pdf_q;
        iir_hit hit;
        if (!iir_rt_intersect(rt, &step.ray, &hit, rays, IIR_RAYS_VPL)) break;
        iir_surface sf = iir_surface_at(scene, &hit, iir_neg(step.ray.dir));
        iir_vec3 rho;
        iir_vpl_lobe lobe = iir_vpl_lobe_at(&sf, &rho);
        if (!iir_is_black(sf.Le) || iir_is_black(rho)) break;
        throughput = iir_mul(throughput, gen == 1 ? rho : iir_mul(rho, step.weight));
        iir_vpl v = {.id = descendant_id(parent->id, gen),
                     .position = sf.p,
                     .albedo = rho,
                     .lobe = lobe,
                     .wi = iir_neg(step.ray.dir),
                     .disk = parent->disk,
                     .emit = parent->emit,
                     .birth = birth,
                     .generation = (uint8_t)(gen < 255 ? gen : 255)};
        iir_vpl_set_normal(&v, sf.ns);
        out[n] = v;
        T[n] = throughput;
        from = &out[n++];
    }
    return n;
}

uint32_t iir_lineage_trace(const iir_scene *scene, const iir_rt *rt, const iir_vpl *parent,
                           int bounces, uint64_t seed, uint32_t birth, iir_vpl *out, uint32_t cap,
                           iir_raystats *rays)
{
    if (parent->null_sample) return 0;
    iir_vec3 T[64];
    lineage l;
    uint32_t n =
        trace(scene, rt, parent, bounces, seed, birth, out, T, cap < 64 ? cap : 64, &l, rays);
    for (uint32_t k = 0; k < n; k++) out[k].flux = iir_mul(iir_mul(parent->flux, l.w0), T[k]);
    return n;
}

/* ---- the lineages ---- */

iir_lineage *iir_lineage_create(const iir_scene *scene, const iir_rt *rt)
{
    iir_lineage *L = calloc(1, sizeof *L);
    if (L) L->scene = scene, L->rt = rt, L->bounces = 2;
    return L;
}

static void release_all(generation *g)
{
    for (uint32_t k = 0; k < g->n; k++) iir_smap_release(&g->v[k].smap);
    g->n = 0, g->num_lin = 0;
}

static void generation_free(generation *g)
{
    release_all(g);
    free(g->lin), free(g->v), free(g->T);
    memset(g, 0, sizeof *g);
}

void iir_lineage_destroy(iir_lineage *L)
{
    if (!L) return;
    generation_free(&L->cur);
    generation_free(&L->next);
    free(L->table), free(L->used);
    free(L);
}

iir_vpl *iir_lineage_vpls(iir_lineage *L, uint32_t *n)
{
    *n = L->cur.n;
    return L->cur.v;
}

/* Room for lin lineages and n descendants in g. */
static bool reserve(generation *g, uint32_t lin, uint32_t n)
{
    if (lin > g->lin_cap) {
        lineage *l = realloc(g->lin, lin * sizeof *l);
        if (!l) return false;
        g->lin = l, g->lin_cap = lin;
    }
    if (n > g->cap) {
        iir_vpl *v = realloc(g->v, n * sizeof *v);
        if (v) g->v = v;
        iir_vec3 *T = realloc(g->T, n * sizeof *T);
        if (T) g->T = T;
        if (!v || !T) return false;
        g->cap = n;
    }
    return true;
}

static uint32_t slot_of(uint32_t id, uint32_t cap)
{
    return (uint32_t)iir_mix64(id) & (cap - 1);
}

/* The table of cur's lineages by parent id, and its used flags cleared. */
static bool index_lineages(iir_lineage *L)
{
    uint32_t want = 16;
    while (want < 2 * L->cur.num_lin) want *= 2;
    if (want > L->table_cap) {
        uint32_t *t = realloc(L->table, want * sizeof *t);
        uint8_t *u = realloc(L->used, want);
        if (t) L->table = t;
        if (u) L->used = u;
        if (!t || !u) return false;
        L->table_cap = want;
    }
    memset(L->table, 0, L->table_cap * sizeof *L->table);
    memset(L->used, 0, L->table_cap);
    for (uint32_t k = 0; k < L->cur.num_lin; k++) {
        uint32_t s = slot_of(L->cur.lin[k].parent, L->table_cap);
        while (L->table[s]) s = (s + 1) & (L->table_cap - 1);
        L->table[s] = k + 1;
    }
    return true;
}

/* cur's lineage of parent id, or UINT32_MAX. */
static uint32_t find(const iir_lineage *L, uint32_t id)
{
    for (uint32_t s = slot_of(id, L->table_cap);; s = (s + 1) & (L->table_cap - 1)) {
        uint32_t k = L->table[s];
        if (!k) return UINT32_MAX;
        if (L->cur.lin[k - 1].parent == id) return k - 1;
    }
}

/* Whether old, parent's lineage of the last frame, still holds: always, unless its first step
 * was a glossy parent's delta and the parent's light has turned since. */
static bool still_holds(const lineage *old, const iir_vpl *parent)
{
    return !old->glossy || old->pdf_q0 > 0.f || iir_dot(old->wi0, parent->wi) > 1.f - 1e-6f;
}

/* Appends parent's lineage to next: cur's carried over (a glossy parent's first step re-weighed
 * for its current wi), else traced. */
static void carry_or_trace(iir_lineage *L, const iir_vpl *parent, uint64_t seed, iir_raystats *rays,
                           iir_lineage_stats *st)
{
    generation *g = &L->next;
    lineage *l = &g->lin[g->num_lin++];
    uint32_t k = find(L, parent->id), first = g->n;
    if (k != UINT32_MAX && still_holds(&L->cur.lin[k], parent)) {
        const lineage *old = &L->cur.lin[k];
        *l = *old;
        memcpy(&g->v[g->n], &L->cur.v[old->first], old->count * sizeof *g->v);
        memcpy(&g->T[g->n], &L->cur.T[old->first], old->count * sizeof *g->T);
        L->used[k] = 1;
        st->kept += old->count;
        if (l->glossy && l->pdf_q0 > 0.f) l->w0 = iir_vpl_lobe_weight(parent, l->d0, l->pdf_q0);
    } else {
        l->count = trace(L->scene, L->rt, parent, L->bounces, seed, parent->birth, &g->v[g->n],
                         &g->T[g->n], (uint32_t)(L->bounces - 2), l, rays);
        st->born += l->count;
    }
    l->first = first;
    iir_vec3 flux = iir_mul(parent->flux, l->w0);
    for (uint32_t j = l->first; j < l->first + l->count; j++) g->v[j].flux = iir_mul(flux, g->T[j]);
    g->n += l->count;
}

iir_status iir_lineage_update(iir_lineage *L, const iir_vpl *parents, uint32_t n, int bounces,
                              uint64_t seed, iir_raystats *rays, iir_lineage_stats *st,
                              iir_error *err)
{
    iir_lineage_stats local = {0};
    if (!st) st = &local;
    memset(st, 0, sizeof *st);
    if (bounces != L->bounces) { /* other paths: every lineage traced again */
        st->died += L->cur.n;
        release_all(&L->cur);
        L->bounces = bounces;
    }
    uint32_t per = bounces > 2 ? (uint32_t)(bounces - 2) : 0;
    if (!index_lineages(L) || !reserve(&L->next, n, n * per)) {
        st->died += L->cur.n;
        release_all(&L->cur);
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for the descendants of %u VPLs", n);
    }
    generation *g = &L->next;
    g->n = 0, g->num_lin = 0;
    for (uint32_t i = 0; per && i < n; i++)
        if (!parents[i].null_sample) carry_or_trace(L, &parents[i], seed, rays, st);
    for (uint32_t k = 0; k < L->cur.num_lin; k++) { /* orphans */
        if (L->used[k]) continue;
        const lineage *old = &L->cur.lin[k];
        for (uint32_t j = old->first; j < old->first + old->count; j++)
            iir_smap_release(&L->cur.v[j].smap);
        st->died += old->count;
    }
    L->cur.n = 0, L->cur.num_lin = 0; /* their maps moved to next or were released */
    generation t = L->cur;
    L->cur = L->next, L->next = t;
    st->count = L->cur.n;
    return IIR_OK;
}

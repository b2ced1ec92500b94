/* lineage.h -- the descendants of a kept VPL set: multi-bounce incremental instant radiosity.
 * Each first-generation VPL (a parent: what the incremental step keeps) carries the rest of its
 * light path, Keller's continuation: from the parent a cosine-sampled direction about its normal,
 * a VPL where the ray lands, and so on, ended by Russian roulette on the albedo (continue with
 * q = min(1, max rho)) or after bounces - 2 descendants (bounces as ir's: 2 = the parents alone,
 * one diffuse bounce). Emitters absorb paths, as in ir; mirrors and glass (albedo 0) end them.
 *
 * The scene is static, so a surviving parent's descendants stay valid as they are, with their
 * shadow maps: only their flux follows the parent's, Phi_k = Phi_parent T_k, where the path
 * throughput T_k = prod_{j=1..k} rho_j / q_{j-1} (q_0 from the parent's albedo) is kept per
 * descendant. They die with their parent and are born with it (traced at the first update that
 * sees it). A parent's path is drawn from a stream hashed from (seed, parent id), so lineages are
 * deterministic and a parent traced once is never traced again. Null samples have none. A
 * descendant carries its parent's birth and its generation (1, 2, ...: vpl.h). */
#ifndef IIR_LINEAGE_H
#define IIR_LINEAGE_H

#include <stdint.h>

#include "iir/rt.h"
#include "iir/status.h"
#include "iir/vpl.h"

#ifdef __cplusplus
extern "C" {
#endif

struct iir_scene;
typedef struct iir_lineage iir_lineage;

typedef struct iir_lineage_stats {
    uint32_t count; /* descendants after the update */
    uint32_t kept;  /* of them, carried over with their parents */
    uint32_t born;  /* traced for new parents */
    uint32_t died;  /* dropped with their parents (their maps released) */
} iir_lineage_stats;

/* NULL when out of memory. scene and rt outlive it. */
iir_lineage *iir_lineage_create(const struct iir_scene *scene, const iir_rt *rt);
/* Frees the descendants and their shadow maps. */
void iir_lineage_destroy(iir_lineage *L);

/* The descendants of parents[0..n): kept for parents seen before, traced for new ones, released
 * for parents gone; every descendant's flux set from its parent's. A new bounces drops every
 * lineage and traces again. st may be NULL. IIR_ERR_NOMEM (the lineages are then empty). */
iir_status iir_lineage_update(iir_lineage *L, const iir_vpl *parents, uint32_t n, int bounces,
                              uint64_t seed, iir_raystats *rays, iir_lineage_stats *st,
                              iir_error *err);
/* The descendants, grouped by parent in the parents' order; their shadow maps are written by the
 * caller (they live here). */
iir_vpl *iir_lineage_vpls(iir_lineage *L, uint32_t *n);

/* Appends parent's descendants (at most bounces - 2) to out[0..cap) without keeping them (for
 * refinement's fresh sets); returns how many. birth is what they carry. */
uint32_t iir_lineage_trace(const struct iir_scene *scene, const iir_rt *rt, const iir_vpl *parent,
                           int bounces, uint64_t seed, uint32_t birth, iir_vpl *out, uint32_t cap,
                           iir_raystats *rays);

#ifdef __cplusplus
}
#endif
#endif

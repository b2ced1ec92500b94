/* vplsets.h -- the VPL sets of several lights kept side by side: one incremental step
 * (incremental.h) per light, with the VPL budget N and the per-frame budgets k_min/k_max split
 * across the lights in proportion to the flux each sends into the scene, and the sets' VPLs
 * gathered into one array for shading. Not shadow maps (the caller renders them on each set's
 * own array, where they live) and not shading.
 *
 * SHARES. Light i's share is F_i / sum F, F_i its flux onto reflecting surfaces as its own set
 * estimated it at the last update (iir_incr_stats.flux_in; a light without a set yet: its
 * emitted flux, iir_light_flux), so a light shining into a wall or out of a window gets few.
 * Every light that is on keeps at least IIR_VPLSETS_MIN_TARGET VPLs (or N / lights when smaller)
 * so that it notices when it turns back into the scene; the rest of N is split by share (largest
 * remainders, ties to the lower index), so the targets sum to N. k_max_i = max(1, round(k_max
 * share_i)), k_min_i = min(k_max_i, round(k_min share_i)); set i > 0 scrambles its Hammersley
 * sets with a seed hashed from (seed, i), set 0 uses the seed itself. The targets move only when a
 * light came, went or switched, N changed, or some new target differs from its old one by more than
 * max(2, 1/16 of the old), so the estimate's noise does not churn the sets; a set whose target
 * falls deletes down to it in that frame, one whose target rises fills by its k_max a frame (never
 * regenerated for it: incremental.h's REGENERATE).
 *
 * ON AND OFF. A light whose intensity is black is off: its set is destroyed and its share goes to
 * the others; switched on again it starts a new set. Lights are matched to sets by index: light i
 * of every update is set i (the view's lights keep their order); a different number of lights
 * than at the last update drops the sets past the end and starts the new ones.
 *
 * DESCENDANTS. With bounces > 2 each set's VPLs carry the rest of their light paths (lineage.h),
 * updated after the set, with ids hashed from their parent's.
 *
 * THE GATHERED ARRAY. Set i's VPLs in ascending id, then its descendants, set after set; a
 * gathered VPL's id is
 * id * count + i (count = the number of lights), so the sets' ids are unique and, with one light,
 * those of the set (a descendant's hashed id may repeat another's: ids only pick interleave
 * subsets and ISM point subsets). Deterministic as incremental.h. */
#ifndef IIR_VPLSETS_H
#define IIR_VPLSETS_H

#include <stdint.h>

#include "iir/incremental.h"

#ifdef __cplusplus
extern "C" {
#endif

#define IIR_VPLSETS_MAX_LIGHTS 64u
#define IIR_VPLSETS_MIN_TARGET 16u

typedef struct iir_vplsets iir_vplsets;

/* Empty sets for the scene traced by rt (both outlive it); *p (the totals) is copied. */
iir_status iir_vplsets_create(const struct iir_scene *scene, const iir_rt *rt,
                              const iir_incr_params *p, iir_vplsets **out, iir_error *err);
void iir_vplsets_destroy(iir_vplsets *g);

/* New totals; shares are recomputed at the next update. IIR_ERR_INVALID leaves the old ones. */
iir_status iir_vplsets_set_params(iir_vplsets *g, const iir_incr_params *p, iir_error *err);
iir_incr_params iir_vplsets_get_params(const iir_vplsets *g);

/* One frame for these lights (at most IIR_VPLSETS_MAX_LIGHTS; more is IIR_ERR_INVALID). st (may
 * be NULL) gets the sum of the sets' stats (phase times, rays, counts; `regenerated` and
 * `initial` when any set's is). Errors as iir_incr_update; a light that fails validation stops
 * the update before any set changes. */
iir_status iir_vplsets_update(iir_vplsets *g, const iir_light *lights, uint32_t n,
                              iir_incr_stats *st, iir_error *err);

/* The number of lights of the last update, and light i's set (NULL while it is off). */
uint32_t iir_vplsets_lights(const iir_vplsets *g);
iir_incr *iir_vplsets_set(iir_vplsets *g, uint32_t i);
/* Light i's descendants (lineage.h; none while bounces <= 2): the caller writes their shadow maps
 * here too. */
iir_vpl *iir_vplsets_descendants(iir_vplsets *g, uint32_t i, uint32_t *n);
/* Light bounces as ir's: 2 (the default) = the sets alone; more = every parent carries up to
 * bounces - 2 descendants (lineage.h), from the next update on. */
void iir_vplsets_set_bounces(iir_vplsets *g, int bounces);
/* Light i's target N_i in force (0 while off). */
uint32_t iir_vplsets_target(const iir_vplsets *g, uint32_t i);

/* Every set's VPLs gathered (see THE GATHERED ARRAY), copied now: call it after the caller has
 * written the sets' shadow maps. Valid until the next call or update. NULL with *n = 0 when out
 * of memory or empty. */
const iir_vpl *iir_vplsets_gather(iir_vplsets *g, uint32_t *n);

#ifdef __cplusplus
}
#endif
#endif

/* surface_cells.h -- surface-aware cell areas for the incremental step: a VPL's flux is the light
 * of the directions it stands for, and where its Voronoi cell reaches over another surface (a
 * table's edge over the floor below, a seat over the chair's back) those directions go to a
 * neighbour on that surface instead. A kept set is not spread like a fresh one (sites ride on
 * their surfaces, so a surface shrinking in the light's view crowds them and one that grows or
 * is uncovered thins out), and plain Voronoi cells then hand the crowded surface's neighbours'
 * light to it: on the conference room's orbit the table top carried +12% and the floor -16% of
 * their flux. Private to core. */
#ifndef IIR_SURFACE_CELLS_H
#define IIR_SURFACE_CELLS_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/status.h"
#include "iir/light_domain.h"
#include "iir/rt.h"
#include "iir/vpl.h"
#include "site_graph.h"

/* ---- surface-aware cell areas ---- */

/* What the light's ray for a domain point found: a reflecting surface at x with normal n (on the
 * light's side) at distance `dist` from the ray's origin, or a null sample. */
typedef struct iir_cell_hit {
    iir_vec3 x, n;
    float dist;
    bool null_sample;
} iir_cell_hit;

/* Traces the light's rays for points j0 .. j0 + m - 1 of the pattern, at domain points s[0 .. m)
 * (up to IIR_CELL_BATCH; neighbours in the domain, so the rays are coherent), into hits[0 .. m):
 * an area light's from a point of the emitter fixed for j, drawn independently of the cells (a
 * cell's owner's own point is not one -- owners are the VPLs that survived, and which of them
 * survive depends on their points); called from several threads at once. */
#define IIR_CELL_BATCH 16
typedef void (*iir_cell_trace_fn)(void *ctx, const double (*s)[3], uint32_t j0, int m,
                                  iir_cell_hit *hits, iir_raystats *rays);

/* Buffers kept across frames. */
typedef struct iir_surface_cells {
    int32_t *delta; /* [n] rays gained minus rays owned */
    float *soa; /* [7 n_cap] the VPLs' planes by coordinate (p, n) and a null sample's penalty */
    uint32_t *nulls; /* [n_null] the null samples */
    uint32_t n_null;
    uint32_t n_cap;
} iir_surface_cells;

void iir_surface_cells_free(iir_surface_cells *c);

/* IIR_CELL_RAYS samples a VPL, on a jittered grid fixed in the light's domain (the same every
 * frame), each standing for area / M of the domain. */
#define IIR_CELL_RAYS 16

/* Corrects the Voronoi cell areas areas[i] of the n VPLs (points xyz) where the light's rays land
 * on another surface than the cell's VPL stands for: the pattern's rays that land on the plane of
 * their cell's VPL (within IIR_CELL_PLANE of the ray's length, normals within ~25 degrees), or
 * that are null samples in a null sample's cell, stay; any other goes to the VPL among the cell's,
 * its neighbours' and theirs whose plane fits the hit best (nearest in the domain among equals),
 * or, when none of those lies on the hit's surface, the best of the whole set.
 * Each area changes by the rays it gained minus those it handed over, times a ray's share of the
 * domain: the exact Voronoi areas stay where nothing moved, and the sum is unchanged (but for an
 * area that would fall below 0, which stays at 0). The rows of the pattern run in bands over the
 * threads; the result does not depend on their number. */
iir_status iir_surface_cells_apply(iir_surface_cells *c, const iir_light_domain *d,
                                   const iir_vpl *vpls, const double *xyz, const iir_site_graph *g,
                                   iir_cell_trace_fn trace, void *ctx, double *areas,
                                   iir_raystats *rays, iir_error *err);

#define IIR_CELL_PLANE 0.02f

#endif

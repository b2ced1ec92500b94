/* stri.h -- libiirtri on the unit sphere: the spherical Delaunay triangulation / Voronoi diagram of
 * VPL sites of a point light's direction domain, behind a plain C API; not how VPLs are chosen,
 * shaded or weighted (that is core's), nor the disk domain (tri.h).
 *
 * WHAT IT IS
 *   A set of sites (unit vectors, each with a caller-chosen uint32_t id) on the unit sphere centred
 *   at the origin -- the point-light domain of DESIGN.md section 5. The set is kept as a CGAL
 *   Delaunay_triangulation_on_sphere_2 (exact predicates, inexact constructions; ids travel as
 *   vertex info). As in tri.h every answer is given by id and nothing depends on input order or on
 *   CGAL's storage order; no C++ type or exception crosses this header (every function catches
 *   everything and returns a status); statuses are tri.h's iir_tri_status, with its meanings and
 *   its rule that a failed call changes nothing (and iir_tri_status_name names them).
 *
 * UNITS AND LAYOUTS
 *   A point buffer `xyz` holds n unit vectors interleaved, x0 y0 z0 x1 y1 z1 ..., stride 3 doubles.
 *   Distances are geodesic: the angle between two unit vectors, in radians, in [0, pi]. Areas are
 *   solid angles in steradians; the Voronoi cells of all sites tile the sphere, so their areas sum
 *   to 4 pi (to ~1e-12 relative; ~1e-9 guaranteed).
 *
 * DEFINITIONS (the contract the incremental step relies on)
 *   - Points: a point is accepted when its length is within IIR_STRI_UNIT_TOL of 1; it is then
 *     normalised and stored normalised (iir_stri_position returns the stored vector). A point
 *     further from unit length, or with a NaN/inf coordinate, is IIR_TRI_BAD_ARG.
 *   - Duplicates: two sites are never closer than IIR_STRI_MIN_DIST (chord length, after
 *     normalising), just above the 2^-23 under which CGAL's on-sphere traits refuse a point as "too
 *     close". iir_stri_insert of a point that close to a site returns IIR_TRI_DUPLICATE_POINT and
 *     changes nothing. iir_stri_build visits the points by ascending id and drops each point that
 *     close to a point it kept, so the smallest id (the oldest VPL) survives at a repeated
 * position.
 *   - Dimension: CGAL's. No triangles exist while all sites lie on one circle (a great circle or a
 *     small one; always so for 3 sites), and 1 or 2 sites have no circle at all. Every query is
 *     answered exactly for these sets too: on one circle the cells are lunes between the two poles
 *     of the circle's plane; 2 sites split the sphere into two hemispheres; 1 site owns it all.
 *   - Denser endpoint of the shortest edge (a, b): for each endpoint its nearest other site,
 *     excluding the partner; the endpoint whose such neighbour is closer (by geodesic distance)
 *     lies in the denser neighbourhood. Ties (equal distances, or no third site) go to the larger
 *     id, the younger VPL.
 *   - Largest empty cap: the point c of the sphere that maximises the geodesic distance to the
 *     nearest site, and that distance (the angular radius of the largest spherical cap with no site
 *     inside). It is a Voronoi vertex (the outward normal of a face of the sites' convex hull,
 *     ghost faces included: when all sites lie in a hemisphere the cap is larger than a
 *     hemisphere) or the interior point of a Voronoi edge of sites a, b farthest from both, the
 *     antipode of their midpoint, -(a + b)/|a + b| (such an edge point wins e.g. for a few sites in
 *     a small region). One site: its antipode, angle pi; two sites: the antipode of their
 *     midpoint. Candidates whose angles agree to IIR_TRI_TIE_TOL (relative) are ties: the cells
 *     are visited by ascending id, and in the first cell holding a tied candidate the candidate
 *     with the smallest key wins, so the answer is reproducible. A key is an ascending id triple
 *     compared lexicographically: a Voronoi vertex's face's three ids; an edge point's two ids
 *     then UINT32_MAX; on one circle, a pole's key is the cell's site and its two neighbours, the
 *     pole on the sites' side first.
 *   - Cell polygon: a cell's Voronoi vertices counter-clockwise seen from outside the sphere,
 *     joined by the shorter great-circle arcs. A Voronoi edge longer than pi/2 (only with few
 *     sites or sites in a small region) also gets equally spaced interior points, so that every
 *     arc between consecutive vertices is at most pi/2 and the drawing is unambiguous: a lune
 *     (sites on one circle) has 4 vertices (its two poles and its two edges' midpoints), a
 *     hemisphere (2 sites) 4 points on its great circle, the whole sphere (1 site) none.
 *
 * BUFFERS AND OWNERSHIP
 *   As in tri.h: the caller owns every buffer and the library keeps no pointer to one; functions
 *   filling a variable-size buffer take its capacity `cap` (in elements of the named unit) and a
 *   `size_t *n` that always receives the size of the full answer. A NULL buffer is a size query
 *   (IIR_TRI_OK, only *n written); a non-NULL buffer that is too small gets nothing written and
 *   IIR_TRI_CAPACITY.
 *
 * THREADS
 *   A handle is not locked. Functions taking a `const iir_stri *` only read and may run
 *   concurrently with each other on one handle; build/insert/remove need exclusive access.
 *   Distinct handles are independent. There is no global mutable state.
 *
 * COST
 *   The handle keeps a summary of every site's cell (area, largest-empty-cap candidates) and
 *   shortest edge; each mutation redoes exactly the summaries it can change, so queries only read
 *   them and answer exactly as if every cell were recomputed. build O(n log n) plus one cell per
 *   site whose position or neighbours changed since the previous set; insert/remove O(degree)
 *   cells plus an O(n) move of small index entries (O(n) cells while all sites lie on one
 *   circle); shortest edge, largest empty cap and all areas O(n) reads without allocating; one
 *   area O(log n); one polygon O(degree).
 */
#ifndef IIR_STRI_H
#define IIR_STRI_H

#include <stddef.h>
#include <stdint.h>

#include "iir/tri.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A point is accepted when | |p| - 1 | <= IIR_STRI_UNIT_TOL (then normalised). */
#define IIR_STRI_UNIT_TOL 1e-6
/* Two positions closer than this (chord length, after normalising) are the same position. */
#define IIR_STRI_MIN_DIST 1.2e-7

/* ---- lifetime ----------------------------------------------------------------------------------
 */

typedef struct iir_stri iir_stri;

/* An empty set on the unit sphere; NULL when out of memory. Free with iir_stri_destroy. */
iir_stri *iir_stri_create(void);

/* Frees the handle; NULL is a no-op. */
void iir_stri_destroy(iir_stri *s);

/* Number of sites (0 for a NULL handle). */
size_t iir_stri_count(const iir_stri *s);

/* ---- building and editing ----------------------------------------------------------------------
 */

/* Replaces the whole set by the n sites (xyz[3i], xyz[3i+1], xyz[3i+2]) with ids[i]; n == 0
 * empties the set (xyz and ids may then be NULL). Input order does not matter.
 * Checks everything first: NaN/inf or a length off 1 by more than IIR_STRI_UNIT_TOL ->
 * IIR_TRI_BAD_ARG, an id given twice -> IIR_TRI_DUPLICATE_ID; on these the previous set is kept.
 * Repeated (or closer than IIR_STRI_MIN_DIST) positions: the smallest id is kept, the others are
 * dropped (see DEFINITIONS), the set IS built and IIR_TRI_DUPLICATE_POINT is returned so the caller
 * can learn (iir_stri_position) which ids were dropped. This is the only status after which a
 * function has changed the set. IIR_TRI_NO_MEMORY / IIR_TRI_INTERNAL keep the previous set. */
iir_tri_status iir_stri_build(iir_stri *s, const double *xyz, const uint32_t *ids, size_t n);

/* Adds one site p (normalised) with `id`. IIR_TRI_BAD_ARG (NULL, NaN/inf, not unit length),
 * IIR_TRI_DUPLICATE_ID (id in use), IIR_TRI_DUPLICATE_POINT (within IIR_STRI_MIN_DIST of a site)
 * leave the set unchanged. IIR_TRI_NO_MEMORY / IIR_TRI_INTERNAL leave it empty (as tri.h). */
iir_tri_status iir_stri_insert(iir_stri *s, const double p[3], uint32_t id);

/* Removes the site with `id`; IIR_TRI_UNKNOWN_ID if there is none (set unchanged). */
iir_tri_status iir_stri_remove(iir_stri *s, uint32_t id);

/* ---- lookup ------------------------------------------------------------------------------------
 */

/* Writes the (normalised) position of site `id` to p[0..2]; IIR_TRI_UNKNOWN_ID if there is none.
 */
iir_tri_status iir_stri_position(const iir_stri *s, uint32_t id, double p[3]);

/* All ids, ascending. `cap` and *n count ids (see BUFFERS). */
iir_tri_status iir_stri_ids(const iir_stri *s, uint32_t *ids, size_t cap, size_t *n);

/* ---- queries for the incremental step ----------------------------------------------------------
 */

/* The shortest Delaunay edge by geodesic length: *angle (radians) and its endpoints split into the
 * one in the denser neighbourhood (`denser_id`, the one to delete) and the other (see
 * DEFINITIONS). Among edges of equal length (equal angle in double, computed from the younger
 * endpoint to the older), the one whose larger id is larger wins, then the one whose smaller id is
 * larger. Each output may be NULL. IIR_TRI_TOO_FEW with fewer than 2 sites. */
iir_tri_status iir_stri_shortest_edge(const iir_stri *s, uint32_t *denser_id, uint32_t *other_id,
                                      double *angle);

/* The largest empty spherical cap (see DEFINITIONS): its centre (a unit vector) in centre[0..2]
 * and *angle = the geodesic distance from that centre to its nearest site (computed from the
 * returned centre, so the two agree exactly). IIR_TRI_TOO_FEW on an empty set. */
iir_tri_status iir_stri_largest_empty_cap(const iir_stri *s, double centre[3], double *angle);

/* Area (steradians) of the Voronoi cell of site `id`; IIR_TRI_UNKNOWN_ID if there is none. One
 * site: 4 pi. */
iir_tri_status iir_stri_cell_area(const iir_stri *s, uint32_t id, double *area);

/* Cell areas of all sites, by ascending id: ids[i] has areas[i]. `cap` and *n count sites; ids and
 * areas are both NULL (size query) or both non-NULL. */
iir_tri_status iir_stri_cell_areas(const iir_stri *s, uint32_t *ids, double *areas, size_t cap,
                                   size_t *n);

/* ---- drawing -----------------------------------------------------------------------------------
 */

/* The Delaunay edges as id pairs: pairs[2k] < pairs[2k+1], sorted ascending by (first, second).
 * `cap` and *n count edges (a buffer of cap edges holds 2 * cap uint32_t). 0 or 1 site: no edges;
 * 2 sites: one; sites on one circle: the cycle of neighbours around it. */
iir_tri_status iir_stri_edges(const iir_stri *s, uint32_t *pairs, size_t cap, size_t *n);

/* The Voronoi polygon of site `id` (see DEFINITIONS): unit vectors xyz[3k..3k+2],
 * counter-clockwise seen from outside, not closed. `cap` and *n count vertices.
 * IIR_TRI_UNKNOWN_ID if there is no such site. */
iir_tri_status iir_stri_cell_polygon(const iir_stri *s, uint32_t id, double *xyz, size_t cap,
                                     size_t *n);

#ifdef __cplusplus
}
#endif

#endif

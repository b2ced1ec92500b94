/* tri.h -- libiirtri: the Delaunay triangulation / Voronoi diagram of VPL sites on the light's disk
 * domain, behind a plain C API; not how VPLs are chosen, shaded or weighted (that is core's).
 *
 * WHAT IT IS
 *   A set of sites (2D points, each with a caller-chosen uint32_t id) inside the closed disk
 *   |s| <= R centred at the origin -- the disk domain of DESIGN.md section 5. The set is kept as a
 *   CGAL Delaunay_triangulation_2 (exact predicates, inexact constructions; ids travel as vertex
 *   info). Every answer is given by id: nothing depends on the order in which points were given or
 *   in which CGAL stores them. The library is independent of libiircore and never includes its
 *   headers. No C++ type or exception crosses this header: every function catches everything and
 *   returns a status.
 *
 * UNITS AND LAYOUTS
 *   All coordinates are doubles in disk units (the unit of R). A point buffer `xy` holds n points
 *   interleaved, x0 y0 x1 y1 ..., stride 2 doubles. Areas are in disk units squared; the clipped
 *   Voronoi cells of all sites tile the disk, so their areas sum to pi R^2 (to ~1e-12 relative).
 *
 * DEFINITIONS (the contract the incremental step relies on)
 *   - Inside: a point is accepted when |s| <= R (1 + IIR_TRI_OUTSIDE_TOL); it is stored as given
 *     (not projected), so points computed "on the circle" with rounding error are accepted. Points
 *     further out are rejected with IIR_TRI_OUTSIDE (the VPL step only inserts points inside).
 *   - Duplicates: two sites never share a position (exact equality of both coordinates).
 *     iir_tri_insert of an occupied position returns IIR_TRI_DUPLICATE_POINT and changes nothing
 * (the site already there keeps its id). iir_tri_build keeps, at each repeated position, the
 * smallest id (the oldest VPL) and drops the others; see iir_tri_build for its return value.
 *   - Clipped cell: the Voronoi cell of a site intersected with the closed disk. Areas are exact
 *     (polygon part plus circular segments), never a polygon approximation of the circle.
 *   - Denser endpoint of the shortest edge (a, b): for each endpoint, its nearest *other* site,
 *     excluding the edge partner (for the closest pair this is the second-nearest neighbour). The
 *     endpoint whose such neighbour is closer lies in the denser neighbourhood. Ties (equal squared
 *     distances, or no third site at all) go to the larger id, the younger VPL.
 *   - Largest empty circle: the point c of the closed disk that maximises the distance to the
 *     nearest site (the exact maximiser over Voronoi vertices inside the disk, Voronoi edges
 * crossing the circle, and the farthest point of each cell's arcs), and that distance. Centres
 * whose radii agree to IIR_TRI_TIE_TOL (relative) are ties; the tie goes to the candidate found
 * first when cells are visited by ascending id, so the answer is reproducible.
 *   - Drawing: arcs of a clipped cell are drawn as chords whose ends lie on the circle; an arc of
 *     angle theta gets ceil(theta * IIR_TRI_ARC_SEGMENTS / (2 pi)) equal chords (a full circle gets
 *     IIR_TRI_ARC_SEGMENTS).
 *
 * BUFFERS AND OWNERSHIP
 *   The caller owns every buffer; the library never keeps a pointer to one after a call returns and
 *   never returns memory the caller must free (except the handle, freed by iir_tri_destroy).
 *   Functions that fill a variable-size buffer take its capacity `cap` (in elements of the named
 *   unit) and a `size_t *n` that always receives the number of elements the full answer has.
 * Passing a NULL buffer is a size query (returns IIR_TRI_OK and writes only *n). A non-NULL buffer
 * that is too small gets nothing written and IIR_TRI_CAPACITY.
 *
 * THREADS
 *   A handle is not locked. Functions taking a `const iir_tri *` only read and may run concurrently
 *   with each other on one handle; build/insert/remove need exclusive access. Distinct handles are
 *   independent. There is no global mutable state.
 *
 * COST
 *   The handle keeps a summary of every site's clipped cell (area, largest-empty-circle candidates)
 *   and shortest edge; each mutation redoes exactly the summaries it can change, so queries only
 *   read them and answer exactly as if every cell were recomputed. build O(n log n) plus one cell
 *   per site whose position or neighbours changed since the previous set; insert/remove O(degree)
 *   cells (O(degree^2) each) plus an O(n) move of small index entries; shortest edge, largest
 *   empty circle and all areas O(n) reads; one area O(log n); one polygon O(degree^2). Collinear
 *   sets (no triangles) are handled exactly.
 */
#ifndef IIR_TRI_H
#define IIR_TRI_H

#include <stddef.h>
#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Relative slack for "inside the disk": |s| <= R * (1 + IIR_TRI_OUTSIDE_TOL) is accepted. */
#define IIR_TRI_OUTSIDE_TOL 1e-9
/* Relative tolerance under which two largest-empty-circle radii are a tie. */
#define IIR_TRI_TIE_TOL 1e-12
/* Chords per full turn when arcs of a clipped cell are drawn as a polygon. */
#define IIR_TRI_ARC_SEGMENTS 64

/* Every function that can fail returns one of these. Any status other than IIR_TRI_OK means the
 * handle and all outputs are unchanged, except: *n of the buffer queries (always written, see
 * BUFFERS), iir_tri_build's IIR_TRI_DUPLICATE_POINT, and the paragraph below. */
typedef enum iir_tri_status {
    IIR_TRI_OK = 0,
    IIR_TRI_BAD_ARG,         /* NULL handle or required pointer, NaN/inf coordinate, radius <= 0 */
    IIR_TRI_OUTSIDE,         /* a point lies outside the disk (beyond IIR_TRI_OUTSIDE_TOL) */
    IIR_TRI_DUPLICATE_ID,    /* the id is already in the set (or repeated within a build) */
    IIR_TRI_DUPLICATE_POINT, /* the position is already taken (iir_tri_build: a warning) */
    IIR_TRI_UNKNOWN_ID,      /* no site has this id */
    IIR_TRI_TOO_FEW,         /* the query needs more sites (shortest edge: 2; empty circle: 1) */
    IIR_TRI_CAPACITY,        /* the output buffer is too small; *n says how much is needed */
    IIR_TRI_NO_MEMORY,       /* allocation failed (mutations: the set is then empty, see below) */
    IIR_TRI_INTERNAL         /* CGAL failed unexpectedly (mutations: the set is then empty) */
} iir_tri_status;
/* A mutation (build, insert, remove) that fails with IIR_TRI_NO_MEMORY or IIR_TRI_INTERNAL after it
 * started changing the triangulation leaves the handle valid but empty (count 0), never corrupt.
 * iir_tri_build is all-or-nothing: on those statuses the previous set is kept. */

/* Short stable name of a status ("ok", "bad_arg", "outside", ...); never NULL. */
const char *iir_tri_status_name(iir_tri_status status);

/* The CGAL version the library was built against, e.g. "5.5"; a static string. */
const char *iir_tri_cgal_version(void);

/* ---- lifetime ----------------------------------------------------------------------------------
 */

typedef struct iir_tri iir_tri;

/* An empty set on the disk of radius `radius` (finite, > 0). Returns NULL on a bad radius or when
 * out of memory. Free with iir_tri_destroy. */
iir_tri *iir_tri_create(double radius);

/* Frees the handle; NULL is a no-op. */
void iir_tri_destroy(iir_tri *tri);

/* The disk radius R given to iir_tri_create (0 for a NULL handle). */
double iir_tri_radius(const iir_tri *tri);

/* Number of sites (0 for a NULL handle). */
size_t iir_tri_count(const iir_tri *tri);

/* ---- building and editing ----------------------------------------------------------------------
 */

/* Replaces the whole set by the n sites (xy[2i], xy[2i+1]) with ids[i]; n == 0 empties the set (xy
 * and ids may then be NULL). Input order does not matter.
 * Checks everything first: NaN/inf -> IIR_TRI_BAD_ARG, a point outside -> IIR_TRI_OUTSIDE, an id
 * given twice -> IIR_TRI_DUPLICATE_ID; on these the previous set is kept.
 * Repeated positions: the smallest id at each position is kept, the others are dropped, the set IS
 * built and IIR_TRI_DUPLICATE_POINT is returned so the caller can learn (iir_tri_position) which
 * ids were dropped. This is the only status after which a function has changed the set. */
iir_tri_status iir_tri_build(iir_tri *tri, const double *xy, const uint32_t *ids, size_t n);

/* Adds one site (x, y) with `id`. IIR_TRI_BAD_ARG (NaN/inf), IIR_TRI_OUTSIDE,
 * IIR_TRI_DUPLICATE_ID (id in use), IIR_TRI_DUPLICATE_POINT (position in use) leave the set
 * unchanged. */
iir_tri_status iir_tri_insert(iir_tri *tri, double x, double y, uint32_t id);

/* Removes the site with `id`; IIR_TRI_UNKNOWN_ID if there is none (set unchanged). */
iir_tri_status iir_tri_remove(iir_tri *tri, uint32_t id);

/* ---- lookup ------------------------------------------------------------------------------------
 */

/* Writes the position of site `id` to xy[0], xy[1]; IIR_TRI_UNKNOWN_ID if there is none. */
iir_tri_status iir_tri_position(const iir_tri *tri, uint32_t id, double xy[2]);

/* All ids, ascending. `cap` and *n count ids (see BUFFERS). */
iir_tri_status iir_tri_ids(const iir_tri *tri, uint32_t *ids, size_t cap, size_t *n);

/* The site nearest to (x, y) (any point of the plane): its id and distance (each output may be
 * NULL). Among equidistant sites CGAL's choice is returned. IIR_TRI_TOO_FEW on an empty set. */
iir_tri_status iir_tri_nearest(const iir_tri *tri, double x, double y, uint32_t *id,
                               double *distance);

/* ---- queries for the incremental step ----------------------------------------------------------
 */

/* The shortest Delaunay edge: its length and its endpoints split into the one in the denser
 * neighbourhood (`denser_id`, the one to delete) and the other (see DEFINITIONS). Among edges of
 * equal length (equal squared length in double), the one whose larger id is larger wins, then the
 * one whose smaller id is larger. Each output may be NULL. IIR_TRI_TOO_FEW with fewer than 2 sites.
 */
iir_tri_status iir_tri_shortest_edge(const iir_tri *tri, uint32_t *denser_id, uint32_t *other_id,
                                     double *length);

/* The largest empty circle with centre in the closed disk (see DEFINITIONS): centre[0], centre[1]
 * and *radius = the distance from the centre to its nearest site (computed from the returned
 * centre, so the two agree exactly). A centre on the circle may lie outside it by rounding (~1e-16
 * R). One site at the origin: the centre is (R, 0), radius R. IIR_TRI_TOO_FEW on an empty set. */
iir_tri_status iir_tri_largest_empty_circle(const iir_tri *tri, double centre[2], double *radius);

/* Area of the clipped Voronoi cell of site `id`; IIR_TRI_UNKNOWN_ID if there is none. */
iir_tri_status iir_tri_cell_area(const iir_tri *tri, uint32_t id, double *area);

/* Clipped cell areas of all sites, by ascending id: ids[i] has areas[i]. `cap` and *n count sites;
 * ids and areas are both NULL (size query) or both non-NULL. */
iir_tri_status iir_tri_cell_areas(const iir_tri *tri, uint32_t *ids, double *areas, size_t cap,
                                  size_t *n);

/* ---- drawing -----------------------------------------------------------------------------------
 */

/* The finite Delaunay edges as id pairs: pairs[2k] < pairs[2k+1], sorted ascending by (first,
 * second). `cap` and *n count edges (a buffer of cap edges holds 2 * cap uint32_t). 0 or 1 site: no
 * edges; collinear sites: the chain between consecutive sites. */
iir_tri_status iir_tri_edges(const iir_tri *tri, uint32_t *pairs, size_t cap, size_t *n);

/* The clipped Voronoi cell of site `id` as a convex polygon, counter-clockwise, not closed (the
 * last vertex is not repeated): xy[2k], xy[2k+1]. Straight sides come from Voronoi edges; arcs of
 * the circle are drawn as chords (see DEFINITIONS). `cap` and *n count vertices. IIR_TRI_UNKNOWN_ID
 * if there is no such site. */
iir_tri_status iir_tri_cell_polygon(const iir_tri *tri, uint32_t id, double *xy, size_t cap,
                                    size_t *n);

#ifdef __cplusplus
}
#endif

#endif

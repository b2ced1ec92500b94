/* domain_sites.h -- the triangulation of a VPL set's domain points, whichever the domain's shape:
 * libiirtri's disk (tri.h) or sphere (stri.h) behind one set of calls, with points always three
 * doubles (x, y, 0 on the disk); the one place that chooses between the two. Private to core: the
 * incremental step edits a set, domain_draw.c reads one. Statuses are tri.h's. */
#ifndef IIR_DOMAIN_SITES_H
#define IIR_DOMAIN_SITES_H

#include <stddef.h>
#include <stdint.h>

#include "iir/light_domain.h"
#include "iir/tri.h"

struct iir_stri;

typedef struct iir_sites {
    iir_domain_shape shape;
    iir_tri *tri;          /* the disk's, radius R */
    struct iir_stri *stri; /* the sphere's */
    double *xy;            /* scratch: points repacked for the disk's build */
    size_t xy_cap;
} iir_sites;

/* Makes *s fit the domain: keeps the triangulation when the shape (and, for a disk, the radius) is
 * unchanged, else makes a new, empty one. IIR_TRI_NO_MEMORY when that fails. */
iir_tri_status iir_sites_fit(iir_sites *s, const iir_light_domain *d);
void iir_sites_free(iir_sites *s);

iir_tri_status iir_sites_build(iir_sites *s, const double *xyz, const uint32_t *ids, size_t n);
iir_tri_status iir_sites_insert(iir_sites *s, const double p[3], uint32_t id);
iir_tri_status iir_sites_remove(iir_sites *s, uint32_t id);
/* Whether the site with this id is in the set. */
int iir_sites_has(const iir_sites *s, uint32_t id);
iir_tri_status iir_sites_shortest_edge(const iir_sites *s, uint32_t *denser_id);
/* The largest empty circle (disk) or cap (sphere): its centre, and its radius (the cap's: geodesic)
 * when radius is not NULL. */
iir_tri_status iir_sites_largest_empty(const iir_sites *s, double centre[3], double *radius);
iir_tri_status iir_sites_cell_areas(const iir_sites *s, uint32_t *ids, double *areas, size_t cap,
                                    size_t *n);

/* ---- reading a set for drawing ---- */

/* A read-only view of an incremental set's triangulation (iir_incr_tri / iir_incr_stri: the one
 * that is not NULL; a disk when both are), for the const calls only. */
iir_sites iir_sites_view(const struct iir_tri *tri, const struct iir_stri *stri);
/* The position of site `id` in p (z = 0 on the disk); IIR_TRI_UNKNOWN_ID if there is none. */
iir_tri_status iir_sites_position(const iir_sites *s, uint32_t id, double p[3]);
/* The Delaunay edges as id pairs, as tri.h's iir_tri_edges. */
iir_tri_status iir_sites_edges(const iir_sites *s, uint32_t *pairs, size_t cap, size_t *n);
/* Site id's cell polygon as tri.h's iir_tri_cell_polygon (the disk's) or stri.h's, with points of
 * three doubles: `cap` and *n count points, xyz holds 3 cap doubles. */
iir_tri_status iir_sites_cell_polygon(const iir_sites *s, uint32_t id, double *xyz, size_t cap,
                                      size_t *n);

#endif

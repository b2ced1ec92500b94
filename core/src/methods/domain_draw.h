/* domain_draw.h -- drawing one VPL set's domain for iir_method_domain: sites, Delaunay edges,
 * Voronoi cells and the last frame's removed points, in the unit disk the client draws: a disk
 * domain scaled to radius 1, the sphere by Lambert's equal-area map about straight down (+y, the
 * point straight up, lies on the rim). Private to the iir method. */
#ifndef IIR_DOMAIN_DRAW_H
#define IIR_DOMAIN_DRAW_H

#include <stdbool.h>
#include <stddef.h>

#include "iir/incremental.h"
#include "iir/method.h"

/* The drawing's buffers (grown, never shrunk) and whether they hold the last frame's. */
typedef struct iir_domain_draw {
    bool valid;
    iir_domain_site *sites;
    size_t sites_cap;
    uint32_t *pairs; /* [2 edges_cap]: id pairs from the triangulation, then index pairs in place */
    size_t edges_cap;
    uint32_t *cell_start; /* [num_sites + 1] */
    size_t cell_start_cap;
    float (*points)[2];
    size_t points_cap;
    double *xy; /* one cell polygon from the triangulation (stride 3) */
    size_t xy_cap;
    float (*removed)[2];
    size_t removed_cap;
    iir_domain d;
} iir_domain_draw;

void iir_domain_draw_free(iir_domain_draw *b);

/* Fills b->d from the set's last update (map: the domain's name for the caption); false when the
 * set has no triangulation yet or out of memory. */
bool iir_domain_draw_build(iir_domain_draw *b, const iir_incr *set, const char *map);

#endif

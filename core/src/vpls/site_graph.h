/* site_graph.h -- an incremental set's triangulation as a graph: the Delaunay neighbours of every
 * VPL (by array index), the nearest site to a domain point by a walk over them, and the interleave
 * keys of new VPLs, spread over their neighbours'. Private to core: incremental.c owns the set and
 * builds the graph once a frame; surface_cells.c walks it. */
#ifndef IIR_SITE_GRAPH_H
#define IIR_SITE_GRAPH_H

#include <stddef.h>
#include <stdint.h>

#include "iir/status.h"
#include "iir/vpl.h"
#include "lights/domain_sites.h"

/* The neighbours of VPL i are adj[off[i] .. off[i + 1]); buffers grow and are reused. */
typedef struct iir_site_graph {
    uint32_t n;
    uint32_t *off;   /* [n + 2] */
    uint32_t *adj;   /* [2 edges] */
    uint32_t *pairs; /* [2 edge_cap] scratch: the triangulation's edges */
    size_t edge_cap;
    uint32_t n_cap;
} iir_site_graph;

/* The index of the VPL with this id in vpls[0 .. n) (ascending ids, as a set keeps them); asserts
 * that it exists. */
uint32_t iir_site_index(const iir_vpl *vpls, uint32_t n, uint32_t id);

/* The graph of the n VPLs of `vpls` (ascending ids, each a site of `sites`). */
iir_status iir_site_graph_build(iir_site_graph *g, const iir_sites *sites, const iir_vpl *vpls,
                                uint32_t n, iir_error *err);
void iir_site_graph_free(iir_site_graph *g);

/* The index of the site nearest to domain point s (xyz: the sites' points, three doubles each),
 * walking from site `start`: a Delaunay graph always has a neighbour nearer to s than a site that
 * is not the nearest. */
uint32_t iir_site_graph_nearest(const iir_site_graph *g, const double *xyz, uint32_t start,
                                const double s[3]);

/* Site i's neighbours (the first *ring1 of ring) and then their other neighbours, at most cap in
 * all; the count. */
uint32_t iir_site_graph_rings(const iir_site_graph *g, uint32_t i, uint32_t *ring, uint32_t cap,
                              uint32_t *ring1);

/* Gives every VPL whose key is 0 (new ones) an interleave key (vpl.h) far, on the circle of keys,
 * from its neighbours' and less so from its neighbours' neighbours', so that the VPLs near each
 * other in the domain fall into different interleave subsets, as a fresh stratified set's would,
 * whatever the interleave. In index order: deterministic. */
void iir_site_keys_assign(iir_vpl *vpls, const iir_site_graph *g);

#endif

/* site_graph.c -- an incremental set's Delaunay graph by array index (site_graph.h), the walk to
 * the nearest site, and interleave keys spread over the neighbours' keys. */
#include "site_graph.h"

#include <assert.h>
#include <stdlib.h>

uint32_t iir_site_index(const iir_vpl *vpls, uint32_t n, uint32_t id)
{
    uint32_t lo = 0, hi = n;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (vpls[mid].id < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    assert(lo < n && vpls[lo].id == id);
    return lo;
}

static bool grow(void **p, size_t count, size_t size)
{
    void *q = realloc(*p, count * size);
    if (!q) return false;
    *p = q;
    return true;
}

/* Room for n sites and the edges of their triangulation (fewer than 3 n on a plane or sphere). */
static bool reserve(iir_site_graph *g, uint32_t n)
{
    size_t edges = 3 * (size_t)n + 6;
    if (n + 2 > g->n_cap) {
        if (!grow((void **)&g->off, n + 2, sizeof *g->off)) return false;
        g->n_cap = n + 2;
    }
    if (edges > g->edge_cap) {
        if (!grow((void **)&g->pairs, 2 * edges, sizeof *g->pairs)) return false;
        if (!grow((void **)&g->adj, 2 * edges, sizeof *g->adj)) return false;
        g->edge_cap = edges;
    }
    return true;
}

iir_status iir_site_graph_build(iir_site_graph *g, const iir_sites *sites, const iir_vpl *vpls,
                                uint32_t n, iir_error *err)
{
    size_t ne = 0;
    g->n = 0;
    if (!reserve(g, n)) return iir_fail(err, IIR_ERR_NOMEM, "out of memory for the site graph");
    iir_tri_status ts = n > 1 ? iir_sites_edges(sites, g->pairs, g->edge_cap, &ne) : IIR_TRI_OK;
    if (ts != IIR_TRI_OK)
        return iir_fail(err, IIR_ERR_INTERNAL, "incremental step: the site graph's edges (%s)",
                        iir_tri_status_name(ts));
    for (uint32_t i = 0; i < n + 2; i++) g->off[i] = 0;
    for (size_t e = 0; e < 2 * ne; e++) {
        g->pairs[e] = iir_site_index(vpls, n, g->pairs[e]);
        g->off[g->pairs[e] + 2]++;
    }
    for (uint32_t i = 2; i < n + 2; i++) g->off[i] += g->off[i - 1];
    for (size_t e = 0; e < ne; e++) { /* off[i + 1] counts i's neighbours placed so far */
        uint32_t a = g->pairs[2 * e], b = g->pairs[2 * e + 1];
        g->adj[g->off[a + 1]++] = b;
        g->adj[g->off[b + 1]++] = a;
    }
    g->n = n;
    return IIR_OK;
}

void iir_site_graph_free(iir_site_graph *g)
{
    free(g->off);
    free(g->adj);
    free(g->pairs);
    *g = (iir_site_graph){0};
}

static double dist2(const double *a, const double *b)
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return dx * dx + dy * dy + dz * dz;
}

uint32_t iir_site_graph_nearest(const iir_site_graph *g, const double *xyz, uint32_t start,
                                const double s[3])
{
    uint32_t at = start;
    double best = dist2(&xyz[3 * at], s);
    for (;;) { /* to the nearest of at's neighbours while it is nearer than at */
        uint32_t next = at;
        for (uint32_t k = g->off[at], end = g->off[at + 1]; k < end; k++) {
            double d = dist2(&xyz[3 * g->adj[k]], s);
            if (d < best) best = d, next = g->adj[k];
        }
        if (next == at) return at;
        at = next;
    }
}

/* ---- interleave keys ---- */

/* The keys balance 16 subsets (interleave 4, the default; and so 2). */
enum { KEY_CANDIDATES = 64, RING_MAX = 128, BALANCE_SUBSETS = 16 };

/* The distance of two keys on the circle of 2^32. */
static uint32_t key_distance(uint32_t a, uint32_t b)
{
    uint32_t d = a - b;
    return d < 0u - d ? d : 0u - d;
}

uint32_t iir_site_graph_rings(const iir_site_graph *g, uint32_t i, uint32_t *ring, uint32_t cap,
                              uint32_t *ring1)
{
    uint32_t n = 0;
    for (uint32_t k = g->off[i]; k < g->off[i + 1] && n < cap; k++) ring[n++] = g->adj[k];
    *ring1 = n;
    for (uint32_t r = 0; r < *ring1; r++)
        for (uint32_t k = g->off[ring[r]]; k < g->off[ring[r] + 1] && n < cap; k++) {
            uint32_t c = g->adj[k];
            bool seen = c == i;
            for (uint32_t j = 0; j < n && !seen; j++) seen = ring[j] == c;
            if (!seen) ring[n++] = c;
        }
    return n;
}

/* The candidate key farthest from the keyed neighbours -- the nearest neighbour's distance plus
 * half the nearest second neighbour's -- among those whose subset of BALANCE_SUBSETS holds at most
 * one VPL more than the smallest. Candidates are KEY_CANDIDATES evenly spaced from the id's hash.
 */
static uint32_t spread_key(const iir_vpl *vpls, uint32_t id, const uint32_t *ring, uint32_t n,
                           uint32_t ring1, const uint32_t *count)
{
    uint32_t best = 1, least = UINT32_MAX;
    for (uint32_t k = 0; k < BALANCE_SUBSETS; k++) least = count[k] < least ? count[k] : least;
    double best_score = -1.0;
    for (uint32_t c = 0; c < KEY_CANDIDATES; c++) {
        uint32_t key = iir_id_key(id) + c * (uint32_t)(0x100000000ull / KEY_CANDIDATES);
        if (!key || count[iir_key_subset(key, BALANCE_SUBSETS)] > least + 1) continue;
        uint32_t near1 = UINT32_MAX, near2 = UINT32_MAX;
        for (uint32_t k = 0; k < n; k++) {
            uint32_t other = vpls[ring[k]].key;
            if (!other) continue;
            uint32_t d = key_distance(key, other);
            uint32_t *near = k < ring1 ? &near1 : &near2;
            if (d < *near) *near = d;
        }
        double score = (double)near1 + 0.5 * (double)near2;
        if (score > best_score) best_score = score, best = key;
    }
    return best;
}

void iir_site_keys_assign(iir_vpl *vpls, const iir_site_graph *g)
{
    uint32_t ring[RING_MAX], ring1, count[BALANCE_SUBSETS] = {0};
    for (uint32_t i = 0; i < g->n; i++)
        if (vpls[i].key) count[iir_key_subset(vpls[i].key, BALANCE_SUBSETS)]++;
    for (uint32_t i = 0; i < g->n; i++) {
        if (vpls[i].key) continue;
        uint32_t n = iir_site_graph_rings(g, i, ring, RING_MAX, &ring1);
        vpls[i].key = spread_key(vpls, vpls[i].id, ring, n, ring1, count);
        count[iir_key_subset(vpls[i].key, BALANCE_SUBSETS)]++;
    }
}

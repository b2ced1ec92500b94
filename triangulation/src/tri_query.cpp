// tri_query.cpp -- questions answered by the Delaunay graph itself: the shortest edge (from the
// per-site summaries) and its denser endpoint, the edge list for drawing; not the Voronoi cells
// (tri_voronoi.cpp) nor keeping the summaries current (tri_domain.cpp).
#include "tri_internal.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <limits>
#include <utility>

using namespace iirtri;

namespace
{

double dist2(const Point &a, const Point &b)
{
    double dx = a.x() - b.x(), dy = a.y() - b.y();
    return dx * dx + dy * dy;
}

// A finite Delaunay edge as its key (tri_cache.hpp).
Edge_key make_edge(const Delaunay::Edge &e)
{
    Vertex_handle a = e.first->vertex(Delaunay::cw(e.second));
    Vertex_handle b = e.first->vertex(Delaunay::ccw(e.second));
    if (a->info().id < b->info().id) std::swap(a, b);
    return {dist2(a->point(), b->point()), a->info().id, b->info().id};
}

// The shortest edge over the summaries: each site's shortest incident edge is remembered, and the
// shortest of those is the shortest of all (the order is total, so this is the edge a scan of all
// edges finds).
Edge_key shortest_edge(const Site_table &table)
{
    const Edge_key *best = nullptr;
    for (const Id_slot &e : table.order) {
        const Site_summary &s = table.summary[e.slot];
        if (s.has_edge && (!best || shorter(s.edge, *best))) best = &s.edge;
    }
    assert(best && "two or more sites have an edge");
    return *best;
}

// Squared distance from p to its nearest site other than p and q (infinity if there is none). That
// site is a Delaunay neighbour of p once q is gone, so it is a neighbour of p or of q now.
double second_nearest2(const Delaunay &dt, Vertex_handle p, Vertex_handle q)
{
    double best = std::numeric_limits<double>::infinity();
    auto visit = [&](Vertex_handle o) {
        if (o != p && o != q) best = std::min(best, dist2(p->point(), o->point()));
    };
    for_each_neighbour(dt, p, visit);
    for_each_neighbour(dt, q, visit);
    return best;
}

Vertex_handle vertex_of(const iir_tri *tri, uint32_t id)
{
    return tri->vertex[tri->table.find(id)->slot];
}

} // namespace

// ---- public queries ----

extern "C" iir_tri_status iir_tri_shortest_edge(const iir_tri *tri, uint32_t *denser_id,
                                                uint32_t *other_id, double *length)
{
    if (!tri) return IIR_TRI_BAD_ARG;
    return guard([&] {
        if (tri->table.order.size() < 2) return IIR_TRI_TOO_FEW;
        Edge_key e = shortest_edge(tri->table);
        Vertex_handle young = vertex_of(tri, e.young), old = vertex_of(tri, e.old);
        // Ties (including "no third site") go to the younger endpoint.
        double dy = second_nearest2(tri->dt, young, old);
        double dold = second_nearest2(tri->dt, old, young);
        bool young_denser = dy <= dold;
        if (denser_id) *denser_id = young_denser ? e.young : e.old;
        if (other_id) *other_id = young_denser ? e.old : e.young;
        if (length) *length = std::sqrt(e.len2);
        return IIR_TRI_OK;
    });
}

extern "C" iir_tri_status iir_tri_edges(const iir_tri *tri, uint32_t *pairs, size_t cap, size_t *n)
{
    if (!tri || !n) return IIR_TRI_BAD_ARG;
    return guard([&] {
        std::vector<std::pair<uint32_t, uint32_t>> edges;
        for (auto it = tri->dt.finite_edges_begin(); it != tri->dt.finite_edges_end(); ++it) {
            Edge_key e = make_edge(*it);
            edges.emplace_back(e.old, e.young);
        }
        iir_tri_status st = fits(pairs, cap, edges.size(), n);
        if (st != IIR_TRI_OK || !pairs) return st;
        std::sort(edges.begin(), edges.end());
        for (size_t k = 0; k < edges.size(); k++) {
            pairs[2 * k] = edges[k].first;
            pairs[2 * k + 1] = edges[k].second;
        }
        return IIR_TRI_OK;
    });
}

// stri_query.cpp -- questions the spherical Delaunay graph answers itself: the shortest edge (from
// the per-site summaries) and its denser endpoint, the edge list for drawing; not the Voronoi cells
// (stri_voronoi.cpp) nor keeping the summaries current (stri_domain.cpp).
#include "stri_internal.hpp"
#include "tri_common.hpp"

#include <algorithm>
#include <cassert>
#include <limits>
#include <utility>

using namespace iirstri;
using iirtri::fits;
using iirtri::guard;

namespace
{

// The shortest edge over the summaries: each site's shortest incident edge is remembered, and the
// shortest of those is the shortest of all (the order is total, so the slots are scanned in
// storage order; free slots have no edge).
Edge_key shortest_edge(const Site_table &table)
{
    const Edge_key *best = nullptr;
    for (const Site_summary &s : table.summary)
        if (s.has_edge && (!best || shorter(s.edge, *best))) best = &s.edge;
    assert(best && "two or more sites have an edge");
    return *best;
}

// Geodesic distance from p to its nearest site other than p and q (infinity if there is none).
// That site is a Delaunay neighbour of p once q is gone, so it is a neighbour of p or of q now.
double second_nearest(const Delaunay &dt, Vertex_handle p, Vertex_handle q)
{
    double best = std::numeric_limits<double>::infinity();
    const Vec3 pp = vec_of(p->point());
    auto visit = [&](Vertex_handle o) {
        if (o != p && o != q) best = std::min(best, angle_between(pp, vec_of(o->point())));
    };
    for_each_neighbour(dt, p, visit);
    for_each_neighbour(dt, q, visit);
    return best;
}

Vertex_handle vertex_of(const iir_stri *s, uint32_t id)
{
    return s->vertex[s->table.find(id)->slot];
}

// Every Delaunay edge as (smaller id, larger id). Two sites have one edge, which CGAL (dimension
// 0) does not store; in dimension 1 the "faces" are the edges around the circle.
void all_edges(const iir_stri *s, std::vector<std::pair<uint32_t, uint32_t>> &out)
{
    const Delaunay &dt = s->dt;
    auto add = [&](Vertex_handle a, Vertex_handle b) {
        out.emplace_back(std::min(a->info().id, b->info().id),
                         std::max(a->info().id, b->info().id));
    };
    if (dt.dimension() == 0) {
        add(dt.vertices_begin(), std::next(dt.vertices_begin()));
        return;
    }
    for (auto it = dt.all_edges_begin(); it != dt.all_edges_end(); ++it) {
        Delaunay::Face_handle f = it->first;
        if (dt.dimension() == 1)
            add(f->vertex(0), f->vertex(1));
        else
            add(f->vertex(Delaunay::cw(it->second)), f->vertex(Delaunay::ccw(it->second)));
    }
}

} // namespace

// ---- public queries ----

extern "C" iir_tri_status iir_stri_shortest_edge(const iir_stri *s, uint32_t *denser_id,
                                                 uint32_t *other_id, double *angle)
{
    if (!s) return IIR_TRI_BAD_ARG;
    return guard([&] {
        if (s->table.order.size() < 2) return IIR_TRI_TOO_FEW;
        Edge_key e = shortest_edge(s->table);
        Vertex_handle young = vertex_of(s, e.young), old = vertex_of(s, e.old);
        // Ties (including "no third site") go to the younger endpoint.
        double dy = second_nearest(s->dt, young, old);
        double dold = second_nearest(s->dt, old, young);
        bool young_denser = dy <= dold;
        if (denser_id) *denser_id = young_denser ? e.young : e.old;
        if (other_id) *other_id = young_denser ? e.old : e.young;
        if (angle) *angle = e.angle;
        return IIR_TRI_OK;
    });
}

extern "C" iir_tri_status iir_stri_edges(const iir_stri *s, uint32_t *pairs, size_t cap, size_t *n)
{
    if (!s || !n) return IIR_TRI_BAD_ARG;
    return guard([&] {
        std::vector<std::pair<uint32_t, uint32_t>> edges;
        if (s->table.order.size() >= 2) all_edges(s, edges);
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

// tri_query.cpp -- questions answered by the Delaunay graph itself: neighbours, the shortest edge
// and its denser endpoint, the edge list for drawing; not the Voronoi cells (tri_voronoi.cpp).
#include "tri_internal.hpp"

#include <algorithm>
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

// Finite Delaunay neighbours of v. The circulator also works in dimension 1 (collinear sites),
// where it alternates between the two edges at v; in dimension 0 it is empty.
template <class Fn> void for_each_neighbour(const Delaunay &dt, Vertex_handle v, Fn &&fn)
{
    Delaunay::Vertex_circulator c = dt.incident_vertices(v), done = c;
    if (c == nullptr) return;
    do {
        if (!dt.is_infinite(c)) fn(Vertex_handle(c));
    } while (++c != done);
}

// An edge as its two endpoints, the younger (larger id) first.
struct Edge {
    Vertex_handle young, old;
    double len2;
};

// Edge order for "shortest": shorter first; among equal lengths, the larger younger id, then the
// larger older id. A strict weak order that depends only on positions and ids.
bool shorter(const Edge &e, const Edge &f)
{
    if (e.len2 != f.len2) return e.len2 < f.len2;
    if (e.young->info() != f.young->info()) return e.young->info() > f.young->info();
    return e.old->info() > f.old->info();
}

Edge make_edge(const Delaunay::Edge &e)
{
    Vertex_handle a = e.first->vertex(Delaunay::cw(e.second));
    Vertex_handle b = e.first->vertex(Delaunay::ccw(e.second));
    if (a->info() < b->info()) std::swap(a, b);
    return {a, b, dist2(a->point(), b->point())};
}

Edge shortest_edge(const Delaunay &dt)
{
    auto it = dt.finite_edges_begin();
    Edge best = make_edge(*it);
    for (++it; it != dt.finite_edges_end(); ++it) {
        Edge e = make_edge(*it);
        if (shorter(e, best)) best = e;
    }
    return best;
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

} // namespace

// ---- the bridge ----

bool iirtri::neighbours(const iir_tri *tri, uint32_t id, Site &self, std::vector<Site> &out)
{
    out.clear();
    auto it = tri->by_id.find(id);
    if (it == tri->by_id.end()) return false;
    self = site_of(it->second);
    for_each_neighbour(tri->dt, it->second, [&](Vertex_handle o) { out.push_back(site_of(o)); });
    std::sort(out.begin(), out.end(), [](const Site &a, const Site &b) { return a.id < b.id; });
    return true;
}

// ---- public queries ----

extern "C" iir_tri_status iir_tri_shortest_edge(const iir_tri *tri, uint32_t *denser_id,
                                                uint32_t *other_id, double *length)
{
    if (!tri) return IIR_TRI_BAD_ARG;
    return guard([&] {
        if (tri->by_id.size() < 2) return IIR_TRI_TOO_FEW;
        Edge e = shortest_edge(tri->dt);
        // Ties (including "no third site") go to the younger endpoint, e.young.
        double dy = second_nearest2(tri->dt, e.young, e.old);
        double dold = second_nearest2(tri->dt, e.old, e.young);
        bool young_denser = dy <= dold;
        Vertex_handle denser = young_denser ? e.young : e.old;
        Vertex_handle other = young_denser ? e.old : e.young;
        if (denser_id) *denser_id = denser->info();
        if (other_id) *other_id = other->info();
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
            Edge e = make_edge(*it);
            edges.emplace_back(e.old->info(), e.young->info());
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

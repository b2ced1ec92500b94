// tri_domain.cpp -- the disk (tri.h): CGAL's Delaunay_triangulation_2 as the geometry of the
// shared handle (tri_handle.hpp), and tri.h's functions over it; not the handle's logic
// (tri_handle.hpp) nor the clipped cells (tri_cell.cpp). The only disk translation unit that
// includes CGAL (each costs ~20 s to compile).
//
// Sites are stored as given; neighbours are ordered by ascending id, so a cell does not depend on
// CGAL's storage order. A position already taken is found by CGAL's locate (an exact predicate).
#include "tri_cell.hpp"
#include "tri_handle.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

namespace iirdisk
{

using iirtri::Vertex_info;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<Vertex_info, K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb>;
using Delaunay = CGAL::Delaunay_triangulation_2<K, Tds>;
using Point = Delaunay::Point;
using Vertex_handle = Delaunay::Vertex_handle;

// The disk as the handle's geometry (see the list at the top of tri_handle.hpp).
struct Disk {
    using Vec = Vec2;
    using Site = iirdisk::Site;
    using Candidate = iirdisk::Candidate;
    using Cell = iirdisk::Cell;
    using Cell_scratch = iirdisk::Cell_scratch;
    using Context = double; // R
    using Delaunay = iirdisk::Delaunay;
    using Vertex_handle = iirdisk::Vertex_handle;
    static constexpr size_t kDim = 2;

    // ---- points and the metric ----

    static Vec2 vec_of(const Point &p) { return {p.x(), p.y()}; }
    static void put(Vec2 v, double *out) { out[0] = v.x, out[1] = v.y; }
    static iir_tri_status check_point(const Delaunay &, double R, const double *p, Vec2 &out)
    {
        if (!std::isfinite(p[0]) || !std::isfinite(p[1])) return IIR_TRI_BAD_ARG;
        const double lim = R * (1.0 + IIR_TRI_OUTSIDE_TOL);
        if (p[0] * p[0] + p[1] * p[1] > lim * lim) return IIR_TRI_OUTSIDE;
        out = {p[0], p[1]};
        return IIR_TRI_OK;
    }
    static double distance(Vec2 a, Vec2 b) { return dist2(a, b); }
    static double edge_length(double len2) { return std::sqrt(len2); }
    static double radius(Vec2 c, Vec2 s) { return std::hypot(c.x - s.x, c.y - s.y); }

    // ---- the graph ----

    template <class Fn> static void for_each_vertex(const Delaunay &dt, Fn &&fn)
    {
        for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) fn(v);
    }
    // Each finite neighbour of v. The circulator also works in dimension 1 (collinear sites),
    // where it alternates between the two edges at v; in dimension 0 it is empty.
    template <class Fn> static void for_each_neighbour(const Delaunay &dt, Vertex_handle v, Fn &&fn)
    {
        Delaunay::Vertex_circulator c = dt.incident_vertices(v), done = c;
        if (c == nullptr) return;
        do {
            if (!dt.is_infinite(c)) fn(Vertex_handle(c));
        } while (++c != done);
    }
    template <class Fn> static void for_each_edge(const Delaunay &dt, Fn &&fn)
    {
        for (auto e = dt.finite_edges_begin(); e != dt.finite_edges_end(); ++e)
            fn(e->first->vertex(Delaunay::cw(e->second)),
               e->first->vertex(Delaunay::ccw(e->second)));
    }
    // The neighbours of v as sites, ascending id (with collinear sites: the previous and next).
    static void gather_neighbours(const Delaunay &dt, Vertex_handle v, std::vector<Site> &out)
    {
        out.clear();
        for_each_neighbour(dt, v, [&](Vertex_handle o) {
            out.push_back({vec_of(o->point()), o->info().id});
        });
        std::sort(out.begin(), out.end(), [](const Site &a, const Site &b) { return a.id < b.id; });
    }
    static Vertex_handle nearest(const Delaunay &dt, Vec2 p, Vertex_handle)
    {
        return dt.nearest_vertex(Point(p.x, p.y));
    }

    // ---- edits ----

    static bool drop_repeated(const std::vector<Vec2> &pts, const uint32_t *ids,
                              std::vector<size_t> &keep);
    static bool triangulate(const std::vector<Vec2> &pts, const uint32_t *ids,
                            const std::vector<size_t> &keep, Delaunay &dt,
                            std::vector<Vertex_handle> &vertex);
    static iir_tri_status insert(Delaunay &dt, Vec2 q, Vertex_handle, Vertex_handle &v)
    {
        Point p(q.x, q.y);
        Delaunay::Locate_type lt;
        int li;
        Delaunay::Face_handle f = dt.locate(p, lt, li);
        if (lt == Delaunay::VERTEX) return IIR_TRI_DUPLICATE_POINT;
        v = dt.insert(p, lt, f, li);
        return IIR_TRI_OK;
    }
    // A cell depends on its site, its neighbours and R only, so a build keeps a summary whatever
    // the dimension; a change of dimension (collinear <-> not) may change any neighbour list.
    static bool full_refresh(int before, int after) { return before != after; }
    static bool reusable(int, int) { return true; }
    template <class Table, class Vertices>
    static void update_context(const Delaunay &, const Table &, const Vertices &,
                               std::vector<Site> &, double &)
    {
    }

    // ---- cells ----

    static const Cell &make_cell(const Site &self, const std::vector<Site> &nbrs, int, double R,
                                 Cell_scratch &s)
    {
        return clip_cell(self, nbrs.data(), nbrs.size(), R, s);
    }
    static double area(const Cell &c) { return cell_area(c); }
    static void candidates(const Cell &c, std::vector<Candidate> &out) { far_candidates(c, out); }
    static void polygon(const Cell &c, std::vector<Vec2> &out) { cell_polygon(c, out); }
    static bool shortest_incident(const Site &self, const std::vector<Site> &nbrs,
                                  iirtri::Edge_key &out)
    {
        return iirdisk::shortest_incident(self, nbrs.data(), nbrs.size(), out);
    }
};

// Input indices with repeated positions removed, keeping the smallest id at each position. Returns
// whether anything was dropped.
bool Disk::drop_repeated(const std::vector<Vec2> &pts, const uint32_t *ids,
                         std::vector<size_t> &keep)
{
    keep.resize(pts.size());
    std::iota(keep.begin(), keep.end(), size_t{0});
    auto key = [&](size_t i) { return std::make_tuple(pts[i].x, pts[i].y, ids[i]); };
    std::sort(keep.begin(), keep.end(), [&](size_t a, size_t b) { return key(a) < key(b); });
    auto same_place = [&](size_t a, size_t b) {
        return pts[a].x == pts[b].x && pts[a].y == pts[b].y;
    };
    auto end = std::unique(keep.begin(), keep.end(), same_place);
    bool dropped = end != keep.end();
    keep.erase(end, keep.end());
    return dropped;
}

// Triangulates pts[keep[k]] into dt by CGAL's bulk insertion (a spatial sort), giving vertex k the
// info {ids[keep[k]], k}. False if CGAL merged points (never: they are distinct).
bool Disk::triangulate(const std::vector<Vec2> &pts, const uint32_t *ids,
                       const std::vector<size_t> &keep, Delaunay &dt,
                       std::vector<Vertex_handle> &vertex)
{
    const size_t m = keep.size();
    std::vector<std::pair<Point, Vertex_info>> in;
    in.reserve(m);
    for (size_t i : keep)
        in.emplace_back(Point(pts[i].x, pts[i].y), Vertex_info{ids[i], (uint32_t)in.size()});
    dt.insert(in.begin(), in.end());
    if (dt.number_of_vertices() != m) return false;
    vertex.resize(m);
    for_each_vertex(dt, [&](Vertex_handle v) { vertex[v->info().slot] = v; });
    return true;
}

} // namespace iirdisk

struct iir_tri : iirtri::Handle<iirdisk::Disk> {
};

using iirtri::guard;

// ---- lifetime ----

extern "C" const char *iir_tri_status_name(iir_tri_status status)
{
    switch (status) {
    case IIR_TRI_OK:
        return "ok";
    case IIR_TRI_BAD_ARG:
        return "bad_arg";
    case IIR_TRI_OUTSIDE:
        return "outside";
    case IIR_TRI_DUPLICATE_ID:
        return "duplicate_id";
    case IIR_TRI_DUPLICATE_POINT:
        return "duplicate_point";
    case IIR_TRI_UNKNOWN_ID:
        return "unknown_id";
    case IIR_TRI_TOO_FEW:
        return "too_few";
    case IIR_TRI_CAPACITY:
        return "capacity";
    case IIR_TRI_NO_MEMORY:
        return "no_memory";
    case IIR_TRI_INTERNAL:
        return "internal";
    }
    return "unknown";
}

extern "C" iir_tri *iir_tri_create(double radius)
{
    if (!std::isfinite(radius) || radius <= 0) return nullptr;
    try {
        iir_tri *tri = new iir_tri();
        tri->ctx = radius;
        return tri;
    } catch (...) {
        return nullptr;
    }
}

extern "C" void iir_tri_destroy(iir_tri *tri)
{
    delete tri;
}

extern "C" double iir_tri_radius(const iir_tri *tri)
{
    return tri ? tri->ctx : 0.0;
}

extern "C" size_t iir_tri_count(const iir_tri *tri)
{
    return tri ? tri->count() : 0;
}

// ---- building and editing ----

extern "C" iir_tri_status iir_tri_build(iir_tri *tri, const double *xy, const uint32_t *ids,
                                        size_t n)
{
    return tri ? tri->build(xy, ids, n) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_tri_insert(iir_tri *tri, double x, double y, uint32_t id)
{
    const double p[2] = {x, y};
    return tri ? tri->insert(p, id) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_tri_remove(iir_tri *tri, uint32_t id)
{
    return tri ? tri->remove(id) : IIR_TRI_BAD_ARG;
}

// ---- lookup ----

extern "C" iir_tri_status iir_tri_position(const iir_tri *tri, uint32_t id, double xy[2])
{
    return tri ? tri->position(id, xy) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_tri_ids(const iir_tri *tri, uint32_t *ids, size_t cap, size_t *n)
{
    return tri ? tri->ids(ids, cap, n) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_tri_nearest(const iir_tri *tri, double x, double y, uint32_t *id,
                                          double *distance)
{
    if (!tri || !std::isfinite(x) || !std::isfinite(y)) return IIR_TRI_BAD_ARG;
    return guard([&] {
        if (tri->count() == 0) return IIR_TRI_TOO_FEW;
        iirdisk::Vertex_handle v = iirdisk::Disk::nearest(tri->dt, {x, y}, {});
        if (id) *id = v->info().id;
        if (distance) *distance = iirdisk::Disk::radius({x, y}, iirdisk::Disk::vec_of(v->point()));
        return IIR_TRI_OK;
    });
}

// ---- queries ----

extern "C" iir_tri_status iir_tri_shortest_edge(const iir_tri *tri, uint32_t *denser_id,
                                                uint32_t *other_id, double *length)
{
    return tri ? tri->shortest_edge(denser_id, other_id, length) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_tri_largest_empty_circle(const iir_tri *tri, double centre[2],
                                                       double *radius)
{
    return tri ? tri->largest_empty(centre, radius) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_tri_cell_area(const iir_tri *tri, uint32_t id, double *area)
{
    return tri ? tri->cell_area(id, area) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_tri_cell_areas(const iir_tri *tri, uint32_t *ids, double *areas,
                                             size_t cap, size_t *n)
{
    return tri ? tri->cell_areas(ids, areas, cap, n) : IIR_TRI_BAD_ARG;
}

// ---- drawing ----

extern "C" iir_tri_status iir_tri_edges(const iir_tri *tri, uint32_t *pairs, size_t cap, size_t *n)
{
    return tri ? tri->edges(pairs, cap, n) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_tri_cell_polygon(const iir_tri *tri, uint32_t id, double *xy,
                                               size_t cap, size_t *n)
{
    return tri ? tri->cell_polygon(id, xy, cap, n) : IIR_TRI_BAD_ARG;
}

// stri_domain.cpp -- the sphere (stri.h): CGAL's Delaunay_triangulation_on_sphere_2 as the
// geometry of the shared handle (tri_handle.hpp), and stri.h's functions over it; not the handle's
// logic (tri_handle.hpp) nor the cell geometry (stri_cell.cpp). The only sphere translation unit
// that includes CGAL.
//
// Points are normalised until CGAL's traits accept them as on the sphere. CGAL's on-sphere traits
// refuse a point closer than 2^-23 to a vertex, but only notice it near the located face; so points
// that close never reach CGAL: build drops them beforehand (a grid over the cube, by ascending
// id), insert refuses them after walking to the nearest site. A cell's neighbours are
// counter-clockwise from the smallest id (dimension 2); while all sites lie on one circle
// (dimension 1) every cell also depends on the circle's plane, the handle's context, so every
// edit then redoes all summaries.
#include "stri_geom.hpp"
#include "tri_handle.hpp"

#include <CGAL/Delaunay_triangulation_on_sphere_2.h>
#include <CGAL/Delaunay_triangulation_on_sphere_traits_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_data_structure_2.h>
#include <CGAL/Triangulation_on_sphere_face_base_2.h>
#include <CGAL/Triangulation_on_sphere_vertex_base_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <utility>

namespace iirstri
{

// The unit sphere at the origin (the traits' defaults).
using iirtri::Vertex_info;
using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Gt = CGAL::Delaunay_triangulation_on_sphere_traits_2<K>;
using Vb =
    CGAL::Triangulation_vertex_base_with_info_2<Vertex_info, Gt,
                                                CGAL::Triangulation_on_sphere_vertex_base_2<Gt>>;
using Fb = CGAL::Triangulation_on_sphere_face_base_2<Gt>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using Delaunay = CGAL::Delaunay_triangulation_on_sphere_2<Gt, Tds>;
using Point = Delaunay::Point;
using Vertex_handle = Delaunay::Vertex_handle;

// The sphere as the handle's geometry (see the list at the top of tri_handle.hpp).
struct Sphere {
    using Vec = Vec3;
    using Site = iirstri::Site;
    using Candidate = iirstri::Candidate;
    using Cell = iirstri::Cell;
    using Cell_scratch = iirstri::Cell_scratch;
    using Context = Frame; // the plane of all sites in dimension 1
    using Delaunay = iirstri::Delaunay;
    using Vertex_handle = iirstri::Vertex_handle;
    static constexpr size_t kDim = 3;

    // ---- points and the metric ----

    static Vec3 vec_of(const Point &p) { return {p.x(), p.y(), p.z()}; }
    static void put(Vec3 v, double *out) { out[0] = v.x, out[1] = v.y, out[2] = v.z; }
    static iir_tri_status check_point(const Delaunay &dt, const Frame &, const double *p,
                                      Vec3 &out);
    static double distance(Vec3 a, Vec3 b) { return angle_between(a, b); }
    static double edge_length(double angle) { return angle; }
    static double radius(Vec3 c, Vec3 s) { return angle_between(c, s); }

    // ---- the graph ----

    template <class Fn> static void for_each_vertex(const Delaunay &dt, Fn &&fn)
    {
        for (auto v = dt.vertices_begin(); v != dt.vertices_end(); ++v) fn(v);
    }
    // Each neighbour of v: counter-clockwise seen from outside in dimension 2 (faces are oriented
    // so), the two neighbours on the circle in dimension 1, none below (two sites are each
    // other's neighbour, but CGAL keeps no edge between them: see gather_neighbours).
    template <class Fn> static void for_each_neighbour(const Delaunay &dt, Vertex_handle v, Fn &&fn)
    {
        if (dt.dimension() < 1) return;
        Delaunay::Vertex_circulator c = dt.incident_vertices(v), done = c;
        if (c == nullptr) return;
        do fn(Vertex_handle(c));
        while (++c != done);
    }
    // Every Delaunay edge. Two sites have one, which CGAL (dimension 0) does not store; in
    // dimension 1 the "faces" are the edges around the circle.
    template <class Fn> static void for_each_edge(const Delaunay &dt, Fn &&fn)
    {
        if (dt.number_of_vertices() < 2) return;
        if (dt.dimension() == 0) return fn(dt.vertices_begin(), std::next(dt.vertices_begin()));
        for (auto it = dt.all_edges_begin(); it != dt.all_edges_end(); ++it) {
            Delaunay::Face_handle f = it->first;
            if (dt.dimension() == 1)
                fn(f->vertex(0), f->vertex(1));
            else
                fn(f->vertex(Delaunay::cw(it->second)), f->vertex(Delaunay::ccw(it->second)));
        }
    }
    static void gather_neighbours(const Delaunay &dt, Vertex_handle v, std::vector<Site> &out);
    static Vertex_handle nearest(const Delaunay &dt, Vec3 p, Vertex_handle from);

    // ---- edits ----

    static bool drop_repeated(const std::vector<Vec3> &pts, const uint32_t *ids,
                              std::vector<size_t> &keep);
    static bool triangulate(const std::vector<Vec3> &pts, const uint32_t *ids,
                            const std::vector<size_t> &keep, Delaunay &dt,
                            std::vector<Vertex_handle> &vertex);
    static iir_tri_status insert(Delaunay &dt, Vec3 q, Vertex_handle start, Vertex_handle &v);
    // In dimension 1 every cell depends on the plane of all sites; below, there are two sites.
    static bool full_refresh(int before, int after) { return !(before == 2 && after == 2); }
    static bool reusable(int old_dim, int new_dim) { return old_dim == 2 && new_dim == 2; }
    // The frame of a one-circle set, from its sites by ascending id (`work`: working storage).
    template <class Table, class Vertices>
    static void update_context(const Delaunay &dt, const Table &table, const Vertices &vertex,
                               std::vector<Site> &work, Frame &frame)
    {
        frame = Frame{};
        if (dt.dimension() != 1) return;
        work.clear();
        for (const iirtri::Id_slot &e : table.order)
            work.push_back({vec_of(vertex[e.slot]->point()), e.id});
        frame = circle_frame(work.data(), work.size());
    }

    // ---- cells ----

    static const Cell &make_cell(const Site &self, const std::vector<Site> &nbrs, int dim,
                                 const Frame &frame, Cell_scratch &s)
    {
        return iirstri::make_cell(Cell_input{dim, self, nbrs.data(), nbrs.size(), frame}, s);
    }
    static double area(const Cell &c) { return c.area; }
    static void candidates(const Cell &c, std::vector<Candidate> &out) { cap_candidates(c, out); }
    static void polygon(const Cell &c, std::vector<Vec3> &out) { cell_polygon(c, out); }
    static bool shortest_incident(const Site &self, const std::vector<Site> &nbrs,
                                  iirtri::Edge_key &out)
    {
        return iirstri::shortest_incident(self, nbrs.data(), nbrs.size(), out);
    }
};

namespace
{

// ---- points ----

// p as a unit vector CGAL accepts as on the sphere; IIR_TRI_BAD_ARG when p is not finite or its
// length is off 1 by more than IIR_STRI_UNIT_TOL.
iir_tri_status to_unit(const double *p, const Gt &gt, Vec3 &out)
{
    Vec3 v = {p[0], p[1], p[2]};
    if (!std::isfinite(v.x) || !std::isfinite(v.y) || !std::isfinite(v.z)) return IIR_TRI_BAD_ARG;
    double l = norm(v);
    if (!(std::fabs(l - 1) <= IIR_STRI_UNIT_TOL)) return IIR_TRI_BAD_ARG;
    for (int k = 0; k < 4; k++) {
        v = {v.x / l, v.y / l, v.z / l};
        if (gt.is_on_sphere(Point(v.x, v.y, v.z))) {
            out = v;
            return IIR_TRI_OK;
        }
        l = norm(v);
    }
    return IIR_TRI_INTERNAL; // normalising did not land on the sphere: never seen
}

bool too_close(Vec3 a, Vec3 b)
{
    Vec3 d = a - b;
    return dot(d, d) <= IIR_STRI_MIN_DIST * IIR_STRI_MIN_DIST;
}

// ---- dropping points too close to an older one (build) ----

constexpr double kGridCell = 0x1p-19; // grid side, >= IIR_STRI_MIN_DIST

int64_t grid_index(double x)
{
    return (int64_t)std::floor(x / kGridCell) + (int64_t{1} << 20); // in [0, 2^21) on [-1, 1]
}

uint64_t grid_key(int64_t i, int64_t j, int64_t k)
{
    return ((uint64_t)i << 42) | ((uint64_t)j << 21) | (uint64_t)k;
}

// ---- the nearest site ----

// A greedy walk from v over Delaunay neighbours while `nearer(candidate, current)`: it ends at the
// site nearest to p (a site that is not the nearest always has a neighbour nearer to p, its Voronoi
// cell being bounded by its neighbours' bisectors).
template <class Nearer> Vertex_handle walk(const Delaunay &dt, Vertex_handle v, Nearer &&nearer)
{
    if (dt.dimension() < 1) {
        for (auto w = dt.vertices_begin(); w != dt.vertices_end(); ++w)
            if (nearer(w, v)) v = w;
        return v;
    }
    for (;;) {
        Vertex_handle next = v;
        Sphere::for_each_neighbour(dt, v, [&](Vertex_handle o) {
            if (nearer(o, next)) next = o;
        });
        if (next == v) return v;
        v = next;
    }
}

// A point that remembers its index in `keep`, for the spatial sort (as CGAL's own bulk insertion
// does internally).
struct Indexed_point : Point {
    Indexed_point(Vec3 p, uint32_t k) : Point(p.x, p.y, p.z), k(k) {}
    uint32_t k;
};

} // namespace

iir_tri_status Sphere::check_point(const Delaunay &dt, const Frame &, const double *p, Vec3 &out)
{
    return to_unit(p, dt.geom_traits(), out);
}

// Input indices to keep: visiting points by ascending id, each point within IIR_STRI_MIN_DIST of
// a point already kept is dropped. Returns whether anything was dropped. A point's close partners
// lie in the grid cells its IIR_STRI_MIN_DIST box touches (mostly just its own).
bool Sphere::drop_repeated(const std::vector<Vec3> &pts, const uint32_t *ids,
                           std::vector<size_t> &keep)
{
    const size_t n = pts.size();
    std::vector<std::pair<uint64_t, size_t>> cells(n);
    for (size_t i = 0; i < n; i++)
        cells[i] = {grid_key(grid_index(pts[i].x), grid_index(pts[i].y), grid_index(pts[i].z)), i};
    std::sort(cells.begin(), cells.end());
    std::vector<size_t> by_id(n);
    std::iota(by_id.begin(), by_id.end(), size_t{0});
    std::sort(by_id.begin(), by_id.end(), [&](size_t a, size_t b) { return ids[a] < ids[b]; });
    std::vector<char> kept(n, 0);
    const double D = IIR_STRI_MIN_DIST;
    auto close_to_kept = [&](size_t i) {
        const Vec3 p = pts[i];
        for (int64_t a = grid_index(p.x - D); a <= grid_index(p.x + D); a++)
            for (int64_t b = grid_index(p.y - D); b <= grid_index(p.y + D); b++)
                for (int64_t c = grid_index(p.z - D); c <= grid_index(p.z + D); c++) {
                    auto it = std::lower_bound(cells.begin(), cells.end(),
                                               std::make_pair(grid_key(a, b, c), size_t{0}));
                    for (; it != cells.end() && it->first == grid_key(a, b, c); ++it)
                        if (kept[it->second] && too_close(p, pts[it->second])) return true;
                }
        return false;
    };
    keep.clear();
    for (size_t i : by_id)
        if (!close_to_kept(i)) {
            kept[i] = 1;
            keep.push_back(i);
        }
    return keep.size() != n;
}

// The vertex nearest to p, from v: a cheap walk by dot product, then one by geodesic distance
// (near pi the dot product cannot tell sites ~1e-14 apart, angle_between can).
Vertex_handle Sphere::nearest(const Delaunay &dt, Vec3 p, Vertex_handle v)
{
    v = walk(dt, v, [&](Vertex_handle a, Vertex_handle b) {
        return dot(p, vec_of(a->point())) > dot(p, vec_of(b->point()));
    });
    return walk(dt, v, [&](Vertex_handle a, Vertex_handle b) {
        return angle_between(p, vec_of(a->point())) < angle_between(p, vec_of(b->point()));
    });
}

// The Delaunay neighbours of v as sites, in the order Cell_input wants.
void Sphere::gather_neighbours(const Delaunay &dt, Vertex_handle v, std::vector<Site> &out)
{
    out.clear();
    if (dt.dimension() == 0) {
        for (auto w = dt.vertices_begin(); w != dt.vertices_end(); ++w)
            if (Vertex_handle(w) != v) out.push_back({vec_of(w->point()), w->info().id});
        return;
    }
    for_each_neighbour(dt, v, [&](Vertex_handle o) {
        out.push_back({vec_of(o->point()), o->info().id});
    });
    if (dt.dimension() == 2) {
        auto smallest = std::min_element(out.begin(), out.end(),
                                         [](const Site &a, const Site &b) { return a.id < b.id; });
        std::rotate(out.begin(), smallest, out.end());
    }
}

// Refuses q within IIR_STRI_MIN_DIST of the site nearest to it (walking from `start`, if any)
// before changing anything; then inserts it with that site's face as hint.
iir_tri_status Sphere::insert(Delaunay &dt, Vec3 q, Vertex_handle start, Vertex_handle &v)
{
    Vertex_handle near;
    if (start != Vertex_handle()) {
        near = nearest(dt, q, start);
        if (too_close(q, vec_of(near->point()))) return IIR_TRI_DUPLICATE_POINT;
    }
    const size_t nv = dt.number_of_vertices();
    Delaunay::Face_handle hint = dt.dimension() == 2 ? near->face() : Delaunay::Face_handle();
    v = dt.insert(Point(q.x, q.y, q.z), hint);
    if (v == Vertex_handle() || dt.number_of_vertices() != nv + 1) return IIR_TRI_INTERNAL;
    return IIR_TRI_OK;
}

// Triangulates pts[keep[k]] into dt, giving vertex k the info {ids[keep[k]], k}: points are
// inserted in CGAL's spatial order on the sphere (a Hilbert sort with a fixed seed), each with the
// previous vertex as hint. False if CGAL refused a point (never: they are on the sphere and apart).
bool Sphere::triangulate(const std::vector<Vec3> &pts, const uint32_t *ids,
                         const std::vector<size_t> &keep, Delaunay &dt,
                         std::vector<Vertex_handle> &vertex)
{
    const size_t m = keep.size();
    std::vector<Indexed_point> points;
    points.reserve(m);
    for (size_t k = 0; k < m; k++) points.emplace_back(pts[keep[k]], (uint32_t)k);
    CGAL::spatial_sort_on_sphere(points.begin(), points.end(), dt.geom_traits(), 1.0,
                                 Point(0, 0, 0));
    vertex.assign(m, Vertex_handle());
    Delaunay::Face_handle hint;
    for (const Indexed_point &p : points) {
        const size_t before = dt.number_of_vertices();
        Vertex_handle v = dt.insert(static_cast<const Point &>(p), hint);
        if (v == Vertex_handle() || dt.number_of_vertices() != before + 1) return false;
        v->info() = {ids[keep[p.k]], p.k};
        vertex[p.k] = v;
        hint = v->face();
    }
    return true;
}

} // namespace iirstri

struct iir_stri : iirtri::Handle<iirstri::Sphere> {
};

// ---- lifetime ----

extern "C" iir_stri *iir_stri_create(void)
{
    try {
        return new iir_stri();
    } catch (...) {
        return nullptr;
    }
}

extern "C" void iir_stri_destroy(iir_stri *s)
{
    delete s;
}

extern "C" size_t iir_stri_count(const iir_stri *s)
{
    return s ? s->count() : 0;
}

// ---- building and editing ----

extern "C" iir_tri_status iir_stri_build(iir_stri *s, const double *xyz, const uint32_t *ids,
                                         size_t n)
{
    return s ? s->build(xyz, ids, n) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_stri_insert(iir_stri *s, const double p[3], uint32_t id)
{
    return s ? s->insert(p, id) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_stri_remove(iir_stri *s, uint32_t id)
{
    return s ? s->remove(id) : IIR_TRI_BAD_ARG;
}

// ---- lookup ----

extern "C" iir_tri_status iir_stri_position(const iir_stri *s, uint32_t id, double p[3])
{
    return s ? s->position(id, p) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_stri_ids(const iir_stri *s, uint32_t *ids, size_t cap, size_t *n)
{
    return s ? s->ids(ids, cap, n) : IIR_TRI_BAD_ARG;
}

// ---- queries ----

extern "C" iir_tri_status iir_stri_shortest_edge(const iir_stri *s, uint32_t *denser_id,
                                                 uint32_t *other_id, double *angle)
{
    return s ? s->shortest_edge(denser_id, other_id, angle) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_stri_largest_empty_cap(const iir_stri *s, double centre[3],
                                                     double *angle)
{
    return s ? s->largest_empty(centre, angle) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_stri_cell_area(const iir_stri *s, uint32_t id, double *area)
{
    return s ? s->cell_area(id, area) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_stri_cell_areas(const iir_stri *s, uint32_t *ids, double *areas,
                                              size_t cap, size_t *n)
{
    return s ? s->cell_areas(ids, areas, cap, n) : IIR_TRI_BAD_ARG;
}

// ---- drawing ----

extern "C" iir_tri_status iir_stri_edges(const iir_stri *s, uint32_t *pairs, size_t cap, size_t *n)
{
    return s ? s->edges(pairs, cap, n) : IIR_TRI_BAD_ARG;
}

extern "C" iir_tri_status iir_stri_cell_polygon(const iir_stri *s, uint32_t id, double *xyz,
                                                size_t cap, size_t *n)
{
    return s ? s->cell_polygon(id, xyz, cap, n) : IIR_TRI_BAD_ARG;
}

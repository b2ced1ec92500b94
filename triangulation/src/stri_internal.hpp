// stri_internal.hpp -- the CGAL types behind an iir_stri handle and the handle itself; only
// stri_domain.cpp and stri_query.cpp include it (each CGAL translation unit is slow to compile),
// the cell geometry never does.
#ifndef IIR_STRI_INTERNAL_HPP
#define IIR_STRI_INTERNAL_HPP

#include "stri_geom.hpp"

#include <CGAL/Delaunay_triangulation_on_sphere_2.h>
#include <CGAL/Delaunay_triangulation_on_sphere_traits_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_data_structure_2.h>
#include <CGAL/Triangulation_on_sphere_face_base_2.h>
#include <CGAL/Triangulation_on_sphere_vertex_base_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

namespace iirstri
{

// What a vertex carries: the caller's id and the slot of its entry in the Site_table.
struct Vertex_info {
    uint32_t id, slot;
};

// The unit sphere at the origin (the traits' defaults).
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

inline Vec3 vec_of(const Point &p)
{
    return {p.x(), p.y(), p.z()};
}

inline Site site_of(Vertex_handle v)
{
    return Site{vec_of(v->point()), v->info().id};
}

// Calls fn on each Delaunay neighbour of v: counter-clockwise seen from outside in dimension 2
// (faces are oriented so), the two neighbours on the circle in dimension 1, none below (two sites
// are each other's neighbour, but CGAL keeps no edge between them: see for_each_site).
template <class Fn> void for_each_neighbour(const Delaunay &dt, Vertex_handle v, Fn &&fn)
{
    if (dt.dimension() < 1) return;
    Delaunay::Vertex_circulator c = dt.incident_vertices(v), done = c;
    if (c == nullptr) return;
    do fn(Vertex_handle(c));
    while (++c != done);
}

} // namespace iirstri

// The handle. Invariants: `table.order` lists every vertex's id once with its slot; vertex[slot] is
// that vertex and its info() is {id, slot}; table.summary[slot] is the summary of its current cell
// input (stri_geom.hpp); `frame` is the plane of all sites while the dimension is 1. `scratch`,
// `spare`, `spare_vertex`, `affected`, `before` and `sites` are working storage of the mutations
// only (never read by a const function), kept to reuse their capacity.
struct iir_stri {
    iirstri::Delaunay dt;
    iirstri::Site_table table;
    std::vector<iirstri::Vertex_handle> vertex; // by slot
    iirstri::Frame frame;
    iirstri::Cell_scratch scratch;
    iirstri::Site_table spare;
    std::vector<iirstri::Vertex_handle> spare_vertex;
    std::vector<uint32_t> affected;
    std::vector<iirstri::Site> before, sites;
};

#endif

// tri_internal.hpp -- the CGAL types behind an iir_tri handle and the handle itself; only
// tri_domain.cpp and tri_query.cpp include it (each CGAL translation unit costs ~20 s to compile),
// the geometry never does.
#ifndef IIR_TRI_INTERNAL_HPP
#define IIR_TRI_INTERNAL_HPP

#include "tri_cache.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

namespace iirtri
{

// What a vertex carries: the caller's id and the slot of its entry in the Site_table.
struct Vertex_info {
    uint32_t id, slot;
};

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<Vertex_info, K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb>;
using Delaunay = CGAL::Delaunay_triangulation_2<K, Tds>;
using Point = Delaunay::Point;
using Vertex_handle = Delaunay::Vertex_handle;

inline Site site_of(Vertex_handle v)
{
    return Site{v->point().x(), v->point().y(), v->info().id};
}

// Calls fn on each finite Delaunay neighbour of v. The circulator also works in dimension 1
// (collinear sites), where it alternates between the two edges at v; in dimension 0 it is empty.
template <class Fn> void for_each_neighbour(const Delaunay &dt, Vertex_handle v, Fn &&fn)
{
    Delaunay::Vertex_circulator c = dt.incident_vertices(v), done = c;
    if (c == nullptr) return;
    do {
        if (!dt.is_infinite(c)) fn(Vertex_handle(c));
    } while (++c != done);
}

} // namespace iirtri

// The handle. Invariants: `table.order` lists every finite vertex's id once with its slot;
// vertex[slot] is that vertex and its info() is {id, slot}; table.summary[slot] is the summary of
// its current neighbour list (tri_cache.hpp). `scratch`, `spare`, `spare_vertex`, `affected` and
// `before` are working storage of the mutations only (never read by a const function), kept to
// reuse their capacity; their contents mean nothing between calls.
struct iir_tri {
    double R;
    iirtri::Delaunay dt;
    iirtri::Site_table table;
    std::vector<iirtri::Vertex_handle> vertex; // by slot
    iirtri::Cell_scratch scratch;
    iirtri::Site_table spare;
    std::vector<iirtri::Vertex_handle> spare_vertex;
    std::vector<uint32_t> affected;
    std::vector<iirtri::Site> before;
};

#endif

// tri_internal.hpp -- the CGAL types behind an iir_tri handle; only tri_domain.cpp and
// tri_query.cpp include it (each CGAL translation unit costs ~20 s to compile), the geometry never
// does.
#ifndef IIR_TRI_INTERNAL_HPP
#define IIR_TRI_INTERNAL_HPP

#include "tri_common.hpp"

#include <CGAL/Delaunay_triangulation_2.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <map>

namespace iirtri
{

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<uint32_t, K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb>;
using Delaunay = CGAL::Delaunay_triangulation_2<K, Tds>;
using Point = Delaunay::Point;
using Vertex_handle = Delaunay::Vertex_handle;

inline Site site_of(Vertex_handle v)
{
    return Site{v->point().x(), v->point().y(), v->info()};
}

} // namespace iirtri

// The handle. Invariant: `by_id` maps every finite vertex's info to that vertex, and nothing else.
struct iir_tri {
    double R;
    iirtri::Delaunay dt;
    std::map<uint32_t, iirtri::Vertex_handle> by_id;
};

#endif

// tri_common.hpp -- what the libiirtri sources share without CGAL: plain sites, the exception
// guard, and the bridge into the triangulation; not the CGAL types (tri_internal.hpp) nor any
// geometry.
#ifndef IIR_TRI_COMMON_HPP
#define IIR_TRI_COMMON_HPP

#include "iir/tri.h"

#include <cstdint>
#include <new>
#include <vector>

namespace iirtri
{

// A site as plain data: position in disk units and its id.
struct Site {
    double x, y;
    uint32_t id;
};

// Runs f (returning iir_tri_status) and turns any escaping exception into a status: no C++
// exception may cross the C API.
template <class F> iir_tri_status guard(F &&f) noexcept
{
    try {
        return f();
    } catch (const std::bad_alloc &) {
        return IIR_TRI_NO_MEMORY;
    } catch (...) {
        return IIR_TRI_INTERNAL;
    }
}

// The answer of a variable-size query (see BUFFERS in tri.h): reports the size, then says whether
// the caller's buffer can take it.
inline iir_tri_status fits(const void *buf, size_t cap, size_t need, size_t *n)
{
    *n = need;
    if (buf && cap < need) return IIR_TRI_CAPACITY;
    return IIR_TRI_OK;
}

// ---- the bridge into the triangulation (tri_domain.cpp, tri_query.cpp); may throw, callers guard
// ----

// The site `id` and its Delaunay neighbours (ascending id); false if there is no such site. With
// collinear sites the neighbours are the previous and next site on the line.
bool neighbours(const iir_tri *tri, uint32_t id, Site &self, std::vector<Site> &out);

// The nearest site to (x, y); false on an empty set.
bool nearest(const iir_tri *tri, double x, double y, Site &out);

} // namespace iirtri

#endif

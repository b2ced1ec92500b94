// tri_domain.cpp -- the iir_tri handle: lifetime, build/insert/remove, the id -> vertex map and
// lookups; not the Delaunay/Voronoi queries (tri_query.cpp, tri_voronoi.cpp).
#include "tri_internal.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>
#include <utility>

using namespace iirtri;

namespace
{

// ---- checks shared by build and insert ----

iir_tri_status check_point(const iir_tri *tri, double x, double y)
{
    if (!std::isfinite(x) || !std::isfinite(y)) return IIR_TRI_BAD_ARG;
    const double lim = tri->R * (1.0 + IIR_TRI_OUTSIDE_TOL);
    if (x * x + y * y > lim * lim) return IIR_TRI_OUTSIDE;
    return IIR_TRI_OK;
}

iir_tri_status check_build_input(const iir_tri *tri, const double *xy, const uint32_t *ids,
                                 size_t n)
{
    if (n > 0 && (!xy || !ids)) return IIR_TRI_BAD_ARG;
    for (size_t i = 0; i < n; i++) {
        iir_tri_status st = check_point(tri, xy[2 * i], xy[2 * i + 1]);
        if (st != IIR_TRI_OK) return st;
    }
    std::vector<uint32_t> sorted(ids, ids + n);
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
        return IIR_TRI_DUPLICATE_ID;
    return IIR_TRI_OK;
}

// Input indices with repeated positions removed, keeping the smallest id at each position. Returns
// whether anything was dropped.
bool unique_positions(const double *xy, const uint32_t *ids, size_t n, std::vector<size_t> &keep)
{
    keep.resize(n);
    std::iota(keep.begin(), keep.end(), size_t{0});
    auto key = [&](size_t i) { return std::make_tuple(xy[2 * i], xy[2 * i + 1], ids[i]); };
    std::sort(keep.begin(), keep.end(), [&](size_t a, size_t b) { return key(a) < key(b); });
    auto same_place = [&](size_t a, size_t b) {
        return xy[2 * a] == xy[2 * b] && xy[2 * a + 1] == xy[2 * b + 1];
    };
    auto end = std::unique(keep.begin(), keep.end(), same_place);
    bool dropped = end != keep.end();
    keep.erase(end, keep.end());
    return dropped;
}

// Runs a mutation; if it throws half-way, empties the handle so it is never left inconsistent.
template <class F> iir_tri_status mutate(iir_tri *tri, F &&f) noexcept
{
    iir_tri_status st = guard(f);
    if (st == IIR_TRI_NO_MEMORY || st == IIR_TRI_INTERNAL) {
        tri->dt.clear();
        tri->by_id.clear();
    }
    return st;
}

} // namespace

// ---- the bridge ----

void iirtri::sites(const iir_tri *tri, std::vector<Site> &out)
{
    out.clear();
    out.reserve(tri->by_id.size());
    for (const auto &kv : tri->by_id) out.push_back(site_of(kv.second));
}

bool iirtri::nearest(const iir_tri *tri, double x, double y, Site &out)
{
    if (tri->by_id.empty()) return false;
    out = site_of(tri->dt.nearest_vertex(Point(x, y)));
    return true;
}

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
        return new iir_tri{radius, {}, {}};
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
    return tri ? tri->R : 0.0;
}

extern "C" size_t iir_tri_count(const iir_tri *tri)
{
    return tri ? tri->by_id.size() : 0;
}

// ---- building and editing ----

extern "C" iir_tri_status iir_tri_build(iir_tri *tri, const double *xy, const uint32_t *ids,
                                        size_t n)
{
    if (!tri) return IIR_TRI_BAD_ARG;
    return guard([&] {
        iir_tri_status st = check_build_input(tri, xy, ids, n);
        if (st != IIR_TRI_OK) return st;
        std::vector<size_t> keep;
        bool dropped = unique_positions(xy, ids, n, keep);
        std::vector<std::pair<Point, uint32_t>> pts;
        pts.reserve(keep.size());
        for (size_t i : keep) pts.emplace_back(Point(xy[2 * i], xy[2 * i + 1]), ids[i]);
        // Build aside and swap in, so a failure keeps the previous set.
        Delaunay dt;
        dt.insert(pts.begin(), pts.end());
        std::map<uint32_t, Vertex_handle> by_id;
        for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v)
            by_id.emplace(v->info(), v);
        CGAL_assertion(by_id.size() == keep.size());
        tri->dt.swap(dt);
        tri->by_id.swap(by_id);
        return dropped ? IIR_TRI_DUPLICATE_POINT : IIR_TRI_OK;
    });
}

extern "C" iir_tri_status iir_tri_insert(iir_tri *tri, double x, double y, uint32_t id)
{
    if (!tri) return IIR_TRI_BAD_ARG;
    iir_tri_status st = check_point(tri, x, y);
    if (st != IIR_TRI_OK) return st;
    if (tri->by_id.count(id)) return IIR_TRI_DUPLICATE_ID;
    return mutate(tri, [&] {
        Point p(x, y);
        Delaunay::Locate_type lt;
        int li;
        Delaunay::Face_handle f = tri->dt.locate(p, lt, li);
        if (lt == Delaunay::VERTEX) return IIR_TRI_DUPLICATE_POINT;
        Vertex_handle v = tri->dt.insert(p, lt, f, li);
        v->info() = id;
        tri->by_id.emplace(id, v);
        return IIR_TRI_OK;
    });
}

extern "C" iir_tri_status iir_tri_remove(iir_tri *tri, uint32_t id)
{
    if (!tri) return IIR_TRI_BAD_ARG;
    auto it = tri->by_id.find(id);
    if (it == tri->by_id.end()) return IIR_TRI_UNKNOWN_ID;
    return mutate(tri, [&] {
        tri->dt.remove(it->second);
        tri->by_id.erase(it);
        return IIR_TRI_OK;
    });
}

// ---- lookup ----

extern "C" iir_tri_status iir_tri_position(const iir_tri *tri, uint32_t id, double xy[2])
{
    if (!tri || !xy) return IIR_TRI_BAD_ARG;
    auto it = tri->by_id.find(id);
    if (it == tri->by_id.end()) return IIR_TRI_UNKNOWN_ID;
    xy[0] = it->second->point().x();
    xy[1] = it->second->point().y();
    return IIR_TRI_OK;
}

extern "C" iir_tri_status iir_tri_ids(const iir_tri *tri, uint32_t *ids, size_t cap, size_t *n)
{
    if (!tri || !n) return IIR_TRI_BAD_ARG;
    iir_tri_status st = fits(ids, cap, tri->by_id.size(), n);
    if (st != IIR_TRI_OK || !ids) return st;
    size_t k = 0;
    for (const auto &kv : tri->by_id) ids[k++] = kv.first;
    return IIR_TRI_OK;
}

extern "C" iir_tri_status iir_tri_nearest(const iir_tri *tri, double x, double y, uint32_t *id,
                                          double *distance)
{
    if (!tri || !std::isfinite(x) || !std::isfinite(y)) return IIR_TRI_BAD_ARG;
    return guard([&] {
        Site s;
        if (!nearest(tri, x, y, s)) return IIR_TRI_TOO_FEW;
        if (id) *id = s.id;
        if (distance) *distance = std::hypot(x - s.x, y - s.y);
        return IIR_TRI_OK;
    });
}

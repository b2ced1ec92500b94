// tri_domain.cpp -- the iir_tri handle: lifetime, build/insert/remove, the id -> slot -> vertex
// index, lookups, and keeping the per-site summaries (tri_cache.hpp) current across edits; not the
// Delaunay/Voronoi queries (tri_query.cpp, tri_voronoi.cpp).
//
// Every mutation redoes, before it returns, the summaries of the sites whose neighbour lists it
// changed (see tri_cache.hpp for which), so queries read summaries and never recompute a cell.
// insert and remove redo O(degree) of them; build redoes those of the sites that moved or whose
// neighbours did (all of them when the light moved, none when it did not).
#include "tri_internal.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
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

// ---- keeping the summaries current ----

// The neighbours of v as sites, ascending id, into out.
void gather_neighbours(const Delaunay &dt, Vertex_handle v, std::vector<Site> &out)
{
    out.clear();
    for_each_neighbour(dt, v, [&](Vertex_handle o) { out.push_back(site_of(o)); });
    std::sort(out.begin(), out.end(), [](const Site &a, const Site &b) { return a.id < b.id; });
}

bool same_bits(double a, double b)
{
    return std::memcmp(&a, &b, sizeof a) == 0;
}

bool same_site(const Site &a, const Site &b)
{
    return a.id == b.id && same_bits(a.x, b.x) && same_bits(a.y, b.y);
}

// The summary tri already holds for `self` (its entry `was`, or nullptr if self.id is new), if self
// and its neighbours `nbrs` (ascending id) are, bit for bit, the site and neighbours it was
// computed from: a summary depends on nothing else (tri_cache.hpp). Lets iir_tri_build keep the
// cells a rebuild did not change, e.g. every cell when the light has not moved. `before` is working
// storage.
const Site_summary *unchanged_summary(const iir_tri *tri, const Id_slot *was, const Site &self,
                                      const std::vector<Site> &nbrs, std::vector<Site> &before)
{
    if (!was) return nullptr;
    Vertex_handle old = tri->vertex[was->slot];
    if (!same_site(site_of(old), self)) return nullptr;
    gather_neighbours(tri->dt, old, before);
    if (before.size() != nbrs.size()) return nullptr;
    for (size_t k = 0; k < nbrs.size(); k++)
        if (!same_site(before[k], nbrs[k])) return nullptr;
    return &tri->table.summary[was->slot];
}

void refresh(const Delaunay &dt, Vertex_handle v, double R, Cell_scratch &scratch,
             Site_summary &out)
{
    gather_neighbours(dt, v, scratch.nbrs);
    summarise(site_of(v), scratch.nbrs.data(), scratch.nbrs.size(), R, scratch, out);
}

void refresh_all(iir_tri *tri)
{
    for (const Id_slot &e : tri->table.order)
        refresh(tri->dt, tri->vertex[e.slot], tri->R, tri->scratch, tri->table.summary[e.slot]);
}

void refresh_affected(iir_tri *tri)
{
    for (uint32_t slot : tri->affected)
        refresh(tri->dt, tri->vertex[slot], tri->R, tri->scratch, tri->table.summary[slot]);
}

// Runs a mutation; if it throws half-way, empties the handle so it is never left inconsistent.
template <class F> iir_tri_status mutate(iir_tri *tri, F &&f) noexcept
{
    iir_tri_status st = guard(f);
    if (st == IIR_TRI_NO_MEMORY || st == IIR_TRI_INTERNAL) {
        tri->dt.clear();
        tri->table.clear();
        tri->vertex.clear();
    }
    return st;
}

} // namespace

// ---- the bridge ----

const Site_table &iirtri::site_table(const iir_tri *tri)
{
    return tri->table;
}

bool iirtri::neighbours(const iir_tri *tri, uint32_t id, Site &self, std::vector<Site> &out)
{
    out.clear();
    const Id_slot *e = tri->table.find(id);
    if (!e) return false;
    Vertex_handle v = tri->vertex[e->slot];
    self = site_of(v);
    for_each_neighbour(tri->dt, v, [&](Vertex_handle o) { out.push_back(site_of(o)); });
    std::sort(out.begin(), out.end(), [](const Site &a, const Site &b) { return a.id < b.id; });
    return true;
}

bool iirtri::nearest(const iir_tri *tri, double x, double y, Site &out)
{
    if (tri->table.order.empty()) return false;
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
        iir_tri *tri = new iir_tri();
        tri->R = radius;
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
    return tri ? tri->R : 0.0;
}

extern "C" size_t iir_tri_count(const iir_tri *tri)
{
    return tri ? tri->table.order.size() : 0;
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
        const size_t m = keep.size();
        std::vector<std::pair<Point, Vertex_info>> pts;
        pts.reserve(m);
        for (size_t i : keep)
            pts.emplace_back(Point(xy[2 * i], xy[2 * i + 1]),
                             Vertex_info{ids[i], (uint32_t)pts.size()});
        // Build the triangulation and its table aside and swap them in, so a failure keeps the
        // previous set. The slot of a site is its index in pts.
        Delaunay dt;
        dt.insert(pts.begin(), pts.end());
        if (dt.number_of_vertices() != m) return IIR_TRI_INTERNAL;
        Site_table &table = tri->spare;
        std::vector<Vertex_handle> &vertex = tri->spare_vertex;
        table.clear();
        table.order.resize(m);
        table.summary.resize(m);
        vertex.resize(m);
        for (auto v = dt.finite_vertices_begin(); v != dt.finite_vertices_end(); ++v) {
            vertex[v->info().slot] = v;
            table.order[v->info().slot] = {v->info().id, v->info().slot};
        }
        std::sort(table.order.begin(), table.order.end(),
                  [](const Id_slot &a, const Id_slot &b) { return a.id < b.id; });
        Cell_scratch &scratch = tri->scratch;
        const std::vector<Id_slot> &old_order = tri->table.order; // ascending id, like table.order
        size_t o = 0;
        for (const Id_slot &e : table.order) {
            Vertex_handle v = vertex[e.slot];
            const Site self = site_of(v);
            gather_neighbours(dt, v, scratch.nbrs);
            while (o < old_order.size() && old_order[o].id < e.id) o++;
            const Id_slot *was =
                o < old_order.size() && old_order[o].id == e.id ? &old_order[o] : nullptr;
            const Site_summary *same = unchanged_summary(tri, was, self, scratch.nbrs, tri->before);
            if (same)
                table.summary[e.slot] = *same;
            else
                summarise(self, scratch.nbrs.data(), scratch.nbrs.size(), tri->R, scratch,
                          table.summary[e.slot]);
        }
        tri->dt.swap(dt);
        std::swap(tri->table, tri->spare);
        tri->vertex.swap(tri->spare_vertex);
        return dropped ? IIR_TRI_DUPLICATE_POINT : IIR_TRI_OK;
    });
}

extern "C" iir_tri_status iir_tri_insert(iir_tri *tri, double x, double y, uint32_t id)
{
    if (!tri) return IIR_TRI_BAD_ARG;
    iir_tri_status st = check_point(tri, x, y);
    if (st != IIR_TRI_OK) return st;
    if (tri->table.find(id)) return IIR_TRI_DUPLICATE_ID;
    return mutate(tri, [&] {
        Point p(x, y);
        Delaunay::Locate_type lt;
        int li;
        Delaunay::Face_handle f = tri->dt.locate(p, lt, li);
        if (lt == Delaunay::VERTEX) return IIR_TRI_DUPLICATE_POINT;
        const int dim = tri->dt.dimension();
        Vertex_handle v = tri->dt.insert(p, lt, f, li);
        Site_table &table = tri->table;
        uint32_t slot;
        if (!table.free_slots.empty()) {
            slot = table.free_slots.back();
            table.free_slots.pop_back();
        } else {
            slot = (uint32_t)table.summary.size();
            table.summary.emplace_back();
            tri->vertex.emplace_back();
        }
        v->info() = {id, slot};
        tri->vertex[slot] = v;
        auto at = std::lower_bound(table.order.begin(), table.order.end(), id,
                                   [](const Id_slot &e, uint32_t key) { return e.id < key; });
        table.order.insert(at, {id, slot});
        if (tri->dt.dimension() != dim) {
            refresh_all(tri);
            return IIR_TRI_OK;
        }
        // v and its neighbours after the insertion.
        tri->affected.clear();
        tri->affected.push_back(slot);
        for_each_neighbour(tri->dt, v,
                           [&](Vertex_handle o) { tri->affected.push_back(o->info().slot); });
        refresh_affected(tri);
        return IIR_TRI_OK;
    });
}

extern "C" iir_tri_status iir_tri_remove(iir_tri *tri, uint32_t id)
{
    if (!tri) return IIR_TRI_BAD_ARG;
    const Id_slot *e = tri->table.find(id);
    if (!e) return IIR_TRI_UNKNOWN_ID;
    const uint32_t slot = e->slot;
    Vertex_handle v = tri->vertex[slot];
    // v's neighbours before the removal; collected before anything changes, so running out of
    // memory here leaves the set as it was.
    iir_tri_status st = guard([&] {
        tri->affected.clear();
        for_each_neighbour(tri->dt, v,
                           [&](Vertex_handle o) { tri->affected.push_back(o->info().slot); });
        return IIR_TRI_OK;
    });
    if (st != IIR_TRI_OK) return st;
    return mutate(tri, [&] {
        const int dim = tri->dt.dimension();
        tri->dt.remove(v);
        Site_table &table = tri->table;
        table.order.erase(table.order.begin() + (e - table.order.data()));
        table.free_slots.push_back(slot);
        if (tri->dt.dimension() != dim)
            refresh_all(tri);
        else
            refresh_affected(tri);
        return IIR_TRI_OK;
    });
}

// ---- lookup ----

extern "C" iir_tri_status iir_tri_position(const iir_tri *tri, uint32_t id, double xy[2])
{
    if (!tri || !xy) return IIR_TRI_BAD_ARG;
    const Id_slot *e = tri->table.find(id);
    if (!e) return IIR_TRI_UNKNOWN_ID;
    const Point &p = tri->vertex[e->slot]->point();
    xy[0] = p.x();
    xy[1] = p.y();
    return IIR_TRI_OK;
}

extern "C" iir_tri_status iir_tri_ids(const iir_tri *tri, uint32_t *ids, size_t cap, size_t *n)
{
    if (!tri || !n) return IIR_TRI_BAD_ARG;
    iir_tri_status st = fits(ids, cap, tri->table.order.size(), n);
    if (st != IIR_TRI_OK || !ids) return st;
    size_t k = 0;
    for (const Id_slot &e : tri->table.order) ids[k++] = e.id;
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

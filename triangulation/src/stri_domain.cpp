// stri_domain.cpp -- the iir_stri handle: lifetime, build/insert/remove, the id -> slot -> vertex
// index, lookups, the nearest-site walk, and keeping the per-site summaries (stri_geom.hpp)
// current across edits; not the Delaunay/Voronoi queries (stri_query.cpp, stri_voronoi.cpp) nor the
// cell geometry (stri_cell.cpp).
//
// Every mutation redoes, before it returns, the summaries of the sites whose cell input it changed,
// so queries read summaries and never recompute a cell. In dimension 2 insert and remove redo
// O(degree) of them (the new vertex and its neighbours after an insertion, the old neighbours after
// a removal: tri_cache.hpp says why), build redoes those of the sites that moved or whose
// neighbours did; a change of dimension, or any edit while all sites lie on one circle, redoes all.
//
// CGAL's on-sphere traits refuse a point closer than 2^-23 to a vertex, but only notice it near the
// located face; so points that close never reach CGAL: build drops them beforehand (a grid over
// the cube, by ascending id), insert refuses them after walking to the nearest site.
#include "stri_internal.hpp"
#include "tri_common.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <numeric>
#include <utility>

using namespace iirstri;
using iirtri::fits;
using iirtri::guard;

namespace
{

// ---- checks shared by build and insert ----

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

// Input indices to keep: visiting points by ascending id, each point within IIR_STRI_MIN_DIST of
// a point already kept is dropped. Returns whether anything was dropped. A point's close partners
// lie in the grid cells its IIR_STRI_MIN_DIST box touches (mostly just its own).
bool drop_close(const std::vector<Vec3> &pts, const uint32_t *ids, std::vector<size_t> &keep)
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

// ---- cell inputs ----

// The Delaunay neighbours of v as sites, in the order Cell_input wants.
void gather_neighbours(const Delaunay &dt, Vertex_handle v, std::vector<Site> &out)
{
    out.clear();
    if (dt.dimension() == 0) {
        for (auto w = dt.vertices_begin(); w != dt.vertices_end(); ++w)
            if (Vertex_handle(w) != v) out.push_back(site_of(w));
        return;
    }
    for_each_neighbour(dt, v, [&](Vertex_handle o) { out.push_back(site_of(o)); });
    if (dt.dimension() == 2) {
        auto smallest = std::min_element(out.begin(), out.end(),
                                         [](const Site &a, const Site &b) { return a.id < b.id; });
        std::rotate(out.begin(), smallest, out.end());
    }
}

Cell_input input_of(const Delaunay &dt, Vertex_handle v, const Frame &frame,
                    std::vector<Site> &nbrs)
{
    gather_neighbours(dt, v, nbrs);
    return Cell_input{dt.dimension(), site_of(v), nbrs.data(), nbrs.size(), frame};
}

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
        for_each_neighbour(dt, v, [&](Vertex_handle o) {
            if (nearer(o, next)) next = o;
        });
        if (next == v) return v;
        v = next;
    }
}

// The vertex nearest to p, from v: a cheap walk by dot product, then one by geodesic distance
// (near pi the dot product cannot tell sites ~1e-14 apart, angle_between can).
Vertex_handle nearest_vertex(const Delaunay &dt, Vec3 p, Vertex_handle v)
{
    v = walk(dt, v, [&](Vertex_handle a, Vertex_handle b) {
        return dot(p, vec_of(a->point())) > dot(p, vec_of(b->point()));
    });
    return walk(dt, v, [&](Vertex_handle a, Vertex_handle b) {
        return angle_between(p, vec_of(a->point())) < angle_between(p, vec_of(b->point()));
    });
}

// ---- keeping the summaries current ----

bool same_site(const Site &a, const Site &b)
{
    return a.id == b.id && std::memcmp(&a.p, &b.p, sizeof a.p) == 0;
}

// The summary the handle already holds for `self` (its entry `was`, or nullptr if new), if both
// the old and the new triangulation have dimension 2 and self and its neighbours `nbrs` are, bit
// for bit, what it was computed from. `before` is working storage.
const Site_summary *unchanged_summary(const iir_stri *s, const Id_slot *was, const Site &self,
                                      const std::vector<Site> &nbrs, std::vector<Site> &before)
{
    if (!was || s->dt.dimension() != 2) return nullptr;
    Vertex_handle old = s->vertex[was->slot];
    if (!same_site(site_of(old), self)) return nullptr;
    gather_neighbours(s->dt, old, before);
    if (before.size() != nbrs.size()) return nullptr;
    for (size_t k = 0; k < nbrs.size(); k++)
        if (!same_site(before[k], nbrs[k])) return nullptr;
    return &s->table.summary[was->slot];
}

// The frame of a one-circle set, from its sites by ascending id.
Frame frame_of(const Delaunay &dt, const Site_table &table,
               const std::vector<Vertex_handle> &vertex, std::vector<Site> &sites)
{
    if (dt.dimension() != 1) return Frame{};
    sites.clear();
    for (const Id_slot &e : table.order) sites.push_back(site_of(vertex[e.slot]));
    return circle_frame(sites.data(), sites.size());
}

void refresh(iir_stri *s, uint32_t slot)
{
    Cell_input in = input_of(s->dt, s->vertex[slot], s->frame, s->scratch.nbrs);
    summarise(in, s->scratch, s->table.summary[slot]);
}

void refresh_all(iir_stri *s)
{
    s->frame = frame_of(s->dt, s->table, s->vertex, s->sites);
    for (auto v = s->dt.vertices_begin(); v != s->dt.vertices_end(); ++v)
        refresh(s, v->info().slot);
}

// After an edit that left the triangulation at dimension `dim` (it was `before`): the affected
// slots in dimension 2, else all.
void refresh_after(iir_stri *s, int before)
{
    if (before != 2 || s->dt.dimension() != 2) return refresh_all(s);
    for (uint32_t slot : s->affected) refresh(s, slot);
}

// Runs a mutation; if it throws half-way (or fails inside CGAL), empties the handle so it is never
// left inconsistent.
template <class F> iir_tri_status mutate(iir_stri *s, F &&f) noexcept
{
    iir_tri_status st = guard(f);
    if (st == IIR_TRI_NO_MEMORY || st == IIR_TRI_INTERNAL) {
        s->dt.clear();
        s->table.clear();
        s->vertex.clear();
    }
    return st;
}

// ---- build, in steps ----

// Checks and normalises the input into pts; a status other than OK rejects the build.
iir_tri_status check_build_input(const Gt &gt, const double *xyz, const uint32_t *ids, size_t n,
                                 std::vector<Vec3> &pts)
{
    if (n > 0 && (!xyz || !ids)) return IIR_TRI_BAD_ARG;
    pts.resize(n);
    for (size_t i = 0; i < n; i++) {
        iir_tri_status st = to_unit(&xyz[3 * i], gt, pts[i]);
        if (st != IIR_TRI_OK) return st;
    }
    std::vector<uint32_t> sorted(ids, ids + n);
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
        return IIR_TRI_DUPLICATE_ID;
    return IIR_TRI_OK;
}

// A point that remembers its index in `keep`, for the spatial sort (as CGAL's own bulk insertion
// does internally).
struct Indexed_point : Point {
    Indexed_point(Vec3 p, uint32_t k) : Point(p.x, p.y, p.z), k(k) {}
    uint32_t k;
};

// Triangulates pts[keep[k]] into dt, giving vertex k the info {ids[keep[k]], k}: points are
// inserted in CGAL's spatial order on the sphere (a Hilbert sort with a fixed seed), each with the
// previous vertex as hint. False if CGAL refused a point (never: they are on the sphere and apart).
bool triangulate(const std::vector<Vec3> &pts, const uint32_t *ids, const std::vector<size_t> &keep,
                 Delaunay &dt, std::vector<Vertex_handle> &vertex)
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

// The summaries of the new triangulation dt (table.order already filled), keeping the handle's
// where nothing changed. Vertices are visited in CGAL's storage order, which follows the spatial
// insertion order: neighbouring cells are computed together, from memory already in cache.
void summarise_build(iir_stri *s, const Delaunay &dt, Site_table &table,
                     const std::vector<Vertex_handle> &vertex)
{
    const Frame frame = frame_of(dt, table, vertex, s->sites);
    Cell_scratch &scratch = s->scratch;
    for (auto v = dt.vertices_begin(); v != dt.vertices_end(); ++v) {
        Cell_input in = input_of(dt, v, frame, scratch.nbrs);
        const Site_summary *same = in.dim == 2 ? unchanged_summary(s, s->table.find(in.self.id),
                                                                   in.self, scratch.nbrs, s->before)
                                               : nullptr;
        if (same)
            table.summary[v->info().slot] = *same;
        else
            summarise(in, scratch, table.summary[v->info().slot]);
    }
    s->frame = frame;
}

// The table of a build: slot k holds the site of keep[k].
void index_build(const uint32_t *ids, const std::vector<size_t> &keep, Site_table &table)
{
    table.clear();
    table.order.resize(keep.size());
    table.summary.resize(keep.size());
    for (uint32_t k = 0; k < keep.size(); k++) table.order[k] = {ids[keep[k]], k};
    std::sort(table.order.begin(), table.order.end(),
              [](const Id_slot &a, const Id_slot &b) { return a.id < b.id; });
}

// Gives the new vertex v a slot (a free one first) and enters it in the index as `id`.
uint32_t index_vertex(iir_stri *s, Vertex_handle v, uint32_t id)
{
    Site_table &table = s->table;
    uint32_t slot;
    if (!table.free_slots.empty()) {
        slot = table.free_slots.back();
        table.free_slots.pop_back();
    } else {
        slot = (uint32_t)table.summary.size();
        table.summary.push_back(neutral_summary());
        s->vertex.emplace_back();
    }
    v->info() = {id, slot};
    s->vertex[slot] = v;
    auto at = std::lower_bound(table.order.begin(), table.order.end(), id,
                               [](const Id_slot &e, uint32_t key) { return e.id < key; });
    table.order.insert(at, {id, slot});
    return slot;
}

} // namespace

// ---- the bridge ----

const Site_table &iirstri::site_table(const iir_stri *s)
{
    return s->table;
}

bool iirstri::cell_input(const iir_stri *s, uint32_t id, Cell_scratch &scratch, Cell_input &out)
{
    const Id_slot *e = s->table.find(id);
    if (!e) return false;
    out = input_of(s->dt, s->vertex[e->slot], s->frame, scratch.nbrs);
    return true;
}

Site iirstri::nearest_site(const iir_stri *s, Vec3 p, uint32_t from)
{
    return site_of(nearest_vertex(s->dt, p, s->vertex[s->table.find(from)->slot]));
}

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
    return s ? s->table.order.size() : 0;
}

// ---- building and editing ----

extern "C" iir_tri_status iir_stri_build(iir_stri *s, const double *xyz, const uint32_t *ids,
                                         size_t n)
{
    if (!s) return IIR_TRI_BAD_ARG;
    return guard([&] {
        std::vector<Vec3> pts;
        iir_tri_status st = check_build_input(s->dt.geom_traits(), xyz, ids, n, pts);
        if (st != IIR_TRI_OK) return st;
        std::vector<size_t> keep;
        const bool dropped = drop_close(pts, ids, keep);
        // Build the triangulation and its table aside and swap them in, so a failure keeps the
        // previous set. The slot of a site is its index in keep.
        Delaunay dt;
        std::vector<Vertex_handle> &vertex = s->spare_vertex;
        if (!triangulate(pts, ids, keep, dt, vertex)) return IIR_TRI_INTERNAL;
        Site_table &table = s->spare;
        index_build(ids, keep, table);
        summarise_build(s, dt, table, vertex);
        s->dt.swap(dt);
        std::swap(s->table, s->spare);
        s->vertex.swap(s->spare_vertex);
        return dropped ? IIR_TRI_DUPLICATE_POINT : IIR_TRI_OK;
    });
}

extern "C" iir_tri_status iir_stri_insert(iir_stri *s, const double p[3], uint32_t id)
{
    if (!s || !p) return IIR_TRI_BAD_ARG;
    Vec3 q;
    iir_tri_status st = guard([&] { return to_unit(p, s->dt.geom_traits(), q); });
    if (st != IIR_TRI_OK) return st;
    if (s->table.find(id)) return IIR_TRI_DUPLICATE_ID;
    Vertex_handle near;
    if (!s->table.order.empty()) {
        near = nearest_vertex(s->dt, q, s->vertex[s->table.order[0].slot]);
        if (too_close(q, vec_of(near->point()))) return IIR_TRI_DUPLICATE_POINT;
    }
    return mutate(s, [&] {
        const int dim = s->dt.dimension();
        const size_t nv = s->dt.number_of_vertices();
        Delaunay::Face_handle hint = dim == 2 ? near->face() : Delaunay::Face_handle();
        Vertex_handle v = s->dt.insert(Point(q.x, q.y, q.z), hint);
        if (v == Vertex_handle() || s->dt.number_of_vertices() != nv + 1) return IIR_TRI_INTERNAL;
        const uint32_t slot = index_vertex(s, v, id);
        // v and its neighbours after the insertion.
        s->affected.clear();
        s->affected.push_back(slot);
        for_each_neighbour(s->dt, v,
                           [&](Vertex_handle o) { s->affected.push_back(o->info().slot); });
        refresh_after(s, dim);
        return IIR_TRI_OK;
    });
}

extern "C" iir_tri_status iir_stri_remove(iir_stri *s, uint32_t id)
{
    if (!s) return IIR_TRI_BAD_ARG;
    const Id_slot *e = s->table.find(id);
    if (!e) return IIR_TRI_UNKNOWN_ID;
    const uint32_t slot = e->slot;
    Vertex_handle v = s->vertex[slot];
    // v's neighbours before the removal; collected before anything changes, so running out of
    // memory here leaves the set as it was.
    iir_tri_status st = guard([&] {
        s->affected.clear();
        for_each_neighbour(s->dt, v,
                           [&](Vertex_handle o) { s->affected.push_back(o->info().slot); });
        return IIR_TRI_OK;
    });
    if (st != IIR_TRI_OK) return st;
    return mutate(s, [&] {
        const int dim = s->dt.dimension();
        s->dt.remove(v);
        Site_table &table = s->table;
        table.order.erase(table.order.begin() + (e - table.order.data()));
        table.free_slots.push_back(slot);
        table.summary[slot] = neutral_summary();
        refresh_after(s, dim);
        return IIR_TRI_OK;
    });
}

// ---- lookup ----

extern "C" iir_tri_status iir_stri_position(const iir_stri *s, uint32_t id, double p[3])
{
    if (!s || !p) return IIR_TRI_BAD_ARG;
    const Id_slot *e = s->table.find(id);
    if (!e) return IIR_TRI_UNKNOWN_ID;
    const Vec3 v = vec_of(s->vertex[e->slot]->point());
    p[0] = v.x;
    p[1] = v.y;
    p[2] = v.z;
    return IIR_TRI_OK;
}

extern "C" iir_tri_status iir_stri_ids(const iir_stri *s, uint32_t *ids, size_t cap, size_t *n)
{
    if (!s || !n) return IIR_TRI_BAD_ARG;
    iir_tri_status st = fits(ids, cap, s->table.order.size(), n);
    if (st != IIR_TRI_OK || !ids) return st;
    size_t k = 0;
    for (const Id_slot &e : s->table.order) ids[k++] = e.id;
    return IIR_TRI_OK;
}

// tri_handle.hpp -- the handle the disk (tri.h) and the sphere (stri.h) share, one template over
// the geometry G: the id -> slot -> vertex index, build/insert/remove keeping the per-site
// summaries (tri_cache.hpp) current, and every query answered from them; not the geometry (G,
// defined with its CGAL types in tri_domain.cpp and stri_domain.cpp) nor the C API over it.
//
// Every mutation redoes, before it returns, the summaries of the sites whose cell input it changed
// (tri_cache.hpp), so queries read summaries and never recompute a cell: insert and remove redo
// O(degree) of them unless G::full_refresh says the edit changed every cell (a change of
// dimension; on the sphere also any edit while all sites lie on one circle); build redoes those of
// the sites that moved or whose neighbours did. A mutation that throws half-way empties the handle.
//
// The largest empty circle (cap) is, among the candidates whose radius is within IIR_TRI_TIE_TOL
// of the largest radius of all, the one with the smallest key in the first cell (ascending id)
// holding one -- two passes, so the choice does not depend on how ties chain. Pass one is the
// maximum of the cells' maxima; pass two finds the first cell whose maximum reaches the threshold
// and reads its kept candidates (in key order, they include every candidate that can reach a
// threshold the cell's own maximum reaches). Only when a cell kept too few is it computed again.
//
// What G provides (all static):
//   types    Vec, Site, Candidate, Cell, Cell_scratch (with vectors `nbrs` and `cands`), Context
//            (what every cell depends on besides its sites), Delaunay, Vertex_handle (vertex info
//            Vertex_info); kDim, the doubles per point in the C API
//   points   vec_of(point), put(vec, double *), check_point(dt, ctx, const double *, vec &)
//   metric   distance(a, b) (of edges and neighbours), edge_length(distance), radius(centre, site)
//   graph    for_each_vertex / for_each_neighbour / for_each_edge, gather_neighbours(dt, v, out)
//            (the cell input's order), nearest(dt, vec, from)
//   edits    drop_repeated, triangulate (build), insert(dt, vec, start, v), full_refresh(before,
//            after), reusable(old_dim, new_dim), update_context(dt, table, vertex, work, ctx)
//   cells    make_cell(self, nbrs, dim, ctx, scratch), area(cell), candidates(cell, out),
//            polygon(cell, out), shortest_incident(self, nbrs, edge)
#ifndef IIR_TRI_HANDLE_HPP
#define IIR_TRI_HANDLE_HPP

#include "tri_cache.hpp"

#include <algorithm>
#include <cassert>
#include <cstring>
#include <limits>
#include <new>
#include <utility>
#include <vector>

namespace iirtri
{

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

// What a vertex carries: the caller's id and the slot of its entry in the Site_table.
struct Vertex_info {
    uint32_t id, slot;
};

// The handle. Invariants: `table.order` lists every vertex's id once with its slot; vertex[slot]
// is that vertex and its info() is {id, slot}; table.summary[slot] is the summary of its current
// cell input, computed with `ctx`. `scratch`, `spare`, `spare_vertex`, `affected` and `before` are
// working storage of the mutations only (never read by a const function), kept to reuse their
// capacity; their contents mean nothing between calls. Pointer arguments are checked here; the C
// API checks the handle.
template <class G> struct Handle {
    using Vec = typename G::Vec;
    using Site = typename G::Site;
    using Candidate = typename G::Candidate;
    using Summary = Site_summary<Candidate>;
    using Table = Site_table<Candidate>;
    using Delaunay = typename G::Delaunay;
    using Vertex_handle = typename G::Vertex_handle;
    using Context = typename G::Context;
    using Cell_scratch = typename G::Cell_scratch;

    Delaunay dt;
    Table table;
    std::vector<Vertex_handle> vertex; // by slot
    Context ctx;
    Cell_scratch scratch;
    Table spare;
    std::vector<Vertex_handle> spare_vertex;
    std::vector<uint32_t> affected;
    std::vector<Site> before;

    // ---- edits (tri.h / stri.h: build, insert, remove) ----
    iir_tri_status build(const double *pts, const uint32_t *ids, size_t n);
    iir_tri_status insert(const double *p, uint32_t id);
    iir_tri_status remove(uint32_t id);

    // ---- lookups and queries, named as in tri.h ----
    size_t count() const { return table.order.size(); }
    iir_tri_status position(uint32_t id, double *p) const;
    iir_tri_status ids(uint32_t *out, size_t cap, size_t *n) const;
    iir_tri_status shortest_edge(uint32_t *denser_id, uint32_t *other_id, double *length) const;
    iir_tri_status largest_empty(double *centre, double *radius) const;
    iir_tri_status cell_area(uint32_t id, double *area) const;
    iir_tri_status cell_areas(uint32_t *out, double *areas, size_t cap, size_t *n) const;
    iir_tri_status edges(uint32_t *pairs, size_t cap, size_t *n) const;
    iir_tri_status cell_polygon(uint32_t id, double *out, size_t cap, size_t *n) const;

    static Site site_of(Vertex_handle v) { return Site{G::vec_of(v->point()), v->info().id}; }
    Vertex_handle vertex_of(uint32_t id) const { return vertex[table.find(id)->slot]; }

  private:
    template <class F> iir_tri_status mutate(F &&f) noexcept;
    iir_tri_status check_build_input(const double *pts, const uint32_t *ids, size_t n,
                                     std::vector<Vec> &out) const;
    void index_build(const uint32_t *ids, const std::vector<size_t> &keep);
    Context summarise_build(const Delaunay &fresh);
    const Summary *unchanged_summary(const Site &self, const std::vector<Site> &nbrs);
    uint32_t index_vertex(Vertex_handle v, uint32_t id);
    void summarise(const Site &self, const std::vector<Site> &nbrs, int dim, const Context &c,
                   Cell_scratch &s, Summary &out) const;
    void refresh(uint32_t slot);
    void refresh_after(int dim_before);
    double second_nearest(Vertex_handle p, Vertex_handle q) const;
    bool cell_of(uint32_t id, Cell_scratch &s) const;
    bool first_candidate_at(uint32_t id, double thr, bool any, Vec &out) const;
    bool pick_largest(Vec &out, uint32_t &from) const;
};

// ---- keeping the summaries current ----

// The summary of `self` with the neighbours nbrs (G::gather_neighbours order) in a triangulation
// of dimension `dim`: its shortest edge, then its cell in s. Throws std::bad_alloc only if a
// scratch buffer must grow.
template <class G>
void Handle<G>::summarise(const Site &self, const std::vector<Site> &nbrs, int dim,
                          const Context &c, Cell_scratch &s, Summary &out) const
{
    out.id = self.id;
    out.has_edge = G::shortest_incident(self, nbrs, out.edge);
    const typename G::Cell &cell = G::make_cell(self, nbrs, dim, c, s);
    out.cell.area = G::area(cell);
    s.cands.clear();
    G::candidates(cell, s.cands);
    keep_top(s.cands, out.cell);
}

template <class G> void Handle<G>::refresh(uint32_t slot)
{
    Vertex_handle v = vertex[slot];
    G::gather_neighbours(dt, v, scratch.nbrs);
    summarise(site_of(v), scratch.nbrs, dt.dimension(), ctx, scratch, table.summary[slot]);
}

// After an edit that left the triangulation at its dimension (it was `dim_before`): the
// `affected` slots, or every slot with a new context when the edit changed every cell.
template <class G> void Handle<G>::refresh_after(int dim_before)
{
    if (!G::full_refresh(dim_before, dt.dimension())) {
        for (uint32_t slot : affected) refresh(slot);
        return;
    }
    G::update_context(dt, table, vertex, before, ctx);
    for (const Id_slot &e : table.order) refresh(e.slot);
}

// Runs a mutation; if it throws half-way (or fails inside CGAL), empties the handle so it is never
// left inconsistent.
template <class G> template <class F> iir_tri_status Handle<G>::mutate(F &&f) noexcept
{
    iir_tri_status st = guard(f);
    if (st == IIR_TRI_NO_MEMORY || st == IIR_TRI_INTERNAL) {
        dt.clear();
        table.clear();
        vertex.clear();
    }
    return st;
}

// Gives the new vertex v a slot (a free one first) and enters it in the index as `id`.
template <class G> uint32_t Handle<G>::index_vertex(Vertex_handle v, uint32_t id)
{
    uint32_t slot;
    if (!table.free_slots.empty()) {
        slot = table.free_slots.back();
        table.free_slots.pop_back();
    } else {
        slot = (uint32_t)table.summary.size();
        table.summary.push_back(neutral_summary<Candidate>());
        vertex.emplace_back();
    }
    v->info() = {id, slot};
    vertex[slot] = v;
    auto at = std::lower_bound(table.order.begin(), table.order.end(), id,
                               [](const Id_slot &e, uint32_t key) { return e.id < key; });
    table.order.insert(at, {id, slot});
    return slot;
}

// ---- build, in steps ----

// Checks the input (G::check_point on each point) into out; a status other than OK rejects it.
template <class G>
iir_tri_status Handle<G>::check_build_input(const double *pts, const uint32_t *ids, size_t n,
                                            std::vector<Vec> &out) const
{
    if (n > 0 && (!pts || !ids)) return IIR_TRI_BAD_ARG;
    out.resize(n);
    for (size_t i = 0; i < n; i++) {
        iir_tri_status st = G::check_point(dt, ctx, &pts[G::kDim * i], out[i]);
        if (st != IIR_TRI_OK) return st;
    }
    std::vector<uint32_t> sorted(ids, ids + n);
    std::sort(sorted.begin(), sorted.end());
    if (std::adjacent_find(sorted.begin(), sorted.end()) != sorted.end())
        return IIR_TRI_DUPLICATE_ID;
    return IIR_TRI_OK;
}

// The table of a build, into `spare`: slot k holds the site of keep[k].
template <class G> void Handle<G>::index_build(const uint32_t *ids, const std::vector<size_t> &keep)
{
    spare.clear();
    spare.order.resize(keep.size());
    spare.summary.resize(keep.size());
    for (uint32_t k = 0; k < keep.size(); k++) spare.order[k] = {ids[keep[k]], k};
    std::sort(spare.order.begin(), spare.order.end(),
              [](const Id_slot &a, const Id_slot &b) { return a.id < b.id; });
}

template <class G> bool same_site(const typename G::Site &a, const typename G::Site &b)
{
    return a.id == b.id && std::memcmp(&a.p, &b.p, sizeof a.p) == 0;
}

// The summary the handle already holds for `self`, if self and its neighbours `nbrs` are, bit for
// bit, what it was computed from (with the same context: the caller asks G::reusable).
template <class G>
auto Handle<G>::unchanged_summary(const Site &self, const std::vector<Site> &nbrs)
    -> const Summary *
{
    const Id_slot *was = table.find(self.id);
    if (!was) return nullptr;
    Vertex_handle old = vertex[was->slot];
    if (!same_site<G>(site_of(old), self)) return nullptr;
    G::gather_neighbours(dt, old, before);
    if (before.size() != nbrs.size()) return nullptr;
    for (size_t k = 0; k < nbrs.size(); k++)
        if (!same_site<G>(before[k], nbrs[k])) return nullptr;
    return &table.summary[was->slot];
}

// The summaries of the new triangulation `fresh` (spare and spare_vertex filled), keeping ours
// where nothing changed; returns fresh's context. Vertices are visited in CGAL's storage order,
// which follows the spatial insertion order: neighbouring cells are computed together, from memory
// already in cache.
template <class G> auto Handle<G>::summarise_build(const Delaunay &fresh) -> Context
{
    Context c = ctx;
    G::update_context(fresh, spare, spare_vertex, before, c);
    const bool reuse = G::reusable(dt.dimension(), fresh.dimension());
    G::for_each_vertex(fresh, [&](Vertex_handle v) {
        const Site self = site_of(v);
        G::gather_neighbours(fresh, v, scratch.nbrs);
        Summary &out = spare.summary[v->info().slot];
        const Summary *same = reuse ? unchanged_summary(self, scratch.nbrs) : nullptr;
        if (same)
            out = *same;
        else
            summarise(self, scratch.nbrs, fresh.dimension(), c, scratch, out);
    });
    return c;
}

template <class G> iir_tri_status Handle<G>::build(const double *pts, const uint32_t *ids, size_t n)
{
    return guard([&] {
        std::vector<Vec> in;
        iir_tri_status st = check_build_input(pts, ids, n, in);
        if (st != IIR_TRI_OK) return st;
        std::vector<size_t> keep;
        const bool dropped = G::drop_repeated(in, ids, keep);
        // Build the triangulation and its table aside and swap them in, so a failure keeps the
        // previous set. The slot of a site is its index in keep.
        Delaunay fresh;
        if (!G::triangulate(in, ids, keep, fresh, spare_vertex)) return IIR_TRI_INTERNAL;
        index_build(ids, keep);
        const Context c = summarise_build(fresh);
        dt.swap(fresh);
        std::swap(table, spare);
        vertex.swap(spare_vertex);
        ctx = c;
        return dropped ? IIR_TRI_DUPLICATE_POINT : IIR_TRI_OK;
    });
}

// ---- insert and remove ----

template <class G> iir_tri_status Handle<G>::insert(const double *p, uint32_t id)
{
    if (!p) return IIR_TRI_BAD_ARG;
    Vec q;
    iir_tri_status st = guard([&] { return G::check_point(dt, ctx, p, q); });
    if (st != IIR_TRI_OK) return st;
    if (table.find(id)) return IIR_TRI_DUPLICATE_ID;
    return mutate([&] {
        const int dim = dt.dimension();
        const Vertex_handle start =
            table.order.empty() ? Vertex_handle() : vertex[table.order[0].slot];
        Vertex_handle v;
        // G::insert refuses a taken position (IIR_TRI_DUPLICATE_POINT) before changing anything.
        iir_tri_status st = G::insert(dt, q, start, v);
        if (st != IIR_TRI_OK) return st;
        const uint32_t slot = index_vertex(v, id);
        // v and its neighbours after the insertion.
        affected.assign(1, slot);
        G::for_each_neighbour(dt, v, [&](Vertex_handle o) { affected.push_back(o->info().slot); });
        refresh_after(dim);
        return IIR_TRI_OK;
    });
}

template <class G> iir_tri_status Handle<G>::remove(uint32_t id)
{
    const Id_slot *e = table.find(id);
    if (!e) return IIR_TRI_UNKNOWN_ID;
    const uint32_t slot = e->slot;
    Vertex_handle v = vertex[slot];
    // v's neighbours before the removal; collected before anything changes, so running out of
    // memory here leaves the set as it was.
    iir_tri_status st = guard([&] {
        affected.clear();
        G::for_each_neighbour(dt, v, [&](Vertex_handle o) { affected.push_back(o->info().slot); });
        return IIR_TRI_OK;
    });
    if (st != IIR_TRI_OK) return st;
    return mutate([&] {
        const int dim = dt.dimension();
        dt.remove(v);
        table.order.erase(table.order.begin() + (e - table.order.data()));
        table.free_slots.push_back(slot);
        table.summary[slot] = neutral_summary<Candidate>();
        refresh_after(dim);
        return IIR_TRI_OK;
    });
}

// ---- lookups ----

template <class G> iir_tri_status Handle<G>::position(uint32_t id, double *p) const
{
    if (!p) return IIR_TRI_BAD_ARG;
    const Id_slot *e = table.find(id);
    if (!e) return IIR_TRI_UNKNOWN_ID;
    G::put(G::vec_of(vertex[e->slot]->point()), p);
    return IIR_TRI_OK;
}

template <class G> iir_tri_status Handle<G>::ids(uint32_t *out, size_t cap, size_t *n) const
{
    if (!n) return IIR_TRI_BAD_ARG;
    iir_tri_status st = fits(out, cap, table.order.size(), n);
    if (st != IIR_TRI_OK || !out) return st;
    size_t k = 0;
    for (const Id_slot &e : table.order) out[k++] = e.id;
    return IIR_TRI_OK;
}

// ---- the Delaunay graph: shortest edge, edges ----

// The shortest edge over the summaries: each site's shortest incident edge is remembered, and the
// shortest of those is the shortest of all (the order is total, so the slots are scanned in
// storage order; free slots have no edge).
template <class Cand> Edge_key shortest_of(const Site_table<Cand> &table)
{
    const Edge_key *best = nullptr;
    for (const Site_summary<Cand> &s : table.summary)
        if (s.has_edge && (!best || shorter(s.edge, *best))) best = &s.edge;
    assert(best && "two or more sites have an edge");
    return *best;
}

// G::distance from p to its nearest site other than p and q (infinity if there is none). That site
// is a Delaunay neighbour of p once q is gone, so it is a neighbour of p or of q now.
template <class G> double Handle<G>::second_nearest(Vertex_handle p, Vertex_handle q) const
{
    double best = std::numeric_limits<double>::infinity();
    const Vec pp = G::vec_of(p->point());
    auto visit = [&](Vertex_handle o) {
        if (o != p && o != q) best = std::min(best, G::distance(pp, G::vec_of(o->point())));
    };
    G::for_each_neighbour(dt, p, visit);
    G::for_each_neighbour(dt, q, visit);
    return best;
}

template <class G>
iir_tri_status Handle<G>::shortest_edge(uint32_t *denser_id, uint32_t *other_id,
                                        double *length) const
{
    return guard([&] {
        if (table.order.size() < 2) return IIR_TRI_TOO_FEW;
        const Edge_key e = shortest_of(table);
        Vertex_handle young = vertex_of(e.young), old = vertex_of(e.old);
        // Ties (including "no third site") go to the younger endpoint.
        const bool young_denser = second_nearest(young, old) <= second_nearest(old, young);
        if (denser_id) *denser_id = young_denser ? e.young : e.old;
        if (other_id) *other_id = young_denser ? e.old : e.young;
        if (length) *length = G::edge_length(e.len);
        return IIR_TRI_OK;
    });
}

template <class G> iir_tri_status Handle<G>::edges(uint32_t *pairs, size_t cap, size_t *n) const
{
    if (!n) return IIR_TRI_BAD_ARG;
    return guard([&] {
        std::vector<std::pair<uint32_t, uint32_t>> all;
        G::for_each_edge(dt, [&](Vertex_handle a, Vertex_handle b) {
            const uint32_t i = a->info().id, j = b->info().id;
            all.emplace_back(std::min(i, j), std::max(i, j));
        });
        iir_tri_status st = fits(pairs, cap, all.size(), n);
        if (st != IIR_TRI_OK || !pairs) return st;
        std::sort(all.begin(), all.end());
        for (size_t k = 0; k < all.size(); k++) {
            pairs[2 * k] = all[k].first;
            pairs[2 * k + 1] = all[k].second;
        }
        return IIR_TRI_OK;
    });
}

// ---- the Voronoi cells: areas, polygons, the largest empty circle (cap) ----

// The cell of site `id` (in s.cell); false if there is no such site.
template <class G> bool Handle<G>::cell_of(uint32_t id, Cell_scratch &s) const
{
    const Id_slot *e = table.find(id);
    if (!e) return false;
    Vertex_handle v = vertex[e->slot];
    G::gather_neighbours(dt, v, s.nbrs);
    G::make_cell(site_of(v), s.nbrs, dt.dimension(), ctx, s);
    return true;
}

template <class G> iir_tri_status Handle<G>::cell_area(uint32_t id, double *area) const
{
    if (!area) return IIR_TRI_BAD_ARG;
    const Id_slot *e = table.find(id);
    if (!e) return IIR_TRI_UNKNOWN_ID;
    *area = table.summary[e->slot].cell.area;
    return IIR_TRI_OK;
}

template <class G>
iir_tri_status Handle<G>::cell_areas(uint32_t *out, double *areas, size_t cap, size_t *n) const
{
    if (!n || (!out != !areas)) return IIR_TRI_BAD_ARG;
    iir_tri_status st = fits(out, cap, table.order.size(), n);
    if (st != IIR_TRI_OK || !out) return st;
    for (size_t k = 0; k < table.order.size(); k++) {
        out[k] = table.order[k].id;
        areas[k] = table.summary[table.order[k].slot].cell.area;
    }
    return IIR_TRI_OK;
}

template <class G>
iir_tri_status Handle<G>::cell_polygon(uint32_t id, double *out, size_t cap, size_t *n) const
{
    if (!n) return IIR_TRI_BAD_ARG;
    return guard([&] {
        Cell_scratch s;
        if (!cell_of(id, s)) return IIR_TRI_UNKNOWN_ID;
        std::vector<Vec> poly;
        G::polygon(s.cell, poly);
        iir_tri_status st = fits(out, cap, poly.size(), n);
        if (st != IIR_TRI_OK || !out) return st;
        for (size_t k = 0; k < poly.size(); k++) G::put(poly[k], &out[G::kDim * k]);
        return IIR_TRI_OK;
    });
}

// The candidate of the cell of `id` with the smallest key whose radius is >= thr (any candidate
// when `any`); false if there is none. Computes the cell again: only for the rare cells whose
// summary kept too few.
template <class G>
bool Handle<G>::first_candidate_at(uint32_t id, double thr, bool any, Vec &out) const
{
    Cell_scratch s;
    cell_of(id, s);
    G::candidates(s.cell, s.cands);
    const Candidate *best = nullptr;
    for (const Candidate &c : s.cands)
        if ((any || c.r >= thr) && (!best || key_less(c.key, best->key))) best = &c;
    if (best) out = best->c;
    return best != nullptr;
}

// The centre of the largest empty circle (cap; see the top of the file) and the site of the cell
// it came from; false if no cell has a candidate. Slots are scanned in storage order (free ones
// hold no candidate); "first by ascending id" is the smallest id among the cells reaching the
// threshold.
template <class G> bool Handle<G>::pick_largest(Vec &out, uint32_t &from) const
{
    double rmax = 0;
    for (const Summary &e : table.summary) rmax = std::max(rmax, e.cell.rmax);
    const double thr = tie_threshold(rmax);
    const Summary *first = nullptr;
    for (const Summary &e : table.summary)
        if (e.cell.ntop > 0 && e.cell.rmax >= thr && (!first || e.id < first->id)) first = &e;
    if (first) {
        from = first->id;
        const Cell_summary<Candidate> &c = first->cell;
        for (uint32_t k = 0; k < c.ntop; k++)
            if (c.top[k].r >= thr) {
                out = c.top[k].c;
                return true;
            }
        if (c.overflow && first_candidate_at(first->id, thr, false, out)) return true;
    }
    // No radius reaches the threshold (only if every radius is NaN): the first candidate of all.
    for (const Id_slot &e : table.order)
        if (first_candidate_at(e.id, thr, true, out)) {
            from = e.id;
            return true;
        }
    return false;
}

template <class G> iir_tri_status Handle<G>::largest_empty(double *centre, double *radius) const
{
    if (!centre || !radius) return IIR_TRI_BAD_ARG;
    return guard([&] {
        if (table.order.empty()) return IIR_TRI_TOO_FEW;
        Vec c;
        uint32_t from = 0;
        if (!pick_largest(c, from)) return IIR_TRI_INTERNAL;
        // The radius is measured from the returned centre, so the two agree exactly.
        const Vec near = G::vec_of(G::nearest(dt, c, vertex_of(from))->point());
        G::put(c, centre);
        *radius = G::radius(c, near);
        return IIR_TRI_OK;
    });
}

} // namespace iirtri

#endif

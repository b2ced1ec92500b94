// tri_cache.hpp -- what a handle (disk or sphere) remembers about each site between calls, without
// CGAL and for either geometry: the id -> slot index, and per slot the summary of the site's
// Voronoi cell (area, its best largest-empty-circle or -cap candidates) and of its shortest
// Delaunay edge; not when summaries are redone nor how queries read them (tri_handle.hpp), nor the
// cells themselves (tri_cell.cpp, stri_cell.cpp).
//
// A summary is a pure function of the site, its Delaunay neighbours (in the geometry's order) and
// the handle's context (the disk's R; the sphere's plane of all sites while they lie on one
// circle), so it stays valid until an edit changes one of those. Inserting site v changes the
// lists of v and of v's neighbours after the insertion (every edge the insertion removes joins two
// of them); removing v changes those of v's neighbours before the removal (the hole is
// retriangulated among them); a change of dimension may change any; a build keeps a summary only
// where the site and its neighbour list are bit for bit what they were. tri_handle.hpp redoes
// exactly those summaries inside the mutation, so that every const function only reads.
#ifndef IIR_TRI_CACHE_HPP
#define IIR_TRI_CACHE_HPP

#include "iir/tri.h"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace iirtri
{

// A site as plain data: its position (Vec2 in disk units, or a unit Vec3) and its id.
template <class Vec> struct Site {
    Vec p;
    uint32_t id;
};

// A Delaunay edge by the ids of its endpoints, the younger (larger id) first, and its length
// measured from young to old by the geometry (the disk: squared distance; the sphere: angle).
struct Edge_key {
    double len;
    uint32_t young, old;
};

// Edge order for "shortest" (tri.h, stri.h): shorter first; among equal lengths, the larger
// younger id, then the larger older id. A strict total order on distinct edges.
inline bool shorter(const Edge_key &e, const Edge_key &f)
{
    if (e.len != f.len) return e.len < f.len;
    if (e.young != f.young) return e.young > f.young;
    return e.old > f.old;
}

// A candidate centre of the largest empty circle (cap), its distance to the site of the cell it
// came from (that site is its nearest, up to rounding), and the key that breaks ties between the
// candidates of one cell (smallest first: `key_less(a, b)`, found next to the key's type).
template <class Vec, class Key> struct Candidate {
    Vec c;
    double r;
    Key key;
};

// How many of a cell's candidates near its own maximum a summary keeps.
constexpr size_t kTopCandidates = 4;

// rmax * (1 - IIR_TRI_TIE_TOL): radii at or above it tie with rmax. Monotone in rmax.
inline double tie_threshold(double rmax)
{
    return rmax * (1 - IIR_TRI_TIE_TOL);
}

// One cell, summarised. `rmax` is the largest candidate radius (0 if none; NaN is ignored, as
// std::max ignores it); `top` holds, in key order, the first `ntop` candidates whose radius is
// >= tie_threshold(rmax); `overflow` says more than kTopCandidates qualified and only those with
// the smallest keys are kept.
template <class Cand> struct Cell_summary {
    double area;
    double rmax;
    uint32_t ntop;
    bool overflow;
    Cand top[kTopCandidates];
};

// Everything remembered about one site: its id, its cell, its shortest edge (`has_edge` is false
// when it has no neighbour). A free slot holds a neutral summary (no edge, no candidate), so that
// queries may scan the slots in storage order.
template <class Cand> struct Site_summary {
    Edge_key edge;
    bool has_edge;
    uint32_t id;
    Cell_summary<Cand> cell;
};

// The summary of a free slot.
template <class Cand> Site_summary<Cand> neutral_summary()
{
    Site_summary<Cand> s{};
    s.has_edge = false;
    s.cell.ntop = 0;
    s.cell.rmax = 0;
    return s;
}

// Keeps of a cell's candidates (in any order; reordered here) the ones near its largest radius.
template <class Cand> void keep_top(std::vector<Cand> &cands, Cell_summary<Cand> &c)
{
    c.rmax = 0;
    for (const Cand &k : cands) c.rmax = std::max(c.rmax, k.r);
    const double thr = tie_threshold(c.rmax);
    auto end =
        std::remove_if(cands.begin(), cands.end(), [&](const Cand &k) { return !(k.r >= thr); });
    std::sort(cands.begin(), end,
              [](const Cand &a, const Cand &b) { return key_less(a.key, b.key); });
    const size_t kept = std::min<size_t>(end - cands.begin(), kTopCandidates);
    std::copy(cands.begin(), cands.begin() + kept, c.top);
    c.ntop = (uint32_t)kept;
    c.overflow = (size_t)(end - cands.begin()) > kTopCandidates;
}

struct Id_slot {
    uint32_t id, slot;
};

// The sites by id and their summaries by slot. Slots are dense indices reused after removals
// (`free_slots`); `summary[slot]` is neutral_summary() for a free slot.
template <class Cand> struct Site_table {
    std::vector<Id_slot> order; // every site, ascending id
    std::vector<Site_summary<Cand>> summary;
    std::vector<uint32_t> free_slots;

    // The entry of `id` in `order`, or nullptr (binary search).
    const Id_slot *find(uint32_t id) const
    {
        auto it = std::lower_bound(order.begin(), order.end(), id,
                                   [](const Id_slot &e, uint32_t key) { return e.id < key; });
        return it != order.end() && it->id == id ? &*it : nullptr;
    }
    void clear()
    {
        order.clear();
        summary.clear();
        free_slots.clear();
    }
};

} // namespace iirtri

#endif

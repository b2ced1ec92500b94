// tri_cache.hpp -- what an iir_tri handle remembers about each site between calls, without CGAL:
// the id -> slot index, and per slot the summary of the site's clipped cell (area, its best
// largest-empty-circle candidates) and of its shortest Delaunay edge; not when summaries are redone
// (tri_domain.cpp) nor how queries read them (tri_voronoi.cpp, tri_query.cpp).
//
// A summary is a pure function of the site, its Delaunay neighbours (ascending id) and R, so it
// stays valid until an edit changes that neighbour list. Inserting site v changes the lists of v
// and of v's neighbours after the insertion (every edge the insertion removes joins two of them);
// removing v changes those of v's neighbours before the removal (the hole is retriangulated among
// them); a change of dimension (collinear <-> not) may change any; a build keeps a summary only
// where the site and its neighbour list are bit for bit what they were. tri_domain.cpp redoes
// exactly those summaries inside the mutation, so that every `const iir_tri *` function only reads.
#ifndef IIR_TRI_CACHE_HPP
#define IIR_TRI_CACHE_HPP

#include "tri_cell.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace iirtri
{

// A candidate centre for the largest empty circle and its distance to the site of the cell it came
// from (that site is its nearest, up to rounding).
struct Candidate {
    Vec2 c;
    double r;
};

// How many of a cell's candidates near its own maximum a summary keeps.
constexpr size_t kTopCandidates = 4;

// One clipped cell, summarised. Of the cell's candidates (far_candidates order) `rmax` is the
// largest radius (0 if there is none; NaN radii are ignored, as std::max ignores them), and `top`
// holds the first `ntop` whose radius is >= rmax * (1 - IIR_TRI_TIE_TOL), in order; `overflow`
// says more than kTopCandidates qualified and only the first ones are kept.
struct Cell_summary {
    double area;
    double rmax;
    Candidate top[kTopCandidates];
    uint32_t ntop;
    bool overflow;
};

// A Delaunay edge by the ids of its endpoints, the younger (larger id) first, and its squared
// length computed as (young - old)^2.
struct Edge_key {
    double len2;
    uint32_t young, old;
};

// Edge order for "shortest" (tri.h): shorter first; among equal lengths, the larger younger id,
// then the larger older id. A strict total order on distinct edges.
inline bool shorter(const Edge_key &e, const Edge_key &f)
{
    if (e.len2 != f.len2) return e.len2 < f.len2;
    if (e.young != f.young) return e.young > f.young;
    return e.old > f.old;
}

// Everything remembered about one site; `has_edge` is false when the site has no neighbour.
struct Site_summary {
    Cell_summary cell;
    Edge_key edge;
    bool has_edge;
};

struct Id_slot {
    uint32_t id, slot;
};

// The sites by id and their summaries by slot. Slots are dense indices reused after removals
// (`free_slots`); `summary[slot]` means something only for slots listed in `order`.
struct Site_table {
    std::vector<Id_slot> order; // every site, ascending id
    std::vector<Site_summary> summary;
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

// The summary of the site `self` whose Delaunay neighbours are nbrs[0..n) in ascending id: clips
// its cell in `scratch`. Throws std::bad_alloc only if a scratch buffer must grow.
void summarise(const Site &self, const Site *nbrs, size_t n, double R, Cell_scratch &scratch,
               Site_summary &out);

// ---- the bridge into the handle (tri_domain.cpp) ----

const Site_table &site_table(const iir_tri *tri);

} // namespace iirtri

#endif

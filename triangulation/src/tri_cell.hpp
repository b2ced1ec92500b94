// tri_cell.hpp -- one Voronoi cell clipped to the disk, as plain geometry: its boundary (segments
// and arcs), exact area, drawing polygon, largest-empty-circle candidates and shortest incident
// edge; not where the sites come from (tri_domain.cpp).
#ifndef IIR_TRI_CELL_HPP
#define IIR_TRI_CELL_HPP

#include "tri_cache.hpp"

#include <cstddef>
#include <vector>

namespace iirdisk
{

struct Vec2 {
    double x, y;
};

using Site = iirtri::Site<Vec2>;

// A candidate's place in far_candidates order: the first one reaching a radius wins a tie.
struct Ring_key {
    uint32_t k;
};

inline bool key_less(Ring_key a, Ring_key b)
{
    return a.k < b.k;
}

using Candidate = iirtri::Candidate<Vec2, Ring_key>;

// One piece of the boundary of a clipped cell, counter-clockwise; piece k ends where piece k+1
// starts. A segment lies on a Voronoi edge inside the disk; an arc runs counter-clockwise on the
// circle from a through `sweep` radians (0 < sweep <= 2 pi) to b.
struct Piece {
    Vec2 a, b;
    bool arc;
    double sweep;
};

// The boundary of (Voronoi cell of `site`) intersected with the closed disk |x| <= R. An empty ring
// means the cell misses the disk (area 0; cannot happen for a site inside the disk).
struct Cell {
    Vec2 site;
    double R;
    std::vector<Piece> ring;
};

// A straight part of the unclipped cell's boundary, either inside the disk or outside it (an
// intermediate of clip_cell, here only so Cell_scratch can hold it).
struct Step {
    Vec2 a, b;
    bool inside;
};

// Working buffers of clip_cell and of the cell summaries. Whoever owns one reuses it across cells,
// so that clipping allocates only while the buffers still grow (the clipping buffers are used up
// to a count kept aside, not up to their size). The contents between calls mean nothing.
struct Cell_scratch {
    std::vector<Vec2> poly, tmp;
    std::vector<double> side;
    std::vector<Step> steps;
    std::vector<char> inside;
    std::vector<Site> nbrs;
    std::vector<Candidate> cands;
    Cell cell;
};

// Clips the cell of `self` (bounded by the bisectors with nbrs[0..n), in that order) to the disk,
// into scratch.cell (its ring is replaced). With no neighbours the cell is the whole disk: a single
// full-circle arc starting at (R, 0). nbrs may point into scratch.nbrs (clipping does not touch
// it). Throws std::bad_alloc only if a buffer must grow.
const Cell &clip_cell(const Site &self, const Site *nbrs, size_t n, double R,
                      Cell_scratch &scratch);

// Exact area of the clipped cell: straight sides plus circular sectors.
double cell_area(const Cell &c);

// The clipped cell as a counter-clockwise polygon, arcs as chords (IIR_TRI_ARC_SEGMENTS per turn).
void cell_polygon(const Cell &c, std::vector<Vec2> &out);

// Appends the points of the clipped cell where the distance to its site can be largest: every
// vertex, and on each arc the point opposite the site (when the arc contains it), each with its
// distance to the site (std::hypot) and its place in this order as its key.
void far_candidates(const Cell &c, std::vector<Candidate> &out);

// Squared distance, the length of an Edge_key: computed as (a - b)^2.
inline double dist2(Vec2 a, Vec2 b)
{
    double dx = a.x - b.x, dy = a.y - b.y;
    return dx * dx + dy * dy;
}

// The shortest edge from `self` to one of nbrs[0..n) into *out (tri_cache.hpp's order), its
// length computed from the younger endpoint to the older; false (out untouched) when n == 0.
bool shortest_incident(const Site &self, const Site *nbrs, size_t n, iirtri::Edge_key &out);

} // namespace iirdisk

#endif

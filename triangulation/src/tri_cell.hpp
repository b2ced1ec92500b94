// tri_cell.hpp -- one Voronoi cell clipped to the disk, as plain geometry: its boundary (segments
// and arcs), exact area, drawing polygon and farthest points; not where the sites come from.
#ifndef IIR_TRI_CELL_HPP
#define IIR_TRI_CELL_HPP

#include "tri_common.hpp"

#include <vector>

namespace iirtri
{

struct Vec2 {
    double x, y;
};

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

// Clips the cell of `self` (bounded by the bisectors with `nbrs`, in the given order) to the disk.
// With no neighbours the cell is the whole disk: a single full-circle arc starting at (R, 0).
Cell clip_cell(const Site &self, const std::vector<Site> &nbrs, double R);

// Exact area of the clipped cell: straight sides plus circular sectors.
double cell_area(const Cell &c);

// The clipped cell as a counter-clockwise polygon, arcs as chords (IIR_TRI_ARC_SEGMENTS per turn).
void cell_polygon(const Cell &c, std::vector<Vec2> &out);

// Appends the points of the clipped cell where the distance to its site can be largest: every
// vertex, and on each arc the point opposite the site (when the arc contains it). Their distance to
// the site is the candidate radius.
void far_candidates(const Cell &c, std::vector<Vec2> &out);

} // namespace iirtri

#endif

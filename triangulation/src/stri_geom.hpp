// stri_geom.hpp -- what the sphere sources of libiirtri share without CGAL: 3-vectors, sites, and
// the spherical Voronoi cell (stri_cell.cpp) the per-site summaries (tri_cache.hpp) are computed
// from; not the CGAL types nor when summaries are redone (stri_domain.cpp, tri_handle.hpp).
//
// A cell is a pure function of a Cell_input: in dimension 2 the site and its Delaunay neighbours
// counter-clockwise (starting at the smallest id), so its summary stays valid until an edit
// changes that list (see tri_cache.hpp for which edits do); in dimension 1 it also depends on the
// plane of all sites (Frame), so every edit redoes them all; dimensions -1 and 0 have at most two
// sites.
#ifndef IIR_STRI_GEOM_HPP
#define IIR_STRI_GEOM_HPP

#include "iir/stri.h"
#include "tri_cache.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace iirstri
{

constexpr double kPi = 3.14159265358979323846264338327950288;

// ---- vectors ----

struct Vec3 {
    double x, y, z;
};

inline Vec3 operator+(Vec3 a, Vec3 b)
{
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3 operator-(Vec3 a, Vec3 b)
{
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3 operator-(Vec3 a)
{
    return {-a.x, -a.y, -a.z};
}
inline Vec3 operator*(double s, Vec3 a)
{
    return {s * a.x, s * a.y, s * a.z};
}
inline double dot(Vec3 a, Vec3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
inline Vec3 cross(Vec3 a, Vec3 b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline double norm(Vec3 a)
{
    return std::sqrt(dot(a, a));
}
// a / |a|; the zero vector stays zero.
inline Vec3 normalize(Vec3 a)
{
    double l = norm(a);
    return l > 0 ? (1 / l) * a : a;
}
// Geodesic distance between unit vectors, in [0, pi]; accurate at every angle.
inline double angle_between(Vec3 a, Vec3 b)
{
    return std::atan2(norm(cross(a, b)), dot(a, b));
}

// ---- sites and candidates ----

using Site = iirtri::Site<Vec3>;

// Which largest-empty-cap candidate this is, for ties: the ascending ids of the sites it is
// equidistant to (unused places hold UINT32_MAX), then `side` (0 or 1: the two poles of a circle
// of sites share their ids). Compared lexicographically.
struct Cap_key {
    uint32_t ids[3];
    uint32_t side;
};

inline bool key_less(const Cap_key &a, const Cap_key &b)
{
    for (int k = 0; k < 3; k++)
        if (a.ids[k] != b.ids[k]) return a.ids[k] < b.ids[k];
    return a.side < b.side;
}

using Candidate = iirtri::Candidate<Vec3, Cap_key>;

// ---- cells ----

// The plane of a set whose sites all lie on one circle: unit normal N (the sites on its side, or
// on it for a great circle) and u, w completing the right-handed frame (u, w, N) in which a site's
// angle around the circle is atan2(p.w, p.u).
struct Frame {
    Vec3 N, u, w;
};

// What one cell depends on. dim is CGAL's: -1 one site, 0 two, 1 all on one circle, 2 otherwise.
// nbrs: dimension 2, the Delaunay neighbours counter-clockwise seen from outside, starting at the
// smallest id; dimension 1, the two neighbours on the circle (either order); dimension 0, the
// other site. `frame` is read in dimension 1 only.
struct Cell_input {
    int dim;
    Site self;
    const Site *nbrs;
    size_t n;
    Frame frame;
};

// One Voronoi edge of a cell: from `from` to `to` along the bisector of the site and `nbr`, turning
// counter-clockwise around the site, i.e. right-handed about `axis` = (site - nbr)/|site - nbr|,
// through `sweep` radians (in [-pi/2, 3 pi/2); exactly pi on a lune, 2 pi for a hemisphere, where
// from == to). `key` names the Voronoi vertex `from` (sides 0/1 for the poles of a circle).
struct Arc {
    Vec3 from, to, axis;
    double sweep;
    Site nbr;
    Cap_key key;
};

// A cell as the cyclic list of its edges, counter-clockwise seen from outside; empty for a lone
// site (the whole sphere). `area` is set by make_cell.
struct Cell {
    Cell_input in;
    std::vector<Arc> ring;
    double area;
};

// Working buffers of the cells and summaries. Whoever owns one reuses it, so that cells allocate
// only while buffers still grow; contents mean nothing between calls.
struct Cell_scratch {
    std::vector<Site> nbrs;
    std::vector<Candidate> cands;
    Cell cell;
};

// The cell of `in` (its ring and area) into scratch.cell. Throws std::bad_alloc only if a buffer
// must grow.
const Cell &make_cell(const Cell_input &in, Cell_scratch &scratch);

// Appends every largest-empty-cap candidate of the cell (Voronoi vertices, and edge points farthest
// from the site) to out, in no particular order. A candidate's radius r is exact where it may tie
// with the cell's largest; the others, further below it than any tie or rounding, get r = -1.
void cap_candidates(const Cell &c, std::vector<Candidate> &out);

// The cell's polygon for drawing (stri.h, DEFINITIONS) into out.
void cell_polygon(const Cell &c, std::vector<Vec3> &out);

// The shortest edge from `self` to one of nbrs[0..n) into *out (tri_cache.hpp's order), its angle
// computed from the younger endpoint to the older; false (out untouched) when n == 0.
bool shortest_incident(const Site &self, const Site *nbrs, size_t n, iirtri::Edge_key &out);

// The frame of a set of sites all on one circle (dimension 1), from the sites by ascending id:
// deterministic for a given set.
Frame circle_frame(const Site *sites, size_t n);

} // namespace iirstri

#endif

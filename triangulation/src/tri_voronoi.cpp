// tri_voronoi.cpp -- the Voronoi side of the API: clipped cell areas and polygons, and the largest
// empty circle in the disk; not the triangulation itself (tri_domain.cpp) nor the cell geometry
// (tri_cell.cpp). No CGAL here: sites and neighbours come through the bridge in tri_common.hpp.
#include "tri_cell.hpp"

#include <algorithm>
#include <cmath>

using namespace iirtri;

namespace
{

// The clipped cell of site `id`; false if there is no such site.
bool cell_of(const iir_tri *tri, uint32_t id, Cell &out)
{
    Site self;
    std::vector<Site> nbrs;
    if (!neighbours(tri, id, self, nbrs)) return false;
    out = clip_cell(self, nbrs, iir_tri_radius(tri));
    return true;
}

// A candidate centre for the largest empty circle and its distance to the site of the cell it came
// from (that site is its nearest, up to rounding).
struct Candidate {
    Vec2 c;
    double r;
};

// Every candidate, cells by ascending id and in ring order within a cell: the exact maximiser of
// the distance to the nearest site over the disk is among them.
std::vector<Candidate> all_candidates(const iir_tri *tri)
{
    std::vector<Site> all;
    sites(tri, all);
    std::vector<Candidate> out;
    std::vector<Vec2> pts;
    Cell cell;
    for (const Site &s : all) {
        cell_of(tri, s.id, cell);
        pts.clear();
        far_candidates(cell, pts);
        for (Vec2 p : pts) out.push_back({p, std::hypot(p.x - s.x, p.y - s.y)});
    }
    return out;
}

// The first candidate within IIR_TRI_TIE_TOL of the largest radius (two passes, so the choice does
// not depend on how ties chain).
Vec2 pick_largest(const std::vector<Candidate> &cands)
{
    double rmax = 0;
    for (const Candidate &k : cands) rmax = std::max(rmax, k.r);
    for (const Candidate &k : cands)
        if (k.r >= rmax * (1 - IIR_TRI_TIE_TOL)) return k.c;
    return cands.front().c;
}

} // namespace

extern "C" iir_tri_status iir_tri_cell_area(const iir_tri *tri, uint32_t id, double *area)
{
    if (!tri || !area) return IIR_TRI_BAD_ARG;
    return guard([&] {
        Cell c;
        if (!cell_of(tri, id, c)) return IIR_TRI_UNKNOWN_ID;
        *area = cell_area(c);
        return IIR_TRI_OK;
    });
}

extern "C" iir_tri_status iir_tri_cell_areas(const iir_tri *tri, uint32_t *ids, double *areas,
                                             size_t cap, size_t *n)
{
    if (!tri || !n || (!ids != !areas)) return IIR_TRI_BAD_ARG;
    return guard([&] {
        iir_tri_status st = fits(ids, cap, iir_tri_count(tri), n);
        if (st != IIR_TRI_OK || !ids) return st;
        std::vector<Site> all;
        sites(tri, all);
        Cell c;
        for (size_t k = 0; k < all.size(); k++) {
            cell_of(tri, all[k].id, c);
            ids[k] = all[k].id;
            areas[k] = cell_area(c);
        }
        return IIR_TRI_OK;
    });
}

extern "C" iir_tri_status iir_tri_cell_polygon(const iir_tri *tri, uint32_t id, double *xy,
                                               size_t cap, size_t *n)
{
    if (!tri || !n) return IIR_TRI_BAD_ARG;
    return guard([&] {
        Cell c;
        if (!cell_of(tri, id, c)) return IIR_TRI_UNKNOWN_ID;
        std::vector<Vec2> poly;
        cell_polygon(c, poly);
        iir_tri_status st = fits(xy, cap, poly.size(), n);
        if (st != IIR_TRI_OK || !xy) return st;
        for (size_t k = 0; k < poly.size(); k++) {
            xy[2 * k] = poly[k].x;
            xy[2 * k + 1] = poly[k].y;
        }
        return IIR_TRI_OK;
    });
}

extern "C" iir_tri_status iir_tri_largest_empty_circle(const iir_tri *tri, double centre[2],
                                                       double *radius)
{
    if (!tri || !centre || !radius) return IIR_TRI_BAD_ARG;
    return guard([&] {
        if (iir_tri_count(tri) == 0) return IIR_TRI_TOO_FEW;
        Vec2 c = pick_largest(all_candidates(tri));
        // The radius is measured from the returned centre, so the two agree exactly.
        Site s;
        nearest(tri, c.x, c.y, s);
        centre[0] = c.x;
        centre[1] = c.y;
        *radius = std::hypot(c.x - s.x, c.y - s.y);
        return IIR_TRI_OK;
    });
}

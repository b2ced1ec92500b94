// tri_voronoi.cpp -- the Voronoi side of the API: clipped cell areas and polygons, the largest
// empty circle in the disk, and the per-site summaries they are answered from; not the
// triangulation itself nor when summaries are redone (tri_domain.cpp), nor the cell geometry
// (tri_cell.cpp). No CGAL here: sites and neighbours come through the bridges in tri_common.hpp
// and tri_cache.hpp.
//
// The largest empty circle is the first candidate, cells by ascending id and in ring order within a
// cell, whose radius is within IIR_TRI_TIE_TOL of the largest radius of all (two passes, so the
// choice does not depend on how ties chain). The summaries make both passes cheap: pass one is the
// maximum of the cells' maxima; pass two skips every cell whose maximum is below the threshold and,
// in the first cell that reaches it, reads the kept candidates (a cell's kept candidates include
// every candidate that can reach a threshold its own maximum reaches). Only when a cell kept too
// few is it clipped again.
#include "tri_cache.hpp"

#include <algorithm>
#include <cmath>

using namespace iirtri;

namespace
{

// rmax * (1 - IIR_TRI_TIE_TOL): radii at or above it tie with rmax. Monotone in rmax.
double tie_threshold(double rmax)
{
    return rmax * (1 - IIR_TRI_TIE_TOL);
}

// The clipped cell of site `id` (in scratch.cell); false if there is no such site.
bool cell_of(const iir_tri *tri, uint32_t id, Cell_scratch &scratch)
{
    Site self;
    if (!neighbours(tri, id, self, scratch.nbrs)) return false;
    clip_cell(self, scratch.nbrs.data(), scratch.nbrs.size(), iir_tri_radius(tri), scratch);
    return true;
}

// The candidates of the clipped cell in scratch.cell (far_candidates order) into scratch.points,
// with their distances to the cell's site into scratch.radii.
void candidates(Cell_scratch &scratch)
{
    const Cell &cell = scratch.cell;
    scratch.points.clear();
    far_candidates(cell, scratch.points);
    scratch.radii.clear();
    for (Vec2 p : scratch.points)
        scratch.radii.push_back(std::hypot(p.x - cell.site.x, p.y - cell.site.y));
}

// The first candidate of the cell of `id` whose radius is >= thr (any candidate when `any`); false
// if there is none. Clips the cell again: only for the rare cells whose summary kept too few.
bool first_candidate_at(const iir_tri *tri, uint32_t id, double thr, bool any, Vec2 &out)
{
    Cell_scratch scratch;
    cell_of(tri, id, scratch);
    candidates(scratch);
    for (size_t k = 0; k < scratch.points.size(); k++)
        if (any || scratch.radii[k] >= thr) {
            out = scratch.points[k];
            return true;
        }
    return false;
}

// The centre of the largest empty circle (see the top of the file); false if no cell has a
// candidate.
bool pick_largest(const iir_tri *tri, Vec2 &out)
{
    const Site_table &table = site_table(tri);
    double rmax = 0;
    for (const Id_slot &e : table.order) rmax = std::max(rmax, table.summary[e.slot].cell.rmax);
    const double thr = tie_threshold(rmax);
    for (const Id_slot &e : table.order) {
        const Cell_summary &c = table.summary[e.slot].cell;
        if (c.ntop == 0 || !(c.rmax >= thr)) continue;
        for (uint32_t k = 0; k < c.ntop; k++)
            if (c.top[k].r >= thr) {
                out = c.top[k].c;
                return true;
            }
        if (c.overflow && first_candidate_at(tri, e.id, thr, false, out)) return true;
    }
    // No radius reaches the threshold (only if every radius is NaN): the first candidate of all.
    for (const Id_slot &e : table.order)
        if (first_candidate_at(tri, e.id, thr, true, out)) return true;
    return false;
}

} // namespace

// ---- per-site summaries (tri_domain.cpp calls this when an edit may have changed them) ----

void iirtri::summarise(const Site &self, const Site *nbrs, size_t n, double R,
                       Cell_scratch &scratch, Site_summary &out)
{
    // The shortest incident edge, its squared length computed as (young - old)^2.
    out.has_edge = n > 0;
    for (size_t k = 0; k < n; k++) {
        const Site &young = self.id > nbrs[k].id ? self : nbrs[k];
        const Site &old = self.id > nbrs[k].id ? nbrs[k] : self;
        double dx = young.x - old.x, dy = young.y - old.y;
        Edge_key e = {dx * dx + dy * dy, young.id, old.id};
        if (k == 0 || shorter(e, out.edge)) out.edge = e;
    }

    // The clipped cell: its area and the candidates near its largest radius.
    Cell_summary &c = out.cell;
    c.area = cell_area(clip_cell(self, nbrs, n, R, scratch));
    candidates(scratch);
    c.rmax = 0;
    for (double r : scratch.radii) c.rmax = std::max(c.rmax, r);
    const double thr = tie_threshold(c.rmax);
    c.ntop = 0;
    c.overflow = false;
    for (size_t k = 0; k < scratch.radii.size() && !c.overflow; k++) {
        if (!(scratch.radii[k] >= thr)) continue;
        if (c.ntop == kTopCandidates)
            c.overflow = true;
        else
            c.top[c.ntop++] = {scratch.points[k], scratch.radii[k]};
    }
}

// ---- the public functions ----

extern "C" iir_tri_status iir_tri_cell_area(const iir_tri *tri, uint32_t id, double *area)
{
    if (!tri || !area) return IIR_TRI_BAD_ARG;
    const Site_table &table = site_table(tri);
    const Id_slot *e = table.find(id);
    if (!e) return IIR_TRI_UNKNOWN_ID;
    *area = table.summary[e->slot].cell.area;
    return IIR_TRI_OK;
}

extern "C" iir_tri_status iir_tri_cell_areas(const iir_tri *tri, uint32_t *ids, double *areas,
                                             size_t cap, size_t *n)
{
    if (!tri || !n || (!ids != !areas)) return IIR_TRI_BAD_ARG;
    const Site_table &table = site_table(tri);
    iir_tri_status st = fits(ids, cap, table.order.size(), n);
    if (st != IIR_TRI_OK || !ids) return st;
    for (size_t k = 0; k < table.order.size(); k++) {
        ids[k] = table.order[k].id;
        areas[k] = table.summary[table.order[k].slot].cell.area;
    }
    return IIR_TRI_OK;
}

extern "C" iir_tri_status iir_tri_cell_polygon(const iir_tri *tri, uint32_t id, double *xy,
                                               size_t cap, size_t *n)
{
    if (!tri || !n) return IIR_TRI_BAD_ARG;
    return guard([&] {
        Cell_scratch scratch;
        if (!cell_of(tri, id, scratch)) return IIR_TRI_UNKNOWN_ID;
        std::vector<Vec2> &poly = scratch.points;
        cell_polygon(scratch.cell, poly);
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
        Vec2 c;
        if (!pick_largest(tri, c)) return IIR_TRI_INTERNAL;
        // The radius is measured from the returned centre, so the two agree exactly.
        Site s;
        nearest(tri, c.x, c.y, s);
        centre[0] = c.x;
        centre[1] = c.y;
        *radius = std::hypot(c.x - s.x, c.y - s.y);
        return IIR_TRI_OK;
    });
}

// stri_voronoi.cpp -- the Voronoi side of the sphere API: cell areas and polygons and the largest
// empty cap, answered from the per-site summaries; not the triangulation nor when summaries are
// redone (stri_domain.cpp), nor the cell geometry (stri_cell.cpp). No CGAL here: sites and
// neighbours come through the bridge in stri_geom.hpp.
//
// The largest empty cap is, among the candidates whose radius is within IIR_TRI_TIE_TOL of the
// largest radius of all, the one with the smallest key in the first cell (ascending id) holding
// one -- two passes, so the choice does not depend on how ties chain. Pass one is the maximum of
// the cells' maxima; pass two skips every cell whose maximum is below the threshold and, in the
// first cell that reaches it, reads the kept candidates (in key order, they include every
// candidate that can reach a threshold the cell's own maximum reaches). Only when a cell kept too
// few is it computed again.
#include "stri_geom.hpp"
#include "tri_common.hpp"

#include <algorithm>
#include <cmath>

using namespace iirstri;
using iirtri::fits;
using iirtri::guard;

namespace
{

// rmax * (1 - IIR_TRI_TIE_TOL): radii at or above it tie with rmax. Monotone in rmax.
double tie_threshold(double rmax)
{
    return rmax * (1 - IIR_TRI_TIE_TOL);
}

// The cell of site `id` (in scratch.cell); false if there is no such site.
bool cell_of(const iir_stri *s, uint32_t id, Cell_scratch &scratch)
{
    Cell_input in;
    if (!cell_input(s, id, scratch, in)) return false;
    make_cell(in, scratch);
    return true;
}

// The candidate of the cell of `id` with the smallest key whose radius is >= thr (any candidate
// when `any`); false if there is none. Computes the cell again: only for the rare cells whose
// summary kept too few.
bool first_candidate_at(const iir_stri *s, uint32_t id, double thr, bool any, Vec3 &out)
{
    Cell_scratch scratch;
    cell_of(s, id, scratch);
    cap_candidates(scratch.cell, scratch.cands);
    const Candidate *best = nullptr;
    for (const Candidate &c : scratch.cands)
        if ((any || c.r >= thr) && (!best || key_less(c.key, best->key))) best = &c;
    if (best) out = best->c;
    return best != nullptr;
}

// The centre of the largest empty cap (see the top of the file) and the site of the cell it came
// from; false if no cell has a candidate. Slots are scanned in storage order (free ones hold no
// candidate); "first by ascending id" is the smallest id among the cells reaching the threshold.
bool pick_largest(const iir_stri *s, Vec3 &out, uint32_t &from)
{
    const Site_table &table = site_table(s);
    double rmax = 0;
    for (const Site_summary &e : table.summary) rmax = std::max(rmax, e.cell.rmax);
    const double thr = tie_threshold(rmax);
    const Site_summary *first = nullptr;
    for (const Site_summary &e : table.summary)
        if (e.cell.ntop > 0 && e.cell.rmax >= thr && (!first || e.id < first->id)) first = &e;
    if (first) {
        from = first->id;
        const Cell_summary &c = first->cell;
        for (uint32_t k = 0; k < c.ntop; k++)
            if (c.top[k].r >= thr) {
                out = c.top[k].c;
                return true;
            }
        if (c.overflow && first_candidate_at(s, first->id, thr, false, out)) return true;
    }
    // No radius reaches the threshold (only if every radius is NaN): the first candidate of all.
    for (const Id_slot &e : table.order)
        if (first_candidate_at(s, e.id, thr, true, out)) {
            from = e.id;
            return true;
        }
    return false;
}

} // namespace

// ---- the public functions ----

extern "C" iir_tri_status iir_stri_cell_area(const iir_stri *s, uint32_t id, double *area)
{
    if (!s || !area) return IIR_TRI_BAD_ARG;
    const Site_table &table = site_table(s);
    const Id_slot *e = table.find(id);
    if (!e) return IIR_TRI_UNKNOWN_ID;
    *area = table.summary[e->slot].cell.area;
    return IIR_TRI_OK;
}

extern "C" iir_tri_status iir_stri_cell_areas(const iir_stri *s, uint32_t *ids, double *areas,
                                              size_t cap, size_t *n)
{
    if (!s || !n || (!ids != !areas)) return IIR_TRI_BAD_ARG;
    const Site_table &table = site_table(s);
    iir_tri_status st = fits(ids, cap, table.order.size(), n);
    if (st != IIR_TRI_OK || !ids) return st;
    for (size_t k = 0; k < table.order.size(); k++) {
        ids[k] = table.order[k].id;
        areas[k] = table.summary[table.order[k].slot].cell.area;
    }
    return IIR_TRI_OK;
}

extern "C" iir_tri_status iir_stri_cell_polygon(const iir_stri *s, uint32_t id, double *xyz,
                                                size_t cap, size_t *n)
{
    if (!s || !n) return IIR_TRI_BAD_ARG;
    return guard([&] {
        Cell_scratch scratch;
        if (!cell_of(s, id, scratch)) return IIR_TRI_UNKNOWN_ID;
        std::vector<Vec3> &poly = scratch.poly;
        cell_polygon(scratch.cell, poly);
        iir_tri_status st = fits(xyz, cap, poly.size(), n);
        if (st != IIR_TRI_OK || !xyz) return st;
        for (size_t k = 0; k < poly.size(); k++) {
            xyz[3 * k] = poly[k].x;
            xyz[3 * k + 1] = poly[k].y;
            xyz[3 * k + 2] = poly[k].z;
        }
        return IIR_TRI_OK;
    });
}

extern "C" iir_tri_status iir_stri_largest_empty_cap(const iir_stri *s, double centre[3],
                                                     double *angle)
{
    if (!s || !centre || !angle) return IIR_TRI_BAD_ARG;
    return guard([&] {
        if (iir_stri_count(s) == 0) return IIR_TRI_TOO_FEW;
        Vec3 c;
        uint32_t from = 0;
        if (!pick_largest(s, c, from)) return IIR_TRI_INTERNAL;
        // The angle is measured from the returned centre, so the two agree exactly.
        const Site near = nearest_site(s, c, from);
        centre[0] = c.x;
        centre[1] = c.y;
        centre[2] = c.z;
        *angle = angle_between(c, near.p);
        return IIR_TRI_OK;
    });
}

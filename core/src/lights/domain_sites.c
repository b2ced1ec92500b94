/* domain_sites.c -- one set of calls over libiirtri's disk and sphere triangulations
 * (domain_sites.h): dispatch by the domain's shape, and the disk's points repacked between the
 * stride 3 of these calls and the stride 2 of tri.h. */
#include "domain_sites.h"

#include <stdlib.h>

#include "iir/stri.h"

static void drop(iir_sites *s)
{
    iir_tri_destroy(s->tri);
    iir_stri_destroy(s->stri);
    s->tri = NULL;
    s->stri = NULL;
}

iir_tri_status iir_sites_fit(iir_sites *s, const iir_light_domain *d)
{
    if (d->shape == IIR_DOMAIN_SPHERE) {
        if (s->shape == IIR_DOMAIN_SPHERE && s->stri) return IIR_TRI_OK;
        drop(s);
        s->shape = IIR_DOMAIN_SPHERE;
        s->stri = iir_stri_create();
        return s->stri ? IIR_TRI_OK : IIR_TRI_NO_MEMORY;
    }
    if (s->shape == IIR_DOMAIN_DISK && s->tri && iir_tri_radius(s->tri) == d->R) return IIR_TRI_OK;
    drop(s);
    s->shape = IIR_DOMAIN_DISK;
    s->tri = iir_tri_create(d->R);
    return s->tri ? IIR_TRI_OK : IIR_TRI_NO_MEMORY;
}

void iir_sites_free(iir_sites *s)
{
    drop(s);
    free(s->xy);
    s->xy = NULL;
    s->xy_cap = 0;
}

iir_tri_status iir_sites_build(iir_sites *s, const double *xyz, const uint32_t *ids, size_t n)
{
    if (s->shape == IIR_DOMAIN_SPHERE) return iir_stri_build(s->stri, xyz, ids, n);
    if (n > s->xy_cap) {
        double *xy = realloc(s->xy, 2 * n * sizeof *xy);
        if (!xy) return IIR_TRI_NO_MEMORY;
        s->xy = xy;
        s->xy_cap = n;
    }
    for (size_t i = 0; i < n; i++) s->xy[2 * i] = xyz[3 * i], s->xy[2 * i + 1] = xyz[3 * i + 1];
    return iir_tri_build(s->tri, s->xy, ids, n);
}

iir_tri_status iir_sites_insert(iir_sites *s, const double p[3], uint32_t id)
{
    if (s->shape == IIR_DOMAIN_SPHERE) return iir_stri_insert(s->stri, p, id);
    return iir_tri_insert(s->tri, p[0], p[1], id);
}

iir_tri_status iir_sites_remove(iir_sites *s, uint32_t id)
{
    if (s->shape == IIR_DOMAIN_SPHERE) return iir_stri_remove(s->stri, id);
    return iir_tri_remove(s->tri, id);
}

int iir_sites_has(const iir_sites *s, uint32_t id)
{
    double p[3];
    return iir_sites_position(s, id, p) == IIR_TRI_OK;
}

iir_tri_status iir_sites_shortest_edge(const iir_sites *s, uint32_t *denser_id)
{
    if (s->shape == IIR_DOMAIN_SPHERE)
        return iir_stri_shortest_edge(s->stri, denser_id, NULL, NULL);
    return iir_tri_shortest_edge(s->tri, denser_id, NULL, NULL);
}

iir_tri_status iir_sites_largest_empty(const iir_sites *s, double centre[3], double *radius)
{
    double r;
    if (!radius) radius = &r;
    if (s->shape == IIR_DOMAIN_SPHERE) return iir_stri_largest_empty_cap(s->stri, centre, radius);
    centre[2] = 0.0;
    return iir_tri_largest_empty_circle(s->tri, centre, radius);
}

iir_tri_status iir_sites_cell_areas(const iir_sites *s, uint32_t *ids, double *areas, size_t cap,
                                    size_t *n)
{
    if (s->shape == IIR_DOMAIN_SPHERE) return iir_stri_cell_areas(s->stri, ids, areas, cap, n);
    return iir_tri_cell_areas(s->tri, ids, areas, cap, n);
}

/* ---- reading a set for drawing ---- */

iir_sites iir_sites_view(const struct iir_tri *tri, const struct iir_stri *stri)
{
    /* the const functions only read through these */
    iir_sites s = {stri ? IIR_DOMAIN_SPHERE : IIR_DOMAIN_DISK, (iir_tri *)tri,
                   (struct iir_stri *)stri, NULL, 0};
    return s;
}

iir_tri_status iir_sites_position(const iir_sites *s, uint32_t id, double p[3])
{
    if (s->shape == IIR_DOMAIN_SPHERE) return iir_stri_position(s->stri, id, p);
    iir_tri_status st = iir_tri_position(s->tri, id, p);
    if (st == IIR_TRI_OK) p[2] = 0.0;
    return st;
}

iir_tri_status iir_sites_edges(const iir_sites *s, uint32_t *pairs, size_t cap, size_t *n)
{
    if (s->shape == IIR_DOMAIN_SPHERE) return iir_stri_edges(s->stri, pairs, cap, n);
    return iir_tri_edges(s->tri, pairs, cap, n);
}

iir_tri_status iir_sites_cell_polygon(const iir_sites *s, uint32_t id, double *xyz, size_t cap,
                                      size_t *n)
{
    if (s->shape == IIR_DOMAIN_SPHERE) return iir_stri_cell_polygon(s->stri, id, xyz, cap, n);
    iir_tri_status st = iir_tri_cell_polygon(s->tri, id, xyz, cap, n);
    if (st != IIR_TRI_OK || !xyz) return st;
    /* stride 2 to 3 in place, from the last point: point k's new place starts at or after its old
     */
    for (size_t k = *n; k-- > 0;) {
        double x = xyz[2 * k], y = xyz[2 * k + 1];
        xyz[3 * k] = x, xyz[3 * k + 1] = y, xyz[3 * k + 2] = 0.0;
    }
    return st;
}

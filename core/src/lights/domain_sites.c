/* domain_sites.c -- one set of calls over libiirtri's disk and sphere triangulations
 * (domain_sites.h): dispatch by the domain's shape, and the disk's points repacked from stride 3
 * to the stride 2 that tri.h takes. */
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
    if (s->shape == IIR_DOMAIN_SPHERE) return iir_stri_position(s->stri, id, p) == IIR_TRI_OK;
    return iir_tri_position(s->tri, id, p) == IIR_TRI_OK;
}

iir_tri_status iir_sites_shortest_edge(const iir_sites *s, uint32_t *denser_id)
{
    if (s->shape == IIR_DOMAIN_SPHERE)
        return iir_stri_shortest_edge(s->stri, denser_id, NULL, NULL);
    return iir_tri_shortest_edge(s->tri, denser_id, NULL, NULL);
}

iir_tri_status iir_sites_largest_empty(const iir_sites *s, double centre[3])
{
    double radius;
    if (s->shape == IIR_DOMAIN_SPHERE) return iir_stri_largest_empty_cap(s->stri, centre, &radius);
    centre[2] = 0.0;
    return iir_tri_largest_empty_circle(s->tri, centre, &radius);
}

iir_tri_status iir_sites_cell_areas(const iir_sites *s, uint32_t *ids, double *areas, size_t cap,
                                    size_t *n)
{
    if (s->shape == IIR_DOMAIN_SPHERE) return iir_stri_cell_areas(s->stri, ids, areas, cap, n);
    return iir_tri_cell_areas(s->tri, ids, areas, cap, n);
}

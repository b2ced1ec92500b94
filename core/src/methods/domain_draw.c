/* domain_draw.c -- a VPL set's domain drawn into the unit disk (domain_draw.h): a disk's points
 * scaled by 1 / R, the sphere's by the equal-area map; edges and cells that the map would tear
 * (across the point straight up, on the rim) are left out of the drawing. The triangulation is
 * read through domain_sites.h, whichever its shape. */
#include "domain_draw.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "lights/domain_sites.h"

/* The set's triangulation, whichever shape, and how its points reach the unit disk. */
typedef struct source {
    iir_sites sites; /* a read-only view */
    float inv_r;     /* disk: 1 / R */
} source;

/* Lambert's azimuthal equal-area map about -y, scaled so that the sphere fills the unit disk. */
static void sphere_to_disk(const double p[3], float out[2])
{
    double c = 1.0 - p[1]; /* 1 + w . (0, -1, 0) */
    if (c < 1e-12) {
        out[0] = 1.f, out[1] = 0.f;
        return;
    }
    double k = 0.5 * sqrt(2.0 / c);
    out[0] = (float)(p[0] * k), out[1] = (float)(p[2] * k);
}

static void to_disk(const source *src, const double *p, float out[2])
{
    if (src->sites.shape == IIR_DOMAIN_SPHERE) return sphere_to_disk(p, out);
    out[0] = (float)(p[0] * src->inv_r), out[1] = (float)(p[1] * src->inv_r);
}

/* A segment the map tore: longer than the disk's radius (only across the rim). */
static bool torn(float ax, float ay, float bx, float by)
{
    float dx = ax - bx, dy = ay - by;
    return dx * dx + dy * dy > 1.f;
}

/* Grows *buf to hold n elements of size `size` (doubling); false when out of memory. */
static bool grow(void **buf, size_t *cap, size_t n, size_t size)
{
    if (n <= *cap) return true;
    size_t c = *cap ? *cap : 64;
    while (c < n) c *= 2;
    void *p = realloc(*buf, c * size);
    if (!p) return false;
    *buf = p;
    *cap = c;
    return true;
}

void iir_domain_draw_free(iir_domain_draw *b)
{
    free(b->sites);
    free(b->pairs);
    free(b->cell_start);
    free(b->points);
    free(b->xy);
    free(b->removed);
}

/* Index of the site with this id (sites sorted by id); UINT32_MAX when absent. */
static uint32_t site_index(const iir_domain_site *sites, uint32_t n, uint32_t id)
{
    uint32_t lo = 0, hi = n;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo) / 2;
        if (sites[mid].id < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < n && sites[lo].id == id ? lo : UINT32_MAX;
}

/* Site i's point in the unit disk: a disk's from the VPL, the sphere's from the triangulation. */
static void site_point(const source *src, const iir_vpl *v, float out[2])
{
    double p[3] = {0.0, 0.0, 0.0};
    if (src->sites.shape == IIR_DOMAIN_SPHERE) {
        iir_sites_position(&src->sites, v->id, p);
        return sphere_to_disk(p, out);
    }
    out[0] = v->disk.x * src->inv_r, out[1] = v->disk.y * src->inv_r;
}

static bool draw_sites(const source *src, const iir_incr *set, iir_domain_draw *b)
{
    uint32_t n = 0;
    const iir_vpl *v = iir_incr_vpls((iir_incr *)set, &n);
    if (!grow((void **)&b->sites, &b->sites_cap, n, sizeof *b->sites) ||
        !grow((void **)&b->cell_start, &b->cell_start_cap, (size_t)n + 1, sizeof *b->cell_start))
        return false;
    uint32_t born = iir_incr_updates(set) - 1;
    for (uint32_t i = 0; i < n; i++) {
        float xy[2];
        site_point(src, &v[i], xy);
        b->sites[i] = (iir_domain_site){xy[0], xy[1], v[i].id,
                                        (uint8_t)((v[i].birth == born ? IIR_SITE_NEW : 0) |
                                                  (v[i].null_sample ? IIR_SITE_NULL : 0))};
    }
    b->d.num_sites = b->d.num_cells = n;
    return true;
}

/* Delaunay edges as index pairs; edges whose ids are not sites, or that the map tore, are
 * dropped. */
static bool draw_edges(const source *src, iir_domain_draw *b)
{
    size_t n = 0;
    if (iir_sites_edges(&src->sites, NULL, 0, &n) != IIR_TRI_OK) return false;
    if (!grow((void **)&b->pairs, &b->edges_cap, n, 2 * sizeof *b->pairs)) return false;
    if (iir_sites_edges(&src->sites, b->pairs, b->edges_cap, &n) != IIR_TRI_OK) return false;
    uint32_t kept = 0;
    for (size_t e = 0; e < n; e++) {
        uint32_t a = site_index(b->sites, b->d.num_sites, b->pairs[2 * e]);
        uint32_t c = site_index(b->sites, b->d.num_sites, b->pairs[2 * e + 1]);
        if (a == UINT32_MAX || c == UINT32_MAX) continue;
        if (torn(b->sites[a].x, b->sites[a].y, b->sites[c].x, b->sites[c].y)) continue;
        b->pairs[2 * kept] = a < c ? a : c;
        b->pairs[2 * kept + 1] = a < c ? c : a;
        kept++;
    }
    b->d.num_edges = kept;
    return true;
}

/* Appends site k's cell (empty when the triangulation does not know the id or the map tore it). */
static bool draw_cell(const source *src, uint32_t k, iir_domain_draw *b, size_t *total)
{
    size_t n = 0;
    iir_tri_status ts =
        iir_sites_cell_polygon(&src->sites, b->sites[k].id, b->xy, b->xy_cap / 3, &n);
    if (ts == IIR_TRI_CAPACITY) {
        if (!grow((void **)&b->xy, &b->xy_cap, 3 * n, sizeof *b->xy)) return false;
        ts = iir_sites_cell_polygon(&src->sites, b->sites[k].id, b->xy, b->xy_cap / 3, &n);
    }
    if (ts != IIR_TRI_OK) n = 0;
    if (!grow((void **)&b->points, &b->points_cap, *total + n, sizeof *b->points)) return false;
    for (size_t j = 0; j < n; j++) to_disk(src, &b->xy[3 * j], b->points[*total + j]);
    for (size_t j = 0; j < n; j++) {
        const float *p = b->points[*total + j], *q = b->points[*total + (j + 1) % n];
        if (torn(p[0], p[1], q[0], q[1])) return true;
    }
    *total += n;
    return true;
}

static bool draw_removed(const source *src, const iir_incr *inc, iir_domain_draw *b)
{
    uint32_t n = 0;
    const double *xyz = iir_incr_removed(inc, &n);
    if (!grow((void **)&b->removed, &b->removed_cap, n, sizeof *b->removed)) return false;
    for (uint32_t i = 0; i < n; i++) to_disk(src, &xyz[3 * i], b->removed[i]);
    b->d.num_removed = n;
    return true;
}

bool iir_domain_draw_build(iir_domain_draw *b, const iir_incr *set, const char *map)
{
    source src = {iir_sites_view(iir_incr_tri(set), iir_incr_stri(set)), 0.f};
    const iir_tri *tri = src.sites.tri; /* NULL for the sphere */
    if (!src.sites.stri && (!tri || iir_tri_radius(tri) <= 0.0)) return false;
    if (tri) src.inv_r = (float)(1.0 / iir_tri_radius(tri));
    memset(&b->d, 0, sizeof b->d);
    /* a non-NULL polygon buffer, so that the triangulation answers IIR_TRI_CAPACITY, not a size
     * query */
    if (!grow((void **)&b->xy, &b->xy_cap, 3 * 64, sizeof *b->xy)) return false;
    if (!draw_sites(&src, set, b) || !draw_edges(&src, b)) return false;
    size_t total = 0;
    for (uint32_t k = 0; k < b->d.num_sites; k++) {
        b->cell_start[k] = (uint32_t)total;
        if (!draw_cell(&src, k, b, &total)) return false;
    }
    b->cell_start[b->d.num_sites] = (uint32_t)total;
    if (!draw_removed(&src, set, b)) return false;
    b->d.map = map;
    b->d.sites = b->sites;
    b->d.edges = (const uint32_t(*)[2])b->pairs;
    b->d.cell_start = b->cell_start;
    b->d.cell_points = (const float(*)[2])b->points;
    b->d.removed = (const float(*)[2])b->removed;
    return true;
}

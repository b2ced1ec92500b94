/* surface_cells.c -- surface-aware cell areas (surface_cells.h): a fixed jittered pattern of the
 * light's rays, traced in parallel, then each ray's cell owner found by a walk over the Delaunay
 * graph and the ray handed to the neighbour whose surface it landed on. */
#include "surface_cells.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "iir/rng.h"

/* The VPLs' planes by coordinate (iir_surface_cells.soa): column k of VPL i is soa[k n_cap + i];
 * PEN is a null sample's penalty, infinite for one and 0 otherwise. */
enum { PX, PY, PZ, NX, NY, NZ, PEN, COLUMNS };

static const float *column(const iir_surface_cells *c, int k)
{
    return c->soa + (size_t)k * c->n_cap;
}

/* A VPL's surface as the hand-over's exact tests read it. */
typedef struct cell_plane {
    iir_vec3 p, n;
    bool null_sample;
} cell_plane;

static cell_plane plane_at(const iir_surface_cells *c, uint32_t i)
{
    const float *s = c->soa + i;
    size_t w = c->n_cap;
    return (cell_plane){iir_v3(s[PX * w], s[PY * w], s[PZ * w]),
                        iir_v3(s[NX * w], s[NY * w], s[NZ * w]), isinf(s[PEN * w])};
}

/* A hit on the surface of plane v: on it within IIR_CELL_PLANE of the ray's length, normals within
 * ~25 degrees; a null sample for a null sample. */
static bool on_surface(const cell_plane *v, const iir_cell_hit *h)
{
    if (v->null_sample || h->null_sample) return v->null_sample == h->null_sample;
    float off = fabsf(iir_dot(iir_sub(h->x, v->p), v->n));
    return off < IIR_CELL_PLANE * h->dist && iir_dot(h->n, v->n) > 0.9f;
}

/* How badly v's surface explains the hit: 0 on it, else the hit's distance from v's plane over the
 * ray's length, plus 1 when the normals are more than 60 degrees apart; a null sample and a
 * surface never explain each other. */
static double misfit(const cell_plane *v, const iir_cell_hit *h)
{
    if (on_surface(v, h)) return 0.0;
    if (v->null_sample || h->null_sample) return INFINITY;
    double off = fabs((double)iir_dot(iir_sub(h->x, v->p), v->n)) / h->dist;
    return off + (iir_dot(h->n, v->n) < 0.5f ? 1.0 : 0.0);
}

static double dist2(const double *a, const double *b)
{
    double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
    return dx * dx + dy * dy + dz * dz;
}

/* The VPL that explains hit h (at domain point s) best: `best` with misfit *fit and distance *d
 * so far, replaced by candidate c when c fits better, or as well and nearer in the domain. */
static void consider(const iir_surface_cells *cells, const double *xyz, uint32_t c,
                     const iir_cell_hit *h, const double s[3], uint32_t *best, double *fit,
                     double *d)
{
    cell_plane v = plane_at(cells, c);
    double f = misfit(&v, h);
    if (!(f <= *fit)) return;
    double dc = dist2(&xyz[3 * c], s);
    if (f < *fit || dc < *d) *best = c, *fit = f, *d = dc;
}

enum { CANDIDATES = 128, CHUNK = 64 };

/* A lower bound of misfit(v, h) for the non-null hit h and every VPL c of [c0, c0 + m), from the
 * packed planes in float (a null sample: infinite): on_surface's test, else the offset over the
 * ray's length plus the normals' penalty. A loop without branches, so the compiler vectors it. */
static void misfit_bounds(const iir_surface_cells *c, uint32_t c0, uint32_t m,
                          const iir_cell_hit *h, float *lb)
{
    const float *px = column(c, PX), *py = column(c, PY), *pz = column(c, PZ), *nx = column(c, NX),
                *ny = column(c, NY), *nz = column(c, NZ), *pen = column(c, PEN);
    float inv = 1.f / h->dist, plane = IIR_CELL_PLANE * h->dist;
    for (uint32_t k = c0; k < c0 + m; k++) {
        float off =
            fabsf((h->x.x - px[k]) * nx[k] + (h->x.y - py[k]) * ny[k] + (h->x.z - pz[k]) * nz[k]);
        float nd = h->n.x * nx[k] + h->n.y * ny[k] + h->n.z * nz[k];
        float f = off * inv + (nd < 0.5f ? 1.f : 0.f);
        lb[k - c0] = (off < plane && nd > 0.9f ? 0.f : f) + pen[k];
    }
}

/* The whole set's best for hit h, after the rings gave *best (misfit *fit): null samples for a
 * null hit; else the VPLs whose bound does not rule them out, checked exactly by consider. */
static void scan_all(const iir_surface_cells *c, const double *xyz, uint32_t n,
                     const iir_cell_hit *h, const double s[3], uint32_t *best, double *fit,
                     double *d)
{
    if (h->null_sample) {
        for (uint32_t k = 0; k < c->n_null; k++) consider(c, xyz, c->nulls[k], h, s, best, fit, d);
        return;
    }
    float lb[CHUNK];
    for (uint32_t c0 = 0; c0 < n; c0 += CHUNK) {
        uint32_t m = n - c0 < CHUNK ? n - c0 : CHUNK;
        misfit_bounds(c, c0, m, h, lb);
        for (uint32_t k = 0; k < m; k++) /* the slack covers float against double rounding */
            if (lb[k] <= *fit * (1.0 + 1e-4) + 1e-6) consider(c, xyz, c0 + k, h, s, best, fit, d);
    }
}

/* Among `owner`, its neighbours and theirs, the VPL whose surface explains hit h (at domain point
 * s) best, the nearest in the domain among equals; when none of them lies on the hit's surface,
 * the best of the whole set (a crowded surface's cells can reach over another's farther than two
 * rings: the conference table's over the floor); the owner when none explains it better. */
static uint32_t best_fit(const iir_surface_cells *c, const double *xyz, const iir_site_graph *g,
                         uint32_t owner, const iir_cell_hit *h, const double s[3])
{
    uint32_t ring[CANDIDATES], ring1, n = iir_site_graph_rings(g, owner, ring, CANDIDATES, &ring1);
    uint32_t best = owner;
    cell_plane v = plane_at(c, owner);
    double fit = misfit(&v, h), d = dist2(&xyz[3 * owner], s);
    for (uint32_t k = 0; k < n; k++) consider(c, xyz, ring[k], h, s, &best, &fit, &d);
    if (fit > 0.0) scan_all(c, xyz, g->n, h, s, &best, &fit, &d);
    return best;
}

static bool reserve(iir_surface_cells *c, uint32_t n)
{
    if (n <= c->n_cap) return true;
    int32_t *delta = realloc(c->delta, n * sizeof *delta);
    if (delta) c->delta = delta;
    float *soa = realloc(c->soa, COLUMNS * (size_t)n * sizeof *soa);
    if (soa) c->soa = soa;
    uint32_t *nulls = realloc(c->nulls, n * sizeof *nulls);
    if (nulls) c->nulls = nulls;
    if (!delta || !soa || !nulls) return false;
    c->n_cap = n;
    return true;
}

void iir_surface_cells_free(iir_surface_cells *c)
{
    free(c->delta);
    free(c->soa);
    free(c->nulls);
    *c = (iir_surface_cells){0};
}

/* Point k of row y of the pattern: cell (x, y) of a side x side grid on [0, 1)^2 with a jitter
 * hashed from its index (the same every frame), mapped onto the domain by area; rows run in
 * alternating directions so that consecutive points are neighbours. */
static void pattern_point(const iir_light_domain *d, uint32_t side, uint32_t y, uint32_t k,
                          double s[3])
{
    uint32_t x = y & 1 ? side - 1 - k : k;
    uint64_t h = iir_mix64(0x5ce11ull << 32 | (uint64_t)(y * side + x));
    float ux = ((float)x + (float)(h & 0xffffff) * 0x1p-24f) / (float)side;
    float uy = ((float)y + (float)(h >> 40) * 0x1p-24f) / (float)side;
    iir_domain_sample(d, iir_v2(fminf(ux, 0x1.fffffep-1f), fminf(uy, 0x1.fffffep-1f)), 0.0, s);
}

/* The rays of pattern rows [y0, y1), IIR_CELL_BATCH at a time: each one's cell owner by a walk
 * from the last one's (from site 0 for the first: the same whatever thread runs the rows), traced,
 * and handed to the neighbour whose surface it hit when it missed the owner's. */
static void rows(iir_surface_cells *c, const iir_light_domain *d, const double *xyz,
                 const iir_site_graph *g, iir_cell_trace_fn trace, void *ctx, uint32_t side,
                 uint32_t y0, uint32_t y1, iir_raystats *rays)
{
    uint32_t owner = 0, owners[IIR_CELL_BATCH];
    double s[IIR_CELL_BATCH][3];
    iir_cell_hit hits[IIR_CELL_BATCH];
    for (uint32_t y = y0; y < y1; y++)
        for (uint32_t k0 = 0; k0 < side; k0 += IIR_CELL_BATCH) {
            int m = side - k0 < IIR_CELL_BATCH ? (int)(side - k0) : IIR_CELL_BATCH;
            for (int q = 0; q < m; q++) {
                pattern_point(d, side, y, k0 + (uint32_t)q, s[q]);
                owners[q] = owner = iir_site_graph_nearest(g, xyz, owner, s[q]);
            }
            trace(ctx, (const double(*)[3])s, y * side + k0, m, hits, rays);
            for (int q = 0; q < m; q++) {
                cell_plane v = plane_at(c, owners[q]);
                if (on_surface(&v, &hits[q])) continue;
                uint32_t to = best_fit(c, xyz, g, owners[q], &hits[q], s[q]);
#pragma omp atomic
                c->delta[owners[q]]--;
#pragma omp atomic
                c->delta[to]++;
            }
        }
}

/* The VPLs' planes into the columns, and the null samples' list. */
static void pack(iir_surface_cells *c, const iir_vpl *vpls, uint32_t n)
{
    float *col[COLUMNS];
    for (int k = 0; k < COLUMNS; k++) col[k] = c->soa + (size_t)k * c->n_cap;
    c->n_null = 0;
    for (uint32_t i = 0; i < n; i++) {
        const iir_vpl *v = &vpls[i];
        col[PX][i] = v->position.x, col[PY][i] = v->position.y, col[PZ][i] = v->position.z;
        col[NX][i] = v->normal.x, col[NY][i] = v->normal.y, col[NZ][i] = v->normal.z;
        col[PEN][i] = v->null_sample ? INFINITY : 0.f;
        if (v->null_sample) c->nulls[c->n_null++] = i;
    }
}

enum { BAND_ROWS = 4 };

iir_status iir_surface_cells_apply(iir_surface_cells *c, const iir_light_domain *d,
                                   const iir_vpl *vpls, const double *xyz, const iir_site_graph *g,
                                   iir_cell_trace_fn trace, void *ctx, double *areas,
                                   iir_raystats *rays, iir_error *err)
{
    uint32_t n = g->n;
    if (n < 2) return IIR_OK;
    if (!reserve(c, n))
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for the surface-aware cell areas");
    uint32_t side = (uint32_t)ceil(sqrt((double)IIR_CELL_RAYS * n));
    uint32_t bands = (side + BAND_ROWS - 1) / BAND_ROWS;
    memset(c->delta, 0, n * sizeof *c->delta);
    pack(c, vpls, n);
#pragma omp parallel
    {
        iir_raystats mine;
        memset(&mine, 0, sizeof mine);
#pragma omp for schedule(dynamic)
        for (uint32_t b = 0; b < bands; b++) {
            uint32_t y1 = (b + 1) * BAND_ROWS < side ? (b + 1) * BAND_ROWS : side;
            rows(c, d, xyz, g, trace, ctx, side, b * BAND_ROWS, y1, &mine);
        }
#pragma omp critical
        iir_raystats_add(rays, &mine);
    }
    double a = d->area / ((double)side * side);
    for (uint32_t i = 0; i < n; i++) areas[i] = fmax(0.0, areas[i] + a * c->delta[i]);
    return IIR_OK;
}

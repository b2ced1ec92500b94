/* render_filter.c -- the geometry-aware filter that gathers the interleaved VPL subsets back, and
 * adding the (filtered or raw) indirect light to the frame; not computing it (render_indirect.c).
 *
 * The window (render.h): offsets -h..h per axis, h = floor(n / 2), weight 1, or 1/2 at +-h when n
 * is even; it is symmetric about the pixel and holds every subset with the same total weight. It
 * runs as two passes, rows then columns, so a pixel costs 2 (2h + 1) taps instead of (2h + 1)^2:
 *  - rows: at (x, y), the weighted sum and weight of the taps (x + dx, y) that see geometry similar
 *    to (x, y) and whose subset has VPLs (pixels of an empty subset hold no estimate);
 *  - columns: the result at (x, y) is sum / weight over the row results (x, y + dy) similar to
 *    (x, y), each bringing its sum and weight.
 * A tap (x + dx, y + dy) thus counts with weight w(dx) w(dy) when it is similar to (x, y + dy) and
 * that is similar to (x, y) -- the separable form of testing it against (x, y) directly. Similar:
 * the normals' cosine is at least filter_normal and the camera depths differ by at most
 * filter_depth relative to the centre's; background (depth INFINITY) is never similar.
 *
 * Threads: both passes are OpenMP loops over tiles writing only their own pixels; the implicit
 * barrier after the row pass orders it before the column pass that reads neighbouring tiles. */
#include <omp.h>

#include "render_internal.h"

typedef struct filter_ctx {
    const iir_renderer *r;
    int n, h;
    float end_weight; /* weight of the offsets +-h */
    float min_cos, max_rel_depth;
    int live[IIR_MAX_SUBSETS]; /* 1 for subsets with VPLs: only their pixels hold an estimate */
} filter_ctx;

/* 1 if pixel j counts for the centre (branch-free: the taps' outcomes are data, not control). */
static inline int similar(const filter_ctx *c, size_t centre, size_t j)
{
    const iir_gbuffer *gb = &c->r->gb;
    float dc = gb->depth[centre];
    return (fabsf(gb->depth[j] - dc) <= c->max_rel_depth * dc) &
           (iir_dot(gb->normal[j], gb->normal[centre]) >= c->min_cos);
}

static inline float tap_weight(const filter_ctx *c, int d)
{
    return d == -c->h || d == c->h ? c->end_weight : 1.f;
}

/* Row pass at (x, y); live points at the subset flags of row y, sx is (x - h) mod n. */
static iir_filter_row row_pass(const filter_ctx *c, int x, int y, const int *live, int sx)
{
    const iir_gbuffer *gb = &c->r->gb;
    int n = c->n, x0 = x - c->h, x1 = x + c->h < gb->width ? x + c->h : gb->width - 1;
    for (; x0 < 0; x0++) sx = sx + 1 == n ? 0 : sx + 1;
    size_t row = (size_t)y * (size_t)gb->width, centre = row + (size_t)x;
    iir_filter_row acc = {iir_v3s(0.f), 0.f};
    for (int xx = x0; xx <= x1; xx++, sx = sx + 1 == n ? 0 : sx + 1) {
        size_t j = row + (size_t)xx;
        float w = (live[sx] & similar(c, centre, j)) ? tap_weight(c, xx - x) : 0.f;
        acc.sum = iir_madd(acc.sum, c->r->raw[j], w);
        acc.w += w;
    }
    return acc;
}

/* Row pass over a tile. */
static void row_pass_tile(const filter_ctx *c, int t)
{
    const iir_gbuffer *gb = &c->r->gb;
    iir_tile tl = iir_tile_at(gb->width, gb->height, IIR_RENDER_TILE, t);
    int n = c->n;
    for (int y = tl.y0; y < tl.y1; y++) {
        const int *live = &c->live[(y % n) * n];
        int sx = ((tl.x0 - c->h) % n + n) % n;
        for (int x = tl.x0; x < tl.x1; x++, sx = sx + 1 == n ? 0 : sx + 1)
            c->r->rows[(size_t)y * (size_t)gb->width + (size_t)x] = row_pass(c, x, y, live, sx);
    }
}

static iir_vec3 column_pass(const filter_ctx *c, int x, int y)
{
    const iir_gbuffer *gb = &c->r->gb;
    int w = gb->width, y0 = y - c->h > 0 ? y - c->h : 0;
    int y1 = y + c->h < gb->height ? y + c->h : gb->height - 1;
    size_t centre = (size_t)y * (size_t)w + (size_t)x;
    iir_vec3 sum = iir_v3s(0.f);
    float wsum = 0.f;
    for (int yy = y0; yy <= y1; yy++) {
        size_t j = (size_t)yy * (size_t)w + (size_t)x;
        float wt = similar(c, centre, j) ? tap_weight(c, yy - y) : 0.f;
        sum = iir_madd(sum, c->r->rows[j].sum, wt);
        wsum += wt * c->r->rows[j].w;
    }
    return wsum > 0.f ? iir_scale(sum, 1.f / wsum) : iir_v3s(0.f);
}

static filter_ctx make_ctx(const iir_renderer *r, const iir_indirect_params *p)
{
    filter_ctx c = {0};
    c.r = r;
    c.n = p->interleave;
    c.h = c.n / 2;
    c.end_weight = c.n % 2 == 0 ? 0.5f : 1.f;
    c.min_cos = p->filter_normal;
    c.max_rel_depth = p->filter_depth;
    for (uint32_t k = 0; k < r->num_subsets; k++) c.live[k] = r->start[k] < r->start[k + 1];
    return c;
}

/* out += rho / pi * E over a tile, E the filtered (or raw) demodulated indirect light. */
static void compose_tile(const filter_ctx *c, bool filter, int t, iir_image *out)
{
    const iir_gbuffer *gb = &c->r->gb;
    iir_tile tl = iir_tile_at(gb->width, gb->height, IIR_RENDER_TILE, t);
    for (int y = tl.y0; y < tl.y1; y++)
        for (int x = tl.x0; x < tl.x1; x++) {
            size_t i = (size_t)y * (size_t)gb->width + (size_t)x;
            if (gb->prim[i] == IIR_NO_HIT) continue;
            iir_vec3 E = filter ? column_pass(c, x, y) : c->r->raw[i];
            iir_vec3 *L = iir_image_at(out, x, y);
            *L = iir_add(*L, iir_mul(iir_scale(gb->albedo[i], IIR_INV_PI), E));
        }
}

void iir_render_filter(const iir_renderer *r, const iir_indirect_params *p, iir_image *out)
{
    filter_ctx c = make_ctx(r, p);
    bool filter = p->filter && p->interleave > 1;
    const iir_gbuffer *gb = &r->gb;
    int tiles = iir_tile_count(gb->width, gb->height, IIR_RENDER_TILE);
#pragma omp parallel
    {
        if (filter) {
#pragma omp for schedule(dynamic, 1)
            for (int t = 0; t < tiles; t++) row_pass_tile(&c, t);
        }
#pragma omp for schedule(dynamic, 1)
        for (int t = 0; t < tiles; t++) compose_tile(&c, filter, t, out);
    }
}

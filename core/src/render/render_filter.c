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
 * the normals' cosine is at least IIR_FILTER_MIN_COS and the camera depths differ by at most
 * IIR_FILTER_MAX_REL_DEPTH relative to the centre's; background (depth INFINITY) is never similar.
 *
 * Multires (r->level set): only level-0 pixels are filtered, and the row pass runs only where a
 * column pass will read it; a pixel of a coarse level is a tap carrying every subset (its value is
 * the upsampled mean of all of them: iir_multires_upsample_span, written to r->raw first in the
 * tiles near level-0 pixels), and takes its own value unfiltered.
 *
 * Threads: both passes are OpenMP loops over whole rows (long runs through each per-pixel array)
 * writing only their own pixels; the implicit barrier after the row pass orders it before the
 * column pass that reads neighbouring rows. */
#include <omp.h>

#include "render_internal.h"

typedef struct filter_ctx {
    const iir_renderer *r;
    const uint32_t *mask; /* r->fmask: which taps are similar (tap_similar) */
    int n, h;
    float end_weight; /* weight of the offsets +-h */
    float min_cos, max_rel_depth;
    int live[IIR_MAX_SUBSETS];   /* 1 for subsets with VPLs: only their pixels hold an estimate */
    iir_receiver_bsdf receivers; /* how r->raw is demodulated (iir_gb_demod) */
} filter_ctx;

/* 1 if pixel j counts for the centre (branch-free: the taps' outcomes are data, not control). */
static inline int similar(const filter_ctx *c, size_t centre, size_t j)
{
    const iir_gbuffer *gb = &c->r->gb;
    float dc = gb->depth[centre];
    return (fabsf(gb->depth[j] - dc) <= c->max_rel_depth * dc) &
           (iir_dot(gb->normal[j], gb->normal[centre]) >= c->min_cos);
}

/* The taps' similarity, per G-buffer: bit MAX_H + d of pixel i's mask says whether the tap d pixels
 * along its row is similar to it, bit 16 + MAX_H + d the tap d pixels along its column (0 beyond
 * the image). It depends only on the G-buffer, which is kept while the camera is still, so the
 * passes read one word per pixel instead of testing depths and normals tap by tap. */
enum { MAX_H = IIR_FILTER_MAX_H, COLUMN = IIR_FILTER_COLUMN };

static uint32_t pixel_mask(const filter_ctx *c, int x, int y)
{
    const iir_gbuffer *gb = &c->r->gb;
    size_t centre = (size_t)y * (size_t)gb->width + (size_t)x;
    uint32_t m = 0;
    for (int d = -c->h; d <= c->h; d++) {
        if (x + d >= 0 && x + d < gb->width)
            m |= (uint32_t)similar(c, centre, centre + (size_t)(ptrdiff_t)d) << (MAX_H + d);
        if (y + d >= 0 && y + d < gb->height)
            m |= (uint32_t)similar(c, centre, centre + (size_t)((ptrdiff_t)d * gb->width))
                 << (COLUMN + MAX_H + d);
    }
    return m;
}

/* Whether the tap d pixels along the row (COLUMN: the column) of pixel i is similar to it. */
static inline int tap_similar(const filter_ctx *c, size_t i, int axis, int d)
{
    return (int)(c->mask[i] >> (axis + MAX_H + d)) & 1;
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
        if (c->r->level) { /* multires: a coarse pixel is a tap of every subset */
            if (!((live[sx] | (c->r->level[j] > 0)) & tap_similar(c, centre, 0, xx - x))) continue;
            float w = tap_weight(c, xx - x);
            acc.sum = iir_madd(acc.sum, c->r->raw[j], w); /* upsample_tile filled it */
            acc.w += w;
            continue;
        }
        float w = (live[sx] & tap_similar(c, centre, 0, xx - x)) ? tap_weight(c, xx - x) : 0.f;
        acc.sum = iir_madd(acc.sum, c->r->raw[j], w);
        acc.w += w;
    }
    return acc;
}

/* Whether a level-0 pixel's column pass reads the row pass at (x, y): always with full shading. */
static bool row_wanted(const filter_ctx *c, int x, int y)
{
    const uint8_t *level = c->r->level;
    if (!level) return true;
    const iir_gbuffer *gb = &c->r->gb;
    int y0 = y - c->h > 0 ? y - c->h : 0, y1 = y + c->h < gb->height ? y + c->h : gb->height - 1;
    for (int yy = y0; yy <= y1; yy++)
        if (level[(size_t)yy * (size_t)gb->width + (size_t)x] == 0) return true;
    return false;
}

/* Whether a level-0 pixel lies in the tile grown by mx columns and my rows: always with full
 * shading. */
static bool tile_near_fine(const filter_ctx *c, const iir_tile *tl, int mx, int my)
{
    const uint8_t *level = c->r->level;
    if (!level) return true;
    const iir_gbuffer *gb = &c->r->gb;
    int y0 = tl->y0 - my > 0 ? tl->y0 - my : 0,
        y1 = tl->y1 + my < gb->height ? tl->y1 + my : gb->height;
    int x0 = tl->x0 - mx > 0 ? tl->x0 - mx : 0,
        x1 = tl->x1 + mx < gb->width ? tl->x1 + mx : gb->width;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++)
            if (level[(size_t)y * (size_t)gb->width + (size_t)x] == 0) return true;
    return false;
}

/* Multires: whether a level-0 pixel lies within h pixels of the tile (into r->near_fine unless it
 * holds it for these levels: `known`), and if so the upsampled value into r->raw at its coarse
 * pixels -- every tap a row pass reads lies in such a tile. */
static void upsample_tile(const filter_ctx *c, int t, bool known)
{
    const iir_gbuffer *gb = &c->r->gb;
    iir_tile tl = iir_tile_at(gb->width, gb->height, IIR_RENDER_TILE, t);
    if (!known) c->r->near_fine[t] = tile_near_fine(c, &tl, c->h, c->h);
    if (!c->r->near_fine[t]) return;
    for (int y = tl.y0; y < tl.y1; y++)
        iir_multires_upsample_span(c->r->mr, y, tl.x0, tl.x1,
                                   c->r->raw + (size_t)y * (size_t)gb->width + (size_t)tl.x0);
}

/* The masks of a tile's pixels (every pixel: the filter of a multires frame reads few, but the
 * masks outlive it). */
static void mask_tile(const filter_ctx *c, int t)
{
    const iir_gbuffer *gb = &c->r->gb;
    iir_tile tl = iir_tile_at(gb->width, gb->height, IIR_RENDER_TILE, t);
    for (int y = tl.y0; y < tl.y1; y++)
        for (int x = tl.x0; x < tl.x1; x++)
            c->r->fmask[(size_t)y * (size_t)gb->width + (size_t)x] = pixel_mask(c, x, y);
}

/* Row pass over row y, in the segments of filter tiles whose rows a column pass reads: whole rows
 * stream through memory (a tile's 16-pixel pieces are too short for the prefetchers). */
static void row_pass_row(const filter_ctx *c, int y)
{
    const iir_gbuffer *gb = &c->r->gb;
    int n = c->n, tiles_x = (gb->width + IIR_RENDER_TILE - 1) / IIR_RENDER_TILE;
    const int *live = &c->live[(y % n) * n];
    for (int tx = 0; tx < tiles_x; tx++) {
        int t = (y / IIR_RENDER_TILE) * tiles_x + tx, x0 = tx * IIR_RENDER_TILE;
        int x1 = x0 + IIR_RENDER_TILE < gb->width ? x0 + IIR_RENDER_TILE : gb->width;
        if (c->r->level && !c->r->near_fine[t]) continue; /* no level-0 pixel reads these rows */
        int sx = ((x0 - c->h) % n + n) % n;
        for (int x = x0; x < x1; x++, sx = sx + 1 == n ? 0 : sx + 1)
            if (row_wanted(c, x, y))
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
        float wt = tap_similar(c, centre, COLUMN, yy - y) ? tap_weight(c, yy - y) : 0.f;
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
    c.min_cos = IIR_FILTER_MIN_COS;
    c.max_rel_depth = IIR_FILTER_MAX_REL_DEPTH;
    for (uint32_t k = 0; k < r->num_subsets; k++) c.live[k] = r->start[k] < r->start[k + 1];
    c.receivers = iir_render_receivers(r, p);
    return c;
}

/* out += through demod / pi * E (iir_gb_demod; through: the pixel's specular chain) over one
 * segment [x0, x1) of row y inside filter tile t, E the filtered (or raw) demodulated indirect
 * light. */
static void compose_segment(const filter_ctx *c, bool filter, int t, int y, int x0, int x1,
                            iir_image *out)
{
    const iir_gbuffer *gb = &c->r->gb;
    /* multires: coarse pixels hold their upsampled value in raw where upsample_tile wrote it */
    bool filled = filter && c->r->level && c->r->near_fine[t];
    iir_vec3 up[IIR_RENDER_TILE];
    if (c->r->level && !filled) iir_multires_upsample_span(c->r->mr, y, x0, x1, up);
    for (int x = x0; x < x1; x++) {
        size_t i = (size_t)y * (size_t)gb->width + (size_t)x;
        if (gb->prim[i] == IIR_NO_HIT) continue;
        bool coarse = c->r->level && c->r->level[i] > 0;
        iir_vec3 E = coarse && !filled   ? up[x - x0]
                     : coarse || !filter ? c->r->raw[i]
                                         : column_pass(c, x, y);
        iir_vec3 *L = iir_image_at(out, x, y);
        iir_vec3 k = gb->any_pbr ? iir_gb_demod(gb, i, c->receivers) : gb->albedo[i];
        if (gb->any_chain) k = iir_mul(k, gb->through[i]);
        iir_compose_add(L, k, E);
    }
}

/* Composes row y, tile by tile along it: whole rows stream through memory (the per-pixel arrays
 * are read once, in order, which a tile's 16-pixel pieces of 16 rows would not do). */
static void compose_row(const filter_ctx *c, bool filter, int y, iir_image *out)
{
    const iir_gbuffer *gb = &c->r->gb;
    int tiles_x = (gb->width + IIR_RENDER_TILE - 1) / IIR_RENDER_TILE;
    for (int tx = 0; tx < tiles_x; tx++) {
        int x0 = tx * IIR_RENDER_TILE;
        int x1 = x0 + IIR_RENDER_TILE < gb->width ? x0 + IIR_RENDER_TILE : gb->width;
        compose_segment(c, filter, (y / IIR_RENDER_TILE) * tiles_x + tx, y, x0, x1, out);
    }
}

#if defined(__x86_64__)
/* Multires: E over [x0, x1) of row y, tile by tile -- in a tile near level-0 pixels, a group of 8
 * holding one by the column pass, its coarse pixels then taking their upsampled value
 * (upsample_tile wrote it in raw), the other groups that value alone; any other tile's pixels,
 * all coarse, their upsampled value. */
static void multires_span(const filter_ctx *c, const iir_filter_lanes *fl, int y, int x0, int x1,
                          iir_vec3 *E)
{
    const iir_renderer *r = c->r;
    int tiles_x = (fl->width + IIR_RENDER_TILE - 1) / IIR_RENDER_TILE;
    for (int s0 = x0; s0 < x1; s0 += IIR_RENDER_TILE) {
        int s1 = s0 + IIR_RENDER_TILE < x1 ? s0 + IIR_RENDER_TILE : x1;
        if (!r->near_fine[(y / IIR_RENDER_TILE) * tiles_x + s0 / IIR_RENDER_TILE]) {
            iir_multires_upsample_span(r->mr, y, s0, s1, E + (s0 - x0));
            continue;
        }
        size_t row = (size_t)y * (size_t)fl->width;
        for (int g = s0; g < s1; g += 8) { /* the column pass only for groups holding level 0 */
            int g1 = g + 8 < s1 ? g + 8 : s1;
            bool fine = iir_filter_any_fine(r->level + row + (size_t)g, g1 - g);
            if (fine) iir_filter_columns_avx2(fl, y, g, g1, E + (g - x0));
            for (int x = g; x < g1; x++)
                if (!fine || r->level[row + (size_t)x] > 0) E[x - x0] = r->raw[row + (size_t)x];
        }
    }
}

/* Composes row y with the column pass 8 pixels a step (AVX2). */
static void compose_row_lanes(const filter_ctx *c, const iir_filter_lanes *fl, int y,
                              iir_image *out)
{
    enum { SPAN = 16 * IIR_RENDER_TILE };
    const iir_gbuffer *gb = &c->r->gb;
    bool plain = !gb->any_pbr && !gb->any_chain; /* albedo / pi alone */
    if (plain && !c->r->level) {
        iir_filter_compose_avx2(fl, gb, y, out);
        return;
    }
    iir_vec3 E[SPAN];
    for (int x0 = 0; x0 < gb->width; x0 += SPAN) {
        int x1 = x0 + SPAN < gb->width ? x0 + SPAN : gb->width;
        if (c->r->level)
            multires_span(c, fl, y, x0, x1, E);
        else
            iir_filter_columns_avx2(fl, y, x0, x1, E);
        if (plain) {
            iir_compose_span_avx2(gb, y, x0, x1, E, out);
            continue;
        }
        for (int x = x0; x < x1; x++) {
            size_t i = (size_t)y * (size_t)gb->width + (size_t)x;
            if (gb->prim[i] == IIR_NO_HIT) continue;
            iir_vec3 *L = iir_image_at(out, x, y);
            iir_vec3 k = gb->any_pbr ? iir_gb_demod(gb, i, c->receivers) : gb->albedo[i];
            if (gb->any_chain) k = iir_mul(k, gb->through[i]);
            iir_compose_add(L, k, E[x - x0]);
        }
    }
}

/* Whether a column pass reads row y's row pass: always with full shading; multires, when a tile
 * within h rows of it lies near level-0 pixels (multires_span). */
static bool row_read(const filter_ctx *c, int y)
{
    const iir_renderer *r = c->r;
    if (!r->level) return true;
    int tiles_x = (r->gb.width + IIR_RENDER_TILE - 1) / IIR_RENDER_TILE;
    int t0 = (y - c->h > 0 ? y - c->h : 0) / IIR_RENDER_TILE;
    int t1 = (y + c->h < r->gb.height ? y + c->h : r->gb.height - 1) / IIR_RENDER_TILE;
    for (int t = t0 * tiles_x; t < (t1 + 1) * tiles_x; t++)
        if (r->near_fine[t]) return true;
    return false;
}

/* Rows [y0, y1) of the filter: each row's row pass into the thread's ring (fl) as soon as a
 * column pass of the band needs it, then the band's rows composed in order -- the row sums stay
 * in the cache instead of going through memory between two passes over the image. */
static void filter_band(const filter_ctx *c, const iir_filter_lanes *fl, int y0, int y1,
                        iir_image *out)
{
    int next = y0 - fl->h > 0 ? y0 - fl->h : 0; /* the next row to pass */
    for (int y = y0; y < y1; y++) {
        int last = y + fl->h < fl->height ? y + fl->h : fl->height - 1;
        for (; next <= last; next++)
            if (row_read(c, next)) iir_filter_rows_avx2(fl, next);
        compose_row_lanes(c, fl, y, out);
    }
}

/* The filter with the AVX2 passes (the scalar ones' image): OpenMP over bands of rows, a thread's
 * row sums in its own ring of 2 h + 1 rows of r->rows (the rows at a band's edges are passed by
 * both bands that read them); where the threads' rings do not fit in r->rows, one row pass over
 * the image and then one column pass. Multires: the coarse values upsampled into raw first
 * (upsample_tile), a coarse pixel a tap of every subset, and the passes only over the groups of 8
 * pixels a level-0 pixel's column pass reads. */
static void filter_lanes(const filter_ctx *c, bool known, iir_image *out)
{
    enum { BAND = 64 }; /* rows: a band passes 2 h rows twice (its edges); 32 were ~5% slower */
    const iir_renderer *r = c->r;
    iir_filter_lanes fl = {r->gb.width,      r->gb.height, c->n,    c->h,
                           c->end_weight,    r->fmask,     c->live, r->raw,
                           (float *)r->rows, r->gb.height, r->level};
    _Static_assert(sizeof(iir_filter_row) == 4 * sizeof(float), "rows hold the four planes");
    int ring = 2 * c->h + 1, bands = (fl.height + BAND - 1) / BAND;
    int tiles = iir_tile_count(fl.width, fl.height, IIR_RENDER_TILE);
    bool fused = (size_t)omp_get_max_threads() * (size_t)ring <= (size_t)fl.height;
#pragma omp parallel
    {
        if (r->level) {
#pragma omp for schedule(dynamic, 1)
            for (int t = 0; t < tiles; t++) upsample_tile(c, t, known);
        }
        if (fused) {
            iir_filter_lanes own = fl;
            own.ring = ring;
            own.planes += (size_t)omp_get_thread_num() * 4 * (size_t)ring * (size_t)fl.width;
#pragma omp for schedule(dynamic, 1)
            for (int b = 0; b < bands; b++)
                filter_band(c, &own, b * BAND,
                            b * BAND + BAND < fl.height ? b * BAND + BAND : fl.height, out);
        } else {
#pragma omp for schedule(dynamic, 8)
            for (int y = 0; y < fl.height; y++)
                if (row_read(c, y)) iir_filter_rows_avx2(&fl, y);
#pragma omp for schedule(dynamic, 8)
            for (int y = 0; y < fl.height; y++) compose_row_lanes(c, &fl, y, out);
        }
    }
}
#endif

void iir_render_filter(iir_renderer *r, const iir_indirect_params *p, iir_image *out)
{
    filter_ctx c = make_ctx(r, p);
    bool filter = !p->unfiltered && p->interleave > 1;
    const iir_gbuffer *gb = &r->gb;
    int tiles = iir_tile_count(gb->width, gb->height, IIR_RENDER_TILE);
    /* the tiles near level-0 pixels change only with the hierarchy (kept while the camera is) */
    uint64_t gen = r->level ? iir_multires_generation(r->mr) : 0;
    bool known = r->near_fine_gen == gen && r->near_fine_h == c.h;
    bool masked = r->fmask_serial == r->gb_serial && r->fmask_h == c.h;
    c.mask = r->fmask;
#if defined(__x86_64__)
    if (filter && r->isa >= IIR_ISA_AVX2) {
        if (!masked) {
#pragma omp parallel for schedule(dynamic, 1)
            for (int t = 0; t < tiles; t++) mask_tile(&c, t);
        }
        filter_lanes(&c, known, out);
        if (r->level) r->near_fine_gen = gen, r->near_fine_h = c.h;
        r->fmask_serial = r->gb_serial, r->fmask_h = c.h;
        return;
    }
#endif
#pragma omp parallel
    {
        if (filter && !masked) {
#pragma omp for schedule(dynamic, 1)
            for (int t = 0; t < tiles; t++) mask_tile(&c, t);
        }
        if (filter && r->level) {
#pragma omp for schedule(dynamic, 1)
            for (int t = 0; t < tiles; t++) upsample_tile(&c, t, known);
        }
        if (filter) {
#pragma omp for schedule(dynamic, 8)
            for (int y = 0; y < gb->height; y++) row_pass_row(&c, y);
        }
#pragma omp for schedule(dynamic, 8)
        for (int y = 0; y < gb->height; y++) compose_row(&c, filter, y, out);
    }
    if (filter && r->level) r->near_fine_gen = gen, r->near_fine_h = c.h;
    if (filter) r->fmask_serial = r->gb_serial, r->fmask_h = c.h;
}

/* multires.c -- the multiresolution shading driver of multires.h: discontinuity mipmaps from the
 * G-buffer, every pixel's level, the texels each level evaluates, their evaluation through the
 * caller's function, the per-level interleave filter and the bilinear upsampling; not what is
 * evaluated (render_indirect.c's VPL sum is one client).
 *
 * Work lists: when the hierarchy is built, each level's texels to evaluate are sorted by class
 * and by tiles of 64 x 64 pixels and cut into items, one per class and tile (up to IIR_MR_BATCH
 * texels): every call of the caller's function gets texels of one class (one VPL subset) lying
 * close together, as the full-resolution indirect tiles do, and a frame only walks the items.
 *
 * Threads: the loops over pixels, items and the larger levels are OpenMP loops writing only their
 * own texels (levels under PARALLEL_MIN texels and the sorting into work lists run on one thread);
 * the evaluation runs one loop over the items of all coarse levels at once, so the coarse levels'
 * few items share the threads. Scratch is sized once per frame size; a build with the camera
 * still is skipped (the G-buffer's serial). */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "iir/multires.h"
#include "render_internal.h"

/* Levels smaller than this many texels are built by one thread: a parallel loop's barrier costs
 * more than their work (and much more on a machine whose cores other jobs share). */
enum { PARALLEL_MIN = 65536 };

enum {
    MARKED = 1, /* a discontinuity lies inside the texel */
    CHOSEN = 2, /* the texel's pixels take this level */
    NEEDED = 4, /* a bilinear tap of some pixel: filtered value wanted */
    EVAL = 8    /* evaluated: a bilinear tap or a filter tap of one */
};

typedef struct mr_level {
    int w, h;
    uint8_t *flag;
    iir_mr_sample *s; /* level >= 1: the mean of the children */
    float *depth;     /* level >= 1: the children's mean camera depth */
    iir_vec3 *E, *F;  /* level >= 1: evaluated and filtered values */
    int n;            /* its interleave (lattice classes n x n; level 0: the caller's) */
    uint64_t work;    /* texels evaluated (level 0: non-background pixels of level 0) */
    uint32_t *order;  /* the texels evaluated, by class: class k is order[start[k] ..
                         start[k + 1]); level 0: its pixels, background last (class n^2) */
    uint32_t start[IIR_MR_MAX_CLASSES + 2];
} mr_level;

/* A unit of evaluation work: up to IIR_MR_BATCH texels of one class of one level. */
typedef struct mr_item {
    int l;
    uint32_t cls, begin, end; /* order[begin .. end) of level l */
} mr_item;

struct iir_multires {
    int width, height; /* the frame size the levels are allocated for */
    mr_level lv[IIR_MR_MAX_LEVEL + 1];
    uint8_t *level; /* per pixel */
    uint8_t *dist;  /* dilation scratch, level 1's size */
    int *cls;       /* class scratch of the work lists, per pixel */
    mr_item *items; /* the coarse levels' work, then level 0's */
    int num_coarse, num_fine, items_cap;
    bool valid;
    uint64_t serial, generation;
    iir_mr_params p;
    int interleave; /* the caller's lattice: n x n classes */
};

/* The side, in texels, of level l's batch tiles: 64 pixels, as the full-resolution indirect tiles,
 * so that a batch of one class sees each VPL's shadow map through a few neighbouring texels (a
 * batch spread over the image spreads the map lookups over the whole map, missing the caches). */
static int batch_tile(int l)
{
    return 64 >> l > 1 ? 64 >> l : 1;
}

/* ---- lifetime ---- */

iir_multires *iir_multires_create(void)
{
    return calloc(1, sizeof(iir_multires));
}

static void free_levels(iir_multires *mr)
{
    for (int l = 0; l <= IIR_MR_MAX_LEVEL; l++) {
        mr_level *v = &mr->lv[l];
        free(v->flag), free(v->s), free(v->depth), free(v->E), free(v->F), free(v->order);
        memset(v, 0, sizeof *v);
    }
    free(mr->level), free(mr->dist), free(mr->items), free(mr->cls);
    mr->cls = NULL;
    mr->level = mr->dist = NULL;
    mr->items = NULL;
    mr->items_cap = mr->num_coarse = mr->num_fine = 0;
    mr->width = mr->height = 0;
    mr->valid = false;
}

void iir_multires_destroy(iir_multires *mr)
{
    if (!mr) return;
    free_levels(mr);
    free(mr);
}

static iir_status alloc_levels(iir_multires *mr, int w, int h, iir_error *err)
{
    if (mr->width == w && mr->height == h) return IIR_OK;
    free_levels(mr);
    bool ok = true;
    for (int l = 0; l <= IIR_MR_MAX_LEVEL; l++) {
        mr_level *v = &mr->lv[l];
        v->w = (w + (1 << l) - 1) >> l, v->h = (h + (1 << l) - 1) >> l;
        size_t n = (size_t)v->w * (size_t)v->h;
        ok &= (v->flag = calloc(n, 1)) != NULL;
        ok &= (v->order = malloc(n * sizeof *v->order)) != NULL;
        int T = batch_tile(l), tiles = ((v->w + T - 1) / T) * ((v->h + T - 1) / T);
        /* an item per class per tile, plus one per full batch */
        mr->items_cap += tiles * IIR_MR_MAX_CLASSES + (int)(n / IIR_MR_BATCH) + 1;
        if (l == 0) continue;
        ok &= (v->s = malloc(n * sizeof *v->s)) != NULL;
        ok &= (v->depth = malloc(n * sizeof *v->depth)) != NULL;
        ok &= (v->E = calloc(n, sizeof *v->E)) != NULL;
        ok &= (v->F = calloc(n, sizeof *v->F)) != NULL;
    }
    ok &= (mr->level = calloc((size_t)w * (size_t)h, 1)) != NULL;
    ok &= (mr->dist = malloc((size_t)mr->lv[1].w * (size_t)mr->lv[1].h)) != NULL;
    ok &= (mr->items = malloc((size_t)mr->items_cap * sizeof *mr->items)) != NULL;
    ok &= (mr->cls = malloc((size_t)w * (size_t)h * sizeof *mr->cls)) != NULL;
    if (!ok) {
        free_levels(mr);
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for the multires levels of %dx%d", w, h);
    }
    mr->width = w, mr->height = h;
    return IIR_OK;
}

iir_status iir_mr_params_validate(const iir_mr_params *p, int interleave, iir_error *err)
{
    if (p->mr_levels < 1 || p->mr_levels > IIR_MR_MAX_LEVEL)
        return iir_fail(err, IIR_ERR_INVALID, "multires max level %d is outside [1, %d]",
                        p->mr_levels, IIR_MR_MAX_LEVEL);
    if (!(p->mr_depth >= 0.f) || isinf(p->mr_depth))
        return iir_fail(err, IIR_ERR_INVALID, "multires depth %g must be finite and >= 0",
                        (double)p->mr_depth);
    if (!(p->mr_normal >= -1.f && p->mr_normal <= 1.f))
        return iir_fail(err, IIR_ERR_INVALID, "multires normal %g is outside [-1, 1]",
                        (double)p->mr_normal);
    if (interleave < 1 || interleave * interleave > IIR_MR_MAX_CLASSES)
        return iir_fail(err, IIR_ERR_INVALID, "multires interleave %d is outside [1, 8]",
                        interleave);
    if (p->mr_window < 1 || p->mr_window > 1024)
        return iir_fail(err, IIR_ERR_INVALID, "multires window %d is outside [1, 1024]",
                        p->mr_window);
    if (p->mr_direct != IIR_MR_DIRECT_FULL && p->mr_direct != IIR_MR_DIRECT_TREE)
        return iir_fail(err, IIR_ERR_INVALID, "multires direct %d is neither full nor tree",
                        (int)p->mr_direct);
    if (!(p->light_split >= 0.f && p->light_split <= 1.f))
        return iir_fail(err, IIR_ERR_INVALID, "multires light_split %g is outside [0, 1]",
                        (double)p->light_split);
    return IIR_OK;
}

/* ---- discontinuities and the mipmaps ---- */

/* Pixel b against pixel a (not background): dissimilar as multires.h defines it. */
static bool dissimilar(const iir_gbuffer *gb, size_t a, size_t b, const iir_mr_params *p)
{
    if (gb->prim[b] == IIR_NO_HIT) return true;
    iir_vec3 na = gb->normal[a], nb = gb->normal[b], d = iir_sub(gb->position[b], gb->position[a]);
    return iir_dot(na, nb) < p->mr_normal || fabsf(iir_dot(na, d)) > p->mr_depth * gb->depth[a] ||
           fabsf(iir_dot(nb, d)) > p->mr_depth * gb->depth[b];
}

enum { RIGHT = 1, BELOW = 2 }; /* a pixel's pair bits: dissimilar to its right / lower neighbour */

/* The pair bits of pixel (x, y); a background pixel is dissimilar to every neighbour. */
static int pair_bits(const iir_gbuffer *gb, int x, int y, const iir_mr_params *p)
{
    size_t w = (size_t)gb->width, i = (size_t)y * w + (size_t)x;
    bool bg = gb->prim[i] == IIR_NO_HIT;
    int bits = 0;
    if (x + 1 < gb->width && (bg || dissimilar(gb, i, i + 1, p))) bits |= RIGHT;
    if (y + 1 < gb->height && (bg || dissimilar(gb, i, i + w, p))) bits |= BELOW;
    return bits;
}

/* Pixel (x, y)'s mark from the pair bits: background, or a pair it belongs to is dissimilar; or
 * a glossy surface (iir_gb_glossy's rule: its light depends on the view, so it is shaded per
 * pixel by its BSDF). */
static uint8_t pixel_mark(const iir_gbuffer *gb, const int *pairs, int x, int y)
{
    size_t w = (size_t)gb->width, i = (size_t)y * w + (size_t)x;
    bool m = gb->prim[i] == IIR_NO_HIT || pairs[i] || (x > 0 && (pairs[i - 1] & RIGHT)) ||
             (y > 0 && (pairs[i - w] & BELOW)) ||
             (gb->any_pbr && iir_gb_glossy(gb, i, IIR_RECEIVER_GLOSSY));
    return m ? MARKED : 0;
}

/* Sums of a texel's children: positions, normals, albedos, depths, how many, any marked. */
typedef struct child_sum {
    iir_vec3 x, n, a;
    float d;
    int k;
    uint8_t marked;
} child_sum;

static void add_child(const iir_multires *mr, const iir_gbuffer *gb, int l, size_t c, child_sum *s)
{
    const mr_level *v = &mr->lv[l - 1];
    s->marked |= v->flag[c] & MARKED;
    if (l == 1) {
        if (gb->prim[c] == IIR_NO_HIT) return;
        s->x = iir_add(s->x, gb->position[c]), s->n = iir_add(s->n, gb->normal[c]);
        s->a = iir_add(s->a, gb->albedo[c]), s->d += gb->depth[c];
    } else {
        s->x = iir_add(s->x, v->s[c].position), s->n = iir_add(s->n, v->s[c].normal);
        s->a = iir_add(s->a, v->s[c].albedo), s->d += v->depth[c];
    }
    s->k++;
}

static void build_texel(iir_multires *mr, const iir_gbuffer *gb, int l, int i, int j)
{
    const mr_level *c = &mr->lv[l - 1];
    mr_level *t = &mr->lv[l];
    child_sum s = {iir_v3s(0.f), iir_v3s(0.f), iir_v3s(0.f), 0.f, 0, 0};
    for (int b = 0; b < 2; b++)
        for (int a = 0; a < 2; a++)
            if (2 * i + a < c->w && 2 * j + b < c->h)
                add_child(mr, gb, l, (size_t)(2 * j + b) * (size_t)c->w + (size_t)(2 * i + a), &s);
    size_t it = (size_t)j * (size_t)t->w + (size_t)i;
    float inv = s.k ? 1.f / (float)s.k : 0.f;
    t->flag[it] = s.marked;
    t->s[it].position = iir_scale(s.x, inv);
    t->s[it].normal = iir_normalize(s.n);
    t->s[it].albedo = iir_scale(s.a, inv);
    t->s[it].pixel = IIR_MR_TEXEL;
    t->depth[it] = s.d * inv;
}

static void build_level(iir_multires *mr, const iir_gbuffer *gb, int l)
{
    const mr_level *t = &mr->lv[l];
#pragma omp parallel for schedule(static) if (t->w * t->h >= PARALLEL_MIN)
    for (int j = 0; j < t->h; j++)
        for (int i = 0; i < t->w; i++) build_texel(mr, gb, l, i, j);
}

/* Level 0's marks and level 1, reading the G-buffer once (a row of level 1 and its two pixel rows
 * at a time): first every pixel's pair bits (each neighbouring pair tested once: the test is
 * symmetric) and level 1's means, then the marks of level 0 and level 1. */
static void build_fine(iir_multires *mr, const iir_gbuffer *gb, int *pairs)
{
    mr_level *t = &mr->lv[1];
    int w = gb->width;
#pragma omp parallel
    {
#pragma omp for schedule(static)
        for (int j = 0; j < t->h; j++) {
            for (int y = 2 * j; y < 2 * j + 2 && y < gb->height; y++)
                for (int x = 0; x < w; x++)
                    pairs[(size_t)y * (size_t)w + (size_t)x] = pair_bits(gb, x, y, &mr->p);
            for (int i = 0; i < t->w; i++) build_texel(mr, gb, 1, i, j); /* marks: below */
        }
#pragma omp for schedule(static)
        for (int j = 0; j < t->h; j++) {
            for (int y = 2 * j; y < 2 * j + 2 && y < gb->height; y++)
                for (int x = 0; x < w; x++)
                    mr->lv[0].flag[(size_t)y * (size_t)w + (size_t)x] = pixel_mark(gb, pairs, x, y);
            for (int i = 0; i < t->w; i++) {
                uint8_t m = 0;
                for (int y = 2 * j; y < 2 * j + 2 && y < gb->height; y++)
                    for (int x = 2 * i; x < 2 * i + 2 && x < w; x++)
                        m |= mr->lv[0].flag[(size_t)y * (size_t)w + (size_t)x];
                t->flag[(size_t)j * (size_t)t->w + (size_t)i] = m & MARKED;
            }
        }
    }
}

static inline bool marked_at(const mr_level *v, int i, int j)
{
    return v->flag[(size_t)j * (size_t)v->w + (size_t)i] & MARKED;
}

/* ---- levels and the texels to evaluate ---- */

static void choose_pixels(iir_multires *mr)
{
    int w = mr->width, L = mr->p.mr_levels;
#pragma omp parallel for schedule(static)
    for (int y = 0; y < mr->height; y++)
        for (int x = 0; x < w; x++) {
            int l = 0;
            while (l < L && !marked_at(&mr->lv[l + 1], x >> (l + 1), y >> (l + 1))) l++;
            mr->level[(size_t)y * (size_t)w + (size_t)x] = (uint8_t)l;
        }
}

/* CHOSEN texels of level l: unmarked, and the parent marked (or l the coarsest). */
static void choose_texels(iir_multires *mr, int l)
{
    mr_level *v = &mr->lv[l];
    const mr_level *up = l < mr->p.mr_levels ? &mr->lv[l + 1] : NULL;
#pragma omp parallel for schedule(static) if (v->w * v->h >= PARALLEL_MIN)
    for (int j = 0; j < v->h; j++)
        for (int i = 0; i < v->w; i++) {
            uint8_t *f = &v->flag[(size_t)j * (size_t)v->w + (size_t)i];
            *f &= MARKED;
            if (!(*f & MARKED) && (!up || marked_at(up, i >> 1, j >> 1))) *f |= CHOSEN;
        }
}

/* Row pass of the Chebyshev distance to the nearest CHOSEN texel, capped at r + 1. */
static void row_distance(iir_multires *mr, int l, int r)
{
    const mr_level *v = &mr->lv[l];
#pragma omp parallel for schedule(static) if (v->w * v->h >= PARALLEL_MIN)
    for (int j = 0; j < v->h; j++)
        for (int i = 0; i < v->w; i++) {
            int best = r + 1;
            for (int d = -r; d <= r; d++) {
                int ii = i + d;
                if (ii >= 0 && ii < v->w &&
                    (v->flag[(size_t)j * (size_t)v->w + (size_t)ii] & CHOSEN) && abs(d) < best)
                    best = abs(d);
            }
            mr->dist[(size_t)j * (size_t)v->w + (size_t)i] = (uint8_t)best;
        }
}

/* NEEDED (distance <= 1) and EVAL (distance <= r) among the unmarked texels of level l. */
static void mark_work(iir_multires *mr, int l, int r)
{
    mr_level *v = &mr->lv[l];
    row_distance(mr, l, r);
    uint64_t work = 0;
#pragma omp parallel for schedule(static) reduction(+ : work) if (v->w * v->h >= PARALLEL_MIN)
    for (int j = 0; j < v->h; j++)
        for (int i = 0; i < v->w; i++) {
            int best = r + 1;
            for (int d = -r; d <= r; d++) {
                int jj = j + d;
                if (jj < 0 || jj >= v->h) continue;
                int rd = mr->dist[(size_t)jj * (size_t)v->w + (size_t)i];
                int cd = abs(d) > rd ? abs(d) : rd;
                if (cd < best) best = cd;
            }
            uint8_t *f = &v->flag[(size_t)j * (size_t)v->w + (size_t)i];
            if (*f & MARKED) continue;
            if (best <= 1) *f |= NEEDED;
            if (best <= r) *f |= EVAL, work++;
        }
    v->work = work;
}

/* ---- the work lists: the texels to evaluate, sorted by class, cut into items ---- */

static int tile_of(const mr_level *v, int T, uint32_t t)
{
    int i = (int)(t % (uint32_t)v->w), j = (int)(t / (uint32_t)v->w);
    return (j / T) * ((v->w + T - 1) / T) + i / T;
}

/* Sorts the texels of class cls_of[i] >= 0 into order by class, and within a class by batch tiles
 * of T x T texels (then rows). */
static void sort_by_class(mr_level *v, int T, int classes, const int *cls_of)
{
    uint32_t count[IIR_MR_MAX_CLASSES + 1] = {0}, next[IIR_MR_MAX_CLASSES + 1];
    size_t n = (size_t)v->w * (size_t)v->h;
    for (size_t i = 0; i < n; i++)
        if (cls_of[i] >= 0) count[cls_of[i]]++;
    v->start[0] = 0;
    for (int k = 0; k < classes; k++) v->start[k + 1] = v->start[k] + count[k];
    for (int k = 0; k < classes; k++) next[k] = v->start[k];
    for (int ty = 0; ty < v->h; ty += T)
        for (int tx = 0; tx < v->w; tx += T)
            for (int j = ty; j < ty + T && j < v->h; j++)
                for (int i = tx; i < tx + T && i < v->w; i++) {
                    size_t t = (size_t)j * (size_t)v->w + (size_t)i;
                    if (cls_of[t] >= 0) v->order[next[cls_of[t]]++] = (uint32_t)t;
                }
}

/* The class of every texel of level l >= 1 that is evaluated, -1 for the others (into tmp). */
static void coarse_classes(const mr_level *v, int *tmp)
{
#pragma omp parallel for schedule(static) if (v->w * v->h >= PARALLEL_MIN)
    for (int j = 0; j < v->h; j++)
        for (int i = 0; i < v->w; i++) {
            size_t t = (size_t)j * (size_t)v->w + (size_t)i;
            tmp[t] = v->flag[t] & EVAL ? (j % v->n) * v->n + i % v->n : -1;
        }
}

/* Level 0's class of pixel (x, y): its class of the caller's n x n lattice, n^2 for background. */
static int fine_class(const iir_gbuffer *gb, int n, int x, int y)
{
    return gb->prim[(size_t)y * (size_t)gb->width + (size_t)x] == IIR_NO_HIT ? n * n
                                                                             : (y % n) * n + x % n;
}

/* Visits the pixels of level 0 -- the children of level 1's marked texels, so only those are
 * touched -- in batch-tile order (a level-1 tile of T texels is level 0's of 2T pixels): counts
 * them by class (order NULL) or files them into order at next. */
static void visit_fine(const iir_multires *mr, const iir_gbuffer *gb, uint32_t *count,
                       uint32_t *next, uint32_t *order)
{
    const mr_level *v = &mr->lv[1];
    int n = mr->interleave, T = batch_tile(1);
    for (int ty = 0; ty < v->h; ty += T)
        for (int tx = 0; tx < v->w; tx += T)
            for (int j = ty; j < ty + T && j < v->h; j++)
                for (int i = tx; i < tx + T && i < v->w; i++) {
                    if (!marked_at(v, i, j)) continue;
                    for (int y = 2 * j; y < 2 * j + 2 && y < gb->height; y++)
                        for (int x = 2 * i; x < 2 * i + 2 && x < gb->width; x++) {
                            int k = fine_class(gb, n, x, y);
                            if (order)
                                order[next[k]++] =
                                    (uint32_t)((size_t)y * (size_t)gb->width + (size_t)x);
                            else
                                count[k]++;
                        }
                }
}

/* Level 0's order: its non-background pixels by class, background pixels as class n^2. */
static void sort_fine(iir_multires *mr, const iir_gbuffer *gb)
{
    mr_level *v0 = &mr->lv[0];
    int n2 = mr->interleave * mr->interleave;
    uint32_t count[IIR_MR_MAX_CLASSES + 1] = {0}, next[IIR_MR_MAX_CLASSES + 1];
    visit_fine(mr, gb, count, NULL, NULL);
    v0->start[0] = 0;
    for (int k = 0; k <= n2; k++) v0->start[k + 1] = v0->start[k] + count[k];
    for (int k = 0; k <= n2; k++) next[k] = v0->start[k];
    visit_fine(mr, gb, NULL, next, v0->order);
}

/* Cuts the classes [0, classes) of level l into items: the texels of one batch tile, at most
 * IIR_MR_BATCH of them. */
static void cut_items(iir_multires *mr, int l, int classes, int *num)
{
    const mr_level *v = &mr->lv[l];
    int T = batch_tile(l);
    for (int k = 0; k < classes; k++)
        for (uint32_t b = v->start[k], e = b; b < v->start[k + 1]; b = e) {
            int tile = tile_of(v, T, v->order[b]);
            while (e < v->start[k + 1] && e - b < IIR_MR_BATCH &&
                   tile_of(v, T, v->order[e]) == tile)
                e++;
            mr->items[(*num)++] = (mr_item){l, (uint32_t)k, b, e};
        }
}

/* Builds every level's order and the items; tmp holds an int per pixel. */
static void build_lists(iir_multires *mr, const iir_gbuffer *gb, int *tmp)
{
    int num = 0;
    for (int l = 1; l <= mr->p.mr_levels; l++) {
        mr_level *v = &mr->lv[l];
        coarse_classes(v, tmp);
        sort_by_class(v, batch_tile(l), v->n * v->n, tmp);
        cut_items(mr, l, v->n * v->n, &num);
    }
    mr->num_coarse = num;
    mr_level *v0 = &mr->lv[0];
    int n2 = mr->interleave * mr->interleave;
    v0->n = mr->interleave;
    sort_fine(mr, gb);
    v0->work = v0->start[n2];
    cut_items(mr, 0, n2, &num);
    mr->num_fine = num - mr->num_coarse;
}

/* Level l's interleave: the window stays `window` pixels wide, at most n texels, at least one. */
static int level_interleave(const iir_mr_params *p, int interleave, int l)
{
    int n = p->mr_window >> l;
    return n < 1 ? 1 : n > interleave ? interleave : n;
}

static bool same_params(const iir_mr_params *a, const iir_mr_params *b)
{
    return a->mr_levels == b->mr_levels && a->mr_depth == b->mr_depth &&
           a->mr_normal == b->mr_normal && a->mr_window == b->mr_window;
}

iir_status iir_multires_build(iir_multires *mr, const iir_gbuffer *gb, uint64_t serial,
                              const iir_mr_params *p, int interleave, iir_error *err)
{
    iir_status s = iir_mr_params_validate(p, interleave, err);
    if (s == IIR_OK) s = alloc_levels(mr, gb->width, gb->height, err);
    if (s != IIR_OK) return s;
    if (mr->valid && mr->serial == serial && mr->interleave == interleave && same_params(&mr->p, p))
        return IIR_OK;
    mr->p = *p;
    mr->interleave = interleave;
    build_fine(mr, gb, mr->cls);
    for (int l = 2; l <= IIR_MR_MAX_LEVEL; l++) build_level(mr, gb, l);
    choose_pixels(mr);
    for (int l = 1; l <= IIR_MR_MAX_LEVEL; l++) {
        mr_level *v = &mr->lv[l];
        v->n = level_interleave(p, interleave, l);
        int r = v->n / 2 + 1;
        if (l > p->mr_levels) {
            for (size_t i = 0; i < (size_t)v->w * (size_t)v->h; i++) v->flag[i] &= MARKED;
            v->work = 0;
            continue;
        }
        choose_texels(mr, l);
        mark_work(mr, l, r);
    }
    build_lists(mr, gb, mr->cls);
    mr->serial = serial;
    mr->generation++;
    mr->valid = true;
    return IIR_OK;
}

/* ---- queries ---- */

int iir_multires_items(const iir_multires *mr)
{
    return mr->valid ? mr->num_coarse + mr->num_fine : 0;
}

void iir_multires_item(const iir_multires *mr, int u, int *m, uint32_t *cls, int *count)
{
    const mr_item *it = &mr->items[u];
    *m = mr->lv[it->l].n, *cls = it->cls, *count = (int)(it->end - it->begin);
}

uint64_t iir_multires_generation(const iir_multires *mr)
{
    return mr->generation;
}

const uint8_t *iir_multires_levels(const iir_multires *mr)
{
    return mr->level;
}

void iir_multires_level_size(const iir_multires *mr, int l, int *w, int *h)
{
    bool ok = l >= 0 && l <= IIR_MR_MAX_LEVEL && mr->valid;
    *w = ok ? mr->lv[l].w : 0;
    *h = ok ? mr->lv[l].h : 0;
}

bool iir_multires_marked(const iir_multires *mr, int l, int i, int j)
{
    return marked_at(&mr->lv[l], i, j);
}

uint64_t iir_multires_work(const iir_multires *mr, int l)
{
    return mr->valid && l >= 0 && l <= IIR_MR_MAX_LEVEL ? mr->lv[l].work : 0;
}

/* ---- evaluation ---- */

typedef struct shade_ctx {
    iir_multires *mr;
    const iir_gbuffer *gb; /* level 0's samples */
    iir_vec3 *out;         /* level 0's values */
    iir_mr_shade_fn fn;
    void *ctx;
    uint64_t live[IIR_MR_MAX_LEVEL + 1]; /* per level: its classes that hold an estimate */
} shade_ctx;

typedef struct texel_batch {
    iir_mr_sample s[IIR_MR_BATCH];
    iir_vec3 E[IIR_MR_BATCH];
} texel_batch;

static iir_mr_sample pixel_sample(const iir_gbuffer *gb, uint32_t i)
{
    return (iir_mr_sample){gb->position[i], gb->normal[i], gb->albedo[i], i};
}

struct iir_mr_samples {
    const shade_ctx *c;
    const mr_item *it;
    iir_mr_sample *s; /* the thread's batch */
    bool read;
};

const iir_mr_sample *iir_mr_samples_read(iir_mr_samples *src)
{
    const mr_item *it = src->it;
    const mr_level *v = &src->c->mr->lv[it->l];
    for (uint32_t q = it->begin; q < it->end && !src->read; q++)
        src->s[q - it->begin] = it->l ? v->s[v->order[q]] : pixel_sample(src->c->gb, v->order[q]);
    src->read = true;
    return src->s;
}

/* Evaluates item u into its level's E (level 0: into out); returns the evaluations. */
static uint64_t shade_item(const shade_ctx *c, int u, texel_batch *b, iir_raystats *st)
{
    const mr_item *it = &c->mr->items[u];
    mr_level *v = &c->mr->lv[it->l];
    int m = (int)(it->end - it->begin);
    iir_mr_samples src = {c, it, b->s, false};
    uint64_t evals = 0;
    if ((c->live[it->l] >> it->cls) & 1)
        evals = c->fn(c->ctx, u, v->n, it->cls, &src, m, b->E, st);
    else
        for (int q = 0; q < m; q++) b->E[q] = iir_v3s(0.f);
    iir_vec3 *E = it->l ? v->E : c->out;
    for (int q = 0; q < m; q++) E[v->order[it->begin + (uint32_t)q]] = b->E[q];
    return evals;
}

/* Evaluates items [first, last); true when stopped. */
static bool evaluate(const shade_ctx *c, int first, int last, iir_stop_fn stop, void *stop_ctx,
                     iir_raystats *st, uint64_t *evals)
{
    int skipped = 0;
    uint64_t sum = 0;
    iir_raystats rays = {0};
#pragma omp parallel reduction(+ : skipped, sum)
    {
        iir_raystats local = {0};
        texel_batch b; /* on the stack: no allocation */
#pragma omp for schedule(dynamic, 1)
        for (int t = first; t < last; t++) {
            if (stop && (skipped || stop(stop_ctx))) {
                skipped = 1;
                continue;
            }
            sum += shade_item(c, t, &b, &local);
        }
#pragma omp critical(iir_multires_rays)
        iir_raystats_add(&rays, &local);
    }
    if (st) iir_raystats_add(st, &rays);
    *evals += sum;
    return skipped > 0;
}

/* ---- the per-level filter and the upsampling ---- */

/* render.h's window weight at offset d of half-width h (1/2 at +-h for an even n). */
static inline float window_weight(int n, int d)
{
    return n % 2 == 0 && (d == n / 2 || d == -n / 2) ? 0.5f : 1.f;
}

/* The filtered value at texel (i, j) of level v: the geometry-aware n x n box over the evaluated
 * texels of live classes similar to it (render.h's similarity on the texels' samples). */
static iir_vec3 filter_texel(const shade_ctx *c, int l, int i, int j)
{
    const mr_level *v = &c->mr->lv[l];
    int n = v->n, h = n / 2;
    size_t centre = (size_t)j * (size_t)v->w + (size_t)i;
    iir_vec3 nc = v->s[centre].normal, sum = iir_v3s(0.f);
    float dc = v->depth[centre], wsum = 0.f;
    float min_cos = IIR_FILTER_MIN_COS, max_rel = IIR_FILTER_MAX_REL_DEPTH;
    for (int dy = -h; dy <= h; dy++) {
        int jj = j + dy;
        if (jj < 0 || jj >= v->h) continue;
        for (int dx = -h; dx <= h; dx++) {
            int ii = i + dx;
            if (ii < 0 || ii >= v->w) continue;
            size_t t = (size_t)jj * (size_t)v->w + (size_t)ii;
            uint32_t cls = (uint32_t)((jj % n) * n + ii % n);
            if (!(v->flag[t] & EVAL) || !((c->live[l] >> cls) & 1) ||
                fabsf(v->depth[t] - dc) > max_rel * dc || iir_dot(v->s[t].normal, nc) < min_cos)
                continue;
            float w = window_weight(n, dx) * window_weight(n, dy);
            sum = iir_madd(sum, v->E[t], w);
            wsum += w;
        }
    }
    return wsum > 0.f ? iir_scale(sum, 1.f / wsum) : iir_v3s(0.f);
}

/* Filters the NEEDED texels of every level (the levels are independent: no barrier between them).
 * Called inside a parallel region. */
static void filter_levels(const shade_ctx *c)
{
    for (int l = 1; l <= c->mr->p.mr_levels; l++) {
        mr_level *v = &c->mr->lv[l];
#pragma omp for schedule(static) nowait
        for (int j = 0; j < v->h; j++)
            for (int i = 0; i < v->w; i++) {
                size_t t = (size_t)j * (size_t)v->w + (size_t)i;
                if (v->flag[t] & NEEDED) v->F[t] = v->n > 1 ? filter_texel(c, l, i, j) : v->E[t];
            }
    }
}

static inline int clampi(int a, int lo, int hi)
{
    return a < lo ? lo : a > hi ? hi : a;
}

/* The four texels around a pixel's bilinear footprint at level l (coordinates clamped), their
 * filtered values and whether each is unmarked (1) or not (0); kept while consecutive pixels of a
 * span share them. */
typedef struct taps {
    int l, i0, j0;
    iir_vec3 F[4];
    float open[4];
    bool all_open;
    iir_vec3 A, B; /* all open: the value is A + fx B along the row (fy fixed by y and l) */
} taps;

static void load_taps(const mr_level *v, int l, int i0, int j0, taps *t)
{
    int ia = clampi(i0, 0, v->w - 1), ib = clampi(i0 + 1, 0, v->w - 1);
    int ja = clampi(j0, 0, v->h - 1), jb = clampi(j0 + 1, 0, v->h - 1);
    size_t k[4] = {(size_t)ja * (size_t)v->w + (size_t)ia, (size_t)ja * (size_t)v->w + (size_t)ib,
                   (size_t)jb * (size_t)v->w + (size_t)ia, (size_t)jb * (size_t)v->w + (size_t)ib};
    t->l = l, t->i0 = i0, t->j0 = j0, t->all_open = true;
    for (int q = 0; q < 4; q++) {
        bool open = !(v->flag[k[q]] & MARKED);
        t->open[q] = open ? 1.f : 0.f;
        t->F[q] = open ? v->F[k[q]] : iir_v3s(0.f);
        t->all_open &= open;
    }
}

/* Where pixel x of row y falls among level l's texel centres: u = (x + 1/2) / 2^l - 1/2 =
 * (2x + 1 - 2^l) / 2^(l+1) = i0 + rem / d (d = 2^(l+1), 0 <= rem < d), floor and fraction exact;
 * one pixel to the right adds 2 to rem. */
typedef struct texel_pos {
    int i0, j0, rem, remy, d;
    float inv; /* 1 / d, exact */
} texel_pos;

static texel_pos texel_at(int l, int x, int y)
{
    static const float INV_D[IIR_MR_MAX_LEVEL + 1] = {0.5f,     0.25f,     0.125f,    0.0625f,
                                                      0.03125f, 0.015625f, 0.0078125f};
    int s = 1 << l, d = 2 * s, nx = 2 * x + 1 - s, ny = 2 * y + 1 - s;
    int i0 = ((nx + d) >> (l + 1)) - 1, j0 = ((ny + d) >> (l + 1)) - 1; /* floor: nx + d > 0 */
    return (texel_pos){i0, j0, nx - i0 * d, ny - j0 * d, d, INV_D[l]};
}

/* The value at fraction fx between the taps t (loaded for fy). */
static iir_vec3 bilinear(const taps *t, float fx, float fy)
{
    if (t->all_open) return iir_madd(t->A, t->B, fx);
    float w[4] = {(1.f - fx) * (1.f - fy), fx * (1.f - fy), (1.f - fx) * fy, fx * fy};
    iir_vec3 sum = iir_v3s(0.f);
    float wsum = 0.f;
    for (int q = 0; q < 4; q++) {
        sum = iir_madd(sum, t->F[q], w[q] * t->open[q]);
        wsum += w[q] * t->open[q];
    }
    return iir_scale(sum, 1.f / wsum);
}

/* Level l's taps at texel (i0, j0) for fraction fy into t, unless it holds them. */
static void taps_for(const mr_level *v, int l, int i0, int j0, float fy, taps *t)
{
    if (t->l == l && t->i0 == i0 && t->j0 == j0) return;
    load_taps(v, l, i0, j0, t);
    t->A = iir_add(iir_scale(t->F[0], 1.f - fy), iir_scale(t->F[2], fy));
    t->B = iir_sub(iir_add(iir_scale(t->F[1], 1.f - fy), iir_scale(t->F[3], fy)), t->A);
}

/* Pixels x .. of row y at level l while they are (below x1) into out[x - x0]: bilinear over the
 * unmarked of each one's four nearest texel centres, weights renormalised (its own texel is
 * unmarked and always among them with weight > 0), the taps reused while consecutive pixels share
 * them. Returns the first pixel past the run. */
static int upsample_run(const mr_level *v, const uint8_t *level, int l, int x, int y, int x1,
                        int x0, iir_vec3 *out, taps *t)
{
    texel_pos p = texel_at(l, x, y);
    float fy = (float)p.remy * p.inv;
    for (; x < x1 && level[x] == l; x++, p.rem += 2) {
        if (p.rem >= p.d) p.rem -= p.d, p.i0++;
        taps_for(v, l, p.i0, p.j0, fy, t);
        out[x - x0] = bilinear(t, (float)p.rem * p.inv, fy);
    }
    return x;
}

/* Writes every coarse pixel's upsampled value. Called inside a parallel region. */
static void upsample_pixels(const iir_multires *mr, iir_vec3 *out)
{
    int w = mr->width;
#pragma omp for schedule(static)
    for (int y = 0; y < mr->height; y++)
        iir_multires_upsample_span(mr, y, 0, w, out + (size_t)y * (size_t)w);
}

/* A class (cx, cy) of an m x m lattice holds an estimate when one of the n x n classes it unites
 * (kx = cx, ky = cy mod m) does. */
static uint64_t level_live(uint64_t live, int n, int m)
{
    uint64_t out = 0;
    for (int k = 0; k < n * n; k++)
        if ((live >> k) & 1) out |= 1ull << ((k / n % m) * m + k % n % m);
    return out;
}

bool iir_multires_shade(iir_multires *mr, iir_mr_shade_fn fn, void *ctx, uint64_t live_classes,
                        iir_vec3 *out, iir_stop_fn stop, void *stop_ctx, iir_raystats *st,
                        uint64_t *evals)
{
    if (!mr->valid) return false;
    shade_ctx c = {mr, NULL, NULL, fn, ctx, {0}};
    for (int l = 1; l <= mr->p.mr_levels; l++)
        c.live[l] = level_live(live_classes, mr->interleave, mr->lv[l].n);
    if (evaluate(&c, 0, mr->num_coarse, stop, stop_ctx, st, evals)) return true;
#pragma omp parallel
    {
        filter_levels(&c);
        if (out) {
#pragma omp barrier
            upsample_pixels(mr, out);
        }
    }
    return false;
}

bool iir_multires_shade_fine(iir_multires *mr, const iir_gbuffer *gb, iir_mr_shade_fn fn, void *ctx,
                             uint64_t live_classes, iir_vec3 *out, iir_stop_fn stop, void *stop_ctx,
                             iir_raystats *st, uint64_t *evals)
{
    if (!mr->valid) return false;
    shade_ctx c = {mr, gb, out, fn, ctx, {live_classes}};
    const mr_level *v = &mr->lv[0];
    int n2 = v->n * v->n;
    for (uint32_t q = v->start[n2]; q < v->start[n2 + 1]; q++) out[v->order[q]] = iir_v3s(0.f);
    return evaluate(&c, mr->num_coarse, mr->num_coarse + mr->num_fine, stop, stop_ctx, st, evals);
}

void iir_multires_upsample_span(const iir_multires *mr, int y, int x0, int x1, iir_vec3 *out)
{
    const uint8_t *level = mr->level + (size_t)y * (size_t)mr->width;
    taps t = {.l = -1};
    for (int x = x0; x < x1;) {
        int l = level[x];
        x = l > 0 ? upsample_run(&mr->lv[l], level, l, x, y, x1, x0, out, &t) : x + 1;
    }
}

/* light_tree.c -- the quadtree of light_tree.h: its arrays, the background blocks, the top
 * corners, each level's probes, splits and fills, the batches of points handed to the caller, and
 * the interpolation of the blocks that did not split. */
#include "light_tree.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

enum {
    ABSENT = 0, /* not in the tree: an ancestor did not split */
    ACTIVE = 1, /* in the tree, not yet decided (level 0: a pixel) */
    LEAF = 2,   /* interpolates its corners */
    SPLIT = 3   /* its children are in the tree */
};

enum {
    CHUNK = 32,   /* blocks per work item: the stop hook is polled between items */
    PROBE_MIN = 2 /* blocks of 4 x 4 pixels and more also test their centre */
};

static const float DARK = 1.f / 20.f; /* Y_dark over the mean luminance of the top corners */

/* ---- arrays ---- */

void light_tree_free(light_tree *t)
{
    free(t->D), free(t->have);
    for (int l = 0; l <= IIR_MR_MAX_LEVEL; l++) free(t->state[l]), free(t->empty[l]);
    memset(t, 0, sizeof *t);
}

static bool alloc_tree(light_tree *t, int w, int h)
{
    if (t->width == w && t->height == h) return true;
    light_tree_free(t);
    size_t n = (size_t)w * (size_t)h;
    bool ok = (t->D = malloc(n * sizeof *t->D)) != NULL && (t->have = malloc(n)) != NULL;
    for (int l = 0; ok && l <= IIR_MR_MAX_LEVEL; l++) {
        t->bw[l] = (w + (1 << l) - 1) >> l, t->bh[l] = (h + (1 << l) - 1) >> l;
        size_t blocks = (size_t)t->bw[l] * (size_t)t->bh[l];
        ok = (t->state[l] = malloc(blocks)) != NULL &&
             (l == 0 || (t->empty[l] = malloc(blocks)) != NULL);
    }
    if (!ok) {
        light_tree_free(t);
        return false;
    }
    t->width = w, t->height = h;
    t->generation = 0; /* the empty blocks are not known yet */
    return true;
}

uint64_t light_tree_memory(int width, int height)
{
    uint64_t px = (uint64_t)width * (uint64_t)height;
    return px * (sizeof(iir_vec3) + 1 + 2); /* D, have, the levels' states and empty flags */
}

/* ---- blocks ---- */

static inline size_t pixel(const light_tree *t, int x, int y)
{
    return (size_t)y * (size_t)t->width + (size_t)x;
}

static inline uint8_t *block(const light_tree *t, int l, int i, int j)
{
    return &t->state[l][(size_t)j * (size_t)t->bw[l] + (size_t)i];
}

static inline uint8_t *empty_at(const light_tree *t, int l, int i, int j)
{
    return &t->empty[l][(size_t)j * (size_t)t->bw[l] + (size_t)i];
}

/* Block (i, j) of level l: its corner pixels x0 <= x1, y0 <= y1. */
typedef struct corners {
    int x0, x1, y0, y1;
} corners;

static corners corners_of(const light_tree *t, int l, int i, int j)
{
    int x0 = i << l, y0 = j << l;
    int x1 = x0 + (1 << l) < t->width - 1 ? x0 + (1 << l) : t->width - 1;
    int y1 = y0 + (1 << l) < t->height - 1 ? y0 + (1 << l) : t->height - 1;
    return (corners){x0, x1, y0, y1};
}

/* A work item's points to evaluate, handed to the caller in batches. */
typedef struct queue {
    const light_tree_input *in;
    uint32_t px[LIGHT_TREE_BATCH];
    int n;
    uint64_t evals;
    iir_raystats rays;
} queue;

static void flush(light_tree *t, queue *q)
{
    if (q->n) q->evals += q->in->eval(q->in->ctx, q->px, q->n, t->D, &q->rays);
    q->n = 0;
}

/* What a pass does to block (i, j) of level m: its points to evaluate go to q. It writes only the
 * block's own points and children (light_tree.h). */
typedef void (*block_fn)(light_tree *t, int m, int i, int j, float Y_dark, queue *q);

/* Runs fn on every block of level m whose state is `want`, CHUNK blocks of a row per item, whose
 * points are evaluated when the item ends; polls stop between items. true when stopped. */
static bool for_blocks(light_tree *t, const light_tree_input *in, int m, uint8_t want, block_fn fn,
                       float Y_dark, const iir_stop *stop, uint64_t *evals, iir_raystats *rays)
{
    const int chunks = (t->bw[m] + CHUNK - 1) / CHUNK;
    int stopped = 0;
    uint64_t sum = 0, n[IIR_RAY_KIND_COUNT] = {0};
#pragma omp parallel for schedule(dynamic, 4) reduction(+ : stopped, sum, n[:IIR_RAY_KIND_COUNT])
    for (int item = 0; item < t->bh[m] * chunks; item++) {
        if (stopped || iir_stop_now(stop)) {
            stopped = 1;
            continue;
        }
        queue q = {.in = in};
        int j = item / chunks, i0 = (item % chunks) * CHUNK;
        for (int i = i0; i < i0 + CHUNK && i < t->bw[m]; i++)
            if (*block(t, m, i, j) == want) fn(t, m, i, j, Y_dark, &q);
        flush(t, &q);
        sum += q.evals;
        for (int k = 0; k < IIR_RAY_KIND_COUNT; k++) n[k] += q.rays.n[k];
    }
    *evals += sum;
    for (int k = 0; k < IIR_RAY_KIND_COUNT; k++) rays->n[k] += n[k];
    return stopped > 0;
}

/* ---- background ---- */

/* Whether every pixel of block (i, j) of level l >= 1 is background: from the G-buffer at level
 * 1, from the children above. */
static uint8_t block_empty(const light_tree *t, const iir_gbuffer *gb, int l, int i, int j)
{
    for (int b = 0; b < 2; b++)
        for (int a = 0; a < 2; a++) {
            int ci = 2 * i + a, cj = 2 * j + b;
            if (l == 1 && ci < t->width && cj < t->height && isfinite(gb->depth[pixel(t, ci, cj)]))
                return 0;
            if (l > 1 && ci < t->bw[l - 1] && cj < t->bh[l - 1] && !*empty_at(t, l - 1, ci, cj))
                return 0;
        }
    return 1;
}

/* The empty flags of levels 1 .. IIR_MR_MAX_LEVEL, when the multires hierarchy (so the G-buffer)
 * changed since they were made. */
static void find_empty(light_tree *t, const light_tree_input *in)
{
    uint64_t g = iir_multires_generation(in->mr);
    if (g == t->generation) return;
    for (int l = 1; l <= IIR_MR_MAX_LEVEL; l++) {
#pragma omp parallel for schedule(static)
        for (int j = 0; j < t->bh[l]; j++)
            for (int i = 0; i < t->bw[l]; i++)
                *empty_at(t, l, i, j) = block_empty(t, in->gb, l, i, j);
    }
    t->generation = g;
}

/* ---- evaluation ---- */

/* D at pixel (x, y), unless evaluated already: queued for the caller's evaluation on a surface
 * (evaluated when the work item ends), 0 on the background. */
static void eval_point(light_tree *t, queue *q, int x, int y)
{
    size_t p = pixel(t, x, y);
    if (t->have[p]) return;
    t->have[p] = 1;
    if (!isfinite(q->in->gb->depth[p])) {
        t->D[p] = iir_v3s(0.f);
        return;
    }
    if (q->n == LIGHT_TREE_BATCH) flush(t, q);
    q->px[q->n++] = (uint32_t)p;
}

/* Whether a corner of c lies on the background (a silhouette that only touches the block's
 * texel diagonally, which multires.h's four-neighbour test does not mark). */
static bool corner_on_background(const light_tree *t, const iir_gbuffer *gb, const corners *c)
{
    return !isfinite(gb->depth[pixel(t, c->x0, c->y0)]) ||
           !isfinite(gb->depth[pixel(t, c->x1, c->y0)]) ||
           !isfinite(gb->depth[pixel(t, c->x0, c->y1)]) ||
           !isfinite(gb->depth[pixel(t, c->x1, c->y1)]);
}

/* Whether block (i, j) of level m, corners c, splits by its geometry: its multires texel is
 * marked, or a corner is background. */
static bool geometry_splits(const light_tree *t, const light_tree_input *in, int m, int i, int j,
                            const corners *c)
{
    return iir_multires_marked(in->mr, m, i, j) || corner_on_background(t, in->gb, c);
}

/* The centre probe of block c of level m (for m >= PROBE_MIN): its pixel (h = 2^(m-1)). */
static void centre_of(const corners *c, int m, int xy[2])
{
    int h = 1 << (m - 1);
    xy[0] = c->x0 + h < c->x1 ? c->x0 + h : c->x1;
    xy[1] = c->y0 + h < c->y1 ? c->y0 + h : c->y1;
}

/* Block (i, j) of level m, in the tree and undecided: when m >= PROBE_MIN and only the light may
 * split it, its centre, for the decision. Queued with the block's corners, by whoever queues them
 * (a clamped centre lies on the block's right or lower edge, its own). */
static void probe(light_tree *t, int m, int i, int j, queue *q)
{
    corners c = corners_of(t, m, i, j);
    if (m < PROBE_MIN || *empty_at(t, m, i, j) || geometry_splits(t, q->in, m, i, j, &c)) return;
    int centre[2];
    centre_of(&c, m, centre);
    eval_point(t, q, centre[0], centre[1]);
}

/* The top level's corners -- each block evaluates its upper left one, the last column's blocks
 * their upper right one too, the last row's their lower ones -- and its probe. */
static void top_corners(light_tree *t, int m, int i, int j, float Y_dark, queue *q)
{
    (void)Y_dark;
    corners c = corners_of(t, m, i, j);
    bool right = i == t->bw[m] - 1 && c.x1 > c.x0, low = j == t->bh[m] - 1 && c.y1 > c.y0;
    eval_point(t, q, c.x0, c.y0);
    if (right) eval_point(t, q, c.x1, c.y0);
    if (low) eval_point(t, q, c.x0, c.y1);
    if (right && low) eval_point(t, q, c.x1, c.y1);
    probe(t, m, i, j, q);
}

/* A split block's children's corners -- the lattice points x0, x0 + 2^(m-1), x1 by y0, y0 +
 * 2^(m-1), y1 not yet evaluated -- and their probes. An edge shared with a block that split as well
 * is the left or upper block's (the right or lower one leaves it), so every point has one writer.
 */
static void fill_children(light_tree *t, int m, int i, int j, float Y_dark, queue *q)
{
    (void)Y_dark;
    corners c = corners_of(t, m, i, j);
    const int h = 1 << (m - 1), xs[3] = {c.x0, c.x0 + h, c.x1}, ys[3] = {c.y0, c.y0 + h, c.y1};
    const bool use_x[3] = {i == 0 || *block(t, m, i - 1, j) != SPLIT, (c.x0 + h < c.x1),
                           (c.x1 > c.x0)};
    const bool use_y[3] = {j == 0 || *block(t, m, i, j - 1) != SPLIT, (c.y0 + h < c.y1),
                           (c.y1 > c.y0)};
    for (int b = 0; b < 3; b++)
        for (int a = 0; a < 3; a++)
            if (use_x[a] && use_y[b]) eval_point(t, q, xs[a], ys[b]);
    for (int b = 0; b < 2; b++)
        for (int a = 0; a < 2; a++)
            if (2 * i + a < t->bw[m - 1] && 2 * j + b < t->bh[m - 1])
                probe(t, m - 1, 2 * i + a, 2 * j + b, q);
}

/* ---- the splits ---- */

static inline float lerpf(float a, float b, float f)
{
    return a + (b - a) * f;
}

/* Whether the light changes across the block of corners c (light_tree.h): the luminances Y of its
 * corners and of the probe p inside it (NULL: none) differ by more than (3 + t) / 4 (max Y +
 * Y_dark), or Y(p) differs from the corners' bilinear interpolation at p by more than t (max Y +
 * Y_dark). */
static bool light_changes(const light_tree *t, const corners *c, const int *p_xy, float threshold,
                          float Y_dark)
{
    const size_t p[4] = {pixel(t, c->x0, c->y0), pixel(t, c->x1, c->y0), pixel(t, c->x0, c->y1),
                         pixel(t, c->x1, c->y1)};
    float Y[4], lo = INFINITY, hi = -INFINITY;
    for (int k = 0; k < 4; k++) {
        assert(t->have[p[k]]);
        Y[k] = iir_luminance(t->D[p[k]]);
        lo = Y[k] < lo ? Y[k] : lo, hi = Y[k] > hi ? Y[k] : hi;
    }
    const float edge = 0.25f * (3.f + threshold); /* a lit corner against a nearly dark one */
    if (!p_xy) return hi - lo > edge * (hi + Y_dark);
    size_t q = pixel(t, p_xy[0], p_xy[1]);
    assert(t->have[q]);
    float Yp = iir_luminance(t->D[q]);
    float fx = c->x1 > c->x0 ? (float)(p_xy[0] - c->x0) / (float)(c->x1 - c->x0) : 0.f;
    float fy = c->y1 > c->y0 ? (float)(p_xy[1] - c->y0) / (float)(c->y1 - c->y0) : 0.f;
    float Y_bilinear = lerpf(lerpf(Y[0], Y[1], fx), lerpf(Y[2], Y[3], fx), fy);
    lo = Yp < lo ? Yp : lo, hi = Yp > hi ? Yp : hi;
    return hi - lo > edge * (hi + Y_dark) || fabsf(Yp - Y_bilinear) > threshold * (hi + Y_dark);
}

static inline iir_vec3 lerp(iir_vec3 a, iir_vec3 b, float f)
{
    return iir_madd(a, iir_sub(b, a), f);
}

/* A leaf's own pixels [x0, x0 + 2^m) x [y0, y0 + 2^m) not evaluated: its corners' bilinear
 * interpolation. */
static void interpolate(light_tree *t, int m, const corners *c)
{
    iir_vec3 *D = t->D;
    const iir_vec3 D00 = D[pixel(t, c->x0, c->y0)], D10 = D[pixel(t, c->x1, c->y0)];
    const iir_vec3 D01 = D[pixel(t, c->x0, c->y1)], D11 = D[pixel(t, c->x1, c->y1)];
    const int xe = c->x0 + (1 << m) < t->width ? c->x0 + (1 << m) : t->width;
    const int ye = c->y0 + (1 << m) < t->height ? c->y0 + (1 << m) : t->height;
    float fx[1 << IIR_MR_MAX_LEVEL];
    for (int x = c->x0; x < xe; x++)
        fx[x - c->x0] = c->x1 > c->x0 ? (float)(x - c->x0) / (float)(c->x1 - c->x0) : 0.f;
    for (int y = c->y0; y < ye; y++) {
        float fy = c->y1 > c->y0 ? (float)(y - c->y0) / (float)(c->y1 - c->y0) : 0.f;
        const uint8_t *have = &t->have[pixel(t, 0, y)];
        iir_vec3 *row = &D[pixel(t, 0, y)];
        for (int x = c->x0; x < xe; x++) {
            if (have[x]) continue;
            float f = fx[x - c->x0];
            row[x] = lerp(lerp(D00, D10, f), lerp(D01, D11, f), fy);
        }
    }
}

/* A block of background: its own pixels not evaluated get no light (their albedo is 0 anyway; the
 * evaluated ones, corners that neighbours read, are 0 already). */
static void clear(light_tree *t, int m, const corners *c)
{
    const int xe = c->x0 + (1 << m) < t->width ? c->x0 + (1 << m) : t->width;
    const int ye = c->y0 + (1 << m) < t->height ? c->y0 + (1 << m) : t->height;
    for (int y = c->y0; y < ye; y++)
        for (int x = c->x0; x < xe; x++) {
            if (t->have[pixel(t, x, y)]) continue;
            t->D[pixel(t, x, y)] = iir_v3s(0.f);
            t->have[pixel(t, x, y)] = 1;
        }
}

/* An undecided block of level m >= 1: all background, it is a leaf without light; else it splits
 * (by its geometry, or where the light changes across it, judged from its corners and, from level
 * PROBE_MIN up, its centre, probed before) and puts its children into level m - 1, or becomes a
 * leaf and interpolates its pixels. */
static void decide(light_tree *t, int m, int i, int j, float Y_dark, queue *q)
{
    corners c = corners_of(t, m, i, j);
    if (*empty_at(t, m, i, j)) {
        *block(t, m, i, j) = LEAF;
        clear(t, m, &c);
        return;
    }
    bool split = geometry_splits(t, q->in, m, i, j, &c);
    if (!split && m >= PROBE_MIN) {
        int centre[2];
        centre_of(&c, m, centre);
        split = light_changes(t, &c, centre, q->in->threshold, Y_dark);
    } else if (!split) {
        split = light_changes(t, &c, NULL, q->in->threshold, Y_dark);
    }
    *block(t, m, i, j) = split ? SPLIT : LEAF;
    if (!split) interpolate(t, m, &c);
    for (int b = 0; split && b < 2; b++)
        for (int a = 0; a < 2; a++)
            if (2 * i + a < t->bw[m - 1] && 2 * j + b < t->bh[m - 1])
                *block(t, m - 1, 2 * i + a, 2 * j + b) = ACTIVE;
}

/* ---- the frame ---- */

/* Y_dark: the mean luminance of the top level's (upper left) corners on surfaces, times DARK. */
static float dark_luminance(const light_tree *t, const light_tree_input *in)
{
    const int l = in->top;
    double sum = 0;
    int n = 0;
    for (int j = 0; j < t->bh[l]; j++)
        for (int i = 0; i < t->bw[l]; i++) {
            size_t p = pixel(t, i << l, j << l);
            if (!isfinite(in->gb->depth[p])) continue;
            sum += iir_luminance(t->D[p]);
            n++;
        }
    return n ? DARK * (float)(sum / n) : 0.f;
}

iir_status light_tree_shade(light_tree *t, const light_tree_input *in, const iir_stop *stop,
                            uint64_t *evals, iir_raystats *rays, iir_error *err)
{
    assert(in->top >= 1 && in->top <= IIR_MR_MAX_LEVEL && in->threshold >= 0.f);
    if (!alloc_tree(t, in->gb->width, in->gb->height))
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for the direct light's tree");
    const int top = in->top;
    find_empty(t, in);
    memset(t->have, 0, (size_t)t->width * (size_t)t->height);
    memset(t->state[top], ACTIVE, (size_t)t->bw[top] * (size_t)t->bh[top]);
    bool stopped = for_blocks(t, in, top, ACTIVE, top_corners, 0.f, stop, evals, rays);
    float Y_dark = stopped ? 0.f : dark_luminance(t, in);
    for (int m = top; m >= 1 && !stopped; m--) {
        memset(t->state[m - 1], ABSENT, (size_t)t->bw[m - 1] * (size_t)t->bh[m - 1]);
        stopped = for_blocks(t, in, m, ACTIVE, decide, Y_dark, stop, evals, rays) ||
                  for_blocks(t, in, m, SPLIT, fill_children, Y_dark, stop, evals, rays);
    }
    if (stopped) return iir_fail(err, IIR_ERR_INTERRUPTED, "frame stopped early");
    return IIR_OK;
}

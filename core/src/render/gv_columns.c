/* gv_columns.c -- the kept VPLs' columns of G V (gv_columns.h): which VPL has which, the epoch
 * they belong to, and where each tile's pixels lie in them. */
#include "gv_columns.h"

#include <stdlib.h>
#include <string.h>

/* One VPL's column and what it was computed for. */
typedef struct slot {
    uint64_t stamp; /* its map's rendering (iir_smap.stamp) */
    iir_vec3 p, n;
    float radius;
    uint32_t cls;  /* the pixel class its subset shades */
    uint64_t last; /* the frame it was last shaded in */
    float *col;    /* NULL until it is written */
    bool ready;    /* col holds G V at every pixel of cls */
    bool writing;  /* this frame writes col */
} slot;

/* What every column depends on besides its VPL. */
typedef struct epoch {
    uint64_t gb_serial, mr_generation; /* multires: the hierarchy's (its items); full: 0 */
    int width, height, n;
    float g_max, rel_bias, eps;
    iir_receiver_bsdf receivers;
} epoch;

struct iir_gv_columns {
    epoch at;
    uint32_t *ord;   /* per (tile, class): gv_columns.h's ord */
    uint32_t *pixel; /* per hit pixel, by class: gv_columns.h's pixel */
    float *soa;      /* per hit pixel, by class: its position and normal, 6 planes */
    uint8_t *glossy; /* per (tile, class) */
    uint32_t base[IIR_MAX_SUBSETS + 1];
    uint32_t len;                    /* the longest slot's samples: every column's length */
    uint32_t total[IIR_MAX_SUBSETS]; /* per slot (class or subset): its samples */
    slot *slots;
    uint32_t num_slots, slot_cap;
    uint32_t *hash; /* open addressing by stamp: slot index + 1, 0 empty */
    uint32_t hash_cap;
    float **spare; /* columns of slots that left, for new ones */
    uint32_t num_spare, spare_cap, columns;
    uint64_t frame;
    uint32_t known; /* this frame's VPLs shaded the frame before as well */
    bool kept_last; /* most of the last frame's VPLs had been shaded the frame before it */
    iir_gv_ref *ref;
    uint32_t ref_cap;
};

void iir_gv_free(iir_gv_columns *c)
{
    if (!c) return;
    for (uint32_t i = 0; i < c->num_slots; i++) free(c->slots[i].col);
    for (uint32_t i = 0; i < c->num_spare; i++) free(c->spare[i]);
    free(c->ord), free(c->pixel), free(c->glossy), free(c->soa);
    free(c->slots), free(c->hash), free(c->spare), free(c->ref);
    free(c);
}

/* Every column dropped (a new epoch). */
static void drop_all(iir_gv_columns *c)
{
    for (uint32_t i = 0; i < c->num_slots; i++) free(c->slots[i].col);
    for (uint32_t i = 0; i < c->num_spare; i++) free(c->spare[i]);
    c->num_slots = c->num_spare = c->columns = 0;
}

/* Hit pixel p of the G-buffer as the o-th of the tiles' pixels by class. */
static void put_pixel(iir_gv_columns *c, const iir_gbuffer *gb, uint32_t o, size_t p)
{
    size_t plane = c->base[c->at.n * c->at.n];
    c->pixel[o] = (uint32_t)p;
    const float v[6] = {gb->position[p].x, gb->position[p].y, gb->position[p].z,
                        gb->normal[p].x,   gb->normal[p].y,   gb->normal[p].z};
    for (int q = 0; q < 6; q++) c->soa[(size_t)q * plane + o] = v[q];
}

/* Tile t's hit pixels by class, in the order render_indirect.c collects them (rows of the class's
 * lattice): into pixel at next[c] when pixel is not NULL, else counted. Their glossy flags too. */
static void tile_pixels(iir_gv_columns *c, const iir_gbuffer *gb, int n, int t, uint32_t *next)
{
    uint32_t n2 = (uint32_t)(n * n);
    iir_tile tl = iir_indirect_tile_at(gb->width, gb->height, t);
    for (int j = 0; j < n && tl.y0 + j < tl.y1; j++)
        for (int i = 0; i < n && tl.x0 + i < tl.x1; i++) {
            uint32_t k = (uint32_t)(((tl.y0 + j) % n) * n + (tl.x0 + i) % n);
            bool glossy = false;
            for (int y = tl.y0 + j; y < tl.y1; y += n)
                for (int x = tl.x0 + i; x < tl.x1; x += n) {
                    size_t p = (size_t)y * (size_t)gb->width + (size_t)x;
                    if (gb->prim[p] == IIR_NO_HIT) continue;
                    if (c->pixel) put_pixel(c, gb, c->base[k] + next[k], p);
                    next[k]++;
                    glossy |= gb->any_pbr && iir_gb_glossy(gb, p, c->at.receivers);
                }
            c->glossy[(size_t)t * n2 + k] = glossy;
        }
}

/* ord, pixel, base, glossy and len for the G-buffer. */
static bool count_pixels(iir_gv_columns *c, const iir_gbuffer *gb, int n)
{
    uint32_t n2 = (uint32_t)(n * n), next[IIR_MAX_SUBSETS] = {0};
    int tiles = iir_indirect_tile_count(gb->width, gb->height);
    free(c->ord), free(c->pixel), free(c->glossy), free(c->soa);
    c->pixel = NULL, c->soa = NULL;
    c->ord = malloc(sizeof *c->ord * (size_t)tiles * n2);
    c->glossy = malloc((size_t)tiles * n2);
    if (!c->ord || !c->glossy) return false;
    for (int t = 0; t < tiles; t++) {
        for (uint32_t k = 0; k < n2; k++) c->ord[(size_t)t * n2 + k] = next[k];
        tile_pixels(c, gb, n, t, next);
    }
    c->len = 0;
    c->base[0] = 0;
    for (uint32_t k = 0; k < n2; k++) {
        c->len = next[k] > c->len ? next[k] : c->len;
        c->total[k] = next[k];
        c->base[k + 1] = c->base[k] + next[k];
        next[k] = 0;
    }
    c->pixel = malloc(sizeof *c->pixel * (c->base[n2] ? c->base[n2] : 1));
    c->soa = malloc(sizeof *c->soa * 6 * (c->base[n2] ? c->base[n2] : 1));
    if (!c->pixel || !c->soa) {
        free(c->pixel), c->pixel = NULL;
        return false;
    }
    for (int t = 0; t < tiles; t++) tile_pixels(c, gb, n, t, next);
    return true;
}

static bool same_epoch(const epoch *a, const epoch *b)
{
    return a->gb_serial == b->gb_serial && a->mr_generation == b->mr_generation &&
           a->width == b->width && a->height == b->height && a->n == b->n && a->g_max == b->g_max &&
           a->rel_bias == b->rel_bias && a->eps == b->eps && a->receivers == b->receivers;
}

static uint32_t hash_of(uint64_t stamp, uint32_t cap)
{
    return (uint32_t)((stamp * 0x9e3779b97f4a7c15ull) >> 32) & (cap - 1);
}

/* The slots shaded last frame, kept (the others give their columns to spare), and the hash of
 * them with room for `more` new ones. */
static bool keep_recent(iir_gv_columns *c, uint32_t more)
{
    if (c->columns > c->spare_cap) { /* every column may become spare */
        float **spare = realloc(c->spare, sizeof *spare * c->columns);
        if (!spare) return false;
        c->spare = spare, c->spare_cap = c->columns;
    }
    uint32_t kept = 0;
    for (uint32_t i = 0; i < c->num_slots; i++) {
        slot *s = &c->slots[i];
        if (s->last + 1 == c->frame) {
            c->slots[kept++] = *s;
        } else if (s->col) {
            c->spare[c->num_spare++] = s->col;
        }
    }
    c->num_slots = kept;
    uint32_t need = kept + more, cap = 16;
    while (cap < 2 * need) cap *= 2;
    if (need > c->slot_cap) {
        slot *grown = realloc(c->slots, sizeof *grown * need);
        if (!grown) return false;
        c->slots = grown, c->slot_cap = need;
    }
    if (cap != c->hash_cap) {
        free(c->hash);
        c->hash = malloc(sizeof *c->hash * cap);
        c->hash_cap = c->hash ? cap : 0;
        if (!c->hash) return false;
    }
    memset(c->hash, 0, sizeof *c->hash * c->hash_cap);
    for (uint32_t i = 0; i < c->num_slots; i++) {
        uint32_t h = hash_of(c->slots[i].stamp, c->hash_cap);
        while (c->hash[h]) h = (h + 1) & (c->hash_cap - 1);
        c->hash[h] = i + 1;
    }
    return true;
}

/* The slot of map stamp, or a new one (its hash entry added). */
static slot *find(iir_gv_columns *c, uint64_t stamp, bool *found)
{
    uint32_t h = hash_of(stamp, c->hash_cap);
    for (; c->hash[h]; h = (h + 1) & (c->hash_cap - 1))
        if (c->slots[c->hash[h] - 1].stamp == stamp) {
            *found = true;
            return &c->slots[c->hash[h] - 1];
        }
    *found = false;
    c->hash[h] = ++c->num_slots;
    slot *s = &c->slots[c->num_slots - 1];
    *s = (slot){.stamp = stamp};
    return s;
}

/* A column for s to write, within the budget (false when there is none). */
static bool take_column(iir_gv_columns *c, slot *s)
{
    if (s->col) return true;
    if (c->num_spare) {
        s->col = c->spare[--c->num_spare];
        return true;
    }
    if ((size_t)(c->columns + 1) * c->len * sizeof(float) > IIR_GV_BUDGET) return false;
    s->col = malloc(sizeof(float) * (c->len ? c->len : 1));
    if (s->col) c->columns++;
    return s->col != NULL;
}

static bool same_vpl(const slot *s, const iir_shade_vpl *v, uint32_t cls)
{
    return s->cls == cls && s->radius == v->radius && s->p.x == v->p.x && s->p.y == v->p.y &&
           s->p.z == v->p.z && s->n.x == v->n.x && s->n.y == v->n.y && s->n.z == v->n.z;
}

/* VPL v's use of its column this frame: read when it is ready; write when v was shaded last
 * frame as well, or is new to a set that keeps its VPLs (kept_last: iir's, not ir's), and a
 * column is to be had; else none. */
static iir_gv_ref assign(iir_gv_columns *c, const iir_shade_vpl *v, uint32_t cls)
{
    iir_gv_ref none = {NULL, IIR_GV_NONE};
    if (!v->smap->stamp || v->smap->res < 2) return none; /* the kernel's own rule for res 1 */
    bool found;
    slot *s = find(c, v->smap->stamp, &found);
    if (found && s->last == c->frame) { /* two VPLs of one map: neither is reused */
        s->ready = s->writing = false;
        return none;
    }
    bool known = found && same_vpl(s, v, cls);
    if (!known) s->ready = false;
    s->p = v->p, s->n = v->n, s->radius = v->radius, s->cls = cls, s->last = c->frame;
    s->writing = false;
    c->known += known;
    if (s->ready) return (iir_gv_ref){s->col, IIR_GV_READ};
    if (!(known || c->kept_last) || !take_column(c, s)) return none;
    s->writing = true;
    return (iir_gv_ref){s->col, IIR_GV_WRITE};
}

/* ord and len for multires's work items: item u's samples in the columns of every subset its
 * class unites (the other entries unused). */
static bool count_items(iir_gv_columns *c, const iir_multires *mr, int n)
{
    uint32_t n2 = (uint32_t)(n * n), total[IIR_MAX_SUBSETS] = {0};
    int items = iir_multires_items(mr);
    free(c->ord), free(c->pixel), free(c->glossy), free(c->soa);
    c->pixel = NULL, c->glossy = NULL, c->soa = NULL;
    c->ord = malloc(sizeof *c->ord * ((size_t)items * n2 + 1));
    if (!c->ord) return false;
    for (int u = 0; u < items; u++) {
        int m, count;
        uint32_t cls;
        iir_multires_item(mr, u, &m, &cls, &count);
        for (uint32_t k = 0; k < n2; k++) {
            bool united = k % (uint32_t)n % (uint32_t)m == cls % (uint32_t)m &&
                          k / (uint32_t)n % (uint32_t)m == cls / (uint32_t)m;
            c->ord[(size_t)u * n2 + k] = total[k];
            if (united) total[k] += (uint32_t)count;
        }
    }
    c->len = 0;
    for (uint32_t k = 0; k < n2; k++) c->len = total[k] > c->len ? total[k] : c->len;
    memcpy(c->total, total, sizeof total);
    return true;
}

/* The epoch of r's G-buffer (and hierarchy, mr not NULL) and the frame's constants; a new one
 * drops every column. */
static bool enter_epoch(iir_gv_columns *c, const iir_renderer *r, const iir_kernel_args *a, int n,
                        iir_receiver_bsdf receivers, const iir_multires *mr)
{
    epoch e = {r->gb_serial,
               mr ? iir_multires_generation(mr) : 0,
               r->gb.width,
               r->gb.height,
               n,
               a->g_max,
               a->rel_bias,
               a->eps,
               receivers};
    if (c->ord && same_epoch(&e, &c->at)) return true;
    drop_all(c);
    c->at = e;
    return mr ? count_items(c, mr, n) : count_pixels(c, &r->gb, n);
}

iir_gv_frame iir_gv_begin(iir_renderer *r, iir_gv_columns **cp, const iir_kernel_args *a, int n,
                          uint32_t shift, iir_receiver_bsdf receivers, const iir_multires *mr)
{
    iir_gv_frame none = {0};
    if (!*cp && !(*cp = calloc(1, sizeof **cp))) return none;
    iir_gv_columns *c = *cp;
    uint32_t n2 = (uint32_t)(n * n), used = r->start[r->num_subsets];
    c->frame++;
    if (!enter_epoch(c, r, a, n, receivers, mr) || !keep_recent(c, used)) {
        drop_all(c);
        free(c->ord), c->ord = NULL; /* a new epoch next time */
        return none;
    }
    if (used > c->ref_cap) {
        iir_gv_ref *grown = realloc(c->ref, sizeof *grown * used);
        if (!grown) return none;
        c->ref = grown, c->ref_cap = used;
    }
    c->known = 0;
    for (uint32_t k = 0; k < r->num_subsets; k++)
        for (uint32_t i = r->start[k]; i < r->start[k + 1]; i++)
            c->ref[i] = assign(c, &r->vpl[i], (k + n2 - shift % n2) % n2);
    c->kept_last = 2 * c->known >= used && used > 0;
    size_t plane = c->base[n2];
    return (iir_gv_frame){c->ref, c->ord, c->pixel, c->base, c->glossy, c->total, c->soa, plane};
}

void iir_gv_end(iir_gv_columns *c, bool complete)
{
    if (!c) return;
    for (uint32_t i = 0; i < c->num_slots; i++) {
        slot *s = &c->slots[i];
        if (s->writing) s->ready = complete;
        s->writing = false;
    }
}

/* render_filter_avx2.c -- the filter's row and column passes and its compose 8 pixels a step with
 * AVX2 (render_internal.h: iir_filter_lanes): the scalar passes of render_filter.c with every
 * tap's product and sum in the same order and without FMA (this file is built with -mavx2 alone),
 * so the image is the same bit for bit. The row pass writes its sums and weights as four planes
 * (x, y, z, w) where the scalar one writes iir_filter_row structs; multires's passes run only over
 * the groups of 8 pixels a level-0 pixel's column pass reads. Called only where the CPU has AVX2.
 */
#include "render_internal.h"

#if defined(__x86_64__)
#include <immintrin.h>
#include <string.h>

#include "render_lanes_avx2.h"

enum { CHUNK = 256 }; /* pixels of a row a step of the row pass converts to planes */

/* Lanes x .. x + 7 below `end`, as a mask for maskload/maskstore. */
static inline __m256i lanes_below(int x, int end)
{
    __m256i idx = _mm256_add_epi32(_mm256_set1_epi32(x), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    return _mm256_cmpgt_epi32(_mm256_set1_epi32(end), idx);
}

static inline float end_weight(const iir_filter_lanes *f, int d)
{
    return d == -f->h || d == f->h ? f->end_weight : 1.f;
}

/* A pass's taps along one row or column, the same for each of its groups of 8 centres -- their
 * similarity bits and weights (and the column pass's rows of planes) set once a row, not per tap
 * of each group (the ring's row index was an integer division per tap). */
typedef struct taps {
    int count;
    __m256i bit[2 * IIR_FILTER_MAX_H + 1];
    __m256 w[2 * IIR_FILTER_MAX_H + 1];
    const float *row[2 * IIR_FILTER_MAX_H + 1]; /* column pass: the planes' row of each tap */
} taps;

static void set_tap(taps *t, int bit, float w)
{
    t->bit[t->count] = _mm256_set1_epi32((int)(1u << bit));
    t->w[t->count++] = _mm256_set1_ps(w);
}

/* The row pass's taps d = -h .. h. */
static taps row_taps(const iir_filter_lanes *f)
{
    taps t = {0};
    for (int d = -f->h; d <= f->h; d++) set_tap(&t, IIR_FILTER_MAX_H + d, end_weight(f, d));
    return t;
}

/* The column pass's taps at row y: those of d = -h .. h inside the image. */
static taps column_taps(const iir_filter_lanes *f, int y)
{
    taps t = {0};
    for (int d = -f->h; d <= f->h; d++) {
        if (y + d < 0 || y + d >= f->height) continue;
        t.row[t.count] = f->planes + (size_t)((y + d) % f->ring) * (size_t)f->width;
        set_tap(&t, IIR_FILTER_COLUMN + IIR_FILTER_MAX_H + d, end_weight(f, d));
    }
    return t;
}

/* Tap i's weight at 8 centres: its weight where its bit of their masks is set, else 0. */
static inline __m256 tap_weights(const taps *t, int i, __m256i masks)
{
    __m256i similar = _mm256_cmpeq_epi32(_mm256_and_si256(masks, t->bit[i]), t->bit[i]);
    return _mm256_and_ps(_mm256_castsi256_ps(similar), t->w[i]);
}

/* Pixels ahead that the row pass asks for (raw light and masks, through the row's end into the
 * next): the loads of both were its top waits (at 1024x768 the pass ~10% faster with this). */
enum { AHEAD = 128 };

/* The lines of pixels i .. i + 15 of raw and of the masks, asked for now. */
IIR_PREFETCH_FN ask_ahead(const iir_filter_lanes *f, size_t i)
{
    for (int b = 0; b < 3; b++) _mm_prefetch((const char *)(f->raw + i) + 64 * b, _MM_HINT_T0);
    _mm_prefetch((const char *)(f->mask + i), _MM_HINT_T0);
}

/* The tap flag of pixel xx of a row (subset sx = xx mod n): its subset has VPLs (pattern[sx],
 * pattern[j] = live[j % n]), or multires: the pixel is coarse (level[xx] > 0). */
static inline float flag1(const float *pattern, int sx, const uint8_t *level, int xx)
{
    return pattern[sx] != 0.f || (level && level[xx] > 0) ? 1.f : 0.f;
}

/* flag1 at 8 pixels from xx. */
static inline __m256 flags8(const float *pattern, int sx, const uint8_t *level, int xx)
{
    __m256 live = _mm256_loadu_ps(pattern + sx);
    if (!level) return live;
    uint64_t bytes;
    memcpy(&bytes, level + xx, sizeof bytes);
    __m256i lv = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128((long long)bytes));
    __m256 coarse = _mm256_castsi256_ps(_mm256_cmpgt_epi32(lv, _mm256_setzero_si256()));
    return _mm256_or_ps(live, _mm256_and_ps(coarse, _mm256_set1_ps(1.f)));
}

/* Row y's raw light and tap flags (its subset has VPLs, or multires: the pixel is coarse) over
 * [x0 - h, x0 + len + h + 8), zero beyond the image: the taps of the groups of 8 centres from x0
 * to below x0 + len. Inside the image 8 pixels a step (their xyz split into planes). */
static void chunk_planes(const iir_filter_lanes *f, int y, int x0, int len, float *R, float *G,
                         float *B, float *L)
{
    const iir_vec3 *raw = f->raw + (size_t)y * (size_t)f->width;
    const int *live = f->live + (y % f->n) * f->n;
    float pattern[IIR_MAX_INTERLEAVE + 8];
    for (int j = 0; j < f->n + 8; j++) pattern[j] = live[j % f->n] ? 1.f : 0.f;
    int xx = x0 - f->h, end = len + 2 * f->h + 8, k = 0;
    for (; k < end && xx < 0; k++, xx++) R[k] = G[k] = B[k] = L[k] = 0.f;
    const uint8_t *level = f->level ? f->level + (size_t)y * (size_t)f->width : NULL;
    size_t at = (size_t)y * (size_t)f->width, last = (size_t)f->width * (size_t)f->height;
    int sx = xx % f->n;
    for (; k + 8 <= end && xx + 8 <= f->width; k += 8, xx += 8, sx = (sx + 8) % f->n) {
        bool ask = !(xx & 8) && at + (size_t)(xx + AHEAD) < last; /* every 16 pixels */
        if (ask) ask_ahead(f, at + (size_t)(xx + AHEAD));
        v3 v = load_aos(raw + xx, raw + xx + 4);
        _mm256_storeu_ps(R + k, v.x), _mm256_storeu_ps(G + k, v.y), _mm256_storeu_ps(B + k, v.z);
        _mm256_storeu_ps(L + k, flags8(pattern, sx, level, xx));
    }
    for (; k < end && xx < f->width; k++, xx++, sx = sx + 1 == f->n ? 0 : sx + 1) {
        R[k] = raw[xx].x, G[k] = raw[xx].y, B[k] = raw[xx].z;
        L[k] = flag1(pattern, sx, level, xx);
    }
    for (; k < end; k++) R[k] = G[k] = B[k] = L[k] = 0.f;
}

/* Lanes `in` of v stored at p (load_*: loaded from p); `all`: the 8 lanes, with a plain store or
 * load (the masked moves are slow). */
static inline void store_lanes(float *p, __m256i in, bool all, __m256 v)
{
    if (all)
        _mm256_storeu_ps(p, v);
    else
        _mm256_maskstore_ps(p, in, v);
}

static inline __m256i load_masks(const uint32_t *p, __m256i in, bool all)
{
    return all ? _mm256_loadu_si256((const __m256i *)p) : _mm256_maskload_epi32((const int *)p, in);
}

static inline __m256 load_lanes(const float *p, __m256i in, bool all)
{
    return all ? _mm256_loadu_ps(p) : _mm256_maskload_ps(p, in);
}

/* Multires: whether a column pass reads the row pass at pixels x .. x + 7 of row y (those below
 * the width): a level-0 pixel among them within h rows. Always with full shading. */
static bool group_read(const iir_filter_lanes *f, int y, int x)
{
    if (!f->level) return true;
    int n = x + 8 <= f->width ? 8 : f->width - x;
    int y0 = y - f->h > 0 ? y - f->h : 0, y1 = y + f->h < f->height ? y + f->h : f->height - 1;
    for (int yy = y0; yy <= y1; yy++)
        if (iir_filter_any_fine(f->level + (size_t)yy * (size_t)f->width + (size_t)x, n))
            return true;
    return false;
}

void iir_filter_rows_avx2(const iir_filter_lanes *f, int y)
{
    _Alignas(32) float R[CHUNK + 2 * IIR_FILTER_MAX_H + 8], G[sizeof R / sizeof *R],
        B[sizeof R / sizeof *R], L[sizeof R / sizeof *R];
    size_t plane = (size_t)f->width * (size_t)f->ring, row = (size_t)y * (size_t)f->width;
    size_t slot = (size_t)(y % f->ring) * (size_t)f->width;
    const taps t = row_taps(f);
    for (int c0 = 0; c0 < f->width; c0 += CHUNK) {
        int c1 = c0 + CHUNK < f->width ? c0 + CHUNK : f->width;
        uint32_t read = 0; /* the chunk's groups of 8 a column pass reads */
        for (int x = c0; x < c1; x += 8) read |= (uint32_t)group_read(f, y, x) << ((x - c0) / 8);
        if (!read) continue;
        int x0 = c0 + 8 * __builtin_ctz(read), x1 = c0 + 8 * (32 - __builtin_clz(read));
        x1 = x1 < c1 ? x1 : c1;
        chunk_planes(f, y, x0, x1 - x0, R, G, B, L);
        for (int x = x0; x < x1; x += 8) {
            if (!((read >> ((x - c0) / 8)) & 1)) continue;
            __m256i in = lanes_below(x, f->width);
            bool all = x + 8 <= f->width;
            __m256i masks = load_masks(f->mask + row + (size_t)x, in, all);
            __m256 r = zero(), g = zero(), b = zero(), w = zero();
            bool background = _mm256_testz_si256(masks, masks); /* no tap: zeros */
            for (int i = 0; i < t.count && !background; i++) {
                int k = x - x0 + i; /* tap i's offset in the chunk's planes */
                __m256 wt =
                    _mm256_and_ps(tap_weights(&t, i, masks),
                                  _mm256_cmp_ps(_mm256_loadu_ps(L + k), zero(), _CMP_NEQ_OQ));
                r = _mm256_add_ps(r, _mm256_mul_ps(_mm256_loadu_ps(R + k), wt));
                g = _mm256_add_ps(g, _mm256_mul_ps(_mm256_loadu_ps(G + k), wt));
                b = _mm256_add_ps(b, _mm256_mul_ps(_mm256_loadu_ps(B + k), wt));
                w = _mm256_add_ps(w, wt);
            }
            float *out = f->planes + slot + (size_t)x;
            store_lanes(out, in, all, r);
            store_lanes(out + plane, in, all, g);
            store_lanes(out + 2 * plane, in, all, b);
            store_lanes(out + 3 * plane, in, all, w);
        }
    }
}

/* The column pass at pixels x .. x + 7, their similarity masks and taps t (lanes `in`; `all`: the
 * 8 of them): E. */
static v3 column8(const iir_filter_lanes *f, const taps *t, int x, __m256i masks, __m256i in,
                  bool all)
{
    size_t plane = (size_t)f->width * (size_t)f->ring;
    __m256 r = zero(), g = zero(), b = zero(), w = zero();
    for (int i = 0; i < t->count; i++) {
        __m256 wt = tap_weights(t, i, masks);
        const float *p = t->row[i] + (size_t)x;
        r = _mm256_add_ps(r, _mm256_mul_ps(load_lanes(p, in, all), wt));
        g = _mm256_add_ps(g, _mm256_mul_ps(load_lanes(p + plane, in, all), wt));
        b = _mm256_add_ps(b, _mm256_mul_ps(load_lanes(p + 2 * plane, in, all), wt));
        w = _mm256_add_ps(w, _mm256_mul_ps(wt, load_lanes(p + 3 * plane, in, all)));
    }
    __m256 any = _mm256_cmp_ps(w, zero(), _CMP_GT_OQ);
    __m256 inv = _mm256_and_ps(any, _mm256_div_ps(_mm256_set1_ps(1.f), w));
    return scale3((v3){r, g, b}, inv);
}

void iir_filter_columns_avx2(const iir_filter_lanes *f, int y, int x0, int x1, iir_vec3 *E)
{
    const taps t = column_taps(f, y);
    for (int x = x0; x < x1; x += 8) {
        _Alignas(32) float ex[8], ey[8], ez[8];
        __m256i in = lanes_below(x, x1);
        bool all = x + 8 <= x1;
        __m256i masks = load_masks(f->mask + (size_t)y * (size_t)f->width + (size_t)x, in, all);
        v3 e = column8(f, &t, x, masks, in, all);
        _mm256_store_ps(ex, e.x), _mm256_store_ps(ey, e.y), _mm256_store_ps(ez, e.z);
        for (int l = 0; l < 8 && x + l < x1; l++) E[x + l - x0] = iir_v3(ex[l], ey[l], ez[l]);
    }
}

/* out += albedo / pi * e at the 8 pixels from i on (row pointer L), those with geometry. */
static inline void compose8(const iir_gbuffer *gb, size_t i, iir_vec3 *L, v3 e)
{
    __m256 hit = hit_lanes(gb->prim + i);
    v3 k = scale3(load_aos(gb->albedo + i, gb->albedo + i + 4), _mm256_set1_ps(IIR_INV_PI));
    v3 l = load_aos(L, L + 4);
    store_aos(blend3(l, add3(l, mul3(k, e)), hit), L, L + 4);
}

/* compose8's sum at pixel x of row y alone. */
static inline void compose1(const iir_gbuffer *gb, int y, int x, iir_image *out, iir_vec3 E)
{
    size_t i = (size_t)y * (size_t)gb->width + (size_t)x;
    iir_vec3 *L = iir_image_at(out, x, y);
    if (gb->prim[i] != IIR_NO_HIT) iir_compose_add(L, gb->albedo[i], E);
}

void iir_filter_compose_avx2(const iir_filter_lanes *f, const iir_gbuffer *gb, int y,
                             iir_image *out)
{
    size_t row = (size_t)y * (size_t)f->width;
    const taps t = column_taps(f, y);
    int x = 0;
    for (; x + 8 <= f->width; x += 8) {
        __m256i masks = _mm256_loadu_si256((const __m256i *)(f->mask + row + (size_t)x));
        if (_mm256_testz_si256(masks, masks)) continue; /* background: nothing to add */
        compose8(gb, row + (size_t)x, iir_image_at(out, x, y),
                 column8(f, &t, x, masks, _mm256_set1_epi32(-1), true));
    }
    if (x == f->width) return;
    iir_vec3 E[8];
    iir_filter_columns_avx2(f, y, x, f->width, E);
    for (int x0 = x; x < f->width; x++) compose1(gb, y, x, out, E[x - x0]);
}

void iir_compose_span_avx2(const iir_gbuffer *gb, int y, int x0, int x1, const iir_vec3 *E,
                           iir_image *out)
{
    size_t row = (size_t)y * (size_t)gb->width;
    int x = x0;
    for (; x + 8 <= x1; x += 8)
        compose8(gb, row + (size_t)x, iir_image_at(out, x, y),
                 load_aos(E + (x - x0), E + (x - x0) + 4));
    for (; x < x1; x++) compose1(gb, y, x, out, E[x - x0]);
}

#endif

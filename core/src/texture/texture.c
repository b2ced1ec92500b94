/* texture.c -- a texture's storage, its mip chain and every lookup (texel, bilinear, trilinear),
 * glTF samplers and KHR_texture_transform; not reading files (texture_decode.c). */
#include "iir/texture.h"
#include "iir/hash.h"
#include "texture_internal.h"

#include <assert.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Levels of a IIR_TEXTURE_MAX_DIM texture: log2(16384) + 1. */
#define IIR_TEX_MAX_LEVELS 15

typedef struct iir_tex_level {
    int width, height;
    size_t first; /* index of the level's first texel in the chain */
} iir_tex_level;

struct iir_texture {
    iir_tex_format format;
    bool srgb;      /* IIR_TEX_RGBA8 colour codes are sRGB-encoded */
    bool has_alpha; /* some texel of level 0 has alpha < 1 */
    int levels;
    iir_tex_level level[IIR_TEX_MAX_LEVELS];
    size_t texel_bytes; /* of the whole chain */
    void *texels;       /* every level, level 0 first, each row-major, top row first */
    float colour8[256]; /* IIR_TEX_RGBA8 colour code -> linear (sRGB EOTF or code / 255) */
    float unorm8[256];  /* IIR_TEX_RGBA8 alpha code -> code / 255 */
};

static size_t format_size(iir_tex_format fmt)
{
    switch (fmt) {
    case IIR_TEX_RGBA8:
        return 4;
    case IIR_TEX_RGBA16:
        return 8;
    case IIR_TEX_RGBA32F:
        return 16;
    }
    assert(!"unknown texture format");
    return 16;
}

static const char *format_name(iir_tex_format fmt)
{
    switch (fmt) {
    case IIR_TEX_RGBA8:
        return "RGBA8";
    case IIR_TEX_RGBA16:
        return "RGBA16";
    case IIR_TEX_RGBA32F:
        return "RGBA32F";
    }
    return "?";
}

double iir_srgb_eotf(double e)
{
    return e <= 0.04045 ? e / 12.92 : pow((e + 0.055) / 1.055, 2.4);
}

/* ======================== creation ======================== */

iir_texture *iir_texture_alloc(int width, int height, iir_tex_format fmt, bool srgb)
{
    if (width < 1 || width > IIR_TEXTURE_MAX_DIM || height < 1 || height > IIR_TEXTURE_MAX_DIM)
        return NULL;
    iir_texture *t = calloc(1, sizeof *t);
    if (!t) return NULL;
    t->format = fmt;
    t->srgb = srgb && fmt == IIR_TEX_RGBA8;
    size_t count = 0;
    int w = width, h = height;
    for (;;) {
        assert(t->levels < IIR_TEX_MAX_LEVELS);
        t->level[t->levels++] = (iir_tex_level){w, h, count};
        count += (size_t)w * (size_t)h;
        if (w == 1 && h == 1) break;
        w = w > 1 ? w / 2 : 1;
        h = h > 1 ? h / 2 : 1;
    }
    t->texel_bytes = count * format_size(fmt);
    t->texels = malloc(t->texel_bytes);
    if (!t->texels) {
        free(t);
        return NULL;
    }
    for (int c = 0; c < 256; c++) {
        t->unorm8[c] = (float)(c / 255.0);
        t->colour8[c] = t->srgb ? (float)iir_srgb_eotf(c / 255.0) : t->unorm8[c];
    }
    return t;
}

void *iir_texture_level0(iir_texture *t)
{
    return t->texels;
}

void iir_texture_destroy(iir_texture *t)
{
    if (!t) return;
    free(t->texels);
    free(t);
}

iir_texture *iir_texture_from_rgba8(int width, int height, const uint8_t *rgba, bool srgb)
{
    iir_texture *t = iir_texture_alloc(width, height, IIR_TEX_RGBA8, srgb);
    if (!t) return NULL;
    memcpy(t->texels, rgba, (size_t)width * (size_t)height * 4);
    iir_texture_finish(t);
    return t;
}

/* ======================== storage: one texel in, one texel out ======================== */

/* Texel x, y of level l, decoded to linear. */
static inline iir_rgba fetch(const iir_texture *t, const iir_tex_level *l, int x, int y)
{
    size_t i = l->first + (size_t)y * (size_t)l->width + (size_t)x;
    switch (t->format) {
    case IIR_TEX_RGBA8: {
        const uint8_t *p = (const uint8_t *)t->texels + 4 * i;
        return (iir_rgba){t->colour8[p[0]], t->colour8[p[1]], t->colour8[p[2]], t->unorm8[p[3]]};
    }
    case IIR_TEX_RGBA16: {
        const uint16_t *p = (const uint16_t *)t->texels + 4 * i;
        const float k = 1.f / 65535.f;
        return (iir_rgba){p[0] * k, p[1] * k, p[2] * k, p[3] * k};
    }
    case IIR_TEX_RGBA32F: {
        const float *p = (const float *)t->texels + 4 * i;
        return (iir_rgba){p[0], p[1], p[2], p[3]};
    }
    }
    return (iir_rgba){0.f, 0.f, 0.f, 1.f};
}

/* The 8-bit sRGB code boundaries: code k (1..255) starts at linear bound[k] = EOTF((k - 0.5) /
 * 255), so a value's code, round(255 OETF(v)), is the number of bounds at or below it. */
typedef struct srgb8_bounds {
    double bound[256]; /* bound[0] unused */
} srgb8_bounds;

static void srgb8_bounds_init(srgb8_bounds *b)
{
    b->bound[0] = -INFINITY;
    for (int k = 1; k < 256; k++) b->bound[k] = iir_srgb_eotf((k - 0.5) / 255.0);
}

static uint8_t srgb8_encode(const srgb8_bounds *b, float v)
{
    int code = 0;
    for (int step = 128; step > 0; step >>= 1)
        if (code + step < 256 && (double)v >= b->bound[code + step]) code += step;
    return (uint8_t)code;
}

static uint8_t unorm8_encode(float v)
{
    return (uint8_t)(iir_clampf(v, 0.f, 1.f) * 255.f + 0.5f);
}

static uint16_t unorm16_encode(float v)
{
    return (uint16_t)(iir_clampf(v, 0.f, 1.f) * 65535.f + 0.5f);
}

/* Writes linear c as texel x, y of level l in the storage format. */
static void store(iir_texture *t, const srgb8_bounds *b, const iir_tex_level *l, int x, int y,
                  iir_rgba c)
{
    size_t i = l->first + (size_t)y * (size_t)l->width + (size_t)x;
    switch (t->format) {
    case IIR_TEX_RGBA8: {
        uint8_t *p = (uint8_t *)t->texels + 4 * i;
        if (t->srgb) {
            p[0] = srgb8_encode(b, c.r);
            p[1] = srgb8_encode(b, c.g);
            p[2] = srgb8_encode(b, c.b);
        } else {
            p[0] = unorm8_encode(c.r);
            p[1] = unorm8_encode(c.g);
            p[2] = unorm8_encode(c.b);
        }
        p[3] = unorm8_encode(c.a);
        return;
    }
    case IIR_TEX_RGBA16: {
        uint16_t *p = (uint16_t *)t->texels + 4 * i;
        p[0] = unorm16_encode(c.r);
        p[1] = unorm16_encode(c.g);
        p[2] = unorm16_encode(c.b);
        p[3] = unorm16_encode(c.a);
        return;
    }
    case IIR_TEX_RGBA32F: {
        float *p = (float *)t->texels + 4 * i;
        p[0] = c.r;
        p[1] = c.g;
        p[2] = c.b;
        p[3] = c.a;
        return;
    }
    }
}

/* ======================== the mip chain ======================== */

/* The box filter along one axis from n_src texels to n_dst: destination texel i covers source
 * [i n_src / n_dst, (i + 1) n_src / n_dst), and each source texel it touches weighs its overlap.
 * Counted in units of 1 / n_dst so the weights are exact ratios of integers. At most 3 taps
 * (n_src = 2 n_dst or 2 n_dst + 1, or both 1). Returns the number of taps. */
static int box_taps(int n_src, int n_dst, int i, int idx[3], float w[3])
{
    long long lo = (long long)i * n_src, hi = lo + n_src;
    int n = 0;
    for (int s = (int)(lo / n_dst); s < n_src && (long long)s * n_dst < hi; s++) {
        long long a = (long long)s * n_dst, b = a + n_dst;
        long long overlap = (b < hi ? b : hi) - (a > lo ? a : lo);
        if (overlap <= 0) continue;
        assert(n < 3);
        idx[n] = s;
        w[n] = (float)((double)overlap / (double)n_src);
        n++;
    }
    return n;
}

/* Level k + 1 from level k, in linear values. */
static void build_level(iir_texture *t, const srgb8_bounds *b, int k)
{
    const iir_tex_level *src = &t->level[k], *dst = &t->level[k + 1];
    for (int y = 0; y < dst->height; y++) {
        int iy[3], ix[3];
        float wy[3], wx[3];
        int ny = box_taps(src->height, dst->height, y, iy, wy);
        for (int x = 0; x < dst->width; x++) {
            int nx = box_taps(src->width, dst->width, x, ix, wx);
            iir_rgba c = {0.f, 0.f, 0.f, 0.f};
            for (int j = 0; j < ny; j++) {
                for (int i = 0; i < nx; i++) {
                    iir_rgba s = fetch(t, src, ix[i], iy[j]);
                    float w = wx[i] * wy[j];
                    c.r += w * s.r;
                    c.g += w * s.g;
                    c.b += w * s.b;
                    c.a += w * s.a;
                }
            }
            store(t, b, dst, x, y, c);
        }
    }
}

static bool level0_has_alpha(const iir_texture *t)
{
    const iir_tex_level *l = &t->level[0];
    for (int y = 0; y < l->height; y++)
        for (int x = 0; x < l->width; x++)
            if (fetch(t, l, x, y).a < 1.f) return true;
    return false;
}

void iir_texture_finish(iir_texture *t)
{
    srgb8_bounds b;
    srgb8_bounds_init(&b);
    for (int k = 0; k + 1 < t->levels; k++) build_level(t, &b, k);
    t->has_alpha = level0_has_alpha(t);
}

/* ======================== introspection ======================== */

int iir_texture_width(const iir_texture *t)
{
    return t->level[0].width;
}

int iir_texture_height(const iir_texture *t)
{
    return t->level[0].height;
}

int iir_texture_levels(const iir_texture *t)
{
    return t->levels;
}

static int clamp_level(const iir_texture *t, int level)
{
    return level < 0 ? 0 : (level >= t->levels ? t->levels - 1 : level);
}

int iir_texture_level_width(const iir_texture *t, int level)
{
    return t->level[clamp_level(t, level)].width;
}

int iir_texture_level_height(const iir_texture *t, int level)
{
    return t->level[clamp_level(t, level)].height;
}

size_t iir_texture_bytes(const iir_texture *t)
{
    return sizeof *t + t->texel_bytes;
}

bool iir_texture_has_alpha(const iir_texture *t)
{
    return t->has_alpha;
}

void iir_texture_describe(const iir_texture *t, char *buf, size_t cap)
{
    snprintf(buf, cap, "%dx%d %s %s, %d levels, %zu bytes%s", t->level[0].width, t->level[0].height,
             format_name(t->format), t->format == IIR_TEX_RGBA8 && t->srgb ? "sRGB" : "linear",
             t->levels, iir_texture_bytes(t), t->has_alpha ? ", alpha" : "");
}

/* ======================== samplers and transforms ======================== */

static iir_wrap gltf_wrap(int mode)
{
    switch (mode) {
    case 33071:
        return IIR_WRAP_CLAMP;
    case 33648:
        return IIR_WRAP_MIRROR;
    default:
        return IIR_WRAP_REPEAT;
    }
}

iir_tex_sampler iir_tex_sampler_from_gltf(int mag_filter, int min_filter, int wrap_s, int wrap_t)
{
    iir_tex_sampler s = {.wrap_s = gltf_wrap(wrap_s), .wrap_t = gltf_wrap(wrap_t)};
    s.mag_nearest = mag_filter == 9728;
    s.min_no_mip = min_filter == 9728 || min_filter == 9729;
    s.min_nearest = min_filter == 9728 || min_filter == 9984 || min_filter == 9986;
    return s;
}

iir_tex_transform iir_tex_transform_identity(void)
{
    return (iir_tex_transform){{0.f, 0.f}, 0.f, {1.f, 1.f}};
}

iir_vec2 iir_tex_transform_apply(const iir_tex_transform *t, iir_vec2 uv)
{
    float c = cosf(t->rotation), s = sinf(t->rotation);
    float x = t->scale.x * uv.x, y = t->scale.y * uv.y;
    return iir_v2(c * x + s * y + t->offset.x, -s * x + c * y + t->offset.y);
}

float iir_tex_transform_width(const iir_tex_transform *t, float width)
{
    return width * fmaxf(fabsf(t->scale.x), fabsf(t->scale.y));
}

/* ======================== lookups ======================== */

static const iir_tex_sampler default_sampler;

/* A coordinate brought into one period of its wrap mode ([0,1] repeat and clamp, [0,2] mirror),
 * where its texel indices fit an int; a non-finite one is 0. Indices are wrapped after. */
static float reduce(float u, iir_wrap w)
{
    if (!isfinite(u)) return 0.f;
    switch (w) {
    case IIR_WRAP_CLAMP:
        return iir_clampf(u, 0.f, 1.f);
    case IIR_WRAP_MIRROR:
        return u - 2.f * floorf(0.5f * u);
    default:
        return u - floorf(u);
    }
}

/* Texel index i of a level n texels wide under wrap mode w (OpenGL's rules). */
static int wrap_index(int i, int n, iir_wrap w)
{
    switch (w) {
    case IIR_WRAP_CLAMP:
        return i < 0 ? 0 : (i >= n ? n - 1 : i);
    case IIR_WRAP_MIRROR: {
        int p = 2 * n;
        i %= p;
        if (i < 0) i += p;
        return i < n ? i : p - 1 - i;
    }
    default:
        i %= n;
        return i < 0 ? i + n : i;
    }
}

static iir_rgba lerp(iir_rgba a, iir_rgba b, float f)
{
    return (iir_rgba){a.r + f * (b.r - a.r), a.g + f * (b.g - a.g), a.b + f * (b.b - a.b),
                      a.a + f * (b.a - a.a)};
}

static iir_rgba nearest_at(const iir_texture *t, const iir_tex_sampler *s, iir_vec2 uv, int level)
{
    const iir_tex_level *l = &t->level[level];
    int x = (int)floorf(reduce(uv.x, s->wrap_s) * (float)l->width);
    int y = (int)floorf(reduce(uv.y, s->wrap_t) * (float)l->height);
    return fetch(t, l, wrap_index(x, l->width, s->wrap_s), wrap_index(y, l->height, s->wrap_t));
}

static iir_rgba bilinear_at(const iir_texture *t, const iir_tex_sampler *s, iir_vec2 uv, int level)
{
    const iir_tex_level *l = &t->level[level];
    float u = reduce(uv.x, s->wrap_s) * (float)l->width - 0.5f;
    float v = reduce(uv.y, s->wrap_t) * (float)l->height - 0.5f;
    float u0 = floorf(u), v0 = floorf(v);
    float fu = u - u0, fv = v - v0;
    int x0 = wrap_index((int)u0, l->width, s->wrap_s);
    int x1 = wrap_index((int)u0 + 1, l->width, s->wrap_s);
    int y0 = wrap_index((int)v0, l->height, s->wrap_t);
    int y1 = wrap_index((int)v0 + 1, l->height, s->wrap_t);
    iir_rgba top = lerp(fetch(t, l, x0, y0), fetch(t, l, x1, y0), fu);
    iir_rgba bottom = lerp(fetch(t, l, x0, y1), fetch(t, l, x1, y1), fu);
    return lerp(top, bottom, fv);
}

static iir_rgba filter_at(const iir_texture *t, const iir_tex_sampler *s, iir_vec2 uv, int level,
                          bool nearest)
{
    return nearest ? nearest_at(t, s, uv, level) : bilinear_at(t, s, uv, level);
}

iir_rgba iir_texture_texel(const iir_texture *t, int level, int x, int y)
{
    assert(level >= 0 && level < t->levels);
    const iir_tex_level *l = &t->level[level];
    assert(x >= 0 && x < l->width && y >= 0 && y < l->height);
    return fetch(t, l, x, y);
}

iir_rgba iir_texture_bilinear(const iir_texture *t, const iir_tex_sampler *s, iir_vec2 uv,
                              int level)
{
    if (!s) s = &default_sampler;
    return filter_at(t, s, uv, clamp_level(t, level), s->mag_nearest);
}

/* log2 of the footprint in texels of level 0, unclamped; -inf for width <= 0 or NaN. */
static float raw_lod(const iir_texture *t, float width)
{
    if (!(width > 0.f)) return -INFINITY;
    int n = t->level[0].width > t->level[0].height ? t->level[0].width : t->level[0].height;
    return log2f(width * (float)n);
}

float iir_texture_lod(const iir_texture *t, float width)
{
    float lambda = raw_lod(t, width);
    return lambda > 0.f ? fminf(lambda, (float)(t->levels - 1)) : 0.f;
}

iir_rgba iir_texture_sample(const iir_texture *t, const iir_tex_sampler *s, iir_vec2 uv,
                            float width)
{
    if (!s) s = &default_sampler;
    float lambda = raw_lod(t, width);
    if (!(lambda > 0.f)) return filter_at(t, s, uv, 0, s->mag_nearest);
    if (s->min_no_mip) return filter_at(t, s, uv, 0, s->min_nearest);
    lambda = fminf(lambda, (float)(t->levels - 1));
    int l0 = (int)lambda;
    float f = lambda - (float)l0;
    iir_rgba c0 = filter_at(t, s, uv, l0, s->min_nearest);
    if (f <= 0.f || l0 + 1 >= t->levels) return c0;
    return lerp(c0, filter_at(t, s, uv, l0 + 1, s->min_nearest), f);
}

uint64_t iir_texture_hash(uint64_t h, const iir_texture *t)
{
    int w = iir_texture_width(t), ht = iir_texture_height(t);
    h = IIR_HASH(h, w);
    h = IIR_HASH(h, ht);
    for (int y = 0; y < ht; y++)
        for (int x = 0; x < w; x++) {
            iir_rgba c = iir_texture_texel(t, 0, x, y);
            h = IIR_HASH(h, c);
        }
    return h;
}

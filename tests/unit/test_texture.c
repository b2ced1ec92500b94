/* test_texture.c -- textures: sRGB and data decoding, wrap modes, bilinear and trilinear lookups,
 * the mip chain, KHR_texture_transform, PNG / JPEG / EXR decoding and bad input; not materials. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <turbojpeg.h>
#include <unistd.h>

#include "iir/image.h"
#include "iir/texture.h"

/* ---- helpers -------------------------------------------------------------------------------- */

/* The sRGB EOTF of an 8-bit code, in double: what every decode is checked against. */
static double eotf8(int code)
{
    double c = code / 255.0;
    return c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
}

static void assert_near(double got, double want, double tol, const char *what)
{
    if (!(fabs(got - want) <= tol))
        fail_msg("%s: got %.9g, want %.9g (tol %g)", what, got, want, tol);
}

/* Relative 1e-6 (absolute for 0). */
static void assert_rel(double got, double want, const char *what)
{
    assert_near(got, want, want == 0.0 ? 1e-12 : 1e-6 * fabs(want), what);
}

static void assert_rgba(iir_rgba got, iir_rgba want, double tol, const char *what)
{
    if (!(fabs(got.r - want.r) <= tol && fabs(got.g - want.g) <= tol &&
          fabs(got.b - want.b) <= tol && fabs(got.a - want.a) <= tol))
        fail_msg("%s: got (%.7g %.7g %.7g %.7g), want (%.7g %.7g %.7g %.7g)", what, got.r, got.g,
                 got.b, got.a, want.r, want.g, want.b, want.a);
}

static iir_rgba mix(iir_rgba a, iir_rgba b, float f)
{
    return (iir_rgba){a.r + f * (b.r - a.r), a.g + f * (b.g - a.g), a.b + f * (b.b - a.b),
                      a.a + f * (b.a - a.a)};
}

static iir_texture *make(int w, int h, const uint8_t *rgba, bool srgb)
{
    iir_texture *t = iir_texture_from_rgba8(w, h, rgba, srgb);
    assert_non_null(t);
    return t;
}

/* A 4x2 data texture whose texels all differ: r = (10 + 30 x + 120 y) / 255, g = 1 - r,
 * b = (x + 4 y) / 255, a = 1. */
static iir_texture *make_4x2(void)
{
    uint8_t px[4 * 2 * 4];
    for (int y = 0; y < 2; y++) {
        for (int x = 0; x < 4; x++) {
            uint8_t *p = &px[4 * (y * 4 + x)];
            p[0] = (uint8_t)(10 + 30 * x + 120 * y);
            p[1] = (uint8_t)(255 - p[0]);
            p[2] = (uint8_t)(x + 4 * y);
            p[3] = 255;
        }
    }
    return make(4, 2, px, false);
}

/* Texel (x, y) of make_4x2's texture, by the formula. */
static iir_rgba texel_4x2(int x, int y)
{
    float r = (float)(10 + 30 * x + 120 * y) / 255.f;
    return (iir_rgba){r, (float)(255 - (10 + 30 * x + 120 * y)) / 255.f, (float)(x + 4 * y) / 255.f,
                      1.f};
}

static iir_rgba avg(iir_rgba a, iir_rgba b)
{
    return mix(a, b, 0.5f);
}

/* Checks a failed call: the status, a NULL texture, a message naming what. */
static void assert_failed(iir_status st, iir_texture *t, const iir_error *err, iir_status want,
                          const char *what)
{
    if (st == IIR_OK) fail_msg("expected an error for %s", what);
    if (st != want) fail_msg("%s: status %d, want %d (%s)", what, (int)st, (int)want, err->msg);
    assert_int_equal(err->status, want);
    assert_null(t);
    if (!strstr(err->msg, what)) fail_msg("message \"%s\" does not name %s", err->msg, what);
}

/* ---- encoding test files in memory ---------------------------------------------------------- */

typedef struct membuf {
    uint8_t *data;
    size_t size, cap;
} membuf;

static void membuf_put(membuf *m, const void *d, size_t n)
{
    if (m->size + n > m->cap) {
        m->cap = (m->size + n) * 2;
        m->data = realloc(m->data, m->cap);
        assert_non_null(m->data);
    }
    memcpy(m->data + m->size, d, n);
    m->size += n;
}

static void png_put(png_structp png, png_bytep d, size_t n)
{
    membuf_put(png_get_io_ptr(png), d, n);
}

static void png_flush_nothing(png_structp png)
{
    (void)png;
}

typedef struct png_spec {
    int w, h, type, depth;
    bool interlace;
    const png_color *palette;
    int npalette;
    const png_byte *trns; /* palette alpha (ntrns entries) */
    int ntrns;
    const png_color_16 *trns_colour; /* grey / RGB transparent colour */
    double gamma;                    /* a gAMA chunk when > 0 */
} png_spec;

/* A PNG of s with the packed rows in pixels (each row ceil(w * channels * depth / 8) bytes,
 * 16-bit samples big-endian), written with libpng's full API; the caller frees .data. */
static membuf png_file(const png_spec *s, const uint8_t *pixels)
{
    membuf m = {0};
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    assert_non_null(info);
    if (setjmp(png_jmpbuf(png))) fail_msg("libpng could not write the test PNG");
    png_set_write_fn(png, &m, png_put, png_flush_nothing);
    png_set_IHDR(png, info, (png_uint_32)s->w, (png_uint_32)s->h, s->depth, s->type,
                 s->interlace ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (s->palette) png_set_PLTE(png, info, s->palette, s->npalette);
    if (s->trns || s->trns_colour) png_set_tRNS(png, info, s->trns, s->ntrns, s->trns_colour);
    if (s->gamma > 0) png_set_gAMA(png, info, s->gamma);
    png_write_info(png, info);
    int channels = s->type == PNG_COLOR_TYPE_RGB_ALPHA ? 4
                   : s->type == PNG_COLOR_TYPE_RGB     ? 3
                   : s->type == PNG_COLOR_TYPE_GA      ? 2
                                                       : 1;
    size_t row = ((size_t)s->w * (size_t)channels * (size_t)s->depth + 7) / 8;
    int passes = png_set_interlace_handling(png);
    for (int p = 0; p < passes; p++)
        for (int y = 0; y < s->h; y++) png_write_row(png, pixels + (size_t)y * row);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    return m;
}

/* A JPEG of w x h RGB pixels at quality 100; the caller tjFree's .data. */
static membuf jpeg_file(int w, int h, const uint8_t *rgb, int subsamp, int pixel_format)
{
    tjhandle tj = tjInitCompress();
    assert_non_null(tj);
    unsigned char *out = NULL;
    unsigned long size = 0;
    int pitch = w * tjPixelSize[pixel_format];
    if (tjCompress2(tj, rgb, w, pitch, h, pixel_format, &out, &size, subsamp, 100, 0) != 0)
        fail_msg("tjCompress2: %s", tjGetErrorStr2(tj));
    tjDestroy(tj);
    return (membuf){out, size, size};
}

static iir_texture *decode_ok(const membuf *m, const char *what, bool srgb)
{
    iir_texture *t = NULL;
    iir_error err = {0};
    iir_status st = iir_texture_decode(m->data, m->size, what, srgb, &t, &err);
    if (st != IIR_OK) fail_msg("decoding %s: %s", what, err.msg);
    assert_non_null(t);
    return t;
}

/* ---- decoding values ------------------------------------------------------------------------ */

static void test_srgb_decode(void **state)
{
    (void)state;
    static const int codes[4] = {0, 10, 128, 255};
    uint8_t px[16];
    for (int i = 0; i < 4; i++) {
        px[4 * i] = px[4 * i + 1] = px[4 * i + 2] = (uint8_t)codes[i];
        px[4 * i + 3] = (uint8_t)codes[3 - i];
    }
    iir_texture *srgb = make(4, 1, px, true), *data = make(4, 1, px, false);
    for (int i = 0; i < 4; i++) {
        iir_rgba s = iir_texture_texel(srgb, 0, i, 0), d = iir_texture_texel(data, 0, i, 0);
        assert_rel(s.r, eotf8(codes[i]), "sRGB r");
        assert_rel(s.g, eotf8(codes[i]), "sRGB g");
        assert_rel(s.b, eotf8(codes[i]), "sRGB b");
        assert_rel(s.a, codes[3 - i] / 255.0, "sRGB texture's alpha is linear");
        assert_rel(d.r, codes[i] / 255.0, "data r");
        assert_rel(d.b, codes[i] / 255.0, "data b");
        assert_rel(d.a, codes[3 - i] / 255.0, "data alpha");
    }
    /* the two pieces of the curve: 10 is on the linear toe, 128 on the power */
    assert_rel(iir_texture_texel(srgb, 0, 1, 0).r, 10.0 / 255.0 / 12.92, "toe");
    assert_rel(iir_texture_texel(srgb, 0, 2, 0).r, pow((128.0 / 255.0 + 0.055) / 1.055, 2.4),
               "power");
    iir_texture_destroy(srgb);
    iir_texture_destroy(data);
}

/* ---- wrap modes and filters ----------------------------------------------------------------- */

static void test_wrap_modes(void **state)
{
    (void)state;
    iir_texture *t = make_4x2();
    const float v0 = 0.25f; /* row 0's centre */
    iir_tex_sampler s = {0};

    /* linear filter at u = -0.25, 1.25, 2.75: halfway between two texel centres */
    s.wrap_s = IIR_WRAP_REPEAT;
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(-0.25f, v0), 0),
                avg(texel_4x2(2, 0), texel_4x2(3, 0)), 1e-6, "repeat -0.25");
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(1.25f, v0), 0),
                avg(texel_4x2(0, 0), texel_4x2(1, 0)), 1e-6, "repeat 1.25");
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(2.75f, v0), 0),
                avg(texel_4x2(2, 0), texel_4x2(3, 0)), 1e-6, "repeat 2.75");
    s.wrap_s = IIR_WRAP_CLAMP;
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(-0.25f, v0), 0), texel_4x2(0, 0), 1e-6,
                "clamp -0.25");
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(1.25f, v0), 0), texel_4x2(3, 0), 1e-6,
                "clamp 1.25");
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(2.75f, v0), 0), texel_4x2(3, 0), 1e-6,
                "clamp 2.75");
    s.wrap_s = IIR_WRAP_MIRROR;
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(-0.25f, v0), 0),
                avg(texel_4x2(0, 0), texel_4x2(1, 0)), 1e-6, "mirror -0.25");
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(1.25f, v0), 0),
                avg(texel_4x2(2, 0), texel_4x2(3, 0)), 1e-6, "mirror 1.25");
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(2.75f, v0), 0),
                avg(texel_4x2(2, 0), texel_4x2(3, 0)), 1e-6, "mirror 2.75");
    /* the edge texel of a mirror is doubled: u = -1/16 blends texel 0 with itself */
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(-0.0625f, v0), 0), texel_4x2(0, 0), 1e-6,
                "mirror -1/16");

    /* nearest texels away from texel edges */
    s.mag_nearest = true;
    static const float u[3] = {-0.3f, 1.1f, 2.6f};
    static const int repeat[3] = {2, 0, 2}, clamp[3] = {0, 3, 3}, mirror[3] = {1, 3, 2};
    for (int i = 0; i < 3; i++) {
        s.wrap_s = IIR_WRAP_REPEAT;
        assert_rgba(iir_texture_bilinear(t, &s, iir_v2(u[i], v0), 0), texel_4x2(repeat[i], 0), 0,
                    "nearest repeat");
        s.wrap_s = IIR_WRAP_CLAMP;
        assert_rgba(iir_texture_bilinear(t, &s, iir_v2(u[i], v0), 0), texel_4x2(clamp[i], 0), 0,
                    "nearest clamp");
        s.wrap_s = IIR_WRAP_MIRROR;
        assert_rgba(iir_texture_bilinear(t, &s, iir_v2(u[i], v0), 0), texel_4x2(mirror[i], 0), 0,
                    "nearest mirror");
    }

    /* v wraps by wrap_t alone: v = 1.5 is halfway between rows 2 and 3 (of 2) */
    s = (iir_tex_sampler){.wrap_s = IIR_WRAP_CLAMP, .wrap_t = IIR_WRAP_REPEAT};
    const float uc = 0.375f; /* column 1's centre */
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(uc, 1.5f), 0),
                avg(texel_4x2(1, 0), texel_4x2(1, 1)), 1e-6, "t repeat 1.5");
    s.wrap_t = IIR_WRAP_CLAMP;
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(uc, 1.5f), 0), texel_4x2(1, 1), 1e-6,
                "t clamp 1.5");
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(uc, -7.f), 0), texel_4x2(1, 0), 1e-6,
                "t clamp -7");
    s.wrap_t = IIR_WRAP_MIRROR;
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(uc, 1.5f), 0),
                avg(texel_4x2(1, 1), texel_4x2(1, 0)), 1e-6, "t mirror 1.5");
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(uc, -0.75f), 0), texel_4x2(1, 1), 1e-6,
                "t mirror -0.75");
    iir_texture_destroy(t);
}

static void test_bilinear(void **state)
{
    (void)state;
    iir_texture *t = make_4x2();
    iir_tex_sampler s = {0};
    /* uv (0.3, 0.6): x = 0.3 * 4 - 0.5 = 0.7 (texels 0, 1), y = 0.6 * 2 - 0.5 = 0.7 (rows 0, 1) */
    iir_rgba want = mix(mix(texel_4x2(0, 0), texel_4x2(1, 0), 0.7f),
                        mix(texel_4x2(0, 1), texel_4x2(1, 1), 0.7f), 0.7f);
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(0.3f, 0.6f), 0), want, 1e-6, "(0.3, 0.6)");
    /* by hand for r: 0.09 * 10 + 0.21 * 40 + 0.21 * 130 + 0.49 * 160, over 255 */
    assert_near(iir_texture_bilinear(t, &s, iir_v2(0.3f, 0.6f), 0).r,
                (0.09 * 10 + 0.21 * 40 + 0.21 * 130 + 0.49 * 160) / 255.0, 1e-6, "r by hand");
    /* (0.5, 0.25): halfway between texels 1 and 2 of row 0 */
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(0.5f, 0.25f), 0),
                avg(texel_4x2(1, 0), texel_4x2(2, 0)), 1e-6, "(0.5, 0.25)");
    /* a texel centre gives the texel */
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(0.625f, 0.75f), 0), texel_4x2(2, 1), 1e-6,
                "centre of (2, 1)");
    /* the default sampler is what NULL means */
    assert_rgba(iir_texture_bilinear(t, NULL, iir_v2(0.3f, 0.6f), 0),
                iir_texture_bilinear(t, &s, iir_v2(0.3f, 0.6f), 0), 0, "NULL sampler");
    /* nearest: the texel under uv */
    s.mag_nearest = true;
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(0.3f, 0.6f), 0), texel_4x2(1, 1), 0,
                "nearest (0.3, 0.6)");
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(0.99f, 0.01f), 0), texel_4x2(3, 0), 0,
                "nearest (0.99, 0.01)");
    iir_texture_destroy(t);

    /* filtering is on linear values: halfway between sRGB 0 and 255 is linear 0.5 */
    uint8_t bw[8] = {0, 0, 0, 255, 255, 255, 255, 255};
    iir_texture *g = make(2, 1, bw, true);
    iir_rgba mid = iir_texture_bilinear(g, NULL, iir_v2(0.5f, 0.5f), 0);
    assert_rgba(mid, (iir_rgba){0.5f, 0.5f, 0.5f, 1.f}, 1e-6, "sRGB midpoint is linear 0.5");
    iir_texture_destroy(g);
}

static void test_nonfinite_uv(void **state)
{
    (void)state;
    iir_texture *t = make_4x2();
    static const iir_wrap modes[3] = {IIR_WRAP_REPEAT, IIR_WRAP_CLAMP, IIR_WRAP_MIRROR};
    for (int m = 0; m < 3; m++) {
        iir_tex_sampler s = {.wrap_s = modes[m], .wrap_t = modes[m]};
        iir_rgba at0 = iir_texture_bilinear(t, &s, iir_v2(0.f, 0.f), 0);
        assert_rgba(iir_texture_bilinear(t, &s, iir_v2(NAN, NAN), 0), at0, 0, "NaN uv is 0");
        assert_rgba(iir_texture_sample(t, &s, iir_v2(NAN, 0.f), NAN), at0, 0, "NaN width");
        static const float odd[] = {INFINITY, -INFINITY, 3e38f, -3e38f, 1e-40f};
        for (size_t i = 0; i < sizeof odd / sizeof *odd; i++) {
            iir_rgba c = iir_texture_sample(t, &s, iir_v2(odd[i], -odd[i]), odd[i]);
            if (!isfinite(c.r) || !isfinite(c.g) || !isfinite(c.b) || !isfinite(c.a))
                fail_msg("non-finite lookup at %g", (double)odd[i]);
            assert_true(c.r >= 0.f && c.r <= 1.f);
        }
    }
    iir_texture_destroy(t);
}

/* ---- the mip chain -------------------------------------------------------------------------- */

static void test_lod(void **state)
{
    (void)state;
    uint8_t px[16 * 8 * 4];
    memset(px, 200, sizeof px);
    iir_texture *t = make(16, 8, px, false);
    assert_int_equal(iir_texture_levels(t), 5);
    static const int w[5] = {16, 8, 4, 2, 1}, h[5] = {8, 4, 2, 1, 1};
    for (int l = 0; l < 5; l++) {
        assert_int_equal(iir_texture_level_width(t, l), w[l]);
        assert_int_equal(iir_texture_level_height(t, l), h[l]);
    }
    assert_near(iir_texture_lod(t, 1.f / 16.f), 0.0, 1e-6, "1/w");
    assert_near(iir_texture_lod(t, 2.f / 16.f), 1.0, 1e-6, "2/w");
    assert_near(iir_texture_lod(t, 4.f / 16.f), 2.0, 1e-6, "4/w");
    assert_near(iir_texture_lod(t, 6.f / 16.f), log2(6.0), 1e-6, "6/w");
    assert_near(iir_texture_lod(t, 1000.f), 4.0, 0, "clamped at the coarsest");
    assert_near(iir_texture_lod(t, INFINITY), 4.0, 0, "infinite");
    assert_near(iir_texture_lod(t, 0.25f / 16.f), 0.0, 0, "magnified");
    assert_near(iir_texture_lod(t, 0.f), 0.0, 0, "zero");
    assert_near(iir_texture_lod(t, -1.f), 0.0, 0, "negative");
    assert_near(iir_texture_lod(t, NAN), 0.0, 0, "NaN");
    iir_texture_destroy(t);

    uint8_t one[4] = {1, 2, 3, 4};
    iir_texture *p = make(1, 1, one, false);
    assert_int_equal(iir_texture_levels(p), 1);
    assert_near(iir_texture_lod(p, 100.f), 0.0, 0, "1x1 has one level");
    iir_texture_destroy(p);
}

static void test_mip_checker(void **state)
{
    (void)state;
    /* data: a 4x4 checker of 0 and 255 */
    uint8_t px[4 * 4 * 4];
    for (int i = 0; i < 16; i++) {
        uint8_t v = ((i % 4) + (i / 4)) % 2 ? 255 : 0;
        px[4 * i] = px[4 * i + 1] = px[4 * i + 2] = v;
        px[4 * i + 3] = (uint8_t)(255 - v); /* alpha: the opposite checker */
    }
    iir_texture *t = make(4, 4, px, false);
    assert_int_equal(iir_texture_levels(t), 3);
    for (int y = 0; y < 2; y++)
        for (int x = 0; x < 2; x++)
            assert_rgba(iir_texture_texel(t, 1, x, y),
                        (iir_rgba){128 / 255.f, 128 / 255.f, 128 / 255.f, 128 / 255.f}, 1e-6,
                        "level 1 of the checker");
    iir_rgba top = iir_texture_texel(t, 2, 0, 0);
    assert_near(top.r, 0.5, 0.5 / 255.0 + 1e-6, "level 2 is the average");
    assert_near(top.a, 0.5, 0.5 / 255.0 + 1e-6, "alpha is averaged linearly");
    iir_texture_destroy(t);

    /* sRGB: a 2x2 checker of 0 and 255 averages to linear 0.5, stored as code 188 */
    double oetf = 1.055 * pow(0.5, 1.0 / 2.4) - 0.055;
    assert_int_equal((int)lround(oetf * 255.0), 188);
    uint8_t bw[16] = {0, 0, 0, 0, 255, 255, 255, 255, 255, 255, 255, 255, 0, 0, 0, 0};
    iir_texture *s = make(2, 2, bw, true);
    iir_rgba c = iir_texture_texel(s, 1, 0, 0);
    assert_rel(c.r, eotf8(188), "level 1 is sRGB code 188");
    assert_rel(c.g, eotf8(188), "g too");
    assert_near(c.r, 0.5, eotf8(188) - eotf8(187), "within an 8-bit step of 0.5");
    assert_rel(c.a, 128 / 255.0, "alpha is linear, not sRGB");
    iir_texture_destroy(s);
}

static void test_mip_odd_sizes(void **state)
{
    (void)state;
    /* 3 -> 1 averages all three texels */
    uint8_t three[12] = {0, 0, 0, 255, 30, 30, 30, 255, 90, 90, 90, 255};
    iir_texture *t = make(3, 1, three, false);
    assert_int_equal(iir_texture_levels(t), 2);
    assert_rel(iir_texture_texel(t, 1, 0, 0).r, 40 / 255.0, "3 -> 1");
    iir_texture_destroy(t);

    /* 5 -> 2: weights (1, 1, 1/2) / 2.5 and (1/2, 1, 1) / 2.5; 2 -> 1 */
    uint8_t five[20];
    for (int i = 0; i < 5; i++) {
        five[4 * i] = five[4 * i + 1] = five[4 * i + 2] = (uint8_t)(10 * (i + 1));
        five[4 * i + 3] = 255;
    }
    t = make(5, 1, five, false);
    assert_int_equal(iir_texture_levels(t), 3);
    assert_int_equal(iir_texture_level_width(t, 1), 2);
    assert_rel(iir_texture_texel(t, 1, 0, 0).r, 18 / 255.0, "5 -> 2, first");
    assert_rel(iir_texture_texel(t, 1, 1, 0).r, 42 / 255.0, "5 -> 2, second");
    assert_rel(iir_texture_texel(t, 2, 0, 0).r, 30 / 255.0, "2 -> 1");
    iir_texture_destroy(t);

    /* 3x3 -> 1x1: the average of nine, in both directions at once */
    uint8_t nine[36];
    for (int i = 0; i < 9; i++) {
        nine[4 * i] = nine[4 * i + 1] = nine[4 * i + 2] = (uint8_t)(9 * i);
        nine[4 * i + 3] = 255;
    }
    t = make(3, 3, nine, false);
    assert_int_equal(iir_texture_levels(t), 2);
    assert_rel(iir_texture_texel(t, 1, 0, 0).r, 36 / 255.0, "3x3 -> 1x1");
    iir_texture_destroy(t);

    /* 5x3 -> 2x1 -> 1x1 */
    uint8_t rect[5 * 3 * 4];
    memset(rect, 77, sizeof rect);
    t = make(5, 3, rect, false);
    assert_int_equal(iir_texture_levels(t), 3);
    assert_int_equal(iir_texture_level_width(t, 1), 2);
    assert_int_equal(iir_texture_level_height(t, 1), 1);
    assert_rel(iir_texture_texel(t, 2, 0, 0).g, 77 / 255.0, "flat stays flat");
    iir_texture_destroy(t);
}

static void test_trilinear(void **state)
{
    (void)state;
    uint8_t px[8 * 8 * 4];
    uint32_t x = 12345;
    for (size_t i = 0; i < sizeof px; i++) {
        x = x * 1664525u + 1013904223u;
        px[i] = (uint8_t)(x >> 24);
    }
    iir_texture *t = make(8, 8, px, true);
    assert_int_equal(iir_texture_levels(t), 4);
    iir_tex_sampler s = {0};
    static const iir_vec2 uvs[3] = {{0.3f, 0.6f}, {0.71f, 0.13f}, {-0.4f, 1.9f}};
    for (int i = 0; i < 3; i++) {
        iir_vec2 uv = uvs[i];
        iir_rgba b0 = iir_texture_bilinear(t, &s, uv, 0), b1 = iir_texture_bilinear(t, &s, uv, 1),
                 b2 = iir_texture_bilinear(t, &s, uv, 2), b3 = iir_texture_bilinear(t, &s, uv, 3);
        assert_near(iir_texture_lod(t, sqrtf(2.f) / 8.f), 0.5, 1e-6, "lod 0.5");
        assert_rgba(iir_texture_sample(t, &s, uv, sqrtf(2.f) / 8.f), avg(b0, b1), 1e-6,
                    "lod 0.5 averages levels 0 and 1");
        assert_rgba(iir_texture_sample(t, &s, uv, exp2f(1.25f) / 8.f), mix(b1, b2, 0.25f), 1e-5,
                    "lod 1.25");
        assert_rgba(iir_texture_sample(t, &s, uv, 2.f / 8.f), b1, 1e-6, "lod 1 is level 1");
        assert_rgba(iir_texture_sample(t, &s, uv, 100.f), b3, 0, "coarsest");
        assert_rgba(iir_texture_sample(t, &s, uv, 0.f), b0, 0, "width 0 is level 0");
        assert_rgba(iir_texture_sample(t, &s, uv, 0.5f / 8.f), b0, 0, "magnified");

        /* min filter without mips: level 0 whatever the footprint */
        iir_tex_sampler nomip = {.min_no_mip = true};
        assert_rgba(iir_texture_sample(t, &nomip, uv, 100.f), b0, 0, "min_no_mip");
        nomip.min_nearest = true;
        iir_tex_sampler near = {.mag_nearest = true};
        assert_rgba(iir_texture_sample(t, &nomip, uv, 100.f), iir_texture_bilinear(t, &near, uv, 0),
                    0, "min NEAREST");
        /* nearest within each level, levels still blended */
        iir_tex_sampler nmip = {.min_nearest = true};
        assert_rgba(
            iir_texture_sample(t, &nmip, uv, sqrtf(2.f) / 8.f),
            avg(iir_texture_bilinear(t, &near, uv, 0), iir_texture_bilinear(t, &near, uv, 1)), 1e-6,
            "NEAREST_MIPMAP_LINEAR");
        /* the mag filter decides below lod 0, the min filter above */
        assert_rgba(iir_texture_sample(t, &near, uv, 0.5f / 8.f),
                    iir_texture_bilinear(t, &near, uv, 0), 0, "mag NEAREST");
        assert_rgba(iir_texture_sample(t, &near, uv, 2.f / 8.f), b1, 1e-6,
                    "mag NEAREST does not touch minification");
    }
    /* levels outside the chain are clamped */
    assert_rgba(iir_texture_bilinear(t, &s, iir_v2(0.2f, 0.2f), 9),
                iir_texture_bilinear(t, &s, iir_v2(0.2f, 0.2f), 3), 0, "level 9 is level 3");
    iir_texture_destroy(t);
}

/* ---- samplers and KHR_texture_transform ----------------------------------------------------- */

static void test_sampler_from_gltf(void **state)
{
    (void)state;
    iir_tex_sampler d = iir_tex_sampler_from_gltf(0, 0, 0, 0);
    assert_int_equal(d.wrap_s, IIR_WRAP_REPEAT);
    assert_int_equal(d.wrap_t, IIR_WRAP_REPEAT);
    assert_false(d.mag_nearest || d.min_no_mip || d.min_nearest);
    iir_tex_sampler s = iir_tex_sampler_from_gltf(9728, 9729, 33071, 33648);
    assert_int_equal(s.wrap_s, IIR_WRAP_CLAMP);
    assert_int_equal(s.wrap_t, IIR_WRAP_MIRROR);
    assert_true(s.mag_nearest);
    assert_true(s.min_no_mip);
    assert_false(s.min_nearest);
    s = iir_tex_sampler_from_gltf(9729, 9728, 10497, 10497);
    assert_false(s.mag_nearest);
    assert_true(s.min_no_mip && s.min_nearest);
    s = iir_tex_sampler_from_gltf(9729, 9986, 10497, 33071);
    assert_false(s.min_no_mip);
    assert_true(s.min_nearest);
    assert_int_equal(s.wrap_t, IIR_WRAP_CLAMP);
    s = iir_tex_sampler_from_gltf(9729, 9987, 10497, 10497);
    assert_false(s.min_no_mip || s.min_nearest);
}

static void assert_uv(iir_vec2 got, float x, float y, const char *what)
{
    if (!(fabsf(got.x - x) <= 1e-6f && fabsf(got.y - y) <= 1e-6f))
        fail_msg("%s: got (%.8g, %.8g), want (%.8g, %.8g)", what, got.x, got.y, x, y);
}

static void test_transform(void **state)
{
    (void)state;
    iir_tex_transform id = iir_tex_transform_identity();
    assert_uv(iir_tex_transform_apply(&id, iir_v2(0.3f, -1.7f)), 0.3f, -1.7f, "identity");

    iir_tex_transform t = id;
    t.offset = iir_v2(0.25f, -0.5f);
    assert_uv(iir_tex_transform_apply(&t, iir_v2(0.3f, 0.2f)), 0.55f, -0.3f, "offset");
    t = id;
    t.scale = iir_v2(2.f, -3.f);
    assert_uv(iir_tex_transform_apply(&t, iir_v2(0.3f, 0.2f)), 0.6f, -0.6f, "scale");

    /* rotation pi/2: the matrix rows (cos, sin), (-sin, cos) take (1,0) to (0,-1), (0,1) to (1,0)
     */
    t = id;
    t.rotation = IIR_PI / 2;
    assert_uv(iir_tex_transform_apply(&t, iir_v2(1.f, 0.f)), 0.f, -1.f, "rotate (1,0)");
    assert_uv(iir_tex_transform_apply(&t, iir_v2(0.f, 1.f)), 1.f, 0.f, "rotate (0,1)");
    /* a general angle against the matrix written out */
    t.rotation = 0.3f;
    float c = cosf(0.3f), s = sinf(0.3f);
    assert_uv(iir_tex_transform_apply(&t, iir_v2(0.7f, 0.4f)), c * 0.7f + s * 0.4f,
              -s * 0.7f + c * 0.4f, "rotate 0.3");

    /* T R S, in that order: scale first, then rotate, then offset */
    t = (iir_tex_transform){{0.1f, 0.2f}, 0.3f, {2.f, 0.5f}};
    float x = 2.f * 0.7f, y = 0.5f * 0.4f;
    assert_uv(iir_tex_transform_apply(&t, iir_v2(0.7f, 0.4f)), c * x + s * y + 0.1f,
              -s * x + c * y + 0.2f, "T R S");

    /* the spec's example: offset (0,1), rotation pi/2, scale 0.5 uses the lower-left quadrant */
    t = (iir_tex_transform){{0.f, 1.f}, 1.57079632679f, {0.5f, 0.5f}};
    assert_uv(iir_tex_transform_apply(&t, iir_v2(0.f, 0.f)), 0.f, 1.f, "example (0,0)");
    assert_uv(iir_tex_transform_apply(&t, iir_v2(1.f, 0.f)), 0.f, 0.5f, "example (1,0)");
    assert_uv(iir_tex_transform_apply(&t, iir_v2(1.f, 1.f)), 0.5f, 0.5f, "example (1,1)");
    assert_uv(iir_tex_transform_apply(&t, iir_v2(0.f, 1.f)), 0.5f, 1.f, "example (0,1)");

    assert_near(iir_tex_transform_width(&t, 0.1f), 0.05, 1e-7, "footprint scaled");
    t.scale = iir_v2(-3.f, 0.5f);
    assert_near(iir_tex_transform_width(&t, 0.1f), 0.3, 1e-6, "the larger scale");
}

/* ---- decoding files ------------------------------------------------------------------------- */

static void test_decode_png_8bit(void **state)
{
    (void)state;
    /* RGB, 3x2: every texel different */
    uint8_t rgb[3 * 2 * 3];
    for (int i = 0; i < 18; i++) rgb[i] = (uint8_t)(13 * i + 7);
    png_spec spec = {.w = 3, .h = 2, .type = PNG_COLOR_TYPE_RGB, .depth = 8};
    membuf m = png_file(&spec, rgb);
    iir_texture *t = decode_ok(&m, "rgb.png", true);
    assert_int_equal(iir_texture_width(t), 3);
    assert_int_equal(iir_texture_height(t), 2);
    assert_int_equal(iir_texture_levels(t), 2);
    assert_false(iir_texture_has_alpha(t));
    for (int y = 0; y < 2; y++) {
        for (int x = 0; x < 3; x++) {
            const uint8_t *p = &rgb[3 * (y * 3 + x)];
            iir_rgba c = iir_texture_texel(t, 0, x, y);
            assert_rel(c.r, eotf8(p[0]), "PNG RGB r");
            assert_rel(c.g, eotf8(p[1]), "PNG RGB g");
            assert_rel(c.b, eotf8(p[2]), "PNG RGB b");
            assert_rel(c.a, 1.0, "PNG RGB has a = 1");
        }
    }
    iir_texture_destroy(t);
    /* the same bytes as data, and a gAMA chunk that glTF says to ignore */
    free(m.data);
    spec.gamma = 1.0;
    m = png_file(&spec, rgb);
    t = decode_ok(&m, "rgb-gamma.png", false);
    assert_rel(iir_texture_texel(t, 0, 2, 1).g, rgb[16] / 255.0, "gAMA ignored, data /255");
    iir_texture_destroy(t);
    free(m.data);

    /* RGBA, interlaced */
    uint8_t rgba[5 * 4 * 4];
    for (int i = 0; i < 80; i++) rgba[i] = (uint8_t)(37 * i + 1);
    spec =
        (png_spec){.w = 5, .h = 4, .type = PNG_COLOR_TYPE_RGB_ALPHA, .depth = 8, .interlace = true};
    m = png_file(&spec, rgba);
    t = decode_ok(&m, "rgba.png", false);
    assert_true(iir_texture_has_alpha(t));
    for (int i = 0; i < 20; i++) {
        iir_rgba c = iir_texture_texel(t, 0, i % 5, i / 5);
        assert_rel(c.r, rgba[4 * i] / 255.0, "PNG RGBA r");
        assert_rel(c.b, rgba[4 * i + 2] / 255.0, "PNG RGBA b");
        assert_rel(c.a, rgba[4 * i + 3] / 255.0, "PNG RGBA a");
    }
    iir_texture_destroy(t);
    free(m.data);

    /* grey: r = g = b */
    uint8_t grey[4] = {0, 64, 200, 255};
    spec = (png_spec){.w = 2, .h = 2, .type = PNG_COLOR_TYPE_GRAY, .depth = 8};
    m = png_file(&spec, grey);
    t = decode_ok(&m, "grey.png", true);
    for (int i = 0; i < 4; i++) {
        iir_rgba c = iir_texture_texel(t, 0, i % 2, i / 2);
        assert_rel(c.r, eotf8(grey[i]), "grey r");
        assert_rel(c.g, eotf8(grey[i]), "grey g");
        assert_rel(c.b, eotf8(grey[i]), "grey b");
        assert_rel(c.a, 1.0, "grey a");
    }
    iir_texture_destroy(t);
    free(m.data);

    /* grey + alpha */
    uint8_t ga[4] = {100, 50, 150, 255};
    spec = (png_spec){.w = 2, .h = 1, .type = PNG_COLOR_TYPE_GA, .depth = 8};
    m = png_file(&spec, ga);
    t = decode_ok(&m, "ga.png", false);
    assert_rgba(iir_texture_texel(t, 0, 0, 0),
                (iir_rgba){100 / 255.f, 100 / 255.f, 100 / 255.f, 50 / 255.f}, 1e-6, "GA 0");
    assert_rgba(iir_texture_texel(t, 0, 1, 0), (iir_rgba){150 / 255.f, 150 / 255.f, 150 / 255.f, 1},
                1e-6, "GA 1");
    assert_true(iir_texture_has_alpha(t));
    iir_texture_destroy(t);
    free(m.data);

    /* palette of 4 bits with tRNS */
    static const png_color pal[3] = {{255, 0, 0}, {0, 128, 0}, {10, 20, 30}};
    static const png_byte trns[2] = {0, 77};
    uint8_t idx[2] = {0x01, 0x20}; /* 4 texels: 0, 1, 2, 0 */
    spec = (png_spec){.w = 4,
                      .h = 1,
                      .type = PNG_COLOR_TYPE_PALETTE,
                      .depth = 4,
                      .palette = pal,
                      .npalette = 3,
                      .trns = trns,
                      .ntrns = 2};
    m = png_file(&spec, idx);
    t = decode_ok(&m, "palette.png", false);
    assert_rgba(iir_texture_texel(t, 0, 0, 0), (iir_rgba){1, 0, 0, 0}, 1e-6, "palette 0");
    assert_rgba(iir_texture_texel(t, 0, 1, 0), (iir_rgba){0, 128 / 255.f, 0, 77 / 255.f}, 1e-6,
                "palette 1");
    assert_rgba(iir_texture_texel(t, 0, 2, 0), (iir_rgba){10 / 255.f, 20 / 255.f, 30 / 255.f, 1},
                1e-6, "palette 2 (past tRNS: opaque)");
    assert_rgba(iir_texture_texel(t, 0, 3, 0), (iir_rgba){1, 0, 0, 0}, 1e-6, "palette 3");
    assert_true(iir_texture_has_alpha(t));
    iir_texture_destroy(t);
    free(m.data);

    /* 1-bit grey with a transparent colour */
    png_color_16 black = {.gray = 0};
    uint8_t bits[1] = {0x50}; /* 0 1 0 1 */
    spec =
        (png_spec){.w = 4, .h = 1, .type = PNG_COLOR_TYPE_GRAY, .depth = 1, .trns_colour = &black};
    m = png_file(&spec, bits);
    t = decode_ok(&m, "bits.png", false);
    assert_rgba(iir_texture_texel(t, 0, 0, 0), (iir_rgba){0, 0, 0, 0}, 0, "1-bit 0, transparent");
    assert_rgba(iir_texture_texel(t, 0, 1, 0), (iir_rgba){1, 1, 1, 1}, 0, "1-bit 1");
    iir_texture_destroy(t);
    free(m.data);
}

static void test_decode_png_16bit(void **state)
{
    (void)state;
    /* RGB 16-bit, big-endian samples */
    static const uint16_t v[2 * 2 * 3] = {0,     1,     1000,  65535, 32768, 12345,
                                          40000, 50000, 60000, 7,     300,   65534};
    uint8_t be[sizeof v];
    for (int i = 0; i < 12; i++) {
        be[2 * i] = (uint8_t)(v[i] >> 8);
        be[2 * i + 1] = (uint8_t)(v[i] & 0xff);
    }
    png_spec spec = {.w = 2, .h = 2, .type = PNG_COLOR_TYPE_RGB, .depth = 16};
    membuf m = png_file(&spec, be);
    iir_texture *t = decode_ok(&m, "wide.png", false);
    assert_int_equal(iir_texture_width(t), 2);
    assert_false(iir_texture_has_alpha(t));
    for (int i = 0; i < 4; i++) {
        iir_rgba c = iir_texture_texel(t, 0, i % 2, i / 2);
        assert_rel(c.r, v[3 * i] / 65535.0, "16-bit data r");
        assert_rel(c.g, v[3 * i + 1] / 65535.0, "16-bit data g");
        assert_rel(c.b, v[3 * i + 2] / 65535.0, "16-bit data b");
        assert_rel(c.a, 1.0, "16-bit a");
    }
    iir_texture_destroy(t);
    /* sRGB 16-bit: decoded, then kept as linear 16 bits (half a step of 1/65535) */
    t = decode_ok(&m, "wide-srgb.png", true);
    for (int i = 0; i < 12; i++) {
        double c = v[i] / 65535.0;
        double want = c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4);
        iir_rgba got = iir_texture_texel(t, 0, (i / 3) % 2, i / 6);
        float ch = i % 3 == 0 ? got.r : (i % 3 == 1 ? got.g : got.b);
        assert_near(ch, want, 0.5 / 65535.0 + 1e-7, "16-bit sRGB");
    }
    /* the chain of a 2x2 16-bit texture: 8 bytes a texel */
    uint8_t one[4] = {0};
    iir_texture *small = make(1, 1, one, false);
    assert_int_equal(iir_texture_bytes(t) - iir_texture_bytes(small), (4 + 1) * 8 - 4);
    iir_texture_destroy(small);
    iir_texture_destroy(t);
    free(m.data);

    /* grey + alpha 16-bit */
    uint8_t ga[4] = {0x12, 0x34, 0x80, 0x00};
    spec = (png_spec){.w = 1, .h = 1, .type = PNG_COLOR_TYPE_GA, .depth = 16};
    m = png_file(&spec, ga);
    t = decode_ok(&m, "ga16.png", false);
    iir_rgba c = iir_texture_texel(t, 0, 0, 0);
    assert_rel(c.r, 0x1234 / 65535.0, "GA16 grey");
    assert_rel(c.b, 0x1234 / 65535.0, "GA16 grey to blue");
    assert_rel(c.a, 0x8000 / 65535.0, "GA16 alpha");
    assert_true(iir_texture_has_alpha(t));
    iir_texture_destroy(t);
    t = decode_ok(&m, "ga16-srgb.png", true);
    c = iir_texture_texel(t, 0, 0, 0);
    double g = 0x1234 / 65535.0;
    assert_near(c.g, pow((g + 0.055) / 1.055, 2.4), 0.5 / 65535.0 + 1e-7, "GA16 sRGB grey");
    assert_rel(c.a, 0x8000 / 65535.0, "GA16 sRGB texture's alpha stays linear");
    iir_texture_destroy(t);
    free(m.data);
}

static void test_decode_jpeg(void **state)
{
    (void)state;
    /* flat colour, 20x12 (not a multiple of the 8x8 blocks) */
    uint8_t rgb[20 * 12 * 3];
    for (int i = 0; i < 20 * 12; i++) {
        rgb[3 * i] = 200;
        rgb[3 * i + 1] = 100;
        rgb[3 * i + 2] = 50;
    }
    membuf m = jpeg_file(20, 12, rgb, TJSAMP_444, TJPF_RGB);
    iir_texture *t = decode_ok(&m, "flat.jpg", false);
    assert_int_equal(iir_texture_width(t), 20);
    assert_int_equal(iir_texture_height(t), 12);
    assert_false(iir_texture_has_alpha(t));
    const double tol = 2.5 / 255.0; /* lossy: quality 100 keeps a flat colour within 2 codes */
    for (int y = 0; y < 12; y += 5) {
        for (int x = 0; x < 20; x += 3) {
            iir_rgba c = iir_texture_texel(t, 0, x, y);
            assert_near(c.r, 200 / 255.0, tol, "JPEG r");
            assert_near(c.g, 100 / 255.0, tol, "JPEG g");
            assert_near(c.b, 50 / 255.0, tol, "JPEG b");
            assert_rel(c.a, 1.0, "JPEG a");
        }
    }
    iir_texture_destroy(t);
    /* as sRGB: the same codes through the EOTF */
    t = decode_ok(&m, "flat-srgb.jpg", true);
    assert_near(iir_texture_texel(t, 0, 7, 7).r, eotf8(200), eotf8(202) - eotf8(200), "sRGB JPEG");
    iir_texture_destroy(t);
    tjFree(m.data);

    /* grey JPEG: r = g = b */
    uint8_t grey[16 * 8];
    memset(grey, 90, sizeof grey);
    m = jpeg_file(16, 8, grey, TJSAMP_GRAY, TJPF_GRAY);
    t = decode_ok(&m, "grey.jpg", false);
    iir_rgba c = iir_texture_texel(t, 0, 3, 3);
    assert_near(c.r, 90 / 255.0, tol, "grey JPEG");
    assert_rel(c.g, c.r, "grey JPEG g = r");
    assert_rel(c.b, c.r, "grey JPEG b = r");
    iir_texture_destroy(t);
    tjFree(m.data);
}

static void test_decode_errors(void **state)
{
    (void)state;
    iir_error err;
    iir_texture *t = NULL;

    /* a PNG cut in half */
    uint8_t rgb[8 * 8 * 3];
    for (size_t i = 0; i < sizeof rgb; i++) rgb[i] = (uint8_t)(i * 31);
    png_spec spec = {.w = 8, .h = 8, .type = PNG_COLOR_TYPE_RGB, .depth = 8};
    membuf m = png_file(&spec, rgb);
    memset(&err, 0, sizeof err);
    iir_status st = iir_texture_decode(m.data, m.size / 2, "half.png", false, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_FORMAT, "half.png");
    /* only the signature and part of the header */
    st = iir_texture_decode(m.data, 12, "header.png", false, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_FORMAT, "header.png");
    /* a damaged image chunk (CRC) */
    m.data[m.size - 20] ^= 0x55;
    st = iir_texture_decode(m.data, m.size, "crc.png", false, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_FORMAT, "crc.png");
    free(m.data);

    /* random bytes */
    uint8_t junk[300];
    uint32_t x = 99;
    for (size_t i = 0; i < sizeof junk; i++) {
        x = x * 1103515245u + 12345u;
        junk[i] = (uint8_t)(x >> 16);
    }
    junk[0] = 0x42;
    st = iir_texture_decode(junk, sizeof junk, "junk.bin", true, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_FORMAT, "junk.bin");
    /* random bytes after a JPEG's magic */
    junk[0] = 0xff;
    junk[1] = 0xd8;
    junk[2] = 0xff;
    st = iir_texture_decode(junk, sizeof junk, "junk.jpg", true, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_FORMAT, "junk.jpg");
    /* nothing */
    st = iir_texture_decode(junk, 0, "empty image", true, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_FORMAT, "empty image");

    /* a JPEG cut short */
    uint8_t flat[32 * 32 * 3];
    memset(flat, 128, sizeof flat);
    m = jpeg_file(32, 32, flat, TJSAMP_420, TJPF_RGB);
    st = iir_texture_decode(m.data, m.size * 2 / 3, "cut.jpg", false, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_FORMAT, "cut.jpg");
    tjFree(m.data);

    /* too large: 16385 texels wide */
    static uint8_t wide[16385 * 3];
    memset(wide, 9, sizeof wide);
    spec = (png_spec){.w = 16385, .h = 1, .type = PNG_COLOR_TYPE_RGB, .depth = 8};
    m = png_file(&spec, wide);
    st = iir_texture_decode(m.data, m.size, "huge.png", false, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_UNSUPPORTED, "huge.png");
    assert_non_null(strstr(err.msg, "16385"));
    free(m.data);
    m = jpeg_file(16385, 1, wide, TJSAMP_444, TJPF_RGB);
    st = iir_texture_decode(m.data, m.size, "huge.jpg", false, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_UNSUPPORTED, "huge.jpg");
    tjFree(m.data);
    /* 16384 is fine */
    spec.w = 16384;
    m = png_file(&spec, wide);
    t = decode_ok(&m, "16384.png", false);
    assert_int_equal(iir_texture_levels(t), 15);
    iir_texture_destroy(t);
    t = NULL;
    free(m.data);

    /* kinds of image this build does not decode say so */
    static const uint8_t webp[16] = {'R', 'I', 'F', 'F', 8, 0, 0, 0, 'W', 'E', 'B', 'P'};
    st = iir_texture_decode(webp, sizeof webp, "tex.webp", true, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_UNSUPPORTED, "tex.webp");
    static const uint8_t ktx[12] = {0xab, 'K',  'T',  'X',  ' ',  '2',
                                    '0',  0xbb, '\r', '\n', 0x1a, '\n'};
    st = iir_texture_decode(ktx, sizeof ktx, "tex.ktx2", true, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_UNSUPPORTED, "tex.ktx2");
}

/* ---- files ---------------------------------------------------------------------------------- */

static void test_read_files(void **state)
{
    (void)state;
    char dir[256], path[300];
    const char *base = getenv("IIR_TEST_TMP");
    snprintf(dir, sizeof dir, "%s/test_texture_XXXXXX", base && *base ? base : "/tmp");
    assert_non_null(mkdtemp(dir));

    /* a PNG file */
    uint8_t rgba[2 * 2 * 4] = {1, 2, 3, 4, 50, 60, 70, 80, 90, 100, 110, 120, 255, 0, 255, 0};
    png_spec spec = {.w = 2, .h = 2, .type = PNG_COLOR_TYPE_RGB_ALPHA, .depth = 8};
    membuf m = png_file(&spec, rgba);
    snprintf(path, sizeof path, "%s/tex.png", dir);
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(m.data, 1, m.size, f), m.size);
    assert_int_equal(fclose(f), 0);
    free(m.data);
    iir_texture *t = NULL;
    iir_error err = {0};
    assert_int_equal(iir_texture_read(path, false, &t, &err), IIR_OK);
    assert_rgba(iir_texture_texel(t, 0, 1, 0),
                (iir_rgba){50 / 255.f, 60 / 255.f, 70 / 255.f, 80 / 255.f}, 1e-6, "PNG file");
    iir_texture_destroy(t);
    t = NULL;
    assert_int_equal(remove(path), 0);

    /* a missing file */
    iir_status st = iir_texture_read(path, false, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_IO, path);
    /* an empty file */
    f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fclose(f), 0);
    st = iir_texture_read(path, false, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_FORMAT, path);
    assert_int_equal(remove(path), 0);

    /* an EXR file: linear floats whatever `srgb` says, negative and NaN values made 0 */
    iir_image *img = iir_image_create(2, 1);
    assert_non_null(img);
    img->pixels[0] = iir_v3(0.25f, 3.5f, 1000.f);
    img->pixels[1] = iir_v3(-1.f, NAN, 1e9f);
    snprintf(path, sizeof path, "%s/tex.EXR", dir);
    assert_int_equal(iir_image_write_exr(img, path, &err), IIR_OK);
    iir_image_destroy(img);
    assert_int_equal(iir_texture_read(path, true, &t, &err), IIR_OK);
    assert_rgba(iir_texture_texel(t, 0, 0, 0), (iir_rgba){0.25f, 3.5f, 1000.f, 1.f}, 0, "EXR");
    assert_rgba(iir_texture_texel(t, 0, 1, 0), (iir_rgba){0.f, 0.f, 65504.f, 1.f}, 0,
                "EXR made finite");
    assert_rgba(iir_texture_texel(t, 1, 0, 0),
                (iir_rgba){0.125f, 1.75f, 0.5f * (1000.f + 65504.f), 1.f}, 1e-3, "EXR mip");
    assert_false(iir_texture_has_alpha(t));
    iir_texture_destroy(t);
    t = NULL;
    /* EXR bytes in memory are refused by name */
    f = fopen(path, "rb");
    assert_non_null(f);
    uint8_t head[64];
    size_t n = fread(head, 1, sizeof head, f);
    fclose(f);
    st = iir_texture_decode(head, n, "embedded.exr", false, &t, &err);
    assert_failed(st, t, &err, IIR_ERR_UNSUPPORTED, "embedded.exr");
    assert_int_equal(remove(path), 0);
    assert_int_equal(rmdir(dir), 0);
}

/* ---- memory and alpha ----------------------------------------------------------------------- */

static void test_alpha_and_bytes(void **state)
{
    (void)state;
    uint8_t px[4 * 4 * 4];
    memset(px, 255, sizeof px);
    iir_texture *opaque = make(4, 4, px, true);
    assert_false(iir_texture_has_alpha(opaque));
    px[4 * 9 + 3] = 254;
    iir_texture *holed = make(4, 4, px, true);
    assert_true(iir_texture_has_alpha(holed));
    uint8_t one[4] = {255, 255, 255, 255};
    iir_texture *dot = make(1, 1, one, true);
    /* a 4x4 RGBA8 chain is (16 + 4 + 1) * 4 bytes plus the struct, which a 1x1 has too */
    assert_int_equal(iir_texture_bytes(opaque) - iir_texture_bytes(dot), (16 + 4 + 1) * 4 - 4);
    assert_true(iir_texture_bytes(dot) >= 4);
    char line[128];
    iir_texture_describe(holed, line, sizeof line);
    assert_non_null(strstr(line, "4x4 RGBA8 sRGB, 3 levels"));
    assert_non_null(strstr(line, "alpha"));
    iir_texture_destroy(opaque);
    iir_texture_destroy(holed);
    iir_texture_destroy(dot);
    iir_texture_destroy(NULL);

    /* bad sizes */
    assert_null(iir_texture_from_rgba8(0, 4, px, false));
    assert_null(iir_texture_from_rgba8(4, -1, px, false));
    assert_null(iir_texture_from_rgba8(16385, 1, px, false));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_srgb_decode),
        cmocka_unit_test(test_wrap_modes),
        cmocka_unit_test(test_bilinear),
        cmocka_unit_test(test_nonfinite_uv),
        cmocka_unit_test(test_lod),
        cmocka_unit_test(test_mip_checker),
        cmocka_unit_test(test_mip_odd_sizes),
        cmocka_unit_test(test_trilinear),
        cmocka_unit_test(test_sampler_from_gltf),
        cmocka_unit_test(test_transform),
        cmocka_unit_test(test_decode_png_8bit),
        cmocka_unit_test(test_decode_png_16bit),
        cmocka_unit_test(test_decode_jpeg),
        cmocka_unit_test(test_decode_errors),
        cmocka_unit_test(test_read_files),
        cmocka_unit_test(test_alpha_and_bytes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

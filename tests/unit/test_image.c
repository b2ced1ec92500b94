/* test_image.c -- image lifetime, tone mapping, PNG/EXR/PFM/JPEG files, bad input; not metrics. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <float.h>
#include <math.h>
#include <OpenEXR/openexr.h> /* the test target does not get OpenEXR's include dir */
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <turbojpeg.h>

#include "iir/image.h"
#include "testutil.h"

/* ---- helpers -------------------------------------------------------------------------------- */

/* dir/name in this executable's scratch directory, in the caller's buffer. */
static const char *scratch_path(char *buf, size_t cap, const char *name)
{
    snprintf(buf, cap, "%s/%s", iir_test_tmpdir("test_image"), name);
    return buf;
}

static void write_bytes(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    if (n) assert_int_equal(fwrite(data, 1, n, f), n);
    assert_int_equal(fclose(f), 0);
}

static int file_exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

/* A non-square image whose pixels all differ, with HDR extremes mixed in. */
static iir_image *make_hdr_image(int w, int h)
{
    static const float special[] = {0.f,   -0.f,  1e-30f,  1e-40f /* denormal */,
                                    1e4f,  1e30f, 65504.f, 3.14159265f,
                                    -3.5f, 0.18f, 1.f,     FLT_MIN};
    iir_image *img = iir_image_create(w, h);
    assert_non_null(img);
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++) {
            int i = y * w + x;
            float base = (float)(i + 1) * 0.37f;
            *iir_image_at(img, x, y) =
                iir_v3(special[i % 12], base, special[(i * 7 + 3) % 12] + (float)y);
        }
    }
    return img;
}

/* Bit-exact comparison of two images of the same size. */
static void assert_same_bits(const iir_image *a, const iir_image *b)
{
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    assert_memory_equal(a->pixels, b->pixels,
                        (size_t)a->width * (size_t)a->height * sizeof(iir_vec3));
}

/* Checks a failed call: non-OK status, the expected code, NULL output, a message naming path. */
static void assert_failed(iir_status st, const iir_error *err, iir_status want, const char *path)
{
    if (st == IIR_OK) fail_msg("expected an error for %s", path);
    assert_int_equal(st, want);
    assert_int_equal(err->status, want);
    if (!strstr(err->msg, path)) fail_msg("message \"%s\" does not name %s", err->msg, path);
}

static void read_expect_failure(const char *path, iir_status want)
{
    iir_error err = {0};
    iir_image *img = (iir_image *)(uintptr_t)1; /* must be reset to NULL */
    iir_status st = iir_image_read(path, &img, &err);
    assert_null(img);
    assert_failed(st, &err, want, path);
}

/* ---- lifetime ------------------------------------------------------------------------------- */

static void test_create_limits(void **state)
{
    (void)state;
    assert_null(iir_image_create(0, 4));
    assert_null(iir_image_create(4, -1));
    assert_null(iir_image_create(IIR_IMAGE_MAX_DIM + 1, 1));
    iir_image *img = iir_image_create(3, 2);
    assert_non_null(img);
    assert_int_equal(img->width, 3);
    assert_int_equal(img->height, 2);
    for (int i = 0; i < 6; i++) assert_true(iir_is_black(img->pixels[i]));
    iir_image_destroy(NULL);
    iir_image_destroy(img);
}

static void test_clear_and_copy(void **state)
{
    (void)state;
    iir_image *a = make_hdr_image(5, 3), *b = iir_image_create(5, 3);
    iir_image_copy(b, a);
    assert_same_bits(a, b);
    iir_image_clear(a);
    for (int i = 0; i < 15; i++) assert_true(iir_is_black(a->pixels[i]));
    assert_false(iir_is_black(b->pixels[1]));
    iir_image_destroy(a);
    iir_image_destroy(b);
}

/* ---- sRGB tone mapping ---------------------------------------------------------------------- */

static uint8_t srgb8_reference(double v)
{
    v = v < 0.0 ? 0.0 : (v > 1.0 ? 1.0 : v);
    double e = v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return (uint8_t)lround(e * 255.0);
}

static uint8_t map_one(float v, float exposure)
{
    iir_image *img = iir_image_create(1, 1);
    img->pixels[0] = iir_v3s(v);
    uint8_t rgb[3];
    iir_image_to_srgb8(img, exposure, rgb);
    iir_image_destroy(img);
    assert_int_equal(rgb[0], rgb[1]);
    assert_int_equal(rgb[1], rgb[2]);
    return rgb[0];
}

static void test_srgb8_known_values(void **state)
{
    (void)state;
    assert_int_equal(map_one(0.f, 0.f), 0);
    assert_int_equal(map_one(1.f, 0.f), 255);
    assert_int_equal(map_one(0.5f, 0.f), 188);
    assert_int_equal(map_one(0.25f, 0.f), 137);
    assert_int_equal(map_one(0.001f, 0.f), 3); /* linear toe: 12.92 * 0.001 * 255 = 3.29 */
    assert_int_equal(map_one(4.f, 0.f), 255);  /* clamped */
    assert_int_equal(map_one(-1.f, 0.f), 0);
    assert_int_equal(map_one(NAN, 0.f), 0);
    assert_int_equal(map_one(INFINITY, 0.f), 255);
    /* exposure +1 doubles, -1 halves */
    assert_int_equal(map_one(0.25f, 1.f), 188);
    assert_int_equal(map_one(0.5f, 1.f), 255);
    assert_int_equal(map_one(1.f, -1.f), 188);
}

/* Every code of a dense sweep matches the OETF rounded directly. */
static void test_srgb8_matches_formula(void **state)
{
    (void)state;
    const int n = 4099;
    iir_image *img = iir_image_create(n, 1);
    for (int i = 0; i < n; i++) {
        double t = (double)i / (n - 1);
        img->pixels[i] = iir_v3((float)(t * t * t), (float)(t * t), (float)t);
    }
    uint8_t *rgb = malloc((size_t)n * 3);
    iir_image_to_srgb8(img, 0.f, rgb);
    for (int i = 0; i < n; i++) {
        const float *c = &img->pixels[i].x;
        for (int k = 0; k < 3; k++)
            if (rgb[3 * i + k] != srgb8_reference(c[k]))
                fail_msg("value %.9g maps to %d, expected %d", c[k], rgb[3 * i + k],
                         srgb8_reference(c[k]));
    }
    free(rgb);
    iir_image_destroy(img);
}

/* ---- PNG ------------------------------------------------------------------------------------ */

/* Reads an 8-bit RGB PNG with libpng's low-level API (no transforms) into rgb[w*h*3]. */
static void read_png_rgb8(const char *path, int w, int h, uint8_t *rgb)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    assert_non_null(png);
    assert_non_null(info);
    if (setjmp(png_jmpbuf(png))) fail_msg("libpng could not read %s", path);
    png_init_io(png, f);
    png_read_png(png, info, PNG_TRANSFORM_IDENTITY, NULL);
    assert_int_equal(png_get_image_width(png, info), w);
    assert_int_equal(png_get_image_height(png, info), h);
    assert_int_equal(png_get_bit_depth(png, info), 8);
    assert_int_equal(png_get_color_type(png, info), PNG_COLOR_TYPE_RGB);
    png_bytepp rows = png_get_rows(png, info);
    for (int y = 0; y < h; y++) memcpy(rgb + (size_t)y * w * 3, rows[y], (size_t)w * 3);
    png_destroy_read_struct(&png, &info, NULL);
    fclose(f);
}

static void test_png_values(void **state)
{
    (void)state;
    /* 3x2, non-square so that a transposition would show */
    const float in[6] = {0.f, 1.f, 0.5f, 0.25f, 2.f, 0.001f};
    const uint8_t want0[6] = {0, 255, 188, 137, 255, 3};
    const uint8_t want1[6] = {0, 255, 255, 188, 255, 7}; /* exposure +1: 0.002 -> 6.6 -> 7 */
    iir_image *img = iir_image_create(3, 2);
    for (int i = 0; i < 6; i++) img->pixels[i] = iir_v3(in[i], in[5 - i], 0.f);
    char path[1024];
    uint8_t rgb[18];
    const float exposures[2] = {0.f, 1.f};
    const uint8_t *wants[2] = {want0, want1};
    for (int e = 0; e < 2; e++) {
        iir_error err = {0};
        scratch_path(path, sizeof path, e ? "values_plus1.PNG" : "values.png");
        assert_int_equal(iir_image_write(img, path, exposures[e], &err), IIR_OK);
        read_png_rgb8(path, 3, 2, rgb);
        for (int i = 0; i < 6; i++) {
            assert_int_equal(rgb[3 * i + 0], wants[e][i]);
            assert_int_equal(rgb[3 * i + 1], wants[e][5 - i]);
            assert_int_equal(rgb[3 * i + 2], 0);
        }
    }
    iir_image_destroy(img);
}

/* The whole file at path, malloc'ed; *n its length. */
static uint8_t *read_bytes(const char *path, size_t *n)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    assert_int_equal(fseek(f, 0, SEEK_END), 0);
    long len = ftell(f);
    assert_true(len > 0);
    rewind(f);
    uint8_t *data = malloc((size_t)len);
    assert_non_null(data);
    assert_int_equal(fread(data, 1, (size_t)len, f), (size_t)len);
    fclose(f);
    *n = (size_t)len;
    return data;
}

/* The encoder's bytes must be the file writer's, byte for byte (one encoder per format). */
static void assert_file_holds(const char *path, const uint8_t *data, size_t size)
{
    size_t n = 0;
    uint8_t *file = read_bytes(path, &n);
    assert_int_equal(n, size);
    assert_memory_equal(file, data, size);
    free(file);
}

static void test_png_encode_in_memory(void **state)
{
    (void)state;
    iir_image *img = make_hdr_image(7, 5);
    for (size_t i = 0; i < 35; i++) img->pixels[i] = iir_scale(img->pixels[i], 0.01f);
    uint8_t *data = NULL;
    size_t size = 0;
    iir_error err = {0};
    assert_int_equal(iir_image_encode_png(img, 0.5f, &data, &size, &err), IIR_OK);
    assert_non_null(data);
    assert_true(size > 8);
    assert_memory_equal(data, "\x89PNG\r\n\x1a\n", 8);

    /* libpng decodes it to exactly the tone-mapped pixels */
    png_image png = {.version = PNG_IMAGE_VERSION};
    assert_true(png_image_begin_read_from_memory(&png, data, size));
    assert_int_equal(png.width, 7);
    assert_int_equal(png.height, 5);
    png.format = PNG_FORMAT_RGB;
    uint8_t got[7 * 5 * 3], want[7 * 5 * 3];
    assert_true(png_image_finish_read(&png, NULL, got, 0, NULL));
    iir_image_to_srgb8(img, 0.5f, want);
    assert_memory_equal(got, want, sizeof want);

    char path[1024];
    scratch_path(path, sizeof path, "encoded.png");
    assert_int_equal(iir_image_write_png(img, path, 0.5f, &err), IIR_OK);
    assert_file_holds(path, data, size);
    free(data);
    iir_image_destroy(img);
}

/* ---- EXR ------------------------------------------------------------------------------------ */

static void test_exr_encode_in_memory(void **state)
{
    (void)state;
    const int sizes[2][2] = {{7, 5}, {3, 40}}; /* 40 rows: several ZIP chunks, a partial last */
    for (int k = 0; k < 2; k++) {
        iir_image *img = make_hdr_image(sizes[k][0], sizes[k][1]), *back = NULL;
        uint8_t *data = NULL;
        size_t size = 0;
        iir_error err = {0};
        assert_int_equal(iir_image_encode_exr(img, &data, &size, &err), IIR_OK);
        assert_non_null(data);
        assert_memory_equal(data, "\x76\x2f\x31\x01", 4); /* the EXR magic number */

        /* the same bytes as the file writer's, and the reader gets the pixels back bit for bit */
        char path[1024];
        scratch_path(path, sizeof path, "encoded.exr");
        assert_int_equal(iir_image_write_exr(img, path, &err), IIR_OK);
        assert_file_holds(path, data, size);
        write_bytes(scratch_path(path, sizeof path, "from_memory.exr"), data, size);
        assert_int_equal(iir_image_read_exr(path, &back, &err), IIR_OK);
        assert_same_bits(img, back);
        iir_image_destroy(back);
        free(data);
        iir_image_destroy(img);
    }
}

static void test_exr_roundtrip_bit_exact(void **state)
{
    (void)state;
    const int sizes[3][2] = {{7, 5}, {1, 33}, {40, 3}}; /* 33 rows: a partial last ZIP chunk */
    for (int s = 0; s < 3; s++) {
        iir_image *img = make_hdr_image(sizes[s][0], sizes[s][1]), *back = NULL;
        char path[1024];
        iir_error err = {0};
        scratch_path(path, sizeof path, s == 1 ? "roundtrip.EXR" : "roundtrip.exr");
        assert_int_equal(iir_image_write(img, path, 3.f /* ignored */, &err), IIR_OK);
        assert_int_equal(iir_image_read(path, &back, &err), IIR_OK);
        assert_non_null(back);
        assert_same_bits(img, back);
        iir_image_destroy(back);
        iir_image_destroy(img);
    }
}

/* An EXR written in the test with the C API directly, to feed the reader what other tools
 * write: any channel set, pixel type, data window origin, scanline or 4x4 tiles. */
typedef struct raw_exr {
    int w, h, min_x, min_y;
    int tiled;
    exr_pixel_type_t type;
    int nch;
    const char *names[4];
    const void *planes[4]; /* one w*h plane per channel */
} raw_exr;

static size_t raw_elem_size(exr_pixel_type_t t)
{
    return t == EXR_PIXEL_HALF ? 2 : 4;
}

/* (x0, y0): the chunk's first pixel relative to the data window. */
static void raw_point(exr_encode_pipeline_t *enc, const raw_exr *r, int x0, int y0)
{
    size_t es = raw_elem_size(r->type);
    for (int c = 0; c < enc->channel_count; c++) {
        exr_coding_channel_info_t *ch = &enc->channels[c];
        int j = 0;
        while (j < r->nch && strcmp(r->names[j], ch->channel_name)) j++;
        assert_true(j < r->nch);
        size_t off = (size_t)y0 * (size_t)r->w + (size_t)x0;
        ch->encode_from_ptr = (const uint8_t *)r->planes[j] + off * es;
        ch->user_pixel_stride = (int32_t)es;
        ch->user_line_stride = (int32_t)(es * (size_t)r->w);
        ch->user_data_type = (uint16_t)r->type;
        ch->user_bytes_per_element = (int16_t)es;
    }
}

static void raw_chunk(exr_context_t ctx, exr_encode_pipeline_t *enc, const raw_exr *r,
                      const exr_chunk_info_t *ci, int x0, int y0)
{
    int first = enc->channels == NULL;
    assert_int_equal(first ? exr_encoding_initialize(ctx, 0, ci, enc)
                           : exr_encoding_update(ctx, 0, ci, enc),
                     EXR_ERR_SUCCESS);
    raw_point(enc, r, x0, y0);
    if (first) assert_int_equal(exr_encoding_choose_default_routines(ctx, 0, enc), 0);
    assert_int_equal(exr_encoding_run(ctx, 0, enc), EXR_ERR_SUCCESS);
}

static void raw_header(exr_context_t ctx, const raw_exr *r)
{
    int part = -1;
    assert_int_equal(
        exr_add_part(ctx, NULL, r->tiled ? EXR_STORAGE_TILED : EXR_STORAGE_SCANLINE, &part), 0);
    exr_attr_box2i_t dw;
    dw.min.x = r->min_x;
    dw.min.y = r->min_y;
    dw.max.x = r->min_x + r->w - 1;
    dw.max.y = r->min_y + r->h - 1;
    exr_attr_v2f_t center;
    center.x = center.y = 0.f;
    assert_int_equal(exr_initialize_required_attr(
                         ctx, part, &dw, &dw, 1.f, &center, 1.f, EXR_LINEORDER_INCREASING_Y,
                         r->tiled ? EXR_COMPRESSION_ZIP : EXR_COMPRESSION_NONE),
                     0);
    if (r->tiled)
        assert_int_equal(
            exr_set_tile_descriptor(ctx, part, 4, 4, EXR_TILE_ONE_LEVEL, EXR_TILE_ROUND_DOWN), 0);
    for (int c = 0; c < r->nch; c++)
        assert_int_equal(
            exr_add_channel(ctx, part, r->names[c], r->type, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1),
            0);
    assert_int_equal(exr_write_header(ctx), 0);
}

static void write_raw_exr(const char *path, const raw_exr *r)
{
    exr_context_t ctx = NULL;
    assert_int_equal(exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, NULL), 0);
    raw_header(ctx, r);
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    exr_chunk_info_t ci;
    if (r->tiled) {
        for (int ty = 0; ty < (r->h + 3) / 4; ty++)
            for (int tx = 0; tx < (r->w + 3) / 4; tx++) {
                assert_int_equal(exr_write_tile_chunk_info(ctx, 0, tx, ty, 0, 0, &ci), 0);
                raw_chunk(ctx, &enc, r, &ci, 4 * tx, 4 * ty); /* ci has tile indices */
            }
    } else {
        int32_t lines = 0;
        assert_int_equal(exr_get_scanlines_per_chunk(ctx, 0, &lines), 0);
        for (int y = r->min_y; y < r->min_y + r->h; y += lines) {
            assert_int_equal(exr_write_scanline_chunk_info(ctx, 0, y, &ci), 0);
            raw_chunk(ctx, &enc, r, &ci, 0, y - r->min_y);
        }
    }
    exr_encoding_destroy(ctx, &enc);
    assert_int_equal(exr_finish(&ctx), 0);
}

/* HALF channels (plus an alpha the reader must skip), data window at (3, -2), scanlines. */
static void test_exr_reads_half(void **state)
{
    (void)state;
    enum { W = 3, H = 2 };
    /* 0, 1, 0.5, 2, -4, 65504 (max half), 2^-24 (smallest subnormal) */
    const uint16_t bits[7] = {0x0000, 0x3C00, 0x3800, 0x4000, 0xC400, 0x7BFF, 0x0001};
    const float vals[7] = {0.f, 1.f, 0.5f, 2.f, -4.f, 65504.f, 5.9604644775390625e-8f};
    uint16_t r[W * H], g[W * H], b[W * H], a[W * H];
    for (int i = 0; i < W * H; i++) {
        r[i] = bits[i % 7];
        g[i] = bits[(i + 1) % 7];
        b[i] = bits[(i + 5) % 7];
        a[i] = 0x3C00;
    }
    raw_exr raw = {W, H, 3, -2, 0, EXR_PIXEL_HALF, 4, {"A", "B", "G", "R"}, {a, b, g, r}};
    char path[1024];
    scratch_path(path, sizeof path, "half.exr");
    write_raw_exr(path, &raw);
    iir_image *img = NULL;
    iir_error err = {0};
    assert_int_equal(iir_image_read_exr(path, &img, &err), IIR_OK);
    assert_int_equal(img->width, W);
    assert_int_equal(img->height, H);
    for (int i = 0; i < W * H; i++) {
        assert_true(img->pixels[i].x == vals[i % 7]);
        assert_true(img->pixels[i].y == vals[(i + 1) % 7]);
        assert_true(img->pixels[i].z == vals[(i + 5) % 7]);
    }
    iir_image_destroy(img);
}

/* UINT channels in 4x4 tiles over a 6x5 image (partial edge tiles). */
static void test_exr_reads_uint_tiled(void **state)
{
    (void)state;
    enum { W = 6, H = 5 };
    uint32_t r[W * H], g[W * H], b[W * H];
    for (int i = 0; i < W * H; i++) {
        r[i] = (uint32_t)i;
        g[i] = (uint32_t)i * 1000u;
        b[i] = i == 0 ? 4294967295u : 7u;
    }
    raw_exr raw = {W, H, 0, 0, 1, EXR_PIXEL_UINT, 3, {"B", "G", "R"}, {b, g, r}};
    char path[1024];
    scratch_path(path, sizeof path, "uint_tiled.exr");
    write_raw_exr(path, &raw);
    iir_image *img = NULL;
    iir_error err = {0};
    assert_int_equal(iir_image_read(path, &img, &err), IIR_OK);
    assert_int_equal(img->width, W);
    assert_int_equal(img->height, H);
    for (int i = 0; i < W * H; i++) {
        assert_true(img->pixels[i].x == (float)i);
        assert_true(img->pixels[i].y == (float)i * 1000.f);
        assert_true(img->pixels[i].z == (i == 0 ? 4294967296.f : 7.f));
    }
    iir_image_destroy(img);
}

static void test_exr_missing_channel(void **state)
{
    (void)state;
    float r[4] = {1, 2, 3, 4}, g[4] = {0};
    raw_exr raw = {2, 2, 0, 0, 0, EXR_PIXEL_FLOAT, 2, {"G", "R"}, {g, r}};
    char path[1024];
    scratch_path(path, sizeof path, "no_blue.exr");
    write_raw_exr(path, &raw);
    iir_error err = {0};
    iir_image *img = NULL;
    iir_status st = iir_image_read(path, &img, &err);
    assert_null(img);
    assert_failed(st, &err, IIR_ERR_FORMAT, path);
    if (!strstr(err.msg, "no B channel")) fail_msg("message \"%s\" does not name B", err.msg);
}

/* ---- PFM ------------------------------------------------------------------------------------ */

static void test_pfm_roundtrip_bit_exact(void **state)
{
    (void)state;
    const int sizes[3][2] = {{7, 5}, {1, 9}, {12, 2}};
    for (int s = 0; s < 3; s++) {
        iir_image *img = make_hdr_image(sizes[s][0], sizes[s][1]), *back = NULL;
        img->pixels[0].y = NAN;
        img->pixels[1].x = -INFINITY;
        char path[1024];
        iir_error err = {0};
        scratch_path(path, sizeof path, s == 2 ? "roundtrip.Pfm" : "roundtrip.pfm");
        assert_int_equal(iir_image_write(img, path, 0.f, &err), IIR_OK);
        assert_int_equal(iir_image_read(path, &back, &err), IIR_OK);
        assert_same_bits(img, back);
        iir_image_destroy(back);
        iir_image_destroy(img);
    }
}

static uint32_t le32(const uint8_t *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* The file itself: "PF", little-endian scale -1, and the bottom image row stored first. */
static void test_pfm_layout_on_disk(void **state)
{
    (void)state;
    iir_image *img = iir_image_create(2, 3);
    for (int i = 0; i < 6; i++) img->pixels[i] = iir_v3((float)i, 10.f + i, 20.f + i);
    char path[1024];
    iir_error err = {0};
    scratch_path(path, sizeof path, "layout.pfm");
    assert_int_equal(iir_image_write_pfm(img, path, &err), IIR_OK);
    uint8_t buf[256];
    FILE *f = fopen(path, "rb");
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    const char *header = "PF\n2 3\n-1.0\n";
    size_t hl = strlen(header);
    assert_int_equal(n, hl + 6 * 12);
    assert_memory_equal(buf, header, hl);
    for (int r = 0; r < 3; r++) {     /* file row r is image row 2 - r */
        for (int k = 0; k < 6; k++) { /* 2 pixels x 3 channels */
            uint32_t u = le32(buf + hl + (size_t)(r * 6 + k) * 4);
            float v;
            memcpy(&v, &u, sizeof v);
            const float *src = &img->pixels[(2 - r) * 2 + k / 3].x;
            assert_true(v == src[k % 3]);
        }
    }
    iir_image_destroy(img);
}

static void put_be32(uint8_t *p, float v)
{
    uint32_t u;
    memcpy(&u, &v, sizeof u);
    p[0] = (uint8_t)(u >> 24);
    p[1] = (uint8_t)(u >> 16);
    p[2] = (uint8_t)(u >> 8);
    p[3] = (uint8_t)u;
}

/* Other writers' files: big-endian colour, and little-endian grey "Pf". */
static void test_pfm_reads_big_endian_and_grey(void **state)
{
    (void)state;
    char path[1024];
    uint8_t buf[256];
    /* big-endian 2x1 colour, odd but legal whitespace in the header */
    const char *hdr = "PF \n 2   1\n4.0\n";
    size_t hl = strlen(hdr);
    memcpy(buf, hdr, hl);
    for (int k = 0; k < 6; k++) put_be32(buf + hl + 4 * k, 0.5f * (float)(k + 1));
    scratch_path(path, sizeof path, "be.pfm");
    write_bytes(path, buf, hl + 24);
    iir_image *img = NULL;
    iir_error err = {0};
    assert_int_equal(iir_image_read(path, &img, &err), IIR_OK);
    assert_int_equal(img->width, 2);
    assert_int_equal(img->height, 1);
    assert_true(img->pixels[0].x == 0.5f && img->pixels[0].z == 1.5f);
    assert_true(img->pixels[1].x == 2.0f && img->pixels[1].z == 3.0f);
    iir_image_destroy(img);

    /* little-endian 1x2 grey: bottom row (file first) 7, top row 9 */
    hdr = "Pf\n1 2\n-1\n";
    hl = strlen(hdr);
    memcpy(buf, hdr, hl);
    float grey[2] = {7.f, 9.f};
    for (int k = 0; k < 2; k++) {
        uint32_t u;
        memcpy(&u, &grey[k], 4);
        for (int b = 0; b < 4; b++) buf[hl + 4 * k + b] = (uint8_t)(u >> (8 * b));
    }
    scratch_path(path, sizeof path, "grey.pfm");
    write_bytes(path, buf, hl + 8);
    assert_int_equal(iir_image_read_pfm(path, &img, &err), IIR_OK);
    assert_true(img->pixels[0].x == 9.f && img->pixels[0].y == 9.f && img->pixels[0].z == 9.f);
    assert_true(img->pixels[1].x == 7.f && img->pixels[1].z == 7.f);
    iir_image_destroy(img);
}

/* ---- bad input ------------------------------------------------------------------------------ */

static void test_read_missing_files(void **state)
{
    (void)state;
    char path[1024];
    read_expect_failure(scratch_path(path, sizeof path, "does_not_exist.pfm"), IIR_ERR_IO);
    read_expect_failure(scratch_path(path, sizeof path, "does_not_exist.exr"), IIR_ERR_IO);
}

static void test_read_empty_files(void **state)
{
    (void)state;
    char path[1024];
    write_bytes(scratch_path(path, sizeof path, "empty.pfm"), "", 0);
    read_expect_failure(path, IIR_ERR_FORMAT);
    write_bytes(scratch_path(path, sizeof path, "empty.exr"), "", 0);
    iir_error err = {0};
    iir_image *img = NULL;
    iir_status st = iir_image_read(path, &img, &err);
    assert_null(img);
    assert_int_not_equal(st, IIR_OK);
    if (!strstr(err.msg, path)) fail_msg("message \"%s\" does not name %s", err.msg, path);
}

static void test_read_text_named_exr(void **state)
{
    (void)state;
    char path[1024];
    const char *text = "this is not an OpenEXR file, just some text\n";
    write_bytes(scratch_path(path, sizeof path, "text.exr"), text, strlen(text));
    read_expect_failure(path, IIR_ERR_FORMAT);
}

/* An EXR cut in the header and one cut in the pixel data. */
static void test_exr_truncated(void **state)
{
    (void)state;
    iir_image *img = make_hdr_image(64, 40);
    char path[1024];
    iir_error err = {0};
    assert_int_equal(iir_image_write(img, scratch_path(path, sizeof path, "whole.exr"), 0.f, &err),
                     IIR_OK);
    iir_image_destroy(img);
    FILE *f = fopen(path, "rb");
    static uint8_t buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf, f);
    fclose(f);
    assert_true(n > 1000 && n < sizeof buf);
    const size_t cuts[2] = {100, n / 2};
    const char *names[2] = {"cut_header.exr", "cut_pixels.exr"};
    for (int i = 0; i < 2; i++) {
        write_bytes(scratch_path(path, sizeof path, names[i]), buf, cuts[i]);
        read_expect_failure(path, IIR_ERR_FORMAT);
    }
}

static void test_pfm_truncated(void **state)
{
    (void)state;
    char path[1024];
    uint8_t buf[64] = {0};
    const char *hdr = "PF\n4 4\n-1.0\n";
    memcpy(buf, hdr, strlen(hdr)); /* 4x4 RGB needs 192 bytes; give 40 */
    write_bytes(scratch_path(path, sizeof path, "truncated.pfm"), buf, strlen(hdr) + 40);
    read_expect_failure(path, IIR_ERR_FORMAT);
    iir_error err = {0};
    iir_image *img = NULL;
    iir_image_read(path, &img, &err);
    if (!strstr(err.msg, "truncated")) fail_msg("message \"%s\" lacks the reason", err.msg);
}

static void test_pfm_bad_headers(void **state)
{
    (void)state;
    static const char *const headers[] = {
        "PF\n100000000 100000000\n-1.0\n", /* absurd dimensions */
        "PF\n99999999999999999999 2\n-1.0\n",
        "PF\n0 4\n-1.0\n",
        "PF\n-3 4\n-1.0\n",
        "PF\nabc 4\n-1.0\n",
        "PF\n4 4\n0.0\n", /* no endianness */
        "PF\n4 4\nnan\n",
        "P6\n4 4\n255\n", /* a PPM */
        "PF\n4",          /* cut short */
        "PFX\n1 1\n-1\n",
    };
    char path[1024], name[32];
    for (size_t i = 0; i < sizeof headers / sizeof headers[0]; i++) {
        snprintf(name, sizeof name, "bad_header_%zu.pfm", i);
        write_bytes(scratch_path(path, sizeof path, name), headers[i], strlen(headers[i]));
        read_expect_failure(path, IIR_ERR_FORMAT);
    }
}

static void test_unknown_extensions(void **state)
{
    (void)state;
    iir_image *img = iir_image_create(2, 2);
    char path[1024];
    iir_error err = {0};
    const char *names[] = {"image.tiff", "no_extension", "dir.exr/file", "image.png"};
    for (int i = 0; i < 3; i++) {
        scratch_path(path, sizeof path, names[i]);
        assert_failed(iir_image_write(img, path, 0.f, &err), &err, IIR_ERR_UNSUPPORTED, path);
        assert_false(file_exists(path));
        read_expect_failure(path, IIR_ERR_UNSUPPORTED);
    }
    read_expect_failure(scratch_path(path, sizeof path, names[3]), IIR_ERR_IO); /* missing */
    iir_image_destroy(img);
}

/* A PNG read back: 8-bit sRGB decoded to linear, within the quantisation of 8 bits; a file that
 * is not a PNG is a format error naming it. */
static void test_png_read(void **state)
{
    (void)state;
    iir_image *img = iir_image_create(3, 2);
    for (int i = 0; i < 6; i++)
        img->pixels[i] = iir_v3(0.1f * i, 1.f - 0.15f * i, i == 2 ? 1.f : 0.f);
    char path[1024];
    iir_error err = {0};
    assert_int_equal(iir_image_write(img, scratch_path(path, sizeof path, "back.png"), 0.f, &err),
                     IIR_OK);
    iir_image *back = NULL;
    assert_int_equal(iir_image_read(path, &back, &err), IIR_OK);
    assert_int_equal(back->width, 3);
    assert_int_equal(back->height, 2);
    for (int i = 0; i < 6; i++) {
        iir_vec3 a = img->pixels[i], b = back->pixels[i];
        /* one 8-bit sRGB step is at most about 1.3% of a linear value above 0.05 */
        assert_true(fabsf(a.x - b.x) <= 0.02f * a.x + 0.002f);
        assert_true(fabsf(a.y - b.y) <= 0.02f * a.y + 0.002f);
        assert_true(fabsf(a.z - b.z) <= 0.02f * a.z + 0.002f);
    }
    iir_image_destroy(back);
    FILE *f = fopen(scratch_path(path, sizeof path, "fake.png"), "w");
    assert_non_null(f);
    fputs("not a png", f);
    fclose(f);
    read_expect_failure(path, IIR_ERR_FORMAT);
    iir_image_destroy(img);
}

static void test_write_into_missing_directory(void **state)
{
    (void)state;
    iir_image *img = make_hdr_image(4, 3);
    const char *names[] = {"no/such/dir/out.png", "no/such/dir/out.exr", "no/such/dir/out.pfm"};
    for (int i = 0; i < 3; i++) {
        char path[1024];
        iir_error err = {0};
        scratch_path(path, sizeof path, names[i]);
        assert_failed(iir_image_write(img, path, 0.f, &err), &err, IIR_ERR_IO, path);
    }
    iir_image_destroy(img);
}

/* ---- JPEG ----------------------------------------------------------------------------------- */

/* Smooth colour ramps away from black, where the sRGB curve is steep enough that 4:2:0 chroma
 * subsampling alone would move a channel by more than the tolerance below. */
static iir_image *make_gradient(int w, int h)
{
    iir_image *img = iir_image_create(w, h);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            *iir_image_at(img, x, y) =
                iir_v3(0.1f + 0.6f * (float)x / (float)w, 0.1f + 0.6f * (float)y / (float)h,
                       0.25f + 0.5f * (float)(x + y) / (float)(w + h));
    return img;
}

/* Decodes with libturbojpeg and compares with the tone-mapped source. */
static void assert_jpeg_close(const uint8_t *data, size_t size, const iir_image *src)
{
    tjhandle d = tjInitDecompress();
    int w = 0, h = 0, sub = 0, cs = 0;
    assert_int_equal(tjDecompressHeader3(d, data, (unsigned long)size, &w, &h, &sub, &cs), 0);
    assert_int_equal(w, src->width);
    assert_int_equal(h, src->height);
    size_t n = (size_t)w * (size_t)h * 3;
    uint8_t *got = malloc(n), *want = malloc(n);
    assert_int_equal(tjDecompress2(d, data, (unsigned long)size, got, w, 0, h, TJPF_RGB, 0), 0);
    iir_image_to_srgb8(src, 0.f, want);
    int max_diff = 0;
    double sum = 0.0;
    for (size_t i = 0; i < n; i++) {
        int diff = abs((int)got[i] - (int)want[i]);
        max_diff = diff > max_diff ? diff : max_diff;
        sum += diff;
    }
    free(got);
    free(want);
    tjDestroy(d);
    if (max_diff > 12 || sum / (double)n > 2.0)
        fail_msg("JPEG colours too far: max %d, mean %.2f", max_diff, sum / (double)n);
}

static void test_jpeg_encode_and_reuse(void **state)
{
    (void)state;
    iir_jpeg_encoder *enc = iir_jpeg_encoder_create();
    assert_non_null(enc);
    iir_image *img = make_gradient(64, 48), *small = make_gradient(32, 16);
    const uint8_t *d1 = NULL, *d2 = NULL, *d3 = NULL;
    size_t s1 = 0, s2 = 0, s3 = 0;
    iir_error err = {0};
    assert_int_equal(iir_jpeg_encode(enc, img, 0.f, 95, &d1, &s1, &err), IIR_OK);
    assert_true(s1 > 2 && d1[0] == 0xFF && d1[1] == 0xD8); /* SOI marker */
    assert_jpeg_close(d1, s1, img);
    assert_int_equal(iir_jpeg_encode(enc, img, 0.f, 95, &d2, &s2, &err), IIR_OK);
    assert_ptr_equal(d1, d2); /* same size: the buffer is reused */
    assert_int_equal(s1, s2);
    assert_jpeg_close(d2, s2, img);
    assert_int_equal(iir_jpeg_encode(enc, small, 0.f, 80, &d3, &s3, &err), IIR_OK);
    assert_ptr_equal(d1, d3); /* smaller: still the same buffer */
    assert_jpeg_close(d3, s3, small);
    iir_image_destroy(small);
    iir_image_destroy(img);
    iir_jpeg_encoder_destroy(enc);
}

static void test_jpeg_bad_quality(void **state)
{
    (void)state;
    iir_jpeg_encoder *enc = iir_jpeg_encoder_create();
    iir_image *img = make_gradient(8, 8);
    const uint8_t *data = (const uint8_t *)"x";
    size_t size = 1;
    iir_error err = {0};
    assert_int_equal(iir_jpeg_encode(enc, img, 0.f, 0, &data, &size, &err), IIR_ERR_INVALID);
    assert_null(data);
    assert_int_equal(size, 0);
    assert_int_equal(iir_jpeg_encode(enc, img, 0.f, 101, &data, &size, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "101"));
    iir_image_destroy(img);
    iir_jpeg_encoder_destroy(enc);
    iir_jpeg_encoder_destroy(NULL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_create_limits),
        cmocka_unit_test(test_clear_and_copy),
        cmocka_unit_test(test_srgb8_known_values),
        cmocka_unit_test(test_srgb8_matches_formula),
        cmocka_unit_test(test_png_values),
        cmocka_unit_test(test_png_encode_in_memory),
        cmocka_unit_test(test_exr_encode_in_memory),
        cmocka_unit_test(test_exr_roundtrip_bit_exact),
        cmocka_unit_test(test_exr_reads_half),
        cmocka_unit_test(test_exr_reads_uint_tiled),
        cmocka_unit_test(test_exr_missing_channel),
        cmocka_unit_test(test_pfm_roundtrip_bit_exact),
        cmocka_unit_test(test_pfm_layout_on_disk),
        cmocka_unit_test(test_pfm_reads_big_endian_and_grey),
        cmocka_unit_test(test_read_missing_files),
        cmocka_unit_test(test_read_empty_files),
        cmocka_unit_test(test_read_text_named_exr),
        cmocka_unit_test(test_exr_truncated),
        cmocka_unit_test(test_pfm_truncated),
        cmocka_unit_test(test_pfm_bad_headers),
        cmocka_unit_test(test_unknown_extensions),
        cmocka_unit_test(test_png_read),
        cmocka_unit_test(test_write_into_missing_directory),
        cmocka_unit_test(test_jpeg_encode_and_reuse),
        cmocka_unit_test(test_jpeg_bad_quality),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* texture_decode.c -- texture files to level 0 of a texture: PNG (libpng), JPEG (libturbojpeg)
 * from memory, EXR files (the image module), sniffing which is which; not filtering or mips
 * (texture.c).
 *
 * PNG goes through libpng's full API rather than the simplified one: the simplified reader
 * applies the file's gAMA / sRGB / iCCP chunks and premultiplies 16-bit output, while glTF says a
 * texture's encoding is its material slot's alone. libpng reports errors by longjmp: every value
 * that outlives the jump lives in a png_job the caller owns (not in the frame that calls setjmp),
 * so nothing is clobbered. */
#include "iir/image.h"
#include "iir/texture.h"
#include "texture_internal.h"

#include <errno.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <turbojpeg.h>

/* ======================== PNG ======================== */

typedef struct png_job {
    const uint8_t *data;
    size_t size, pos; /* bytes read so far */
    bool srgb;
    iir_texture *tex; /* made once the header is read; the caller frees it on error */
    png_bytep *rows;  /* into tex's level 0; the caller frees it */
    bool wide;        /* 16 bits a channel */
    iir_status st;    /* IIR_ERR_FORMAT unless the job gets further */
    char why[200];
} png_job;

static void png_on_error(png_structp png, png_const_charp msg)
{
    png_job *job = png_get_error_ptr(png);
    snprintf(job->why, sizeof job->why, "%s", msg);
    png_longjmp(png, 1);
}

static void png_on_warning(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg; /* ancillary-chunk trouble: the image itself is fine */
}

static void png_read_memory(png_structp png, png_bytep out, size_t n)
{
    png_job *job = png_get_io_ptr(png);
    if (n > job->size - job->pos) png_error(png, "the data ends early (truncated)");
    memcpy(out, job->data + job->pos, n);
    job->pos += n;
}

/* Reads the PNG into job->tex's level 0 as RGBA, 8 or 16 bits big-endian. Leaves job->st IIR_OK
 * on success; on failure job->st and job->why say why. */
static void png_run(png_job *job, png_structp png, png_infop info)
{
    if (setjmp(png_jmpbuf(png))) return;
    png_set_read_fn(png, job, png_read_memory);
    png_read_info(png, info);
    png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
    png_byte type = png_get_color_type(png, info);
    if (w > IIR_TEXTURE_MAX_DIM || h > IIR_TEXTURE_MAX_DIM) {
        job->st = IIR_ERR_UNSUPPORTED;
        snprintf(job->why, sizeof job->why, "%ux%u is larger than %d texels a side", (unsigned)w,
                 (unsigned)h, IIR_TEXTURE_MAX_DIM);
        return;
    }
    bool alpha = (type & PNG_COLOR_MASK_ALPHA) || png_get_valid(png, info, PNG_INFO_tRNS);
    png_set_expand(png); /* palette -> RGB, grey below 8 bits -> 8, tRNS -> alpha */
    if (!(type & PNG_COLOR_MASK_COLOR)) png_set_gray_to_rgb(png);
    if (!alpha) png_set_add_alpha(png, 0xffff, PNG_FILLER_AFTER);
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    job->wide = png_get_bit_depth(png, info) == 16;
    size_t row = (size_t)w * (job->wide ? 8 : 4);
    if (png_get_rowbytes(png, info) != row) png_error(png, "unexpected row layout");
    job->tex =
        iir_texture_alloc((int)w, (int)h, job->wide ? IIR_TEX_RGBA16 : IIR_TEX_RGBA8, job->srgb);
    job->rows = malloc((size_t)h * sizeof *job->rows);
    if (!job->tex || !job->rows) {
        job->st = IIR_ERR_NOMEM;
        snprintf(job->why, sizeof job->why, "out of memory for %ux%u texels", (unsigned)w,
                 (unsigned)h);
        return;
    }
    uint8_t *level0 = iir_texture_level0(job->tex);
    for (size_t y = 0; y < h; y++) job->rows[y] = level0 + y * row;
    png_read_image(png, job->rows);
    png_read_end(png, NULL);
    job->st = IIR_OK;
}

/* 16-bit big-endian codes in place to native linear RGBA16: colour through the sRGB EOTF when
 * srgb (a 65536-entry table, built once per image), alpha and data as they are. */
static iir_status png_widen(iir_texture *tex, bool srgb)
{
    uint16_t *table = NULL;
    if (srgb) {
        table = malloc(65536 * sizeof *table);
        if (!table) return IIR_ERR_NOMEM;
        for (int c = 0; c < 65536; c++)
            table[c] = (uint16_t)lround(iir_srgb_eotf(c / 65535.0) * 65535.0);
    }
    size_t n = 4 * (size_t)iir_texture_width(tex) * (size_t)iir_texture_height(tex);
    uint8_t *be = iir_texture_level0(tex);
    uint16_t *out = iir_texture_level0(tex);
    for (size_t i = 0; i < n; i++) {
        uint16_t v = (uint16_t)(be[2 * i] << 8 | be[2 * i + 1]);
        out[i] = table && i % 4 != 3 ? table[v] : v;
    }
    free(table);
    return IIR_OK;
}

static iir_status decode_png(const uint8_t *data, size_t size, const char *what, bool srgb,
                             iir_texture **out, iir_error *err)
{
    png_job job = {.data = data, .size = size, .srgb = srgb, .st = IIR_ERR_FORMAT};
    png_structp png =
        png_create_read_struct(PNG_LIBPNG_VER_STRING, &job, png_on_error, png_on_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!info) {
        png_destroy_read_struct(&png, NULL, NULL);
        return iir_fail(err, IIR_ERR_NOMEM, "cannot decode PNG %s: out of memory", what);
    }
    png_run(&job, png, info);
    png_destroy_read_struct(&png, &info, NULL);
    free(job.rows);
    if (job.st == IIR_OK && job.wide && png_widen(job.tex, srgb) != IIR_OK) {
        job.st = IIR_ERR_NOMEM;
        snprintf(job.why, sizeof job.why, "out of memory");
    }
    if (job.st != IIR_OK) {
        iir_texture_destroy(job.tex);
        return iir_fail(err, job.st, "cannot decode PNG %s: %s", what, job.why);
    }
    iir_texture_finish(job.tex);
    *out = job.tex;
    return IIR_OK;
}

/* ======================== JPEG ======================== */

/* Baseline or progressive, grey or YCbCr, decoded to RGBA8 (alpha 255). A warning from libjpeg
 * (a truncated or corrupt stream that it would fill with grey) fails like an error. */
static iir_status decode_jpeg(const uint8_t *data, size_t size, const char *what, bool srgb,
                              iir_texture **out, iir_error *err)
{
    tjhandle tj = tjInitDecompress();
    if (!tj) return iir_fail(err, IIR_ERR_NOMEM, "cannot decode JPEG %s: out of memory", what);
    int w = 0, h = 0, subsamp = 0, space = 0;
    iir_status st = IIR_OK;
    iir_texture *tex = NULL;
    if (tjDecompressHeader3(tj, data, (unsigned long)size, &w, &h, &subsamp, &space) != 0)
        st = iir_fail(err, IIR_ERR_FORMAT, "cannot decode JPEG %s: %s", what, tjGetErrorStr2(tj));
    else if (space == TJCS_CMYK || space == TJCS_YCCK)
        st = iir_fail(err, IIR_ERR_UNSUPPORTED, "cannot decode JPEG %s: CMYK is not decoded", what);
    else if (w < 1 || h < 1) /* a tables-only stream: no frame header */
        st = iir_fail(err, IIR_ERR_FORMAT, "cannot decode JPEG %s: it holds no image", what);
    else if (w > IIR_TEXTURE_MAX_DIM || h > IIR_TEXTURE_MAX_DIM)
        st = iir_fail(err, IIR_ERR_UNSUPPORTED,
                      "cannot decode JPEG %s: %dx%d is larger than %d texels a side", what, w, h,
                      IIR_TEXTURE_MAX_DIM);
    else if (!(tex = iir_texture_alloc(w, h, IIR_TEX_RGBA8, srgb)))
        st = iir_fail(err, IIR_ERR_NOMEM, "cannot decode JPEG %s: out of memory for %dx%d texels",
                      what, w, h);
    else if (tjDecompress2(tj, data, (unsigned long)size, iir_texture_level0(tex), w, 4 * w, h,
                           TJPF_RGBA, 0) != 0)
        st = iir_fail(err, IIR_ERR_FORMAT, "cannot decode JPEG %s: %s", what, tjGetErrorStr2(tj));
    tjDestroy(tj);
    if (st != IIR_OK) {
        iir_texture_destroy(tex);
        return st;
    }
    iir_texture_finish(tex);
    *out = tex;
    return IIR_OK;
}

/* ======================== EXR ======================== */

/* Linear RGB floats kept as they are, except what a lookup must not return: NaN and negative
 * values become 0, values above half's largest (65504, and infinities) become 65504. */
static float exr_value(float v)
{
    return v > 0.f ? fminf(v, 65504.f) : 0.f;
}

static iir_status read_exr(const char *path, iir_texture **out, iir_error *err)
{
    iir_image *img = NULL;
    iir_status st = iir_image_read_exr(path, &img, err);
    if (st != IIR_OK) return st;
    iir_texture *tex = iir_texture_alloc(img->width, img->height, IIR_TEX_RGBA32F, false);
    if (!tex) {
        st = iir_fail(err, IIR_ERR_NOMEM, "cannot read EXR %s: out of memory for %dx%d texels",
                      path, img->width, img->height);
        iir_image_destroy(img);
        return st;
    }
    float *p = iir_texture_level0(tex);
    for (size_t i = 0; i < (size_t)img->width * (size_t)img->height; i++) {
        p[4 * i] = exr_value(img->pixels[i].x);
        p[4 * i + 1] = exr_value(img->pixels[i].y);
        p[4 * i + 2] = exr_value(img->pixels[i].z);
        p[4 * i + 3] = 1.f;
    }
    iir_image_destroy(img);
    iir_texture_finish(tex);
    *out = tex;
    return IIR_OK;
}

/* ======================== sniffing and files ======================== */

static bool starts_with(const uint8_t *data, size_t size, const char *magic, size_t n)
{
    return size >= n && memcmp(data, magic, n) == 0;
}

iir_status iir_texture_decode(const void *data, size_t size, const char *what, bool srgb,
                              iir_texture **out, iir_error *err)
{
    *out = NULL;
    const uint8_t *d = data;
    if (!d || size == 0)
        return iir_fail(err, IIR_ERR_FORMAT, "cannot decode %s: it is empty", what);
    if (starts_with(d, size, "\x89PNG\r\n\x1a\n", 8))
        return decode_png(d, size, what, srgb, out, err);
    if (starts_with(d, size, "\xff\xd8\xff", 3)) return decode_jpeg(d, size, what, srgb, out, err);
    if (starts_with(d, size, "\x76\x2f\x31\x01", 4))
        return iir_fail(err, IIR_ERR_UNSUPPORTED,
                        "cannot decode %s: an EXR image is read from a file only", what);
    if (starts_with(d, size, "RIFF", 4) && size >= 12 && memcmp(d + 8, "WEBP", 4) == 0)
        return iir_fail(err, IIR_ERR_UNSUPPORTED,
                        "cannot decode %s: WebP (EXT_texture_webp) is not decoded", what);
    if (starts_with(d, size, "\xabKTX 20\xbb", 8))
        return iir_fail(err, IIR_ERR_UNSUPPORTED,
                        "cannot decode %s: KTX2 (KHR_texture_basisu) is not decoded", what);
    return iir_fail(err, IIR_ERR_FORMAT, "cannot decode %s: not a PNG or JPEG image", what);
}

static bool has_extension(const char *path, const char *ext)
{
    size_t n = strlen(path), k = strlen(ext);
    return n >= k && strcasecmp(path + n - k, ext) == 0;
}

/* The whole file in a malloc'ed buffer (*data, *size: the caller frees it). */
static iir_status read_file(const char *path, uint8_t **data, size_t *size, iir_error *err)
{
    *data = NULL;
    *size = 0;
    FILE *f = fopen(path, "rb");
    if (!f) return iir_fail(err, IIR_ERR_IO, "cannot read texture %s: %s", path, strerror(errno));
    size_t cap = 1 << 16, n = 0;
    uint8_t *buf = malloc(cap);
    while (buf) {
        n += fread(buf + n, 1, cap - n, f);
        if (n < cap) break;
        uint8_t *grown = cap <= SIZE_MAX / 2 ? realloc(buf, cap * 2) : NULL;
        if (!grown) {
            free(buf);
            buf = NULL;
            break;
        }
        buf = grown;
        cap *= 2;
    }
    bool failed = buf && ferror(f);
    int saved = errno;
    fclose(f);
    if (!buf) return iir_fail(err, IIR_ERR_NOMEM, "cannot read texture %s: out of memory", path);
    if (failed) {
        free(buf);
        return iir_fail(err, IIR_ERR_IO, "cannot read texture %s: %s", path, strerror(saved));
    }
    *data = buf;
    *size = n;
    return IIR_OK;
}

iir_status iir_texture_read(const char *path, bool srgb, iir_texture **out, iir_error *err)
{
    *out = NULL;
    if (has_extension(path, ".exr")) return read_exr(path, out, err);
    uint8_t *data = NULL;
    size_t size = 0;
    iir_status st = read_file(path, &data, &size, err);
    if (st == IIR_OK) st = iir_texture_decode(data, size, path, srgb, out, err);
    free(data);
    return st;
}

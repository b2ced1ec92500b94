/* image.c -- image lifetime, sRGB tone mapping, dispatch by extension, saving encoded bytes to a
 * file; not the file formats. */
#include "iir/image.h"
#include "image_internal.h"

#include <assert.h>
#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

/* ---- lifetime ---------------------------------------------------------------------------- */

iir_image *iir_image_create(int width, int height)
{
    if (width < 1 || width > IIR_IMAGE_MAX_DIM || height < 1 || height > IIR_IMAGE_MAX_DIM)
        return NULL;
    iir_image *img = calloc(1, sizeof *img);
    if (!img) return NULL;
    img->pixels = calloc((size_t)width * (size_t)height, sizeof *img->pixels);
    if (!img->pixels) {
        free(img);
        return NULL;
    }
    img->width = width;
    img->height = height;
    return img;
}

void iir_image_destroy(iir_image *img)
{
    if (!img) return;
    free(img->pixels);
    free(img);
}

void iir_image_clear(iir_image *img)
{
    memset(img->pixels, 0, (size_t)img->width * (size_t)img->height * sizeof *img->pixels);
}

void iir_image_copy(iir_image *dst, const iir_image *src)
{
    assert(dst->width == src->width && dst->height == src->height);
    memcpy(dst->pixels, src->pixels,
           (size_t)src->width * (size_t)src->height * sizeof *src->pixels);
}

/* ---- tone mapping -------------------------------------------------------------------------- */

/* Exact 8-bit sRGB without a pow per channel. t[k] (k = 1..255) is the smallest linear value whose
 * rounded code is k: the linear value of the code boundary (k - 0.5) / 255. The OETF is monotonic,
 * so a value's code is the number of boundaries at or below it. To find it fast, values in
 * [2^-13, 1) are bucketed by their float exponent and top 7 mantissa bits; a bucket holds the code
 * of its lower edge, which is at most one boundary below the code of any value in the bucket
 * (a bucket is 0.8% wide; the steepest part of the curve moves 0.9 codes across that; checked
 * over every float in [1e-5, 1]). Values below t[1] (> 2^-13), negative or NaN give 0; 1 and
 * above give 255. */
#define SRGB8_LO_EXP 13   /* buckets start at 2^-13 */
#define SRGB8_MANT_BITS 7 /* buckets per power of two: 2^7 */
#define SRGB8_BUCKETS (SRGB8_LO_EXP << SRGB8_MANT_BITS)

typedef struct srgb8_lut {
    float t[257]; /* t[0] = -inf and t[256] = +inf are sentinels */
    uint8_t bucket[SRGB8_BUCKETS];
    uint32_t lo_bits; /* bit pattern of 2^-13 */
} srgb8_lut;

/* Inverse of the sRGB OETF: encoded value e in [0,1] to linear. */
static double srgb_to_linear(double e)
{
    return e <= 0.04045 ? e / 12.92 : pow((e + 0.055) / 1.055, 2.4);
}

/* The sRGB OETF rounded to 8 bits, for v in [0, 1]: the definition the thresholds must match. */
static int srgb8_direct(float v)
{
    double e = v <= 0.0031308f ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055;
    return (int)lround(e * 255.0);
}

/* The smallest float whose code is k: the analytic boundary, nudged by an ulp or two so that
 * rounding of the boundary itself cannot disagree with srgb8_direct. */
static float srgb8_threshold(int k)
{
    float t = (float)srgb_to_linear((k - 0.5) / 255.0);
    while (srgb8_direct(t) < k) t = nextafterf(t, INFINITY);
    while (srgb8_direct(nextafterf(t, -INFINITY)) >= k) t = nextafterf(t, -INFINITY);
    return t;
}

/* Binary search: the number of boundaries t[1..255] at or below v. */
static int srgb8_search(const float t[257], float v)
{
    int code = 0;
    for (int step = 128; step > 0; step >>= 1)
        if (v >= t[code + step]) code += step;
    return code;
}

static void srgb8_lut_init(srgb8_lut *L)
{
    L->t[0] = -INFINITY;
    L->t[256] = INFINITY;
    for (int k = 1; k < 256; k++) L->t[k] = srgb8_threshold(k);
    L->lo_bits = iir_float_bits(ldexpf(1.f, -SRGB8_LO_EXP));
    for (uint32_t i = 0; i < SRGB8_BUCKETS; i++) {
        uint32_t edge = L->lo_bits + (i << (23 - SRGB8_MANT_BITS));
        float v;
        memcpy(&v, &edge, sizeof v);
        L->bucket[i] = (uint8_t)srgb8_search(L->t, v);
    }
}

static uint8_t srgb8_encode(const srgb8_lut *L, float v)
{
    if (!(v >= L->t[1])) return 0;
    if (v >= 1.f) return 255;
    int code = L->bucket[(iir_float_bits(v) - L->lo_bits) >> (23 - SRGB8_MANT_BITS)];
    while (v >= L->t[code + 1]) code++;
    return (uint8_t)code;
}

void iir_image_to_srgb8(const iir_image *img, float exposure, uint8_t *rgb)
{
    srgb8_lut L;
    srgb8_lut_init(&L);
    const float scale = exp2f(exposure);
    const size_t n = (size_t)img->width * (size_t)img->height;
    for (size_t i = 0; i < n; i++) {
        const iir_vec3 c = img->pixels[i];
        rgb[3 * i + 0] = srgb8_encode(&L, c.x * scale);
        rgb[3 * i + 1] = srgb8_encode(&L, c.y * scale);
        rgb[3 * i + 2] = srgb8_encode(&L, c.z * scale);
    }
}

/* ---- saving encoded bytes ------------------------------------------------------------------ */

iir_status iir_image_save_bytes(const char *path, const char *format, const uint8_t *data,
                                size_t size, iir_error *err)
{
    FILE *f = fopen(path, "wb");
    if (!f)
        return iir_fail(err, IIR_ERR_IO, "cannot create %s %s: %s", format, path, strerror(errno));
    bool ok = fwrite(data, 1, size, f) == size;
    int e = errno;
    if (fclose(f) != 0 && ok) ok = false, e = errno;
    if (ok) return IIR_OK;
    unlink(path);
    return iir_fail(err, IIR_ERR_IO, "cannot write %s %s: %s", format, path, strerror(e));
}

/* ---- dispatch by extension ----------------------------------------------------------------- */

/* The extension of the last path component (without the dot), or "" when there is none. */
static const char *path_extension(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(slash ? slash + 1 : path, '.');
    return dot ? dot + 1 : "";
}

iir_status iir_image_write(const iir_image *img, const char *path, float exposure, iir_error *err)
{
    const char *ext = path_extension(path);
    if (strcasecmp(ext, "png") == 0) return iir_image_write_png(img, path, exposure, err);
    if (strcasecmp(ext, "exr") == 0) return iir_image_write_exr(img, path, err);
    if (strcasecmp(ext, "pfm") == 0) return iir_image_write_pfm(img, path, err);
    return iir_fail(err, IIR_ERR_UNSUPPORTED,
                    "cannot write image %s: unknown extension \"%s\" (use .png, .exr or .pfm)",
                    path, ext);
}

iir_status iir_image_read(const char *path, iir_image **out, iir_error *err)
{
    *out = NULL;
    const char *ext = path_extension(path);
    if (strcasecmp(ext, "exr") == 0) return iir_image_read_exr(path, out, err);
    if (strcasecmp(ext, "pfm") == 0) return iir_image_read_pfm(path, out, err);
    if (strcasecmp(ext, "png") == 0) return iir_image_read_png(path, out, err);
    return iir_fail(err, IIR_ERR_UNSUPPORTED,
                    "cannot read image %s: unknown extension \"%s\" (readable: .exr, .pfm, .png)",
                    path, ext);
}

/* image_png.c -- 8-bit sRGB PNG through libpng's simplified API, into memory (a PNG file holds the
 * same bytes), and reading a PNG into linear RGB (emission maps). Not tone mapping (image.c). */
#include "iir/image.h"
#include "image_internal.h"

#include <errno.h>
#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The error of encoding for path (NULL: into memory). */
static iir_status png_failure(iir_error *err, iir_status st, const char *path, const char *why)
{
    if (path) return iir_fail(err, st, "cannot write PNG %s: %s", path, why);
    return iir_fail(err, st, "cannot encode PNG: %s", why);
}

/* Compresses rgb (width*height*3 bytes) into a buffer of libpng's worst-case size, then gives the
 * unused tail back. */
static iir_status compress_rgb(const iir_image *img, const uint8_t *rgb, const char *path,
                               uint8_t **data, size_t *size, iir_error *err)
{
    png_image png = {.version = PNG_IMAGE_VERSION,
                     .width = (png_uint_32)img->width,
                     .height = (png_uint_32)img->height,
                     .format = PNG_FORMAT_RGB};
    png_alloc_size_t n = PNG_IMAGE_PNG_SIZE_MAX(png);
    uint8_t *buf = malloc(n);
    if (!buf) return png_failure(err, IIR_ERR_NOMEM, path, "out of memory for the compressed data");
    if (!png_image_write_to_memory(&png, buf, &n, 0, rgb, 0, NULL)) {
        iir_status st = png_failure(err, IIR_ERR_INTERNAL, path, png.message);
        png_image_free(&png);
        free(buf);
        return st;
    }
    uint8_t *fit = realloc(buf, n);
    *data = fit ? fit : buf;
    *size = n;
    return IIR_OK;
}

/* The PNG's bytes; path (NULL: none) only names the file in messages. */
static iir_status encode_png(const iir_image *img, float exposure, const char *path, uint8_t **data,
                             size_t *size, iir_error *err)
{
    *data = NULL;
    *size = 0;
    uint8_t *rgb = malloc((size_t)img->width * (size_t)img->height * 3);
    if (!rgb) {
        char why[96];
        snprintf(why, sizeof why, "out of memory for %dx%d pixels", img->width, img->height);
        return png_failure(err, IIR_ERR_NOMEM, path, why);
    }
    iir_image_to_srgb8(img, exposure, rgb);
    iir_status st = compress_rgb(img, rgb, path, data, size, err);
    free(rgb);
    return st;
}

iir_status iir_image_encode_png(const iir_image *img, float exposure, uint8_t **data, size_t *size,
                                iir_error *err)
{
    return encode_png(img, exposure, NULL, data, size, err);
}

iir_status iir_image_write_png(const iir_image *img, const char *path, float exposure,
                               iir_error *err)
{
    uint8_t *data = NULL;
    size_t size = 0;
    iir_status st = encode_png(img, exposure, path, &data, &size, err);
    if (st == IIR_OK) st = iir_image_save_bytes(path, "PNG", data, size, err);
    free(data);
    return st;
}

/* The linear value of 8-bit sRGB code c (IEC 61966-2-1). */
static float srgb8_decode(uint8_t c)
{
    float v = (float)c / 255.f;
    return v <= 0.04045f ? v / 12.92f : powf((v + 0.055f) / 1.055f, 2.4f);
}

/* libpng converts the file to 8-bit sRGB (any bit depth, palette or gamma; alpha dropped), which is
 * decoded here with the exact sRGB curve (libpng's own linear output approximates it by a 2.2
 * power, up to 3% off in the mid-tones). */
iir_status iir_image_read_png(const char *path, iir_image **out, iir_error *err)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return iir_fail(err, IIR_ERR_IO, "cannot read PNG %s: %s", path, strerror(errno));
    fclose(f);
    png_image png = {.version = PNG_IMAGE_VERSION};
    if (!png_image_begin_read_from_file(&png, path))
        return iir_fail(err, IIR_ERR_FORMAT, "cannot read PNG %s: %s", path, png.message);
    png.format = PNG_FORMAT_RGB;
    iir_image *img = iir_image_create((int)png.width, (int)png.height);
    uint8_t *px = img ? malloc(PNG_IMAGE_SIZE(png)) : NULL;
    if (!px) {
        png_image_free(&png);
        iir_image_destroy(img);
        return iir_fail(err, IIR_ERR_NOMEM, "cannot read PNG %s: out of memory for %ux%u pixels",
                        path, (unsigned)png.width, (unsigned)png.height);
    }
    if (!png_image_finish_read(&png, NULL, px, 0, NULL)) {
        iir_status st = iir_fail(err, IIR_ERR_FORMAT, "cannot read PNG %s: %s", path, png.message);
        png_image_free(&png);
        free(px);
        iir_image_destroy(img);
        return st;
    }
    float lut[256];
    for (int c = 0; c < 256; c++) lut[c] = srgb8_decode((uint8_t)c);
    for (size_t i = 0; i < (size_t)img->width * (size_t)img->height; i++)
        img->pixels[i] = iir_v3(lut[px[3 * i]], lut[px[3 * i + 1]], lut[px[3 * i + 2]]);
    free(px);
    *out = img;
    return IIR_OK;
}

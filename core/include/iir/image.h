/* image.h -- float RGB images (linear, HDR) and their files: PNG (exposure + sRGB, libpng) and EXR
 * (OpenEXR C API, 32-bit float), encoded in memory or written to files, PFM (written and read
 * directly), and JPEG encoding for streamed frames (libturbojpeg). Not metrics (metrics.h). */
#ifndef IIR_IMAGE_H
#define IIR_IMAGE_H

#include <stddef.h>
#include <stdint.h>

#include "iir/status.h"
#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

#define IIR_IMAGE_MAX_DIM 16384

/* Row-major, top row first, width * height pixels of linear RGB. */
typedef struct iir_image {
    int width, height;
    iir_vec3 *pixels;
} iir_image;

/* Zero-filled image; NULL when a dimension is outside [1, IIR_IMAGE_MAX_DIM] or allocation fails.
 */
iir_image *iir_image_create(int width, int height);
void iir_image_destroy(iir_image *img);
void iir_image_clear(iir_image *img);
/* dst must have the same size as src. */
void iir_image_copy(iir_image *dst, const iir_image *src);

static inline iir_vec3 *iir_image_at(iir_image *img, int x, int y)
{
    return &img->pixels[(size_t)y * (size_t)img->width + (size_t)x];
}

/* Tone mapping shared by PNG and JPEG: value * 2^exposure, clamped to [0,1], sRGB-encoded, 8 bits.
 * rgb must hold width*height*3 bytes. */
void iir_image_to_srgb8(const iir_image *img, float exposure, uint8_t *rgb);

/* Writes by the extension of path: .png, .exr or .pfm (case-insensitive). Exposure (stops) applies
 * to PNG only; EXR and PFM keep the linear values. Errors name the path and the reason. */
iir_status iir_image_write(const iir_image *img, const char *path, float exposure, iir_error *err);
iir_status iir_image_write_png(const iir_image *img, const char *path, float exposure,
                               iir_error *err);
iir_status iir_image_write_exr(const iir_image *img, const char *path, iir_error *err);
iir_status iir_image_write_pfm(const iir_image *img, const char *path, iir_error *err);

/* The bytes of the PNG or EXR file that iir_image_write_png / iir_image_write_exr would write
 * (those writers encode with these, then save the bytes). On success *data is malloc'ed and the
 * caller frees it; *size is its length. On error *data is NULL, *size 0, and err says why
 * (IIR_ERR_NOMEM, or IIR_ERR_INTERNAL when the library fails). */
iir_status iir_image_encode_png(const iir_image *img, float exposure, uint8_t **data, size_t *size,
                                iir_error *err);
iir_status iir_image_encode_exr(const iir_image *img, uint8_t **data, size_t *size, iir_error *err);

/* Reads .exr (R, G, B channels, any pixel type), .pfm (colour "PF" or grey "Pf") or .png (8 or 16
 * bits, decoded from sRGB to linear, alpha dropped). On error *out stays NULL and err names the
 * file and the problem. */
iir_status iir_image_read(const char *path, iir_image **out, iir_error *err);
iir_status iir_image_read_png(const char *path, iir_image **out, iir_error *err);
iir_status iir_image_read_exr(const char *path, iir_image **out, iir_error *err);
iir_status iir_image_read_pfm(const char *path, iir_image **out, iir_error *err);

/* A reusable JPEG encoder (one per thread; owns its output buffer, so steady-state encoding does
 * not allocate). */
typedef struct iir_jpeg_encoder iir_jpeg_encoder;
iir_jpeg_encoder *iir_jpeg_encoder_create(void);
void iir_jpeg_encoder_destroy(iir_jpeg_encoder *enc);
/* Encodes img (tone-mapped as iir_image_to_srgb8) at quality 1..100. *data points into the encoder
 * and stays valid until the next call or destroy. */
iir_status iir_jpeg_encode(iir_jpeg_encoder *enc, const iir_image *img, float exposure, int quality,
                           const uint8_t **data, size_t *size, iir_error *err);

#ifdef __cplusplus
}
#endif
#endif

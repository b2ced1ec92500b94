/* image_jpeg.c -- the reusable JPEG encoder for streamed frames; not how frames are sent. */

/* The encoder keeps its RGB8 scratch and its JPEG output buffer between calls and only grows them
 * when a frame is larger than any before it. The output buffer is sized with tjBufSize (the worst
 * case for the chosen subsampling) and TJFLAG_NOREALLOC forbids libturbojpeg to replace it, so a
 * steady stream of same-sized frames allocates nothing here. One encoder per thread. */
#include "iir/image.h"

#include <limits.h>
#include <stdlib.h>
#include <turbojpeg.h>

#define IIR_JPEG_SUBSAMP TJSAMP_420

struct iir_jpeg_encoder {
    tjhandle tj;
    uint8_t *rgb; /* tone-mapped input, rgb_cap bytes */
    size_t rgb_cap;
    unsigned char *jpeg; /* output, from tjAlloc, jpeg_cap bytes */
    unsigned long jpeg_cap;
};

iir_jpeg_encoder *iir_jpeg_encoder_create(void)
{
    iir_jpeg_encoder *enc = calloc(1, sizeof *enc);
    if (!enc) return NULL;
    enc->tj = tjInitCompress();
    if (!enc->tj) {
        free(enc);
        return NULL;
    }
    return enc;
}

void iir_jpeg_encoder_destroy(iir_jpeg_encoder *enc)
{
    if (!enc) return;
    tjDestroy(enc->tj);
    tjFree(enc->jpeg);
    free(enc->rgb);
    free(enc);
}

/* Grows the scratch and output buffers to fit a w x h frame; keeps them when they already do. */
static iir_status reserve_buffers(iir_jpeg_encoder *enc, int w, int h, iir_error *err)
{
    size_t rgb_need = (size_t)w * (size_t)h * 3;
    if (rgb_need > enc->rgb_cap) {
        uint8_t *rgb = realloc(enc->rgb, rgb_need);
        if (!rgb) return iir_fail(err, IIR_ERR_NOMEM, "JPEG encoder: no memory for %dx%d", w, h);
        enc->rgb = rgb;
        enc->rgb_cap = rgb_need;
    }
    unsigned long jpeg_need = tjBufSize(w, h, IIR_JPEG_SUBSAMP);
    if (jpeg_need == (unsigned long)-1 || jpeg_need > (unsigned long)INT_MAX)
        return iir_fail(err, IIR_ERR_INVALID, "JPEG encoder: cannot size a %dx%d frame", w, h);
    if (jpeg_need > enc->jpeg_cap) {
        unsigned char *jpeg = tjAlloc((int)jpeg_need);
        if (!jpeg) return iir_fail(err, IIR_ERR_NOMEM, "JPEG encoder: no memory for %dx%d", w, h);
        tjFree(enc->jpeg);
        enc->jpeg = jpeg;
        enc->jpeg_cap = jpeg_need;
    }
    return IIR_OK;
}

iir_status iir_jpeg_encode(iir_jpeg_encoder *enc, const iir_image *img, float exposure, int quality,
                           const uint8_t **data, size_t *size, iir_error *err)
{
    *data = NULL;
    *size = 0;
    if (quality < 1 || quality > 100)
        return iir_fail(err, IIR_ERR_INVALID, "JPEG quality %d is outside 1..100", quality);
    iir_status st = reserve_buffers(enc, img->width, img->height, err);
    if (st != IIR_OK) return st;
    iir_image_to_srgb8(img, exposure, enc->rgb);
    unsigned char *out = enc->jpeg;
    unsigned long out_size = enc->jpeg_cap;
    if (tjCompress2(enc->tj, enc->rgb, img->width, 0, img->height, TJPF_RGB, &out, &out_size,
                    IIR_JPEG_SUBSAMP, quality, TJFLAG_NOREALLOC) != 0)
        return iir_fail(err, IIR_ERR_INTERNAL, "JPEG encoding of a %dx%d frame failed: %s",
                        img->width, img->height, tjGetErrorStr2(enc->tj));
    *data = out;
    *size = out_size;
    return IIR_OK;
}

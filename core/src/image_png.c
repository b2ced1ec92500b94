/* image_png.c -- writes 8-bit sRGB PNG through libpng; not tone mapping, not reading PNG. */
#include "iir/image.h"

#include <png.h>
#include <stdlib.h>
#include <string.h>

iir_status iir_image_write_png(const iir_image *img, const char *path, float exposure,
                               iir_error *err)
{
    size_t row_bytes = (size_t)img->width * 3;
    uint8_t *rgb = malloc(row_bytes * (size_t)img->height);
    if (!rgb)
        return iir_fail(err, IIR_ERR_NOMEM, "cannot write PNG %s: out of memory for %dx%d pixels",
                        path, img->width, img->height);
    iir_image_to_srgb8(img, exposure, rgb);

    png_image png;
    memset(&png, 0, sizeof png);
    png.version = PNG_IMAGE_VERSION;
    png.width = (png_uint_32)img->width;
    png.height = (png_uint_32)img->height;
    png.format = PNG_FORMAT_RGB;
    /* On failure libpng closes and removes the partly written file and fills png.message. */
    int ok = png_image_write_to_file(&png, path, 0, rgb, (png_int_32)row_bytes, NULL);
    free(rgb);
    if (!ok) {
        iir_status st = iir_fail(err, IIR_ERR_IO, "cannot write PNG %s: %s", path, png.message);
        png_image_free(&png);
        return st;
    }
    return IIR_OK;
}

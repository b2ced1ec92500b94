/* image_internal.h -- what the image formats share inside libiircore: putting an encoded file's
 * bytes on disk. Not any format (image_png.c, image_exr.c) and not the public API (image.h). */
#ifndef IIR_IMAGE_INTERNAL_H
#define IIR_IMAGE_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "iir/status.h"

/* Writes size bytes to path (created or truncated). On failure removes the partly written file
 * and fills err with "cannot create|write FORMAT PATH: reason" (format: "PNG", "EXR"). */
iir_status iir_image_save_bytes(const char *path, const char *format, const uint8_t *data,
                                size_t size, iir_error *err);

#endif

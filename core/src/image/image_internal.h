/* image_internal.h -- what the image formats share inside libiircore: putting an encoded file's
 * bytes on disk, and reading a PFM from memory (for the fuzz targets). Not any format
 * (image_png.c, image_exr.c) and not the public API (image.h). */
#ifndef IIR_IMAGE_INTERNAL_H
#define IIR_IMAGE_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "iir/image.h"
#include "iir/status.h"

/* Writes size bytes to path (created or truncated). On failure removes the partly written file
 * and fills err with "cannot create|write FORMAT PATH: reason" (format: "PNG", "EXR"). */
iir_status iir_image_save_bytes(const char *path, const char *format, const uint8_t *data,
                                size_t size, iir_error *err);

/* image_pfm.c: reads a PFM held in memory (size bytes; data is only read) as iir_image_read_pfm
 * reads a file, with name in messages. On error *out is NULL. */
iir_status iir_image_read_pfm_memory(const uint8_t *data, size_t size, const char *name,
                                     iir_image **out, iir_error *err);

#endif

/* texture_internal.h -- what the texture decoders share with texture.c: the storage formats and
 * the two-step construction (allocate the chain, fill level 0, build the mips). Not the public API
 * (texture.h) and not any file format (texture_decode.c). */
#ifndef IIR_TEXTURE_INTERNAL_H
#define IIR_TEXTURE_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "iir/texture.h"

/* How texels are stored; every format holds 4 channels, R G B A in that order. */
typedef enum iir_tex_format {
    IIR_TEX_RGBA8,  /* uint8_t: colour through the texture's decode table, alpha / 255 */
    IIR_TEX_RGBA16, /* uint16_t, linear: value / 65535 */
    IIR_TEX_RGBA32F /* float, linear */
} iir_tex_format;

/* The chain of a texture of width x height with format fmt, its level 0 uninitialised: the caller
 * fills iir_texture_level0(t) (row-major, top row first, no padding) and then calls
 * iir_texture_finish. srgb applies to IIR_TEX_RGBA8 only. NULL on a bad size or no memory. */
iir_texture *iir_texture_alloc(int width, int height, iir_tex_format fmt, bool srgb);

/* Level 0's texels: width * height * 4 channels of the format's type. */
void *iir_texture_level0(iir_texture *t);

/* Builds levels 1.. from level 0 and notes whether level 0 has alpha below 1. */
void iir_texture_finish(iir_texture *t);

/* The sRGB EOTF: encoded e in [0, 1] to linear. */
double iir_srgb_eotf(double e);

#endif

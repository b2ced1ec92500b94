/* texture.h -- glTF 2.0 material textures: decoding PNG / JPEG (files or a .glb's bytes) and EXR
 * files, the mip chain, filtered lookups with glTF samplers, KHR_texture_transform. Not which
 * material slot a texture feeds or how a BSDF uses it (scene.h, bsdf.h).
 *
 * Conventions (glTF's):
 *  - uv (0,0) is the top-left corner of the image (its first row), u grows right, v down; the
 *    centre of texel (i, j) is ((i + 0.5) / w, (j + 0.5) / h). No flip anywhere.
 *  - Every value a lookup returns is linear: sRGB-encoded colour (base colour, emission) is decoded
 *    with the exact sRGB EOTF, data (normal, metallic-roughness, occlusion) is code / (2^bits - 1).
 *    Alpha is always linear. Missing channels: grey gives r = g = b, no alpha gives a = 1.
 *  - Colour-space chunks in the files (PNG gAMA, sRGB, iCCP; JPEG ICC) are ignored, as glTF
 *    requires: the material slot alone says whether a texture is sRGB.
 *
 * Storage (what iir_texture_bytes counts): 8-bit sources are RGBA8, 4 bytes a texel, decoded at
 * lookup through a 256-entry float table (sRGB EOTF or /255; alpha /255). 16-bit PNGs are
 * converted to linear and kept as RGBA16 unorm (8 bytes a texel; linear 16 bits are finer than
 * 8-bit sRGB at every level). EXR files are RGBA float (16 bytes a texel; alpha 1; NaN and
 * negative values become 0, values above 65504 become 65504).
 *
 * Mip chain: level k+1 is floor(w/2) x floor(h/2) (at least 1) of level k, down to 1x1. Each
 * texel is the box filter of its exact footprint on the level above, in linear values: an even
 * size averages 2x2 texels; an odd size w = 2n + 1 gives each of the n texels a footprint of
 * w / n texels with fractional weights at its ends (3 -> 1 averages all three at 1/3; 5 -> 2 is
 * (1, 1, 1/2) / 2.5 and (1/2, 1, 1) / 2.5). Colour and alpha are averaged independently (alpha as
 * coverage, colour not premultiplied), then re-encoded to the storage format, rounded to the
 * nearest code (sRGB8 by the exact inverse EOTF). Each level is filtered from the stored (rounded)
 * level above it.
 *
 * Threads: a texture is immutable once created; every lookup is read-only, allocates nothing and
 * takes no lock, so any number of threads may share one. */
#ifndef IIR_TEXTURE_H
#define IIR_TEXTURE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "iir/status.h"
#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Largest width or height accepted, as the image module's (IIR_IMAGE_MAX_DIM). */
#define IIR_TEXTURE_MAX_DIM 16384

/* A filtered texel, linear. */
typedef struct iir_rgba {
    float r, g, b, a;
} iir_rgba;

/* glTF wrap modes: 10497 REPEAT, 33071 CLAMP_TO_EDGE, 33648 MIRRORED_REPEAT. */
typedef enum iir_wrap { IIR_WRAP_REPEAT = 0, IIR_WRAP_CLAMP, IIR_WRAP_MIRROR } iir_wrap;

/* A glTF sampler; a zero-initialised one is glTF's default (repeat, linear, mip-mapped). Between
 * two mip levels the blend is always linear (minFilter 9984 / 9985, *_MIPMAP_NEAREST, blend too).
 */
typedef struct iir_tex_sampler {
    iir_wrap wrap_s, wrap_t;
    bool mag_nearest; /* magFilter 9728 NEAREST */
    bool min_no_mip;  /* minFilter 9728 NEAREST or 9729 LINEAR: no mip-mapping */
    bool min_nearest; /* minFilter 9728/9984/9986: nearest within a level */
} iir_tex_sampler;

/* The sampler of glTF's integer fields; 0 (or any value glTF does not define) for a field the file
 * leaves out gives that field's default. */
iir_tex_sampler iir_tex_sampler_from_gltf(int mag_filter, int min_filter, int wrap_s, int wrap_t);

/* KHR_texture_transform: uv' = T(offset) R(rotation) S(scale) uv. Identity: offset 0, rotation 0,
 * scale (1,1) -- note that a zero-initialised struct is NOT the identity (scale 0). */
typedef struct iir_tex_transform {
    iir_vec2 offset;
    float rotation; /* radians, counter-clockwise in uv space (v down: clockwise on the image) */
    iir_vec2 scale;
} iir_tex_transform;

iir_tex_transform iir_tex_transform_identity(void);

/* The matrix the extension's implementations and its example use (glTF issue #1563: the spec's
 * GLSL listing, read column-major, rotates the other way):
 *   u' =  cos(r) sx u + sin(r) sy v + offset.x
 *   v' = -sin(r) sx u + cos(r) sy v + offset.y
 * so rotation pi/2 maps (1,0) to (0,-1), and the spec's example (offset (0,1), rotation pi/2,
 * scale 0.5) maps the unit square onto the lower-left quadrant. */
iir_vec2 iir_tex_transform_apply(const iir_tex_transform *t, iir_vec2 uv);

/* A footprint of `width` uv units before the transform, after it: width * max(|sx|, |sy|) (the
 * rotation keeps lengths; the larger scale keeps the lookup from aliasing). */
float iir_tex_transform_width(const iir_tex_transform *t, float width);

/* An image and its mip chain; immutable after creation, shared by threads. */
typedef struct iir_texture iir_texture;

/* Decodes the file at path: .exr (case-insensitive) by the image module (linear, `srgb` ignored),
 * anything else as iir_texture_decode does with `what` = path. On success *out is the caller's
 * (iir_texture_destroy). On error *out stays NULL and err names the file and the reason:
 * IIR_ERR_IO (missing, unreadable), IIR_ERR_FORMAT (empty, truncated, corrupt, not an image),
 * IIR_ERR_UNSUPPORTED (larger than IIR_TEXTURE_MAX_DIM, or a kind of image this build does not
 * decode: WebP, KTX2, CMYK JPEG, ...), IIR_ERR_NOMEM. */
iir_status iir_texture_read(const char *path, bool srgb, iir_texture **out, iir_error *err);

/* Decodes size bytes of PNG (1 to 16 bits, grey, grey + alpha, RGB, RGBA, palette, tRNS,
 * interlaced) or JPEG (baseline or progressive, grey or colour), told apart by their magic bytes.
 * `what` (a file name, or a label like "scene.glb image 3") names the data in messages; data is
 * only read. `srgb`: the colour channels are sRGB-encoded (base colour, emission); false: data.
 * Errors as iir_texture_read's, without IIR_ERR_IO. */
iir_status iir_texture_decode(const void *data, size_t size, const char *what, bool srgb,
                              iir_texture **out, iir_error *err);

/* A texture of width x height RGBA8 texels (row-major, top row first, 4 bytes a texel, copied),
 * sRGB-encoded colour if srgb. NULL when a dimension is outside [1, IIR_TEXTURE_MAX_DIM] or
 * memory runs out. For tests and generated textures. */
iir_texture *iir_texture_from_rgba8(int width, int height, const uint8_t *rgba, bool srgb);

/* Frees t and its mip chain (t may be NULL). */
void iir_texture_destroy(iir_texture *t);

int iir_texture_width(const iir_texture *t);
int iir_texture_height(const iir_texture *t);
/* The number of levels: floor(log2(max(width, height))) + 1. */
int iir_texture_levels(const iir_texture *t);
/* The size of `level` (clamped to [0, levels-1]). */
int iir_texture_level_width(const iir_texture *t, int level);
int iir_texture_level_height(const iir_texture *t, int level);
/* Memory held: the struct (with its decode tables) and every level's texels. */
size_t iir_texture_bytes(const iir_texture *t);
/* h extended by the texture's size and its finest level's texels (its mips follow from them): a
 * content key for caches that depend on a texture (reference images, radiosity's form factors
 * through a cut-out). */
uint64_t iir_texture_hash(uint64_t h, const iir_texture *t);
/* Whether any texel of level 0 has alpha < 1. */
bool iir_texture_has_alpha(const iir_texture *t);
/* A line for logs, e.g. "512x256 RGBA8 sRGB, 10 levels, 701372 bytes, alpha", in buf (cap bytes,
 * truncated to fit). */
void iir_texture_describe(const iir_texture *t, char *buf, size_t cap);

/* ---- lookups: no allocation, no locks; finite results for any uv (a non-finite coordinate is
 * taken as 0); a NULL sampler is the default one ---------------------------------------------- */

/* Texel (x, y) of `level`, decoded. No wrapping: the caller passes indices inside the level
 * (asserted). */
iir_rgba iir_texture_texel(const iir_texture *t, int level, int x, int y);

/* Bilinear filtering of `level` (clamped to [0, levels-1]) at uv, wrapped per s; the nearest
 * texel instead when s->mag_nearest. */
iir_rgba iir_texture_bilinear(const iir_texture *t, const iir_tex_sampler *s, iir_vec2 uv,
                              int level);

/* The level of detail of a footprint `width` uv units wide (from ray cones or differentials):
 * lambda = log2(width * max(w, h)), clamped to [0, levels-1]; 0 for width <= 0 or NaN. */
float iir_texture_lod(const iir_texture *t, float width);

/* Trilinear filtering by footprint. When width * max(w, h) <= 1 (magnification) the mag filter
 * applies at level 0: bilinear, or nearest if s->mag_nearest. Otherwise the min filter: with
 * s->min_no_mip level 0 only; else the levels floor(lambda) and floor(lambda) + 1 blended
 * linearly by the fraction of lambda. Within a level: bilinear, or nearest if s->min_nearest. */
iir_rgba iir_texture_sample(const iir_texture *t, const iir_tex_sampler *s, iir_vec2 uv,
                            float width);

#ifdef __cplusplus
}
#endif
#endif

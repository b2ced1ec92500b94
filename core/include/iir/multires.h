/* multires.h -- multiresolution image-space shading over a camera G-buffer (Nichols & Wyman,
 * "Multiresolution splatting for indirect illumination", I3D 2009; Nichols, Shopf & Wyman,
 * "Hierarchical image-space radiosity for interactive global illumination", EGSR 2009): where to
 * evaluate a smooth quantity (indirect light) at a coarse resolution, evaluating it there through a
 * caller's function, and upsampling it back to the pixels. Not what is evaluated (the caller's
 * iir_mr_shade_fn: the VPL sum of render.h, an RSM gather) nor the G-buffer (render.h).
 *
 * The hierarchy (levels 0 .. max_level; level l has ceil(W / 2^l) x ceil(H / 2^l) texels, texel
 * (i, j) covering pixels [i 2^l, (i + 1) 2^l) x [j 2^l, (j + 1) 2^l)):
 *  - Discontinuity (level 0): pixel p is marked when it is background or one of its four
 *    neighbours q inside the image is background, or n_p . n_q < normal, or
 *    |n_p . (x_q - x_p)| > depth d_p or |n_q . (x_p - x_q)| > depth d_q (x position, n normal, d
 *    camera depth: each lies off the other's tangent plane by more than `depth` relative to its
 *    depth, so a plane seen at a grazing angle is not marked while a step or a silhouette is).
 *    Symmetric: both pixels of a dissimilar pair are marked.
 *  - Mipmaps: a texel of level l >= 1 is marked when any of its (up to four) children is (a max
 *    mipmap: a discontinuity lies inside it); its sample is the mean of its children's positions,
 *    normals (renormalised), albedos and depths.
 *  - Levels: pixel (x, y) takes the coarsest level l in [1, max_level] whose texel holding it is
 *    unmarked, or 0 when its level-1 texel is marked (the caller shades level-0 pixels at full
 *    resolution). Its value is the bilinear interpolation of its level's four nearest texel centres
 *    (coordinates clamped to the level), over the unmarked ones only, weights renormalised: the
 *    bilinear support never crosses a discontinuity (an unmarked tap touches the pixel's own
 *    unmarked texel, so no dissimilar pixel pair lies between them).
 *  - Interleaving per level (interleave n > 1): texel (i, j) of every level is of lattice class
 *    (j mod n) n + (i mod n); the caller evaluates a class's own share (the VPL subset) and a
 *    geometry-aware n x n box over the level (render.h's filter window and similarity, on the
 *    texels' samples, unmarked taps only) gathers the classes back before upsampling. Every texel
 *    thus costs 1 / n^2 of an evaluation at every level, as a pixel does at full resolution.
 *  - Work: a level evaluates only its unmarked texels within h + 1 texels (h = floor(n / 2)) of a
 *    texel whose pixels take that level -- the bilinear taps and their filter taps -- in batches
 *    of one class each (the lists are built with the hierarchy).
 *
 * Threads: one thread at a time per object; the build, evaluation, filter and upsampling are
 * OpenMP loops over rows or tiles writing only their own texels, so results do not depend on the
 * thread count. Memory: the object owns every level (allocated for IIR_MR_MAX_LEVEL when the frame
 * size changes, then reused); the hierarchy is kept while the G-buffer (its serial) and the
 * parameters are unchanged. */
#ifndef IIR_MULTIRES_H
#define IIR_MULTIRES_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/render.h"
#include "iir/rt.h"
#include "iir/status.h"
#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

enum { IIR_MR_MAX_LEVEL = 6, IIR_MR_BATCH = 256, IIR_MR_MAX_CLASSES = 64 };

/* iir_mr_params, the hierarchy's knobs: render.h. */

/* A point to evaluate: a pixel's or a coarse texel's G-buffer sample. */
typedef struct iir_mr_sample {
    iir_vec3 position, normal, albedo;
    uint32_t pixel; /* a pixel's G-buffer index; IIR_MR_TEXEL for a coarse texel */
} iir_mr_sample;
#define IIR_MR_TEXEL UINT32_MAX

/* A work item's samples, gathered from the hierarchy (or the G-buffer) only when the shading
 * function reads them: a sum from cached columns (render_indirect.c) needs their count alone. */
typedef struct iir_mr_samples iir_mr_samples;

/* The item's samples, gathered on the first call. */
const iir_mr_sample *iir_mr_samples_read(iir_mr_samples *src);

/* Evaluates count (<= IIR_MR_BATCH) samples of class cls = cy m + cx of an m x m lattice (m
 * divides nothing in particular: the class unites the caller's n x n classes (kx, ky) with
 * kx mod m = cx and ky mod m = cy; m = 1: all of them) into E[0 .. count) and returns the
 * evaluations it made (the VPL sum: sample-VPL pairs). The samples (iir_mr_samples_read(src)) are
 * work item `item` of the hierarchy (iir_multires_item): the same ones, in the same order, every
 * frame of one generation. Called from several threads at once with the same ctx (which it must
 * only read) and the calling thread's own ray counters st. */
typedef uint64_t (*iir_mr_shade_fn)(void *ctx, int item, int m, uint32_t cls, iir_mr_samples *src,
                                    int count, iir_vec3 *E, iir_raystats *st);

typedef struct iir_multires iir_multires;

/* NULL on allocation failure. Allocates no level yet. */
iir_multires *iir_multires_create(void);
void iir_multires_destroy(iir_multires *mr);

/* IIR_ERR_INVALID naming the field and its range (interleave: the caller's lattice, [1, 8]). */
iir_status iir_mr_params_validate(const iir_mr_params *p, int interleave, iir_error *err);

/* Builds the hierarchy (discontinuities, samples, every pixel's level, the texels to evaluate) for
 * gb and the caller's n x n interleave lattice, or keeps it when `serial` (the caller's count of
 * G-buffers rendered), p and interleave are those of the last build. Errors: IIR_ERR_INVALID for
 * bad params, IIR_ERR_NOMEM when growing fails (the object is then empty and builds again next
 * time). */
iir_status iir_multires_build(iir_multires *mr, const iir_gbuffer *gb, uint64_t serial,
                              const iir_mr_params *p, int interleave, iir_error *err);

/* Per pixel (row-major, the G-buffer's size): the level its value comes from, 0 = the caller
 * shades it at full resolution. Valid after a build, until the next build or destroy. */
const uint8_t *iir_multires_levels(const iir_multires *mr);

/* How many times the hierarchy was (re)built: it changes exactly when the levels may have, so a
 * caller can keep what it derives from them (0 before the first build). */
uint64_t iir_multires_generation(const iir_multires *mr);

/* The hierarchy's work items (coarse levels' first, then level 0's): how many; and item u's
 * lattice m, class cls and sample count, as iir_mr_shade_fn gets them. */
int iir_multires_items(const iir_multires *mr);
void iir_multires_item(const iir_multires *mr, int u, int *m, uint32_t *cls, int *count);

/* Level l's size in texels (l = 0: pixels); 0 x 0 before a build. */
void iir_multires_level_size(const iir_multires *mr, int l, int *w, int *h);

/* Whether texel (i, j) of level l (l = 0: pixel) is marked as holding a discontinuity. */
bool iir_multires_marked(const iir_multires *mr, int l, int i, int j);

/* Texels of level l evaluated per frame (l = 0: pixels left to the caller). */
uint64_t iir_multires_work(const iir_multires *mr, int l);

/* Evaluates every level's texels to evaluate through fn (classes whose bit of live_classes is 0
 * are not evaluated and hold no estimate), filters each level and writes the upsampled value of
 * every pixel of level > 0 into out (row-major, the G-buffer's size; level-0 pixels are left
 * untouched; out NULL: nothing is written, iir_multires_upsample_span gives the values). Adds fn's
 * evaluations to *evals and its rays to *st. With stop set, polls it per tile and returns true once
 * it said stop (out is then incomplete). */
bool iir_multires_shade(iir_multires *mr, iir_mr_shade_fn fn, void *ctx, uint64_t live_classes,
                        iir_vec3 *out, iir_stop_fn stop, void *stop_ctx, iir_raystats *st,
                        uint64_t *evals);

/* After iir_multires_shade: the upsampled values of pixels x0 .. x1 - 1 of row y into
 * out[0 .. x1 - x0), for a caller that reads each pixel once (writing none into a frame-sized
 * buffer saves a pass over the frame). Pixels of level 0 are left untouched. */
void iir_multires_upsample_span(const iir_multires *mr, int y, int x0, int x1, iir_vec3 *out);

/* Evaluates every level-0 (full-resolution) pixel through fn: pixel (x, y) is of class
 * (y mod n) n + (x mod n) of the n x n lattice (n = interleave; fn gets m = n), its value into
 * out; pixels of classes not in live_classes get 0, and so do background pixels. gb must be the
 * G-buffer of the last build. Pixels of coarser levels are left untouched (iir_multires_shade
 * writes them). Evaluations, rays and stop as iir_multires_shade. */
bool iir_multires_shade_fine(iir_multires *mr, const iir_gbuffer *gb, iir_mr_shade_fn fn, void *ctx,
                             uint64_t live_classes, iir_vec3 *out, iir_stop_fn stop, void *stop_ctx,
                             iir_raystats *st, uint64_t *evals);

#ifdef __cplusplus
}
#endif
#endif

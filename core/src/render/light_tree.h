/* light_tree.h -- direct light on a quadtree of the image that is refined where the light changes
 * as well as where the geometry does: hier's direct light (methods/hier.c) and, with shading
 * multires, the point, spot and sun lights of the VPL renderer (render_direct.c). Not the light at
 * a point: the caller's function evaluates it, a batch of pixels at a time.
 *
 * Level l's blocks are 2^l x 2^l pixels: block (i, j) owns the pixels [i 2^l, (i + 1) 2^l) x
 * [j 2^l, (j + 1) 2^l) -- the multires texel (i, j) of level l (multires.h) -- and its corners
 * are the pixel centres x0 = i 2^l, x1 = min(x0 + 2^l, W - 1) by y0, y1 (rows the same), shared
 * with its neighbours.
 *  - Every corner of the top level is evaluated: the caller's D (the direct irradiance) at its
 *    G-buffer sample.
 *  - A block all of background is a leaf without light (a background pixel's albedo is 0).
 *  - Another block splits into its (up to four) children when its multires texel is marked (a
 *    depth or normal discontinuity, or background, lies in it or between it and its corners), when
 *    a corner is background (touching it diagonally), or when the light changes across it: with Y
 *    the luminance of D at its four corners and, for blocks of 4 x 4 pixels and more, at its
 *    centre c (evaluated for the test), Y^ the corners' bilinear interpolation and t the
 *    threshold,
 *            |Y(c) - Y^(c)| > t (max Y + Y_dark)        (not the plane its corners span)
 *        or  max Y - min Y > (3 + t) / 4 (max Y + Y_dark)   (a nearly dark corner by a lit one),
 *    Y_dark = the mean Y of the top corners / 20 (a difference among dark values counts less).
 *    t = 0 splits wherever the light is not linear; t = 1 only at discontinuities (the multires
 *    hierarchy alone). A smooth fall-off is left to the interpolation (a steep one across a large
 *    block too: the second test asks for a nearly dark corner), a cone's or a shadow's edge is
 *    not. A split evaluates its children's corners.
 *  - A block that does not split gives each pixel it owns the bilinear interpolation of its four
 *    corners; a block of level 0 is a pixel, evaluated.
 * A cone's edge, a shadow's edge and a small pool thus end at pixel resolution, while smooth light
 * is interpolated from about one evaluation per 2^top x 2^top pixels.
 *
 * Evaluation: each work item (a run of blocks of a row) collects the points it needs and hands
 * them to the caller's function at once (a batch of up to LIGHT_TREE_BATCH pixels), so that the
 * caller can trace their shadow rays as packets; a block's centre probe is evaluated in a pass
 * before the blocks decide.
 *
 * Threads: light_tree_shade runs OpenMP loops over the blocks of one level at a time, each block
 * writing only its own pixels (its centre, its interpolated or cleared pixels), its children's
 * states and its children's corners, where an edge shared by two split blocks is the left or
 * upper one's; so every point has one writer and the result does not depend on the thread count.
 * The background flags are kept while the multires hierarchy is (its generation). */
#ifndef IIR_LIGHT_TREE_H
#define IIR_LIGHT_TREE_H

#include <stdint.h>

#include "iir/multires.h"
#include "iir/render.h"
#include "iir/status.h"

typedef struct light_tree {
    int width, height;                    /* the frame size the arrays are for */
    iir_vec3 *D;                          /* per pixel: the direct irradiance */
    uint8_t *have;                        /* per pixel: D evaluated this frame */
    uint8_t *state[IIR_MR_MAX_LEVEL + 1]; /* per level, per block: ABSENT .. SPLIT (light_tree.c) */
    uint8_t *empty[IIR_MR_MAX_LEVEL + 1]; /* per level >= 1, per block: all background */
    uint64_t generation;                  /* the multires hierarchy's the empty flags are of */
    int bw[IIR_MR_MAX_LEVEL + 1], bh[IIR_MR_MAX_LEVEL + 1]; /* blocks per row and column */
} light_tree;

/* The most pixels one call of a light_tree_eval_fn gets. */
enum { LIGHT_TREE_BATCH = 320 };

/* Evaluates D[px[i]] for the n (<= LIGHT_TREE_BATCH) surface pixels px[0 .. n) of the G-buffer:
 * their direct irradiance, or whatever the caller interpolates as such; adds the rays it traced to
 * *st and returns the light-point evaluations it made. Called from several threads at once, each
 * with its own pixels and st. */
typedef uint64_t (*light_tree_eval_fn)(void *ctx, const uint32_t *px, int n, iir_vec3 *D,
                                       iir_raystats *st);

/* What a frame's tree is built from: the G-buffer, the multires hierarchy built from it (its marks
 * at every level up to top), the evaluation, the top level [1, IIR_MR_MAX_LEVEL] and the
 * threshold t >= 0. */
typedef struct light_tree_input {
    const iir_gbuffer *gb;
    const iir_multires *mr;
    light_tree_eval_fn eval;
    void *ctx;
    int top;
    float threshold;
} light_tree_input;

/* Fills t->D for every pixel of the G-buffer (0 on the background), adds the evaluations to *evals
 * and the rays to *rays. Errors: IIR_ERR_NOMEM when the arrays cannot grow (t is then empty),
 * IIR_ERR_INTERRUPTED when stop said so (polled every few points; D is then incomplete). */
iir_status light_tree_shade(light_tree *t, const light_tree_input *in, const iir_stop *stop,
                            uint64_t *evals, iir_raystats *rays, iir_error *err);

void light_tree_free(light_tree *t);

/* Bytes the arrays take for a frame of width x height. */
uint64_t light_tree_memory(int width, int height);

#endif

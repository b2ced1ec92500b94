/* gv_columns.h -- the VPL sum's reusable part: for each VPL kept from frame to frame, its clamped
 * geometry term times its shadow map's visibility (G V) at every pixel its subset shades, a
 * "column". Once the camera is still, what changes from frame to frame for a kept VPL is its
 * power alone (its flux follows the light; its position, normal and map stay), so a frame adds
 * power times the column instead of evaluating the geometry and the map again: the same floats,
 * added in the same order (render_kernel_avx2.c), so frames are the same to the bit with or without
 * the columns. Not the kernels (render_batch.h) and not the choice of VPL subsets
 * (render_indirect.c). Internal to libiircore.
 *
 * Full shading's columns run over the pixels of the VPL's subset, tile by tile (the indirect
 * phase's tiles: bands of rows, iir_indirect_tile_at), and keep a copy of those pixels' positions
 * and normals in that order (so that a batch holding a VPL without a column is copied, not
 * gathered from the G-buffer: 24 bytes a pixel); multires's over
 * the samples of the hierarchy's work items whose class unites the subset (its coarse texels and
 * the pixels it shades at full resolution). A renderer keeps one of the two at a time.
 *
 * A column depends on the VPL's map (iir_smap.stamp: a new rendering is a new column), position,
 * normal and sphere radius, on the pixel class its subset shades, and on the frame's G-buffer (and
 * hierarchy), interleave and kernel constants (the epoch: any change drops every column). A VPL's
 * column is written the first frame it is shaded when most of the last frame's VPLs had been
 * shaded the frame before it (a set that keeps its VPLs, iir's), else the second frame in a row
 * (a set regenerated every frame, ir's, writes none), and read from the next frame on; a frame
 * stopped early leaves the columns it was writing unwritten. Columns take at most IIR_GV_BUDGET
 * bytes (a VPL beyond them is evaluated every frame): 48 KB a VPL at 512x384 with 4x4 interleave,
 * 192 KB at 1024x768. */
#ifndef IIR_GV_COLUMNS_H
#define IIR_GV_COLUMNS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "iir/multires.h"
#include "render_batch.h"

#define IIR_GV_BUDGET ((size_t)256 << 20) /* bytes of columns per renderer */

typedef struct iir_gv_columns iir_gv_columns;

/* What a frame does with the columns: for each VPL of r->vpl, a column and whether the kernel
 * writes or reads it (render_batch.h's iir_gv_ref), and per (tile, class) where the tile's pixels
 * of that class begin in their class's columns, which pixels those are and whether one of them is
 * glossy (iir_gb_glossy: its light goes through its BSDF). */
typedef struct iir_gv_frame {
    const iir_gv_ref *ref; /* parallel to r->vpl; NULL: no columns this frame */
    const uint32_t *ord;   /* ord[t n^2 + c]: hit pixels of class c in the tiles before tile t */
    const uint32_t *pixel; /* pixel[base[c] + o]: the G-buffer index of class c's o-th pixel */
    const uint32_t *base;  /* per class */
    const uint8_t *glossy; /* glossy[t n^2 + c]: tile t has a glossy pixel of class c */
    const uint32_t *total; /* per class (multires: subset): the samples in its columns */
    const float *soa;      /* soa[q plane + base[c] + o]: class c's o-th pixel's position (q 0-2)
                              and normal (q 3-5); full shading only */
    size_t plane;
} iir_gv_frame;

/* The frame's columns *cp (created on first use) for r's VPLs (r->vpl, sorted by subset; subset k
 * shades pixel class (k - shift) mod n^2), with the frame's kernel constants a and receivers. The
 * columns run over the full-resolution tiles' pixels (mr NULL; the frame's ord, pixel, base and
 * glossy) or over the multires hierarchy's work items (mr: ord[u n^2 + k], item u's first sample
 * in subset k's columns when u's class unites k; shift 0). Returns a frame with no columns when
 * they cannot be had (out of memory). Single-threaded. */
iir_gv_frame iir_gv_begin(iir_renderer *r, iir_gv_columns **cp, const iir_kernel_args *a, int n,
                          uint32_t shift, iir_receiver_bsdf receivers, const iir_multires *mr);

/* After the frame's VPL sum: the columns it wrote are ready to read when it ran to the end
 * (complete), else they are written again next time. */
void iir_gv_end(iir_gv_columns *c, bool complete);

void iir_gv_free(iir_gv_columns *c);

#endif

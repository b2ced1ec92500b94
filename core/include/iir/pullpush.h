/* pullpush.h -- filling the holes of a 2D map by pull-push (Gortler et al. 1996; Marroquim et al.
 * 2007; the hole filling of imperfect shadow maps, Ritschel et al. 2008); not how the map was
 * splatted (ism.h) nor how it is read (shadowmap.h).
 *
 * A map is w x h floats, row-major (row j holds texels j w .. j w + w - 1). A texel is defined when
 * it is finite; a hole is INFINITY (any non-finite value counts as a hole).
 *
 * Level 0 is the map. Level l + 1 has ceil(w_l / 2) x ceil(h_l / 2) texels, texel (i, j) having
 * the children (2i + a, 2j + b), a, b in {0, 1}, that exist at level l.
 *  - Pull: a texel of level l + 1 is the mean of its defined children, and a hole only when all of
 *    them are holes. Pulling stops at the first complete level (no hole), or at the 1 x 1 level.
 *  - Push: from that level down, every hole of level l takes the bilinear interpolation of level
 *    l + 1 (already complete) at its centre: texel i's centre lies at i / 2 - 1/4 in level l + 1's
 *    texel coordinates, so its taps are i / 2 - 1 and i / 2 with weights 1/4, 3/4 (i even) or
 *    (i - 1) / 2 and (i + 1) / 2 with weights 3/4, 1/4 (i odd), clamped to the level's edge
 *    (the 9/16, 3/16, 3/16, 1/16 pattern in 2D). Defined texels are never changed.
 * A map without any defined texel pulls up to 1 x 1, finds that a hole too, and stays all holes.
 *
 * Bilinear push (rather than copying the parent texel) keeps filled regions free of the parent's
 * 2^l-texel blocks: a hole between two depths gets a ramp between them. */
#ifndef IIR_PULLPUSH_H
#define IIR_PULLPUSH_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

/* Floats of scratch iir_pullpush needs for a w x h map: levels 1 .. up to 1 x 1 (under w h / 2
 * for w, h >= 2). */
size_t iir_pullpush_scratch_floats(int w, int h);

/* Fills the holes of map (w x h, w, h >= 1) in place by pull-push, using scratch (at least
 * iir_pullpush_scratch_floats(w, h) floats, contents ignored and overwritten; nothing is
 * allocated). Returns the level pulling stopped at: 0 when the map had no hole (it is unchanged),
 * else the first complete level L >= 1 (levels above L are never built), or the 1 x 1 level when
 * none before it was complete. */
int iir_pullpush(float *map, int w, int h, float *scratch);

#ifdef __cplusplus
}
#endif
#endif

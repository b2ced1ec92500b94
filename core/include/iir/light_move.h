/* light_move.h -- where a moved light may go: inside the scene's bounds and on this side of the
 * surfaces between its old and new position, so that a drag, a wheel notch or a script never puts a
 * light behind a wall, above the ceiling or inside solid geometry. The daemon applies it to every
 * light move (docs/protocol.md, `light`). */
#ifndef IIR_LIGHT_MOVE_H
#define IIR_LIGHT_MOVE_H

#include "iir/rt.h"
#include "iir/scene.h"
#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The position a light moving from `from` towards `to` takes: `to` clamped into the scene's box
 * (its bounds and its lights' own positions, grown by 1% of the bounds' diagonal on each side),
 * then, if a surface lies on the segment from `from` (itself clamped into the box) to there, the
 * point short of the first such surface by 0.5% of the diagonal (or at `from` when that is
 * closer). `to` itself when nothing is in the way. */
iir_vec3 iir_light_move_inside(const iir_scene *scene, const iir_rt *rt, iir_vec3 from,
                               iir_vec3 to);

#ifdef __cplusplus
}
#endif

#endif

/* camera_move.h -- where a moved camera may go: an eye that saw its target keeps seeing it, so an
 * orbit or a dolly never takes the camera behind a wall of the room it looks into (the view would
 * be the room's outside: black). The daemon applies it to every camera move (docs/protocol.md,
 * `camera`), as it keeps a moved light inside the scene (light_move.h). */
#ifndef IIR_CAMERA_MOVE_H
#define IIR_CAMERA_MOVE_H

#include "iir/camera.h"
#include "iir/rt.h"
#include "iir/scene.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The camera a move from `from` to `to` takes: `to`, unless `from`'s target is in open space (seen
 * from it, the first surface towards its eye shows its front, or there is none: a camera in a room
 * or at its opening, not one looking at the middle of a closed object) and a surface now lies
 * between `to`'s target and its eye. Then `to` with its eye moved along that line towards the
 * target, 2% of the scene's diagonal (at most half the way) in front of the first surface seen from
 * the target -- the eye keeps seeing its target, as an orbit camera that meets a wall does -- or,
 * when that surface is not half the way to the room's wall (the farthest surface on the line,
 * facing the target, open space before it: an obstacle next to the target), in front of the wall.
 * `from` when even that would put the eye on the target (a target on a surface facing away). */
iir_camera iir_camera_keep_view(const iir_scene *scene, const iir_rt *rt, const iir_camera *from,
                                const iir_camera *to);

#ifdef __cplusplus
}
#endif

#endif

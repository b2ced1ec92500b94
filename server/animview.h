/* animview.h -- which light of a scene an animation script moves, and the view (lights and
 * camera) of one of the script's frames. Shared by `iird render --anim` and `iird bench`; not
 * loading scripts (cli.h, anim.h) or rendering them. */
#ifndef IIRD_ANIMVIEW_H
#define IIRD_ANIMVIEW_H

#include <stdint.h>

#include "iir/anim.h"
#include "iir/method.h"
#include "iir/scene.h"

/* The index of the scene's first spot light, the one a script's light track moves. On a scene
 * without a spot returns IIR_ERR_INVALID naming the scene and leaves *spot unchanged. */
iir_status iird_find_spot(const iir_scene *scene, uint32_t *spot, iir_error *err);

/* The view of script frame f: the scene's lights copied into `lights` (room for
 * scene->num_lights; the returned view points into it) with lights[spot] moved by the script,
 * and the scene's camera moved by the script. A spot index outside the scene's lights moves no
 * light (a camera-only script on a scene without a spot). */
iir_view iird_anim_view(const iir_anim *a, const iir_scene *scene, uint32_t spot, iir_light *lights,
                        int f);

#endif

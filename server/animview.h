/* animview.h -- which light of a scene an animation script moves, and the view (lights and
 * camera) of one of the script's frames. Shared by `iird render --anim` and `iird bench`; not
 * loading scripts (cli.h, anim.h) or rendering them. */
#ifndef IIRD_ANIMVIEW_H
#define IIRD_ANIMVIEW_H

#include <stdint.h>

#include "iir/anim.h"
#include "iir/method.h"
#include "iir/scene.h"

/* The light a script's light track moves, as the daemon's sessions move it
 * (iir_scene_moved_light): the first spot, else the first light, else (scene->num_lights) the spot
 * made up for a scene without lights, so that a recording replays on the scene it was made on. */
uint32_t iird_moved_light(const iir_scene *scene);

/* The view of script frame f: the scene's lights copied into `lights` (room for
 * scene->num_lights + 1; the returned view points into it) with lights[spot] moved by the script,
 * plus the made-up spot when spot is scene->num_lights, and the scene's camera moved by the
 * script. */
iir_view iird_anim_view(const iir_anim *a, const iir_scene *scene, uint32_t spot, iir_light *lights,
                        int f);

#endif

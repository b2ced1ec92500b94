/* animview.c -- the scene light a script moves and the view of a script frame (see animview.h). */
#include "animview.h"

#include <string.h>

uint32_t iird_moved_light(const iir_scene *scene)
{
    iir_light l;
    return iir_scene_moved_light(scene, &l);
}

iir_view iird_anim_view(const iir_anim *a, const iir_scene *scene, uint32_t spot, iir_light *lights,
                        int f)
{
    double t = iir_anim_frame_time(a, f);
    uint32_t n = scene->num_lights;
    if (n) /* a scene of emissive triangles only has no light array */
        memcpy(lights, scene->lights, sizeof(iir_light) * n);
    if (spot == n) iir_scene_moved_light(scene, &lights[n++]); /* the made-up spot */
    iir_anim_lights(a, lights, n, spot, t, lights); /* the light track's and the "lights" tracks' */
    iir_view v = {lights, n, iir_anim_camera(a, &scene->camera, t)};
    return v;
}

/* animview.c -- the scene light a script moves and the view of a script frame (see animview.h). */
#include "animview.h"

#include <string.h>

iir_status iird_find_spot(const iir_scene *scene, uint32_t *spot, iir_error *err)
{
    for (uint32_t i = 0; i < scene->num_lights; i++)
        if (scene->lights[i].type == IIR_LIGHT_SPOT) {
            *spot = i;
            return IIR_OK;
        }
    return iir_fail(err, IIR_ERR_INVALID, "scene '%s' has no spot light to move", scene->name);
}

iir_view iird_anim_view(const iir_anim *a, const iir_scene *scene, uint32_t spot, iir_light *lights,
                        int f)
{
    double t = iir_anim_frame_time(a, f);
    if (scene->num_lights) /* a scene of emissive triangles only has no light array */
        memcpy(lights, scene->lights, sizeof(iir_light) * scene->num_lights);
    if (spot < scene->num_lights) lights[spot] = iir_anim_light(a, &scene->lights[spot], t);
    iir_view v = {lights, scene->num_lights, iir_anim_camera(a, &scene->camera, t)};
    return v;
}

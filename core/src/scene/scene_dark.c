/* scene_dark.c -- why a view of a scene may render entirely black, in words for a warning: no
 * lights, a camera that sees no geometry, a camera inside geometry, lights shut in a room the
 * camera is outside of (or the other way round), or light that reaches nothing the camera sees.
 * A few hundred rays; a hint, not a proof. Not deciding that an image is black (the caller). */
#include <math.h>
#include <stdio.h>

#include "iir/camera.h"
#include "scene_probe.h"

enum { GRID = 16 }; /* camera rays per side when looking for geometry in view */

static const float CRAMPED = 0.02f; /* median distance to the surfaces, of the scene's diagonal */

/* Whether any of a GRID x GRID set of camera rays hits the scene. */
static bool sees_geometry(const iir_rt *rt, const iir_camera *camera)
{
    iir_camera_frame cf = iir_camera_setup(camera, GRID, GRID);
    iir_raystats st = {0};
    for (int i = 0; i < GRID * GRID; i++) {
        iir_vec3 d = iir_camera_dir(&cf, (float)(i % GRID) + 0.5f, (float)(i / GRID) + 0.5f);
        iir_ray ray = iir_make_ray(cf.origin, d, 0.f, INFINITY);
        iir_hit hit;
        if (iir_rt_intersect(rt, &ray, &hit, &st, IIR_RAYS_BENCH)) return true;
    }
    return false;
}

void iir_scene_explain_dark(const iir_scene *s, const iir_rt *rt, const iir_light *lights,
                            uint32_t num_lights, const iir_camera *camera, char *buf, size_t n)
{
    if (!iir_probe_has_lights(s, lights, num_lights)) {
        snprintf(buf, n,
                 "the scene has no lights (give it some in a sidecar, docs/scene-format.md, or "
                 "an emissive material)");
        return;
    }
    if (!sees_geometry(rt, camera)) {
        snprintf(buf, n, "the camera sees no geometry: it looks away from the scene");
        return;
    }
    iir_probe cam = iir_probe_at(s, rt, camera->position);
    bool cam_shut = iir_probe_enclosed(&cam);
    bool light_shut = iir_probe_light_enclosed(s, rt, lights, num_lights);
    float diagonal = iir_length(iir_sub(s->bounds_max, s->bounds_min));
    bool sees = iir_probe_sees_light(s, rt, lights, num_lights, camera->position);
    if (cam_shut && !sees &&
        (cam.front_fraction < 0.5f || cam.median_distance < CRAMPED * diagonal))
        snprintf(buf, n,
                 "the camera may be inside geometry: surfaces close around it on every side, "
                 "seen from behind, and no light in there");
    else if (!cam_shut && light_shut && !sees)
        snprintf(buf, n,
                 "no light reaches the camera: the lights are inside a closed room and the camera "
                 "is outside it");
    else if (cam_shut && !sees)
        snprintf(buf, n,
                 "no light reaches the camera: it is in a closed space that no light shines into "
                 "(the lights are outside it, or behind a wall)");
    else
        snprintf(buf, n,
                 "no light reaches what the camera sees (are the lights aimed away from it, or "
                 "hidden behind something?)");
}

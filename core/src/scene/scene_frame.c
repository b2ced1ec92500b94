/* scene_frame.c -- the camera of a scene that gives none, and saying which camera a scene has.
 * The builder puts such a camera outside the bounds looking at their centre (scene_build.c); once
 * the scene has its ray tracer, iir_scene_frame moves it inside when the scene is a closed room
 * with its lights inside (an OBJ room without a sidecar would otherwise show the room's outside:
 * black). Not loading, not rendering. */
#include <math.h>
#include <stdio.h>

#include "scene_build.h"
#include "scene_probe.h"

static const float INSIDE_FOV_Y = 60.f; /* degrees: a wide view of the room */
static const float BACK_OFF = 0.85f;    /* how far towards the wall behind the camera stands */

/* A closed room rather than a closed object: its lights are enclosed too (a lamp outside a
 * closed statue is not), or, without lights, the surfaces around the centre face it. */
static bool is_room(const iir_scene *s, const iir_rt *rt, const iir_probe *centre)
{
    if (!iir_probe_enclosed(centre)) return false;
    if (iir_probe_has_lights(s, s->lights, s->num_lights))
        return iir_probe_light_enclosed(s, rt, s->lights, s->num_lights);
    return centre->front_fraction >= 0.5f;
}

/* The most open enclosed point of a 3x3x3 grid inside the bounds (the largest median distance to
 * the surfaces around it: not inside furniture), the centre first. */
static iir_vec3 open_point(const iir_scene *s, const iir_rt *rt)
{
    static const float at[3] = {0.5f, 0.3f, 0.7f};
    iir_vec3 lo = s->bounds_min, ext = iir_sub(s->bounds_max, s->bounds_min);
    iir_vec3 best = iir_madd(lo, ext, 0.5f);
    float best_d = -1.f;
    for (int i = 0; i < 27; i++) {
        iir_vec3 p = iir_v3(lo.x + at[i % 3] * ext.x, lo.y + at[i / 3 % 3] * ext.y,
                            lo.z + at[i / 9] * ext.z);
        iir_probe pr = iir_probe_at(s, rt, p);
        if (iir_probe_enclosed(&pr) && pr.median_distance > best_d)
            best = p, best_d = pr.median_distance;
    }
    return best;
}

/* Stands at f backed off towards the wall behind (along +axis, the room's longer horizontal
 * side) and looks the other way, across the room. */
static iir_camera inside_camera(const iir_scene *s, const iir_rt *rt, iir_vec3 f)
{
    iir_vec3 ext = iir_sub(s->bounds_max, s->bounds_min);
    bool along_x = ext.x > ext.z;
    iir_vec3 axis = along_x ? iir_v3(1.f, 0.f, 0.f) : iir_v3(0.f, 0.f, 1.f);
    float room = along_x ? s->bounds_max.x - f.x : s->bounds_max.z - f.z;
    iir_ray ray = iir_make_ray(f, axis, 0.f, room);
    iir_hit hit;
    iir_raystats st = {0};
    float back = iir_rt_intersect(rt, &ray, &hit, &st, IIR_RAYS_BENCH) ? hit.t : room;
    iir_camera cam;
    cam.position = iir_madd(f, axis, BACK_OFF * back);
    cam.target = iir_sub(cam.position, axis);
    cam.up = iir_v3(0.f, 1.f, 0.f);
    cam.fov_y = INSIDE_FOV_Y;
    return cam;
}

void iir_scene_frame(iir_scene *s, const iir_rt *rt)
{
    if (s->camera_origin != IIR_CAMERA_OUTSIDE) return;
    iir_vec3 centre = iir_scale(iir_add(s->bounds_min, s->bounds_max), 0.5f);
    iir_probe pr = iir_probe_at(s, rt, centre);
    if (!is_room(s, rt, &pr)) return;
    iir_camera cam = inside_camera(s, rt, open_point(s, rt));
    iir_error err;
    if (iir_camera_validate(&cam, &err) != IIR_OK) return;
    s->camera = cam;
    s->camera_origin = IIR_CAMERA_INSIDE;
}

void iir_scene_describe_camera(const iir_scene *s, char *buf, size_t n)
{
    const iir_camera *c = &s->camera;
    char where[200];
    snprintf(where, sizeof where, "at (%.3g, %.3g, %.3g) looking at (%.3g, %.3g, %.3g), fov_y %.3g",
             (double)c->position.x, (double)c->position.y, (double)c->position.z,
             (double)c->target.x, (double)c->target.y, (double)c->target.z, (double)c->fov_y);
    switch (s->camera_origin) {
    case IIR_CAMERA_OUTSIDE:
        snprintf(buf, n, "no camera in the scene: framed from outside, %s (its centre)", where);
        break;
    case IIR_CAMERA_INSIDE:
        snprintf(buf, n, "no camera in the scene: framed from inside (it is a closed room), %s",
                 where);
        break;
    case IIR_CAMERA_SIDECAR:
        snprintf(buf, n, "the sidecar's camera, %s", where);
        break;
    case IIR_CAMERA_BUILTIN:
        snprintf(buf, n, "the built-in box's camera, %s", where);
        break;
    default:
        snprintf(buf, n, "the camera of %s, %s", s->source, where);
    }
}

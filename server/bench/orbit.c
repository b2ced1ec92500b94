/* orbit.c -- the built-in smooth orbit of a spot light (see orbit.h). */
#include "orbit.h"

#include <math.h>

/* Where the spot's axis meets the scene, or a point one diagonal away when it meets nothing. */
static iir_vec3 aim_point(const iir_scene *s, const iir_rt *rt, const iir_light *l, float diag)
{
    iir_ray ray = iir_make_ray(l->position, l->direction, 0.f, INFINITY);
    iir_hit hit;
    float t = iir_rt_intersect(rt, &ray, &hit, NULL, IIR_RAYS_BENCH) ? hit.t : diag;
    (void)s;
    return iir_madd(l->position, l->direction, t);
}

iir_light iird_orbit_light(const iir_scene *scene, const iir_rt *rt, const iir_light *base, int f,
                           int frames)
{
    float diag = iir_length(iir_sub(scene->bounds_max, scene->bounds_min));
    float r = 0.15f * diag, theta = 2.f * IIR_PI * (float)f / (float)frames;
    iir_vec3 target = aim_point(scene, rt, base, diag);
    iir_light l = *base;
    l.position = iir_add(base->position, iir_v3(r * cosf(theta), 0.f, r * sinf(theta)));
    iir_vec3 aim = iir_add(target, iir_v3(-r * cosf(theta), 0.f, -r * sinf(theta)));
    l.direction = iir_normalize(iir_sub(aim, l.position));
    return l;
}

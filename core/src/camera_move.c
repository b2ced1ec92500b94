/* camera_move.c -- keeping a moved camera's view of its target (camera_move.h): one ray from the
 * old target towards its eye says whether the target is in open space; rays from the new target
 * towards the new eye find the surfaces in the way, and the eye stops in front of the first, or of
 * the room's wall when the first is close to the target. Not the camera model (camera.c) and not
 * the light's moves (lights/light_move.c). */
#include "iir/camera_move.h"

#include <math.h>

enum { MAX_CROSSINGS = 64 }; /* surfaces followed from the target towards the eye */

/* The first surface along ray (its t, and its triangle in *prim), or -1 when none. */
static float first_hit(const iir_rt *rt, iir_ray ray, uint32_t *prim)
{
    iir_hit hit;
    iir_raystats st = {{0}};
    if (!iir_rt_intersect(rt, &ray, &hit, &st, IIR_RAYS_BENCH)) return -1.f;
    *prim = hit.prim;
    return hit.t;
}

/* The farthest surface on the ray (within MAX_CROSSINGS of them): its t and triangle, or -1. */
static float last_hit(const iir_rt *rt, iir_ray ray, uint32_t *prim)
{
    float last = -1.f, eps = iir_rt_epsilon(rt);
    uint32_t p = 0;
    for (int i = 0; i < MAX_CROSSINGS; i++) {
        float t = first_hit(rt, ray, &p);
        if (t < 0.f) break;
        last = t;
        *prim = p;
        ray.tnear = t + eps;
    }
    return last;
}

/* p is in open space (not inside an object): seen from p, the first surface towards dir (within
 * len) shows its front (winding normal), or there is none. */
static bool open_at(const iir_scene *s, const iir_rt *rt, iir_vec3 p, iir_vec3 dir, float len)
{
    uint32_t prim = 0;
    float t = first_hit(rt, iir_make_ray(p, dir, iir_rt_epsilon(rt), len), &prim);
    return t < 0.f || iir_dot(s->normals[prim], dir) < 0.f;
}

/* The camera's target is in open space (not inside an object): from the target towards the eye,
 * the first surface is seen from its front (winding normal), or there is none. */
static bool target_open(const iir_scene *s, const iir_rt *rt, const iir_camera *c)
{
    iir_vec3 d = iir_sub(c->position, c->target);
    float len = iir_length(d);
    return !(len > 0.f) || open_at(s, rt, c->target, iir_scale(d, 1.f / len), len);
}

/* How far from the target along ray the eye stands: in front of the first surface, unless that is
 * not half the way to the room's wall (the farthest surface, facing the target, open space before
 * it): then in front of the wall, so an obstacle next to the target does not pull the eye onto
 * it. margin: the gap left before the surface (at most half the way to it). */
static float eye_distance(const iir_scene *s, const iir_rt *rt, iir_ray ray, float first,
                          float margin)
{
    uint32_t prim = 0;
    float wall = last_hit(rt, ray, &prim) - margin;
    bool room = wall > 2.f * first && iir_dot(s->normals[prim], ray.dir) < 0.f &&
                open_at(s, rt, iir_madd(ray.org, ray.dir, wall), iir_neg(ray.dir), wall);
    return room ? wall : first - fminf(margin, 0.5f * first);
}

iir_camera iir_camera_keep_view(const iir_scene *scene, const iir_rt *rt, const iir_camera *from,
                                const iir_camera *to)
{
    float diag = iir_length(iir_sub(scene->bounds_max, scene->bounds_min));
    iir_vec3 d = iir_sub(to->position, to->target);
    float len = iir_length(d), eps = iir_rt_epsilon(rt);
    if (!(diag > 0.f) || !(len > 2.f * eps) || !target_open(scene, rt, from)) return *to;
    iir_ray ray = iir_make_ray(to->target, iir_scale(d, 1.f / len), eps, len);
    uint32_t prim = 0;
    float t = first_hit(rt, ray, &prim);
    if (t < 0.f) return *to;
    t = eye_distance(scene, rt, ray, t, 0.02f * diag);
    if (!(t > 1e-3f * diag)) return *from;
    iir_camera out = *to;
    out.position = iir_madd(to->target, ray.dir, t);
    return out;
}

/* light_move.c -- keeping a moved light inside the scene (light_move.h): a box clamp, then one
 * ray from the old position to the new that stops the move short of the first surface. */
#include "iir/light_move.h"

#include <math.h>

static float clampf(float x, float lo, float hi)
{
    return x < lo ? lo : x > hi ? hi : x;
}

static iir_vec3 clamp3(iir_vec3 p, iir_vec3 lo, iir_vec3 hi)
{
    return iir_v3(clampf(p.x, lo.x, hi.x), clampf(p.y, lo.y, hi.y), clampf(p.z, lo.z, hi.z));
}

/* The scene's bounds and its lights' positions, grown by `margin` on every side. */
static void light_box(const iir_scene *scene, float margin, iir_vec3 *lo, iir_vec3 *hi)
{
    *lo = scene->bounds_min;
    *hi = scene->bounds_max;
    for (uint32_t i = 0; i < scene->num_lights; i++) {
        iir_vec3 p = scene->lights[i].position;
        *lo = iir_v3(fminf(lo->x, p.x), fminf(lo->y, p.y), fminf(lo->z, p.z));
        *hi = iir_v3(fmaxf(hi->x, p.x), fmaxf(hi->y, p.y), fmaxf(hi->z, p.z));
    }
    *lo = iir_sub(*lo, iir_v3s(margin));
    *hi = iir_add(*hi, iir_v3s(margin));
}

iir_vec3 iir_light_move_inside(const iir_scene *scene, const iir_rt *rt, iir_vec3 from, iir_vec3 to)
{
    float diag = iir_length(iir_sub(scene->bounds_max, scene->bounds_min));
    if (!(diag > 0.f)) return to;
    iir_vec3 lo, hi;
    light_box(scene, 0.01f * diag, &lo, &hi);
    iir_vec3 start = clamp3(from, lo, hi), end = clamp3(to, lo, hi);
    iir_vec3 d = iir_sub(end, start);
    float len = iir_length(d);
    if (!(len > 0.f)) return end;
    iir_ray ray = iir_make_ray(start, iir_scale(d, 1.f / len), 0.f, len);
    iir_hit hit;
    iir_raystats st = {{0}};
    if (!iir_rt_intersect(rt, &ray, &hit, &st, IIR_RAYS_BENCH)) return end;
    float t = fmaxf(0.f, hit.t - 0.005f * diag);
    return iir_add(start, iir_scale(ray.dir, t));
}

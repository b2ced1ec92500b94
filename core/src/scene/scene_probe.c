/* scene_probe.c -- probing the space around a point with rays (scene_probe.h): enclosure, the
 * distance and side of the surfaces around it, and the lights it sees; not what a caller decides
 * from them (scene_frame.c, scene_dark.c). */
#include "scene_probe.h"

#include <math.h>
#include <stdlib.h>

enum { MAX_EMITTERS = 16 }; /* emissive triangles looked at, spread over the scene's */

static const float ENCLOSED = 0.9f;

/* Direction i of n, a Fibonacci set: evenly spread over the unit sphere. */
static iir_vec3 fibonacci_dir(int i, int n)
{
    const float golden = IIR_PI * (3.f - sqrtf(5.f));
    float z = 1.f - (2.f * (float)i + 1.f) / (float)n;
    float r = iir_safe_sqrt(1.f - z * z), phi = golden * (float)i;
    return iir_v3(r * cosf(phi), r * sinf(phi), z);
}

static int compare_floats(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

iir_probe iir_probe_at(const iir_scene *s, const iir_rt *rt, iir_vec3 p)
{
    float dist[IIR_PROBE_RAYS];
    int hits = 0, front = 0;
    iir_raystats st = {0};
    for (int i = 0; i < IIR_PROBE_RAYS; i++) {
        iir_vec3 d = fibonacci_dir(i, IIR_PROBE_RAYS);
        iir_ray ray = iir_make_ray(p, d, 0.f, INFINITY);
        iir_hit hit;
        if (!iir_rt_intersect(rt, &ray, &hit, &st, IIR_RAYS_BENCH)) continue;
        dist[hits++] = hit.t;
        front += iir_dot(s->normals[hit.prim], d) < 0.f;
    }
    iir_probe pr = {(float)hits / IIR_PROBE_RAYS, hits ? (float)front / (float)hits : 0.f,
                    INFINITY};
    if (hits) {
        qsort(dist, (size_t)hits, sizeof(float), compare_floats);
        pr.median_distance = dist[hits / 2];
    }
    return pr;
}

bool iir_probe_enclosed(const iir_probe *pr)
{
    return pr->hit_fraction >= ENCLOSED;
}

static bool emissive(const iir_scene *s, uint32_t t)
{
    return !iir_is_black(s->material_list[s->materials[t]].emission);
}

/* Up to MAX_EMITTERS points just in front of emissive triangles, spread over them; their count. */
static int emitter_points(const iir_scene *s, const iir_rt *rt, iir_vec3 out[MAX_EMITTERS])
{
    uint32_t total = 0;
    for (uint32_t t = 0; t < s->num_triangles; t++) total += emissive(s, t);
    uint32_t stride = total > MAX_EMITTERS ? total / MAX_EMITTERS : 1, seen = 0;
    float eps = 10.f * iir_rt_epsilon(rt);
    int n = 0;
    for (uint32_t t = 0; t < s->num_triangles && n < MAX_EMITTERS; t++) {
        if (!emissive(s, t) || seen++ % stride) continue;
        const uint32_t *v = s->indices + 3 * (size_t)t;
        iir_vec3 c =
            iir_scale(iir_add(iir_add(s->positions[v[0]], s->positions[v[1]]), s->positions[v[2]]),
                      1.f / 3.f);
        out[n++] = iir_madd(c, s->normals[t], eps);
    }
    return n;
}

bool iir_probe_has_lights(const iir_scene *s, const iir_light *lights, uint32_t num_lights)
{
    for (uint32_t i = 0; i < num_lights; i++)
        if (!iir_is_black(lights[i].intensity)) return true;
    for (uint32_t t = 0; t < s->num_triangles; t++)
        if (emissive(s, t)) return true;
    return false;
}

/* Every light point: punctual positions, then points in front of emitters; their count. */
static int light_points(const iir_scene *s, const iir_rt *rt, const iir_light *lights,
                        uint32_t num_lights, iir_vec3 *out, int max)
{
    int n = 0;
    for (uint32_t i = 0; i < num_lights && n < max; i++)
        if (!iir_is_black(lights[i].intensity) && iir_light_has_position(&lights[i]))
            out[n++] = lights[i].position; /* a sun's position is only its disk's centre */
    iir_vec3 em[MAX_EMITTERS];
    int m = emitter_points(s, rt, em);
    for (int i = 0; i < m && n < max; i++) out[n++] = em[i];
    return n;
}

enum { MAX_POINTS = 64 };

bool iir_probe_light_enclosed(const iir_scene *s, const iir_rt *rt, const iir_light *lights,
                              uint32_t num_lights)
{
    iir_vec3 pts[MAX_POINTS];
    int n = light_points(s, rt, lights, num_lights, pts, MAX_POINTS);
    for (int i = 0; i < n; i++) {
        iir_probe pr = iir_probe_at(s, rt, pts[i]);
        if (iir_probe_enclosed(&pr)) return true;
    }
    return false;
}

bool iir_probe_sees_light(const iir_scene *s, const iir_rt *rt, const iir_light *lights,
                          uint32_t num_lights, iir_vec3 p)
{
    iir_vec3 pts[MAX_POINTS];
    int n = light_points(s, rt, lights, num_lights, pts, MAX_POINTS);
    float eps = iir_rt_epsilon(rt);
    iir_raystats st = {0};
    for (int i = 0; i < n; i++) {
        iir_vec3 d = iir_sub(pts[i], p);
        float len = iir_length(d);
        if (!(len > 2.f * eps)) return true;
        iir_ray ray = iir_make_ray(p, iir_scale(d, 1.f / len), eps, len - eps);
        if (!iir_rt_occluded(rt, &ray, &st, IIR_RAYS_BENCH)) return true;
    }
    return false;
}

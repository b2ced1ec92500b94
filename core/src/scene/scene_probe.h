/* scene_probe.h -- probing the space around a point of a scene with rays: whether it is enclosed
 * (a closed room, or the inside of an object), how far the surfaces around it are, which side of
 * them it sees, and whether it sees the scene's lights. Used to frame a scene without a camera
 * (scene_frame.c) and to explain a black image (scene_dark.c). Internal; not rendering. */
#ifndef IIR_SCENE_PROBE_H
#define IIR_SCENE_PROBE_H

#include <stdbool.h>

#include "iir/light.h"
#include "iir/rt.h"
#include "iir/scene.h"

enum { IIR_PROBE_RAYS = 128 }; /* directions per probe, spread evenly over the sphere */

typedef struct iir_probe {
    float hit_fraction;    /* of the rays, those that hit geometry */
    float front_fraction;  /* of the hits, those on a surface's front (winding-normal) side */
    float median_distance; /* of the hits; INFINITY when none hit */
} iir_probe;

/* Casts IIR_PROBE_RAYS rays from p in a Fibonacci set of directions. */
iir_probe iir_probe_at(const iir_scene *s, const iir_rt *rt, iir_vec3 p);

/* Hits in almost every direction (at least 90% of them): p is inside a closed room or object. */
bool iir_probe_enclosed(const iir_probe *pr);

/* The scene has a light: a punctual one in lights, or an emissive triangle. */
bool iir_probe_has_lights(const iir_scene *s, const iir_light *lights, uint32_t num_lights);

/* Some light -- a punctual light's position, or the front side of one of the first emissive
 * triangles -- is enclosed (iir_probe_enclosed). */
bool iir_probe_light_enclosed(const iir_scene *s, const iir_rt *rt, const iir_light *lights,
                              uint32_t num_lights);

/* Some light, as above, can be seen from p (the segment between them is not occluded). */
bool iir_probe_sees_light(const iir_scene *s, const iir_rt *rt, const iir_light *lights,
                          uint32_t num_lights, iir_vec3 p);

#endif

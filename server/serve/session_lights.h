/* session_lights.h -- the lights a session renders and moves: the scene's own, in the scene's
 * order (or, for a scene without lights, the spot iird makes up for it, alone), each on or off,
 * and the one a `light` message without a name moves. Not applying messages to them
 * (session_msg.c, protocol.h) and not rendering. The session's lock guards its set; nothing here
 * locks. */
#ifndef IIRD_SESSION_LIGHTS_H
#define IIRD_SESSION_LIGHTS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "iir/light.h"
#include "iir/scene.h"

typedef struct iird_lights {
    iir_light *v;     /* [n]: poses and intensities; a light switched off keeps its intensity */
    bool *on;         /* [n] */
    iir_light *shown; /* [n]: scratch for iird_lights_shown */
    uint32_t n;
    uint32_t moved; /* the light a `light` message without a name moves (iir_scene_moved_light) */
    bool made_up;   /* the scene has no light: v[0] is the spot iird made up */
} iird_lights;

/* The lights of scene, all on. False when out of memory (then *L is empty: n = 0). */
bool iird_lights_init(iird_lights *L, const iir_scene *scene);
/* Frees the arrays and empties *L (an empty set is fine). */
void iird_lights_free(iird_lights *L);

/* Index of the first light named name, or -1. */
int iird_lights_find(const iird_lights *L, const char *name);
/* The lights' names and kinds for a message: "'key' (spot), 'fill' (point)", cut to fit n. */
void iird_lights_names(const iird_lights *L, char *out, size_t n);

/* The lights as rendered: a light switched off has black intensity (vplsets.h: off), the others
 * are v's. Written into L->shown, valid until the next call or change. */
const iir_light *iird_lights_shown(iird_lights *L);

#endif

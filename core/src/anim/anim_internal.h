/* anim_internal.h -- the parsed form of an animation script, shared by anim_parse.c (which builds
 * it) and anim_eval.c (which reads it). Not part of the public API. */
#ifndef IIR_ANIM_INTERNAL_H
#define IIR_ANIM_INTERNAL_H

#include <stdbool.h>

#include "iir/anim.h"
#include "iir/vecmath.h"

/* Which fields a key gives (bit mask). */
enum {
    IIR_AF_POSITION = 1u << 0,
    IIR_AF_DIRECTION = 1u << 1,
    IIR_AF_TARGET = 1u << 2,
    IIR_AF_CONE = 1u << 3,
    IIR_AF_SMOOTH = 1u << 4,
    IIR_AF_INTENSITY = 1u << 5,
    IIR_AF_FOV = 1u << 6,
    IIR_AF_UP = 1u << 7,       /* camera; light: its up hint */
    IIR_AF_EXPOSURE = 1u << 8, /* the exposure track's "stops" */
    IIR_AF_INNER = 1u << 9,    /* a glTF spot's inner_angle */
    IIR_AF_SIZE = 1u << 10,    /* an area light's size */
    IIR_AF_ON = 1u << 11,      /* on / off (a step field) */
};

typedef struct iir_anim_key {
    double t;        /* seconds */
    unsigned fields; /* IIR_AF_* given by this key */
    bool step;       /* the fields this key gives jump to it (no interpolation into it) */
    iir_vec3 position;
    iir_vec3 direction; /* unit */
    iir_vec3 target;
    iir_vec3 intensity;
    iir_vec3 up;                    /* camera, light: up hint, as written */
    iir_vec3 size;                  /* area light: width, height (z = 0) */
    float cone, smooth, inner, fov; /* degrees, as written */
    float stops;                    /* exposure */
    bool on;                        /* light: on (true) or off */
    bool on_held; /* the on/off in force from this key on: the last "on" at or before it (true
                     before any), set once the track is parsed */
} iir_anim_key;

typedef enum iir_anim_interp {
    IIR_ANIM_LINEAR,
    IIR_ANIM_CATMULL_ROM,
    IIR_ANIM_STEP
} iir_anim_interp;

typedef enum iir_anim_path { IIR_ANIM_KEYS, IIR_ANIM_ORBIT, IIR_ANIM_SWEEP } iir_anim_path;

/* One track. Parametric paths keep their constant fields (aim, cone, ...) in a single key at
 * t = 0 and compute the position from the parameters below. */
typedef struct iir_anim_track {
    bool present;
    char name[64]; /* a light track's "name" ("" when it gives none) */
    iir_anim_path path;
    iir_anim_interp interp;
    int num_keys;
    iir_anim_key *keys;
    iir_vec3 center;      /* orbit */
    double radius, turns; /* orbit */
    double phase;         /* orbit, radians */
    iir_vec3 from, to;    /* sweep */
} iir_anim_track;

struct iir_anim {
    char source[160];  /* the script's file or label, for messages */
    char scene[129];   /* the scene the script was made for ("" when it names none) */
    char scenes[4096]; /* the scenes folder it was found in ("" when the script names none) */
    int width, height; /* the frame size it was made at ("size"; 0 when it gives none) */
    double fps, duration;
    iir_anim_track light, camera, exposure; /* light.name: "" when it names none */
    int num_lights;                         /* "lights": named tracks, names distinct */
    iir_anim_track *lights;
};

#endif

/* anim.h -- animation scripts: parsing and validating a JSON script (docs/animation-format.md),
 * checking it against a scene's lights, and evaluating "the lights and camera at time t / frame
 * f". Not rendering or benchmarking them.
 *
 * A script has an optional light track (the scene light a session moves), named light tracks
 * ("lights": each moves the scene light of its name) and an optional camera track, each either
 * keyframes (linear, Catmull-Rom or step) or a parametric path (orbit, sweep), and an optional
 * exposure (a number or keyframes). Light keys may switch their light on and off. Evaluation
 * starts from the scene's own lights or camera and overrides only what the script animates;
 * lights no track moves keep their scene pose. An iir_anim is immutable after parsing, so any
 * number of threads may evaluate the same one. */
#ifndef IIR_ANIM_H
#define IIR_ANIM_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/camera.h"
#include "iir/light.h"
#include "iir/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct iir_anim iir_anim;

/* Parses and validates a script held in json_text (NUL-terminated). source_name (may be NULL)
 * only prefixes error messages, e.g. "orbit.json: light.keys[2].postion: unknown field".
 * On success *out is a new script the caller frees with iir_anim_destroy. On error returns
 * IIR_ERR_FORMAT (bad JSON, unknown field, wrong type), IIR_ERR_INVALID (a value out of range,
 * not finite, times not increasing, zero direction, target == position) or IIR_ERR_NOMEM, fills
 * err with a message naming the JSON path of the field, and leaves *out NULL. */
iir_status iir_anim_parse(const char *json_text, const char *source_name, iir_anim **out,
                          iir_error *err);

/* Reads the file at path (at most 16 MiB) and parses it as iir_anim_parse does, with the file's
 * path in messages. IIR_ERR_IO when the file cannot be read; *out is left NULL on error. */
iir_status iir_anim_load(const char *path, iir_anim **out, iir_error *err);

/* Frees a script; NULL is ignored. */
void iir_anim_destroy(iir_anim *a);

/* Script length in seconds, and frames per second, as given. */
double iir_anim_duration(const iir_anim *a);
double iir_anim_fps(const iir_anim *a);
/* The scene the script names ("scene": recordings name the scene they were made on), "" if none. */
const char *iir_anim_scene(const iir_anim *a);
/* The scenes folder the script names ("scenes": a recording's is the daemon's --scenes folder, an
 * absolute path), "" if none. */
const char *iir_anim_scenes_dir(const iir_anim *a);
/* The frame size the script names ("size": a recording's is the session's frame size): true with
 * *width and *height set, each in [1, 16384]; false, leaving them unchanged, when it names none. */
bool iir_anim_size(const iir_anim *a, int *width, int *height);

/* Number of frames: floor(duration * fps) + 1 (frame 0 is t = 0; the last frame is at or just
 * before t = duration). Always >= 1. */
int iir_anim_frame_count(const iir_anim *a);

/* Time in seconds of a frame: frame / fps. Frames outside [0, frame_count) are clamped into it. */
double iir_anim_frame_time(const iir_anim *a, int frame);

/* True when the script animates the light / the camera / the exposure. Without a track,
 * iir_anim_light, iir_anim_camera and iir_anim_exposure return the base unchanged. */
bool iir_anim_has_light(const iir_anim *a);
bool iir_anim_has_camera(const iir_anim *a);
bool iir_anim_has_exposure(const iir_anim *a);

/* The name the light track gives ("light": {"name": ...}: informational, the track moves the
 * scene's moved light whatever its name), "" when it gives none. */
const char *iir_anim_light_name(const iir_anim *a);

/* The named light tracks ("lights"): how many, and the name of track i (NULL outside [0, count);
 * names are distinct, and differ from the light track's name). */
int iir_anim_num_light_tracks(const iir_anim *a);
const char *iir_anim_light_track_name(const iir_anim *a, int i);

/* The index of the light called `name` among lights[0..n): -1 when none is, -2 when several are. */
int iir_anim_find_light(const iir_light *lights, uint32_t n, const char *name);

/* Checks the script against the lights it will animate -- the scene's, with the spot made up for
 * a scene without lights appended (iir_scene_moved_light) -- where lights[moved] is the one the
 * light track moves (moved >= n: none). IIR_ERR_INVALID, with a message that starts with the
 * script's name and gives the JSON path, when a "lights" track names no light (the message lists
 * the lights' names) or a name several lights share, names lights[moved] while the script has a
 * light track, or a track gives a field its light's kind lacks (cone_angle on a point light or a
 * sun or an area light, smooth on a glTF spot, inner_angle on anything but a glTF spot, size on
 * anything but an area light, a sun's position without a target in the same key). Call it once
 * the scene is loaded, before evaluating. */
iir_status iir_anim_check_lights(const iir_anim *a, const iir_light *lights, uint32_t n,
                                 uint32_t moved, iir_error *err);

/* The light of the light track at time t (seconds; clamped into [0, duration]): a copy of *base
 * (the scene's moved light) with what the track animates overridden; *base when the script has no
 * light track. Keeps base's type and name, and a sun's disk (position, radius). If base passes
 * iir_light_validate, so does the result: the direction and up are unit length, the cone angle
 * is kept in (0, 90] degrees, the smooth edge and inner cone within the cone, the size positive
 * and the intensity non-negative (a Catmull-Rom overshoot is clamped); a light switched off has
 * black intensity. */
iir_light iir_anim_light(const iir_anim *a, const iir_light *base, double t);

/* All lights at time t: out[i] is lights[i] moved by the track that animates it -- the light
 * track for i == moved (moved >= n: no light is), the "lights" track of its name otherwise -- as
 * iir_anim_light does; lights no track names are copied unchanged. out may be lights (updated in
 * place). Assumes iir_anim_check_lights accepted these lights (a track whose name matches none
 * or several is skipped). */
void iir_anim_lights(const iir_anim *a, const iir_light *lights, uint32_t n, uint32_t moved,
                     double t, iir_light *out);

/* The camera at time t, likewise from *base: position, target, fov_y (kept in (0, 180)) and up
 * (as interpolated, of any length; base's where the keys' ups cancel) are overridden where
 * animated. */
iir_camera iir_anim_camera(const iir_anim *a, const iir_camera *base, double t);

/* The exposure in stops at time t (the script's "exposure", kept in [-30, 30]), or base when the
 * script has none. */
float iir_anim_exposure(const iir_anim *a, float base, double t);

#ifdef __cplusplus
}
#endif
#endif

/* recording.h -- recording every light of a session (named "lights" tracks) into the `record`
 * script. The rest of the recording interface (create, the moved light, camera, exposure, the
 * script and the replies) is in protocol.h; both are implemented by recording.c. */
#ifndef IIRD_RECORDING_H
#define IIRD_RECORDING_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/light.h"
#include "protocol.h"

/* Adds the state of all n lights applied at t seconds since start: one key on each light's track
 * of the script's "lights" (docs/animation-format.md), named after the light, giving the fields
 * of its kind (a sun: its direction, never its position; a glTF spot: inner_angle; an area
 * light: size); a light with black intensity is recorded as off ("on": false). Times, pauses and
 * limits as iird_recording_add (every light's key counts towards the 100000). The first call fixes
 * the lights: a later call with another number of lights, or another name or kind at some index,
 * fails (internal). False with err filled and the recording unchanged on any failure. A
 * recording uses either this or iird_recording_add for its lights, not both: a replay refuses a
 * light moved by both tracks. */
bool iird_recording_add_lights(iird_recording *r, double t, const iir_light *lights, uint32_t n,
                               iird_proto_error *err);

#endif

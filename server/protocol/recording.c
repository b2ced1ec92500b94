/* recording.c -- `record`: the light states a session applied, kept as timed keyframes and
 * written as an animation script (docs/animation-format.md) with linear keys that reproduces the
 * light at every recorded time. Not deciding when a state is recorded (the session does). */
#include "protocol_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

enum { MAX_KEYFRAMES = 100000 };
#define MAX_SECONDS 36000.0 /* the longest script docs/animation-format.md allows */

typedef struct rec_key {
    double t; /* seconds since start, rounded to microseconds */
    iir_vec3 position, direction, intensity;
    float cone, smooth; /* radians, as in iir_light */
} rec_key;

struct iird_recording {
    int fps;
    char scene[129]; /* the scene it was recorded on */
    uint32_t count, cap;
    rec_key *keys;
};

iird_recording *iird_recording_create(int fps, const char *scene)
{
    iird_recording *r = calloc(1, sizeof *r);
    if (r) r->fps = fps < 1 ? 1 : fps > 240 ? 240 : fps;
    if (r) snprintf(r->scene, sizeof r->scene, "%s", scene ? scene : "");
    return r;
}

int iird_recording_fps(const iird_recording *r)
{
    return r->fps;
}

void iird_recording_destroy(iird_recording *r)
{
    if (!r) return;
    free(r->keys);
    free(r);
}

static bool grow(iird_recording *r)
{
    if (r->count < r->cap) return true;
    uint32_t cap = r->cap ? r->cap * 2 : 64;
    if (cap > MAX_KEYFRAMES) cap = MAX_KEYFRAMES;
    rec_key *k = realloc(r->keys, cap * sizeof *k);
    if (!k) return false;
    r->keys = k;
    r->cap = cap;
    return true;
}

/* Times are rounded to microseconds so that two keys never print as the same number; a time at
 * or before the last key's (two states in the same microsecond, or a clock step back) replaces
 * that key's light and keeps its time. */
bool iird_recording_add(iird_recording *r, double t, const iir_light *light, iird_proto_error *err)
{
    if (!isfinite(t))
        return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "recording time is not finite");
    t = fmax(0.0, round(t * 1e6) / 1e6);
    if (t > MAX_SECONDS)
        return iird_proto_fail(err, IIRD_E_TOO_LARGE, NULL,
                               "the recording is longer than %.0f s; stop it", MAX_SECONDS);
    bool replace = r->count > 0 && t <= r->keys[r->count - 1].t;
    if (!replace && r->count >= MAX_KEYFRAMES)
        return iird_proto_fail(err, IIRD_E_TOO_LARGE, NULL,
                               "the recording holds the most keyframes allowed (%d); stop it",
                               MAX_KEYFRAMES);
    if (!replace && !grow(r))
        return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory for the recording");
    rec_key *k = &r->keys[replace ? r->count - 1 : r->count++];
    if (!replace) k->t = t;
    k->position = light->position;
    k->direction = light->direction;
    k->intensity = light->intensity;
    k->cone = light->cone_angle;
    k->smooth = light->smooth;
    return true;
}

static double duration(const iird_recording *r)
{
    double last = r->count ? r->keys[r->count - 1].t : 0.0;
    return fmax(last, 1.0 / r->fps);
}

static cJSON *key_json(const rec_key *k)
{
    float cone = fminf(iir_degrees(k->cone), 90.f);
    float smooth = fminf(fmaxf(iir_degrees(k->smooth), 0.f), cone);
    cJSON *o = cJSON_CreateObject();
    bool ok =
        o && iird_json_add_num(o, "t", k->t) && iird_json_add_vec3(o, "position", k->position) &&
        iird_json_add_vec3(o, "direction", k->direction) &&
        iird_json_add_float(o, "cone_angle", cone) && iird_json_add_float(o, "smooth", smooth) &&
        iird_json_add_vec3(o, "intensity", k->intensity);
    if (ok) return o;
    cJSON_Delete(o);
    return NULL;
}

/* The script as a cJSON tree; NULL on out-of-memory. No light track without keyframes. */
static cJSON *script_json(const iird_recording *r)
{
    cJSON *o = cJSON_CreateObject(), *light = NULL, *keys = NULL;
    bool ok = o && (!r->scene[0] || cJSON_AddStringToObject(o, "scene", r->scene)) &&
              iird_json_add_num(o, "fps", r->fps) && iird_json_add_num(o, "duration", duration(r));
    if (ok && r->count)
        ok = (light = cJSON_AddObjectToObject(o, "light")) &&
             cJSON_AddStringToObject(light, "interpolation", "linear") &&
             (keys = cJSON_AddArrayToObject(light, "keys"));
    for (uint32_t i = 0; ok && i < r->count; i++) {
        cJSON *k = key_json(&r->keys[i]);
        ok = k && cJSON_AddItemToArray(keys, k);
        if (!ok) cJSON_Delete(k);
    }
    if (ok) return o;
    cJSON_Delete(o);
    return NULL;
}

char *iird_recording_script(const iird_recording *r)
{
    return iird_json_finish(script_json(r));
}

char *iird_json_record_stop(const iird_recording *r, int64_t seq)
{
    return iird_json_record_part(r, seq, false);
}

char *iird_json_record_part(const iird_recording *r, int64_t seq, bool continues)
{
    cJSON *o = cJSON_CreateObject(), *script = script_json(r);
    bool ok = o && script && cJSON_AddStringToObject(o, "type", "record") &&
              (seq < 0 || iird_json_add_num(o, "seq", (double)seq)) &&
              (!continues || cJSON_AddBoolToObject(o, "recording", true)) &&
              iird_json_add_num(o, "keyframes", r->count) &&
              iird_json_add_num(o, "duration", duration(r)) &&
              cJSON_AddItemToObject(o, "script", script);
    if (!ok) {
        if (!o || !cJSON_GetObjectItemCaseSensitive(o, "script")) cJSON_Delete(script);
        cJSON_Delete(o);
        return NULL;
    }
    return iird_json_finish(o);
}

char *iird_json_record_start(int64_t seq)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o && cJSON_AddStringToObject(o, "type", "record") &&
              (seq < 0 || iird_json_add_num(o, "seq", (double)seq)) &&
              cJSON_AddBoolToObject(o, "recording", true);
    if (ok) return iird_json_finish(o);
    cJSON_Delete(o);
    return NULL;
}

/* recording.c -- `record`: what a session showed over time -- its light, its camera and its
 * exposure, each a track of timed keyframes -- written as an animation script
 * (docs/animation-format.md) that reproduces them at every recorded time. Not deciding when a
 * state is recorded (the session does).
 *
 * The light and camera tracks are linear; the key that ends a pause longer than a frame (1/fps) is
 * a step key (the part holds until it, then jumps, as the session showed it), so that a move after
 * a pause is not spread over the pause. The exposure track is a step track (the browser changes it
 * in steps).
 * The script lasts a whole number of frames, until at least the end of the recording, so its
 * last frame shows the state at the end. */
#include "protocol_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_KEYFRAMES = 100000 }; /* keys of every track together */
#define MAX_SECONDS 36000.0      /* the longest script docs/animation-format.md allows */

enum { TRACK_LIGHT, TRACK_CAMERA, TRACK_EXPOSURE, NUM_TRACKS };

typedef struct rec_key {
    double t;  /* seconds since start, rounded to microseconds */
    bool step; /* it ends a pause: the part jumps to it ("step": true) */
    union {
        struct {
            iir_vec3 position, direction, intensity;
            float cone, smooth; /* radians, as in iir_light */
        } light;
        iir_camera camera;
        float stops;
    } v;
} rec_key;

typedef struct rec_track {
    uint32_t count, cap;
    rec_key *keys;
} rec_track;

struct iird_recording {
    int fps;
    char scene[129];     /* the scene it was recorded on */
    char light_name[64]; /* the light the light track moves (its first key's) */
    double end;          /* iird_recording_end's time; 0 until then */
    uint32_t total;      /* keys of every track */
    rec_track tracks[NUM_TRACKS];
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
    for (int k = 0; k < NUM_TRACKS; k++) free(r->tracks[k].keys);
    free(r);
}

/* ======================== adding keys ======================== */

/* Room for one more key in tr; false on out-of-memory. */
static bool grow(rec_track *tr)
{
    if (tr->count < tr->cap) return true;
    uint32_t cap = tr->cap ? tr->cap * 2 : 64;
    if (cap > MAX_KEYFRAMES) cap = MAX_KEYFRAMES;
    rec_key *k = realloc(tr->keys, cap * sizeof *k);
    if (!k) return false;
    tr->keys = k;
    tr->cap = cap;
    return true;
}

static double round_us(double t)
{
    return fmax(0.0, round(t * 1e6) / 1e6);
}

/* The time checks of every add: finite, within MAX_SECONDS. *t is rounded to microseconds. */
static bool check_time(double *t, iird_proto_error *err)
{
    if (!isfinite(*t))
        return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "recording time is not finite");
    *t = round_us(*t);
    if (*t > MAX_SECONDS)
        return iird_proto_fail(err, IIRD_E_TOO_LARGE, NULL,
                               "the recording is longer than %.0f s; stop it", MAX_SECONDS);
    return true;
}

/* True when a key at t on track k ends a pause: a linear track whose last key is more than a
 * frame (1/fps) older. */
static bool ends_pause(const iird_recording *r, int k, double t)
{
    const rec_track *tr = &r->tracks[k];
    return k != TRACK_EXPOSURE && tr->count > 0 &&
           t - tr->keys[tr->count - 1].t > 1.0 / r->fps + 1e-9;
}

/* Appends key (at t, rounded) to track k, a step key when it ends a pause. A t at or before the
 * track's last key replaces that key's value and keeps its time. */
static bool add_key(iird_recording *r, int k, double t, rec_key key, iird_proto_error *err)
{
    if (!check_time(&t, err)) return false;
    rec_track *tr = &r->tracks[k];
    if (tr->count > 0 && t <= tr->keys[tr->count - 1].t) {
        key.t = tr->keys[tr->count - 1].t;
        key.step = tr->keys[tr->count - 1].step;
        tr->keys[tr->count - 1] = key;
        return true;
    }
    if (r->total >= MAX_KEYFRAMES)
        return iird_proto_fail(err, IIRD_E_TOO_LARGE, NULL,
                               "the recording holds the most keyframes allowed (%d); stop it",
                               MAX_KEYFRAMES);
    if (!grow(tr))
        return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory for the recording");
    key.t = t;
    key.step = ends_pause(r, k, t);
    tr->keys[tr->count++] = key;
    r->total++;
    return true;
}

bool iird_recording_room(iird_recording *r, double t, iird_proto_error *err)
{
    if (!check_time(&t, err)) return false;
    if (r->total >= MAX_KEYFRAMES)
        return iird_proto_fail(err, IIRD_E_TOO_LARGE, NULL,
                               "the recording holds the most keyframes allowed (%d); stop it",
                               MAX_KEYFRAMES);
    for (int k = 0; k < NUM_TRACKS; k++)
        if (!grow(&r->tracks[k]))
            return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory for the recording");
    return true;
}

bool iird_recording_add(iird_recording *r, double t, const iir_light *light, iird_proto_error *err)
{
    rec_key k = {.v.light = {light->position, light->direction, light->intensity, light->cone_angle,
                             light->smooth}};
    if (!add_key(r, TRACK_LIGHT, t, k, err)) return false;
    if (!r->light_name[0]) snprintf(r->light_name, sizeof r->light_name, "%s", light->name);
    return true;
}

bool iird_recording_add_camera(iird_recording *r, double t, const iir_camera *camera,
                               iird_proto_error *err)
{
    rec_key k = {.v.camera = *camera};
    return add_key(r, TRACK_CAMERA, t, k, err);
}

bool iird_recording_add_exposure(iird_recording *r, double t, float stops, iird_proto_error *err)
{
    rec_key k = {.v.stops = stops};
    return add_key(r, TRACK_EXPOSURE, t, k, err);
}

void iird_recording_end(iird_recording *r, double t)
{
    if (isfinite(t)) r->end = fmin(round_us(t), MAX_SECONDS);
}

/* ======================== the script ======================== */

/* A whole number of frames, until at least the last key and the end (at least one frame). */
static double duration(const iird_recording *r)
{
    double last = r->end;
    for (int k = 0; k < NUM_TRACKS; k++) {
        const rec_track *tr = &r->tracks[k];
        if (tr->count) last = fmax(last, tr->keys[tr->count - 1].t);
    }
    double d = ceil(last * r->fps - 1e-9) / r->fps;
    return fmin(fmax(fmax(d, last), 1.0 / r->fps), MAX_SECONDS);
}

static bool light_key(cJSON *o, const rec_key *k)
{
    float cone = fminf(iir_degrees(k->v.light.cone), 90.f);
    float smooth = fminf(fmaxf(iir_degrees(k->v.light.smooth), 0.f), cone);
    return iird_json_add_vec3(o, "position", k->v.light.position) &&
           iird_json_add_vec3(o, "direction", k->v.light.direction) &&
           iird_json_add_float(o, "cone_angle", cone) && iird_json_add_float(o, "smooth", smooth) &&
           iird_json_add_vec3(o, "intensity", k->v.light.intensity);
}

static bool camera_key(cJSON *o, const rec_key *k)
{
    const iir_camera *c = &k->v.camera;
    return iird_json_add_vec3(o, "position", c->position) &&
           iird_json_add_vec3(o, "target", c->target) && iird_json_add_vec3(o, "up", c->up) &&
           iird_json_add_float(o, "fov_y", c->fov_y);
}

static cJSON *key_json(int track, const rec_key *k)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o && iird_json_add_num(o, "t", k->t) &&
              (!k->step || cJSON_AddBoolToObject(o, "step", true));
    if (ok && track == TRACK_LIGHT) ok = light_key(o, k);
    if (ok && track == TRACK_CAMERA) ok = camera_key(o, k);
    if (ok && track == TRACK_EXPOSURE) ok = iird_json_add_float(o, "stops", k->v.stops);
    if (ok) return o;
    cJSON_Delete(o);
    return NULL;
}

/* Adds track k to the script as `name` (nothing for a track without keys). */
static bool add_track(const iird_recording *r, cJSON *script, int k, const char *name)
{
    const rec_track *tr = &r->tracks[k];
    cJSON *track = NULL, *keys = NULL;
    if (!tr->count) return true;
    bool ok =
        (track = cJSON_AddObjectToObject(script, name)) &&
        (k != TRACK_LIGHT || !r->light_name[0] ||
         cJSON_AddStringToObject(track, "name", r->light_name)) &&
        cJSON_AddStringToObject(track, "interpolation", k == TRACK_EXPOSURE ? "step" : "linear") &&
        (keys = cJSON_AddArrayToObject(track, "keys"));
    for (uint32_t i = 0; ok && i < tr->count; i++) {
        cJSON *key = key_json(k, &tr->keys[i]);
        ok = key && cJSON_AddItemToArray(keys, key);
        if (!ok) cJSON_Delete(key);
    }
    return ok;
}

/* The script as a cJSON tree; NULL on out-of-memory. */
static cJSON *script_json(const iird_recording *r)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o && (!r->scene[0] || cJSON_AddStringToObject(o, "scene", r->scene)) &&
              iird_json_add_num(o, "fps", r->fps) &&
              iird_json_add_num(o, "duration", duration(r)) &&
              add_track(r, o, TRACK_LIGHT, "light") && add_track(r, o, TRACK_CAMERA, "camera") &&
              add_track(r, o, TRACK_EXPOSURE, "exposure");
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
              iird_json_add_num(o, "keyframes", r->tracks[TRACK_LIGHT].count) &&
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

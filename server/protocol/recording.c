/* recording.c -- `record`: what a session showed over time -- its lights (the one it moves, as
 * the "light" track, or all of them, as named "lights" tracks), its camera and its exposure, each
 * a track of timed keyframes -- written as an animation script (docs/animation-format.md) that
 * reproduces them at every recorded time. Not deciding when a state is recorded (the session
 * does).
 *
 * The light and camera tracks are linear; the key that ends a pause longer than a frame (1/fps) is
 * a step key (the part holds until it, then jumps, as the session showed it), so that a move after
 * a pause is not spread over the pause. The exposure track is a step track (the browser changes it
 * in steps). A light's keys give the fields of its kind; a light with black intensity is off
 * ("on": false, written on a track's first key and where it changes) and its key keeps the
 * intensity it had before, so the intensity curve does not dip towards black around the switch.
 * The script lasts a whole number of frames, until at least the end of the recording, so its
 * last frame shows the state at the end. It names where and how it was made -- the scene, the
 * folder that scene is found in and the session's frame size -- so that `iird render --anim` of
 * it, given nothing else, renders the session's frames. */
#include "recording.h"
#include "iir/image.h" /* IIR_IMAGE_MAX_DIM */
#include "protocol_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_KEYFRAMES = 100000 }; /* keys of every track together */
#define MAX_SECONDS 36000.0      /* the longest script docs/animation-format.md allows */

enum { TRACK_LIGHT, TRACK_CAMERA, TRACK_EXPOSURE, NUM_TRACKS };

/* A light's state at a key: what the script's light keys give. */
typedef struct rec_light {
    iir_vec3 position, direction, up, intensity; /* intensity: the last lit one while off */
    iir_vec2 size;
    float cone, smooth, inner; /* radians, as in iir_light */
    bool on;                   /* intensity not black */
} rec_light;

typedef struct rec_key {
    double t;  /* seconds since start, rounded to microseconds */
    bool step; /* it ends a pause: the part jumps to it ("step": true) */
    union {
        rec_light light;
        iir_camera camera;
        float stops;
    } v;
} rec_key;

typedef struct rec_track {
    uint32_t count, cap;
    rec_key *keys;
    char name[64]; /* a light track: its light's name (the first key's) */
    iir_light_type type;
    iir_spot_profile profile; /* a light track: its light's kind, for the fields its keys give */
} rec_track;

struct iird_recording {
    int fps;
    char scene[129];   /* the scene it was recorded on */
    char scenes[4096]; /* the folder that scene is found in ("" for none) */
    int width, height; /* the session's frame size (iird_recording_set_size; 0: not given) */
    double end;        /* iird_recording_end's time; 0 until then */
    uint32_t total;    /* keys of every track */
    rec_track tracks[NUM_TRACKS];
    bool lights_started; /* iird_recording_add_lights was called: lights[] are its lights */
    uint32_t num_lights;
    rec_track *lights;
};

iird_recording *iird_recording_create(int fps, const char *scene, const char *scenes_dir)
{
    iird_recording *r = calloc(1, sizeof *r);
    if (!r) return NULL;
    r->fps = fps < 1 ? 1 : fps > 240 ? 240 : fps;
    snprintf(r->scene, sizeof r->scene, "%s", scene ? scene : "");
    snprintf(r->scenes, sizeof r->scenes, "%s", scenes_dir ? scenes_dir : "");
    return r;
}

void iird_recording_set_size(iird_recording *r, int width, int height)
{
    bool ok = width >= 1 && width <= IIR_IMAGE_MAX_DIM && height >= 1 &&
              height <= IIR_IMAGE_MAX_DIM; /* the parser's range */
    r->width = ok ? width : 0;
    r->height = ok ? height : 0;
}

int iird_recording_fps(const iird_recording *r)
{
    return r->fps;
}

void iird_recording_destroy(iird_recording *r)
{
    if (!r) return;
    for (int k = 0; k < NUM_TRACKS; k++) free(r->tracks[k].keys);
    for (uint32_t i = 0; i < r->num_lights; i++) free(r->lights[i].keys);
    free(r->lights);
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

/* True when a key at t on track tr ends a pause: a linear track whose last key is more than a
 * frame (1/fps) older. */
static bool ends_pause(const iird_recording *r, const rec_track *tr, double t)
{
    return tr != &r->tracks[TRACK_EXPOSURE] && tr->count > 0 &&
           t - tr->keys[tr->count - 1].t > 1.0 / r->fps + 1e-9;
}

/* True when a key at t (rounded) would replace tr's last key rather than follow it. */
static bool replaces_last(const rec_track *tr, double t)
{
    return tr->count > 0 && t <= tr->keys[tr->count - 1].t;
}

/* Appends key (at t, rounded) to track tr, a step key when it ends a pause. A t at or before the
 * track's last key replaces that key's value and keeps its time. */
static bool add_key(iird_recording *r, rec_track *tr, double t, rec_key key, iird_proto_error *err)
{
    if (!check_time(&t, err)) return false;
    if (replaces_last(tr, t)) {
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
    key.step = ends_pause(r, tr, t);
    tr->keys[tr->count++] = key;
    r->total++;
    return true;
}

/* Keys one state of every part takes: one per light of add_lights, at least one. */
static uint32_t state_keys(const iird_recording *r)
{
    return r->num_lights > 1 ? r->num_lights : 1;
}

bool iird_recording_room(iird_recording *r, double t, iird_proto_error *err)
{
    if (!check_time(&t, err)) return false;
    if (r->total + state_keys(r) > MAX_KEYFRAMES)
        return iird_proto_fail(err, IIRD_E_TOO_LARGE, NULL,
                               "the recording holds the most keyframes allowed (%d); stop it",
                               MAX_KEYFRAMES);
    bool ok = true;
    for (int k = 0; k < NUM_TRACKS; k++) ok = ok && grow(&r->tracks[k]);
    for (uint32_t i = 0; i < r->num_lights; i++) ok = ok && grow(&r->lights[i]);
    if (!ok) return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory for the recording");
    return true;
}

/* The key of light L on track tr: off when its intensity is black, then keeping the intensity of
 * the track's last key (black for a first key). */
static rec_key light_key(const rec_track *tr, const iir_light *L)
{
    rec_light l = {L->position,   L->direction, L->up,          L->intensity, L->size,
                   L->cone_angle, L->smooth,    L->inner_angle, true};
    l.on = fmaxf(L->intensity.x, fmaxf(L->intensity.y, L->intensity.z)) > 0.f;
    if (!l.on) l.intensity = tr->count ? tr->keys[tr->count - 1].v.light.intensity : iir_v3s(0.f);
    return (rec_key){.v.light = l};
}

/* Names the track after L and takes its kind when it has no key yet. */
static void name_track(rec_track *tr, const iir_light *L)
{
    if (tr->count) return;
    snprintf(tr->name, sizeof tr->name, "%s", L->name);
    tr->type = L->type;
    tr->profile = L->profile;
}

bool iird_recording_add(iird_recording *r, double t, const iir_light *light, iird_proto_error *err)
{
    rec_track *tr = &r->tracks[TRACK_LIGHT];
    name_track(tr, light); /* a failed first add leaves a name on an empty track: never written */
    return add_key(r, tr, t, light_key(tr, light), err);
}

/* The first add_lights: one track per light, named after it. */
static bool start_lights(iird_recording *r, const iir_light *lights, uint32_t n,
                         iird_proto_error *err)
{
    r->lights = n ? calloc(n, sizeof *r->lights) : NULL;
    if (n && !r->lights)
        return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory for the recording");
    r->num_lights = n;
    r->lights_started = true;
    for (uint32_t i = 0; i < n; i++) name_track(&r->lights[i], &lights[i]);
    return true;
}

/* The same lights as the first add_lights (as many, the same names and kinds, in order), or
 * false with err naming the first difference. */
static bool same_lights(const iird_recording *r, const iir_light *lights, uint32_t n,
                        iird_proto_error *err)
{
    if (n != r->num_lights)
        return iird_proto_fail(err, IIRD_E_INTERNAL, NULL,
                               "the recording's %u lights are now %u; stop it and start a new one",
                               r->num_lights, n);
    for (uint32_t i = 0; i < n; i++) {
        const rec_track *tr = &r->lights[i];
        if (strcmp(tr->name, lights[i].name) || tr->type != lights[i].type ||
            tr->profile != lights[i].profile)
            return iird_proto_fail(err, IIRD_E_INTERNAL, NULL,
                                   "the recording's light %u, '%s', is now '%s' (%s); stop it and "
                                   "start a new one",
                                   i, tr->name, lights[i].name, iir_light_kind(&lights[i]));
    }
    return true;
}

/* Room for one key on every light track at t (rounded): nothing can fail after it. */
static bool lights_room(iird_recording *r, double t, iird_proto_error *err)
{
    bool adds = r->num_lights && !replaces_last(&r->lights[0], t);
    if (adds && r->total + r->num_lights > MAX_KEYFRAMES)
        return iird_proto_fail(err, IIRD_E_TOO_LARGE, NULL,
                               "the recording holds the most keyframes allowed (%d); stop it",
                               MAX_KEYFRAMES);
    for (uint32_t i = 0; i < r->num_lights; i++)
        if (!grow(&r->lights[i]))
            return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory for the recording");
    return true;
}

bool iird_recording_add_lights(iird_recording *r, double t, const iir_light *lights, uint32_t n,
                               iird_proto_error *err)
{
    if (!check_time(&t, err)) return false;
    if (!r->lights_started && !start_lights(r, lights, n, err)) return false;
    if (!same_lights(r, lights, n, err) || !lights_room(r, t, err)) return false;
    for (uint32_t i = 0; i < n; i++) /* cannot fail now: time checked, room made */
        add_key(r, &r->lights[i], t, light_key(&r->lights[i], &lights[i]), err);
    return true;
}

bool iird_recording_add_camera(iird_recording *r, double t, const iir_camera *camera,
                               iird_proto_error *err)
{
    rec_key k = {.v.camera = *camera};
    return add_key(r, &r->tracks[TRACK_CAMERA], t, k, err);
}

bool iird_recording_add_exposure(iird_recording *r, double t, float stops, iird_proto_error *err)
{
    rec_key k = {.v.stops = stops};
    return add_key(r, &r->tracks[TRACK_EXPOSURE], t, k, err);
}

void iird_recording_end(iird_recording *r, double t)
{
    if (isfinite(t)) r->end = fmin(round_us(t), MAX_SECONDS);
}

/* ======================== the script ======================== */

static double last_t(const rec_track *tr, double t)
{
    return tr->count ? fmax(t, tr->keys[tr->count - 1].t) : t;
}

/* A whole number of frames, until at least the last key and the end (at least one frame). */
static double duration(const iird_recording *r)
{
    double last = r->end;
    for (int k = 0; k < NUM_TRACKS; k++) last = last_t(&r->tracks[k], last);
    for (uint32_t i = 0; i < r->num_lights; i++) last = last_t(&r->lights[i], last);
    double d = ceil(last * r->fps - 1e-9) / r->fps;
    return fmin(fmax(fmax(d, last), 1.0 / r->fps), MAX_SECONDS);
}

/* A spot's cone, smooth edge (cosine) or inner cone (glTF), in degrees within the parser's ranges.
 */
static bool spot_json(cJSON *o, const rec_track *tr, const rec_light *l)
{
    float cone = fminf(fmaxf(iir_degrees(l->cone), 1e-3f), 90.f);
    bool gltf = tr->profile == IIR_SPOT_GLTF;
    float edge = fminf(fmaxf(iir_degrees(gltf ? l->inner : l->smooth), 0.f), cone);
    return iird_json_add_float(o, "cone_angle", cone) &&
           iird_json_add_float(o, gltf ? "inner_angle" : "smooth", edge);
}

/* An area light's size, within the parser's (0, 1e6]. */
static bool size_json(cJSON *o, const rec_light *l)
{
    cJSON *a = cJSON_AddArrayToObject(o, "size");
    float w = fminf(fmaxf(l->size.x, 1e-6f), 1e6f), h = fminf(fmaxf(l->size.y, 1e-6f), 1e6f);
    return a && cJSON_AddItemToArray(a, cJSON_CreateNumber(iird_compact_float(w))) &&
           cJSON_AddItemToArray(a, cJSON_CreateNumber(iird_compact_float(h)));
}

/* Key i of light track tr: the fields of its kind; "on" on the first key and where it changes. */
static bool light_json(cJSON *o, const rec_track *tr, uint32_t i)
{
    const rec_light *l = &tr->keys[i].v.light;
    bool sun = tr->type == IIR_LIGHT_SUN, point = tr->type == IIR_LIGHT_POINT;
    bool ok = (sun || iird_json_add_vec3(o, "position", l->position)) &&
              (point || iird_json_add_vec3(o, "direction", l->direction)) &&
              (point || !(iir_length(l->up) > 1e-12f) || iird_json_add_vec3(o, "up", l->up)) &&
              (tr->type != IIR_LIGHT_SPOT || spot_json(o, tr, l)) &&
              (tr->type != IIR_LIGHT_AREA || size_json(o, l)) &&
              iird_json_add_vec3(o, "intensity", l->intensity);
    if (ok && (i == 0 || l->on != tr->keys[i - 1].v.light.on))
        ok = cJSON_AddBoolToObject(o, "on", l->on) != NULL;
    return ok;
}

static bool camera_key(cJSON *o, const rec_key *k)
{
    const iir_camera *c = &k->v.camera;
    return iird_json_add_vec3(o, "position", c->position) &&
           iird_json_add_vec3(o, "target", c->target) && iird_json_add_vec3(o, "up", c->up) &&
           iird_json_add_float(o, "fov_y", c->fov_y);
}

/* Key i of track tr, a track of kind k (TRACK_LIGHT for every light track). */
static cJSON *key_json(int k, const rec_track *tr, uint32_t i)
{
    const rec_key *key = &tr->keys[i];
    cJSON *o = cJSON_CreateObject();
    bool ok = o && iird_json_add_num(o, "t", key->t) &&
              (!key->step || cJSON_AddBoolToObject(o, "step", true));
    if (ok && k == TRACK_LIGHT) ok = light_json(o, tr, i);
    if (ok && k == TRACK_CAMERA) ok = camera_key(o, key);
    if (ok && k == TRACK_EXPOSURE) ok = iird_json_add_float(o, "stops", key->v.stops);
    if (ok) return o;
    cJSON_Delete(o);
    return NULL;
}

/* Fills the track object `track` from tr (of kind k): name, interpolation, keys. */
static bool track_json(cJSON *track, int k, const rec_track *tr)
{
    cJSON *keys = NULL;
    bool ok =
        track &&
        (k != TRACK_LIGHT || !tr->name[0] || cJSON_AddStringToObject(track, "name", tr->name)) &&
        cJSON_AddStringToObject(track, "interpolation", k == TRACK_EXPOSURE ? "step" : "linear") &&
        (keys = cJSON_AddArrayToObject(track, "keys"));
    for (uint32_t i = 0; ok && i < tr->count; i++) {
        cJSON *key = key_json(k, tr, i);
        ok = key && cJSON_AddItemToArray(keys, key);
        if (!ok) cJSON_Delete(key);
    }
    return ok;
}

/* Adds track k to the script as `name` (nothing for a track without keys). */
static bool add_track(const iird_recording *r, cJSON *script, int k, const char *name)
{
    const rec_track *tr = &r->tracks[k];
    return !tr->count || track_json(cJSON_AddObjectToObject(script, name), k, tr);
}

/* Adds "lights": every light of add_lights, a named track each (nothing before its first key). */
static bool add_lights(const iird_recording *r, cJSON *script)
{
    if (!r->num_lights || !r->lights[0].count) return true;
    cJSON *arr = cJSON_AddArrayToObject(script, "lights");
    bool ok = arr != NULL;
    for (uint32_t i = 0; ok && i < r->num_lights; i++) {
        cJSON *track = cJSON_CreateObject();
        ok = track_json(track, TRACK_LIGHT, &r->lights[i]) && cJSON_AddItemToArray(arr, track);
        if (!ok) cJSON_Delete(track);
    }
    return ok;
}

/* The light keyframes: the light track's, else each "lights" track's. */
static uint32_t light_keys(const iird_recording *r)
{
    uint32_t n = r->tracks[TRACK_LIGHT].count;
    return n || !r->num_lights ? n : r->lights[0].count;
}

/* "scene", "scenes" and "size": where and how the script was made (each when known). */
static bool origin_json(cJSON *o, const iird_recording *r)
{
    cJSON *size = NULL;
    return (!r->scene[0] || cJSON_AddStringToObject(o, "scene", r->scene)) &&
           (!r->scenes[0] || cJSON_AddStringToObject(o, "scenes", r->scenes)) &&
           (!r->width || ((size = cJSON_AddArrayToObject(o, "size")) &&
                          cJSON_AddItemToArray(size, cJSON_CreateNumber(r->width)) &&
                          cJSON_AddItemToArray(size, cJSON_CreateNumber(r->height))));
}

/* The script as a cJSON tree; NULL on out-of-memory. */
static cJSON *script_json(const iird_recording *r)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o && origin_json(o, r) && iird_json_add_num(o, "fps", r->fps) &&
              iird_json_add_num(o, "duration", duration(r)) &&
              add_track(r, o, TRACK_LIGHT, "light") && add_lights(r, o) &&
              add_track(r, o, TRACK_CAMERA, "camera") &&
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
              iird_json_add_num(o, "keyframes", light_keys(r)) &&
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

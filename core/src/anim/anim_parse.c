/* anim_parse.c -- reading and validating animation scripts into an iir_anim, and the frame
 * arithmetic; not evaluating tracks (anim_eval.c) or checking them against a scene's lights
 * (anim_check.c). The format is docs/animation-format.md. */
#include "anim_internal.h"
#include "iir/json_read.h"
#include "iir/image.h" /* IIR_IMAGE_MAX_DIM: a "size" side */

#include <cjson/cJSON.h>

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define IIR_ANIM_MAX_BYTES (16u << 20)
#define IIR_ANIM_PATH 160

/* Which track is being parsed: each has its own key fields. */
typedef enum anim_kind { KIND_LIGHT, KIND_CAMERA, KIND_EXPOSURE } anim_kind;

typedef struct iir_anim_ctx {
    const char *src; /* prefix of messages */
    iir_error *err;
    double duration;
    anim_kind kind;   /* the track being parsed */
    iir_json_file jf; /* json_read.h's readers, their faults into err */
} iir_anim_ctx;

static iir_status anim_fail(const iir_anim_ctx *c, iir_status st, const char *path, const char *fmt,
                            ...) __attribute__((format(printf, 4, 5)));

static iir_status anim_fail(const iir_anim_ctx *c, iir_status st, const char *path, const char *fmt,
                            ...)
{
    char msg[384];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return iir_fail(c->err, st, "%s: %s: %s", c->src, path, msg);
}

/* out = path.name (or name at the top level). */
static void path_join(char *out, const char *path, const char *name)
{
    /* a path longer than the buffer is cut short; the message stays readable */
    if (snprintf(out, IIR_ANIM_PATH, "%s%s%s", path, *path ? "." : "", name) >= IIR_ANIM_PATH)
        out[IIR_ANIM_PATH - 1] = '\0';
}

/* ======================== fields (json_read.h) ======================== */

/* IIR_ERR_FORMAT naming the first member of obj not in allowed (NULL-terminated) or given twice,
 * or obj when it is no object. */
static iir_status check_fields(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                               const char *const *allowed)
{
    return iir_json_file_status(&c->jf, iir_json_fields(&c->jf.r, obj, path, allowed));
}

/* Member `name` of obj and its path p; *present tells whether it is there. */
static const cJSON *member(const cJSON *obj, const char *path, const char *name,
                           char p[IIR_ANIM_PATH], bool *present)
{
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(obj, name);
    *present = m != NULL;
    path_join(p, path, name);
    return m;
}

/* A number member that must lie in [lo, hi] (lo excluded when open_lo). */
static iir_status get_ranged(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                             const char *name, double lo, bool open_lo, double hi, double *out,
                             bool *present)
{
    char p[IIR_ANIM_PATH];
    const cJSON *m = member(obj, path, name, p, present);
    if (!m) return IIR_OK;
    iir_json_range range = {lo, hi, open_lo, false, NULL};
    return iir_json_file_status(&c->jf, iir_json_number(&c->jf.r, m, p, range, out));
}

/* Bound of every vec3 element (coordinates, directions, intensities), as in the protocol and the
 * sidecar: a direction's or an aim's length, squared, must not overflow a float. */
#define MAX_VEC3_ELEMENT 1e6

/* A member [x, y, z] of numbers within +-MAX_VEC3_ELEMENT. A plain number is accepted as
 * [v, v, v] when allow_scalar. */
static iir_status get_vec3(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                           const char *name, bool allow_scalar, iir_vec3 *out, bool *present)
{
    char p[IIR_ANIM_PATH];
    const cJSON *m = member(obj, path, name, p, present);
    if (!m) return IIR_OK;
    if (allow_scalar && !cJSON_IsArray(m)) {
        if (!cJSON_IsNumber(m))
            return anim_fail(c, IIR_ERR_FORMAT, p,
                             "must be a number or an array of 3 numbers, got %s", iir_json_kind(m));
        double v = 0.0;
        iir_json_range range = {-MAX_VEC3_ELEMENT, MAX_VEC3_ELEMENT, false, false, NULL};
        if (!iir_json_number(&c->jf.r, m, p, range, &v)) return c->jf.status;
        *out = iir_v3s((float)v);
        return IIR_OK;
    }
    return iir_json_file_status(
        &c->jf, iir_json_vec3(&c->jf.r, m, p, -MAX_VEC3_ELEMENT, MAX_VEC3_ELEMENT, out));
}

/* A member [w, h] of numbers in (0, 1e6] (an area light's size), kept in out->x, out->y. */
static iir_status get_size(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                           const char *name, iir_vec3 *out, bool *present)
{
    char p[IIR_ANIM_PATH];
    const cJSON *m = member(obj, path, name, p, present);
    if (!m) return IIR_OK;
    double v[2];
    if (!iir_json_numbers(&c->jf.r, m, p, 2, 0.0, MAX_VEC3_ELEMENT, v)) return c->jf.status;
    for (int i = 0; i < 2; i++)
        if (!(v[i] > 0.0))
            return anim_fail(c, IIR_ERR_INVALID, p, "element %d (%g) is outside (0, 1e6]", i, v[i]);
    *out = iir_v3((float)v[0], (float)v[1], 0.f);
    return IIR_OK;
}

/* A member true / false. */
static iir_status get_bool(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                           const char *name, bool *out, bool *present)
{
    char p[IIR_ANIM_PATH];
    const cJSON *m = member(obj, path, name, p, present);
    if (!m) return IIR_OK;
    return iir_json_file_status(&c->jf, iir_json_bool(&c->jf.r, m, p, out));
}

/* ======================== keys ======================== */

/* up (camera, light): any length, not zero. */
static iir_status parse_up(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                           iir_anim_key *k)
{
    char p[IIR_ANIM_PATH];
    bool has;
    iir_status st = get_vec3(c, obj, path, "up", false, &k->up, &has);
    k->fields |= has ? IIR_AF_UP : 0u;
    path_join(p, path, "up");
    if (st == IIR_OK && has && !(iir_length(k->up) > 1e-12f))
        return anim_fail(c, IIR_ERR_INVALID, p, "must not be zero");
    return st;
}

/* Position, aim (direction XOR target) and, for a light, up of a key or parametric object. */
static iir_status parse_placement(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                                  iir_anim_key *k)
{
    char p[IIR_ANIM_PATH];
    bool has_p, has_d = false, has_t;
    iir_status st = get_vec3(c, obj, path, "position", false, &k->position, &has_p);
    if (st == IIR_OK && c->kind == KIND_LIGHT)
        st = get_vec3(c, obj, path, "direction", false, &k->direction, &has_d);
    if (st == IIR_OK) st = get_vec3(c, obj, path, "target", false, &k->target, &has_t);
    if (st != IIR_OK) return st;
    k->fields |= (has_p ? IIR_AF_POSITION : 0u) | (has_d ? IIR_AF_DIRECTION : 0u) |
                 (has_t ? IIR_AF_TARGET : 0u);
    path_join(p, path, "direction");
    if (has_d && has_t)
        return anim_fail(c, IIR_ERR_INVALID, p, "give direction or target, not both");
    if (has_d && !(iir_length(k->direction) > 1e-12f))
        return anim_fail(c, IIR_ERR_INVALID, p, "must not be zero");
    k->direction = iir_normalize(k->direction);
    path_join(p, path, "target");
    if (has_p && has_t && iir_length(iir_sub(k->target, k->position)) < 1e-6f)
        return anim_fail(c, IIR_ERR_INVALID, p, "equals position");
    return c->kind == KIND_LIGHT ? parse_up(c, obj, path, k) : IIR_OK;
}

/* Camera: fov_y and up. */
static iir_status parse_lens(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                             iir_anim_key *k)
{
    bool has;
    double v = 0.0;
    iir_status st = get_ranged(c, obj, path, "fov_y", 0.0, true, 179.999, &v, &has);
    k->fov = (float)v;
    k->fields |= has ? IIR_AF_FOV : 0u;
    return st == IIR_OK ? parse_up(c, obj, path, k) : st;
}

/* Exposure: stops, the range of iird render --exposure. */
static iir_status parse_stops(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                              iir_anim_key *k)
{
    bool has;
    double v = 0.0;
    iir_status st = get_ranged(c, obj, path, "stops", -30.0, false, 30.0, &v, &has);
    k->stops = (float)v;
    k->fields |= has ? IIR_AF_EXPOSURE : 0u;
    return st;
}

/* Light: inner_angle (glTF spot), size (area light), on. */
static iir_status parse_light_extras(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                                     iir_anim_key *k)
{
    char p[IIR_ANIM_PATH];
    bool has;
    double v = 0.0;
    iir_status st = get_ranged(c, obj, path, "inner_angle", 0.0, false, 90.0, &v, &has);
    k->inner = (float)v;
    k->fields |= has ? IIR_AF_INNER : 0u;
    path_join(p, path, "inner_angle");
    if (st == IIR_OK && (k->fields & IIR_AF_CONE) && has && k->inner > k->cone)
        return anim_fail(c, IIR_ERR_INVALID, p, "%g is wider than cone_angle %g", k->inner,
                         k->cone);
    if (st == IIR_OK) st = get_size(c, obj, path, "size", &k->size, &has);
    k->fields |= has ? IIR_AF_SIZE : 0u;
    if (st == IIR_OK) st = get_bool(c, obj, path, "on", &k->on, &has);
    k->fields |= has ? IIR_AF_ON : 0u;
    return st;
}

/* Light: cone_angle, smooth, intensity, inner_angle, size, on; camera: fov_y, up; exposure:
 * stops. */
static iir_status parse_optics(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                               iir_anim_key *k)
{
    char p[IIR_ANIM_PATH];
    bool has;
    double v = 0.0;
    if (c->kind == KIND_CAMERA) return parse_lens(c, obj, path, k);
    if (c->kind == KIND_EXPOSURE) return parse_stops(c, obj, path, k);
    iir_status st = get_ranged(c, obj, path, "cone_angle", 0.0, true, 90.0, &v, &has);
    k->cone = (float)v;
    k->fields |= has ? IIR_AF_CONE : 0u;
    if (st == IIR_OK) st = get_ranged(c, obj, path, "smooth", 0.0, false, 90.0, &v, &has);
    k->smooth = (float)v;
    k->fields |= has ? IIR_AF_SMOOTH : 0u;
    path_join(p, path, "smooth");
    if (st == IIR_OK && (k->fields & IIR_AF_CONE) && has && k->smooth > k->cone)
        return anim_fail(c, IIR_ERR_INVALID, p, "%g is wider than cone_angle %g", k->smooth,
                         k->cone);
    if (st == IIR_OK) st = get_vec3(c, obj, path, "intensity", true, &k->intensity, &has);
    k->fields |= has ? IIR_AF_INTENSITY : 0u;
    path_join(p, path, "intensity");
    if (st == IIR_OK && has && fminf(k->intensity.x, fminf(k->intensity.y, k->intensity.z)) < 0.f)
        return anim_fail(c, IIR_ERR_INVALID, p, "must not be negative");
    return st == IIR_OK ? parse_light_extras(c, obj, path, k) : st;
}

static const char *const LIGHT_KEY_FIELDS[] = {
    "t",      "step",        "position", "direction", "target", "up", "cone_angle",
    "smooth", "inner_angle", "size",     "intensity", "on",     NULL};
static const char *const CAMERA_KEY_FIELDS[] = {"t",     "step", "position", "target",
                                                "fov_y", "up",   NULL};
static const char *const EXPOSURE_KEY_FIELDS[] = {"t", "step", "stops", NULL};
static const char *const *const KEY_FIELDS[] = {LIGHT_KEY_FIELDS, CAMERA_KEY_FIELDS,
                                                EXPOSURE_KEY_FIELDS};

/* One keyframe; prev_t is the previous key's time (-inf for the first). */
static iir_status parse_key(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                            double prev_t, iir_anim_key *k)
{
    char p[IIR_ANIM_PATH];
    bool has;
    iir_status st = check_fields(c, obj, path, KEY_FIELDS[c->kind]);
    if (st == IIR_OK) st = get_ranged(c, obj, path, "t", 0.0, false, c->duration, &k->t, &has);
    if (st != IIR_OK) return st;
    path_join(p, path, "t");
    if (!has) return anim_fail(c, IIR_ERR_FORMAT, p, "is missing");
    if (!(k->t > prev_t))
        return anim_fail(c, IIR_ERR_INVALID, p, "%g is not after the previous key's %g", k->t,
                         prev_t);
    const cJSON *step = cJSON_GetObjectItemCaseSensitive(obj, "step");
    path_join(p, path, "step");
    if (step && !cJSON_IsBool(step)) return anim_fail(c, IIR_ERR_FORMAT, p, "must be true/false");
    k->step = cJSON_IsTrue(step);
    st = c->kind == KIND_EXPOSURE ? IIR_OK : parse_placement(c, obj, path, k);
    return st == IIR_OK ? parse_optics(c, obj, path, k) : st;
}

static iir_status parse_interp(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                               iir_anim_interp *out)
{
    char p[IIR_ANIM_PATH];
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(obj, "interpolation");
    *out = IIR_ANIM_LINEAR;
    if (!m) return IIR_OK;
    path_join(p, path, "interpolation");
    const char *s = cJSON_GetStringValue(m);
    if (!s) return anim_fail(c, IIR_ERR_FORMAT, p, "must be a string");
    if (strcmp(s, "linear") == 0) return IIR_OK;
    *out = strcmp(s, "catmull-rom") == 0 ? IIR_ANIM_CATMULL_ROM : IIR_ANIM_STEP;
    if (*out == IIR_ANIM_STEP && strcmp(s, "step") != 0)
        return anim_fail(c, IIR_ERR_INVALID, p,
                         "'%s' is not one of \"linear\", \"catmull-rom\", \"step\"", s);
    return IIR_OK;
}

/* Each key's on_held: the "on" of the last key at or before it that gives one (true before). */
static void hold_on(iir_anim_track *tr)
{
    bool on = true;
    for (int i = 0; i < tr->num_keys; i++) {
        if (tr->keys[i].fields & IIR_AF_ON) on = tr->keys[i].on;
        tr->keys[i].on_held = on;
    }
}

static iir_status parse_keys(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                             iir_anim_track *tr)
{
    char p[IIR_ANIM_PATH], kp[IIR_ANIM_PATH];
    const cJSON *keys = cJSON_GetObjectItemCaseSensitive(obj, "keys");
    path_join(p, path, "keys");
    if (!cJSON_IsArray(keys) || cJSON_GetArraySize(keys) < 1)
        return anim_fail(c, IIR_ERR_FORMAT, p, "must be a non-empty array of keys");
    iir_status st = parse_interp(c, obj, path, &tr->interp);
    if (st != IIR_OK) return st;
    tr->path = IIR_ANIM_KEYS;
    tr->num_keys = cJSON_GetArraySize(keys);
    tr->keys = calloc((size_t)tr->num_keys, sizeof *tr->keys);
    if (!tr->keys) return anim_fail(c, IIR_ERR_NOMEM, p, "out of memory");
    double prev_t = -INFINITY;
    /* Walk the child list: cJSON_GetArrayItem(keys, i) is O(i), so indexing is quadratic. */
    const cJSON *key = keys->child;
    for (int i = 0; i < tr->num_keys && st == IIR_OK; i++, key = key->next) {
        if (snprintf(kp, sizeof kp, "%s[%d]", p, i) >= (int)sizeof kp) kp[sizeof kp - 1] = '\0';
        st = parse_key(c, key, kp, prev_t, &tr->keys[i]);
        prev_t = tr->keys[i].t;
    }
    hold_on(tr);
    return st;
}

/* ======================== parametric paths ======================== */

static const char *const LIGHT_ORBIT_FIELDS[] = {
    "center",     "radius", "turns",       "phase", "direction", "target", "up",
    "cone_angle", "smooth", "inner_angle", "size",  "intensity", "on",     NULL};
static const char *const CAMERA_ORBIT_FIELDS[] = {"center", "radius", "turns", "phase",
                                                  "target", "fov_y",  "up",    NULL};
static const char *const LIGHT_SWEEP_FIELDS[] = {"from", "to",         "direction", "target",
                                                 "up",   "cone_angle", "smooth",    "inner_angle",
                                                 "size", "intensity",  "on",        NULL};
static const char *const CAMERA_SWEEP_FIELDS[] = {"from", "to", "target", "fov_y", "up", NULL};

/* A required vec3 member. */
static iir_status need_vec3(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                            const char *name, iir_vec3 *out)
{
    char p[IIR_ANIM_PATH];
    bool has;
    iir_status st = get_vec3(c, obj, path, name, false, out, &has);
    path_join(p, path, name);
    if (st == IIR_OK && !has) return anim_fail(c, IIR_ERR_FORMAT, p, "is missing");
    return st;
}

static iir_status parse_orbit(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                              iir_anim_track *tr)
{
    char p[IIR_ANIM_PATH];
    bool has = false;
    double phase = 0.0;
    tr->path = IIR_ANIM_ORBIT;
    tr->turns = 1.0;
    iir_status st = need_vec3(c, obj, path, "center", &tr->center);
    if (st == IIR_OK) st = get_ranged(c, obj, path, "radius", 0.0, true, 1e6, &tr->radius, &has);
    path_join(p, path, "radius");
    if (st == IIR_OK && !has) return anim_fail(c, IIR_ERR_FORMAT, p, "is missing");
    if (st == IIR_OK) st = get_ranged(c, obj, path, "turns", -1e4, false, 1e4, &tr->turns, &has);
    if (st == IIR_OK) st = get_ranged(c, obj, path, "phase", -360, false, 360, &phase, &has);
    tr->phase = phase * (3.14159265358979323846 / 180.0);
    return st;
}

static iir_status parse_sweep(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                              iir_anim_track *tr)
{
    tr->path = IIR_ANIM_SWEEP;
    iir_status st = need_vec3(c, obj, path, "from", &tr->from);
    return st == IIR_OK ? need_vec3(c, obj, path, "to", &tr->to) : st;
}

/* "orbit": {...} or "sweep": {...}: the position from the parameters, the rest in one key. */
static iir_status parse_parametric(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                                   bool orbit, iir_anim_track *tr)
{
    bool camera = c->kind == KIND_CAMERA;
    const char *const *allowed = orbit ? (camera ? CAMERA_ORBIT_FIELDS : LIGHT_ORBIT_FIELDS)
                                       : (camera ? CAMERA_SWEEP_FIELDS : LIGHT_SWEEP_FIELDS);
    iir_status st = check_fields(c, obj, path, allowed);
    if (st != IIR_OK) return st;
    tr->interp = IIR_ANIM_LINEAR;
    tr->num_keys = 1;
    tr->keys = calloc(1, sizeof *tr->keys);
    if (!tr->keys) return anim_fail(c, IIR_ERR_NOMEM, path, "out of memory");
    st = orbit ? parse_orbit(c, obj, path, tr) : parse_sweep(c, obj, path, tr);
    if (st == IIR_OK) st = parse_placement(c, obj, path, &tr->keys[0]);
    if (st == IIR_OK) st = parse_optics(c, obj, path, &tr->keys[0]);
    hold_on(tr);
    return st;
}

static const char *const LIGHT_TRACK_FIELDS[] = {"name",  "interpolation", "keys",
                                                 "orbit", "sweep",         NULL};
static const char *const CAMERA_TRACK_FIELDS[] = {"interpolation", "keys", "orbit", "sweep", NULL};
static const char *const EXPOSURE_TRACK_FIELDS[] = {"interpolation", "keys", NULL};
static const char *const *const TRACK_FIELDS[] = {LIGHT_TRACK_FIELDS, CAMERA_TRACK_FIELDS,
                                                  EXPOSURE_TRACK_FIELDS};

/* A light track's "name": the scene light it moves (required in "lights"). */
static iir_status parse_track_name(const iir_anim_ctx *c, const cJSON *obj, const char *path,
                                   bool required, iir_anim_track *tr)
{
    char p[IIR_ANIM_PATH];
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(obj, "name");
    path_join(p, path, "name");
    if (!name && required)
        return anim_fail(c, IIR_ERR_FORMAT, p, "is missing: the name of the scene light it moves");
    if (!name) return IIR_OK;
    if (!cJSON_IsString(name) || !name->valuestring[0] ||
        strlen(name->valuestring) >= sizeof tr->name)
        return anim_fail(c, IIR_ERR_FORMAT, p, "must be a light's name of 1 to %zu bytes",
                         sizeof tr->name - 1);
    snprintf(tr->name, sizeof tr->name, "%s", name->valuestring);
    return IIR_OK;
}

/* "exposure": a number is a constant, one key at t = 0. */
static iir_status parse_constant_exposure(iir_anim_ctx *c, const cJSON *obj, iir_anim_track *tr)
{
    tr->present = true;
    tr->num_keys = 1;
    tr->keys = calloc(1, sizeof *tr->keys);
    if (!tr->keys) return anim_fail(c, IIR_ERR_NOMEM, "exposure", "out of memory");
    double v = obj->valuedouble;
    if (!isfinite(v) || v < -30.0 || v > 30.0)
        return anim_fail(c, IIR_ERR_INVALID, "exposure", "%g is outside [-30, 30] stops", v);
    tr->keys[0].stops = (float)v;
    tr->keys[0].fields = IIR_AF_EXPOSURE;
    return IIR_OK;
}

static iir_status parse_track(iir_anim_ctx *c, const cJSON *obj, const char *name,
                              iir_anim_track *tr)
{
    char p[IIR_ANIM_PATH];
    if (!obj) return IIR_OK;
    c->kind = !strcmp(name, "camera")     ? KIND_CAMERA
              : !strcmp(name, "exposure") ? KIND_EXPOSURE
                                          : KIND_LIGHT;
    if (c->kind == KIND_EXPOSURE && cJSON_IsNumber(obj)) return parse_constant_exposure(c, obj, tr);
    tr->present = true;
    iir_status st = check_fields(c, obj, name, TRACK_FIELDS[c->kind]);
    if (st != IIR_OK) return st;
    const cJSON *keys = cJSON_GetObjectItemCaseSensitive(obj, "keys");
    const cJSON *orbit = cJSON_GetObjectItemCaseSensitive(obj, "orbit");
    const cJSON *sweep = cJSON_GetObjectItemCaseSensitive(obj, "sweep");
    if ((keys != NULL) + (orbit != NULL) + (sweep != NULL) != 1)
        return anim_fail(c, IIR_ERR_FORMAT, name,
                         c->kind == KIND_EXPOSURE ? "needs keys (or give a number)"
                                                  : "needs exactly one of keys, orbit, sweep");
    if (keys) return parse_keys(c, obj, name, tr);
    path_join(p, name, "interpolation");
    if (cJSON_GetObjectItemCaseSensitive(obj, "interpolation"))
        return anim_fail(c, IIR_ERR_FORMAT, p, "only applies to keys");
    path_join(p, name, orbit ? "orbit" : "sweep");
    return parse_parametric(c, orbit ? orbit : sweep, p, orbit != NULL, tr);
}

/* ======================== the script ======================== */

static const char *const TOP_FIELDS[] = {"fps",    "duration",    "light", "lights",
                                         "camera", "description", "scene", "scenes",
                                         "size",   "exposure",    NULL};

/* Track i of "lights" (at path): a light track with a name no other track of the script has. */
static iir_status parse_named_track(iir_anim_ctx *c, const cJSON *obj, const char *path,
                                    iir_anim *a, int i)
{
    char p[IIR_ANIM_PATH];
    iir_anim_track *tr = &a->lights[i];
    iir_status st = parse_track(c, obj, path, tr);
    if (st == IIR_OK) st = parse_track_name(c, obj, path, true, tr);
    if (st != IIR_OK) return st;
    path_join(p, path, "name");
    if (a->light.present && !strcmp(a->light.name, tr->name))
        return anim_fail(c, IIR_ERR_INVALID, p,
                         "'%s' is also the name the \"light\" track gives: animate a light in "
                         "one track",
                         tr->name);
    for (int j = 0; j < i; j++)
        if (!strcmp(a->lights[j].name, tr->name))
            return anim_fail(c, IIR_ERR_INVALID, p, "'%s' is also lights[%d]'s light", tr->name, j);
    return IIR_OK;
}

/* "lights": [track, ...], each naming its light. */
static iir_status parse_lights(iir_anim_ctx *c, const cJSON *arr, iir_anim *a)
{
    char p[IIR_ANIM_PATH];
    if (!arr) return IIR_OK;
    if (!cJSON_IsArray(arr))
        return anim_fail(c, IIR_ERR_FORMAT, "lights", "must be an array of light tracks");
    int n = cJSON_GetArraySize(arr);
    a->lights = calloc(n > 0 ? (size_t)n : 1u, sizeof *a->lights);
    if (!a->lights) return anim_fail(c, IIR_ERR_NOMEM, "lights", "out of memory");
    a->num_lights = n;
    iir_status st = IIR_OK;
    const cJSON *track = arr->child;
    for (int i = 0; i < n && st == IIR_OK; i++, track = track->next) {
        snprintf(p, sizeof p, "lights[%d]", i);
        st = parse_named_track(c, track, p, a, i);
    }
    return st;
}

/* A string member of at most n - 1 bytes, copied into out (n bytes). */
static iir_status get_string(const iir_anim_ctx *c, const cJSON *obj, const char *name, char *out,
                             size_t n)
{
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(obj, name);
    if (!m) return IIR_OK;
    return iir_json_file_status(&c->jf, iir_json_string(&c->jf.r, m, name, 0, n - 1, out));
}

/* "size": [width, height], whole numbers of pixels in [1, IIR_IMAGE_MAX_DIM]. */
static iir_status get_frame_size(const iir_anim_ctx *c, const cJSON *root, iir_anim *a)
{
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(root, "size");
    if (!m) return IIR_OK;
    const cJSON *w = cJSON_GetArrayItem(m, 0), *h = cJSON_GetArrayItem(m, 1);
    if (!cJSON_IsArray(m) || cJSON_GetArraySize(m) != 2 || !cJSON_IsNumber(w) || !cJSON_IsNumber(h))
        return anim_fail(c, IIR_ERR_FORMAT, "size", "must be [width, height] in pixels");
    for (const cJSON *d = w; d; d = d->next)
        if (!(d->valuedouble >= 1.0 && d->valuedouble <= IIR_IMAGE_MAX_DIM) ||
            d->valuedouble != floor(d->valuedouble))
            return anim_fail(c, IIR_ERR_INVALID, d == w ? "size[0]" : "size[1]",
                             "%g is not a whole number of pixels in [1, %d]", d->valuedouble,
                             IIR_IMAGE_MAX_DIM);
    a->width = (int)w->valuedouble;
    a->height = (int)h->valuedouble;
    return IIR_OK;
}

/* What the script says of where it was made: "description", "scene", "scenes", "size". */
static iir_status parse_origin(iir_anim_ctx *c, const cJSON *root, iir_anim *a)
{
    const cJSON *desc = cJSON_GetObjectItemCaseSensitive(root, "description");
    if (desc && !cJSON_IsString(desc))
        return anim_fail(c, IIR_ERR_FORMAT, "description", "must be a string");
    iir_status st = get_string(c, root, "scene", a->scene, sizeof a->scene);
    if (st == IIR_OK) st = get_string(c, root, "scenes", a->scenes, sizeof a->scenes);
    return st == IIR_OK ? get_frame_size(c, root, a) : st;
}

static iir_status parse_root(iir_anim_ctx *c, const cJSON *root, iir_anim *a)
{
    bool has;
    iir_status st = check_fields(c, root, "", TOP_FIELDS);
    if (st == IIR_OK) st = parse_origin(c, root, a);
    a->fps = 30.0;
    if (st == IIR_OK) st = get_ranged(c, root, "", "fps", 1.0, false, 1000.0, &a->fps, &has);
    if (st == IIR_OK)
        st = get_ranged(c, root, "", "duration", 0.0, true, 36000.0, &a->duration, &has);
    if (st == IIR_OK && !has) return anim_fail(c, IIR_ERR_FORMAT, "duration", "is missing");
    c->duration = a->duration;
    if (st == IIR_OK)
        st = parse_track(c, cJSON_GetObjectItemCaseSensitive(root, "light"), "light", &a->light);
    if (st == IIR_OK)
        st = parse_track(c, cJSON_GetObjectItemCaseSensitive(root, "camera"), "camera", &a->camera);
    if (st == IIR_OK)
        st = parse_track(c, cJSON_GetObjectItemCaseSensitive(root, "exposure"), "exposure",
                         &a->exposure);
    if (st == IIR_OK && a->light.present)
        st = parse_track_name(c, cJSON_GetObjectItemCaseSensitive(root, "light"), "light", false,
                              &a->light);
    if (st == IIR_OK) st = parse_lights(c, cJSON_GetObjectItemCaseSensitive(root, "lights"), a);
    return st;
}

iir_status iir_anim_parse(const char *json_text, const char *source_name, iir_anim **out,
                          iir_error *err)
{
    iir_anim_ctx c = {
        source_name ? source_name : "animation", err, 0.0, KIND_LIGHT, {{0}, NULL, NULL, IIR_OK}};
    iir_json_file_init(&c.jf, c.src, err);
    *out = NULL;
    const char *end = NULL;
    cJSON *root = json_text ? cJSON_ParseWithOpts(json_text, &end, true) : NULL;
    if (!root) {
        long at = json_text && end ? (long)(end - json_text) : 0;
        return iir_fail(err, IIR_ERR_FORMAT, "%s: not valid JSON near byte %ld", c.src, at);
    }
    iir_anim *a = calloc(1, sizeof *a);
    if (a) snprintf(a->source, sizeof a->source, "%s", c.src);
    iir_status st = a ? parse_root(&c, root, a) : iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    cJSON_Delete(root);
    if (st != IIR_OK) {
        iir_anim_destroy(a);
        return st;
    }
    *out = a;
    return IIR_OK;
}

iir_status iir_anim_load(const char *path, iir_anim **out, iir_error *err)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return iir_fail(err, IIR_ERR_IO, "cannot read %s: %s", path, strerror(errno));
    char *buf = malloc(IIR_ANIM_MAX_BYTES + 1);
    size_t n = buf ? fread(buf, 1, IIR_ANIM_MAX_BYTES + 1, f) : 0;
    bool failed = buf && ferror(f);
    fclose(f);
    if (!buf) return iir_fail(err, IIR_ERR_NOMEM, "%s: out of memory", path);
    if (failed || n > IIR_ANIM_MAX_BYTES) {
        free(buf);
        return iir_fail(err, IIR_ERR_IO, "cannot read %s: %s", path,
                        failed ? "read error" : "larger than 16 MiB");
    }
    buf[n] = '\0';
    iir_status st = iir_anim_parse(buf, path, out, err);
    free(buf);
    return st;
}

void iir_anim_destroy(iir_anim *a)
{
    if (!a) return;
    free(a->light.keys);
    free(a->camera.keys);
    free(a->exposure.keys);
    for (int i = 0; i < a->num_lights; i++) free(a->lights[i].keys);
    free(a->lights);
    free(a);
}

/* ======================== frames ======================== */

double iir_anim_duration(const iir_anim *a)
{
    return a->duration;
}
double iir_anim_fps(const iir_anim *a)
{
    return a->fps;
}

const char *iir_anim_scene(const iir_anim *a)
{
    return a->scene;
}

const char *iir_anim_scenes_dir(const iir_anim *a)
{
    return a->scenes;
}

bool iir_anim_size(const iir_anim *a, int *width, int *height)
{
    if (!a->width) return false;
    *width = a->width;
    *height = a->height;
    return true;
}

int iir_anim_frame_count(const iir_anim *a)
{
    /* the epsilon keeps 2 s at 30 fps at 61 frames despite rounding in duration * fps */
    return (int)floor(a->duration * a->fps + 1e-9) + 1;
}

double iir_anim_frame_time(const iir_anim *a, int frame)
{
    int last = iir_anim_frame_count(a) - 1;
    frame = frame < 0 ? 0 : (frame > last ? last : frame);
    return fmin((double)frame / a->fps, a->duration);
}

bool iir_anim_has_light(const iir_anim *a)
{
    return a->light.present;
}
bool iir_anim_has_camera(const iir_anim *a)
{
    return a->camera.present;
}
bool iir_anim_has_exposure(const iir_anim *a)
{
    return a->exposure.present;
}

const char *iir_anim_light_name(const iir_anim *a)
{
    return a->light.name;
}

int iir_anim_num_light_tracks(const iir_anim *a)
{
    return a->num_lights;
}

const char *iir_anim_light_track_name(const iir_anim *a, int i)
{
    return i >= 0 && i < a->num_lights ? a->lights[i].name : NULL;
}

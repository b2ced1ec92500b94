/* session_msg.c -- a session's client messages, on the service thread: assembling WebSocket
 * pieces, the rate limit, hello and the token, and each message applied all or nothing (parsing
 * and validation are protocol.h's). Not the worker and not writing. */
#include <math.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

#include "iir/camera_move.h"
#include "iir/light_move.h"
#include "iir/timer.h"
#include "budget.h"
#include "scene_save.h"
#include "session_internal.h"

/* ======================== pieces, size and rate ======================== */

/* False (and one rate_limited error per second) when the client is over its message rate. */
static bool take_token(iird_session *s)
{
    double now = iir_now_ms();
    s->tokens =
        fmin((double)IIRD_RATE_BURST, s->tokens + (now - s->tokens_ms) * IIRD_RATE_PER_S / 1000.0);
    s->tokens_ms = now;
    if (s->tokens >= 1.0) {
        s->tokens -= 1.0;
        return true;
    }
    if (now - s->rate_error_ms >= 1000.0) {
        iird_proto_error e = {.seq = IIRD_NO_SEQ};
        s->rate_error_ms = now;
        iird_proto_fail(&e, IIRD_E_RATE_LIMITED, NULL,
                        "more than %d messages per second (burst %d): messages are dropped",
                        IIRD_RATE_PER_S, IIRD_RATE_BURST);
        iird_queue_error(s, &e);
    }
    return false;
}

static void reply_error(iird_session *s, iird_err code, const char *fmt, const char *arg)
{
    iird_proto_error e = {.seq = IIRD_NO_SEQ};
    iird_proto_fail(&e, code, NULL, fmt, arg);
    iird_queue_error(s, &e);
}

void iird_session_receive(iird_session *s, const void *data, size_t len, bool final, bool binary)
{
    if (!s->rx) s->rx = malloc(IIRD_MAX_MESSAGE_BYTES + 1);
    if (!s->rx || s->rx_len + len > IIRD_MAX_MESSAGE_BYTES) s->rx_too_large = true;
    if (!s->rx_too_large) {
        memcpy(s->rx + s->rx_len, data, len);
        s->rx_len += len;
    }
    if (!final) return;
    bool too_large = s->rx_too_large;
    size_t n = s->rx_len;
    s->rx_len = 0;
    s->rx_too_large = false;
    atomic_fetch_add(&s->env->metrics->messages, 1);
    if (!take_token(s)) return;
    if (too_large)
        reply_error(s, IIRD_E_TOO_LARGE, "a message is at most %s bytes", "65536");
    else if (binary)
        reply_error(s, IIRD_E_BAD_JSON, "%s", "binary messages are not accepted: send JSON text");
    else
        iird_session_handle(s, s->rx, n);
}

/* ======================== the messages ======================== */

/* Seconds since the recording started (the lock is held). */
static double rec_time_locked(const iird_session *s)
{
    return (iir_now_ms() - s->rec_start_ms) / 1e3;
}

/* An input changed the state (the lock is held): the worker renders the newest. */
static void input_changed_locked(iird_session *s, int64_t seq)
{
    s->version++;
    if (seq != IIRD_NO_SEQ) s->seq = seq;
    s->input_ms = iir_now_ms();
    if (s->sched_added) iird_sched_promote(s->env->sched, &s->sched); /* refinement yields */
    pthread_cond_broadcast(&s->wake);
}

static bool token_matches(const char *want, const char *got)
{
    size_t a = strlen(want), b = strlen(got);
    unsigned diff = (unsigned)(a ^ b);
    for (size_t i = 0; i < a; i++) diff |= (unsigned char)want[i] ^ (unsigned char)got[i % (b + 1)];
    return diff == 0;
}

/* The welcome's and save replies' scene names: all but the older saved scenes (scene_save.h);
 * free the array (not its names). NULL when out of memory. */
static const char **listed_scenes(const iird_session *s, size_t *more)
{
    return iird_saves_listed(s->env->saves, iird_scene_cache_names(s->env->scenes),
                             IIRD_SAVED_LISTED, more);
}

static bool on_hello(iird_session *s, const iird_msg *m, iird_proto_error *err)
{
    if (m->u.hello.protocol != IIRD_PROTOCOL_VERSION)
        return iird_proto_fail(err, IIRD_E_UNSUPPORTED, "hello.protocol",
                               "protocol %d is not supported; this server speaks %d",
                               m->u.hello.protocol, IIRD_PROTOCOL_VERSION);
    const char *token = s->env->token;
    if (token && (!m->u.hello.has_token || !token_matches(token, m->u.hello.token))) {
        iird_proto_fail(err, IIRD_E_UNAUTHORIZED, "hello.token",
                        m->u.hello.has_token ? "wrong token" : "this server needs a token");
        iird_queue_error(s, err);
        iird_session_close(s, 1008); /* policy violation */
        return true;
    }
    size_t more = 0;
    const char **names = listed_scenes(s, &more);
    if (!names) return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory");
    s->hello_ok = true;
    pthread_mutex_lock(&s->lock);
    iird_state_view v = iird_state_view_locked(s);
    char *json = iird_json_welcome(&v, s->id, names, more, &s->env->limits, m->seq);
    free(names);
    iird_queue_text_locked(s, json, false);
    s->ready = true;
    pthread_cond_broadcast(&s->wake);
    pthread_mutex_unlock(&s->lock);
    free(json);
    return true;
}

/* A moved light stays in the scene (iir/light_move.h): the position is stopped short of the first
 * surface between the old (`from`) and the new one, and a light aimed at a target is aimed at it
 * again from there. A sun keeps its disk over the scene (it only turns). True when the position
 * changed from what was asked. */
static bool keep_inside_locked(const iird_session *s, const iird_msg_light *m, iir_vec3 from,
                               iir_light *light)
{
    const iird_scene_entry *sc = s->scene;
    if (light->type == IIR_LIGHT_SUN) {
        iir_vec3 asked = light->position;
        iir_light_fit_sun(light, sc->scene);
        return (m->has & (1u << IIRD_L_POSITION)) &&
               (asked.x != light->position.x || asked.y != light->position.y ||
                asked.z != light->position.z);
    }
    if (!(m->has & (1u << IIRD_L_POSITION))) return false;
    iir_vec3 p = iir_light_move_inside(sc->scene, sc->rt, from, light->position);
    if (p.x == light->position.x && p.y == light->position.y && p.z == light->position.z)
        return false;
    light->position = p;
    iir_vec3 d = iir_sub(m->target, p);
    if ((m->has & (1u << IIRD_L_TARGET)) && iir_length(d) > 0.f)
        light->direction = iir_normalize(d);
    return true;
}

/* The light a message addresses: the one it names, else the moved one; -1 with err naming the
 * scene's lights when no light has that name (the lock is held). */
static int which_light_locked(const iird_session *s, const iird_msg_light *m, iird_proto_error *err)
{
    if (!(m->has & (1u << IIRD_L_NAME))) return (int)s->lights.moved;
    int i = iird_lights_find(&s->lights, m->name);
    if (i >= 0) return i;
    char names[200];
    iird_lights_names(&s->lights, names, sizeof names);
    iird_proto_fail(err, IIRD_E_BAD_FIELD, "light.name",
                    "light.name: scene %s has no light named '%s'; its lights: %s", s->scene->name,
                    m->name, names);
    return -1;
}

/* Light i becomes *light (on or off), recorded first when recording: a full recording refuses
 * the whole message and nothing changes (the lock is held). */
static bool set_light_locked(iird_session *s, int i, const iir_light *light, bool on,
                             iird_proto_error *err)
{
    iir_light was = s->lights.v[i];
    bool was_on = s->lights.on[i];
    s->lights.v[i] = *light;
    s->lights.on[i] = on;
    if (!s->rec || iird_session_record_lights_locked(s, s->rec, rec_time_locked(s), err))
        return true;
    s->lights.v[i] = was;
    s->lights.on[i] = was_on;
    return false;
}

static bool on_light(iird_session *s, const iird_msg *m, iird_proto_error *err)
{
    const iird_msg_light *ml = &m->u.light;
    pthread_mutex_lock(&s->lock);
    int i = which_light_locked(s, ml, err);
    bool ok = i >= 0, moved = false;
    iir_light light = ok ? s->lights.v[i] : (iir_light){0};
    bool on = ok && ((ml->has & (1u << IIRD_L_ON)) ? ml->on : s->lights.on[i]);
    ok = ok && iird_apply_light(ml, &light, err);
    moved = ok && keep_inside_locked(s, ml, s->lights.v[i].position, &light);
    ok = ok && set_light_locked(s, i, &light, on, err);
    char *json = NULL;
    if (ok) input_changed_locked(s, m->seq);
    if (ok && moved) { /* the client learns the position used */
        iird_state_view v = iird_state_view_locked(s);
        json = iird_json_state(&v, m->seq);
        iird_queue_text_locked(s, json, false);
    }
    pthread_mutex_unlock(&s->lock);
    free(json);
    return ok;
}

/* A moved camera keeps its view of its target (iir/camera_move.h): an eye that saw its target is
 * stopped in front of the first surface between the new target and the new eye, so an orbit never
 * leaves the room. True when the position changed from what was asked (the lock is held). */
static bool keep_view_locked(const iird_session *s, iir_camera *camera)
{
    iir_camera kept = iir_camera_keep_view(s->scene->scene, s->scene->rt, &s->camera, camera);
    bool moved = kept.position.x != camera->position.x || kept.position.y != camera->position.y ||
                 kept.position.z != camera->position.z;
    *camera = kept;
    return moved;
}

static bool on_camera(iird_session *s, const iird_msg *m, iird_proto_error *err)
{
    pthread_mutex_lock(&s->lock);
    iir_camera camera = s->camera;
    bool ok = iird_apply_camera(&m->u.camera, &camera, err);
    bool moved = ok && keep_view_locked(s, &camera);
    if (ok && s->rec) /* recorded first: a full recording refuses the whole message */
        ok = iird_recording_add_camera(s->rec, rec_time_locked(s), &camera, err);
    char *json = NULL;
    if (ok) {
        s->camera = camera;
        input_changed_locked(s, m->seq);
    }
    if (ok && moved) { /* the client learns the position used */
        iird_state_view v = iird_state_view_locked(s);
        json = iird_json_state(&v, m->seq);
        iird_queue_text_locked(s, json, false);
    }
    pthread_mutex_unlock(&s->lock);
    free(json);
    return ok;
}

static bool on_params(iird_session *s, const iird_msg *m, iird_proto_error *err)
{
    pthread_mutex_lock(&s->lock);
    iird_settings settings = s->settings;
    bool ok = iird_apply_params(&m->u.params, &s->env->limits, &settings, err);
    iir_error e;
    if (ok && iir_method_supports(settings.method, s->lights.v, s->lights.n, &e) != IIR_OK) {
        char alt[96];
        iird_session_alternatives(s->lights.v, s->lights.n, settings.method, alt, sizeof alt);
        ok = iird_proto_fail(err, IIRD_E_UNSUPPORTED, "params.method", "scene %s: %s%s",
                             s->scene->name, e.msg, alt);
    }
    /* a new exposure is recorded once nothing can refuse the message any more */
    bool rec_exposure = ok && s->rec && settings.exposure != s->settings.exposure;
    double rec_t = s->rec ? rec_time_locked(s) : 0.0;
    if (rec_exposure) ok = iird_recording_room(s->rec, rec_t, err);
    /* last: the reservation changes only when the settings do */
    ok = ok &&
         iird_budget_reserve(s->env->budget, &s->reserved, iird_session_estimate(&settings), err);
    char *json = NULL;
    if (ok && rec_exposure) iird_recording_add_exposure(s->rec, rec_t, settings.exposure, err);
    if (ok) {
        s->settings = settings;
        s->generation++;
        input_changed_locked(s, m->seq);
        iird_state_view v = iird_state_view_locked(s);
        json = iird_json_state(&v, m->seq);
        iird_queue_text_locked(s, json, false);
    }
    pthread_mutex_unlock(&s->lock);
    free(json);
    return ok;
}

static bool on_scene(iird_session *s, const iird_msg *m, iird_proto_error *err)
{
    const char *name = m->u.scene.name;
    if (strchr(name, '/') || strchr(name, '\\') || strstr(name, ".."))
        return iird_proto_fail(err, IIRD_E_BAD_FIELD, "scene.name",
                               "scene names may not contain '/', '\\' or '..'");
    if (!iird_scene_cache_has(s->env->scenes, name))
        return iird_proto_fail(err, IIRD_E_BAD_FIELD, "scene.name",
                               "no scene named '%s' (welcome.scenes lists them)", name);
    pthread_mutex_lock(&s->lock);
    /* Latest-wins: a switch still waiting for the worker is replaced, and answered now (every
       request with a seq gets its reply) by the state as it is, marked superseded. */
    char *json = NULL;
    if (s->scene_pending && s->scene_seq != IIRD_NO_SEQ) {
        iird_state_view v = iird_state_view_locked(s);
        json = iird_json_state_superseded(&v, s->scene_seq);
        iird_queue_text_locked(s, json, false);
    }
    s->scene_pending = true;
    snprintf(s->scene_name, sizeof s->scene_name, "%s", name);
    s->scene_seq = m->seq;
    s->scene_version = s->version;
    pthread_cond_broadcast(&s->wake);
    pthread_mutex_unlock(&s->lock);
    free(json);
    return true;
}

/* The ray through the centre of the pixel under (x, y) (the lock is held). */
static bool pick_locked(const iird_session *s, double x, double y, iir_vec3 *p, iir_vec3 *n,
                        float *t)
{
    iir_camera_frame cf = iir_camera_setup(&s->camera, s->settings.width, s->settings.height);
    iir_vec3 dir = iir_camera_dir(&cf, floorf((float)x) + 0.5f, floorf((float)y) + 0.5f);
    iir_ray ray = iir_make_ray(cf.origin, dir, 0.f, INFINITY);
    iir_hit hit;
    iir_raystats rs = {{0}};
    if (!iir_rt_intersect(s->scene->rt, &ray, &hit, &rs, IIR_RAYS_CAMERA)) return false;
    *t = hit.t;
    *p = iir_add(cf.origin, iir_scale(dir, hit.t));
    *n = s->scene->scene->normals[hit.prim];
    if (iir_dot(*n, dir) > 0.f) *n = iir_scale(*n, -1.f); /* the side the camera sees */
    return true;
}

static bool on_pick(iird_session *s, const iird_msg *m, iird_proto_error *err)
{
    double x = m->u.pick.x, y = m->u.pick.y;
    pthread_mutex_lock(&s->lock);
    int w = s->settings.width, h = s->settings.height;
    bool ok = true, hit = false;
    iir_vec3 p = {0}, n = {0};
    float t = 0.f;
    if (!(x >= 0 && x < w))
        ok = iird_proto_fail(err, IIRD_E_OUT_OF_RANGE, "pick.x",
                             "pick.x must be in [0, %d) (the frame width), got %g", w, x);
    else if (!(y >= 0 && y < h))
        ok = iird_proto_fail(err, IIRD_E_OUT_OF_RANGE, "pick.y",
                             "pick.y must be in [0, %d) (the frame height), got %g", h, y);
    else
        hit = pick_locked(s, x, y, &p, &n, &t);
    pthread_mutex_unlock(&s->lock);
    if (!ok) return false;
    char *json = iird_json_pick(m->seq, hit, p, n, t);
    pthread_mutex_lock(&s->lock);
    iird_queue_text_locked(s, json, false);
    pthread_mutex_unlock(&s->lock);
    free(json);
    return true;
}

/* At most one snapshot per session between the request and its bytes leaving: another request
 * meanwhile is answered busy (never merged, never queued). */
static bool on_snapshot(iird_session *s, const iird_msg *m, iird_proto_error *err)
{
    pthread_mutex_lock(&s->lock);
    if (s->snapshot_busy) {
        pthread_mutex_unlock(&s->lock);
        return iird_proto_fail(err, IIRD_E_BUSY, "snapshot",
                               "a snapshot is already being made or sent; ask again once it "
                               "has arrived");
    }
    s->snapshot_busy = true;
    s->snapshot_pending = true;
    s->snapshot_exr = m->u.snapshot.exr;
    s->snapshot_seq = m->seq;
    pthread_cond_broadcast(&s->wake);
    pthread_mutex_unlock(&s->lock);
    return true;
}

/* The recording (s->rec, guarded by the lock: a scene switch on the worker ends it too). */
static bool on_record(iird_session *s, const iird_msg *m, iird_proto_error *err)
{
    char *json = NULL;
    bool ok = true;
    pthread_mutex_lock(&s->lock);
    if (m->u.record.start) {
        iird_recording_destroy(s->rec);
        s->rec = iird_session_record_start_locked(s, m->u.record.fps, err);
        ok = s->rec != NULL;
        if (ok) json = iird_json_record_start(m->seq);
    } else if (!s->rec) {
        ok = iird_proto_fail(err, IIRD_E_BAD_FIELD, "record.action",
                             "stop without a recording: send action start first");
    } else {
        iird_session_record_end_locked(s, rec_time_locked(s));
        json = iird_json_record_stop(s->rec, m->seq);
        iird_recording_destroy(s->rec);
        s->rec = NULL;
    }
    if (ok) iird_queue_text_locked(s, json, false);
    pthread_mutex_unlock(&s->lock);
    free(json);
    return ok;
}

/* ---- save ---- */

void iird_session_set_address(iird_session *s, const char *addr)
{
    snprintf(s->addr, sizeof s->addr, "%s", addr);
}

/* What a save needs of the session, copied under its lock (the worker may swap the scene). */
typedef struct save_state {
    char scene[130];
    char base[130]; /* what the sidecar names: the scene, flattened (iird_save_base) */
    bool in_dir;    /* the scene can be a sidecar's base */
    iir_camera camera;
    float aspect;
    iir_light *lights; /* the session's lights as rendered (one switched off black), in order */
    uint32_t num_lights;
} save_state;

static bool copy_save_state(iird_session *s, save_state *st)
{
    pthread_mutex_lock(&s->lock);
    snprintf(st->scene, sizeof st->scene, "%s", s->scene->name);
    st->in_dir = iird_scene_cache_in_dir(s->env->scenes, s->scene);
    st->camera = s->camera;
    st->aspect = (float)s->settings.width / (float)s->settings.height;
    st->lights = malloc(s->lights.n * sizeof *st->lights);
    if (st->lights)
        memcpy(st->lights, iird_lights_shown(&s->lights), s->lights.n * sizeof *st->lights);
    if (st->lights) st->num_lights = s->lights.n;
    pthread_mutex_unlock(&s->lock);
    snprintf(st->base, sizeof st->base, "%s", st->scene);
    return st->lights != NULL;
}

/* Whether the session may write scene `name` now: --allow-save, a new name, a scene of the
 * scenes directory, the address's rate and the total (scene_save.h); false with err filled. */
static bool may_save(iird_session *s, const save_state *st, const char *name, iird_proto_error *err)
{
    if (!s->env->limits.allow_save)
        return iird_proto_fail(err, IIRD_E_UNSUPPORTED, "save.name",
                               "this server does not write scenes (it was started without "
                               "--allow-save); send save without a name to get the sidecar");
    if (iird_scene_cache_has(s->env->scenes, name))
        return iird_proto_fail(err, IIRD_E_BAD_FIELD, "save.name",
                               "a scene named '%s' exists; pick another name", name);
    if (!st->in_dir)
        return iird_proto_fail(err, IIRD_E_UNSUPPORTED, "save.name",
                               "scene %s was loaded from outside the scenes directory, so a saved "
                               "scene cannot name it as its base; send save without a name to "
                               "get the sidecar",
                               st->scene);
    return !s->env->saves || iird_saves_admit(s->env->saves, s->addr, iir_now_ms(), err);
}

/* Writes the sidecar as the new scene `name` (may_save said yes) and lists it; false with err
 * filled otherwise. */
static bool save_named(iird_session *s, const iird_sidecar_view *v, const char *name,
                       iird_proto_error *err)
{
    char *text = iird_sidecar_text(v);
    bool ok = text ? iird_scene_save(iird_scene_cache_dir(s->env->scenes), name, text, err)
                   : iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory");
    free(text);
    if (ok) iird_scene_cache_add_name(s->env->scenes, name);
    if (ok && s->env->saves) iird_saves_added(s->env->saves, name);
    return ok;
}

/* The save reply: the sidecar, and after a named save the names a client may now ask for. */
static char *save_reply(iird_session *s, const iird_sidecar_view *v, int64_t seq, const char *name)
{
    size_t more = 0;
    const char **names = name ? listed_scenes(s, &more) : NULL;
    if (name && !names) return NULL;
    char *json = iird_json_save(v, seq, name, names, more);
    free(names);
    return json;
}

/* `save`: the session's lights and camera as a sidecar based on its scene (flattened: a scene
 * iird saved gives way to its own base), sent back; with a name also written into the scenes
 * directory as a new scene (only with --allow-save). A name refuses a sidecar the loader could
 * not load; without one the sidecar keeps the scene as its base then. */
static bool on_save(iird_session *s, const iird_msg *m, iird_proto_error *err)
{
    const char *name = m->u.save.has_name ? m->u.save.name : NULL;
    save_state st = {0};
    if (!copy_save_state(s, &st))
        return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory");
    iird_proto_error flat = *err;
    bool ok = !name || may_save(s, &st, name, err);
    bool based = ok && (!st.in_dir || iird_save_base(iird_scene_cache_dir(s->env->scenes), st.scene,
                                                     st.base, sizeof st.base, name ? err : &flat));
    iird_sidecar_view v = {st.base, &st.camera, st.aspect, st.lights, st.num_lights};
    ok = ok && (based || !name) && (!name || save_named(s, &v, name, err));
    char *json = ok ? save_reply(s, &v, m->seq, name) : NULL;
    free(st.lights);
    if (ok && !json) return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory");
    if (ok) {
        pthread_mutex_lock(&s->lock);
        iird_queue_text_locked(s, json, false);
        pthread_mutex_unlock(&s->lock);
    }
    free(json);
    return ok;
}

/* `scenes`: every name a client may ask for, saved scenes welcome left out included. */
static bool on_scenes(iird_session *s, const iird_msg *m, iird_proto_error *err)
{
    char *json = iird_json_scenes(iird_scene_cache_names(s->env->scenes), m->seq);
    if (!json) return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory");
    pthread_mutex_lock(&s->lock);
    iird_queue_text_locked(s, json, false);
    pthread_mutex_unlock(&s->lock);
    free(json);
    return true;
}

static bool dispatch(iird_session *s, const iird_msg *m, iird_proto_error *err)
{
    switch (m->type) {
    case IIRD_MSG_HELLO:
        return on_hello(s, m, err);
    case IIRD_MSG_LIGHT:
        return on_light(s, m, err);
    case IIRD_MSG_CAMERA:
        return on_camera(s, m, err);
    case IIRD_MSG_PARAMS:
        return on_params(s, m, err);
    case IIRD_MSG_SCENE:
        return on_scene(s, m, err);
    case IIRD_MSG_PICK:
        return on_pick(s, m, err);
    case IIRD_MSG_SNAPSHOT:
        return on_snapshot(s, m, err);
    case IIRD_MSG_RECORD:
        return on_record(s, m, err);
    case IIRD_MSG_SAVE:
        return on_save(s, m, err);
    case IIRD_MSG_SCENES:
        return on_scenes(s, m, err);
    }
    return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "unhandled message type %d", (int)m->type);
}

void iird_session_handle(iird_session *s, const char *text, size_t len)
{
    iird_msg m;
    iird_proto_error err = {.seq = IIRD_NO_SEQ};
    if (!iird_parse_message(text, len, &s->env->limits, &m, &err)) {
        iird_queue_error(s, &err);
        return;
    }
    err.seq = m.seq;
    if (!s->hello_ok && m.type != IIRD_MSG_HELLO) {
        if (s->env->token)
            iird_proto_fail(&err, IIRD_E_UNAUTHORIZED, NULL,
                            "send hello with the server's token first");
        else
            iird_proto_fail(&err, IIRD_E_NOT_READY, NULL, "send hello first");
        iird_queue_error(s, &err);
        return;
    }
    if (!dispatch(s, &m, &err)) iird_queue_error(s, &err);
}

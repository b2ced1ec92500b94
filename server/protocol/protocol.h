/* protocol.h -- the live protocol's messages (docs/protocol.md) as C values: parsing and validating
 * client messages, applying them to a session's state all-or-nothing, and building the server's
 * replies as JSON text and binary frame headers. No sockets, threads or sessions live here. */
#ifndef IIRD_PROTOCOL_H
#define IIRD_PROTOCOL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "iir/camera.h"
#include "iir/light.h"
#include "iir/method.h"
#include "iir/params.h"

struct cJSON;
struct iir_domain; /* method.h: the light's disk domain (sites, Delaunay edges, Voronoi cells) */

enum {
    IIRD_PROTOCOL_VERSION = 1,
    IIRD_MAX_MESSAGE_BYTES = 65536,
    IIRD_FRAME_HEADER_BYTES = 44,
    IIRD_NO_SEQ = -1, /* a message without "seq" */
};

typedef enum iird_msg_type {
    IIRD_MSG_HELLO,
    IIRD_MSG_LIGHT,
    IIRD_MSG_CAMERA,
    IIRD_MSG_PARAMS,
    IIRD_MSG_SCENE,
    IIRD_MSG_PICK,
    IIRD_MSG_SNAPSHOT,
    IIRD_MSG_RECORD,
    IIRD_MSG_SAVE,
    IIRD_MSG_SCENES, /* the whole list of scene names (welcome's may leave saved ones out) */
} iird_msg_type;

/* Error codes, in the order of docs/protocol.md's table; names via iird_err_name. */
typedef enum iird_err {
    IIRD_E_BAD_JSON,
    IIRD_E_TOO_LARGE,
    IIRD_E_BAD_TYPE,
    IIRD_E_UNKNOWN_TYPE,
    IIRD_E_UNKNOWN_FIELD,
    IIRD_E_OUT_OF_RANGE,
    IIRD_E_BAD_FIELD,
    IIRD_E_NOT_READY,
    IIRD_E_UNAUTHORIZED,
    IIRD_E_UNSUPPORTED,
    IIRD_E_RATE_LIMITED,
    IIRD_E_SCENE_ERROR,
    IIRD_E_BUSY,
    IIRD_E_INTERNAL,
    IIRD_E_IDLE_TIMEOUT,
    IIRD_E_COUNT
} iird_err;

const char *iird_err_name(iird_err code); /* "bad_json", ... */

/* An error reply: code, the offending field as a path ("light.position[1]", "" for none), a
 * message a user can act on, and the seq of the message when it had a valid one. */
typedef struct iird_proto_error {
    iird_err code;
    char field[96];
    char message[256];
    int64_t seq; /* IIRD_NO_SEQ when absent */
} iird_proto_error;

/* Fills e's code, field (NULL or "" for none) and printf-style message, cut to fit at a UTF-8
 * character boundary; leaves e->seq unchanged. Returns false, so callers can write
 * `return iird_proto_fail(err, IIRD_E_BUSY, NULL, "...")`. For the daemon's own errors too. */
bool iird_proto_fail(iird_proto_error *e, iird_err code, const char *field, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* Server limits that bound client values (from the serve command line). Method parameters are
 * bound by their tables' live maxima (params.h). */
typedef struct iird_limits {
    int max_width, max_height;
    bool allow_save; /* `save` with a name may write into the scenes directory (--allow-save) */
} iird_limits;

/* The defaults of `iird serve`: 1920 x 1080. */
iird_limits iird_limits_default(void);

/* Everything a `params` message can set: the method, method parameters (any method's, by name),
 * and the session's own frame and stream settings, whose table is iird_stream_table. */
typedef struct iird_settings {
    char method[16];
    iir_params params; /* the method parameters given so far; the rest are their defaults */
    int width, height;
    int quality; /* JPEG */
    float exposure;
    bool refine; /* progressive refinement when idle */
    bool domain; /* send domain messages */
} iird_settings;

/* The frame and stream settings of iird_settings (width ... domain) as a parameter table, so that
 * they are parsed, checked, sent in `welcome` and drawn in the web form like a method's. */
extern const iir_param_table iird_stream_table;

iird_settings iird_settings_default(void);

/* Which optional fields a message carried: bit (1u << field enum) set when present. */
enum {
    IIRD_L_POSITION,
    IIRD_L_DIRECTION,
    IIRD_L_TARGET,
    IIRD_L_CONE,
    IIRD_L_INTENSITY,
    IIRD_L_NAME,
    IIRD_L_ON,
    IIRD_L_INNER,
    IIRD_L_SIZE
};
enum { IIRD_C_POSITION, IIRD_C_TARGET, IIRD_C_UP, IIRD_C_FOV };

/* A light message: which light (name; the session's moved light without one), whether it is on,
 * and the fields it changes. */
typedef struct iird_msg_light {
    unsigned has;
    char name[64]; /* as iir_light.name */
    bool on;
    iir_vec3 position, direction, target;
    float cone_angle_deg, inner_angle_deg;
    iir_vec2 size; /* area light: width, height */
    bool intensity_is_scalar;
    iir_vec3 intensity; /* RGB, or the scalar in .x */
} iird_msg_light;

typedef struct iird_msg_camera {
    unsigned has;
    iir_vec3 position, target, up;
    float fov;
} iird_msg_camera;

/* A params message: the method if given, and every other field by name (stream settings and
 * method parameters alike), applied onto a copy of the current settings. */
typedef struct iird_msg_params {
    bool has_method;
    char method[16];
    iir_params values;
} iird_msg_params;

typedef struct iird_msg {
    iird_msg_type type;
    int64_t seq; /* IIRD_NO_SEQ when absent */
    union {
        struct {
            int protocol;
            char token[257];
            char client[129];
            bool has_token;
        } hello;
        iird_msg_light light;
        iird_msg_camera camera;
        iird_msg_params params;
        struct {
            char name[129];
        } scene;
        struct {
            double x, y; /* checked against the frame size by the session */
        } pick;
        struct {
            bool exr;
        } snapshot;
        struct {
            bool start;
            int fps;
        } record;
        struct {
            bool has_name; /* write the scene under this name; else only reply with it */
            char name[129];
        } save;
    } u;
} iird_msg;

/* Parses and validates one client text message (len bytes, not NUL-terminated) against the
 * protocol's types and ranges (not against the session's state: see the apply functions).
 * Returns false with *err filled on any problem; *out is then unspecified. */
bool iird_parse_message(const char *text, size_t len, const iird_limits *limits, iird_msg *out,
                        iird_proto_error *err);

/* Apply a message to the session's state, all or nothing: on false *err is filled (but for
 * err->seq, which is left as iird_parse_message set it) and the state is unchanged. Light: the
 * fields its kind has (bad_field naming the light for another kind's: a cone for a spot,
 * inner_angle for a glTF spot, size for an area light; a sun's position only with a target, which
 * it then turns towards), target/direction/position combined, intensity scalar scaling, then
 * iir_light_validate; `name` and `on` are the session's (which light, rendered black or not). A
 * sun's position is left as asked: the caller fits it again (iir_light_fit_sun). Camera:
 * iir_camera_validate. Params: merged, the stream settings against the limits, every method
 * parameter against each method's row of its name (live maxima), then the session's method's
 * tables with their checks (kmin <= kmax <= vpls), blaming a field the message carried. */
bool iird_apply_light(const iird_msg_light *m, iir_light *light, iird_proto_error *err);
bool iird_apply_camera(const iird_msg_camera *m, iir_camera *camera, iird_proto_error *err);
bool iird_apply_params(const iird_msg_params *m, const iird_limits *limits, iird_settings *settings,
                       iird_proto_error *err);

/* The session's check of a parsed `pick` against the current frame size: out_of_range naming
 * pick.x or pick.y unless 0 <= x < width and 0 <= y < height. Sets err->seq from m. */
bool iird_check_pick(const iird_msg *m, int width, int height, iird_proto_error *err);

/* ---- replies: each returns a malloc'd NUL-terminated JSON text (NULL only on out-of-memory) ----
 */

typedef struct iird_state_view {
    const char *scene;
    const iir_light *light; /* the light a `light` message without a name moves */
    const iir_camera *camera;
    const iird_settings *settings;
    uint32_t generation; /* bumped by every accepted scene switch and params change */
    bool default_light;  /* the scene has no light: the session's spot was made up */
    const struct iir_scene *scene_data; /* for `notes` (iir_method_dropped); NULL: none */
    const iir_light *lights; /* every light of the session in the scene's order; NULL: `light` */
    const bool *on;          /* [num_lights]: which are on; NULL: all */
    uint32_t num_lights;
} iird_state_view;

char *iird_json_error(const iird_proto_error *e);
/* A parameter table as the JSON array of `welcome` (docs/protocol.md): per row name, type,
 * default, min, max, live_max, choices, unit, help, effect. */
struct cJSON *iird_json_param_table(const iir_param_table *t);
/* Every parameter of `method` with the value it uses under p (p's, else the default), keyed by
 * name: enums as their names, booleans as booleans, numbers as numbers. render.json and `state`. */
struct cJSON *iird_json_method_params(const char *method, const iir_params *p);
char *iird_json_state(const iird_state_view *s, int64_t seq);
/* The reply to a `scene` replaced by a newer one before its load began: the state as it is, with
 * "superseded": true (the switch was not made; the newer request gets its own reply). */
char *iird_json_state_superseded(const iird_state_view *s, int64_t seq);
/* scenes: NULL-terminated names, scenes_more: saved scenes left out of them (sent as
 * "scenes_more" when not 0; a `scenes` request lists them); methods: iir_method_names(). */
char *iird_json_welcome(const iird_state_view *s, uint32_t session, const char *const *scenes,
                        size_t scenes_more, const iird_limits *limits, int64_t seq);
/* The `scenes` reply: every name a client may ask for (NULL-terminated). */
char *iird_json_scenes(const char *const *scenes, int64_t seq);

typedef struct iird_stats_view {
    uint32_t frame;
    int64_t seq;
    const char *method;
    uint32_t pass;
    bool converged;
    bool reencoded; /* the last image again, only its encoding changed: "reencoded", no render */
    const iir_frame_stats *stats;
    double encode_ms, latency_ms, fps;
    size_t bytes;
    uint64_t dropped, memory_bytes;
} iird_stats_view;
char *iird_json_stats(const iird_stats_view *v);

/* The parts of a frame's stats as JSON objects, keyed as in the `stats` message (the phases and
 * counters method `method` declares, VPL counts, rays by kind); render.json writes its frames with
 * them too. Phase times are rounded to 1/scale ms, shares to 1e-4. NULL only on out-of-memory. */
struct cJSON *iird_json_phases(const char *method, const iir_frame_stats *st, double scale);
struct cJSON *iird_json_counters(const char *method, const iir_frame_stats *st);
/* The frame-time controller's state after the frame (target_ms, mean_ms, predicted_ms, reachable,
 * vpls, interleave, sm_res, rung, rungs, moves), or JSON null when it had none (target_fps 0). */
struct cJSON *iird_json_ctl(const iir_frame_stats *st);
struct cJSON *iird_json_vpl_counts(const iir_vpl_counts *c);
struct cJSON *iird_json_rays(const iir_raystats *r);

/* vpl_px: per VPL its pixel position (x, y; -1, -1 when not visible) and flags; dom may be NULL
 * for methods without a disk domain. */
char *iird_json_domain(uint32_t frame, const float (*vpl_px)[2], const uint8_t *vpl_flags,
                       uint32_t num_vpls, const struct iir_domain *dom);
char *iird_json_pick(int64_t seq, bool hit, iir_vec3 position, iir_vec3 normal, float distance);
char *iird_json_snapshot(int64_t seq, const char *format, uint32_t frame, uint32_t pass,
                         size_t bytes, int width, int height);

/* ---- recording: what a session showed over time (its light, camera and exposure), written as an
 * animation script ---- */
typedef struct iird_recording iird_recording;
/* scene: the scene it is recorded on, named in the script (NULL: none); scenes_dir: the folder,
 * absolute, that finds it by that name, named as the script's "scenes" (NULL or "": none, e.g. the
 * built-in box). NULL on out-of-memory. */
iird_recording *iird_recording_create(int fps, const char *scene, const char *scenes_dir);
/* The frame size the session renders at, named as the script's "size" (the last one set; a size
 * outside [1, 16384] names none). */
void iird_recording_set_size(iird_recording *r, int width, int height);
int iird_recording_fps(const iird_recording *r);
void iird_recording_destroy(iird_recording *r);
/* Each adds the state applied at t seconds since start to its track. t is rounded to
 * microseconds; a t at or before the track's last key replaces that key's value. The key that
 * ends a pause of the light or camera longer than a frame (1/fps) is a step key (held, then a
 * jump at t). False (too_large) past 100000 keys in all or 36000 s, internal for a t that is not
 * finite or out of memory; the recording is then unchanged. The session adds every part at t = 0
 * on `start`, so the script starts where the session was; the light track is named after the
 * first light added. */
bool iird_recording_add(iird_recording *r, double t, const iir_light *light, iird_proto_error *err);
bool iird_recording_add_camera(iird_recording *r, double t, const iir_camera *camera,
                               iird_proto_error *err);
bool iird_recording_add_exposure(iird_recording *r, double t, float stops, iird_proto_error *err);
/* True when one more state can be added at t (false with err as an add would fill it), and then
 * the add of one state at t that follows, before any other, cannot fail: for a message that must
 * check everything before it changes anything. */
bool iird_recording_room(iird_recording *r, double t, iird_proto_error *err);
/* Where the recording ends (stop, or a scene switch), t seconds since start: the script lasts a
 * whole number of frames until at least then, so its last frame shows the state at t. */
void iird_recording_end(iird_recording *r, double t);
/* The script (docs/animation-format.md) that iir_anim_parse accepts and that reproduces the light,
 * camera and exposure at every recorded time; wrapped in the `record` reply, whose "keyframes" are
 * the light track's keys. */
char *iird_json_record_stop(const iird_recording *r, int64_t seq);
char *iird_json_record_start(int64_t seq);
/* The `record` reply with the script so far; continues: the recording goes on (a scene switch:
 * "recording": true, the client keeps its recording state). iird_json_record_stop = not. */
char *iird_json_record_part(const iird_recording *r, int64_t seq, bool continues);
/* The script alone (malloc'd JSON text, NULL on out-of-memory), e.g. to save it to a file. */
char *iird_recording_script(const iird_recording *r);

/* ---- save: the session's lights and camera as a scene sidecar (docs/scene-format.md) ---- */
typedef struct iird_sidecar_view {
    const char *base; /* the scene it is based on: "builtin" or a name in the scenes dir */
    const iir_camera *camera;
    float aspect; /* the camera's width / height (the session's frame) */
    const iir_light *lights;
    uint32_t num_lights;
} iird_sidecar_view;
/* The sidecar as indented JSON text, for the file (malloc'd; NULL on out-of-memory). */
char *iird_sidecar_text(const iird_sidecar_view *v);
/* The `save` reply: the sidecar, and with a name (NULL: none) that name and the scene names a
 * client may now ask for (scenes: NULL-terminated; scenes_more as in iird_json_welcome). */
char *iird_json_save(const iird_sidecar_view *v, int64_t seq, const char *name,
                     const char *const *scenes, size_t scenes_more);

/* ---- binary frames ---- */
typedef struct iird_frame_header {
    uint8_t kind; /* 1 frame (JPEG), 2 snapshot */
    uint32_t frame_id;
    uint32_t seq; /* 0xFFFFFFFF: no input yet */
    uint16_t width, height;
    float render_ms, encode_ms;
    uint32_t pass;
    uint32_t flags; /* bit 0 converged, bit 1 refinement frame */
    uint32_t payload_bytes;
    uint32_t generation; /* of the session state it shows (docs/protocol.md, `state`) */
} iird_frame_header;

/* Writes the 44-byte little-endian header of docs/protocol.md (version 2). */
void iird_frame_header_write(const iird_frame_header *h, uint8_t out[IIRD_FRAME_HEADER_BYTES]);

#endif

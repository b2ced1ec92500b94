/* protocol_parse.c -- one client text message (docs/protocol.md, "Client -> server") into an
 * iird_msg: size, UTF-8, JSON, `seq`, `type`, the fields each type has and their types and
 * ranges. Not checks against the session's state (protocol_apply.c).
 *
 * Order of checks, so that a message with several problems always gets the same error: size
 * (too_large), empty / not UTF-8 / not JSON / trailing text / not an object (bad_json), `seq`
 * (so that every later error can echo it), `type` (bad_type, unknown_type), every member's name
 * (unknown_field; a repeated name is bad_json, since cJSON would keep both and the meaning is
 * ambiguous), then the fields in the order of the type's table. */
#include "protocol_internal.h"

#include <assert.h>
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_FIELDS = 64 };

static const char *const HELLO_FIELDS[] = {"protocol", "token", "client", NULL};
/* same order as IIRD_L_* and IIRD_C_* */
static const char *const LIGHT_FIELDS[] = {"position",  "direction", "target", "cone_angle",
                                           "intensity", "name",      "on",     "inner_angle",
                                           "size",      NULL};
static const char *const CAMERA_FIELDS[] = {"position", "target", "up", "fov", NULL};
/* "method", the stream settings, then every method parameter (each name once); built once. */
static const char *PARAMS_FIELDS[MAX_FIELDS + 1];
static pthread_once_t params_fields_once = PTHREAD_ONCE_INIT;

static void add_field(int *n, const char *name)
{
    for (int i = 0; i < *n; i++)
        if (!strcmp(PARAMS_FIELDS[i], name)) return;
    assert(*n < MAX_FIELDS && "MAX_FIELDS holds every params field");
    PARAMS_FIELDS[(*n)++] = name;
}

static void build_params_fields(void)
{
    int n = 0;
    add_field(&n, "method");
    for (int i = 0; i < iird_stream_table.count; i++) add_field(&n, iird_stream_table.rows[i].name);
    for (const iir_param_table *const *t = iir_method_all_tables(); *t; t++)
        for (int i = 0; i < (*t)->count; i++) add_field(&n, (*t)->rows[i].name);
    PARAMS_FIELDS[n] = NULL;
}
static const char *const SCENE_FIELDS[] = {"name", NULL};
static const char *const PICK_FIELDS[] = {"x", "y", NULL};
static const char *const SNAPSHOT_FIELDS[] = {"format", NULL};
static const char *const RECORD_FIELDS[] = {"action", "fps", NULL};
static const char *const SAVE_FIELDS[] = {"name", NULL};
static const char *const SCENES_FIELDS[] = {NULL};

static const char *const FORMAT_NAMES[] = {"png", "exr", NULL};
static const char *const ACTION_NAMES[] = {"start", "stop", NULL};

/* Joins names as "a, b, c" into out. */
static void join(char *out, size_t size, const char *const *names)
{
    out[0] = '\0';
    for (int i = 0; names[i]; i++) {
        size_t used = strlen(out);
        snprintf(out + used, size - used, "%s%s", i ? ", " : "", names[i]);
    }
}

static bool required(const iird_pctx *c, const cJSON *v, const char *name, const char *what)
{
    char path[IIRD_PATH_BYTES];
    if (v) return true;
    iird_path(path, c->prefix, name);
    return iird_proto_fail(c->err, IIRD_E_BAD_TYPE, path, "%s is required (%s)", path, what);
}

/* ======================== per message type ======================== */

static bool parse_hello(const iird_pctx *c, const cJSON *const *f, const iird_limits *lim,
                        iird_msg *out)
{
    (void)lim;
    double v = 1.0;
    iird_range any = {-DBL_MAX, DBL_MAX, false, false, NULL};
    out->u.hello.protocol = IIRD_PROTOCOL_VERSION;
    if (f[0] && !iird_get_number(c, f[0], "protocol", any, &v)) return false;
    if (v != floor(v))
        return iird_proto_fail(c->err, IIRD_E_BAD_TYPE, "hello.protocol",
                               "hello.protocol must be an integer, got %.15g", v);
    if (v != IIRD_PROTOCOL_VERSION)
        return iird_proto_fail(c->err, IIRD_E_UNSUPPORTED, "hello.protocol",
                               "protocol %.15g is not supported; this server speaks protocol %d", v,
                               IIRD_PROTOCOL_VERSION);
    out->u.hello.has_token = f[1] != NULL;
    if (f[1] &&
        !iird_get_string(c, f[1], "token", sizeof out->u.hello.token - 1, out->u.hello.token))
        return false;
    return !f[2] ||
           iird_get_string(c, f[2], "client", sizeof out->u.hello.client - 1, out->u.hello.client);
}

/* A vector that must not be zero (directions, up); normalised in double precision. */
static bool get_dir(const iird_pctx *c, const cJSON *v, const char *name, bool normalise,
                    iir_vec3 *out)
{
    char path[IIRD_PATH_BYTES];
    if (!iird_get_vec3(c, v, name, -IIRD_MAX_COORD, IIRD_MAX_COORD, out)) return false;
    double x = out->x, y = out->y, z = out->z, len = sqrt(x * x + y * y + z * z);
    iird_path(path, c->prefix, name);
    if (!(len > 0.0))
        return iird_proto_fail(c->err, IIRD_E_OUT_OF_RANGE, path, "%s must not be zero", path);
    if (normalise) *out = iir_v3((float)(x / len), (float)(y / len), (float)(z / len));
    return true;
}

static bool get_point(const iird_pctx *c, const cJSON *v, const char *name, iir_vec3 *out)
{
    return iird_get_vec3(c, v, name, -IIRD_MAX_COORD, IIRD_MAX_COORD, out);
}

static bool get_intensity(const iird_pctx *c, const cJSON *v, iird_msg_light *m)
{
    double s = 0.0;
    iird_range r = {0.0, IIRD_MAX_COORD, false, false, NULL};
    m->intensity_is_scalar = cJSON_IsNumber(v);
    if (!m->intensity_is_scalar && !cJSON_IsArray(v))
        return iird_proto_fail(c->err, IIRD_E_BAD_TYPE, "light.intensity",
                               "light.intensity must be an array of 3 numbers or a number, got %s",
                               iird_json_kind(v));
    if (!m->intensity_is_scalar)
        return iird_get_vec3(c, v, "intensity", 0.0, IIRD_MAX_COORD, &m->intensity);
    if (!iird_get_number(c, v, "intensity", r, &s)) return false;
    m->intensity = iir_v3((float)s, 0.f, 0.f);
    return true;
}

/* [width, height]: exactly 2 numbers, each in (0, IIRD_MAX_COORD]. */
static bool get_size(const iird_pctx *c, const cJSON *v, iir_vec2 *out)
{
    iird_range r = {0.0, IIRD_MAX_COORD, true, false, NULL};
    double e[2];
    int n = cJSON_IsArray(v) ? cJSON_GetArraySize(v) : -1, i = 0;
    if (n < 0)
        return iird_proto_fail(c->err, IIRD_E_BAD_TYPE, "light.size",
                               "light.size must be an array of 2 numbers (width, height), got %s",
                               iird_json_kind(v));
    if (n != 2)
        return iird_proto_fail(c->err, IIRD_E_BAD_TYPE, "light.size",
                               "light.size must be an array of 2 numbers (width, height), got %d "
                               "elements",
                               n);
    for (const cJSON *x = v->child; x; x = x->next, i++)
        if (!iird_get_number(c, x, i ? "size[1]" : "size[0]", r, &e[i])) return false;
    *out = iir_v2((float)e[0], (float)e[1]);
    return true;
}

/* The light a message addresses: name, and whether it is switched on or off. */
static bool get_which(const iird_pctx *c, const cJSON *const *f, iird_msg_light *m)
{
    if (f[IIRD_L_NAME] && !iird_get_string(c, f[IIRD_L_NAME], "name", sizeof m->name - 1, m->name))
        return false;
    if (f[IIRD_L_NAME] && !m->name[0])
        return iird_proto_fail(c->err, IIRD_E_BAD_FIELD, "light.name",
                               "light.name must name one of the scene's lights (state.lights)");
    return !f[IIRD_L_ON] || iird_get_bool(c, f[IIRD_L_ON], "on", &m->on);
}

static bool parse_light(const iird_pctx *c, const cJSON *const *f, const iird_limits *lim,
                        iird_msg *out)
{
    (void)lim;
    iird_msg_light *m = &out->u.light;
    iird_range cone = {0.0, 90.0, true, false, "degrees"};
    iird_range inner = {0.0, 90.0, false, false, "degrees"};
    double deg = 0.0, inner_deg = 0.0;
    for (int i = 0; LIGHT_FIELDS[i]; i++) m->has |= f[i] ? 1u << i : 0u;
    if (!(m->has & ~(1u << IIRD_L_NAME)))
        return iird_proto_fail(c->err, IIRD_E_BAD_FIELD, "light",
                               "a light message needs at least one of position, direction, "
                               "target, cone_angle, inner_angle, size, intensity, on");
    if (!get_which(c, f, m)) return false;
    if (f[IIRD_L_POSITION] && !get_point(c, f[IIRD_L_POSITION], "position", &m->position))
        return false;
    if (f[IIRD_L_DIRECTION] && !get_dir(c, f[IIRD_L_DIRECTION], "direction", true, &m->direction))
        return false;
    if (f[IIRD_L_TARGET] && !get_point(c, f[IIRD_L_TARGET], "target", &m->target)) return false;
    if (f[IIRD_L_DIRECTION] && f[IIRD_L_TARGET])
        return iird_proto_fail(c->err, IIRD_E_BAD_FIELD, "light.target",
                               "light.target cannot be given together with light.direction: "
                               "give one of them");
    if (f[IIRD_L_CONE] && !iird_get_number(c, f[IIRD_L_CONE], "cone_angle", cone, &deg))
        return false;
    if (f[IIRD_L_INNER] && !iird_get_number(c, f[IIRD_L_INNER], "inner_angle", inner, &inner_deg))
        return false;
    m->cone_angle_deg = (float)deg;
    m->inner_angle_deg = (float)inner_deg;
    if (f[IIRD_L_SIZE] && !get_size(c, f[IIRD_L_SIZE], &m->size)) return false;
    return !f[IIRD_L_INTENSITY] || get_intensity(c, f[IIRD_L_INTENSITY], m);
}

static bool parse_camera(const iird_pctx *c, const cJSON *const *f, const iird_limits *lim,
                         iird_msg *out)
{
    (void)lim;
    iird_msg_camera *m = &out->u.camera;
    iird_range fov = {1.0, 170.0, false, false, "degrees"};
    double deg = 0.0;
    for (int i = 0; CAMERA_FIELDS[i]; i++) m->has |= f[i] ? 1u << i : 0u;
    if (f[IIRD_C_POSITION] && !get_point(c, f[IIRD_C_POSITION], "position", &m->position))
        return false;
    if (f[IIRD_C_TARGET] && !get_point(c, f[IIRD_C_TARGET], "target", &m->target)) return false;
    if (f[IIRD_C_UP] && !get_dir(c, f[IIRD_C_UP], "up", false, &m->up)) return false;
    if (f[IIRD_C_FOV] && !iird_get_number(c, f[IIRD_C_FOV], "fov", fov, &deg)) return false;
    m->fov = (float)deg;
    return true;
}

/* "method" names a method; every other field is read by its row (protocol_params.c). */
static bool parse_params(const iird_pctx *c, const cJSON *const *f, const iird_limits *lim,
                         iird_msg *out)
{
    (void)lim;
    iird_msg_params *m = &out->u.params;
    int k = 0;
    if (f[0] && !iird_get_enum(c, f[0], "method", iir_method_names(), &k)) return false;
    if (f[0]) m->has_method = true;
    if (f[0]) snprintf(m->method, sizeof m->method, "%s", iir_method_names()[k]);
    for (int i = 1; PARAMS_FIELDS[i]; i++) {
        const iir_param *row = f[i] ? iird_params_row(PARAMS_FIELDS[i]) : NULL;
        double v = 0.0;
        iir_error e;
        if (!row) continue;
        if (!iird_get_param(c, f[i], row, &v)) return false;
        if (iir_params_set(&m->values, row, v, &e) != IIR_OK)
            return iird_proto_fail(c->err, IIRD_E_OUT_OF_RANGE, "params", "params: %s", e.msg);
    }
    return true;
}

static bool parse_scene(const iird_pctx *c, const cJSON *const *f, const iird_limits *lim,
                        iird_msg *out)
{
    (void)lim;
    char *name = out->u.scene.name;
    if (!required(c, f[0], "name", "a string") ||
        !iird_get_string(c, f[0], "name", sizeof out->u.scene.name - 1, name))
        return false;
    bool bad = name[0] == '\0' || name[0] == '.' || strchr(name, '/') || strchr(name, '\\') ||
               strstr(name, "..");
    for (const char *s = name; *s && !bad; s++) bad = (unsigned char)*s < 0x20;
    if (bad)
        return iird_proto_fail(c->err, IIRD_E_BAD_FIELD, "scene.name",
                               "scene.name must be the name of a scene in the scenes directory "
                               "(no '/', '\\', '..', leading '.' or control characters)");
    return true;
}

static bool parse_pick(const iird_pctx *c, const cJSON *const *f, const iird_limits *lim,
                       iird_msg *out)
{
    iird_range rx = {0.0, lim->max_width, false, true, "pixels"};
    iird_range ry = {0.0, lim->max_height, false, true, "pixels"};
    return required(c, f[0], "x", "a number") && required(c, f[1], "y", "a number") &&
           iird_get_number(c, f[0], "x", rx, &out->u.pick.x) &&
           iird_get_number(c, f[1], "y", ry, &out->u.pick.y);
}

static bool parse_snapshot(const iird_pctx *c, const cJSON *const *f, const iird_limits *lim,
                           iird_msg *out)
{
    (void)lim;
    int k = 0;
    if (!required(c, f[0], "format", "\"png\" or \"exr\"") ||
        !iird_get_enum(c, f[0], "format", FORMAT_NAMES, &k))
        return false;
    out->u.snapshot.exr = k == 1;
    return true;
}

static bool parse_record(const iird_pctx *c, const cJSON *const *f, const iird_limits *lim,
                         iird_msg *out)
{
    (void)lim;
    int k = 0;
    out->u.record.fps = 30;
    if (!required(c, f[0], "action", "\"start\" or \"stop\"") ||
        !iird_get_enum(c, f[0], "action", ACTION_NAMES, &k))
        return false;
    out->u.record.start = k == 0;
    if (f[1] && !iird_get_int32(c, f[1], "fps", 1, 240, &out->u.record.fps)) return false;
    if (f[1] && !out->u.record.start)
        return iird_proto_fail(c->err, IIRD_E_BAD_FIELD, "record.fps",
                               "record.fps only goes with action \"start\"");
    return true;
}

/* A name to save a scene under: a bare name as the scenes directory's (letters, digits, '_',
 * '-', '.'; not starting with '.', no '..'), and not the built-in box's. */
static bool parse_save(const iird_pctx *c, const cJSON *const *f, const iird_limits *lim,
                       iird_msg *out)
{
    (void)lim;
    char *name = out->u.save.name;
    out->u.save.has_name = f[0] != NULL;
    if (!f[0]) return true;
    if (!iird_get_string(c, f[0], "name", 100, name)) return false;
    bool bad = name[0] == '\0' || name[0] == '.' || strstr(name, "..") || !strcmp(name, "builtin");
    for (const char *s = name; *s && !bad; s++)
        bad = !((*s >= 'a' && *s <= 'z') || (*s >= 'A' && *s <= 'Z') || (*s >= '0' && *s <= '9') ||
                *s == '_' || *s == '-' || *s == '.');
    if (bad)
        return iird_proto_fail(c->err, IIRD_E_BAD_FIELD, "save.name",
                               "save.name must be a new scene's bare name: letters, digits, '_', "
                               "'-' and '.', not starting with '.', no '..', not \"builtin\"");
    return true;
}

/* `scenes` has no fields of its own. */
static bool parse_scenes(const iird_pctx *c, const cJSON *const *f, const iird_limits *lim,
                         iird_msg *out)
{
    (void)c, (void)f, (void)lim, (void)out;
    return true;
}

/* ======================== the message ======================== */

typedef bool (*parse_fn)(const iird_pctx *c, const cJSON *const *f, const iird_limits *lim,
                         iird_msg *out);

static const struct msg_kind {
    const char *name;
    iird_msg_type type;
    const char *const *fields;
    parse_fn parse;
} KINDS[] = {
    {"hello", IIRD_MSG_HELLO, HELLO_FIELDS, parse_hello},
    {"light", IIRD_MSG_LIGHT, LIGHT_FIELDS, parse_light},
    {"camera", IIRD_MSG_CAMERA, CAMERA_FIELDS, parse_camera},
    {"params", IIRD_MSG_PARAMS, PARAMS_FIELDS, parse_params},
    {"scene", IIRD_MSG_SCENE, SCENE_FIELDS, parse_scene},
    {"pick", IIRD_MSG_PICK, PICK_FIELDS, parse_pick},
    {"snapshot", IIRD_MSG_SNAPSHOT, SNAPSHOT_FIELDS, parse_snapshot},
    {"record", IIRD_MSG_RECORD, RECORD_FIELDS, parse_record},
    {"save", IIRD_MSG_SAVE, SAVE_FIELDS, parse_save},
    {"scenes", IIRD_MSG_SCENES, SCENES_FIELDS, parse_scenes},
};
enum { NUM_KINDS = sizeof KINDS / sizeof KINDS[0] };

static int index_of(const char *const *names, const char *name)
{
    for (int i = 0; names[i]; i++)
        if (strcmp(names[i], name) == 0) return i;
    return -1;
}

/* Every member of root by its index in k->fields; unknown_field for a name the type does not
 * have, bad_json for a name given twice. */
static bool collect_fields(const iird_pctx *c, const cJSON *root, const struct msg_kind *k,
                           const cJSON **f)
{
    char path[IIRD_PATH_BYTES], list[200];
    int type_seen = 0, seq_seen = 0;
    for (const cJSON *m = root->child; m; m = m->next) {
        const char *name = m->string ? m->string : "";
        int i = index_of(k->fields, name);
        bool dup = false;
        if (strcmp(name, "type") == 0)
            dup = type_seen++ > 0;
        else if (strcmp(name, "seq") == 0)
            dup = seq_seen++ > 0;
        else if (i < 0) {
            iird_path(path, c->prefix, name);
            join(list, sizeof list, k->fields);
            return iird_proto_fail(c->err, IIRD_E_UNKNOWN_FIELD, path,
                                   "%s is not a field of %s (fields: %s)", path, k->name, list);
        } else {
            dup = f[i] != NULL;
            f[i] = m;
        }
        iird_path(path, i < 0 ? "" : c->prefix, name);
        if (dup)
            return iird_proto_fail(c->err, IIRD_E_BAD_JSON, path, "%s is given more than once",
                                   path);
    }
    return true;
}

static const struct msg_kind *find_kind(const iird_pctx *c, const cJSON *type)
{
    char got[40], list[120];
    const char *names[NUM_KINDS + 1];
    for (int i = 0; i < NUM_KINDS; i++) names[i] = KINDS[i].name;
    names[NUM_KINDS] = NULL;
    if (!type) {
        iird_proto_fail(c->err, IIRD_E_BAD_TYPE, "type", "a message needs a string field \"type\"");
        return NULL;
    }
    if (!cJSON_IsString(type) || !type->valuestring) {
        iird_proto_fail(c->err, IIRD_E_BAD_TYPE, "type", "type must be a string, got %s",
                        iird_json_kind(type));
        return NULL;
    }
    if (strchr(type->valuestring, IIRD_NUL_MARK)) {
        iird_proto_fail(c->err, IIRD_E_OUT_OF_RANGE, "type",
                        "type must not hold a NUL character (\\u0000)");
        return NULL;
    }
    for (int i = 0; i < NUM_KINDS; i++)
        if (strcmp(KINDS[i].name, type->valuestring) == 0) return &KINDS[i];
    snprintf(got, sizeof got, "%s", type->valuestring);
    iird_utf8_trim(got);
    join(list, sizeof list, names);
    iird_proto_fail(c->err, IIRD_E_UNKNOWN_TYPE, "type",
                    "\"%s\" is not a client message type (types: %s)", got, list);
    return NULL;
}

static bool parse_root(const cJSON *root, const iird_limits *lim, iird_msg *out,
                       iird_proto_error *err)
{
    iird_pctx top = {"", err};
    int64_t seq = 0;
    if (!cJSON_IsObject(root))
        return iird_proto_fail(err, IIRD_E_BAD_JSON, NULL,
                               "a message must be a JSON object, got %s", iird_json_kind(root));
    const cJSON *s = cJSON_GetObjectItemCaseSensitive(root, "seq");
    if (s && !iird_get_int(&top, s, "seq", 0.0, 4294967294.0, &seq)) return false;
    if (s) out->seq = err->seq = seq;
    const struct msg_kind *k = find_kind(&top, cJSON_GetObjectItemCaseSensitive(root, "type"));
    if (!k) return false;
    iird_pctx c = {k->name, err};
    const cJSON *f[MAX_FIELDS] = {NULL};
    out->type = k->type;
    return collect_fields(&c, root, k, f) && k->parse(&c, f, lim, out);
}

/* Where a \u0000 escape starts inside a JSON string of text[0..len) from i on; len if none. A
 * backslash escapes the next character, so "\\u0000" (a backslash, then u0000) is not one. */
static size_t next_nul_escape(const char *text, size_t len, size_t i, bool *in_string)
{
    for (; i < len; i++) {
        if (text[i] == '"') {
            *in_string = !*in_string;
        } else if (*in_string && text[i] == '\\') {
            if (len - i >= 6 && text[i + 1] == 'u' && !memcmp(text + i + 2, "0000", 4)) return i;
            i++;
        }
    }
    return len;
}

/* A copy of text with every \u0000 escape inside a string replaced by IIRD_NUL_MARK (one byte for
 * six), or NULL when there is none or no memory (*oom then set). *out_len is the copy's length. */
static char *mark_nul_escapes(const char *text, size_t len, size_t *out_len, bool *oom)
{
    bool in_string = false;
    size_t at = next_nul_escape(text, len, 0, &in_string);
    *oom = false;
    if (at == len) return NULL;
    char *copy = malloc(len);
    if (!copy) return *oom = true, NULL;
    size_t n = 0, from = 0;
    while (at < len) {
        memcpy(copy + n, text + from, at - from);
        n += at - from;
        copy[n++] = IIRD_NUL_MARK;
        from = at + 6;
        at = next_nul_escape(text, len, from, &in_string);
    }
    memcpy(copy + n, text + from, len - from);
    *out_len = n + (len - from);
    return copy;
}

static bool json_space(char ch)
{
    return ch == ' ' || ch == '\t' || ch == '\n' || ch == '\r';
}

bool iird_parse_message(const char *text, size_t len, const iird_limits *limits, iird_msg *out,
                        iird_proto_error *err)
{
    iird_proto_error scratch;
    iird_limits lim = limits ? *limits : iird_limits_default();
    if (!err) err = &scratch;
    pthread_once(&params_fields_once, build_params_fields);
    memset(out, 0, sizeof *out);
    out->seq = err->seq = IIRD_NO_SEQ;
    if (len > IIRD_MAX_MESSAGE_BYTES)
        return iird_proto_fail(err, IIRD_E_TOO_LARGE, NULL,
                               "message of %zu bytes is over the limit of %d bytes", len,
                               IIRD_MAX_MESSAGE_BYTES);
    if (!text || len == 0) return iird_proto_fail(err, IIRD_E_BAD_JSON, NULL, "empty message");
    if (!iird_utf8_valid(text, len))
        return iird_proto_fail(err, IIRD_E_BAD_JSON, NULL,
                               "message is not UTF-8 text (or holds a NUL byte)");
    bool oom = false;
    char *marked = mark_nul_escapes(text, len, &len, &oom);
    if (oom) return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "out of memory");
    if (marked) text = marked;
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithLengthOpts(text, len, &end, false);
    if (!root) {
        long at = end && end >= text && end <= text + len ? (long)(end - text) : 0;
        free(marked);
        return iird_proto_fail(
            err, IIRD_E_BAD_JSON, NULL,
            "not valid JSON (nested too deeply, or a syntax error near byte %ld)", at);
    }
    while (end < text + len && json_space(*end)) end++;
    bool ok = end == text + len
                  ? parse_root(root, &lim, out, err)
                  : iird_proto_fail(err, IIRD_E_BAD_JSON, NULL,
                                    "unexpected text after the JSON value at byte %ld",
                                    (long)(end - text));
    cJSON_Delete(root);
    free(marked);
    return ok;
}

/* protocol_apply.c -- applying parsed `light`, `camera` and `params` messages to a session's
 * state, all or nothing: each works on a copy, checks the combined result (iir_light_validate,
 * iir_camera_validate, the stream table and the server limits, the methods' parameter tables with
 * their checks) and writes it back only when it is acceptable. The settings' defaults. Not parsing
 * (protocol_parse.c). */
#include "protocol_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

iird_limits iird_limits_default(void)
{
    iird_limits l = {.max_width = 1920, .max_height = 1080};
    return l;
}

iird_settings iird_settings_default(void)
{
    iird_settings s;
    memset(&s, 0, sizeof s);
    snprintf(s.method, sizeof s.method, "%s", "iir");
    s.params = iir_params_default();
    iir_params_defaults(&iird_stream_table, &s);
    return s;
}

/* ======================== light ======================== */

/* b - a in double precision, and its length. */
static double diff_len(iir_vec3 a, iir_vec3 b, double d[3])
{
    d[0] = (double)b.x - a.x;
    d[1] = (double)b.y - a.y;
    d[2] = (double)b.z - a.z;
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
}

/* Tolerance under which two points count as equal: relative to their size, as camera.c does. */
static double point_eps(iir_vec3 a, iir_vec3 b)
{
    return 1e-6 * fmax(1.0, fmax(iir_length(a), iir_length(b)));
}

/* Scales the colour so that its largest channel is s; a black (or broken) colour becomes grey. */
static iir_vec3 scale_intensity(iir_vec3 rgb, float s)
{
    float m = iir_max_comp(rgb);
    if (!(m > 0.f) || !iir_is_finite3(rgb) || fminf(rgb.x, fminf(rgb.y, rgb.z)) < 0.f)
        return iir_v3s(s);
    double k = (double)s / m;
    iir_vec3 out = iir_v3((float)(rgb.x * k), (float)(rgb.y * k), (float)(rgb.z * k));
    if (rgb.x == m) out.x = s; /* exactly s, not s up to rounding */
    if (rgb.y == m) out.y = s;
    if (rgb.z == m) out.z = s;
    return out;
}

static bool is_spot(const iir_light *L)
{
    return L->type == IIR_LIGHT_SPOT;
}

static bool is_gltf_spot(const iir_light *L)
{
    return is_spot(L) && L->profile == IIR_SPOT_GLTF;
}

/* The protocol field behind an iir_light_validate failure, and its code. */
static const char *light_problem(const iir_light *L, iird_err *code)
{
    *code = IIRD_E_OUT_OF_RANGE;
    if (!iir_is_finite3(L->position)) return "light.position";
    if (!iir_is_finite3(L->intensity) ||
        fminf(L->intensity.x, fminf(L->intensity.y, L->intensity.z)) < 0.f)
        return "light.intensity";
    if (is_spot(L) && !(L->cone_angle > 0.f && L->cone_angle <= IIR_PI * 0.5f + 1e-6f))
        return "light.cone_angle";
    *code = IIRD_E_BAD_FIELD;
    if (!iir_is_finite3(L->direction) || iir_length(L->direction) < 1e-6f) return "light.direction";
    if (L->type == IIR_LIGHT_AREA) return "light.size";
    if (is_gltf_spot(L) && !(L->inner_angle >= 0.f && L->inner_angle <= L->cone_angle))
        return "light.inner_angle";
    return "light.cone_angle"; /* the smooth edge is wider than the cone */
}

/* bad_field on `field` unless the light has it (kind: what a light needs to have it). */
static bool has_field(const iir_light *L, bool has, const char *field, const char *kind,
                      iird_proto_error *err)
{
    if (has) return true;
    return iird_proto_fail(err, IIRD_E_BAD_FIELD, field,
                           "%s: light '%s' is a %s light; only %s have this field", field, L->name,
                           iir_light_kind(L), kind);
}

/* The message's fields against the light's kind: a cone for spots, an inner cone for glTF spots,
 * a size for area lights, and a sun's position only to aim it (with a target). */
static bool fields_of_kind(const iird_msg_light *m, const iir_light *L, iird_proto_error *err)
{
    unsigned has = m->has;
    if ((has & (1u << IIRD_L_CONE)) && !has_field(L, is_spot(L), "light.cone_angle", "spots", err))
        return false;
    if ((has & (1u << IIRD_L_INNER)) &&
        !has_field(L, is_gltf_spot(L), "light.inner_angle", "glTF spots", err))
        return false;
    if ((has & (1u << IIRD_L_SIZE)) &&
        !has_field(L, L->type == IIR_LIGHT_AREA, "light.size", "area lights", err))
        return false;
    if (L->type == IIR_LIGHT_SUN && (has & (1u << IIRD_L_POSITION)) &&
        !(has & (1u << IIRD_L_TARGET)))
        return iird_proto_fail(err, IIRD_E_BAD_FIELD, "light.position",
                               "light.position: light '%s' is a sun: its light covers the whole "
                               "scene from no position; turn it with direction, or with target "
                               "(and position: the way from position to target)",
                               L->name);
    return true;
}

/* Aims L from its (new) position at target. */
static bool aim_at(iir_light *L, iir_vec3 target, iird_proto_error *err)
{
    double d[3], len = diff_len(L->position, target, d);
    if (!(len > point_eps(L->position, target)))
        return iird_proto_fail(err, IIRD_E_BAD_FIELD, "light.target",
                               "light.target (%g, %g, %g) equals the light's position",
                               (double)target.x, (double)target.y, (double)target.z);
    L->direction = iir_v3((float)(d[0] / len), (float)(d[1] / len), (float)(d[2] / len));
    return true;
}

/* The cone, inner cone and size fields onto L. A new cone narrows the edge and inner cone to fit
 * in it; an inner cone given is taken as it is (validation refuses it when wider). */
static void apply_shape(const iird_msg_light *m, iir_light *L)
{
    if (m->has & (1u << IIRD_L_CONE)) {
        L->cone_angle = fminf(iir_radians(m->cone_angle_deg), IIR_PI * 0.5f);
        L->smooth = fminf(fmaxf(L->smooth, 0.f), L->cone_angle);
        L->inner_angle = fminf(fmaxf(L->inner_angle, 0.f), L->cone_angle);
    }
    if (m->has & (1u << IIRD_L_INNER)) L->inner_angle = iir_radians(m->inner_angle_deg);
    if (m->has & (1u << IIRD_L_SIZE)) L->size = m->size;
}

bool iird_apply_light(const iird_msg_light *m, iir_light *light, iird_proto_error *err)
{
    iir_light L = *light;
    iir_error e;
    iird_err code;
    if (!fields_of_kind(m, &L, err)) return false;
    if (m->has & (1u << IIRD_L_POSITION)) L.position = m->position;
    if (m->has & (1u << IIRD_L_DIRECTION)) L.direction = iir_normalize(m->direction);
    if ((m->has & (1u << IIRD_L_TARGET)) && !aim_at(&L, m->target, err)) return false;
    apply_shape(m, &L);
    if (m->has & (1u << IIRD_L_INTENSITY))
        L.intensity =
            m->intensity_is_scalar ? scale_intensity(L.intensity, m->intensity.x) : m->intensity;
    if (iir_light_validate(&L, &e) != IIR_OK) {
        const char *field = light_problem(&L, &code);
        return iird_proto_fail(err, code, field, "%s: %s", field, e.msg);
    }
    *light = L;
    return true;
}

/* ======================== camera ======================== */

/* The protocol field behind an iir_camera_validate failure, and its code. */
static const char *camera_problem(const iir_camera *C, unsigned has, iird_err *code)
{
    double d[3];
    *code = IIRD_E_OUT_OF_RANGE;
    if (!iir_is_finite3(C->position)) return "camera.position";
    if (!iir_is_finite3(C->target)) return "camera.target";
    if (!iir_is_finite3(C->up)) return "camera.up";
    if (!(C->fov_y > 0.f && C->fov_y < 180.f)) return "camera.fov";
    *code = IIRD_E_BAD_FIELD;
    if (diff_len(C->position, C->target, d) <= point_eps(C->position, C->target))
        return (has & (1u << IIRD_C_TARGET)) || !(has & (1u << IIRD_C_POSITION))
                   ? "camera.target"
                   : "camera.position";
    return "camera.up";
}

bool iird_apply_camera(const iird_msg_camera *m, iir_camera *camera, iird_proto_error *err)
{
    iir_camera C = *camera;
    iir_error e;
    iird_err code;
    if (m->has & (1u << IIRD_C_POSITION)) C.position = m->position;
    if (m->has & (1u << IIRD_C_TARGET)) C.target = m->target;
    if (m->has & (1u << IIRD_C_UP)) C.up = m->up;
    if (m->has & (1u << IIRD_C_FOV)) C.fov_y = m->fov;
    if (iir_camera_validate(&C, &e) != IIR_OK) {
        const char *field = camera_problem(&C, m->has, &code);
        return iird_proto_fail(err, code, field, "%s: %s", field, e.msg);
    }
    *camera = C;
    return true;
}

/* ======================== params ======================== */

static bool known_method(const char *name)
{
    for (const char *const *n = iir_method_names(); *n; n++)
        if (strcmp(*n, name) == 0) return true;
    return false;
}

static bool int_in(int v, int lo, int hi, const char *field, iird_proto_error *err)
{
    if (v >= lo && v <= hi) return true;
    return iird_proto_fail(err, IIRD_E_OUT_OF_RANGE, field, "%s must be in [%d, %d], got %d", field,
                           lo, hi, v);
}

/* The value set split: the stream table's rows into *stream, the rest into *method. */
static void split(const iir_params *v, iir_params *stream, iir_params *method)
{
    for (uint32_t k = 0; k < v->count; k++) {
        bool own = iir_param_table_find(&iird_stream_table, v->v[k].name) != NULL;
        iir_params *to = own ? stream : method;
        to->v[to->count++] = v->v[k];
    }
}

/* err from a failed check of row as "params.<name> ..." (kind: out_of_range or bad_field). */
static bool param_problem(iir_error *e, const iir_param *row, iird_err kind, iird_proto_error *err)
{
    char field[IIRD_PATH_BYTES];
    if (!row) return iird_proto_fail(err, kind, "params", "params: %s", e->msg);
    iird_path(field, "params", row->name);
    iir_param_reword(e, row, field);
    return iird_proto_fail(err, kind, field, "%s", e->msg);
}

/* The stream settings (from S's current ones plus the message's) into S, against the limits. */
static bool apply_stream(const iir_params *given, const iird_limits *lim, iird_settings *S,
                         iird_proto_error *err)
{
    iir_params all = iir_params_default();
    const iir_param *bad = NULL;
    iir_error e;
    for (int i = 0; i < iird_stream_table.count; i++) {
        const iir_param *row = &iird_stream_table.rows[i];
        iir_params_set(&all, row, iir_param_read(row, S), &e);
    }
    iir_params_merge(&all, given);
    if (iir_params_bind(&iird_stream_table, &all, given, S, &bad, &e) != IIR_OK)
        return param_problem(&e, bad, IIRD_E_OUT_OF_RANGE, err);
    return int_in(S->width, 16, lim->max_width, "params.width", err) &&
           int_in(S->height, 16, lim->max_height, "params.height", err);
}

bool iird_apply_params(const iird_msg_params *m, const iird_limits *limits, iird_settings *settings,
                       iird_proto_error *err)
{
    iird_limits lim = limits ? *limits : iird_limits_default();
    iird_settings S = *settings;
    iir_params stream = iir_params_default(), method = iir_params_default();
    const iir_param *bad = NULL;
    iir_error e;
    split(&m->values, &stream, &method);
    if (m->has_method) memcpy(S.method, m->method, sizeof S.method);
    if (!known_method(S.method))
        return iird_proto_fail(err, IIRD_E_OUT_OF_RANGE, "params.method",
                               "params.method '%s' is not a method of this server", S.method);
    if (!apply_stream(&stream, &lim, &S, err)) return false;
    if (!iir_params_merge(&S.params, &method))
        return iird_proto_fail(err, IIRD_E_OUT_OF_RANGE, "params", "params: too many parameters");
    if (iir_method_params_check(&method, true, &bad, &e) != IIR_OK)
        return param_problem(&e, bad, IIRD_E_OUT_OF_RANGE, err);
    if (iir_method_params_validate(S.method, &S.params, &method, &bad, &e) != IIR_OK)
        return param_problem(&e, bad, IIRD_E_BAD_FIELD, err);
    *settings = S;
    return true;
}

/* ======================== pick ======================== */

bool iird_check_pick(const iird_msg *m, int width, int height, iird_proto_error *err)
{
    err->seq = m->seq;
    double x = m->u.pick.x, y = m->u.pick.y;
    if (!(x >= 0.0 && x < width))
        return iird_proto_fail(err, IIRD_E_OUT_OF_RANGE, "pick.x",
                               "pick.x must be in [0, %d) pixels (the frame's width), got %g",
                               width, x);
    if (!(y >= 0.0 && y < height))
        return iird_proto_fail(err, IIRD_E_OUT_OF_RANGE, "pick.y",
                               "pick.y must be in [0, %d) pixels (the frame's height), got %g",
                               height, y);
    return true;
}

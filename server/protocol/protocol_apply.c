/* protocol_apply.c -- applying parsed `light`, `camera` and `params` messages to a session's
 * state, all or nothing: each works on a copy, checks the combined result (iir_light_validate,
 * iir_camera_validate, iir_params_validate and the cross-field rules of docs/protocol.md) and
 * writes it back only when it is acceptable. The settings' defaults. Not parsing
 * (protocol_parse.c). */
#include "protocol_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

iird_limits iird_limits_default(void)
{
    iird_limits l = {.max_width = 1920, .max_height = 1080, .max_vpls = 4096};
    return l;
}

iird_settings iird_settings_default(void)
{
    iird_settings s;
    memset(&s, 0, sizeof s);
    snprintf(s.method, sizeof s.method, "%s", "iir");
    s.params = iir_params_default();
    s.params.bounces = 2;
    s.params.spp = 1;
    s.width = 512;
    s.height = 384;
    s.quality = 80;
    s.exposure = 0.f;
    s.refine = true;
    s.domain = true;
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

/* The protocol field behind an iir_light_validate failure, and its code. */
static const char *light_problem(const iir_light *L, iird_err *code)
{
    *code = IIRD_E_OUT_OF_RANGE;
    if (!iir_is_finite3(L->position)) return "light.position";
    if (!iir_is_finite3(L->intensity) ||
        fminf(L->intensity.x, fminf(L->intensity.y, L->intensity.z)) < 0.f)
        return "light.intensity";
    if (!(L->cone_angle > 0.f && L->cone_angle <= IIR_PI * 0.5f + 1e-6f)) return "light.cone_angle";
    *code = IIRD_E_BAD_FIELD;
    if (!iir_is_finite3(L->direction) || iir_length(L->direction) < 1e-6f) return "light.direction";
    return "light.cone_angle"; /* the smooth edge is wider than the cone */
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

bool iird_apply_light(const iird_msg_light *m, iir_light *light, iird_proto_error *err)
{
    iir_light L = *light;
    iir_error e;
    iird_err code;
    if (m->has & (1u << IIRD_L_POSITION)) L.position = m->position;
    if (m->has & (1u << IIRD_L_DIRECTION)) L.direction = iir_normalize(m->direction);
    if ((m->has & (1u << IIRD_L_TARGET)) && !aim_at(&L, m->target, err)) return false;
    if (m->has & (1u << IIRD_L_CONE)) {
        L.cone_angle = fminf(iir_radians(m->cone_angle_deg), IIR_PI * 0.5f);
        L.smooth = fminf(fmaxf(L.smooth, 0.f), L.cone_angle);
    }
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

/* Copies params field i from v into s. */
static void merge_field(iird_settings *s, const iird_settings *v, int i)
{
    iir_params *p = &s->params;
    const iir_params *q = &v->params;
    switch (i) {
    case IIRD_P_METHOD:
        memcpy(s->method, v->method, sizeof s->method);
        break;
    case IIRD_P_VPLS:
        p->vpls = q->vpls;
        break;
    case IIRD_P_KMIN:
        p->kmin = q->kmin;
        break;
    case IIRD_P_KMAX:
        p->kmax = q->kmax;
        break;
    case IIRD_P_WEIGHTS:
        p->weights = q->weights;
        break;
    case IIRD_P_VISIBILITY:
        p->visibility = q->visibility;
        break;
    case IIRD_P_INTERLEAVE:
        p->interleave = q->interleave;
        break;
    case IIRD_P_CLAMP:
        p->clamp = q->clamp;
        break;
    case IIRD_P_SM_RES:
        p->sm_res = q->sm_res;
        break;
    case IIRD_P_BOUNCES:
        p->bounces = q->bounces;
        break;
    case IIRD_P_SPP:
        p->spp = q->spp;
        break;
    case IIRD_P_WIDTH:
        s->width = v->width;
        break;
    case IIRD_P_HEIGHT:
        s->height = v->height;
        break;
    case IIRD_P_QUALITY:
        s->quality = v->quality;
        break;
    case IIRD_P_EXPOSURE:
        s->exposure = v->exposure;
        break;
    case IIRD_P_REFINE:
        s->refine = v->refine;
        break;
    case IIRD_P_REFINE_PASSES:
        p->refine_passes = q->refine_passes;
        break;
    case IIRD_P_DOMAIN:
        s->domain = v->domain;
        break;
    case IIRD_P_SEED:
        p->seed = q->seed;
        break;
    default:
        break;
    }
}

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

/* The frame and stream settings against the server's limits. */
static bool check_frame(const iird_settings *s, const iird_limits *lim, iird_proto_error *err)
{
    if (!known_method(s->method))
        return iird_proto_fail(err, IIRD_E_OUT_OF_RANGE, "params.method",
                               "params.method '%s' is not a method of this server", s->method);
    if (!(s->exposure >= -20.f && s->exposure <= 20.f))
        return iird_proto_fail(err, IIRD_E_OUT_OF_RANGE, "params.exposure",
                               "params.exposure must be in [-20, 20], got %g", (double)s->exposure);
    return int_in(s->width, 16, lim->max_width, "params.width", err) &&
           int_in(s->height, 16, lim->max_height, "params.height", err) &&
           int_in(s->quality, 1, 100, "params.quality", err) &&
           int_in(s->params.vpls, 1, lim->max_vpls, "params.vpls", err);
}

/* kmin <= kmax <= vpls, blaming the field the message changed. */
static bool check_budgets(const iir_params *p, unsigned long long has, iird_proto_error *err)
{
    if (p->kmin > p->kmax) {
        const char *f = (has & (1ull << IIRD_P_KMIN)) || !(has & (1ull << IIRD_P_KMAX))
                            ? "params.kmin"
                            : "params.kmax";
        return iird_proto_fail(err, IIRD_E_BAD_FIELD, f, "%s: kmin %d must not exceed kmax %d", f,
                               p->kmin, p->kmax);
    }
    if (p->kmax > p->vpls) {
        const char *f = (has & (1ull << IIRD_P_KMAX)) || !(has & (1ull << IIRD_P_VPLS))
                            ? "params.kmax"
                            : "params.vpls";
        return iird_proto_fail(err, IIRD_E_BAD_FIELD, f, "%s: kmax %d must not exceed vpls %d", f,
                               p->kmax, p->vpls);
    }
    return true;
}

/* params.<first word of the validator's message> when that is a protocol field, else "params". */
static void params_problem(const char *msg, char field[IIRD_PATH_BYTES])
{
    snprintf(field, IIRD_PATH_BYTES, "params");
    for (int i = 0; i < IIRD_P_COUNT; i++) {
        const char *n = iird_params_field_name(i);
        size_t len = strlen(n);
        if (strncmp(msg, n, len) == 0 && (msg[len] == ' ' || msg[len] == '\0'))
            snprintf(field, IIRD_PATH_BYTES, "params.%s", n);
    }
}

bool iird_apply_params(const iird_msg_params *m, const iird_limits *limits, iird_settings *settings,
                       iird_proto_error *err)
{
    iird_limits lim = limits ? *limits : iird_limits_default();
    iird_settings S = *settings;
    char field[IIRD_PATH_BYTES];
    iir_error e;
    for (int i = 0; i < IIRD_P_COUNT; i++)
        if (m->has & (1ull << i)) merge_field(&S, &m->values, i);
    if (!check_frame(&S, &lim, err) || !check_budgets(&S.params, m->has, err)) return false;
    if (iir_params_validate(&S.params, &e) != IIR_OK) {
        params_problem(e.msg, field);
        return iird_proto_fail(err, IIRD_E_OUT_OF_RANGE, field, "%s: %s", field, e.msg);
    }
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

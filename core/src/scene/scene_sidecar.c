/* scene_sidecar.c -- the JSON scene sidecar (NAME.scene.json): reading and validating it with
 * cJSON, and applying it to a builder that holds the mesh; not mesh loading (scene_assimp.c) and
 * not how a sidecar is found (scene.c). The format is documented in docs/scene-format.md.
 *
 * Every field is checked: an unknown or repeated field, a wrong type, a NaN, an out-of-range value
 * is an error naming the file and the JSON field path ("lights[0].cone_angle"), so that a typo is
 * never silently ignored. Angles are degrees in the file and radians in memory.
 *
 * An area light may be taken from a material of the mesh ("material": "NAME"): its triangles must
 * be one-sided and planar (scene_area.c); they become the light (a rectangle, or a shape in its
 * bounding rectangle) and leave the geometry when the sidecar is applied (the builder holds the
 * mesh only then). An area light given by its pose may carry a "shape": triangles in its
 * light-local coordinates, as the scene writer saves a shaped light. Until then the name waits in a
 * block after the light array, in the same allocation (light_material), so iir_sidecar keeps its
 * shape. */
#include "scene_build.h"

#include "iir/json_read.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#define MAX_SIDECAR_BYTES (16L << 20)
#define MAX_COORD 1e6     /* positions, targets, directions: |x| <= this (world units) */
#define MAX_INTENSITY 1e9 /* W/sr (a sun's: W/m^2), and emission in W/sr/m^2 */

typedef char material_name[64]; /* an area light's "material", "" for none */

/* Light i's "material" in a parsed sidecar: the block after the n = num_lights lights. */
static material_name *light_material(iir_sidecar *sc, uint32_t i)
{
    return (material_name *)(void *)(sc->lights + sc->num_lights) + i;
}

/* Where errors go: the sidecar's path and the caller's error. */
typedef struct ctx {
    const char *path;
    iir_error *err;
    iir_json_file jf; /* json_read.h's readers, their faults into err */
} ctx;

static iir_status field_error(const ctx *c, iir_status st, const char *field, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static iir_status field_error(const ctx *c, iir_status st, const char *field, const char *fmt, ...)
{
    char msg[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return iir_fail(c->err, st, "%s: %s: %s", c->path, field, msg);
}

/* ======================== typed getters (json_read.h) ======================== */

/* A member of a JSON object and its path for messages; item is NULL when it is absent. */
typedef struct member {
    const cJSON *item;
    char field[IIR_JSON_PATH];
} member;

static member get_member(const cJSON *obj, const char *where, const char *name)
{
    member m;
    iir_json_path(m.field, where, name);
    m.item = cJSON_GetObjectItemCaseSensitive(obj, name);
    return m;
}

static iir_status required(const ctx *c, const member *m, const char *what)
{
    if (m->item) return IIR_OK;
    return iir_fail(c->err, IIR_ERR_FORMAT, "%s: %s is required%s", c->path, m->field, what);
}

/* Fails on a field of obj not named in `allowed` (NULL-terminated) or named twice. */
static iir_status check_fields(const ctx *c, const cJSON *obj, const char *where,
                               const char *const *allowed)
{
    return iir_json_file_status(&c->jf, iir_json_fields(&c->jf.r, obj, where, allowed));
}

static iir_status get_number(const ctx *c, const cJSON *item, const char *field, double lo,
                             double hi, double *out)
{
    iir_json_range range = {lo, hi, false, false, NULL};
    return iir_json_file_status(&c->jf, iir_json_number(&c->jf.r, item, field, range, out));
}

/* An [x, y, z] array of numbers, each within [lo, hi]. */
static iir_status get_vec3(const ctx *c, const cJSON *item, const char *field, double lo, double hi,
                           iir_vec3 *out)
{
    return iir_json_file_status(&c->jf, iir_json_vec3(&c->jf.r, item, field, lo, hi, out));
}

/* A colour: one number (grey) or [r, g, b], each within [0, hi]. */
static iir_status get_color(const ctx *c, const cJSON *item, const char *field, double hi,
                            iir_vec3 *out)
{
    if (cJSON_IsArray(item)) return get_vec3(c, item, field, 0.0, hi, out);
    double v = 0.0;
    iir_status st = get_number(c, item, field, 0.0, hi, &v);
    if (st == IIR_OK) *out = iir_v3s((float)v);
    return st;
}

/* A non-empty string that fits out's n bytes. */
static iir_status get_string(const ctx *c, const cJSON *item, const char *field, char *out,
                             size_t n)
{
    return iir_json_file_status(&c->jf, iir_json_string(&c->jf.r, item, field, 1, n - 1, out));
}

static iir_status get_position(const ctx *c, const cJSON *item, const char *field, iir_vec3 *out)
{
    return get_vec3(c, item, field, -MAX_COORD, MAX_COORD, out);
}

/* A direction (or up vector): finite, not zero. */
static iir_status get_direction(const ctx *c, const cJSON *item, const char *field, iir_vec3 *out)
{
    iir_status st = get_vec3(c, item, field, -MAX_COORD, MAX_COORD, out);
    if (st == IIR_OK && iir_length(*out) < 1e-12f)
        return field_error(c, IIR_ERR_INVALID, field, "must not be zero");
    return st;
}

/* ======================== per-object parsers ======================== */

/* True if some '/'-separated component of p is "..". */
static bool has_dotdot(const char *p)
{
    for (const char *q = p; *q;) {
        size_t len = strcspn(q, "/");
        if (len == 2 && q[0] == '.' && q[1] == '.') return true;
        q += len;
        if (*q == '/') q++;
    }
    return false;
}

/* "file": a relative path that stays inside the sidecar's folder, joined with that folder. */
static iir_status parse_file(const ctx *c, const cJSON *item, iir_sidecar *sc)
{
    char rel[512];
    iir_status st = get_string(c, item, "file", rel, sizeof rel);
    if (st != IIR_OK) return st;
    if (rel[0] == '/' || has_dotdot(rel))
        return field_error(
            c, IIR_ERR_INVALID, "file",
            "'%s' must be a path inside the sidecar's folder (no '..', not absolute)", rel);
    const char *slash = strrchr(c->path, '/');
    int dir_len = slash ? (int)(slash - c->path) : 1;
    const char *dir = slash ? c->path : ".";
    if (snprintf(sc->file, sizeof sc->file, "%.*s/%s", dir_len, dir, rel) >= (int)sizeof sc->file)
        return field_error(c, IIR_ERR_INVALID, "file", "path is too long");
    struct stat stt;
    if (stat(sc->file, &stt) != 0)
        return field_error(c, IIR_ERR_IO, "file", "cannot open %s: %s", sc->file, strerror(errno));
    return IIR_OK;
}

/* "base": a scene this one is based on, as a bare name ("builtin", or a folder beside the
 * sidecar's own folder): letters, digits, '_', '-', '.', not starting with '.'. */
static iir_status parse_base(const ctx *c, const cJSON *item, iir_sidecar *sc)
{
    iir_status st = get_string(c, item, "base", sc->base, sizeof sc->base);
    if (st != IIR_OK) return st;
    bool ok = sc->base[0] != '.' && !strstr(sc->base, "..");
    for (const char *p = sc->base; *p && ok; p++)
        ok = (*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') ||
             *p == '_' || *p == '-' || *p == '.';
    if (!ok)
        return field_error(c, IIR_ERR_INVALID, "base",
                           "'%s' must be a scene's bare name (letters, digits, '_', '-', '.'; no "
                           "'..', not starting with '.')",
                           sc->base);
    if (sc->file[0]) return field_error(c, IIR_ERR_INVALID, "base", "give file or base, not both");
    return IIR_OK;
}

static iir_status parse_unit_scale(const ctx *c, const cJSON *item, iir_sidecar *sc)
{
    double s = 0.0;
    iir_status st = get_number(c, item, "unit_scale", 0.0, MAX_COORD, &s);
    if (st == IIR_OK && !(s > 0.0))
        return field_error(c, IIR_ERR_INVALID, "unit_scale", "must be positive, got %g", s);
    if (st == IIR_OK) sc->unit_scale = (float)s;
    return st;
}

/* fov_y in degrees; 0 when absent (iir_sidecar_apply then keeps the mesh file's, else 45). */
static iir_status parse_fov(const ctx *c, const member *m, float *fov_y)
{
    *fov_y = 0.f;
    if (!m->item) return IIR_OK;
    double f = 0.0;
    iir_status st = get_number(c, m->item, m->field, -360.0, 360.0, &f);
    if (st == IIR_OK && !(f > 0.0 && f < 180.0))
        return field_error(c, IIR_ERR_INVALID, m->field, "%g degrees is outside (0, 180)", f);
    *fov_y = (float)f;
    return st;
}

/* camera.aspect (width / height); 0 when absent (iir_sidecar_apply then keeps the file's). */
static iir_status parse_aspect(const ctx *c, const member *m, float *aspect)
{
    *aspect = 0.f;
    if (!m->item) return IIR_OK;
    double a = 0.0;
    iir_status st = get_number(c, m->item, m->field, 0.0, 100.0, &a);
    if (st == IIR_OK && !(a >= 0.01))
        return field_error(c, IIR_ERR_INVALID, m->field, "%g is outside [0.01, 100]", a);
    *aspect = (float)a;
    return st;
}

static iir_status check_view(const ctx *c, const iir_camera *cam)
{
    iir_vec3 view = iir_sub(cam->target, cam->position);
    if (iir_length(view) < 1e-6f)
        return field_error(c, IIR_ERR_INVALID, "camera.target", "equals camera.position");
    if (iir_length(iir_cross(iir_normalize(view), iir_normalize(cam->up))) < 1e-6f)
        return field_error(c, IIR_ERR_INVALID, "camera.up", "is parallel to the view direction");
    return IIR_OK;
}

static iir_status parse_camera(const ctx *c, const cJSON *obj, iir_sidecar *sc)
{
    static const char *const fields[] = {"position", "target", "up", "fov_y", "aspect", NULL};
    if (!cJSON_IsObject(obj)) return field_error(c, IIR_ERR_FORMAT, "camera", "must be an object");
    member pos = get_member(obj, "camera", "position"), tgt = get_member(obj, "camera", "target");
    member up = get_member(obj, "camera", "up"), fov = get_member(obj, "camera", "fov_y");
    member aspect = get_member(obj, "camera", "aspect");
    iir_camera *cam = &sc->camera;
    cam->up = iir_v3(0.f, 1.f, 0.f);
    iir_status st = check_fields(c, obj, "camera", fields);
    if (st == IIR_OK) st = required(c, &pos, "");
    if (st == IIR_OK) st = required(c, &tgt, "");
    if (st == IIR_OK) st = get_position(c, pos.item, pos.field, &cam->position);
    if (st == IIR_OK) st = get_position(c, tgt.item, tgt.field, &cam->target);
    if (st == IIR_OK && up.item) st = get_direction(c, up.item, up.field, &cam->up);
    if (st == IIR_OK) st = parse_fov(c, &fov, &cam->fov_y);
    if (st == IIR_OK) st = parse_aspect(c, &aspect, &sc->aspect);
    if (st == IIR_OK) st = check_view(c, cam);
    sc->has_camera = st == IIR_OK;
    return st;
}

/* A spot's axis or an area light's normal: exactly one of "target" and "direction". */
static iir_status parse_axis(const ctx *c, const cJSON *obj, const char *where, iir_light *l)
{
    member tgt = get_member(obj, where, "target"), dir = get_member(obj, where, "direction");
    if (!tgt.item == !dir.item)
        return field_error(c, IIR_ERR_FORMAT, where,
                           "a%s light needs exactly one of \"target\" and \"direction\"",
                           l->type == IIR_LIGHT_AREA ? "n area" : " spot");
    iir_vec3 v = {0.f, 0.f, 0.f};
    iir_status st = tgt.item ? get_position(c, tgt.item, tgt.field, &v)
                             : get_direction(c, dir.item, dir.field, &v);
    if (st != IIR_OK) return st;
    if (tgt.item) v = iir_sub(v, l->position);
    if (tgt.item && iir_length(v) < 1e-6f)
        return field_error(c, IIR_ERR_INVALID, tgt.field, "equals the light's position");
    l->direction = iir_normalize(v);
    return IIR_OK;
}

/* cone_angle (required) and, for a cosine spot, smooth (default 0) or, for a glTF spot,
 * inner_angle (default 0): degrees in the file, radians in l. */
static iir_status parse_cone(const ctx *c, const cJSON *obj, const char *where, iir_light *l)
{
    bool gltf = l->profile == IIR_SPOT_GLTF;
    member cone = get_member(obj, where, "cone_angle");
    member edge = get_member(obj, where, gltf ? "inner_angle" : "smooth");
    double alpha = 0.0, e = 0.0;
    iir_status st = required(c, &cone, " for a spot light");
    if (st == IIR_OK) st = get_number(c, cone.item, cone.field, -360.0, 360.0, &alpha);
    if (st == IIR_OK && !(alpha > 0.0 && alpha <= 90.0))
        return field_error(c, IIR_ERR_INVALID, cone.field, "%g degrees is outside (0, 90]", alpha);
    if (st == IIR_OK && edge.item) st = get_number(c, edge.item, edge.field, 0.0, alpha, &e);
    l->cone_angle = iir_radians((float)alpha);
    float edge_angle = fminf(iir_radians((float)e), l->cone_angle);
    if (gltf)
        l->inner_angle = edge_angle;
    else
        l->smooth = edge_angle;
    return st;
}

/* An error on the first of the NULL-terminated `names` that obj has: `why`. */
static iir_status forbid(const ctx *c, const cJSON *obj, const char *where,
                         const char *const *names, const char *why)
{
    for (; *names; names++) {
        member m = get_member(obj, where, *names);
        if (m.item) return field_error(c, IIR_ERR_INVALID, m.field, "%s", why);
    }
    return IIR_OK;
}

static const char *const AREA_ONLY[] = {"size", "material", "shape", "emission_map", NULL};
static const char *const AREA_ONLY_WHY = "only area lights (type \"area\") have this field";

/* The spots' fields: axis, up (default +y), cone, and the edge of the other profile refused. */
static iir_status parse_spot(const ctx *c, const cJSON *obj, const char *where, iir_light *l)
{
    static const char *const smooth[] = {"smooth", NULL}, *const inner[] = {"inner_angle", NULL};
    bool gltf = l->profile == IIR_SPOT_GLTF;
    iir_status st = forbid(c, obj, where, AREA_ONLY, AREA_ONLY_WHY);
    if (st == IIR_OK)
        st = gltf ? forbid(c, obj, where, smooth,
                           "a glTF spot has no smooth edge: its profile fades from "
                           "inner_angle to cone_angle")
                  : forbid(c, obj, where, inner,
                           "only glTF spots (type \"gltf_spot\") have this field; a "
                           "spot's edge is \"smooth\"");
    member up = get_member(obj, where, "up");
    l->up = iir_v3(0.f, 1.f, 0.f);
    if (st == IIR_OK) st = parse_axis(c, obj, where, l);
    if (st == IIR_OK && up.item) st = get_direction(c, up.item, up.field, &l->up);
    if (st == IIR_OK) st = parse_cone(c, obj, where, l);
    return st;
}

/* A sun's fields: direction (required), up (default +y); no position, target or cone. Its disk
 * is a placeholder until iir_builder_finish fits it to the scene (iir_light_fit_sun). */
static iir_status parse_sun(const ctx *c, const cJSON *obj, const char *where, iir_light *l)
{
    static const char *const pos[] = {"position", NULL}, *const tgt[] = {"target", NULL};
    static const char *const cone[] = {"cone_angle", "smooth", "inner_angle", NULL};
    member dir = get_member(obj, where, "direction"), up = get_member(obj, where, "up");
    l->up = iir_v3(0.f, 1.f, 0.f);
    l->radius = 1.f;
    iir_status st = forbid(c, obj, where, pos,
                           "a sun has no position: its parallel light covers the whole scene");
    if (st == IIR_OK)
        st = forbid(c, obj, where, tgt, "a sun is aimed by \"direction\", not at a target");
    if (st == IIR_OK) st = forbid(c, obj, where, cone, "a sun has no cone");
    if (st == IIR_OK) st = forbid(c, obj, where, AREA_ONLY, AREA_ONLY_WHY);
    if (st == IIR_OK) st = required(c, &dir, " for a sun (the way its light travels)");
    if (st == IIR_OK) st = get_direction(c, dir.item, dir.field, &l->direction);
    if (st == IIR_OK && up.item) st = get_direction(c, up.item, up.field, &l->up);
    if (st == IIR_OK) l->direction = iir_normalize(l->direction);
    return st;
}

static iir_status point_has_no(const ctx *c, const cJSON *obj, const char *where)
{
    static const char *const spot_only[] = {"target",     "direction", "up",
                                            "cone_angle", "smooth",    NULL};
    static const char *const gltf_only[] = {"inner_angle", NULL};
    iir_status st = forbid(c, obj, where, spot_only, "only spot lights have this field");
    if (st == IIR_OK)
        st = forbid(c, obj, where, gltf_only,
                    "only glTF spots (type \"gltf_spot\") have this field");
    if (st == IIR_OK) st = forbid(c, obj, where, AREA_ONLY, AREA_ONLY_WHY);
    return st;
}

/* size: [w, h], each > 0 (world units). */
static iir_status parse_size(const ctx *c, const member *m, iir_vec2 *size)
{
    if (!cJSON_IsArray(m->item) || cJSON_GetArraySize(m->item) != 2)
        return field_error(c, IIR_ERR_FORMAT, m->field, "must be an array of 2 numbers [w, h]");
    double v[2] = {0.0, 0.0};
    int i = 0;
    for (const cJSON *e = m->item->child; e; e = e->next, i++) {
        char sub[208];
        snprintf(sub, sizeof sub, "%s[%d]", m->field, i);
        iir_status st = get_number(c, e, sub, 0.0, MAX_COORD, &v[i]);
        if (st != IIR_OK) return st;
        if (!(v[i] > 0.0)) return field_error(c, IIR_ERR_INVALID, sub, "must be > 0, got %g", v[i]);
    }
    *size = iir_v2((float)v[0], (float)v[1]);
    return IIR_OK;
}

/* Corner k of a shape's triangle: [x, y], each in [-1/2, 1/2]. */
static iir_status parse_shape_corner(const ctx *c, const cJSON *item, const char *field,
                                     iir_vec2 *out)
{
    if (!cJSON_IsArray(item) || cJSON_GetArraySize(item) != 2)
        return field_error(c, IIR_ERR_FORMAT, field, "must be an array of 2 numbers [x, y]");
    double v[2] = {0.0, 0.0};
    int i = 0;
    for (const cJSON *e = item->child; e; e = e->next, i++) {
        char sub[256];
        snprintf(sub, sizeof sub, "%s[%d]", field, i);
        iir_status st = get_number(c, e, sub, -0.5, 0.5, &v[i]);
        if (st != IIR_OK) return st;
    }
    *out = iir_v2((float)v[0], (float)v[1]);
    return IIR_OK;
}

/* shape: [[[x, y], [x, y], [x, y]], ...], 1 to IIR_AREA_MAX_TRIANGLES triangles in light-local
 * coordinates, none degenerate, none overlapping (iir_area_shape_check). */
static iir_status parse_shape(const ctx *c, const member *m, iir_area_shape *shape)
{
    int n = cJSON_IsArray(m->item) ? cJSON_GetArraySize(m->item) : -1;
    if (n < 0)
        return field_error(c, IIR_ERR_FORMAT, m->field,
                           "must be an array of 1 to %d triangles [[x, y], [x, y], [x, y]]",
                           IIR_AREA_MAX_TRIANGLES);
    if (n < 1 || n > IIR_AREA_MAX_TRIANGLES)
        return field_error(c, IIR_ERR_INVALID, m->field,
                           "has %d triangles: a shape has 1 to %d triangles", n,
                           IIR_AREA_MAX_TRIANGLES);
    memset(shape, 0, sizeof *shape);
    int t = 0;
    for (const cJSON *tri = m->item->child; tri; tri = tri->next, t++) {
        char field[208];
        snprintf(field, sizeof field, "%s[%d]", m->field, t);
        if (!cJSON_IsArray(tri) || cJSON_GetArraySize(tri) != 3)
            return field_error(c, IIR_ERR_FORMAT, field,
                               "must be a triangle: an array of 3 corners [x, y]");
        int k = 0;
        for (const cJSON *p = tri->child; p; p = p->next, k++) {
            char sub[224];
            snprintf(sub, sizeof sub, "%s[%d]", field, k);
            iir_status st = parse_shape_corner(c, p, sub, &shape->tri[t][k]);
            if (st != IIR_OK) return st;
        }
        shape->num_triangles++;
    }
    const char *why = iir_area_shape_check(shape);
    return why ? field_error(c, IIR_ERR_INVALID, m->field, "%s", why) : IIR_OK;
}

/* An area light given by its pose: position, normal (target or direction), up, size and
 * optionally its shape. */
static iir_status parse_area_pose(const ctx *c, const cJSON *obj, const char *where, iir_light *l)
{
    member pos = get_member(obj, where, "position"), up = get_member(obj, where, "up");
    member size = get_member(obj, where, "size"), shape = get_member(obj, where, "shape");
    iir_status st = required(c, &pos, " for an area light (its centre)");
    if (st == IIR_OK) st = get_position(c, pos.item, pos.field, &l->position);
    if (st == IIR_OK) st = parse_axis(c, obj, where, l);
    if (st == IIR_OK && up.item) st = get_direction(c, up.item, up.field, &l->up);
    if (st == IIR_OK) st = required(c, &size, " for an area light ([width, height])");
    if (st == IIR_OK) st = parse_size(c, &size, &l->size);
    if (st == IIR_OK && shape.item) st = parse_shape(c, &shape, &l->shape);
    return st;
}

/* An area light's fields: its pose, or a material whose triangles give it (then no pose: it is
 * filled in by iir_sidecar_apply). No cone. */
static iir_status parse_area(const ctx *c, const cJSON *obj, const char *where, iir_light *l,
                             material_name *material)
{
    static const char *const cone[] = {"cone_angle", "smooth", "inner_angle", NULL};
    static const char *const pose[] = {"position", "target", "direction", "up",
                                       "size",     "shape",  NULL};
    member mat = get_member(obj, where, "material");
    l->up = iir_v3(0.f, 1.f, 0.f);
    iir_status st = forbid(c, obj, where, cone, "an area light has no cone");
    if (st != IIR_OK) return st;
    if (!mat.item) return parse_area_pose(c, obj, where, l);
    st = forbid(c, obj, where, pose,
                "an area light taken from a material gets its pose, size and shape from the "
                "material's triangles");
    if (st == IIR_OK) st = get_string(c, mat.item, mat.field, *material, sizeof *material);
    return st;
}

static iir_status parse_light_type(const ctx *c, const member *m, iir_light *l)
{
    static const char *const names[] = {"spot", "point", "gltf_spot", "sun", "area"};
    static const iir_light_type types[] = {IIR_LIGHT_SPOT, IIR_LIGHT_POINT, IIR_LIGHT_SPOT,
                                           IIR_LIGHT_SUN, IIR_LIGHT_AREA};
    char type[16];
    iir_status st = required(c, m, " (\"spot\", \"gltf_spot\", \"point\", \"sun\" or \"area\")");
    if (st == IIR_OK) st = get_string(c, m->item, m->field, type, sizeof type);
    if (st != IIR_OK) return st;
    int k = 0;
    while (k < 5 && strcmp(type, names[k]) != 0) k++;
    if (k == 5)
        return field_error(c, IIR_ERR_INVALID, m->field,
                           "must be \"spot\", \"gltf_spot\", \"point\", \"sun\" or \"area\", "
                           "got \"%s\"",
                           type);
    l->type = types[k];
    l->profile = k == 2 ? IIR_SPOT_GLTF : IIR_SPOT_COSINE;
    return IIR_OK;
}

/* The fields of one kind: a sun's or an area light's, or a position and then a spot's or none
 * (point). */
static iir_status parse_kind(const ctx *c, const cJSON *obj, const char *where, iir_light *l,
                             material_name *material)
{
    if (l->type == IIR_LIGHT_SUN) return parse_sun(c, obj, where, l);
    if (l->type == IIR_LIGHT_AREA) return parse_area(c, obj, where, l, material);
    member pos = get_member(obj, where, "position");
    iir_status st = required(c, &pos, "");
    if (st == IIR_OK) st = get_position(c, pos.item, pos.field, &l->position);
    if (st == IIR_OK)
        st = l->type == IIR_LIGHT_SPOT ? parse_spot(c, obj, where, l) : point_has_no(c, obj, where);
    return st;
}

/* intensity: required, except on an area light taken from a material: its emission then, which
 * iir_sidecar_apply fills in where this leaves -1. */
static iir_status parse_intensity(const ctx *c, const member *in, iir_light *l, bool from_material)
{
    l->intensity = iir_v3s(-1.f);
    if (!in->item && from_material) return IIR_OK;
    iir_status st = required(c, in, "");
    if (st == IIR_OK) st = get_color(c, in->item, in->field, MAX_INTENSITY, &l->intensity);
    return st;
}

static iir_status parse_light(const ctx *c, const cJSON *obj, int index, iir_light *l,
                              material_name *material)
{
    static const char *const fields[] = {"type",        "name",         "position",   "target",
                                         "direction",   "up",           "cone_angle", "smooth",
                                         "inner_angle", "size",         "shape",      "material",
                                         "intensity",   "emission_map", NULL};
    char where[32];
    snprintf(where, sizeof where, "lights[%d]", index);
    if (!cJSON_IsObject(obj)) return field_error(c, IIR_ERR_FORMAT, where, "must be an object");
    member type = get_member(obj, where, "type"), name = get_member(obj, where, "name");
    member in = get_member(obj, where, "intensity");
    memset(l, 0, sizeof *l);
    snprintf(l->name, sizeof l->name, "light%d", index);
    iir_status st = check_fields(c, obj, where, fields);
    if (st == IIR_OK) st = parse_light_type(c, &type, l);
    if (st == IIR_OK && name.item)
        st = get_string(c, name.item, name.field, l->name, sizeof l->name);
    if (st == IIR_OK) st = parse_kind(c, obj, where, l, material);
    bool from_material = (*material)[0] != '\0';
    if (st == IIR_OK) st = parse_intensity(c, &in, l, from_material);
    iir_error e; /* a material's light is checked once it has its pose (apply_area_material) */
    if (st == IIR_OK && !from_material && iir_light_validate(l, &e) != IIR_OK)
        return field_error(c, e.status, where, "%s", e.msg);
    return st;
}

/* An area light's "emission_map": an image file (.png, .exr, .pfm) named relative to the
 * sidecar's folder, read now; light l points at it, sc owns it. */
static iir_status parse_emission_map(const ctx *c, const cJSON *obj, int index, iir_light *l,
                                     iir_sidecar *sc)
{
    char where[32], name[512], path[2048];
    snprintf(where, sizeof where, "lights[%d]", index);
    member m = get_member(obj, where, "emission_map");
    if (!m.item) return IIR_OK;
    iir_status st = get_string(c, m.item, m.field, name, sizeof name);
    if (st != IIR_OK) return st;
    const char *slash = strrchr(c->path, '/');
    int dir_len = slash ? (int)(slash - c->path) : 1;
    if (name[0] == '/')
        snprintf(path, sizeof path, "%s", name);
    else
        snprintf(path, sizeof path, "%.*s/%s", dir_len, slash ? c->path : ".", name);
    iir_emission_map **grown = realloc(sc->maps, sizeof *grown * (sc->num_maps + 1));
    if (!grown) return iir_fail(c->err, IIR_ERR_NOMEM, "%s: out of memory", c->path);
    sc->maps = grown;
    iir_error e = {0};
    iir_emission_map *map = NULL;
    if (iir_emission_map_load(path, &map, &e) != IIR_OK)
        return field_error(c, e.status, m.field, "%s", e.msg);
    sc->maps[sc->num_maps++] = map;
    l->map = map;
    return IIR_OK;
}

static iir_status parse_lights(const ctx *c, const cJSON *arr, iir_sidecar *sc)
{
    if (!cJSON_IsArray(arr)) return field_error(c, IIR_ERR_FORMAT, "lights", "must be an array");
    int n = cJSON_GetArraySize(arr);
    sc->has_lights = true;
    if (n == 0) return IIR_OK;
    sc->lights = calloc((size_t)n, sizeof *sc->lights + sizeof(material_name));
    if (!sc->lights) return iir_fail(c->err, IIR_ERR_NOMEM, "%s: out of memory", c->path);
    material_name *materials = (material_name *)(void *)(sc->lights + n);
    int i = 0;
    for (const cJSON *e = arr->child; e; e = e->next, i++) {
        iir_status st = parse_light(c, e, i, &sc->lights[i], &materials[i]);
        if (st == IIR_OK) st = parse_emission_map(c, e, i, &sc->lights[i], sc);
        if (st != IIR_OK) return st;
        sc->num_lights++;
    }
    return IIR_OK;
}

/* "kind": "diffuse", "mirror" or "glass". */
static iir_status parse_material_kind(const ctx *c, const member *k, iir_sidecar_material *m)
{
    static const iir_material_kind kinds[] = {IIR_MATERIAL_DIFFUSE, IIR_MATERIAL_MIRROR,
                                              IIR_MATERIAL_GLASS};
    if (!cJSON_IsString(k->item))
        return field_error(c, IIR_ERR_FORMAT, k->field,
                           "must be \"diffuse\", \"mirror\" or \"glass\"");
    for (size_t i = 0; i < sizeof kinds / sizeof kinds[0]; i++)
        if (strcmp(k->item->valuestring, iir_material_kind_name(kinds[i])) == 0) {
            m->kind = kinds[i];
            return IIR_OK;
        }
    return field_error(c, IIR_ERR_INVALID, k->field,
                       "'%s' is not a material kind (known: diffuse, mirror, glass)",
                       k->item->valuestring);
}

/* The specular fields: "kind", "specular" (mirror, glass) and "ior" (glass, in [1, 3]). */
static iir_status parse_material_specular(const ctx *c, const cJSON *obj, const char *where,
                                          iir_sidecar_material *m)
{
    member kind = get_member(obj, where, "kind"), spec = get_member(obj, where, "specular"),
           ior = get_member(obj, where, "ior");
    m->has_kind = kind.item != NULL;
    m->has_specular = spec.item != NULL;
    m->has_ior = ior.item != NULL;
    iir_status st = kind.item ? parse_material_kind(c, &kind, m) : IIR_OK;
    if (st == IIR_OK && spec.item) st = get_color(c, spec.item, spec.field, 1.0, &m->specular);
    double v = 0.0;
    if (st == IIR_OK && ior.item &&
        (st = get_number(c, ior.item, ior.field, 1.0, 3.0, &v)) == IIR_OK)
        m->ior = (float)v;
    if (st == IIR_OK && m->has_kind && m->kind == IIR_MATERIAL_DIFFUSE && (spec.item || ior.item))
        return field_error(c, IIR_ERR_INVALID, spec.item ? spec.field : ior.field,
                           "a diffuse material has no specular colour or ior");
    if (st == IIR_OK && m->has_kind && m->kind == IIR_MATERIAL_MIRROR && ior.item)
        return field_error(c, IIR_ERR_INVALID, ior.field, "a mirror has no ior (only glass)");
    return st;
}

static iir_status parse_material(const ctx *c, const cJSON *obj, iir_sidecar_material *m)
{
    static const char *const fields[] = {"albedo", "emission", "kind", "specular", "ior", NULL};
    char where[96];
    snprintf(where, sizeof where, "materials.%s", obj->string);
    if (strlen(obj->string) >= sizeof m->name)
        return field_error(c, IIR_ERR_INVALID, where, "material names have at most %zu characters",
                           sizeof m->name - 1);
    if (!cJSON_IsObject(obj)) return field_error(c, IIR_ERR_FORMAT, where, "must be an object");
    member albedo = get_member(obj, where, "albedo"), emission = get_member(obj, where, "emission");
    iir_scene_strcpy(m->name, sizeof m->name, obj->string);
    m->has_albedo = albedo.item != NULL;
    m->has_emission = emission.item != NULL;
    iir_status st = check_fields(c, obj, where, fields);
    if (st == IIR_OK && albedo.item) st = get_color(c, albedo.item, albedo.field, 1.0, &m->albedo);
    if (st == IIR_OK && emission.item)
        st = get_color(c, emission.item, emission.field, MAX_INTENSITY, &m->emission);
    if (st == IIR_OK) st = parse_material_specular(c, obj, where, m);
    return st;
}

static iir_status parse_materials(const ctx *c, const cJSON *obj, iir_sidecar *sc)
{
    if (!cJSON_IsObject(obj))
        return field_error(c, IIR_ERR_FORMAT, "materials", "must be an object {NAME: {...}}");
    int n = cJSON_GetArraySize(obj);
    if (n == 0) return IIR_OK;
    sc->materials = calloc((size_t)n, sizeof *sc->materials);
    if (!sc->materials) return iir_fail(c->err, IIR_ERR_NOMEM, "%s: out of memory", c->path);
    for (const cJSON *e = obj->child; e; e = e->next) {
        for (const cJSON *prev = obj->child; prev != e; prev = prev->next)
            if (strcmp(prev->string, e->string) == 0)
                return field_error(c, IIR_ERR_FORMAT, "materials", "'%s' is given twice",
                                   e->string);
        iir_status st = parse_material(c, e, &sc->materials[sc->num_materials]);
        if (st != IIR_OK) return st;
        sc->num_materials++;
    }
    return IIR_OK;
}

static iir_status parse_paths(const ctx *c, const cJSON *obj, iir_sidecar *sc)
{
    if (!cJSON_IsObject(obj)) return field_error(c, IIR_ERR_FORMAT, "paths", "must be an object");
    char *text = cJSON_PrintUnformatted(obj);
    sc->paths_json = text ? strdup(text) : NULL;
    cJSON_free(text);
    if (!sc->paths_json) return iir_fail(c->err, IIR_ERR_NOMEM, "%s: out of memory", c->path);
    return IIR_OK;
}

static iir_status parse_root(const ctx *c, const cJSON *root, iir_sidecar *sc)
{
    static const char *const fields[] = {"file",   "base",      "unit_scale", "camera",
                                         "lights", "materials", "paths",      NULL};
    if (!cJSON_IsObject(root))
        return iir_fail(c->err, IIR_ERR_FORMAT, "%s: the top level must be a JSON object", c->path);
    iir_status st = check_fields(c, root, "", fields);
    const cJSON *it;
    if (st == IIR_OK && (it = cJSON_GetObjectItemCaseSensitive(root, "file")))
        st = parse_file(c, it, sc);
    if (st == IIR_OK && (it = cJSON_GetObjectItemCaseSensitive(root, "base")))
        st = parse_base(c, it, sc);
    if (st == IIR_OK && (it = cJSON_GetObjectItemCaseSensitive(root, "unit_scale")))
        st = parse_unit_scale(c, it, sc);
    if (st == IIR_OK && (it = cJSON_GetObjectItemCaseSensitive(root, "camera")))
        st = parse_camera(c, it, sc);
    if (st == IIR_OK && (it = cJSON_GetObjectItemCaseSensitive(root, "lights")))
        st = parse_lights(c, it, sc);
    if (st == IIR_OK && (it = cJSON_GetObjectItemCaseSensitive(root, "materials")))
        st = parse_materials(c, it, sc);
    if (st == IIR_OK && (it = cJSON_GetObjectItemCaseSensitive(root, "paths")))
        st = parse_paths(c, it, sc);
    return st;
}

/* ======================== reading ======================== */

/* Reads the whole file into a NUL-terminated buffer the caller frees. */
static iir_status read_text(const char *path, char **out, size_t *len, iir_error *err)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return iir_fail(err, IIR_ERR_IO, "cannot read sidecar %s: %s", path, strerror(errno));
    char *buf = malloc(MAX_SIDECAR_BYTES + 1);
    size_t n = buf ? fread(buf, 1, MAX_SIDECAR_BYTES + 1, f) : 0;
    bool failed = buf && ferror(f);
    fclose(f);
    if (!buf) return iir_fail(err, IIR_ERR_NOMEM, "%s: out of memory", path);
    if (failed || n > MAX_SIDECAR_BYTES) {
        free(buf);
        return iir_fail(err, IIR_ERR_IO, "cannot read sidecar %s: %s", path,
                        failed ? "read error" : "larger than 16 MiB");
    }
    buf[n] = '\0';
    *out = buf;
    *len = n;
    return IIR_OK;
}

/* Line and column (from 1) of offset `at` in text. */
static void line_column(const char *text, size_t at, int *line, int *col)
{
    *line = 1;
    *col = 1;
    for (size_t i = 0; i < at && text[i]; i++) {
        if (text[i] == '\n') {
            (*line)++;
            *col = 1;
        } else {
            (*col)++;
        }
    }
}

static iir_status parse_json(const char *path, const char *text, size_t len, cJSON **out,
                             iir_error *err)
{
    const char *end = NULL;
    *out = cJSON_ParseWithLengthOpts(text, len, &end, false);
    /* only white space may follow the object: trailing text is a cut-and-paste slip, not ignored */
    size_t rest = *out && end ? (size_t)(end - text) : 0;
    while (*out && rest < len && strchr(" \t\r\n", text[rest]) && text[rest]) rest++;
    if (*out && rest < len) {
        cJSON_Delete(*out);
        *out = NULL;
    }
    if (*out) return IIR_OK;
    int line, col;
    size_t at = end && end >= text && end <= text + len ? (size_t)(end - text) : 0;
    line_column(text, at, &line, &col);
    return iir_fail(err, IIR_ERR_FORMAT, "%s: malformed JSON at line %d, column %d", path, line,
                    col);
}

/* ======================== the sidecar's life ======================== */

iir_status iir_sidecar_parse_text(const char *path, const char *text, size_t len, iir_sidecar *sc,
                                  iir_error *err)
{
    memset(sc, 0, sizeof *sc);
    sc->unit_scale = 1.f;
    iir_scene_strcpy(sc->path, sizeof sc->path, path);
    cJSON *root;
    iir_status st = parse_json(path, text, len, &root, err);
    if (st == IIR_OK) {
        ctx c = {path, err, {{0}, NULL, NULL, IIR_OK}};
        iir_json_file_init(&c.jf, path, err);
        st = parse_root(&c, root, sc);
        cJSON_Delete(root);
    }
    if (st != IIR_OK) iir_sidecar_free(sc);
    return st;
}

iir_status iir_sidecar_parse(const char *path, iir_sidecar *sc, iir_error *err)
{
    memset(sc, 0, sizeof *sc);
    char *text = NULL;
    size_t len = 0;
    iir_status st = read_text(path, &text, &len, err);
    if (st != IIR_OK) return st;
    st = iir_sidecar_parse_text(path, text, len, sc, err);
    free(text);
    return st;
}

void iir_sidecar_free(iir_sidecar *sc)
{
    free(sc->lights);
    free(sc->materials);
    free(sc->paths_json);
    for (uint32_t i = 0; i < sc->num_maps; i++) iir_emission_map_free(sc->maps[i]);
    free(sc->maps);
    sc->maps = NULL;
    sc->num_maps = 0;
    sc->lights = NULL;
    sc->materials = NULL;
    sc->paths_json = NULL;
    sc->num_lights = sc->num_materials = 0;
}

/* Lists the builder's material names into buf, for "no such material" errors. */
static void material_names(const iir_scene_builder *b, char *buf, size_t n)
{
    buf[0] = '\0';
    for (uint32_t i = 0; i < b->num_materials; i++) {
        size_t used = strlen(buf);
        if (used + 8 >= n) {
            snprintf(buf + used, n - used, "...");
            return;
        }
        snprintf(buf + used, n - used, "%s%s", i ? ", " : "", b->materials[i].name);
    }
}

/* Material m's kind as override o says: a new kind starts from its defaults (diffuse: albedo 0.8
 * unless given; mirror and glass: no albedo, specular 1, glass ior 1.5), then o's fields. */
static void apply_kind(const iir_sidecar_material *o, iir_material *m)
{
    if (o->has_kind && o->kind != m->kind) {
        if (o->kind == IIR_MATERIAL_DIFFUSE) m->albedo = iir_v3s(0.8f);
        m->kind = o->kind;
        m->specular = iir_v3s(o->kind == IIR_MATERIAL_DIFFUSE ? 0.f : 1.f);
        m->ior = o->kind == IIR_MATERIAL_GLASS ? 1.5f : 0.f;
    }
    if (m->kind != IIR_MATERIAL_DIFFUSE && !o->has_albedo) m->albedo = iir_v3s(0.f);
    if (o->has_specular) m->specular = o->specular;
    if (o->has_ior) m->ior = o->ior;
}

/* Applies override o to material m; IIR_ERR_INVALID when the result is not a usable material. */
static iir_status apply_material(const iir_sidecar *sc, const iir_sidecar_material *o,
                                 iir_material *m, iir_error *err)
{
    if (o->has_albedo) m->albedo = o->albedo;
    if (o->has_emission) m->emission = o->emission;
    apply_kind(o, m);
    if (m->kind == IIR_MATERIAL_DIFFUSE && (o->has_specular || o->has_ior))
        return iir_fail(err, IIR_ERR_INVALID,
                        "%s: materials.%s: %s is only for a mirror or glass (this material is "
                        "diffuse: give \"kind\")",
                        sc->path, o->name, o->has_ior ? "ior" : "specular");
    char why[160];
    if (iir_material_check(m, why, sizeof why))
        return iir_fail(err, IIR_ERR_INVALID, "%s: materials.%s: %s", sc->path, o->name, why);
    return IIR_OK;
}

static iir_status apply_materials(const iir_sidecar *sc, iir_scene_builder *b, iir_error *err)
{
    for (uint32_t k = 0; k < sc->num_materials; k++) {
        const iir_sidecar_material *o = &sc->materials[k];
        bool found = false;
        for (uint32_t i = 0; i < b->num_materials; i++) {
            if (strcmp(b->materials[i].name, o->name) != 0) continue;
            iir_status st = apply_material(sc, o, &b->materials[i], err);
            if (st != IIR_OK) return st;
            found = true;
        }
        if (!found) {
            char names[256];
            material_names(b, names, sizeof names);
            return iir_fail(err, IIR_ERR_INVALID,
                            "%s: materials.%s: the mesh has no material of that name (it has: %s)",
                            sc->path, o->name, names);
        }
    }
    return IIR_OK;
}

static iir_status apply_camera(const iir_sidecar *sc, iir_scene_builder *b, iir_error *err)
{
    iir_camera cam = sc->camera;
    if (cam.fov_y == 0.f) cam.fov_y = b->has_camera ? b->camera.fov_y : 45.f;
    float aspect = sc->aspect > 0.f ? sc->aspect : b->has_camera ? b->aspect : 0.f;
    iir_error e;
    if (iir_camera_validate(&cam, &e) != IIR_OK)
        return iir_fail(err, e.status, "%s: camera: %s", sc->path, e.msg);
    iir_builder_set_camera(b, &cam);
    iir_builder_set_camera_origin(b, IIR_CAMERA_SIDECAR, aspect);
    return IIR_OK;
}

/* ======================== area lights from materials ======================== */

/* Light i of the sidecar, taken from its material: the pose, size and shape its triangles give
 * (iir_builder_fit_area_light), the material's emission unless the light gives an intensity; the
 * triangles leave the mesh and the material stops emitting (nothing uses it any more). */
static iir_status apply_area_material(iir_sidecar *sc, iir_scene_builder *b, uint32_t i,
                                      iir_error *err)
{
    const char *name = *light_material(sc, i);
    iir_light *l = &sc->lights[i];
    int64_t m = iir_builder_find_material(b, name);
    if (m < 0) {
        char names[256];
        material_names(b, names, sizeof names);
        return iir_fail(err, IIR_ERR_INVALID,
                        "%s: lights[%u].material: the mesh has no material '%s' (it has: %s)",
                        sc->path, i, name, names);
    }
    iir_area_fit fit;
    iir_status st = iir_builder_fit_area_light(b, name, l, &fit);
    if (st != IIR_OK)
        return iir_fail(err, st,
                        "%s: lights[%u].material: material '%s' %s (an area light taken from a "
                        "material needs one-sided coplanar triangles: at most %d, or any number "
                        "forming one rectangle; %u triangles, area %g of a %g x %g bounding "
                        "rectangle)",
                        sc->path, i, name, fit.why, IIR_AREA_MAX_TRIANGLES, fit.triangles, fit.area,
                        fit.w, fit.h);
    if (l->intensity.x < 0.f) l->intensity = b->materials[m].emission; /* none given */
    iir_builder_take_emitter(b, name);
    return IIR_OK;
}

iir_status iir_sidecar_apply(iir_sidecar *sc, iir_scene_builder *b, iir_error *err)
{
    if (sc->unit_scale != 1.f) iir_builder_scale(b, sc->unit_scale);
    iir_status st = apply_materials(sc, b, err);
    if (st == IIR_OK && sc->has_camera) st = apply_camera(sc, b, err);
    if (st == IIR_OK && sc->has_lights) {
        iir_builder_clear_lights(b);
        for (uint32_t i = 0; st == IIR_OK && i < sc->num_lights; i++) {
            if ((*light_material(sc, i))[0]) st = apply_area_material(sc, b, i, err);
            if (st == IIR_OK) st = iir_builder_add_light(b, &sc->lights[i], err);
        }
    }
    for (uint32_t i = 0; i < sc->num_maps; i++) { /* the builder owns them now, even on error */
        iir_status s = iir_builder_add_map(b, sc->maps[i], err);
        if (st == IIR_OK) st = s;
    }
    sc->num_maps = 0;
    if (st == IIR_OK && sc->paths_json) {
        free(b->paths_json);
        b->paths_json = sc->paths_json;
        sc->paths_json = NULL;
    }
    return st;
}

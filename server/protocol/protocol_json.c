/* protocol_json.c -- the server's replies (docs/protocol.md, "Server -> client") as JSON text:
 * welcome, state, stats, domain, pick, snapshot, error; the binary frame header; compact numbers.
 * Not the `record` reply's script (recording.c).
 *
 * Numbers: floats are printed with the fewest digits that read back as the same float (0.1, not
 * 0.10000000149011612), times in ms rounded to microseconds, angles to 1e-4 degrees, and 64-bit
 * counters with all their digits. Every builder returns NULL only when memory runs out. */
#include "protocol_internal.h"

#include <assert.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef IIR_VERSION
#define IIR_VERSION "0"
#endif

/* ======================== numbers ======================== */

double iird_compact_float(float f)
{
    char buf[32];
    if (!isfinite(f)) return f;
    for (int digits = 6; digits <= 9; digits++) {
        snprintf(buf, sizeof buf, "%.*g", digits, (double)f);
        double d = strtod(buf, NULL);
        if ((float)d == f) return d;
    }
    return f;
}

/* v rounded to a multiple of 1/scale (0 when not finite: JSON has no NaN). */
static double rounded(double v, double scale)
{
    return isfinite(v) ? round(v * scale) / scale : 0.0;
}

/* Adds item to an object (name) or an array (name == NULL). */
static bool add_item(cJSON *parent, const char *name, cJSON *item)
{
    if (!item) return false;
    if (name ? cJSON_AddItemToObject(parent, name, item) : cJSON_AddItemToArray(parent, item))
        return true;
    cJSON_Delete(item);
    return false;
}

bool iird_json_add_num(cJSON *obj, const char *name, double v)
{
    return add_item(obj, name, cJSON_CreateNumber(isfinite(v) ? v : 0.0));
}

bool iird_json_add_float(cJSON *obj, const char *name, float v)
{
    return iird_json_add_num(obj, name, iird_compact_float(v));
}

bool iird_json_add_u64(cJSON *obj, const char *name, uint64_t v)
{
    char buf[24];
    if (v <= (uint64_t)INT_MAX) return iird_json_add_num(obj, name, (double)v);
    snprintf(buf, sizeof buf, "%llu", (unsigned long long)v);
    return add_item(obj, name, cJSON_CreateRaw(buf));
}

bool iird_json_add_vec3(cJSON *obj, const char *name, iir_vec3 v)
{
    cJSON *a = cJSON_CreateArray();
    if (!add_item(obj, name, a)) return false;
    return iird_json_add_float(a, NULL, v.x) && iird_json_add_float(a, NULL, v.y) &&
           iird_json_add_float(a, NULL, v.z);
}

bool iird_json_add_shape(cJSON *obj, const iir_area_shape *shape)
{
    cJSON *tris = cJSON_CreateArray();
    if (!add_item(obj, "shape", tris)) return false;
    for (uint32_t t = 0; t < shape->num_triangles; t++) {
        cJSON *tri = cJSON_CreateArray();
        if (!add_item(tris, NULL, tri)) return false;
        for (int k = 0; k < 3; k++) {
            cJSON *p = cJSON_CreateArray();
            if (!add_item(tri, NULL, p) || !iird_json_add_float(p, NULL, shape->tri[t][k].x) ||
                !iird_json_add_float(p, NULL, shape->tri[t][k].y))
                return false;
        }
    }
    return true;
}

static bool add_str(cJSON *obj, const char *name, const char *s)
{
    return cJSON_AddStringToObject(obj, name, s ? s : "") != NULL;
}

static bool add_bool(cJSON *obj, const char *name, bool b)
{
    return cJSON_AddBoolToObject(obj, name, b) != NULL;
}

static bool add_seq(cJSON *obj, int64_t seq)
{
    return seq < 0 || iird_json_add_num(obj, "seq", (double)seq);
}

char *iird_json_finish(cJSON *obj)
{
    char *text = obj ? cJSON_PrintUnformatted(obj) : NULL;
    cJSON_Delete(obj);
    return text;
}

/* {"type": type, "seq": seq} (seq only when the message had one). */
static cJSON *reply(const char *type, int64_t seq)
{
    cJSON *o = cJSON_CreateObject();
    if (o && (!add_str(o, "type", type) || !add_seq(o, seq))) {
        cJSON_Delete(o);
        return NULL;
    }
    return o;
}

/* Deletes o and returns NULL unless ok. */
static cJSON *keep_if(cJSON *o, bool ok)
{
    if (ok) return o;
    cJSON_Delete(o);
    return NULL;
}

/* ======================== error ======================== */

char *iird_json_error(const iird_proto_error *e)
{
    cJSON *o = reply("error", e->seq);
    bool ok =
        o && add_str(o, "code", iird_err_name(e->code)) &&
        (e->field[0] ? add_str(o, "field", e->field) : cJSON_AddNullToObject(o, "field") != NULL) &&
        add_str(o, "message", e->message);
    return iird_json_finish(keep_if(o, ok));
}

/* ======================== state and welcome ======================== */

static double degrees(float radians)
{
    return rounded((double)radians * (180.0 / 3.14159265358979323846), 1e4);
}

static bool add_vec2(cJSON *obj, const char *name, iir_vec2 v)
{
    cJSON *a = cJSON_CreateArray();
    return add_item(obj, name, a) && iird_json_add_float(a, NULL, v.x) &&
           iird_json_add_float(a, NULL, v.y);
}

/* The fields only some kinds have: a spot's cone, a glTF spot's inner cone, an area light's up
 * hint (its frame: r = up x direction, u = direction x r), size and, when it is not the whole
 * rectangle, shape (light-local triangles, for drawing its outline). */
static bool add_kind_fields(cJSON *o, const iir_light *L)
{
    bool spot = L->type == IIR_LIGHT_SPOT, area = L->type == IIR_LIGHT_AREA;
    return (!spot || iird_json_add_num(o, "cone_angle", degrees(L->cone_angle))) &&
           (!spot || L->profile != IIR_SPOT_GLTF ||
            iird_json_add_num(o, "inner_angle", degrees(L->inner_angle))) &&
           (!area || iird_json_add_vec3(o, "up", L->up)) &&
           (!area || add_vec2(o, "size", L->size)) &&
           (!area || !L->shape.num_triangles || iird_json_add_shape(o, &L->shape));
}

/* One light: name, kind, on, its pose (a sun's position is the centre of its disk over the scene)
 * and the fields of its kind, intensity (kept while it is off). */
static cJSON *light_json(const iir_light *L, bool on)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o && add_str(o, "name", L->name) && add_str(o, "kind", iir_light_kind(L)) &&
              add_bool(o, "on", on) && iird_json_add_vec3(o, "position", L->position) &&
              iird_json_add_vec3(o, "direction", L->direction) && add_kind_fields(o, L) &&
              iird_json_add_vec3(o, "intensity", L->intensity);
    return keep_if(o, ok);
}

/* Every light of the session, in the scene's order (the view's `light` alone without a list). */
static cJSON *lights_json(const iird_state_view *s)
{
    cJSON *a = cJSON_CreateArray();
    bool ok = a != NULL;
    uint32_t n = s->lights ? s->num_lights : 1;
    for (uint32_t i = 0; ok && i < n; i++) {
        const iir_light *L = s->lights ? &s->lights[i] : s->light;
        ok = add_item(a, NULL, light_json(L, !s->lights || !s->on || s->on[i]));
    }
    return keep_if(a, ok);
}

/* Whether the moved light is on (it is one of s->lights, or the view has no list). */
static bool moved_on(const iird_state_view *s)
{
    for (uint32_t i = 0; s->lights && s->on && i < s->num_lights; i++)
        if (&s->lights[i] == s->light) return s->on[i];
    return true;
}

static cJSON *camera_json(const iir_camera *C)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o && iird_json_add_vec3(o, "position", C->position) &&
              iird_json_add_vec3(o, "target", C->target) && iird_json_add_vec3(o, "up", C->up) &&
              iird_json_add_float(o, "fov", C->fov_y);
    return keep_if(o, ok);
}

/* method, the stream settings, then the method's parameters as it uses them. */
static cJSON *params_json(const iird_settings *s)
{
    cJSON *o = iird_json_method_params(s->method, &s->params);
    bool ok = o && cJSON_AddItemToObject(o, "method", cJSON_CreateString(s->method));
    for (int i = 0; ok && i < iird_stream_table.count; i++) {
        const iir_param *row = &iird_stream_table.rows[i];
        ok = add_item(o, row->name, iird_json_param_value(row, iir_param_read(row, s)));
    }
    return keep_if(o, ok);
}

/* What the method does not render of the scene (iir_method_dropped), and at its parameters
 * (iir_method_dropped_by_params: pt's glass at too few bounces), for the client's notes, each with
 * its severity: "warning" for what is left out, "note" for what was made of the scene (an emissive
 * material that became the movable area light), which is rendered. */
static cJSON *notes_json(const iird_state_view *s)
{
    cJSON *a = cJSON_CreateArray();
    if (!a || !s->scene_data) return a;
    enum { MAX_NOTES = 32 };
    iir_dropped d[MAX_NOTES];
    const iir_scene *sc = s->scene_data;
    const iir_light *lights = s->lights ? s->lights : s->light;
    const char *method = s->settings->method;
    uint32_t n =
        iir_method_dropped(method, sc, lights, s->lights ? s->num_lights : 1, d, MAX_NOTES);
    if (n < MAX_NOTES)
        n += iir_method_dropped_by_params(method, sc, &s->settings->params, d + n, MAX_NOTES - n);
    bool ok = true;
    for (uint32_t i = 0; ok && i < n && i < MAX_NOTES; i++) {
        cJSON *e = cJSON_CreateObject();
        ok = add_item(a, NULL, e) && add_str(e, "method", d[i].method) &&
             add_str(e, "kind", d[i].kind) && add_str(e, "name", d[i].name) &&
             add_str(e, "what", d[i].what) &&
             add_str(e, "severity", d[i].note ? "note" : "warning");
    }
    return keep_if(a, ok);
}

/* Adds scene, generation, light, lights, default_light, camera, params and notes to o. */
static bool add_state(cJSON *o, const iird_state_view *s)
{
    return add_str(o, "scene", s->scene) && iird_json_add_num(o, "generation", s->generation) &&
           add_item(o, "light", light_json(s->light, moved_on(s))) &&
           add_item(o, "lights", lights_json(s)) &&
           add_bool(o, "default_light", s->default_light) &&
           add_item(o, "camera", camera_json(s->camera)) &&
           add_item(o, "params", params_json(s->settings)) && add_item(o, "notes", notes_json(s));
}

char *iird_json_state(const iird_state_view *s, int64_t seq)
{
    cJSON *o = reply("state", seq);
    return iird_json_finish(keep_if(o, o && add_state(o, s)));
}

char *iird_json_state_superseded(const iird_state_view *s, int64_t seq)
{
    cJSON *o = reply("state", seq);
    return iird_json_finish(keep_if(o, o && add_bool(o, "superseded", true) && add_state(o, s)));
}

/* Method `name`'s phases (names, in order) and counters ({name, kind, help}) into m. */
static bool add_declared(cJSON *m, const char *name)
{
    const iir_phase *ph;
    const iir_counter *c;
    int np = iir_method_phases(name, &ph), nc = iir_method_counters(name, &c);
    cJSON *phases = cJSON_CreateArray(), *counters = cJSON_CreateArray();
    bool ok = add_item(m, "phases", phases) && add_item(m, "counters", counters);
    for (int i = 0; ok && i < np; i++)
        ok = add_item(phases, NULL, cJSON_CreateString(iir_phase_name(ph[i])));
    for (int i = 0; ok && i < nc; i++) {
        cJSON *o = cJSON_CreateObject();
        ok = add_item(counters, NULL, o) && add_str(o, "name", c[i].name) &&
             add_str(o, "kind", c[i].kind == IIR_COUNTER_SHARE ? "share" : "events") &&
             add_str(o, "help", c[i].help);
    }
    return ok;
}

/* Per method its name, summary, parameters (each of its tables' rows, in order), phases and
 * counters. */
static cJSON *methods_json(void)
{
    cJSON *a = cJSON_CreateArray();
    bool ok = a != NULL;
    for (const char *const *n = iir_method_names(); ok && *n; n++) {
        cJSON *m = cJSON_CreateObject(), *params = NULL;
        ok = add_item(a, NULL, m) && add_str(m, "name", *n) &&
             add_str(m, "summary", iir_method_summary(*n)) && add_declared(m, *n) &&
             add_item(m, "params", (params = cJSON_CreateArray()));
        for (const iir_param_table *const *t = iir_method_tables(*n); ok && *t; t++) {
            cJSON *rows = iird_json_param_table(*t), *row;
            ok = rows != NULL;
            while (ok && (row = cJSON_DetachItemFromArray(rows, 0)))
                ok = add_item(params, NULL, row);
            cJSON_Delete(rows);
        }
    }
    return keep_if(a, ok);
}

static cJSON *limits_json(const iird_limits *lim)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o && iird_json_add_num(o, "max_width", lim->max_width) &&
              iird_json_add_num(o, "max_height", lim->max_height) &&
              iird_json_add_num(o, "max_message_bytes", IIRD_MAX_MESSAGE_BYTES) &&
              iird_json_add_num(o, "max_rate", 250) && add_bool(o, "allow_save", lim->allow_save);
    return keep_if(o, ok);
}

static cJSON *names_json(const char *const *scenes)
{
    cJSON *names = cJSON_CreateArray();
    bool ok = names != NULL;
    for (const char *const *n = scenes; ok && n && *n; n++)
        ok = add_item(names, NULL, cJSON_CreateString(*n));
    return keep_if(names, ok);
}

char *iird_json_scenes(const char *const *scenes, int64_t seq)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o && add_str(o, "type", "scenes") && add_seq(o, seq) &&
              add_item(o, "scenes", names_json(scenes));
    return iird_json_finish(keep_if(o, ok));
}

char *iird_json_welcome(const iird_state_view *s, uint32_t session, const char *const *scenes,
                        size_t scenes_more, const iird_limits *limits, int64_t seq)
{
    iird_limits lim = limits ? *limits : iird_limits_default();
    cJSON *o = cJSON_CreateObject(), *state = NULL;
    bool ok = o && add_str(o, "type", "welcome") &&
              iird_json_add_num(o, "protocol", IIRD_PROTOCOL_VERSION) &&
              add_str(o, "server", "iird " IIR_VERSION) &&
              iird_json_add_num(o, "session", session) && add_seq(o, seq) &&
              add_item(o, "scenes", names_json(scenes)) &&
              (!scenes_more || iird_json_add_num(o, "scenes_more", (double)scenes_more));
    ok = ok && add_item(o, "methods", methods_json()) &&
         add_item(o, "settings", iird_json_param_table(&iird_stream_table)) &&
         add_item(o, "limits", limits_json(&lim)) &&
         add_item(o, "state", (state = cJSON_CreateObject())) && add_state(state, s);
    return iird_json_finish(keep_if(o, ok));
}

/* ======================== stats ======================== */

cJSON *iird_json_phases(const char *method, const iir_frame_stats *st, double scale)
{
    const iir_phase *ph;
    int n = iir_method_phases(method, &ph);
    cJSON *o = cJSON_CreateObject();
    bool ok = o != NULL;
    for (int i = 0; ok && i < n; i++)
        ok = iird_json_add_num(o, iir_phase_name(ph[i]), rounded(st->phase_ms[ph[i]], scale));
    return keep_if(o, ok);
}

cJSON *iird_json_counters(const char *method, const iir_frame_stats *st)
{
    const iir_counter *c;
    int n = iir_method_counters(method, &c);
    cJSON *o = cJSON_CreateObject();
    bool ok = o != NULL;
    for (int i = 0; ok && i < n; i++)
        ok = c[i].kind == IIR_COUNTER_SHARE
                 ? iird_json_add_num(o, c[i].name, rounded(st->counter[i], 1e4))
                 : iird_json_add_u64(o, c[i].name, (uint64_t)st->counter[i]);
    return keep_if(o, ok);
}

cJSON *iird_json_vpl_counts(const iir_vpl_counts *v)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o && iird_json_add_num(o, "count", v->count) &&
              iird_json_add_num(o, "valid", v->valid) &&
              iird_json_add_num(o, "invalidated", v->invalidated) &&
              iird_json_add_num(o, "deleted", v->deleted) &&
              iird_json_add_num(o, "inserted", v->inserted) &&
              iird_json_add_num(o, "null", v->null_samples) &&
              iird_json_add_num(o, "regenerated", v->regenerated) &&
              iird_json_add_num(o, "shadowmaps", v->shadowmaps) &&
              iird_json_add_num(o, "descendants", v->descendants);
    return keep_if(o, ok);
}

cJSON *iird_json_rays(const iir_raystats *r)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o != NULL;
    for (int i = 0; ok && i < IIR_RAY_KIND_COUNT; i++)
        ok = iird_json_add_u64(o, iir_ray_kind_name((iir_ray_kind)i), r->n[i]);
    return keep_if(o, ok);
}

cJSON *iird_json_ctl(const iir_frame_stats *st)
{
    if (!st->controlled) return cJSON_CreateNull();
    const iir_ctl_report *c = &st->ctl;
    cJSON *o = cJSON_CreateObject();
    bool ok = o && iird_json_add_num(o, "target_ms", rounded(c->target_ms, 1e3)) &&
              iird_json_add_num(o, "mean_ms", rounded(c->mean_ms, 1e3)) &&
              iird_json_add_u64(o, "frames", c->frames) &&
              iird_json_add_num(o, "predicted_ms", rounded(c->predicted_ms, 1e3)) &&
              add_bool(o, "reachable", c->reachable) && add_bool(o, "busy", c->busy) &&
              iird_json_add_num(o, "vpls", c->setting.vpls) &&
              iird_json_add_num(o, "interleave", c->setting.interleave) &&
              iird_json_add_num(o, "sm_res", c->setting.sm_res) &&
              iird_json_add_num(o, "vpls_min", c->floor.vpls) &&
              iird_json_add_num(o, "sm_res_min", c->floor.sm_res) &&
              iird_json_add_num(o, "rung", c->rung) && iird_json_add_num(o, "rungs", c->rungs) &&
              iird_json_add_num(o, "moves", c->moves) && iird_json_add_num(o, "undone", c->undone);
    return keep_if(o, ok);
}

char *iird_json_stats(const iird_stats_view *v)
{
    iir_frame_stats zero;
    memset(&zero, 0, sizeof zero);
    const iir_frame_stats *st = v->stats ? v->stats : &zero;
    cJSON *o = cJSON_CreateObject();
    bool ok = o && add_str(o, "type", "stats") && iird_json_add_num(o, "frame", v->frame) &&
              add_seq(o, v->seq) && add_str(o, "method", v->method) &&
              iird_json_add_num(o, "pass", v->pass) && add_bool(o, "converged", v->converged) &&
              add_bool(o, "reencoded", v->reencoded) &&
              iird_json_add_num(o, "total_ms", rounded(st->total_ms, 1e3)) &&
              iird_json_add_num(o, "encode_ms", rounded(v->encode_ms, 1e3)) &&
              iird_json_add_num(o, "latency_ms", rounded(v->latency_ms, 1e3)) &&
              iird_json_add_num(o, "fps", rounded(v->fps, 1e2)) &&
              iird_json_add_u64(o, "bytes", v->bytes) &&
              add_item(o, "phases", iird_json_phases(v->method, st, 1e3)) &&
              add_item(o, "vpl", iird_json_vpl_counts(&st->vpl)) &&
              add_item(o, "rays", iird_json_rays(&st->rays)) &&
              iird_json_add_u64(o, "vpl_evals", st->vpl_evals) &&
              iird_json_add_u64(o, "vpl_reused", st->vpl_reused) &&
              add_item(o, "counters", iird_json_counters(v->method, st)) &&
              add_item(o, "ctl", iird_json_ctl(st)) &&
              iird_json_add_u64(o, "dropped", v->dropped) &&
              iird_json_add_u64(o, "memory_bytes", v->memory_bytes);
    return iird_json_finish(keep_if(o, ok));
}

/* ======================== domain ======================== */

/* [a, b] or [a, b, c] (c < 0: left out) of floats rounded as given. */
static cJSON *tuple(double a, double b, double c, double d)
{
    cJSON *t = cJSON_CreateArray();
    bool ok = t && iird_json_add_num(t, NULL, a) && iird_json_add_num(t, NULL, b) &&
              (c < 0.0 || iird_json_add_num(t, NULL, c)) &&
              (d < 0.0 || iird_json_add_num(t, NULL, d));
    return keep_if(t, ok);
}

static bool add_domain(cJSON *o, const struct iir_domain *dom);

char *iird_json_domain(uint32_t frame, const float (*vpl_px)[2], const uint8_t *vpl_flags,
                       uint32_t num_vpls, const struct iir_domain *dom)
{
    cJSON *o = cJSON_CreateObject(), *vpls = NULL;
    bool ok = o && add_str(o, "type", "domain") && iird_json_add_num(o, "frame", frame) &&
              add_item(o, "vpls", (vpls = cJSON_CreateArray()));
    for (uint32_t i = 0; ok && i < num_vpls; i++) {
        double x = vpl_px ? rounded(vpl_px[i][0], 100.0) : -1.0;
        double y = vpl_px ? rounded(vpl_px[i][1], 100.0) : -1.0;
        ok = add_item(vpls, NULL, tuple(x, y, vpl_flags ? vpl_flags[i] : 0, -1.0));
    }
    ok = ok && (!dom || !dom->map || add_str(o, "map", dom->map)) && (!dom || add_domain(o, dom));
    return iird_json_finish(keep_if(o, ok));
}

/* Disk coordinates rounded to 1e-5 of the disk's radius: plenty for drawing, half the bytes. */
static double disk(float v)
{
    return rounded(v, 1e5);
}

static cJSON *points_json(const float (*pts)[2], uint32_t begin, uint32_t end)
{
    cJSON *a = cJSON_CreateArray();
    bool ok = a != NULL;
    for (uint32_t i = begin; ok && i < end; i++)
        ok = add_item(a, NULL, tuple(disk(pts[i][0]), disk(pts[i][1]), -1.0, -1.0));
    return keep_if(a, ok);
}

static bool add_domain(cJSON *o, const struct iir_domain *dom)
{
    cJSON *sites = NULL, *edges = NULL, *cells = NULL;
    bool ok = add_item(o, "sites", (sites = cJSON_CreateArray())) &&
              add_item(o, "edges", (edges = cJSON_CreateArray())) &&
              add_item(o, "cells", (cells = cJSON_CreateArray()));
    for (uint32_t i = 0; ok && i < dom->num_sites; i++) {
        const iir_domain_site *st = &dom->sites[i];
        ok = add_item(sites, NULL, tuple(disk(st->x), disk(st->y), st->id, st->flags));
    }
    for (uint32_t i = 0; ok && i < dom->num_edges; i++)
        ok = add_item(edges, NULL, tuple(dom->edges[i][0], dom->edges[i][1], -1.0, -1.0));
    for (uint32_t k = 0; ok && k < dom->num_cells; k++) {
        assert(dom->cell_start[k] <= dom->cell_start[k + 1] && "iir_domain: cell_start decreases");
        ok = add_item(cells, NULL,
                      points_json(dom->cell_points, dom->cell_start[k], dom->cell_start[k + 1]));
    }
    return ok && add_item(o, "removed", points_json(dom->removed, 0, dom->num_removed));
}

/* ======================== pick, snapshot ======================== */

char *iird_json_pick(int64_t seq, bool hit, iir_vec3 position, iir_vec3 normal, float distance)
{
    cJSON *o = reply("pick", seq);
    bool ok = o && add_bool(o, "hit", hit);
    if (ok && hit)
        ok = iird_json_add_vec3(o, "position", position) &&
             iird_json_add_vec3(o, "normal", normal) &&
             iird_json_add_float(o, "distance", distance);
    return iird_json_finish(keep_if(o, ok));
}

char *iird_json_snapshot(int64_t seq, const char *format, uint32_t frame, uint32_t pass,
                         size_t bytes, int width, int height)
{
    cJSON *o = reply("snapshot", seq);
    bool ok = o && add_str(o, "format", format) && iird_json_add_num(o, "frame", frame) &&
              iird_json_add_num(o, "pass", pass) && iird_json_add_u64(o, "bytes", bytes) &&
              iird_json_add_num(o, "width", width) && iird_json_add_num(o, "height", height);
    return iird_json_finish(keep_if(o, ok));
}

/* ======================== binary frames ======================== */

static void put16(uint8_t *p, uint16_t v)
{
    p[0] = (uint8_t)(v & 0xFF);
    p[1] = (uint8_t)(v >> 8);
}

static void put32(uint8_t *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) p[i] = (uint8_t)(v >> (8 * i));
}

static void put_f32(uint8_t *p, float f)
{
    uint32_t bits;
    memcpy(&bits, &f, sizeof bits); /* IEEE 754 binary32, written little-endian below */
    put32(p, bits);
}

void iird_frame_header_write(const iird_frame_header *h, uint8_t out[IIRD_FRAME_HEADER_BYTES])
{
    out[0] = 'I';
    out[1] = 'I';
    out[2] = 'R';
    out[3] = 'F';
    out[4] = h->kind;
    out[5] = 2; /* header version */
    put16(out + 6, IIRD_FRAME_HEADER_BYTES);
    put32(out + 8, h->frame_id);
    put32(out + 12, h->seq);
    put16(out + 16, h->width);
    put16(out + 18, h->height);
    put_f32(out + 20, h->render_ms);
    put_f32(out + 24, h->encode_ms);
    put32(out + 28, h->pass);
    put32(out + 32, h->flags);
    put32(out + 36, h->payload_bytes);
    put32(out + 40, h->generation);
}

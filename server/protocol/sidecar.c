/* sidecar.c -- `save`: a session's lights and camera as a scene sidecar (docs/scene-format.md,
 * section 5) based on the scene it shows ("base"), and the `save` reply that carries it. Not
 * writing the file or checking the name against the scenes directory (serve/scene_save.c).
 *
 * Numbers are written as the shortest decimals that read back as the same floats, so a sidecar
 * loads the camera and lights the session rendered (angles go through degrees: within an ulp). */
#include "protocol_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static cJSON *camera_json(const iir_camera *c, float aspect)
{
    cJSON *o = cJSON_CreateObject();
    bool ok =
        o && iird_json_add_vec3(o, "position", c->position) &&
        iird_json_add_vec3(o, "target", c->target) && iird_json_add_vec3(o, "up", c->up) &&
        iird_json_add_float(o, "fov_y", c->fov_y) &&
        (!(aspect > 0.f) || iird_json_add_float(o, "aspect", fminf(fmaxf(aspect, .01f), 100.f)));
    if (ok) return o;
    cJSON_Delete(o);
    return NULL;
}

/* The spots' fields: axis, up hint, cone and, by profile, the smooth edge or the inner cone, in
 * degrees (within the sidecar's ranges). */
static bool spot_json(cJSON *o, const iir_light *L)
{
    float cone = fminf(iir_degrees(L->cone_angle), 90.f);
    bool gltf = L->profile == IIR_SPOT_GLTF;
    float edge = fminf(fmaxf(iir_degrees(gltf ? L->inner_angle : L->smooth), 0.f), cone);
    return iird_json_add_vec3(o, "direction", L->direction) && iird_json_add_vec3(o, "up", L->up) &&
           iird_json_add_float(o, "cone_angle", cone) &&
           iird_json_add_float(o, gltf ? "inner_angle" : "smooth", edge);
}

/* A sun's: the way its light travels and the up hint (its disk is refitted on load). */
static bool sun_json(cJSON *o, const iir_light *L)
{
    return iird_json_add_vec3(o, "direction", L->direction) && iird_json_add_vec3(o, "up", L->up);
}

/* "emission_map": the image as seen from the saved sidecar, which lies in a folder beside the
 * scene folder the image is in: "../FOLDER/FILE". */
static bool map_json(cJSON *o, const iir_emission_map *m)
{
    const char *file = strrchr(m->path, '/');
    if (!file) return cJSON_AddStringToObject(o, "emission_map", m->path) != NULL;
    const char *folder = file;
    while (folder > m->path && folder[-1] != '/') folder--;
    char rel[1100];
    snprintf(rel, sizeof rel, "../%.*s%s", (int)(file - folder), folder, file);
    return cJSON_AddStringToObject(o, "emission_map", rel) != NULL;
}

/* An area light's: its normal, the up hint (its frame, as a spot's), [width, height] and, for a
 * shaped light, "shape": its triangles' light-local corners [[x, y], [x, y], [x, y]] (floats in
 * [-1/2, 1/2], written so they read back the same). */
static bool area_json(cJSON *o, const iir_light *L)
{
    if (!iird_json_add_vec3(o, "direction", L->direction) || !iird_json_add_vec3(o, "up", L->up))
        return false;
    cJSON *size = cJSON_AddArrayToObject(o, "size");
    if (!size || !iird_json_add_float(size, NULL, L->size.x) ||
        !iird_json_add_float(size, NULL, L->size.y))
        return false;
    return (L->shape.num_triangles == 0 || iird_json_add_shape(o, &L->shape)) &&
           (!L->map || map_json(o, L->map));
}

/* The light's kind-specific fields: a point's position, a spot's position and cone, a sun's
 * direction, an area light's position, normal and size. */
static bool kind_json(cJSON *o, const iir_light *L)
{
    if (L->type == IIR_LIGHT_SUN) return sun_json(o, L);
    if (!iird_json_add_vec3(o, "position", L->position)) return false;
    if (L->type == IIR_LIGHT_AREA) return area_json(o, L);
    return L->type != IIR_LIGHT_SPOT || spot_json(o, L);
}

static cJSON *light_json(const iir_light *L)
{
    cJSON *o = cJSON_CreateObject();
    bool ok = o && cJSON_AddStringToObject(o, "type", iir_light_kind(L)) &&
              (!L->name[0] || cJSON_AddStringToObject(o, "name", L->name)) && kind_json(o, L) &&
              iird_json_add_vec3(o, "intensity", L->intensity);
    if (ok) return o;
    cJSON_Delete(o);
    return NULL;
}

/* {"base", "camera", "lights"}; NULL on out-of-memory. */
static cJSON *sidecar_json(const iird_sidecar_view *v)
{
    cJSON *o = cJSON_CreateObject(), *lights = NULL, *camera = camera_json(v->camera, v->aspect);
    bool ok = o && camera && cJSON_AddStringToObject(o, "base", v->base);
    if (ok) ok = cJSON_AddItemToObject(o, "camera", camera);
    if (!ok) cJSON_Delete(camera);
    ok = ok && (lights = cJSON_AddArrayToObject(o, "lights"));
    for (uint32_t i = 0; ok && i < v->num_lights; i++) {
        cJSON *l = light_json(&v->lights[i]);
        ok = l && cJSON_AddItemToArray(lights, l);
        if (!ok) cJSON_Delete(l);
    }
    if (ok) return o;
    cJSON_Delete(o);
    return NULL;
}

char *iird_sidecar_text(const iird_sidecar_view *v)
{
    cJSON *o = sidecar_json(v);
    char *text = o ? cJSON_Print(o) : NULL;
    cJSON_Delete(o);
    return text;
}

static bool add_names(cJSON *o, const char *const *scenes)
{
    cJSON *a = cJSON_AddArrayToObject(o, "scenes");
    for (const char *const *n = scenes; a && n && *n; n++)
        if (!cJSON_AddItemToArray(a, cJSON_CreateString(*n))) return false;
    return a != NULL;
}

char *iird_json_save(const iird_sidecar_view *v, int64_t seq, const char *name,
                     const char *const *scenes, size_t scenes_more)
{
    cJSON *o = cJSON_CreateObject(), *sidecar = sidecar_json(v);
    bool ok =
        o && sidecar && cJSON_AddStringToObject(o, "type", "save") &&
        (seq < 0 || iird_json_add_num(o, "seq", (double)seq)) &&
        (!name || (cJSON_AddStringToObject(o, "name", name) && add_names(o, scenes) &&
                   (!scenes_more || iird_json_add_num(o, "scenes_more", (double)scenes_more))));
    if (ok) ok = cJSON_AddItemToObject(o, "sidecar", sidecar);
    if (!ok) {
        if (!o || !cJSON_GetObjectItemCaseSensitive(o, "sidecar")) cJSON_Delete(sidecar);
        cJSON_Delete(o);
        return NULL;
    }
    return iird_json_finish(o);
}

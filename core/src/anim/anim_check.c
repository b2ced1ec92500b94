/* anim_check.c -- checking a parsed script against the lights it will animate, once the scene is
 * known: every "lights" track names exactly one of them, not the one the "light" track moves,
 * and every track gives only the fields its light's kind has. Not parsing (anim_parse.c) or
 * evaluating (anim_eval.c). */
#include "anim_internal.h"

#include <stdio.h>
#include <string.h>

/* "its lights: a, b, c" (cut short with "..." past the buffer), or "it has no lights". */
static void list_names(const iir_light *lights, uint32_t n, char *buf, size_t size)
{
    size_t used = (size_t)snprintf(buf, size, n ? "its lights: " : "it has no lights");
    for (uint32_t i = 0; i < n && used < size; i++) {
        int w = snprintf(buf + used, size - used, "%s%s", i ? ", " : "", lights[i].name);
        if (w < 0 || used + (size_t)w >= size) {
            if (size > 4) snprintf(buf + size - 4, 4, "...");
            return;
        }
        used += (size_t)w;
    }
}

/* The first key of tr giving any of `fields` (-1 when none does). */
static int first_with(const iir_anim_track *tr, unsigned fields)
{
    for (int i = 0; i < tr->num_keys; i++)
        if (tr->keys[i].fields & fields) return i;
    return -1;
}

/* The JSON path of a key of track `path`: "lights[1].keys[3]", or "lights[1].orbit" for a
 * parametric path's constant fields. */
static void key_path(const iir_anim_track *tr, const char *path, int key, char *buf, size_t size)
{
    if (tr->path == IIR_ANIM_KEYS)
        snprintf(buf, size, "%s.keys[%d]", path, key);
    else
        snprintf(buf, size, "%s.%s", path, tr->path == IIR_ANIM_ORBIT ? "orbit" : "sweep");
}

typedef struct kind_rule {
    unsigned field;
    const char *name;
    bool (*has)(const iir_light *L);
    const char *applies; /* the kinds it applies to */
} kind_rule;

static bool is_spot(const iir_light *L)
{
    return L->type == IIR_LIGHT_SPOT;
}
static bool is_cosine_spot(const iir_light *L)
{
    return L->type == IIR_LIGHT_SPOT && L->profile == IIR_SPOT_COSINE;
}
static bool is_gltf_spot(const iir_light *L)
{
    return L->type == IIR_LIGHT_SPOT && L->profile == IIR_SPOT_GLTF;
}
static bool is_area(const iir_light *L)
{
    return L->type == IIR_LIGHT_AREA;
}

/* The kind of L in words, with its sidecar type. */
static const char *kind_text(const iir_light *L)
{
    switch (L->type) {
    case IIR_LIGHT_POINT:
        return "a point light (point)";
    case IIR_LIGHT_SPOT:
        return L->profile == IIR_SPOT_GLTF ? "a glTF spot (gltf_spot)" : "a cosine spot (spot)";
    case IIR_LIGHT_SUN:
        return "a sun (sun)";
    case IIR_LIGHT_AREA:
        return "an area light (area)";
    }
    return "a light of unknown kind";
}

static const kind_rule RULES[] = {
    {IIR_AF_CONE, "cone_angle", is_spot, "spots (spot, gltf_spot)"},
    {IIR_AF_SMOOTH, "smooth", is_cosine_spot, "cosine spots (spot; a gltf_spot has inner_angle)"},
    {IIR_AF_INNER, "inner_angle", is_gltf_spot, "glTF spots (gltf_spot)"},
    {IIR_AF_SIZE, "size", is_area, "area lights"},
};

/* A sun is never moved: a position only aims it, with a target in the same key. */
static iir_status check_sun(const iir_anim *a, const iir_anim_track *tr, const char *path,
                            const iir_light *L, iir_error *err)
{
    char kp[192];
    for (int i = 0; i < tr->num_keys; i++) {
        const iir_anim_key *k = &tr->keys[i];
        bool moves = (k->fields & IIR_AF_POSITION) || tr->path != IIR_ANIM_KEYS;
        if (!moves || (k->fields & IIR_AF_TARGET)) continue;
        key_path(tr, path, i, kp, sizeof kp);
        return iir_fail(err, IIR_ERR_INVALID,
                        "%s: %s: '%s' is a sun, which is never moved: give direction, or a "
                        "position with a target to aim it",
                        a->source, kp, L->name);
    }
    return IIR_OK;
}

/* Every field track tr gives fits light L's kind. */
static iir_status check_kind(const iir_anim *a, const iir_anim_track *tr, const char *path,
                             const iir_light *L, iir_error *err)
{
    char kp[192];
    for (size_t r = 0; r < sizeof RULES / sizeof RULES[0]; r++) {
        int k = first_with(tr, RULES[r].field);
        if (k < 0 || RULES[r].has(L)) continue;
        key_path(tr, path, k, kp, sizeof kp);
        return iir_fail(err, IIR_ERR_INVALID, "%s: %s.%s: light '%s' is %s; %s applies to %s",
                        a->source, kp, RULES[r].name, L->name, kind_text(L), RULES[r].name,
                        RULES[r].applies);
    }
    return L->type == IIR_LIGHT_SUN ? check_sun(a, tr, path, L, err) : IIR_OK;
}

/* lights[k]'s light: exactly one of the lights has its name, and it is not the moved one. */
static iir_status check_named(const iir_anim *a, int k, const iir_light *lights, uint32_t n,
                              uint32_t moved, iir_error *err)
{
    char names[512];
    const char *name = a->lights[k].name;
    int i = iir_anim_find_light(lights, n, name);
    if (i == -1) {
        list_names(lights, n, names, sizeof names);
        return iir_fail(err, IIR_ERR_INVALID,
                        "%s: lights[%d].name: the scene has no light named "
                        "'%s' (%s)",
                        a->source, k, name, names);
    }
    if (i == -2)
        return iir_fail(err, IIR_ERR_INVALID,
                        "%s: lights[%d].name: the scene has several lights named '%s'; give "
                        "them distinct names (the sidecar's lights[i].name)",
                        a->source, k, name);
    if ((uint32_t)i == moved && a->light.present)
        return iir_fail(err, IIR_ERR_INVALID,
                        "%s: lights[%d].name: '%s' is the light the \"light\" track moves; "
                        "animate it in one track",
                        a->source, k, name);
    char path[32];
    snprintf(path, sizeof path, "lights[%d]", k);
    return check_kind(a, &a->lights[k], path, &lights[i], err);
}

iir_status iir_anim_check_lights(const iir_anim *a, const iir_light *lights, uint32_t n,
                                 uint32_t moved, iir_error *err)
{
    iir_status st = IIR_OK;
    if (a->light.present && moved < n) st = check_kind(a, &a->light, "light", &lights[moved], err);
    for (int k = 0; st == IIR_OK && k < a->num_lights; k++)
        st = check_named(a, k, lights, n, moved, err);
    return st;
}

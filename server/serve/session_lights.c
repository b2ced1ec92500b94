/* session_lights.c -- a session's lights, on or off, and which one it moves (session_lights.h). */
#include "session_lights.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

bool iird_lights_init(iird_lights *L, const iir_scene *scene)
{
    memset(L, 0, sizeof *L);
    iir_light made_up;
    uint32_t moved = iir_scene_moved_light(scene, &made_up);
    uint32_t n = scene->num_lights > 0 ? scene->num_lights : 1;
    L->v = malloc(n * sizeof *L->v);
    L->shown = malloc(n * sizeof *L->shown);
    L->on = malloc(n * sizeof *L->on);
    if (!L->v || !L->shown || !L->on) {
        iird_lights_free(L);
        return false;
    }
    if (scene->num_lights > 0)
        memcpy(L->v, scene->lights, n * sizeof *L->v);
    else
        L->v[0] = made_up;
    for (uint32_t i = 0; i < n; i++) L->on[i] = true;
    L->n = n;
    L->made_up = scene->num_lights == 0;
    L->moved = L->made_up ? 0 : moved;
    return true;
}

void iird_lights_free(iird_lights *L)
{
    free(L->v);
    free(L->shown);
    free(L->on);
    memset(L, 0, sizeof *L);
}

int iird_lights_find(const iird_lights *L, const char *name)
{
    for (uint32_t i = 0; i < L->n; i++)
        if (strcmp(L->v[i].name, name) == 0) return (int)i;
    return -1;
}

void iird_lights_names(const iird_lights *L, char *out, size_t n)
{
    size_t used = 0;
    if (n) out[0] = '\0';
    for (uint32_t i = 0; i < L->n && used < n; i++)
        used += (size_t)snprintf(out + used, n - used, "%s'%s' (%s)", i ? ", " : "", L->v[i].name,
                                 iir_light_kind(&L->v[i]));
}

const iir_light *iird_lights_shown(iird_lights *L)
{
    for (uint32_t i = 0; i < L->n; i++) {
        L->shown[i] = L->v[i];
        if (!L->on[i]) L->shown[i].intensity = iir_v3s(0.f);
    }
    return L->shown;
}

/* dropped.c -- what the methods leave out of a scene, as the named entries of iir_method_dropped
 * (method.h): the scene's own notes (lights and materials nothing renders), then each method's own
 * list (its ops' `dropped`, in the method's file; the emitters' entries are built here), and what
 * a method leaves out at its parameters (pt: mirrors and glass at too few bounces). Not the
 * loader's notes (scene_assimp.c makes them). */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "iir/render.h"
#include "iir/scene.h"
#include "method_internal.h"

void iir_dropped_add(iir_dropped *out, uint32_t max, uint32_t *n, const char *method,
                     const char *kind, const char *name, const char *fmt, ...)
{
    if (*n < max) {
        iir_dropped *d = &out[*n];
        memset(d, 0, sizeof *d);
        snprintf(d->method, sizeof d->method, "%s", method);
        snprintf(d->kind, sizeof d->kind, "%s", kind);
        snprintf(d->name, sizeof d->name, "%s", name);
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(d->what, sizeof d->what, fmt, ap);
        va_end(ap);
    }
    (*n)++;
}

uint32_t iir_dropped_emitters(const iir_scene *scene, const char *method, iir_dropped *out,
                              uint32_t max)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < scene->num_materials; i++) {
        const iir_material *m = &scene->material_list[i];
        const iir_method_ops *ops = iir_method_ops_of(method);
        /* rsm and hier gather one bounce from the lights' maps: no light paths go on */
        bool maps = strcmp(method, "rsm") == 0 || strcmp(method, "hier") == 0;
        /* one text for every glossy material (no per-material figures), so the commands and the
           page say it once, naming them all; short enough for iir_dropped.what */
        if (iir_material_is_glossy(m) && ops && ops->full_surfaces && maps)
            iir_dropped_add(out, max, &n, method, "material", m->name,
                            "is glossy (a metal, or roughness below 0.6): %s renders it by the "
                            "full BSDF, the maps' texels on it too (one bounce, its lobe "
                            "clamped); pt renders more bounces",
                            method);
        else if (iir_material_is_glossy(m) && ops && ops->full_surfaces)
            iir_dropped_add(out, max, &n, method, "material", m->name,
                            "is glossy (a metal, or roughness below 0.6): %s renders it by the "
                            "full BSDF, VPLs on it and the light paths leaving them too, but "
                            "clamps its lobes as the geometry term; pt does not clamp",
                            method);
        else if (iir_material_is_glossy(m))
            iir_dropped_add(out, max, &n, method, "material", m->name,
                            "is glossy (a metal, or roughness below 0.6): %s renders its direct "
                            "light by the full BSDF, its bounce light as diffuse only; pt renders "
                            "both",
                            method);
        else if ((m->kind == IIR_MATERIAL_MIRROR || m->kind == IIR_MATERIAL_GLASS) && ops &&
                 ops->full_surfaces)
            iir_dropped_add(out, max, &n, method, "material", m->name,
                            "is a %s: %s shows what it reflects or lets through (%d deep, glass "
                            "by its stronger branch), but no light reaches the room by it (no "
                            "caustics); pt renders both",
                            m->kind == IIR_MATERIAL_GLASS ? "dielectric (glass)" : "mirror", method,
                            IIR_VPL_SPECULAR_DEPTH);
        else if (m->kind == IIR_MATERIAL_MIRROR || m->kind == IIR_MATERIAL_GLASS)
            iir_dropped_add(out, max, &n, method, "material", m->name,
                            "is a %s: %s renders it black (its VPLs and shading are diffuse "
                            "only); use pt, whitted or hybrid",
                            m->kind == IIR_MATERIAL_GLASS ? "dielectric (glass)" : "mirror",
                            method);
        if (iir_is_black(m->emission)) continue;
        iir_dropped_add(out, max, &n, method, "material", m->name,
                        "emits light: its indirect light is left out, as %s's VPLs come from "
                        "punctual lights only (its direct light is rendered)",
                        method);
    }
    return n;
}

uint32_t iir_method_dropped_by_params(const char *name, const iir_scene *scene, const iir_params *p,
                                      iir_dropped *out, uint32_t max)
{
    const iir_method_ops *ops = iir_method_ops_of(name);
    if (!ops || !ops->dropped_by_params) return 0;
    void *opts = iir_method_bind_opts(ops, p);
    uint32_t n = opts ? ops->dropped_by_params(scene, opts, out, max) : 0;
    free(opts);
    return n;
}

uint32_t iir_method_dropped(const char *name, const iir_scene *scene, const iir_light *lights,
                            uint32_t num_lights, iir_dropped *out, uint32_t max)
{
    const iir_method_ops *ops = iir_method_ops_of(name);
    if (!ops) return 0;
    uint32_t n = 0;
    for (uint32_t i = 0; i < scene->num_dropped; i++, n++)
        if (n < max) out[n] = scene->dropped[i];
    if (ops->dropped)
        n += ops->dropped(scene, lights, num_lights, n < max ? out + n : NULL,
                          n < max ? max - n : 0);
    return n;
}

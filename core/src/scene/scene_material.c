/* scene_material.c -- the material kinds (diffuse, mirror, glass): their names and the checks
 * every loader's material passes through (iir_builder_add_material). Not reading them from a file
 * (scene_assimp.c, scene_sidecar.c) and not their optics (specular.h). */
#include <math.h>
#include <stdio.h>

#include "iir/hash.h"
#include "scene_build.h"

const char *iir_material_kind_name(iir_material_kind kind)
{
    switch (kind) {
    case IIR_MATERIAL_DIFFUSE:
        return "diffuse";
    case IIR_MATERIAL_MIRROR:
        return "mirror";
    case IIR_MATERIAL_GLASS:
        return "glass";
    }
    return "unknown";
}

int iir_material_specular_depth(const iir_material *m)
{
    return m->kind == IIR_MATERIAL_GLASS ? 2 : m->kind == IIR_MATERIAL_MIRROR ? 1 : 0;
}

uint64_t iir_material_hash(uint64_t h, const iir_material *m)
{
    int32_t kind = (int32_t)m->kind;
    h = IIR_HASH(h, kind);
    h = IIR_HASH(h, m->albedo);
    h = IIR_HASH(h, m->emission);
    h = IIR_HASH(h, m->specular);
    return IIR_HASH(h, m->ior);
}

static bool unit_range(iir_vec3 c)
{
    return c.x >= 0.f && c.x <= 1.f && c.y >= 0.f && c.y <= 1.f && c.z >= 0.f && c.z <= 1.f;
}

const char *iir_material_check(const iir_material *m, char *why, size_t n)
{
    if (m->kind != IIR_MATERIAL_DIFFUSE && m->kind != IIR_MATERIAL_MIRROR &&
        m->kind != IIR_MATERIAL_GLASS)
        return snprintf(why, n, "kind %d is not diffuse, mirror or glass", (int)m->kind), why;
    if (m->kind == IIR_MATERIAL_DIFFUSE) return NULL;
    if (!unit_range(m->specular))
        return snprintf(why, n, "specular (%g, %g, %g) must be in [0, 1]", (double)m->specular.x,
                        (double)m->specular.y, (double)m->specular.z),
               why;
    if (!iir_is_black(m->albedo))
        return snprintf(why, n, "a %s has no diffuse albedo (give its colour as \"specular\")",
                        iir_material_kind_name(m->kind)),
               why;
    if (m->kind == IIR_MATERIAL_GLASS && !(isfinite(m->ior) && m->ior >= 1.f && m->ior <= 3.f))
        return snprintf(why, n, "ior %g must be a finite number in [1, 3]", (double)m->ior), why;
    return NULL;
}

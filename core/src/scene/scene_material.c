/* scene_material.c -- the material kinds (diffuse, mirror, glass): their names and the checks
 * every loader's material passes through (iir_builder_add_material). Not reading them from a file
 * (scene_assimp.c, scene_sidecar.c) and not their optics (specular.h). */
#include <math.h>
#include <stdio.h>

#include "iir/bsdf.h"
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
    case IIR_MATERIAL_METAL_ROUGH:
        return "metal_rough";
    }
    return "unknown";
}

int iir_material_specular_depth(const iir_material *m)
{
    return m->kind == IIR_MATERIAL_GLASS ? 2 : m->kind == IIR_MATERIAL_MIRROR ? 1 : 0;
}

bool iir_material_is_glossy(const iir_material *m)
{
    return m->kind == IIR_MATERIAL_METAL_ROUGH && iir_bsdf_params_glossy(m->metallic, m->roughness);
}

uint64_t iir_material_hash(uint64_t h, const iir_material *m)
{
    int32_t kind = (int32_t)m->kind;
    h = IIR_HASH(h, kind);
    h = IIR_HASH(h, m->albedo);
    h = IIR_HASH(h, m->emission);
    h = IIR_HASH(h, m->specular);
    h = IIR_HASH(h, m->ior);
    h = IIR_HASH(h, m->metallic);
    h = IIR_HASH(h, m->roughness);
    h = IIR_HASH(h, m->specular_f0);
    h = IIR_HASH(h, m->opacity);
    int32_t mode = (int32_t)m->alpha_mode;
    h = IIR_HASH(h, mode);
    h = IIR_HASH(h, m->alpha_cutoff);
    h = IIR_HASH(h, m->normal_scale);
    const iir_texref *refs[] = {&m->base_tex, &m->mr_tex, &m->normal_tex, &m->emission_tex};
    for (size_t k = 0; k < sizeof refs / sizeof *refs; k++) {
        h = IIR_HASH(h, refs[k]->texture);
        h = IIR_HASH(h, refs[k]->sampler);
        h = IIR_HASH(h, refs[k]->transform);
    }
    return h;
}

static bool unit_range(iir_vec3 c)
{
    return c.x >= 0.f && c.x <= 1.f && c.y >= 0.f && c.y <= 1.f && c.z >= 0.f && c.z <= 1.f;
}

const char *iir_material_check(const iir_material *m, char *why, size_t n)
{
    if (m->kind != IIR_MATERIAL_DIFFUSE && m->kind != IIR_MATERIAL_MIRROR &&
        m->kind != IIR_MATERIAL_GLASS && m->kind != IIR_MATERIAL_METAL_ROUGH)
        return snprintf(why, n, "kind %d is not diffuse, mirror, glass or metal_rough",
                        (int)m->kind),
               why;
    if (!(m->specular_f0 >= 0.f && m->specular_f0 <= 1.f))
        return snprintf(why, n, "specular f0 %g must be in [0, 1]", (double)m->specular_f0), why;
    if (!(m->metallic >= 0.f && m->metallic <= 1.f && m->roughness >= 0.f && m->roughness <= 1.f))
        return snprintf(why, n, "metallic %g and roughness %g must be in [0, 1]",
                        (double)m->metallic, (double)m->roughness),
               why;
    if (m->alpha_mode && !(m->opacity >= 0.f && m->opacity <= 1.f && m->alpha_cutoff >= 0.f &&
                           m->alpha_cutoff <= 1.f))
        return snprintf(why, n, "alpha %g and its cutoff %g must be in [0, 1]", (double)m->opacity,
                        (double)m->alpha_cutoff),
               why;
    if (m->kind == IIR_MATERIAL_DIFFUSE || m->kind == IIR_MATERIAL_METAL_ROUGH) return NULL;
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

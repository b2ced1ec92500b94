/* vpl_lobe.h -- how a VPL born on a surface reflects the light it got: its lobe (diffuse, or the
 * surface's glossy metallic-roughness BSDF) and the albedo its flux is weighted by, shared by ir's
 * paths (methods/ir.c), iir's samples (incremental.c) and descendants (lineage.c); paths go on
 * from a glossy VPL in directions sampled from its BSDF (light_path.h). Internal; inline. */
#ifndef IIR_VPL_LOBE_H
#define IIR_VPL_LOBE_H

#include <math.h>

#include "../surface.h"
#include "iir/bsdf.h"
#include "iir/vpl.h"

/* The lobe of a VPL at sf; *albedo gets sf's diffuse albedo, or for a glossy lobe
 * iir_bsdf_reflectance (c_diff + F0). */
static inline iir_vpl_lobe iir_vpl_lobe_at(const iir_surface *sf, iir_vec3 *albedo)
{
    iir_vpl_lobe lobe = {0};
    *albedo = sf->albedo;
    if (sf->kind != IIR_MATERIAL_METAL_ROUGH ||
        !iir_bsdf_params_glossy(sf->metallic, sf->roughness))
        return lobe;
    lobe.glossy = true;
    lobe.metallic = sf->metallic, lobe.roughness = sf->roughness, lobe.f0 = sf->specular_f0;
    lobe.base = sf->base;
    *albedo = iir_bsdf_reflectance(sf->albedo, sf->base, sf->metallic, sf->specular_f0);
    return lobe;
}

/* Glossy lobe l as a BSDF about unit normal n. */
static inline iir_bsdf iir_lobe_bsdf(const iir_vpl_lobe *l, iir_vec3 n)
{
    return iir_bsdf_make_f0(n, l->base, l->metallic, l->roughness, l->f0);
}

/* The BSDF of glossy VPL v's surface (its normal: the side its light arrived from). */
static inline iir_bsdf iir_vpl_lobe_bsdf(const iir_vpl *v)
{
    return iir_lobe_bsdf(&v->lobe, v->normal);
}

/* What a light path leaving glossy VPL v along d carries relative to v's flux, d having been
 * sampled with density pdf and the path kept with probability q:
 *     f(wi, d) |n . d| / (pdf q albedo)
 * (v's flux is the arriving flux times its albedo; light_path.h). With v's current wi it
 * re-weighs a kept path whose VPL's light has turned (lineage.c). */
static inline iir_vec3 iir_vpl_lobe_weight(const iir_vpl *v, iir_vec3 d, float pdf_q)
{
    iir_bsdf b = iir_vpl_lobe_bsdf(v);
    iir_vec3 f = iir_scale(iir_bsdf_f(&b, v->wi, d), fabsf(iir_dot(v->normal, d)) / pdf_q);
    return iir_v3(f.x / v->albedo.x, f.y / v->albedo.y, f.z / v->albedo.z);
}

#endif

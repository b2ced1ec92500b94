/* vpl_lobe.h -- how a VPL born on a surface reflects the light it got: its lobe (diffuse, or the
 * surface's glossy metallic-roughness BSDF) and the albedo its flux is weighted by, shared by ir's
 * paths (methods/ir.c), iir's samples (incremental.c) and descendants (lineage.c). Paths go on
 * from a glossy VPL as from a diffuse one of that albedo (light_path.h): energy kept, directions
 * cosine-distributed. Internal; inline. */
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

#endif

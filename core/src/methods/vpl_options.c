/* vpl_options.c -- the parameters of the VPL shading that ir and iir share (visibility, shadow
 * maps, interleaving, clamping) as one table, what they ask of the renderer, and the memory the
 * VPL renderer and a VPL set take. Not how VPLs are chosen (the methods) or shaded (render.h). */
#include <stddef.h>

#include "iir/vpl.h"
#include "method_internal.h"

static const char *const VISIBILITY_CHOICES[] = {"shadowmap", "rays", NULL};

static const iir_param VPL_ROWS[] = {
    {"visibility", IIR_PARAM_ENUM, offsetof(iir_vpl_options, visibility), IIR_VIS_SHADOWMAP, 0, 1,
     0, VISIBILITY_CHOICES, "", "VPL visibility: shadowmap (fast) or rays (exact, slow)",
     IIR_PARAM_LIVE},
    {"sm_res", IIR_PARAM_INT, offsetof(iir_vpl_options, sm_res), 128, 8, 2048, 0, NULL, "pixels",
     "shadow-map resolution (res^2 rays and 4 res^2 bytes per VPL, paid at its birth)",
     IIR_PARAM_RESTART},
    {"sm_bias", IIR_PARAM_FLOAT, offsetof(iir_vpl_options, sm_bias), 0.005, 0, 1, 0, NULL, "",
     "shadow-map bias as a fraction of the VPL-receiver distance", IIR_PARAM_LIVE},
    {"interleave", IIR_PARAM_INT, offsetof(iir_vpl_options, interleave), 4, 1, 8, 0, NULL, "",
     "n x n interleaved VPL subsets with a geometry-aware filter; 1 = every VPL at every pixel",
     IIR_PARAM_LIVE},
    /* G stops growing below a tenth of the scene diagonal; on the Cornell box orbit 100 gave the
       lowest error against pt of 0, 25, 100, 400 and 1600 for both ir and iir */
    {"clamp", IIR_PARAM_FLOAT, offsetof(iir_vpl_options, clamp), 100, 0, 1e6, 0, NULL, "",
     "bound the geometry term at clamp / D^2, D the scene diagonal; 0 = no clamp", IIR_PARAM_LIVE},
};
const iir_param_table iir_vpl_table = {"VPL shading (ir, iir)", VPL_ROWS,
                                       sizeof VPL_ROWS / sizeof VPL_ROWS[0], NULL};

iir_indirect_params iir_vpl_indirect(const iir_vpl_options *o)
{
    iir_indirect_params ind = iir_indirect_params_default();
    ind.visibility = o->visibility;
    ind.interleave = o->interleave;
    ind.clamp = o->clamp;
    ind.sm_bias = o->sm_bias;
    return ind;
}

uint64_t iir_vpl_memory(const iir_vpl_options *o, uint32_t n, int width, int height)
{
    uint64_t px = (uint64_t)width * (uint64_t)height;
    uint64_t bytes = px * (56 + 12 + 16); /* G-buffer, raw indirect, filter rows */
    bytes += px * (24 + 12);              /* refinement: double sum + pass image */
    uint64_t map = o->visibility == IIR_VIS_SHADOWMAP ? 4ull * (uint64_t)o->sm_res * o->sm_res : 0;
    return bytes + (uint64_t)n * (sizeof(iir_vpl) + map);
}

/* render_params.c -- the VPL shading's parameters (visibility and shadow maps; bias and
 * interleaving; shading and its hierarchy; clamping and its compensation) as tables bound to
 * iir_indirect_params wherever a method keeps one (ir, iir and ism list them; rsm and hier the
 * shading, clamp and multires ones), their defaults, and the memory the VPL renderer and a VPL set
 * take. Not how VPLs are chosen (the methods) or shaded (render.c and its phases). */
#include <stddef.h>
#include <string.h>

#include "iir/render.h"
#include "iir/vpl.h"
#include "gv_columns.h"
#include "light_tree.h"

static const char *const VISIBILITY_CHOICES[] = {"shadowmap", "rays", "ism", NULL};

static const char *const SHADING_CHOICES[] = {"full", "multires", NULL};

static const char *const RECEIVER_CHOICES[] = {"glossy", "all", "diffuse", NULL};

static const char *const VPL_KIND_CHOICES[] = {"point", "sphere", NULL};

static const char *const MR_DIRECT_CHOICES[] = {"full", "tree", NULL};

static const char *const CLAMP_COMP_CHOICES[] = {"off", "full", "interleaved", NULL};

static const iir_param VIS_ROWS[] = {
    {"visibility", IIR_PARAM_ENUM, offsetof(iir_indirect_params, visibility), IIR_VIS_SHADOWMAP, 0,
     2, 0, VISIBILITY_CHOICES, "",
     "VPL visibility: shadowmap (fast), rays (exact, slow) or ism (imperfect shadow maps, cheap)",
     IIR_PARAM_LIVE},
    {"sm_res", IIR_PARAM_INT, offsetof(iir_indirect_params, sm_res), 128, 8, 2048, 0, NULL,
     "pixels", "shadow-map resolution (res^2 rays and 2 res^2 bytes per VPL, paid at its birth)",
     IIR_PARAM_RESTART},
};
const iir_param_table iir_vis_table = {"VPL visibility (ir, iir)", VIS_ROWS,
                                       sizeof VIS_ROWS / sizeof VIS_ROWS[0], NULL};

static const iir_param VPL_ROWS[] = {
    {"sm_bias", IIR_PARAM_FLOAT, offsetof(iir_indirect_params, sm_bias), 0.005, 0, 1, 0, NULL, "",
     "shadow-map bias as a fraction of the VPL-receiver distance", IIR_PARAM_LIVE},
    {"interleave", IIR_PARAM_INT, offsetof(iir_indirect_params, interleave), 4, 1, 8, 0, NULL, "",
     "n x n interleaved VPL subsets with a geometry-aware filter; 1 = every VPL at every pixel",
     IIR_PARAM_LIVE},
    /* cornell_area orbit, frames 0-3 at 512x512, relRMSE against 1024 samples: 1, 4, 8, 16 and 64
       samples 0.137, 0.025, 0.013, 0.0067 and 0.0022 for 1x, 2x, 2.8x, 4.5x and 15x the CPU time
       of a frame (docs/architecture.md); a live session may ask for 64 */
    {"area_samples", IIR_PARAM_INT, offsetof(iir_indirect_params, area_samples), 8, 1, 4096, 1024,
     NULL, "samples",
     "direct light: stratified samples per pixel over each area light and the emissive triangles "
     "(one shadow ray each; a still averages refine_passes passes of them)",
     IIR_PARAM_LIVE},
    /* material room, frames 0-3 at 256x192, iir relMSE against pt: diffuse 0.0141, glossy
       0.0128, all 0.0109, for 3.8, 4.7 and 11.0 ms of indirect light a frame; the conference
       room (every material a rough dielectric): the same relMSE in all three, 1.5x the frame
       time with all (docs/experiments.md) */
    {"receiver_bsdf", IIR_PARAM_ENUM, offsetof(iir_indirect_params, receiver_bsdf),
     IIR_RECEIVER_GLOSSY, 0, 2, 0, RECEIVER_CHOICES, "",
     "which pixels reflect VPL light by their full BSDF: glossy (metals, roughness below 0.6), "
     "all (every metallic-roughness material; glossy with shading multires) or diffuse (none)",
     IIR_PARAM_LIVE},
    {"vpl_kind", IIR_PARAM_ENUM, offsetof(iir_indirect_params, vpl_kind), IIR_VPL_POINT, 0, 1, 0,
     VPL_KIND_CHOICES, "",
     "a VPL is a point, or a virtual spherical light of radius its 4th-nearest VPL's distance "
     "(falling off as 1/(d^2+r^2); a glossy receiver's BSDF averaged over the cone it subtends)",
     IIR_PARAM_LIVE},
};
const iir_param_table iir_vpl_table = {"VPL shading (ir, iir, ism)", VPL_ROWS,
                                       sizeof VPL_ROWS / sizeof VPL_ROWS[0], NULL};

/* Bound to one iir_shading, wherever a method keeps it (iir_indirect_params.shading for ir and
 * iir). */
static const iir_param SHADING_ROWS[] = {
    {"shading", IIR_PARAM_ENUM, 0, IIR_SHADING_FULL, 0, 1, 0, SHADING_CHOICES, "",
     "indirect light at every pixel (full) or on coarse levels where the G-buffer is smooth "
     "(multires)",
     IIR_PARAM_LIVE},
};
const iir_param_table iir_shading_table = {"shading (ir, iir, ism, rsm)", SHADING_ROWS,
                                           sizeof SHADING_ROWS / sizeof SHADING_ROWS[0], NULL};

/* multires.h's hierarchy, for every method that shades on it. */
static const iir_param MULTIRES_ROWS[] = {
    {"mr_levels", IIR_PARAM_INT, offsetof(iir_mr_params, mr_levels), 4, 1, 6, 0, NULL, "",
     "multires: coarsest level (texels of 2^levels pixels)", IIR_PARAM_LIVE},
    {"mr_depth", IIR_PARAM_FLOAT, offsetof(iir_mr_params, mr_depth), 0.01, 0, 1, 0, NULL, "",
     "multires: a depth discontinuity where a neighbour lies off a pixel's tangent plane by more "
     "than this times its depth",
     IIR_PARAM_LIVE},
    {"mr_normal", IIR_PARAM_FLOAT, offsetof(iir_mr_params, mr_normal), 0.95, -1, 1, 0, NULL, "",
     "multires: a normal discontinuity where neighbours' normals' cosine is below this",
     IIR_PARAM_LIVE},
    /* Cornell box orbit, frames 0-29 at 512x384 (N 256, interleave 4), relMSE against pt over 6
       reference frames: 4, 8, 16, 32 and 64 pixels evaluated 2.0x, 3.3x, 4.7x, 6.1x and 6.4x
       fewer pixel-VPL pairs than full shading for +7%, +10%, +15%, +36% and +126% relMSE: past
       16 the coarse levels' filter blurs the light */
    {"mr_window", IIR_PARAM_INT, offsetof(iir_mr_params, mr_window), 16, 1, 1024, 0, NULL, "pixels",
     "multires: the widest a level's interleave filter spans (coarser levels interleave fewer, "
     "down to every VPL per texel)",
     IIR_PARAM_LIVE},
    /* Cornell orbit at 1024x768, 3 alternating pairs: tree's direct phase 0.85x full's, the frame
       0.97x; at 256x192 against 256-spp references relMSE +6%, flicker +31% (docs/experiments.md):
       not worth it by default */
    {"mr_direct", IIR_PARAM_ENUM, offsetof(iir_mr_params, mr_direct), IIR_MR_DIRECT_FULL, 0, 1, 0,
     MR_DIRECT_CHOICES, "",
     "multires: direct light of point, spot and sun lights on diffuse surfaces at every pixel "
     "(full) or on a quadtree refined where the light changes (tree; light_split; hier's is "
     "always the tree)",
     IIR_PARAM_LIVE},
    {"light_split", IIR_PARAM_FLOAT, offsetof(iir_mr_params, light_split), 0.02, 0, 1, 0, NULL, "",
     "multires direct light on a quadtree (hier's; mr_direct tree's): split a block "
     "where its light changes -- its centre off its corners' interpolation by more than this "
     "fraction of the brightest, or a corner under (1 - this) / 4 of the brightest (0: wherever "
     "the light is not linear; 1: only at depth and normal discontinuities)",
     IIR_PARAM_LIVE},
};
const iir_param_table iir_multires_table = {"multiresolution shading (shading=multires)",
                                            MULTIRES_ROWS,
                                            sizeof MULTIRES_ROWS / sizeof MULTIRES_ROWS[0], NULL};

/* Bound to one float, wherever a method keeps it (iir_indirect_params.clamp for ir and iir). */
static const iir_param CLAMP_ROWS[] = {
    /* G stops growing below a tenth of the scene diagonal; on the Cornell box orbit 100 gave the
       lowest error against pt of 0, 25, 100, 400 and 1600 for both ir and iir */
    {"clamp", IIR_PARAM_FLOAT, 0, 100, 0, 1e6, 0, NULL, "",
     "bound the geometry term at clamp / D^2, D the scene diagonal; 0 = no clamp", IIR_PARAM_LIVE},
};
const iir_param_table iir_clamp_table = {"VPL clamping (ir, iir, rsm)", CLAMP_ROWS,
                                         sizeof CLAMP_ROWS / sizeof CLAMP_ROWS[0], NULL};

/* Bound to the whole iir_indirect_params after its shading (ir, iir and ism): compensation adds to
 * every pixel's own indirect light, which multires shading does not have. */
static const iir_param CLAMP_COMP_ROWS[] = {
    {"clamp_compensation", IIR_PARAM_ENUM, offsetof(iir_indirect_params, clamp_comp),
     IIR_CLAMP_COMP_OFF, 0, 2, 0, CLAMP_COMP_CHOICES, "",
     "give back what the clamp removes near corners (Kollig & Keller): a cosine ray from every "
     "pixel (full) or from n times fewer, gathered by the interleave filter (interleaved); needs "
     "shading full",
     IIR_PARAM_LIVE},
};

static iir_status clamp_comp_check(const void *opts, const iir_params *given, const iir_param **bad,
                                   iir_error *err)
{
    const iir_indirect_params *o = opts;
    if (o->clamp_comp == IIR_CLAMP_COMP_OFF || o->shading != IIR_SHADING_MULTIRES) return IIR_OK;
    bool blame_shading =
        iir_params_has(given, "shading") && !iir_params_has(given, "clamp_compensation");
    *bad = blame_shading ? &SHADING_ROWS[0] : &CLAMP_COMP_ROWS[0];
    return iir_fail(err, IIR_ERR_INVALID,
                    "%s: clamp_compensation needs shading full (multires shades coarse texels, "
                    "not every pixel's own indirect light)",
                    (*bad)->name);
}

const iir_param_table iir_clamp_comp_table = {
    "clamping compensation (ir, iir, ism)", CLAMP_COMP_ROWS,
    sizeof CLAMP_COMP_ROWS / sizeof CLAMP_COMP_ROWS[0], clamp_comp_check};

iir_indirect_params iir_indirect_params_default(void)
{
    iir_indirect_params p;
    memset(&p, 0, sizeof p);
    iir_params_defaults(&iir_vis_table, &p);
    iir_params_defaults(&iir_vpl_table, &p);
    iir_params_defaults(&iir_clamp_table, &p.clamp);
    iir_params_defaults(&iir_clamp_comp_table, &p);
    iir_params_defaults(&iir_shading_table, &p.shading);
    iir_params_defaults(&iir_multires_table, &p.mr);
    p.bounces = 2;
    return p;
}

uint64_t iir_gv_memory(const iir_indirect_params *o, uint32_t n, int width, int height)
{
    if (o->visibility == IIR_VIS_RAYS) return 0;
    uint64_t n2 = (uint64_t)o->interleave * (uint64_t)o->interleave;
    uint64_t px = (uint64_t)width * (uint64_t)height, samples = (px + n2 - 1) / n2;
    if (o->shading == IIR_SHADING_MULTIRES) samples += px / 3; /* a coarse texel may be in all */
    uint64_t column = samples * sizeof(float);
    uint64_t bytes = (uint64_t)n * column;
    /* full shading: each pixel's index, position and normal by class, for the tiles' batches */
    uint64_t pixels =
        o->shading == IIR_SHADING_FULL ? px * (sizeof(uint32_t) + 6 * sizeof(float)) : 0;
    return (bytes < IIR_GV_BUDGET ? bytes : IIR_GV_BUDGET) + pixels;
}

uint64_t iir_vpl_memory(const iir_indirect_params *o, uint32_t n, int width, int height)
{
    uint64_t px = (uint64_t)width * (uint64_t)height;
    uint64_t bytes = iir_renderer_memory(width, height);
    /* multires.c: per pixel a level, a flag, an order and a class entry; per texel of the coarser
       levels (a third of the pixels) a flag, a sample, a depth, E, F and an order entry */
    if (o->shading == IIR_SHADING_MULTIRES) bytes += px * (1 + 1 + 4 + 4) + px / 3 * 69;
    if (o->shading == IIR_SHADING_MULTIRES && o->mr.mr_direct == IIR_MR_DIRECT_TREE)
        bytes += light_tree_memory(width, height);
    bytes += px * (24 + 12); /* refinement: double sum + pass image */
    uint64_t map = o->visibility == IIR_VIS_SHADOWMAP ? 2ull * (uint64_t)o->sm_res * o->sm_res : 0;
    return bytes + (uint64_t)n * (sizeof(iir_vpl) + map);
}

/* ism.c -- imperfect shadow maps as a method, "ism" (Ritschel et al. 2008): instant radiosity
 * (ir.c, run through its operations) in the paper's setting -- one fresh set of many one-bounce
 * VPLs every frame, each with a cheap imperfect shadow map (visibility=ism, always; ism.h) instead
 * of a ray-traced one. Not the maps (visibility/ism.c) nor their parameters (ism_options.c).
 * Parameters: the VPL count below (a larger default than ir's), the VPL shading's (not its
 * visibility and shadow-map resolution: always ISMs), the ISMs' and every method's. Refinement is
 * ir's (exact rays). */
#include <stddef.h>

#include "method_internal.h"

static const iir_param ISM_ROWS[] = {
    /* the paper's setting: ~1k VPLs whose maps are cheap (32^2, 1k points each) */
    {"vpls", IIR_PARAM_INT, offsetof(iir_ir_options, vpls), 1024, 1, 16384, 4096, NULL, "paths",
     "light paths per frame (one bounce: each path's first diffuse vertex a VPL)",
     IIR_PARAM_RESTART},
};
static const iir_param_table ISM_TABLE = {"ism: light paths", ISM_ROWS,
                                          sizeof ISM_ROWS / sizeof ISM_ROWS[0], NULL};

/* ir's options for ism's: one bounce, fresh random numbers, ISM visibility. */
static iir_ir_options as_ir(const void *opts)
{
    iir_ir_options o = *(const iir_ir_options *)opts;
    o.bounces = 2;
    o.same_random = false;
    o.vpl.visibility = IIR_VIS_ISM;
    return o;
}

static iir_status ism_create(const iir_scene *scene, const iir_rt *rt, const void *opts,
                             const iir_stop *stop, void **state, iir_error *err)
{
    iir_ir_options o = as_ir(opts);
    return iir_method_ir.create(scene, rt, &o, stop, state, err);
}

static void ism_update(void *state, const void *opts)
{
    iir_ir_options o = as_ir(opts);
    iir_method_ir.update(state, &o);
}

static uint64_t ism_memory(const void *opts, int width, int height)
{
    iir_ir_options o = as_ir(opts);
    return iir_method_ir.memory(&o, width, height);
}

/* The rest is ir's, as it is. */
static void ism_destroy(void *state)
{
    iir_method_ir.destroy(state);
}

static iir_status ism_render(void *state, const iir_view *view, iir_image *out,
                             iir_frame_stats *stats, iir_error *err)
{
    return iir_method_ir.render(state, view, out, stats, err);
}

static iir_status ism_refine(void *state, iir_image *out, iir_frame_stats *stats, iir_error *err)
{
    return iir_method_ir.refine(state, out, stats, err);
}

static const iir_vpl *ism_vpls(const void *state, uint32_t *n)
{
    return iir_method_ir.vpls(state, n);
}

static void ism_set_stop(void *state, iir_stop_fn fn, void *ctx)
{
    iir_method_ir.set_stop(state, fn, ctx);
}

/* Like ir, light paths leave the punctual lights only. */
static uint32_t ism_dropped(const iir_scene *scene, const iir_light *lights, uint32_t num_lights,
                            iir_dropped *out, uint32_t max)
{
    (void)lights, (void)num_lights;
    return iir_dropped_emitters(scene, "ism", out, max);
}

const iir_method_ops iir_method_ism = {
    .full_surfaces = true,
    .name = "ism",
    .summary = "imperfect shadow maps: many one-bounce VPLs per frame, each with a low-resolution "
               "depth map splatted from scene points and filled by pull-push",
    .tables = {{&ISM_TABLE, 0},
               {&iir_vpl_table, offsetof(iir_ir_options, vpl)},
               {&iir_ism_table, offsetof(iir_ir_options, ism)},
               {&iir_clamp_table, offsetof(iir_ir_options, vpl.clamp)},
               {&iir_shading_table, offsetof(iir_ir_options, vpl.shading)},
               {&iir_clamp_comp_table, offsetof(iir_ir_options, vpl)}, /* after shading */
               {&iir_multires_table, offsetof(iir_ir_options, vpl.mr)},
               {&iir_common_table, offsetof(iir_ir_options, common)}},
    .opts_size = sizeof(iir_ir_options),
    .create = ism_create,
    .destroy = ism_destroy,
    .render = ism_render,
    .refine = ism_refine,
    .vpls = ism_vpls,
    .domain = NULL,
    .set_stop = ism_set_stop,
    .update = ism_update,
    .memory = ism_memory,
    .dropped = ism_dropped,
    .phases = IIR_VPL_PHASES,
};

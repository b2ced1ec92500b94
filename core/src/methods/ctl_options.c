/* ctl_options.c -- the frame-time controller's parameters (target_fps, its ceiling ctl_vpls_max
 * and its quality floor ctl_vpls_min, ctl_sm_res_min) as the VPL methods list them, and the glue
 * between a method's frames and the controller (controller.h); not the controller itself, nor
 * which frames it is given (iir.c). */
#include <stddef.h>

#include "method_internal.h"

static const iir_param CTL_ROWS[] = {
    {"target_fps", IIR_PARAM_FLOAT, offsetof(iir_ctl_options, target_fps), 0, 0, 1000, 0, NULL,
     "fps",
     "frame rate to hold: a controller picks vpls, interleave and sm_res every frame (vpls the "
     "start; frames then depend on the machine's speed); 0 = off",
     IIR_PARAM_LIVE},
    {"ctl_vpls_max", IIR_PARAM_INT, offsetof(iir_ctl_options, vpls_max), 1024, 1, 16384, 4096, NULL,
     "VPLs",
     "the most VPLs the controller uses: where the scene's error stops falling (iird bench "
     "--sweep vpls)",
     IIR_PARAM_LIVE},
    /* the Cornell orbit at 256x192, interactive frames, relMSE against pt: 0.0100 at 16 VPLs
       (blotchy while dragging), 0.0029 at 32, 0.0028 at 64, 0.0013 at 128, 0.0010 at 256; flicker
       0.0056, 0.0028, 0.0028, 0.0006, 0.0003 (docs/experiments.md) */
    {"ctl_vpls_min", IIR_PARAM_INT, offsetof(iir_ctl_options, vpls_min), 64, 1, 16384, 4096, NULL,
     "VPLs",
     "the fewest VPLs the controller uses, its quality floor (at most ctl_vpls_max): below it a "
     "frame is blotchy, whatever the rate",
     IIR_PARAM_LIVE},
    {"ctl_sm_res_min", IIR_PARAM_INT, offsetof(iir_ctl_options, sm_res_min), 64, 8, 2048, 0, NULL,
     "pixels",
     "the coarsest shadow maps the controller builds (at most sm_res): its floor for the maps "
     "of a fast light's new VPLs",
     IIR_PARAM_LIVE},
};

const iir_param_table iir_ctl_table = {"frame-time controller (iir)", CTL_ROWS,
                                       sizeof CTL_ROWS / sizeof CTL_ROWS[0], NULL};

iir_status iir_ctl_follow(iir_ctl **ctl, const iir_ctl_options *o, const iir_indirect_params *v,
                          int start_vpls, iir_error *err)
{
    if (o->target_fps <= 0.f) {
        iir_ctl_destroy(*ctl);
        *ctl = NULL;
        return IIR_OK;
    }
    iir_ctl_config cfg = {.target_ms = 1000.0 / o->target_fps,
                          .vpls_max = o->vpls_max,
                          .vpls_min = o->vpls_min,
                          .interleave = v->interleave,
                          .sm_res = v->sm_res,
                          .sm_res_min = o->sm_res_min};
    if (*ctl) return iir_ctl_configure(*ctl, &cfg, err);
    return iir_ctl_create(&cfg, start_vpls, ctl, err);
}

iir_ctl_sample iir_ctl_sample_of(const iir_frame_stats *fs, iir_ctl_setting used)
{
    iir_ctl_sample s = {.setting = used,
                        .total_ms = fs->total_ms,
                        .step_ms = fs->phase_ms[IIR_PHASE_VPLS],
                        .shadowmap_ms = fs->phase_ms[IIR_PHASE_SHADOWMAPS],
                        .indirect_ms = fs->phase_ms[IIR_PHASE_INDIRECT],
                        .filter_ms = fs->phase_ms[IIR_PHASE_FILTER],
                        .vpls = (double)fs->vpl.count, /* N: descendants ride on it */
                        .vpl_evals = (double)fs->vpl_evals,
                        .maps = (double)fs->vpl.shadowmaps,
                        .inserted = (double)fs->vpl.inserted,
                        .regenerated = fs->vpl.regenerated != 0};
    return s;
}

int iir_ctl_vpls_bound(const iir_ctl_options *o, int vpls)
{
    return o->target_fps > 0.f && o->vpls_max > vpls ? o->vpls_max : vpls;
}

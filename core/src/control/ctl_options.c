/* ctl_options.c -- the frame-time controller's parameters (target_fps, ctl_vpls_max) as the VPL
 * methods list them, and the glue between a method's frames and the controller (controller.h);
 * not the controller itself. */
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
};

const iir_param_table iir_ctl_table = {"frame-time controller (iir)", CTL_ROWS,
                                       sizeof CTL_ROWS / sizeof CTL_ROWS[0], NULL};

iir_status iir_ctl_follow(iir_ctl **ctl, const iir_ctl_options *o, const iir_vpl_options *v,
                          int start_vpls, iir_error *err)
{
    if (o->target_fps <= 0.f) {
        iir_ctl_destroy(*ctl);
        *ctl = NULL;
        return IIR_OK;
    }
    iir_ctl_config cfg = {.target_ms = 1000.0 / o->target_fps,
                          .vpls_max = o->vpls_max,
                          .interleave = v->interleave,
                          .sm_res = v->sm_res};
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

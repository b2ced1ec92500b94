/* ism_options.c -- imperfect shadow maps as the VPL methods' visibility (visibility=ism in ir, iir
 * and the ism method): their parameters as one table, building a VPL set's ISMs with the point set
 * the method keeps, and the memory they take. Not the point set or the maps themselves
 * (visibility/ism.c) nor the visibility option (vpl_options.c). */
#include <stddef.h>

#include "iir/ism.h"
#include "iir/rng.h"
#include "method_internal.h"

/* Defaults, from `iird bench --anim orbit --frames 0:40 --size 256x192 --methods ir
 * --visibility ism --ref-spp 256 --ref-every 10` with --sweep over each on the Cornell box (256
 * VPLs; with exact 128^2 maps relMSE is 1.02e-3):
 *  - ism_points_per_vpl 256, 1024, 4096: relMSE 1.20e-3, 1.10e-3, 1.07e-3, for maps costing about
 *    1 : 1.2 : 3 -- 1024 is the knee (about one point per texel of the hemisphere; pull-push
 *    fills the rest);
 *  - ism_res 16, 32, 64 (1024 points): 1.17e-3, 1.10e-3, 1.14e-3 -- coarser maps blur shadows,
 *    finer ones have more holes and more texels that only a background point reached;
 *  - ism_points 16384: each VPL's 1024 consecutive points overlap another's by 1/16 on average.
 * Pair agreement with exact rays at these settings: tests/unit/test_ism.c. */
static const iir_param ISM_ROWS[] = {
    {"ism_points", IIR_PARAM_INT, offsetof(iir_ism_options, points), 16384, 1024, 262144, 0, NULL,
     "points", "ISM: points sampled uniformly over the scene's area, once per method",
     IIR_PARAM_RESTART},
    {"ism_res", IIR_PARAM_INT, offsetof(iir_ism_options, res), 32, 8, 128, 0, NULL, "pixels",
     "ISM: resolution of each VPL's imperfect shadow map (2 res^2 bytes per VPL)",
     IIR_PARAM_RESTART},
    {"ism_points_per_vpl", IIR_PARAM_INT, offsetof(iir_ism_options, points_per_vpl), 1024, 64,
     262144, 0, NULL, "points",
     "ISM: points splatted into each VPL's map, its own random subset (at most ism_points)",
     IIR_PARAM_RESTART},
};
const iir_param_table iir_ism_table = {"imperfect shadow maps (visibility=ism)", ISM_ROWS,
                                       sizeof ISM_ROWS / sizeof ISM_ROWS[0], NULL};

iir_status iir_ism_maps_build(iir_ism_points **pts, const iir_scene *scene, const iir_rt *rt,
                              const iir_ism_options *o, uint64_t seed, uint64_t salt, iir_vpl *vpls,
                              uint32_t n, iir_stop_fn stop, void *ctx, uint32_t *built,
                              iir_error *err)
{
    *built = 0;
    if (!*pts) {
        iir_status st =
            iir_ism_points_create(scene, (uint32_t)o->points, iir_hash3(seed, 0x15a, 0), pts, err);
        if (st != IIR_OK) return st;
    }
    iir_ism_params p = {.res = o->res,
                        .points_per_vpl = (uint32_t)o->points_per_vpl,
                        .key = iir_hash3(seed, 0x15a, salt + 1)};
    *built = iir_ism_build_until(vpls, n, *pts, &p, iir_rt_epsilon(rt), stop, ctx);
    return IIR_OK;
}

uint64_t iir_ism_memory(const iir_ism_options *o, iir_visibility visibility, uint32_t n)
{
    if (visibility != IIR_VIS_ISM) return 0;
    uint64_t map = 2ull * (uint64_t)o->res * (uint64_t)o->res;
    uint64_t points = (uint64_t)o->points * (sizeof(iir_ism_sample) + sizeof(iir_vec3));
    return (uint64_t)n * map + points;
}

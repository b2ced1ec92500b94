/* raybench.h -- the machine's raw ray rate on a scene: random incoherent rays (origins on the
 * surfaces, area-weighted; directions uniform on the sphere) traced with no shading, closest hit
 * and occlusion. The yardstick every later speed figure is compared against. */
#ifndef IIR_RAYBENCH_H
#define IIR_RAYBENCH_H

#include <stdint.h>

#include "iir/rt.h"
#include "iir/scene.h"
#include "iir/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct iir_raybench_result {
    uint64_t rays;        /* per kind */
    double closest_ms;    /* wall time for all closest-hit rays */
    double occluded_ms;   /* wall time for all occlusion rays */
    double closest_per_s; /* rays per second */
    double occluded_per_s;
    double hit_fraction; /* of closest-hit rays, for sanity */
    int threads;
} iir_raybench_result;

/* Generates `rays` rays from `seed` (not timed), then traces them on all OpenMP threads. */
iir_status iir_raybench_run(const iir_scene *scene, const iir_rt *rt, uint64_t rays, uint64_t seed,
                            iir_raybench_result *out, iir_error *err);

#ifdef __cplusplus
}
#endif
#endif

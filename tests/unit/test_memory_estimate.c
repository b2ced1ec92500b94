/* test_memory_estimate.c -- a method's memory estimate for a scene (iir_method_memory_on, what the
 * daemon checks against its budgets before creating) agrees with what the created method holds by
 * its real counts (iir_method_memory_held) within 25%, on every shipped scene radiosity can mesh,
 * at the defaults and at settings towards the live limits. The estimate traces only a few sampled
 * hemicube rows; the held figure counts the real patches, vertices and form-factor non-zeros. The
 * parameter-only estimate (iir_method_memory) it replaces was 1.2 / patch_area patches whatever
 * the scene: 10x too low on living_room_screen (143,548 patches where it assumed 601), so a
 * session budget of 512 MiB let radiosity grow to 956 MB there. */
#include <math.h>
#include <omp.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "testutil.h"

#include "iir/method.h"
#include "iir/timer.h"

enum { W = 64, H = 48 };

typedef struct mem_case {
    const char *scene; /* a name in scenes/, or "builtin" */
    const char *method;
    double patch_area; /* 0: the default */
    int hemicube_res;  /* 0: the default */
} mem_case;

/* Estimate and held bytes of one case; false (with a message) when the method refuses it. */
static void check_case(const mem_case *c)
{
    iir_scene *scene = NULL;
    iir_rt *rt = NULL;
    iir_error err = {0};
    if (iir_scene_open(c->scene, IIR_SOURCE_DIR "/scenes", &scene, &rt, &err) != IIR_OK)
        fail_msg("%s: %s", c->scene, err.msg);
    iir_params p = iir_params_default();
    if (c->patch_area > 0) iir_test_set(&p, "patch_area", c->patch_area);
    if (c->hemicube_res > 0) iir_test_set(&p, "hemicube_res", c->hemicube_res);
    double t0 = iir_now_ms();
    uint64_t est = iir_method_memory_on(c->method, scene, rt, &p, W, H);
    double est_ms = iir_now_ms() - t0;
    uint64_t old = iir_method_memory(c->method, &p, W, H);
    iir_method *m = NULL;
    if (iir_method_create(c->method, scene, rt, &p, &m, &err) != IIR_OK)
        fail_msg("%s %s: %s", c->scene, c->method, err.msg);
    uint64_t held = iir_method_memory_held(m, W, H);
    double ratio = (double)est / (double)held;
    fprintf(stderr,
            "  %-18s %-9s patch_area %-7g res %-3d: estimate %7.1f MiB in %5.1f ms, held %7.1f "
            "MiB (x%.2f); parameters alone said %.1f MiB\n",
            c->scene, c->method, c->patch_area, c->hemicube_res, est / 1048576.0, est_ms,
            held / 1048576.0, ratio, old / 1048576.0);
    iir_method_destroy(m);
    iir_rt_destroy(rt);
    iir_scene_destroy(scene);
    if (fabs(ratio - 1.0) > 0.25)
        fail_msg("%s %s: estimate %llu bytes, held %llu (x%.2f, bound 25%%)", c->scene, c->method,
                 (unsigned long long)est, (unsigned long long)held, ratio);
}

static void test_radiosity_estimate_matches_held(void **state)
{
    (void)state;
    const mem_case cases[] = {
        {"builtin", "radiosity", 0, 0},           {"builtin", "radiosity", 2e-4, 16},
        {"builtin", "radiosity", 0.002, 128},     {"builtin", "hybrid", 0.001, 32},
        {"cornell_box", "radiosity", 0, 0},       {"cornell_spheres", "radiosity", 0, 0},
        {"cornell_area", "radiosity", 0, 0},      {"cornell_point", "radiosity", 5e-4, 16},
        {"cornell_gltf_spot", "radiosity", 0, 0},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) check_case(&cases[k]);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_radiosity_estimate_matches_held),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* test_stop.c -- every method stops within milliseconds when its stop hook says so, whatever it is
 * doing: creating itself (radiosity's meshing and form factors, hier's voxels), taking new
 * parameters that re-create it, rendering a frame at the daemon's live limits, refining. Each case
 * is chosen to take seconds (checked: a case that finishes before its hook fires fails), the hook
 * fires DELAY_MS after the call starts, and the call must return IIR_ERR_INTERRUPTED within
 * BOUND_MS of that. A stopped create or set_params leaves nothing behind (the sanitizer build's
 * leak check) and set_params leaves the method as it was.
 *
 * The bound: the work polls its hook every few milliseconds of one core's work (a few thousand
 * rays, a slice of voxels, a pivot of 3000^2 operations); under ASan that is ~3x slower and on a
 * loaded 2-core machine ~2x again, so a poll interval of ~5 ms becomes ~30 ms; 150 ms leaves room
 * for the threads to finish their current item. Before the hooks reached creation these calls took
 * 2.8 s (ir) to 30 s and more (radiosity's form factors). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "testutil.h"

#include "iir/method.h"
#include "iir/timer.h"

enum { DELAY_MS = 40, BOUND_MS = 150 };

/* Says stop from fire_at on (thread-safe: read-only after setup). */
typedef struct stopper {
    double fire_at;
    atomic_int polls;
} stopper;

static bool stopper_fn(void *ctx)
{
    stopper *s = ctx;
    atomic_fetch_add_explicit(&s->polls, 1, memory_order_relaxed);
    return iir_now_ms() >= s->fire_at;
}

static void arm(stopper *s)
{
    s->fire_at = iir_now_ms() + DELAY_MS;
    atomic_store(&s->polls, 0);
}

/* The call that just returned st was stopped, and soon enough after its hook fired. */
static void check_stopped(const char *what, const stopper *s, iir_status st, const iir_error *err)
{
    double late = iir_now_ms() - s->fire_at;
    fprintf(stderr, "  %-44s returned %.1f ms after its hook fired (%d polls)\n", what, late,
            atomic_load(&s->polls));
    if (st == IIR_OK)
        fail_msg("%s finished before its hook fired (%.0f ms): not a case that tests stopping",
                 what, DELAY_MS + late);
    if (st != IIR_ERR_INTERRUPTED) fail_msg("%s failed otherwise: %s", what, err->msg);
    if (late > BOUND_MS)
        fail_msg("%s returned %.0f ms after its hook fired (bound %d ms)", what, late, BOUND_MS);
}

typedef struct setting {
    const char *name;
    double value;
} setting;

static iir_params params_of(const setting *set)
{
    iir_params p = iir_params_default();
    for (; set && set->name; set++) iir_test_set(&p, set->name, set->value);
    return p;
}

/* ---- creation ---- */

static void create_case(const iir_test_cornell *f, const char *method, const setting *set)
{
    iir_params p = params_of(set);
    stopper s;
    iir_method *m = NULL;
    iir_error err = {0};
    arm(&s);
    iir_status st =
        iir_method_create_stoppable(method, f->scene, f->rt, &p, stopper_fn, &s, &m, &err);
    char what[96];
    snprintf(what, sizeof what, "%s: create", method);
    check_stopped(what, &s, st, &err);
    assert_null(m);
}

/* radiosity's form factors of ~11k patches through 3 x 512^2-cell hemicubes (the issue's
 * message); the same inside hybrid; hier's voxel grid at its live limit. */
static void test_create_stops(void **state)
{
    const iir_test_cornell *f = *state;
    const setting fine[] = {{"patch_area", 1e-4}, {"hemicube_res", 512}, {NULL, 0}};
    const setting voxels[] = {{"voxel_res", 512}, {NULL, 0}};
    create_case(f, "radiosity", fine);
    create_case(f, "hybrid", fine);
    create_case(f, "hier", voxels);
}

/* A live radiosity given parameters that re-create it: stopped, it keeps its old state. */
static void test_set_params_stops(void **state)
{
    const iir_test_cornell *f = *state;
    const char *methods[] = {"radiosity", "hybrid"};
    for (int k = 0; k < 2; k++) {
        iir_params cheap = iir_params_default(), fine = cheap;
        iir_test_set(&cheap, "patch_area", 0.02);
        iir_test_set(&cheap, "hemicube_res", 16);
        iir_test_set(&fine, "patch_area", 1e-4);
        iir_test_set(&fine, "hemicube_res", 512);
        iir_method *m = iir_test_method(f, methods[k], &cheap);
        stopper s;
        iir_method_set_stop(m, stopper_fn, &s);
        iir_error err = {0};
        bool restarted = false;
        arm(&s);
        iir_status st = iir_method_set_params(m, &fine, &restarted, &err);
        char what[96];
        snprintf(what, sizeof what, "%s: set_params", methods[k]);
        check_stopped(what, &s, st, &err);
        assert_true(iir_params_equal(iir_method_params(m), &cheap));
        iir_method_destroy(m);
    }
}

/* ---- frames ---- */

static void render_case(const iir_test_cornell *f, const char *method, const setting *set, int w,
                        int h)
{
    iir_params p = params_of(set);
    iir_method *m = iir_test_method(f, method, &p);
    iir_image *img = iir_image_create(w, h);
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    stopper s;
    iir_method_set_stop(m, stopper_fn, &s);
    iir_frame_stats fs;
    iir_error err = {0};
    arm(&s);
    iir_status st = iir_method_render(m, &v, img, &fs, &err);
    char what[96];
    snprintf(what, sizeof what, "%s: render %dx%d", method, w, h);
    check_stopped(what, &s, st, &err);
    iir_image_destroy(img);
    iir_method_destroy(m);
}

/* Each method at the daemon's live limits (the welcome table's live maxima). */
static void test_render_stops(void **state)
{
    const iir_test_cornell *f = *state;
    const setting rsm[] = {{"rsm_res", 256}, {"rsm_samples", 1024}, {"rsm_lowres", 1}, {NULL, 0}};
    const setting ir[] = {{"vpls", 4096}, {"bounces", 8}, {"clamp_compensation", 1}, {NULL, 0}};
    const setting ism[] = {{"vpls", 4096}, {"ism_points", 262144}, {NULL, 0}};
    const setting iir[] = {{"vpls", 4096}, {"sm_res", 512}, {"area_samples", 1024}, {NULL, 0}};
    const setting pt[] = {{"spp", 64}, {"bounces", 8}, {NULL, 0}};
    const setting whitted[] = {{"area_samples", 1024}, {NULL, 0}};
    const setting hier[] = {{"area_samples", 1024}, {"rsm_samples", 1024}, {NULL, 0}};
    render_case(f, "rsm", rsm, 1920, 1080);
    render_case(f, "ir", ir, 1280, 720);
    render_case(f, "ism", ism, 1280, 720);
    render_case(f, "iir", iir, 1280, 720);
    render_case(f, "pt", pt, 1280, 720);
    render_case(f, "whitted", whitted, 1280, 720);
    render_case(f, "hier", hier, 1920, 1080);
}

/* radiosity's solvers on a frame: Gauss on 3000 patches (~10^10 operations), Gauss-Seidel and
 * shooting on ~11k patches at a tolerance that takes many sweeps and shots. Created without a
 * hook (the form factors are then cached for the next case). */
static void test_solve_stops(void **state)
{
    const iir_test_cornell *f = *state;
    const setting gauss[] = {
        {"patch_area", 4.2e-4}, {"hemicube_res", 16}, {"solver", 0}, {NULL, 0}};
    const setting gs[] = {{"patch_area", 1e-4},
                          {"hemicube_res", 16},
                          {"tolerance", 1e-9},
                          {"iterations", 100000},
                          {NULL, 0}};
    const setting prog[] = {{"patch_area", 1e-4},     {"hemicube_res", 16}, {"solver", 2},
                            {"shoot_batch", 1000000}, {"tolerance", 1e-9},  {NULL, 0}};
    render_case(f, "radiosity", gauss, 256, 192);
    render_case(f, "radiosity", gs, 256, 192);
    render_case(f, "radiosity", prog, 256, 192);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_create_stops),
        cmocka_unit_test(test_set_params_stops),
        cmocka_unit_test(test_render_stops),
        cmocka_unit_test(test_solve_stops),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

/* test_insert_budget.c -- iir's insertion by time (insert_ms) and by refill (the default): when
 * many VPLs die at once the set refills in the next frame as far as the budget allows, and with
 * refill in the frame they died, where a fixed kmax (refill false) leaves it short for many frames;
 * a budget too small for one VPL still inserts one; kmax 0 (no cap) without a budget is refused.
 * Counts from the method's frame stats on the built-in Cornell box. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "iir/method.h"
#include "iir/scene.h"
#include "testutil.h"

typedef iir_test_cornell fixture;

/* Renders the box's spot aimed straight down, then swung towards the red wall (about a third of
 * the VPLs die: below the regeneration threshold), then `more` frames of the swung light; returns
 * the VPL count after the swing's first frame and, in *last, after the last one. */
static uint32_t count_after_swing(const fixture *f, const iir_params *p, int more, uint32_t *last,
                                  uint32_t *died)
{
    iir_method *m = iir_test_method(f, "iir", p);
    iir_image *img = iir_image_create(32, 24);
    iir_light l = f->scene->lights[0];
    l.direction = iir_v3(0, -1, 0);
    iir_view view = {&l, 1, f->scene->camera};
    iir_frame_stats fs;
    for (int k = 0; k < 3; k++) iir_test_render(m, &view, img, &fs);
    l.direction = iir_normalize(iir_v3(-0.6f, -1, 0));
    iir_test_render(m, &view, img, &fs);
    uint32_t first = fs.vpl.count;
    *died = fs.vpl.invalidated;
    for (int k = 0; k < more; k++) iir_test_render(m, &view, img, &fs);
    *last = fs.vpl.count;
    assert_int_equal(fs.vpl.regenerated, 0);
    iir_image_destroy(img);
    iir_method_destroy(m);
    return first;
}

static void test_budget_refills(void **state)
{
    const fixture *f = *state;
    iir_params fixed = iir_params_default(), budget, refill;
    iir_test_set(&fixed, "vpls", 128);
    iir_test_set(&fixed, "sm_res", 16);
    iir_test_set(&fixed, "interleave", 1);
    refill = fixed; /* the default: what died is replaced in its frame */
    iir_test_set(&fixed, "refill", 0);
    budget = fixed;
    iir_test_set(&budget, "kmax", 0);
    iir_test_set(&budget, "insert_ms", 1000); /* far more than 128 small maps cost */
    uint32_t last_fixed, last_budget, last_refill, died_fixed, died_budget, died_refill;
    uint32_t n_fixed = count_after_swing(f, &fixed, 2, &last_fixed, &died_fixed);
    uint32_t n_budget = count_after_swing(f, &budget, 2, &last_budget, &died_budget);
    uint32_t n_refill = count_after_swing(f, &refill, 2, &last_refill, &died_refill);
    print_message("after the swing (%u, %u and %u died): kmax 8 keeps %u (then %u), insert_ms "
                  "1000 keeps %u (then %u), refill keeps %u (then %u) of 128\n",
                  died_fixed, died_budget, died_refill, n_fixed, last_fixed, n_budget, last_budget,
                  n_refill, last_refill);
    assert_true(died_fixed > 16 && died_budget > 16 && died_refill > 16);
    assert_true(n_fixed < 128 - 8);
    assert_int_equal(n_budget, 128);
    assert_int_equal(last_budget, 128);
    assert_int_equal(n_refill, 128);
    assert_int_equal(last_refill, 128);
}

/* A budget smaller than any VPL's cost still inserts one a frame (the step needs one). */
static void test_tiny_budget_inserts_one(void **state)
{
    const fixture *f = *state;
    iir_params p = iir_params_default();
    iir_test_set(&p, "vpls", 64);
    iir_test_set(&p, "sm_res", 16);
    iir_test_set(&p, "kmax", 0);
    iir_test_set(&p, "insert_ms", 1e-6);
    uint32_t last, died, first = count_after_swing(f, &p, 3, &last, &died);
    print_message("tiny budget: %u died, %u after the swing, %u three frames later\n", died, first,
                  last);
    assert_true(first < 64);
    assert_true(last > first && last <= first + 3 + 1); /* at least (about) one a frame */
}

static void test_kmax_zero_needs_budget(void **state)
{
    const fixture *f = *state;
    iir_params p = iir_params_default();
    iir_error err = {0};
    assert_int_equal(iir_params_set(&p, iir_method_any_param("kmax"), 0, &err), IIR_OK);
    iir_method *m = NULL;
    assert_int_equal(iir_method_create("iir", f->scene, f->rt, &p, &m, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "insert_ms"));
    assert_null(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_budget_refills),
        cmocka_unit_test(test_tiny_budget_inserts_one),
        cmocka_unit_test(test_kmax_zero_needs_budget),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

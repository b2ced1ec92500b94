/* test_pullpush.c -- pull-push hole filling (pullpush.h) against values worked out by hand from its
 * definition: holes filled from the first complete level, bilinearly (9/16, 3/16, 3/16, 1/16); a
 * complete map untouched; the pyramid never built past its first complete level; a map without a
 * defined texel left all holes. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/pullpush.h"

#define HOLE INFINITY

static void assert_near(float got, float want)
{
    if (fabsf(got - want) > 1e-6f) fail_msg("got %.7g, want %.7g", got, want);
}

/* A 4 x 4 map of constant quadrants: top-left 1, top-right 2, bottom-left 3, bottom-right 4. */
static void quadrants(float m[16])
{
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) m[j * 4 + i] = (float)(1 + (i >= 2) + 2 * (j >= 2));
}

/* Two holes in the top-left quadrant. Level 1 (2 x 2): the top-left texel is the mean of its two
 * defined children, 1, so level 1 = [1 2; 3 4] is complete and pulling stops there. Push:
 * texel (0, 0) has both taps at coarse (0, 0) on each axis -> 1; texel (1, 1) has taps 0 (3/4)
 * and 1 (1/4) on each axis -> 9/16 * 1 + 3/16 * 2 + 3/16 * 3 + 1/16 * 4 = 28/16. */
static void test_fills_holes_from_level_1(void **state)
{
    (void)state;
    float m[16];
    quadrants(m);
    m[0] = HOLE, m[1 * 4 + 1] = HOLE;
    /* scratch for level 1 only: building level 2 would overrun it (the ASan build catches it) */
    float *scratch = malloc(4 * sizeof(float));
    assert_int_equal(iir_pullpush_scratch_floats(4, 4), 4 + 1);
    assert_int_equal(iir_pullpush(m, 4, 4, scratch), 1);
    assert_near(m[0], 1.f);
    assert_near(m[1 * 4 + 1], (9.f * 1 + 3.f * 2 + 3.f * 3 + 1.f * 4) / 16.f);
    /* defined texels are unchanged */
    float q[16];
    quadrants(q);
    for (int k = 0; k < 16; k++)
        if (k != 0 && k != 5) assert_true(m[k] == q[k]);
    free(scratch);
}

/* The whole top-left quadrant is a hole. Level 1 = [hole 2; 3 4] is not complete; level 2 (1 x 1)
 * is the mean of the three defined, 3, and complete: pulling stops at 2. Push to level 1: the hole
 * takes the 1 x 1 level, 3, so level 1 = [3 2; 3 4]. Push to level 0 (taps as above):
 *   (0, 0): coarse (0, 0)                            = 3
 *   (1, 0): x taps 0 (3/4), 1 (1/4); row 0           = 3/4 * 3 + 1/4 * 2       = 2.75
 *   (0, 1): column 0; y taps 0 (3/4), 1 (1/4)         = 3/4 * 3 + 1/4 * 3       = 3
 *   (1, 1): 9/16 * 3 + 3/16 * 2 + 3/16 * 3 + 1/16 * 4 = 46/16 */
static void test_fills_a_quadrant_from_level_2(void **state)
{
    (void)state;
    float m[16], scratch[5];
    quadrants(m);
    m[0] = m[1] = m[4] = m[5] = HOLE;
    assert_int_equal(iir_pullpush(m, 4, 4, scratch), 2);
    assert_near(m[0], 3.f);
    assert_near(m[1], 0.75f * 3 + 0.25f * 2);
    assert_near(m[4], 0.75f * 3 + 0.25f * 3);
    assert_near(m[5], (9.f * 3 + 3.f * 2 + 3.f * 3 + 1.f * 4) / 16.f);
    assert_true(m[2] == 2.f && m[8] == 3.f && m[15] == 4.f);
}

/* An odd width: 3 x 1 = [1 hole 3]. Level 1 is 2 x 1: [1 3] (texel 1 has one child, x = 2),
 * complete. The hole (odd i = 1) has taps 0 (3/4) and 1 (1/4): 0.75 + 0.75 = 1.5. */
static void test_odd_size(void **state)
{
    (void)state;
    float m[3] = {1.f, HOLE, 3.f}, scratch[3];
    assert_int_equal(iir_pullpush_scratch_floats(3, 1), 2 + 1);
    assert_int_equal(iir_pullpush(m, 3, 1, scratch), 1);
    assert_near(m[1], 0.75f * 1 + 0.25f * 3);
}

/* A complete map: level 0 is complete, nothing is pulled or changed (scratch is not touched). */
static void test_complete_map_unchanged(void **state)
{
    (void)state;
    float m[64], before[64];
    for (int k = 0; k < 64; k++) m[k] = before[k] = 0.25f * (float)(k % 11) + 1.f;
    assert_int_equal(iir_pullpush(m, 8, 8, NULL), 0);
    assert_memory_equal(m, before, sizeof m);
}

/* No defined texel: the pyramid goes up to 1 x 1 (levels 4x4, 2x2, 1x1: 3), which is a hole too,
 * and the map stays all holes. */
static void test_all_holes_stay_holes(void **state)
{
    (void)state;
    float m[64], scratch[21];
    for (int k = 0; k < 64; k++) m[k] = HOLE;
    assert_int_equal(iir_pullpush_scratch_floats(8, 8), 16 + 4 + 1);
    assert_int_equal(iir_pullpush(m, 8, 8, scratch), 3);
    for (int k = 0; k < 64; k++) assert_true(isinf(m[k]) && m[k] > 0.f);
}

/* One defined texel fills the whole map with its value (every level above is that value). */
static void test_single_texel_spreads(void **state)
{
    (void)state;
    float m[64], scratch[21];
    for (int k = 0; k < 64; k++) m[k] = HOLE;
    m[3 * 8 + 5] = 2.5f;
    assert_int_equal(iir_pullpush(m, 8, 8, scratch), 3);
    for (int k = 0; k < 64; k++) assert_near(m[k], 2.5f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fills_holes_from_level_1),
        cmocka_unit_test(test_fills_a_quadrant_from_level_2),
        cmocka_unit_test(test_odd_size),
        cmocka_unit_test(test_complete_map_unchanged),
        cmocka_unit_test(test_all_holes_stay_holes),
        cmocka_unit_test(test_single_texel_spreads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

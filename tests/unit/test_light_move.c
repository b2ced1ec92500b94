/* test_light_move.c -- a moved light stays in the room (core/src/lights/light_move.c): on the
 * built-in Cornell box (walls at x = -1 and 1, floor y = 0, ceiling y = 1.99, open towards +z), a
 * free move is kept as asked, a move through the red wall or the ceiling stops just inside, and a
 * far-away target is clamped into the scene's box. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include "iir/light_move.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "testutil.h"

typedef iir_test_cornell fixture; /* the built-in box and its rays (testutil.h) */

static void test_a_free_move_is_kept(void **state)
{
    fixture *f = *state;
    iir_vec3 to = iir_v3(0.3f, 1.5f, 0.2f);
    iir_vec3 p = iir_light_move_inside(f->scene, f->rt, iir_v3(0.f, 1.5f, 0.f), to);
    assert_true(p.x == to.x && p.y == to.y && p.z == to.z);
}

static void test_a_move_through_the_red_wall_stops_inside(void **state)
{
    fixture *f = *state;
    iir_vec3 p =
        iir_light_move_inside(f->scene, f->rt, iir_v3(0.f, 1.5f, 0.f), iir_v3(-1.11f, 1.5f, 0.f));
    float wall = f->scene->bounds_min.x;
    assert_true(p.x > wall && p.x < wall + 0.05f);
    assert_true(fabsf(p.y - 1.5f) < 1e-4f && fabsf(p.z) < 1e-4f);
}

static void test_a_move_through_the_ceiling_stops_under_it(void **state)
{
    fixture *f = *state;
    iir_vec3 p =
        iir_light_move_inside(f->scene, f->rt, iir_v3(0.2f, 1.8f, 0.1f), iir_v3(0.2f, 2.4f, 0.1f));
    assert_true(p.y < 1.99f && p.y > 1.9f);
}

static void test_a_far_target_is_clamped_into_the_box(void **state)
{
    fixture *f = *state;
    iir_vec3 p = iir_light_move_inside(f->scene, f->rt, iir_v3(0.f, 1.f, 0.5f),
                                       iir_v3(0.f, 1.f, 1e5f)); /* out of the open side */
    float diag = iir_length(iir_sub(f->scene->bounds_max, f->scene->bounds_min));
    assert_true(p.z > f->scene->bounds_max.z && p.z <= f->scene->bounds_max.z + 0.011f * diag);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_a_free_move_is_kept),
        cmocka_unit_test(test_a_move_through_the_red_wall_stops_inside),
        cmocka_unit_test(test_a_move_through_the_ceiling_stops_under_it),
        cmocka_unit_test(test_a_far_target_is_clamped_into_the_box),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

/* test_camera_move.c -- a moved camera keeps its view (core/src/camera_move.c): on the built-in
 * Cornell box (walls at x = -1 and 1, back wall z = -1.04, floor y = 0, ceiling y = 1.99, open
 * towards +z; its camera at z = 3.9 looks in through the opening), an orbit that stays in front of
 * the opening is kept as asked, one that swings the eye behind a wall brings it just inside the
 * room (in front of the farthest wall, in open space), a dolly through the floor stops above it,
 * and a camera that looked at the middle of a closed block is moved as asked; an orbit on from an
 * eye kept behind the tall block (which hides the target) stays in the room too. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include "iir/camera_move.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "testutil.h"

typedef iir_test_cornell fixture; /* the built-in box and its rays (testutil.h) */

/* The box's camera orbited by yaw degrees about the vertical through its target. */
static iir_camera orbited(const fixture *f, float yaw)
{
    iir_camera c = f->scene->camera;
    iir_vec3 off = iir_sub(c.position, c.target);
    float a = iir_radians(yaw), s = sinf(a), co = cosf(a);
    c.position = iir_add(c.target, iir_v3(co * off.x + s * off.z, off.y, -s * off.x + co * off.z));
    return c;
}

static bool same(iir_vec3 a, iir_vec3 b)
{
    return iir_length(iir_sub(a, b)) < 1e-6f;
}

static bool in_room(iir_vec3 p)
{
    return p.x > -1.f && p.x < 1.f && p.y > 0.f && p.y < 1.99f && p.z > -1.04f && p.z < 0.99f;
}

static void test_an_orbit_before_the_opening_is_kept(void **state)
{
    const fixture *f = *state;
    iir_camera home = f->scene->camera, to = orbited(f, 10.f);
    iir_camera got = iir_camera_keep_view(f->scene, f->rt, &home, &to);
    assert_true(same(got.position, to.position) && same(got.target, to.target));
}

static void test_an_orbit_behind_a_wall_stays_in_the_room(void **state)
{
    const fixture *f = *state;
    for (float yaw = 60.f; yaw <= 300.f; yaw += 30.f) {
        iir_camera home = f->scene->camera, to = orbited(f, yaw);
        iir_camera got = iir_camera_keep_view(f->scene, f->rt, &home, &to);
        float r = iir_length(iir_sub(got.position, got.target));
        print_message("yaw %g: eye (%.3f %.3f %.3f), %.3f from the target\n", yaw, got.position.x,
                      got.position.y, got.position.z, r);
        assert_true(in_room(got.position));
        /* on the line from the target to the asked eye, in front of what is in the way */
        iir_vec3 a = iir_normalize(iir_sub(to.position, to.target));
        iir_vec3 b = iir_normalize(iir_sub(got.position, got.target));
        assert_true(iir_dot(a, b) > 0.9999f);
        assert_true(r > 0.5f); /* not pulled onto the target by the tall block next to it */
    }
}

/* An orbit in steps of 10 degrees, each from the camera the last one kept: in the room all the
 * way round, also from an eye the tall block hides the target from. */
static void test_an_orbit_in_steps_stays_in_the_room(void **state)
{
    const fixture *f = *state;
    iir_camera at = f->scene->camera;
    for (float yaw = 10.f; yaw < 360.f; yaw += 10.f) {
        iir_camera to = orbited(f, yaw);
        at = iir_camera_keep_view(f->scene, f->rt, &at, &to);
        if (yaw >= 60.f && yaw <= 300.f && !in_room(at.position))
            fail_msg("yaw %g: eye (%g %g %g) left the room", yaw, at.position.x, at.position.y,
                     at.position.z);
    }
}

static void test_a_dolly_through_the_floor_stops_above_it(void **state)
{
    const fixture *f = *state;
    iir_camera home = f->scene->camera;
    home.position = iir_v3(0.f, 1.f, 0.5f); /* inside, looking back */
    iir_camera to = home;
    to.position = iir_v3(0.f, -2.f, 0.5f);
    iir_camera got = iir_camera_keep_view(f->scene, f->rt, &home, &to);
    assert_true(got.position.y > 0.f && got.position.y < 0.2f);
}

static void test_a_view_into_a_block_moves_as_asked(void **state)
{
    const fixture *f = *state;
    iir_camera home = f->scene->camera;
    home.target = iir_v3(-0.33f, 0.6f, -0.3f); /* inside the tall block */
    iir_camera to = home;
    to.position = iir_v3(-3.f, 1.f, -2.f);
    iir_camera got = iir_camera_keep_view(f->scene, f->rt, &home, &to);
    assert_true(same(got.position, to.position));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_an_orbit_before_the_opening_is_kept),
        cmocka_unit_test(test_an_orbit_behind_a_wall_stays_in_the_room),
        cmocka_unit_test(test_an_orbit_in_steps_stays_in_the_room),
        cmocka_unit_test(test_a_dolly_through_the_floor_stops_above_it),
        cmocka_unit_test(test_a_view_into_a_block_moves_as_asked),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

/* test_anim.c -- animation scripts: keys hit exactly, linear and Catmull-Rom interpolation (C1),
 * held fields, step keys, orbit and sweep paths, frame arithmetic, exposure tracks, the camera's up
 * and the light track's name, several named light tracks (on/off, sun directions, glTF spots,
 * area lights) and their check against a scene's lights, a recording's script, rejection of bad
 * scripts with the field's path in the message, and the shipped Cornell-box paths. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/anim.h"
#include "iir/scene.h"
#include "testutil.h"

static iir_light base_spot(void)
{
    iir_light l = {.type = IIR_LIGHT_SPOT, .name = "spot"};
    l.position = iir_v3(0.f, 1.9f, 0.f);
    l.direction = iir_v3(0.f, -1.f, 0.f);
    l.up = iir_v3(0.f, 0.f, -1.f);
    l.cone_angle = iir_radians(60.f);
    l.intensity = iir_v3(4.f, 3.f, 2.f);
    return l;
}

static iir_anim *parse_ok(const char *json)
{
    iir_anim *a = NULL;
    iir_error err = {0};
    iir_status st = iir_anim_parse(json, "test", &a, &err);
    if (st != IIR_OK) fail_msg("unexpected error: %s", err.msg);
    assert_non_null(a);
    return a;
}

static void assert_near3(iir_vec3 a, iir_vec3 b, float tol)
{
    if (iir_length(iir_sub(a, b)) > tol)
        fail_msg("(%g %g %g) != (%g %g %g)", a.x, a.y, a.z, b.x, b.y, b.z);
}

static const char KEYS3[] =
    "{\"fps\": 10, \"duration\": 4, \"light\": {\"interpolation\": \"%s\", \"keys\": ["
    "{\"t\": 0, \"position\": [0, 1.8, 0], \"cone_angle\": 30, \"intensity\": 2},"
    "{\"t\": 1, \"position\": [1, 1.6, 0], \"cone_angle\": 50},"
    "{\"t\": 3, \"position\": [1, 1.0, 1], \"cone_angle\": 40, \"intensity\": [1, 2, 3]},"
    "{\"t\": 3.5, \"position\": [-1, 1.2, 0.5]}]}}";

static iir_anim *parse_keys3(const char *interp)
{
    char json[1024];
    snprintf(json, sizeof json, KEYS3, interp);
    return parse_ok(json);
}

/* At every key time each field equals the key's value, for both interpolations. */
/* A script may name the scene it was made for (recordings do); only as a string. */
static void test_scene_name(void **state)
{
    (void)state;
    iir_anim *a = parse_ok("{\"duration\": 1, \"scene\": \"cornell_box\"}");
    assert_string_equal(iir_anim_scene(a), "cornell_box");
    iir_anim_destroy(a);
    a = parse_ok("{\"duration\": 1}");
    assert_string_equal(iir_anim_scene(a), "");
    iir_anim_destroy(a);
    iir_error err = {0};
    a = NULL;
    assert_int_equal(iir_anim_parse("{\"duration\": 1, \"scene\": 3}", "t", &a, &err),
                     IIR_ERR_FORMAT);
    assert_non_null(strstr(err.msg, "scene"));
    assert_null(a);
}

/* A script may name the scenes folder and the frame size it was made at (recordings do): a string,
 * and two whole numbers of pixels in [1, 16384]. */
static void test_scenes_and_size(void **state)
{
    (void)state;
    int w = 7, h = 7;
    iir_anim *a = parse_ok("{\"duration\": 1, \"scenes\": \"/data/scenes\", \"size\": [512, 384]}");
    assert_string_equal(iir_anim_scenes_dir(a), "/data/scenes");
    assert_true(iir_anim_size(a, &w, &h) && w == 512 && h == 384);
    iir_anim_destroy(a);
    a = parse_ok("{\"duration\": 1}");
    assert_string_equal(iir_anim_scenes_dir(a), "");
    assert_false(iir_anim_size(a, &w, &h));
    assert_true(w == 512 && h == 384); /* unchanged */
    iir_anim_destroy(a);
    static const struct {
        const char *json, *path;
        iir_status st;
    } bad[] = {
        {"{\"duration\": 1, \"scenes\": 3}", "scenes", IIR_ERR_FORMAT},
        {"{\"duration\": 1, \"size\": 512}", "size", IIR_ERR_FORMAT},
        {"{\"duration\": 1, \"size\": [512]}", "size", IIR_ERR_FORMAT},
        {"{\"duration\": 1, \"size\": [512, \"384\"]}", "size", IIR_ERR_FORMAT},
        {"{\"duration\": 1, \"size\": [0, 384]}", "size[0]", IIR_ERR_INVALID},
        {"{\"duration\": 1, \"size\": [512, 384.5]}", "size[1]", IIR_ERR_INVALID},
        {"{\"duration\": 1, \"size\": [512, 16385]}", "size[1]", IIR_ERR_INVALID},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        iir_error err = {0};
        a = NULL;
        assert_int_equal(iir_anim_parse(bad[i].json, "t", &a, &err), bad[i].st);
        if (!strstr(err.msg, bad[i].path)) fail_msg("%s: %s", bad[i].json, err.msg);
        assert_null(a);
    }
}

static void test_keys_hit_exactly(void **state)
{
    (void)state;
    const char *modes[] = {"linear", "catmull-rom"};
    const iir_vec3 pos[] = {{0, 1.8f, 0}, {1, 1.6f, 0}, {1, 1.0f, 1}, {-1, 1.2f, 0.5f}};
    const double t[] = {0, 1, 3, 3.5};
    iir_light base = base_spot();
    for (int m = 0; m < 2; m++) {
        iir_anim *a = parse_keys3(modes[m]);
        for (int k = 0; k < 4; k++) {
            iir_light L = iir_anim_light(a, &base, t[k]);
            assert_near3(L.position, pos[k], 1e-5f);
        }
        assert_float_equal(iir_anim_light(a, &base, 1.0).cone_angle, iir_radians(50.f), 1e-5f);
        assert_near3(iir_anim_light(a, &base, 3.0).intensity, iir_v3(1, 2, 3), 1e-5f);
        iir_anim_destroy(a);
    }
}

/* Linear interpolation: the midpoint of a segment is the mean of its keys; before the first key
 * the first holds, after the last the last. */
static void test_linear_midpoints(void **state)
{
    (void)state;
    iir_light base = base_spot();
    iir_anim *a = parse_keys3("linear");
    assert_near3(iir_anim_light(a, &base, 0.5).position, iir_v3(0.5f, 1.7f, 0.f), 1e-5f);
    assert_near3(iir_anim_light(a, &base, 2.0).position, iir_v3(1.f, 1.3f, 0.5f), 1e-5f);
    assert_float_equal(iir_anim_light(a, &base, 0.5).cone_angle, iir_radians(40.f), 1e-5f);
    assert_near3(iir_anim_light(a, &base, 3.9).position, iir_v3(-1, 1.2f, 0.5f), 1e-6f);
    assert_near3(iir_anim_light(a, &base, -5.0).position, iir_v3(0, 1.8f, 0), 1e-6f);
    iir_anim_destroy(a);
}

/* Catmull-Rom passes through its keys (above), its velocity is continuous across interior keys
 * (finite differences from both sides agree), and with two keys it equals linear. */
static void test_catmull_rom_c1(void **state)
{
    (void)state;
    iir_light base = base_spot();
    iir_anim *a = parse_keys3("catmull-rom");
    const double keys[] = {1.0, 3.0};
    const double h = 1e-3;
    for (int k = 0; k < 2; k++) {
        iir_vec3 p0 = iir_anim_light(a, &base, keys[k] - h).position;
        iir_vec3 p1 = iir_anim_light(a, &base, keys[k]).position;
        iir_vec3 p2 = iir_anim_light(a, &base, keys[k] + h).position;
        iir_vec3 v_left = iir_scale(iir_sub(p1, p0), (float)(1.0 / h));
        iir_vec3 v_right = iir_scale(iir_sub(p2, p1), (float)(1.0 / h));
        assert_near3(v_left, v_right, 0.05f);
    }
    iir_anim_destroy(a);

    const char *two = "{\"duration\": 2, \"light\": {\"interpolation\": \"%s\", \"keys\": ["
                      "{\"t\": 0.5, \"position\": [0, 1.8, 0]},"
                      "{\"t\": 1.5, \"position\": [0.6, 1.2, -0.4]}]}}";
    char json[512];
    snprintf(json, sizeof json, two, "catmull-rom");
    iir_anim *cr = parse_ok(json);
    snprintf(json, sizeof json, two, "linear");
    iir_anim *lin = parse_ok(json);
    for (double t = 0.0; t <= 2.0; t += 0.125)
        assert_near3(iir_anim_light(cr, &base, t).position, iir_anim_light(lin, &base, t).position,
                     1e-5f);
    iir_anim_destroy(cr);
    iir_anim_destroy(lin);
}

/* A field missing from a key is interpolated between the keys that give it; one no key gives
 * stays the base light's. */
static void test_held_fields(void **state)
{
    (void)state;
    iir_light base = base_spot();
    iir_anim *a = parse_keys3("linear");
    /* intensity given at t=0 (2) and t=3 ([1,2,3]); at t=1.5 halfway */
    assert_near3(iir_anim_light(a, &base, 1.5).intensity, iir_v3(1.5f, 2.f, 2.5f), 1e-5f);
    /* intensity held after its last key, cone held after t=3 */
    assert_near3(iir_anim_light(a, &base, 3.5).intensity, iir_v3(1, 2, 3), 1e-6f);
    assert_float_equal(iir_anim_light(a, &base, 3.5).cone_angle, iir_radians(40.f), 1e-6f);
    /* no key aims the light: the base direction */
    assert_near3(iir_anim_light(a, &base, 2.0).direction, base.direction, 0.f);
    iir_anim_destroy(a);

    a = parse_ok("{\"duration\": 1, \"light\": {\"keys\": [{\"t\": 0.5, \"cone_angle\": 20}]}}");
    iir_light L = iir_anim_light(a, &base, 0.7);
    assert_near3(L.position, base.position, 0.f);
    assert_near3(L.intensity, base.intensity, 0.f);
    assert_float_equal(L.cone_angle, iir_radians(20.f), 1e-6f);
    assert_false(iir_anim_has_camera(a));
    iir_camera cam = {iir_v3(0, 1, 3.9f), iir_v3(0, 1, 0), iir_v3(0, 1, 0), 39.3f};
    iir_camera c2 = iir_anim_camera(a, &cam, 0.5);
    assert_memory_equal(&c2, &cam, sizeof cam);
    iir_anim_destroy(a);
}

/* "step": true jumps at its key; "interpolation": "step" jumps at every key. */
static void test_step_keys(void **state)
{
    (void)state;
    iir_light base = base_spot();
    iir_anim *a = parse_ok("{\"duration\": 3, \"light\": {\"keys\": ["
                           "{\"t\": 0, \"position\": [0, 1.8, 0]},"
                           "{\"t\": 1, \"position\": [0.5, 1.8, 0]},"
                           "{\"t\": 2, \"position\": [-0.5, 1.0, 0.5], \"step\": true}]}}");
    assert_near3(iir_anim_light(a, &base, 0.5).position, iir_v3(0.25f, 1.8f, 0), 1e-5f);
    assert_near3(iir_anim_light(a, &base, 1.999).position, iir_v3(0.5f, 1.8f, 0), 0.f);
    assert_near3(iir_anim_light(a, &base, 2.0).position, iir_v3(-0.5f, 1.0f, 0.5f), 0.f);
    iir_anim_destroy(a);

    a = parse_ok("{\"duration\": 3, \"light\": {\"interpolation\": \"step\", \"keys\": ["
                 "{\"t\": 0, \"intensity\": 1}, {\"t\": 1, \"intensity\": 5}]}}");
    assert_near3(iir_anim_light(a, &base, 0.99).intensity, iir_v3s(1.f), 0.f);
    assert_near3(iir_anim_light(a, &base, 1.0).intensity, iir_v3s(5.f), 0.f);
    iir_anim_destroy(a);
}

/* Orbit: on the circle at t = 0 and half-way (opposite points for one turn), at the radius
 * everywhere, aiming at its target. Sweep: its endpoints at 0 and duration. */
static void test_orbit_and_sweep(void **state)
{
    (void)state;
    iir_light base = base_spot();
    iir_anim *a = parse_ok("{\"fps\": 30, \"duration\": 6, \"light\": {\"orbit\": {"
                           "\"center\": [0, 1.9, 0], \"radius\": 0.5, \"turns\": 1, "
                           "\"target\": [0, 0, 0]}}}");
    iir_vec3 c = iir_v3(0, 1.9f, 0);
    assert_near3(iir_anim_light(a, &base, 0.0).position, iir_v3(0.5f, 1.9f, 0), 1e-5f);
    assert_near3(iir_anim_light(a, &base, 3.0).position, iir_v3(-0.5f, 1.9f, 0), 1e-5f);
    for (double t = 0.0; t <= 6.0; t += 0.37) {
        iir_light L = iir_anim_light(a, &base, t);
        assert_float_equal(iir_length(iir_sub(L.position, c)), 0.5f, 1e-5f);
        assert_float_equal(L.position.y, 1.9f, 1e-6f);
        assert_near3(L.direction, iir_normalize(iir_neg(L.position)), 1e-5f);
    }
    iir_anim_destroy(a);

    a = parse_ok("{\"fps\": 30, \"duration\": 2, \"light\": {\"sweep\": {\"from\": [-0.8, 1.8, "
                 "0], \"to\": [0.8, 1.8, 0], \"target\": [0, 0, 0]}}}");
    assert_near3(iir_anim_light(a, &base, 0.0).position, iir_v3(-0.8f, 1.8f, 0), 1e-6f);
    assert_near3(iir_anim_light(a, &base, 2.0).position, iir_v3(0.8f, 1.8f, 0), 1e-6f);
    assert_near3(iir_anim_light(a, &base, 1.0).position, iir_v3(0.f, 1.8f, 0), 1e-6f);
    iir_anim_destroy(a);
}

/* Target keys aim at the target; direction keys are normalised; the camera track moves the
 * camera. */
static void test_aim_and_camera(void **state)
{
    (void)state;
    iir_light base = base_spot();
    iir_anim *a = parse_ok(
        "{\"duration\": 2, \"light\": {\"keys\": ["
        "{\"t\": 0, \"position\": [0.5, 1.5, 0], \"target\": [0.5, 0, 0]},"
        "{\"t\": 2, \"direction\": [0, 0, 3]}]},"
        "\"camera\": {\"keys\": [{\"t\": 0, \"position\": [0, 1, 3.9], \"fov_y\": 30},"
        "{\"t\": 2, \"position\": [0, 1, 2.9], \"target\": [0, 0.5, 0], \"fov_y\": 50}]}}");
    assert_near3(iir_anim_light(a, &base, 0.0).direction, iir_v3(0, -1, 0), 1e-6f);
    assert_near3(iir_anim_light(a, &base, 2.0).direction, iir_v3(0, 0, 1), 1e-6f);
    assert_near3(iir_anim_light(a, &base, 1.0).direction, iir_normalize(iir_v3(0, -1, 1)), 1e-5f);
    iir_camera cam = {iir_v3(0, 1, 3.9f), iir_v3(0, 1, 0), iir_v3(0, 1, 0), 39.3f};
    assert_true(iir_anim_has_camera(a));
    iir_camera c1 = iir_anim_camera(a, &cam, 1.0);
    assert_near3(c1.position, iir_v3(0, 1, 3.4f), 1e-5f);
    assert_near3(c1.target, iir_v3(0, 0.5f, 0), 1e-6f); /* only key: held */
    assert_float_equal(c1.fov_y, 40.f, 1e-4f);
    assert_int_equal(iir_camera_validate(&c1, NULL), IIR_OK);
    iir_anim_destroy(a);
}

/* Exposure: a number is a constant; keys follow the track's interpolation (a recording's step
 * track holds each value until the next key); without one, the base. */
static void test_exposure(void **state)
{
    (void)state;
    iir_anim *a = parse_ok("{\"duration\": 2}");
    assert_false(iir_anim_has_exposure(a));
    assert_float_equal(iir_anim_exposure(a, 0.5f, 1.0), 0.5f, 0.f);
    iir_anim_destroy(a);
    a = parse_ok("{\"duration\": 2, \"exposure\": -1.5}");
    assert_true(iir_anim_has_exposure(a));
    assert_float_equal(iir_anim_exposure(a, 0.f, 0.0), -1.5f, 0.f);
    assert_float_equal(iir_anim_exposure(a, 0.f, 2.0), -1.5f, 0.f);
    iir_anim_destroy(a);
    const char *json = "{\"duration\": 2, \"exposure\": {\"interpolation\": \"%s\", \"keys\": ["
                       "{\"t\": 0, \"stops\": 0}, {\"t\": 1, \"stops\": 2}]}}";
    char buf[256];
    snprintf(buf, sizeof buf, json, "step");
    a = parse_ok(buf);
    assert_float_equal(iir_anim_exposure(a, 9.f, 0.0), 0.f, 0.f);
    assert_float_equal(iir_anim_exposure(a, 9.f, 0.999), 0.f, 0.f);
    assert_float_equal(iir_anim_exposure(a, 9.f, 1.0), 2.f, 0.f);
    assert_float_equal(iir_anim_exposure(a, 9.f, 5.0), 2.f, 0.f);
    assert_false(iir_anim_has_light(a) || iir_anim_has_camera(a));
    iir_anim_destroy(a);
    snprintf(buf, sizeof buf, json, "linear");
    a = parse_ok(buf);
    assert_float_equal(iir_anim_exposure(a, 9.f, 0.5), 1.f, 1e-6f);
    iir_anim_destroy(a);
}

/* A camera key may give up (interpolated, any length, the base's when absent); the light track
 * may name the light it moves. */
static void test_camera_up_and_light_name(void **state)
{
    (void)state;
    iir_anim *a =
        parse_ok("{\"duration\": 2, \"light\": {\"name\": \"desk lamp\", \"keys\": [{\"t\": 0}]},"
                 "\"camera\": {\"keys\": [{\"t\": 0, \"up\": [0, 2, 0]}, {\"t\": 1, \"fov_y\": 40},"
                 "{\"t\": 2, \"up\": [2, 0, 0]}]}}");
    assert_string_equal(iir_anim_light_name(a), "desk lamp");
    iir_camera cam = {iir_v3(0, 1, 3.9f), iir_v3(0, 1, 0), iir_v3(0, 0, 1), 39.3f};
    assert_near3(iir_anim_camera(a, &cam, 0.0).up, iir_v3(0, 2, 0), 0.f);
    assert_near3(iir_anim_camera(a, &cam, 1.0).up, iir_v3(1, 1, 0), 1e-6f);
    assert_near3(iir_anim_camera(a, &cam, 2.0).up, iir_v3(2, 0, 0), 0.f);
    iir_anim_destroy(a);
    a = parse_ok("{\"duration\": 2, \"camera\": {\"keys\": [{\"t\": 0, \"fov_y\": 30}]}}");
    assert_string_equal(iir_anim_light_name(a), "");
    assert_near3(iir_anim_camera(a, &cam, 1.0).up, iir_v3(0, 0, 1), 0.f);
    iir_anim_destroy(a);
}

/* A recording's script (what iird serve's `record` writes) replays its keys exactly: linear light
 * and camera tracks whose key after a pause is a step key, a step exposure track. */
static void test_recorded_script(void **state)
{
    (void)state;
    iir_anim *a = parse_ok(
        "{\"scene\": \"builtin\", \"fps\": 5, \"duration\": 1.6,"
        "\"light\": {\"name\": \"spot\", \"interpolation\": \"linear\", \"keys\": ["
        "{\"t\": 0, \"position\": [0, 1.9, 0], \"direction\": [0, -1, 0], \"cone_angle\": 60,"
        "\"smooth\": 0, \"intensity\": [4.0482664, 2.8575997, 0.95253325]},"
        "{\"t\": 0.501097, \"step\": true, \"position\": [0.3, 1.7, 0.2],"
        "\"direction\": [0, -1, 0], \"cone_angle\": 45, \"smooth\": 0, \"intensity\": [4, 2, 1]},"
        "{\"t\": 0.532105, \"position\": [0.4, 1.7, 0.2]}]},"
        "\"camera\": {\"interpolation\": \"linear\", \"keys\": ["
        "{\"t\": 0, \"position\": [0, 1, 3.9], \"target\": [0, 1, 0], \"up\": [0, 1, 0],"
        "\"fov_y\": 39.3}]},"
        "\"exposure\": {\"interpolation\": \"step\", \"keys\": [{\"t\": 0, \"stops\": 0},"
        "{\"t\": 1.2, \"stops\": 1.5}]}}");
    iir_light base = base_spot();
    iir_light first = iir_anim_light(a, &base, iir_anim_frame_time(a, 0));
    iir_light last = iir_anim_light(a, &base, iir_anim_frame_time(a, iir_anim_frame_count(a) - 1));
    assert_int_equal(iir_anim_frame_count(a), 9);
    assert_true(first.position.x == 0.f && first.position.y == 1.9f);
    assert_true(first.cone_angle == iir_radians(60.f));
    assert_true(last.position.x == 0.4f && last.position.z == 0.2f);
    assert_true(last.intensity.x == 4.f && last.intensity.z == 1.f);
    /* held through the pause, not drifting from t = 0; the key itself is hit exactly */
    assert_true(iir_anim_light(a, &base, 0.5).position.x == 0.f);
    assert_true(iir_anim_light(a, &base, 0.501097).position.x == 0.3f);
    assert_float_equal(iir_anim_light(a, &base, 0.516601).position.x, 0.35f, 1e-4f);
    assert_float_equal(iir_anim_exposure(a, 0.f, iir_anim_frame_time(a, 5)), 0.f, 0.f);
    assert_float_equal(iir_anim_exposure(a, 0.f, iir_anim_frame_time(a, 6)), 1.5f, 0.f);
    iir_anim_destroy(a);
}

/* ======================== several lights ======================== */

/* A spot (the moved light), a point lamp, a sun, a glTF spot, an area light and a spare point. */
static void scene_lights(iir_light L[6])
{
    L[0] = base_spot();
    L[1] = (iir_light){.type = IIR_LIGHT_POINT, .name = "lamp"};
    L[1].position = iir_v3(0.5f, 1.f, 0.f);
    L[1].intensity = iir_v3s(2.f);
    L[2] = (iir_light){.type = IIR_LIGHT_SUN, .name = "sun", .radius = 3.f};
    L[2].position = iir_v3(0.f, 1.f, 0.f);
    L[2].direction = iir_normalize(iir_v3(1.f, -1.f, 0.f));
    L[2].up = iir_v3(0.f, 1.f, 0.f);
    L[2].intensity = iir_v3s(5.f);
    L[3] = base_spot();
    snprintf(L[3].name, sizeof L[3].name, "gltf");
    L[3].profile = IIR_SPOT_GLTF;
    L[3].inner_angle = iir_radians(10.f);
    L[4] = (iir_light){.type = IIR_LIGHT_AREA, .name = "panel", .size = {0.4f, 0.3f}};
    L[4].position = iir_v3(0.f, 1.98f, 0.f);
    L[4].direction = iir_v3(0.f, -1.f, 0.f);
    L[4].up = iir_v3(0.f, 0.f, 1.f);
    L[4].intensity = iir_v3s(10.f);
    L[5] = L[1];
    snprintf(L[5].name, sizeof L[5].name, "spare");
}

static const char SEVERAL[] =
    "{\"duration\": 4, \"light\": {\"keys\": [{\"t\": 0, \"position\": [0, 1.5, 0]}]},"
    "\"lights\": ["
    "{\"name\": \"lamp\", \"interpolation\": \"linear\", \"keys\": ["
    "  {\"t\": 0, \"position\": [0, 1, 0]}, {\"t\": 2, \"position\": [1, 1, 0], \"on\": false},"
    "  {\"t\": 3, \"on\": true, \"intensity\": 4}]},"
    "{\"name\": \"sun\", \"keys\": [{\"t\": 0, \"direction\": [1, -1, 0]},"
    "  {\"t\": 4, \"direction\": [-1, -1, 0]}]},"
    "{\"name\": \"gltf\", \"keys\": [{\"t\": 0, \"inner_angle\": 20, \"cone_angle\": 40},"
    "  {\"t\": 4, \"inner_angle\": 60}]},"
    "{\"name\": \"panel\", \"keys\": [{\"t\": 0, \"size\": [1, 2], \"up\": [1, 0, 0]},"
    "  {\"t\": 2, \"size\": [3, 2], \"on\": false}]}]}";

/* Named tracks move their lights (the light track the moved one), on/off steps at its keys (on
 * before the first key that gives it), a sun turns but keeps its disk, a glTF spot's inner cone
 * stays inside its cone, an area light resizes; unnamed lights keep their pose; in place works. */
static void test_several_lights(void **state)
{
    (void)state;
    iir_light L[6], out[6];
    scene_lights(L);
    iir_anim *a = parse_ok(SEVERAL);
    assert_int_equal(iir_anim_num_light_tracks(a), 4);
    assert_string_equal(iir_anim_light_track_name(a, 3), "panel");
    assert_null(iir_anim_light_track_name(a, 4));
    iir_error err = {0};
    if (iir_anim_check_lights(a, L, 6, 0, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_anim_lights(a, L, 6, 0, 1.0, out);
    assert_near3(out[0].position, iir_v3(0, 1.5f, 0), 0.f);
    assert_near3(out[1].position, iir_v3(0.5f, 1, 0), 1e-6f);
    /* on (no key before gives "on"), at the first intensity key's value (held before it) */
    assert_near3(out[1].intensity, iir_v3s(4.f), 0.f);
    assert_near3(out[2].direction, iir_normalize(iir_v3(0.5f, -1.f, 0.f)), 1e-6f);
    assert_near3(out[2].position, L[2].position, 0.f);
    assert_float_equal(out[2].radius, 3.f, 0.f);
    assert_float_equal(out[3].inner_angle, iir_radians(30.f), 1e-6f); /* 20 -> 60 over 4 s */
    assert_float_equal(out[3].cone_angle, iir_radians(40.f), 1e-6f);
    assert_float_equal(out[4].size.x, 2.f, 1e-6f);
    assert_near3(out[4].up, iir_v3(1, 0, 0), 0.f);
    assert_memory_equal(&out[5], &L[5], sizeof L[5]);
    iir_anim_lights(a, L, 6, 0, 2.0, out); /* off from t = 2 */
    assert_near3(out[1].intensity, iir_v3s(0.f), 0.f);
    assert_near3(out[4].intensity, iir_v3s(0.f), 0.f);
    assert_near3(out[1].position, iir_v3(1, 1, 0), 0.f);
    iir_anim_lights(a, L, 6, 0, 2.999, out);
    assert_near3(out[1].intensity, iir_v3s(0.f), 0.f);
    iir_anim_lights(a, L, 6, 0, 3.0, out); /* back on, at the key's intensity */
    assert_near3(out[1].intensity, iir_v3s(4.f), 0.f);
    iir_anim_lights(a, L, 6, 0, 4.0, out);
    assert_float_equal(out[3].inner_angle, out[3].cone_angle, 0.f); /* 60 > cone 40: clamped */
    assert_near3(out[2].direction, iir_normalize(iir_v3(-1, -1, 0)), 1e-6f);
    for (int i = 0; i < 4; i++)
        if (iir_light_validate(&out[i], &err) != IIR_OK) fail_msg("light %d: %s", i, err.msg);
    memcpy(out, L, sizeof out); /* in place */
    iir_anim_lights(a, out, 6, 0, 4.0, out);
    assert_near3(out[2].direction, iir_normalize(iir_v3(-1, -1, 0)), 1e-6f);
    /* without a light track, a "lights" track may move the moved light */
    iir_anim *b = parse_ok("{\"duration\": 1, \"lights\": [{\"name\": \"spot\", \"keys\": ["
                           "{\"t\": 0, \"position\": [0.1, 1, 0]}]}]}");
    assert_int_equal(iir_anim_check_lights(b, L, 6, 0, &err), IIR_OK);
    iir_anim_lights(b, L, 6, 0, 0.5, out);
    assert_near3(out[0].position, iir_v3(0.1f, 1, 0), 0.f);
    iir_anim_destroy(b);
    /* no light track moved: the light track is not applied */
    iir_anim_lights(a, L, 6, 6, 1.0, out);
    assert_memory_equal(&out[0], &L[0], sizeof L[0]);
    iir_anim_destroy(a);
}

/* A sun's track aims it: an orbit with a target turns its direction towards the target (a day
 * across the sky), never moving its disk; the light track may switch its light off too. */
static void test_sun_paths(void **state)
{
    (void)state;
    iir_light L[6], out[6];
    scene_lights(L);
    iir_anim *a = parse_ok(
        "{\"duration\": 2, \"light\": {\"keys\": [{\"t\": 1, \"on\": false}]},"
        "\"lights\": [{\"name\": \"sun\", \"orbit\": {\"center\": [0, 0, 0], \"radius\": 10,"
        "\"turns\": 0.5, \"target\": [0, 0, 0]}}]}");
    iir_error err = {0};
    if (iir_anim_check_lights(a, L, 6, 0, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_anim_lights(a, L, 6, 0, 0.0, out);
    assert_near3(out[2].direction, iir_v3(-1, 0, 0), 1e-6f); /* from (10, 0, 0) to the origin */
    assert_near3(out[0].intensity, L[0].intensity, 0.f);
    iir_anim_lights(a, L, 6, 0, 1.0, out);
    assert_near3(out[2].direction, iir_v3(0, 0, -1), 1e-5f); /* from (0, 0, 10) */
    assert_near3(out[2].position, L[2].position, 0.f);
    assert_near3(out[0].intensity, iir_v3s(0.f), 0.f);
    iir_anim_destroy(a);
}

typedef struct check_case {
    const char *json, *needle;
} check_case;

#define NAMED(name, k)                                                                             \
    "{\"duration\": 5, \"lights\": [{\"name\": \"" name "\", \"keys\": [" k "]}]}"

static const check_case CHECK_BAD[] = {
    {NAMED("lmap", "{\"t\": 0}"),
     "no light named 'lmap' (its lights: spot, lamp, sun, gltf, panel, "
     "spare, lamp2)"},
    {NAMED("twin", "{\"t\": 0}"), "several lights named 'twin'"},
    {"{\"duration\": 5, \"light\": {\"keys\": [{\"t\": 0}]}, \"lights\": [{\"name\": \"spot\","
     "\"keys\": [{\"t\": 0}]}]}",
     "lights[0].name: 'spot' is the light the \"light\" track moves"},
    {NAMED("lamp", "{\"t\": 0},{\"t\": 1, \"cone_angle\": 30}"),
     "lights[0].keys[1].cone_angle: light 'lamp' is a point light"},
    {NAMED("sun", "{\"t\": 0, \"cone_angle\": 30}"), "lights[0].keys[0].cone_angle"},
    {NAMED("spot", "{\"t\": 0, \"inner_angle\": 30}"), "lights[0].keys[0].inner_angle"},
    {NAMED("gltf", "{\"t\": 0, \"smooth\": 3}"), "lights[0].keys[0].smooth"},
    {NAMED("spot", "{\"t\": 0, \"size\": [1, 1]}"), "lights[0].keys[0].size"},
    {NAMED("sun", "{\"t\": 0, \"position\": [0, 5, 0]}"), "lights[0].keys[0]: 'sun' is a sun"},
    {"{\"duration\": 5, \"lights\": [{\"name\": \"sun\", \"sweep\": {\"from\": [0, 5, 0],"
     "\"to\": [1, 5, 0]}}]}",
     "lights[0].sweep: 'sun' is a sun"},
    {"{\"duration\": 5, \"light\": {\"keys\": [{\"t\": 0, \"size\": [1, 1]}]}}",
     "light.keys[0].size: light 'spot' is a cosine spot"},
};

/* A script that does not fit the scene's lights is refused once they are known, with the
 * script's name, the field's path and what would fit. */
static void test_check_lights(void **state)
{
    (void)state;
    iir_light L[8];
    scene_lights(L);
    L[6] = L[1];
    snprintf(L[6].name, sizeof L[6].name, "lamp2");
    L[7] = L[1];
    snprintf(L[7].name, sizeof L[7].name, "twin");
    iir_light twins[2] = {L[7], L[7]};
    for (size_t i = 0; i < sizeof CHECK_BAD / sizeof CHECK_BAD[0]; i++) {
        iir_anim *a = NULL;
        iir_error err = {0};
        if (iir_anim_parse(CHECK_BAD[i].json, "x.json", &a, &err) != IIR_OK)
            fail_msg("case %zu: %s", i, err.msg);
        bool two = strstr(CHECK_BAD[i].json, "twin") != NULL;
        iir_status st = two ? iir_anim_check_lights(a, twins, 2, 2, &err)
                            : iir_anim_check_lights(a, L, 7, 0, &err);
        assert_int_equal(st, IIR_ERR_INVALID);
        if (!strstr(err.msg, CHECK_BAD[i].needle) || strncmp(err.msg, "x.json: ", 8) != 0)
            fail_msg("case %zu: message '%s' lacks '%s'", i, err.msg, CHECK_BAD[i].needle);
        iir_anim_destroy(a);
    }
    /* a scene without lights: the made-up spot may be named; the list says there are none */
    iir_anim *a = parse_ok(NAMED("spot", "{\"t\": 0, \"cone_angle\": 30}"));
    iir_error err = {0};
    assert_int_equal(iir_anim_check_lights(a, L, 1, 0, &err), IIR_OK);
    iir_anim_destroy(a);
    a = parse_ok(NAMED("lamp", "{\"t\": 0}"));
    assert_int_equal(iir_anim_check_lights(a, NULL, 0, 0, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "(it has no lights)"));
    iir_anim_destroy(a);
}

/* floor(duration * fps) + 1 frames at frame / fps, clamped. */
static void test_frames(void **state)
{
    (void)state;
    iir_anim *a = parse_ok("{\"fps\": 30, \"duration\": 2}");
    assert_int_equal(iir_anim_frame_count(a), 61);
    assert_float_equal(iir_anim_frame_time(a, 0), 0.0, 0.0);
    assert_float_equal(iir_anim_frame_time(a, 15), 0.5, 1e-12);
    assert_float_equal(iir_anim_frame_time(a, 60), 2.0, 1e-12);
    assert_float_equal(iir_anim_frame_time(a, 99), 2.0, 1e-12);
    assert_false(iir_anim_has_light(a));
    iir_anim_destroy(a);
    a = parse_ok("{\"fps\": 30, \"duration\": 6.67}");
    assert_int_equal(iir_anim_frame_count(a), 201);
    iir_anim_destroy(a);
    a = parse_ok("{\"duration\": 0.01}"); /* default 30 fps */
    assert_int_equal(iir_anim_frame_count(a), 1);
    iir_anim_destroy(a);
}

typedef struct bad_case {
    const char *json, *needle;
} bad_case;

#define LK(k) "{\"duration\": 5, \"light\": {\"keys\": [" k "]}}"

static const bad_case BAD[] = {
    {"{\"duration\": 5, \"lite\": {}}", "lite"},
    {LK("{\"t\": 0},{\"t\": 1},{\"t\": 2, \"postion\": [0,1,0]}"), "light.keys[2].postion"},
    {"{\"duration\": 5, \"light\": {\"orbit\": {\"center\": [0,1,0], \"radius\": 1, "
     "\"spin\": 2}}}",
     "light.orbit.spin"},
    {"{\"duration\": 5, \"camera\": {\"keys\": [{\"t\": 0, \"cone_angle\": 30}]}}",
     "camera.keys[0].cone_angle"},
    {LK("{\"t\": 0, \"position\": [0, \"a\", 0]}"), "light.keys[0].position"},
    {LK("{\"t\": 0, \"position\": [0, 1]}"), "light.keys[0].position"},
    {LK("{\"t\": \"0\"}"), "light.keys[0].t"},
    {LK("{\"t\": 0, \"step\": 1}"), "light.keys[0].step"},
    {LK("{\"t\": 0, \"position\": [0, 1e400, 0]}"), "light.keys[0].position"},
    {LK("{\"t\": 0, \"position\": [0, 1e300, 0]}"), "light.keys[0].position"},
    {LK("{\"t\": 0, \"intensity\": 1e400}"), "light.keys[0].intensity"},
    {LK("{\"t\": 0, \"intensity\": -1}"), "light.keys[0].intensity"},
    {LK("{\"t\": 1e400}"), "light.keys[0].t"},
    {LK("{\"t\": 1},{\"t\": 1}"), "light.keys[1].t"},
    {LK("{\"t\": 2},{\"t\": 1}"), "light.keys[1].t"},
    {LK("{\"t\": -0.5}"), "light.keys[0].t"},
    {LK("{\"t\": 6}"), "light.keys[0].t"},
    {LK("{\"position\": [0, 1, 0]}"), "light.keys[0].t"},
    {"{\"fps\": 0, \"duration\": 5}", "fps"},
    {"{\"fps\": 1001, \"duration\": 5}", "fps"},
    {"{\"fps\": 30, \"duration\": 0}", "duration"},
    {"{\"fps\": 30, \"duration\": 36001}", "duration"},
    {"{\"fps\": 30, \"duration\": 1e400}", "duration"},
    {"{\"fps\": 30}", "duration"},
    {LK("{\"t\": 0, \"cone_angle\": 0}"), "light.keys[0].cone_angle"},
    {LK("{\"t\": 0, \"cone_angle\": 91}"), "light.keys[0].cone_angle"},
    {LK("{\"t\": 0, \"cone_angle\": 30, \"smooth\": 40}"), "light.keys[0].smooth"},
    {LK("{\"t\": 0, \"direction\": [0, 0, 0]}"), "light.keys[0].direction"},
    {LK("{\"t\": 0, \"direction\": [0, -1, 0], \"target\": [0, 0, 0]}"), "light.keys[0].direction"},
    {LK("{\"t\": 0, \"position\": [0, 1, 0], \"target\": [0, 1, 0]}"), "light.keys[0].target"},
    {"{\"duration\": 5, \"light\": {\"keys\": []}}", "light.keys"},
    {"{\"duration\": 5, \"light\": {\"interpolation\": \"cubic\", \"keys\": [{\"t\": 0}]}}",
     "light.interpolation"},
    {"{\"duration\": 5, \"light\": {\"orbit\": {\"center\": [0,1,0]}}}", "light.orbit.radius"},
    {"{\"duration\": 5, \"light\": {\"orbit\": {\"center\": [0,1,0], \"radius\": -1}}}",
     "light.orbit.radius"},
    {"{\"duration\": 5, \"light\": {\"sweep\": {\"from\": [0,1,0]}}}", "light.sweep.to"},
    {"{\"duration\": 5, \"light\": {\"keys\": [{\"t\": 0}], \"sweep\": {}}}", "light"},
    {"{\"duration\": 5, \"light\": [1]}", "light"},
    {"{\"duration\": 5, \"camera\": {\"keys\": [{\"t\": 0, \"fov_y\": 180}]}}",
     "camera.keys[0].fov_y"},
    {"{\"duration\": 5, \"camera\": {\"keys\": [{\"t\": 0, \"up\": [0, 0, 0]}]}}",
     "camera.keys[0].up"},
    {"{\"duration\": 5, \"camera\": {\"name\": \"cam\", \"keys\": [{\"t\": 0}]}}", "camera.name"},
    {"{\"duration\": 5, \"light\": {\"name\": 3, \"keys\": [{\"t\": 0}]}}", "light.name"},
    {"{\"duration\": 5, \"light\": {\"name\": \"\", \"keys\": [{\"t\": 0}]}}", "light.name"},
    {"{\"duration\": 5, \"exposure\": 31}", "exposure"},
    {"{\"duration\": 5, \"exposure\": \"1\"}", "exposure"},
    {"{\"duration\": 5, \"exposure\": {\"keys\": [{\"t\": 0, \"stops\": -31}]}}",
     "exposure.keys[0].stops"},
    {"{\"duration\": 5, \"exposure\": {\"keys\": [{\"t\": 0, \"position\": [0, 1, 0]}]}}",
     "exposure.keys[0].position"},
    {"{\"duration\": 5, \"exposure\": {\"orbit\": {\"center\": [0, 1, 0], \"radius\": 1}}}",
     "exposure.orbit"},
    {"{\"duration\": 5, \"exposure\": {}}", "exposure"},
    {"{\"duration\": 5, \"lights\": {}}", "lights"},
    {"{\"duration\": 5, \"lights\": [{\"keys\": [{\"t\": 0}]}]}", "lights[0].name"},
    {"{\"duration\": 5, \"lights\": [{\"name\": \"a\", \"keys\": [{\"t\": 0}]},"
     "{\"name\": \"a\", \"keys\": [{\"t\": 0}]}]}",
     "lights[1].name"},
    {"{\"duration\": 5, \"light\": {\"name\": \"a\", \"keys\": [{\"t\": 0}]},"
     "\"lights\": [{\"name\": \"a\", \"keys\": [{\"t\": 0}]}]}",
     "lights[0].name"},
    {"{\"duration\": 5, \"lights\": [{\"name\": \"a\", \"keys\": [{\"t\": 0, \"on\": 1}]}]}",
     "lights[0].keys[0].on"},
    {"{\"duration\": 5, \"lights\": [{\"name\": \"a\", \"keys\": [{\"t\": 0, \"fov_y\": 1}]}]}",
     "lights[0].keys[0].fov_y"},
    {LK("{\"t\": 0, \"size\": [1, 0]}"), "light.keys[0].size"},
    {LK("{\"t\": 0, \"size\": [1, 2, 3]}"), "light.keys[0].size"},
    {LK("{\"t\": 0, \"cone_angle\": 30, \"inner_angle\": 40}"), "light.keys[0].inner_angle"},
    {LK("{\"t\": 0, \"up\": [0, 0, 0]}"), "light.keys[0].up"},
    {"[1, 2]", "top level"},
    {"{\"duration\": 5,", "JSON"},
};

/* Every bad script fails with a message naming the field's path; nothing is returned. */
static void test_bad_scripts(void **state)
{
    (void)state;
    for (size_t i = 0; i < sizeof BAD / sizeof BAD[0]; i++) {
        iir_anim *a = (iir_anim *)(uintptr_t)1;
        iir_error err = {0};
        iir_status st = iir_anim_parse(BAD[i].json, "bad.json", &a, &err);
        if (st == IIR_OK) fail_msg("case %zu accepted: %s", i, BAD[i].json);
        assert_true(st == IIR_ERR_FORMAT || st == IIR_ERR_INVALID);
        assert_null(a);
        if (!strstr(err.msg, BAD[i].needle) || !strstr(err.msg, "bad.json"))
            fail_msg("case %zu: message '%s' lacks '%s'", i, err.msg, BAD[i].needle);
    }
    iir_anim *a = NULL;
    iir_error err = {0};
    assert_int_equal(iir_anim_load("/nonexistent/x.json", &a, &err), IIR_ERR_IO);
    assert_non_null(strstr(err.msg, "/nonexistent/x.json"));
    assert_null(a);
}

/* The shipped Cornell-box paths parse, animate the light, and every frame's light is valid with
 * the built-in box's spot as base. */
static void test_shipped_paths(void **state)
{
    (void)state;
    const char *names[] = {"orbit",  "sweep-fast", "teleport", "occluder",
                           "corner", "grazing",    "void"};
    iir_scene *scene = iir_scene_create_cornell_box();
    assert_non_null(scene);
    const iir_light *base = &scene->lights[0];
    for (size_t n = 0; n < sizeof names / sizeof names[0]; n++) {
        char path[1024];
        snprintf(path, sizeof path, "%s/scenes/cornell_box/paths/%s.json", IIR_SOURCE_DIR,
                 names[n]);
        iir_anim *a = NULL;
        iir_error err = {0};
        if (iir_anim_load(path, &a, &err) != IIR_OK) fail_msg("%s", err.msg);
        assert_true(iir_anim_has_light(a));
        for (int f = 0; f < iir_anim_frame_count(a); f++) {
            iir_light L = iir_anim_light(a, base, iir_anim_frame_time(a, f));
            if (iir_light_validate(&L, &err) != IIR_OK)
                fail_msg("%s frame %d: %s", path, f, err.msg);
            assert_float_equal(iir_length(L.direction), 1.f, 1e-5f);
        }
        iir_anim_destroy(a);
    }
    iir_scene_destroy(scene);
}

static iir_anim *load_path(const char *name)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/cornell_box/paths/%s.json", IIR_SOURCE_DIR, name);
    iir_anim *a = NULL;
    iir_error err = {0};
    if (iir_anim_load(path, &a, &err) != IIR_OK) fail_msg("%s", err.msg);
    return a;
}

#define GRID 32

/* Emission rays of L on a GRID x GRID stratified grid: how many miss the scene, and the first
 * hit points (VPL sites) of the others. */
static int trace_emission(const iir_rt *rt, const iir_light *L, iir_vec3 *hits, int *misses)
{
    iir_raystats st = {0};
    int n = 0;
    *misses = 0;
    for (int i = 0; i < GRID * GRID; i++) {
        iir_vec2 u = iir_v2(((float)(i % GRID) + 0.5f) / GRID, ((float)(i / GRID) + 0.5f) / GRID);
        iir_light_ray r = iir_light_sample_emission(L, u);
        iir_ray ray = iir_make_ray(r.origin, r.dir, 1e-4f, INFINITY);
        iir_hit hit;
        if (iir_rt_intersect(rt, &ray, &hit, &st, IIR_RAYS_BENCH))
            hits[n++] = iir_madd(r.origin, r.dir, hit.t);
        else
            (*misses)++;
    }
    return n;
}

/* Emission rays of the animated light at t that miss the scene. */
static int misses_at(const iir_rt *rt, const iir_anim *a, const iir_light *base, double t,
                     iir_vec3 *pts)
{
    iir_light L = iir_anim_light(a, base, t);
    int misses;
    trace_emission(rt, &L, pts, &misses);
    return misses;
}

/* Fraction of points still visible from light position p. */
static float visible_fraction(const iir_rt *rt, iir_vec3 p, const iir_vec3 *pts, int n)
{
    iir_raystats st = {0};
    int vis = 0;
    for (int i = 0; i < n; i++) {
        iir_vec3 d = iir_sub(pts[i], p);
        float len = iir_length(d);
        iir_ray ray = iir_make_ray(p, iir_scale(d, 1.f / len), 1e-4f, len * (1.f - 1e-3f));
        vis += !iir_rt_occluded(rt, &ray, &st, IIR_RAYS_BENCH);
    }
    return n ? (float)vis / (float)n : 0.f;
}

/* The shipped paths do what their names say, checked with rays in the built-in box: occluder
 * hides most VPL sites of its first pose at once; void sends most light out of the box and then
 * back; corner's axis lands in a corner; grazing stays nearly parallel to the back wall;
 * sweep-fast crosses the room in under a second; teleport jumps; orbit moves smoothly.
 * (Measured when written: occluder keeps 15% of its sites visible, void loses all rays.) */
static void test_paths_mean_their_names(void **state)
{
    iir_test_cornell *tc = *state;
    const iir_light *base = &tc->scene->lights[0];
    iir_vec3 *pts = malloc(GRID * GRID * sizeof *pts);
    assert_non_null(pts);
    int misses;

    iir_anim *a = load_path("occluder");
    iir_light L0 = iir_anim_light(a, base, 0.0), L1 = iir_anim_light(a, base, 1.0);
    int n = trace_emission(tc->rt, &L0, pts, &misses);
    assert_true(visible_fraction(tc->rt, L1.position, pts, n) > 0.99f);
    float vis = visible_fraction(tc->rt, iir_anim_light(a, base, 2.0).position, pts, n);
    if (vis > 0.3f) fail_msg("occluder: %.2f of the VPL sites stay visible", vis);
    iir_anim_destroy(a);

    a = load_path("void");
    int m0 = misses_at(tc->rt, a, base, 0.0, pts), m2 = misses_at(tc->rt, a, base, 2.0, pts);
    int m5 = misses_at(tc->rt, a, base, 5.0, pts);
    if (m2 < GRID * GRID * 9 / 10) fail_msg("void: only %d of %d rays escape", m2, GRID * GRID);
    assert_true(m0 < GRID * GRID / 10 && m5 < GRID * GRID / 10);
    iir_anim_destroy(a);

    a = load_path("corner");
    for (int f = 0; f < iir_anim_frame_count(a); f += 10) {
        iir_light L = iir_anim_light(a, base, iir_anim_frame_time(a, f));
        iir_ray ray = iir_make_ray(L.position, L.direction, 1e-4f, INFINITY);
        iir_hit hit;
        iir_raystats st = {0};
        assert_true(iir_rt_intersect(tc->rt, &ray, &hit, &st, IIR_RAYS_BENCH));
        iir_vec3 x = iir_madd(L.position, L.direction, hit.t);
        assert_true(iir_length(iir_sub(x, iir_v3(1.f, 0.f, -1.04f))) < 0.1f);
    }
    iir_anim_destroy(a);

    a = load_path("grazing");
    for (int f = 0; f < iir_anim_frame_count(a); f++)
        assert_true(fabsf(iir_anim_light(a, base, iir_anim_frame_time(a, f)).direction.z) < 0.1f);
    iir_anim_destroy(a);

    a = load_path("sweep-fast");
    iir_vec3 p0 = iir_anim_light(a, base, 1.0).position, p1 = iir_anim_light(a, base, 1.9).position;
    assert_true(iir_length(iir_sub(p1, p0)) > 1.5f);
    iir_anim_destroy(a);

    const char *smooth_or_jumpy[] = {"teleport", "orbit"};
    for (int k = 0; k < 2; k++) {
        a = load_path(smooth_or_jumpy[k]);
        int jumps = 0;
        float max_step = 0.f;
        for (int f = 1; f < iir_anim_frame_count(a); f++) {
            iir_vec3 q0 = iir_anim_light(a, base, iir_anim_frame_time(a, f - 1)).position;
            iir_vec3 q1 = iir_anim_light(a, base, iir_anim_frame_time(a, f)).position;
            float d = iir_length(iir_sub(q1, q0));
            jumps += d > 0.5f;
            max_step = fmaxf(max_step, d);
        }
        if (k == 0)
            assert_true(jumps >= 3);
        else
            assert_true(max_step < 0.02f);
        iir_anim_destroy(a);
    }
    free(pts);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_scene_name),       cmocka_unit_test(test_scenes_and_size),
        cmocka_unit_test(test_keys_hit_exactly), cmocka_unit_test(test_linear_midpoints),
        cmocka_unit_test(test_catmull_rom_c1),   cmocka_unit_test(test_held_fields),
        cmocka_unit_test(test_step_keys),        cmocka_unit_test(test_orbit_and_sweep),
        cmocka_unit_test(test_aim_and_camera),   cmocka_unit_test(test_frames),
        cmocka_unit_test(test_bad_scripts),      cmocka_unit_test(test_shipped_paths),
        cmocka_unit_test(test_exposure),         cmocka_unit_test(test_camera_up_and_light_name),
        cmocka_unit_test(test_recorded_script),  cmocka_unit_test(test_several_lights),
        cmocka_unit_test(test_sun_paths),        cmocka_unit_test(test_check_lights),
    };
    const struct CMUnitTest scene_tests[] = {cmocka_unit_test(test_paths_mean_their_names)};
    int failed = cmocka_run_group_tests(tests, NULL, NULL);
    return failed +
           cmocka_run_group_tests(scene_tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

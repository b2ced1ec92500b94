/* test_emission_map.c -- an area light whose radiance is an image (a "screen"): the lookup's
 * orientation and the flux against the image's own numbers; a two-colour screen close to a wall
 * lights the wall red where its red half faces it and green where its green half does, in pt, in
 * ir and iir (VPLs from the screen's points) and in hier; the sidecar refuses what it cannot use.
 */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "testutil.h"

#include "iir/anim.h"
#include "iir/image.h"
#include "iir/method.h"
#include "iir/scene.h"

/* A 2 x 1 image, red | green, as PNG (sRGB on disk: 1 and 0 survive exactly). */
static const char *write_two_colours(const char *dir)
{
    iir_image *img = iir_image_create(2, 1);
    img->pixels[0] = iir_v3(1, 0, 0);
    img->pixels[1] = iir_v3(0, 1, 0);
    static char path[1200];
    snprintf(path, sizeof path, "%s/two.png", dir);
    iir_error err = {0};
    assert_int_equal(iir_image_write_png(img, path, 0.f, &err), IIR_OK);
    iir_image_destroy(img);
    return path;
}

static void test_lookup_and_flux(void **state)
{
    (void)state;
    const char *dir = iir_test_tmpdir("emission-map");
    iir_emission_map *m = NULL;
    iir_error err = {0};
    assert_int_equal(iir_emission_map_load(write_two_colours(dir), &m, &err), IIR_OK);
    assert_int_equal(m->width, 2);
    assert_true(fabsf(m->mean.x - 0.5f) < 1e-4f && fabsf(m->mean.y - 0.5f) < 1e-4f);
    assert_true(m->path[0] == '/');
    iir_light l = {.type = IIR_LIGHT_AREA,
                   .direction = iir_v3(0, 0, 1),
                   .up = iir_v3(0, 1, 0),
                   .size = iir_v2(2, 1),
                   .intensity = iir_v3s(3.f),
                   .map = m};
    /* the left quarter is all red, the right all green, the middle half-and-half */
    iir_vec3 left = iir_area_light_radiance(&l, iir_v2(-0.4f, 0.f));
    iir_vec3 right = iir_area_light_radiance(&l, iir_v2(0.4f, 0.3f));
    iir_vec3 mid = iir_area_light_radiance(&l, iir_v2(0.f, 0.f));
    assert_true(fabsf(left.x - 3.f) < 1e-4f && left.y < 1e-4f);
    assert_true(right.x < 1e-4f && fabsf(right.y - 3.f) < 1e-4f);
    assert_true(fabsf(mid.x - 1.5f) < 1e-4f && fabsf(mid.y - 1.5f) < 1e-4f);
    /* "left" is the left of a viewer facing the front: r = up x f */
    iir_frame fr = iir_spot_frame(&l);
    iir_vec3 viewer_right = iir_cross(iir_neg(l.direction), l.up);
    assert_true(iir_dot(fr.r, viewer_right) > 0.99f);
    iir_vec3 at = iir_area_light_radiance_at(&l, &fr, iir_add(l.position, iir_scale(fr.r, -0.8f)));
    assert_true(fabsf(at.x - 3.f) < 1e-4f);
    /* flux: pi A times the mean radiance */
    iir_vec3 phi = iir_light_flux(&l);
    assert_true(fabsf(phi.x - (float)M_PI * 2.f * 1.5f) < 1e-3f);
    assert_true(fabsf(phi.z) < 1e-6f);
    iir_emission_map_free(m);
}

/* A wall z = 0 (4 x 2); the screen (2 x 1, red | green) 0.25 in front of it, facing it; the camera
 * behind the screen, looking through its back at the wall. */
typedef iir_test_cornell loaded; /* a scene and its rays */

static loaded load_wall(void)
{
    const char *dir = iir_test_tmpdir("emission-map-wall");
    write_two_colours(dir);
    iir_test_write_file(dir, "w.mtl", "newmtl white\nKd 0.8 0.8 0.8\n");
    char path[1200];
    snprintf(path, sizeof path, "%s/w.obj", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "mtllib w.mtl\n");
    iir_test_write_quad(f, "white", iir_v3(0, 0, 0), iir_v3(2, 0, 0), iir_v3(0, 1, 0));
    fclose(f);
    iir_test_write_file(
        dir, "w.scene.json",
        "{\"camera\": {\"position\": [0, 0, 3], \"target\": [0, 0, 0], \"fov_y\": 40},"
        " \"lights\": [{\"type\": \"area\", \"name\": \"screen\","
        " \"position\": [0, 0, 0.25], \"direction\": [0, 0, -1], \"up\": [0, 1, 0],"
        " \"size\": [2, 1], \"intensity\": 2, \"emission_map\": \"two.png\"}]}");
    return iir_test_load(dir, "w");
}

/* Mean colour of the image's columns [x0, x1) in its middle third of rows. */
static iir_vec3 band(const iir_image *img, int x0, int x1)
{
    iir_vec3 s = iir_v3s(0.f);
    int n = 0;
    for (int y = img->height / 3; y < 2 * img->height / 3; y++)
        for (int x = x0; x < x1; x++, n++) s = iir_add(s, img->pixels[y * img->width + x]);
    return iir_scale(s, 1.f / (float)n);
}

/* mirror: how far the two halves' light may differ (the VPL methods' frames take one sample of the
 * screen per pixel for direct light: noisy this close). */
static void check_two_colours(const char *method, const loaded *l, const iir_params *p,
                              float mirror)
{
    enum { W = 48, H = 32 };
    iir_view v = {l->scene->lights, l->scene->num_lights, l->scene->camera};
    iir_image *img = iir_image_create(W, H);
    iir_method *m = NULL;
    iir_frame_stats fs;
    iir_error err = {0};
    if (iir_method_create(method, l->scene, l->rt, p, &m, &err) != IIR_OK) fail_msg("%s", err.msg);
    if (iir_method_render(m, &v, img, &fs, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_method_destroy(m);
    /* The screen's red half is on the left of whoever faces its front (at the wall, looking at
       +z): at +x, on the right of this camera, which sees the wall from behind the screen. */
    iir_vec3 green = band(img, W / 4, W / 2 - 4), red = band(img, W / 2 + 4, 3 * W / 4);
    print_message("%-4s wall where the red half faces it (%.3f, %.3f), the green half (%.3f, "
                  "%.3f)\n",
                  method, red.x, red.y, green.x, green.y);
    assert_true(red.x > 3.f * red.y);
    assert_true(green.y > 3.f * green.x);
    assert_true(fabsf(red.x - green.y) < mirror * red.x); /* a mirror image */
    iir_image_destroy(img);
}

static void test_screen_lights_the_wall(void **state)
{
    (void)state;
    loaded l = load_wall();
    assert_int_equal(l.scene->num_lights, 1);
    assert_non_null(l.scene->lights[0].map);
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", 256);
    iir_test_set(&p, "jitter", 0);
    check_two_colours("pt", &l, &p, 0.02f);
    check_two_colours("hier", &l, &p, 0.02f);
    iir_test_set(&p, "vpls", 1024);
    check_two_colours("ir", &l, &p, 0.15f);
    check_two_colours("iir", &l, &p, 0.15f);
    iir_rt_destroy(l.rt);
    iir_scene_destroy(l.scene);
}

static void test_sidecar_refusals(void **state)
{
    (void)state;
    const char *dir = iir_test_tmpdir("emission-map-bad");
    iir_test_write_file(dir, "b.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    iir_test_write_file(dir, "not.png", "this is not a PNG");
    const char *cases[][2] = {
        {"\"type\": \"spot\", \"position\": [0,0,1], \"direction\": [0,0,-1], \"cone_angle\": 30,"
         " \"intensity\": 1, \"emission_map\": \"two.png\"",
         "emission_map"},
        {"\"type\": \"area\", \"position\": [0,0,1], \"direction\": [0,0,-1], \"size\": [1,1],"
         " \"intensity\": 1, \"emission_map\": \"missing.png\"",
         "missing.png"},
        {"\"type\": \"area\", \"position\": [0,0,1], \"direction\": [0,0,-1], \"size\": [1,1],"
         " \"intensity\": 1, \"emission_map\": \"not.png\"",
         "not.png"},
        {"\"type\": \"area\", \"position\": [0,0,1], \"direction\": [0,0,-1], \"size\": [1,1],"
         " \"intensity\": 1, \"emission_map\": 7",
         "emission_map"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char json[1024];
        snprintf(json, sizeof json, "{\"lights\": [{%s}]}", cases[i][0]);
        iir_test_write_file(dir, "b.scene.json", json);
        iir_scene *s = NULL;
        iir_rt *rt = NULL;
        iir_error err = {0};
        assert_int_not_equal(iir_test_load_obj(dir, "b", &s, &rt, &err), IIR_OK);
        assert_null(s);
        print_message("refused: %s\n", err.msg);
        assert_non_null(strstr(err.msg, cases[i][1]));
    }
}

/* The shipped living_room_screen: its screen has the colour bars, and its path moves it keeping the
 * image. */
static void test_shipped_screen(void **state)
{
    (void)state;
    iir_scene *s = NULL;
    iir_error err = {0};
    if (iir_scene_load(IIR_SOURCE_DIR "/scenes/living_room_screen", &s, &err) != IIR_OK)
        fail_msg("%s", err.msg);
    uint32_t k = 0;
    while (k < s->num_lights && strcmp(s->lights[k].name, "screen") != 0) k++;
    assert_true(k < s->num_lights);
    const iir_light *screen = &s->lights[k];
    assert_non_null(screen->map);
    assert_int_equal(screen->map->width, 96);
    assert_int_equal(screen->map->height, 54);
    iir_anim *a = NULL;
    if (iir_anim_load(IIR_SOURCE_DIR "/scenes/living_room_screen/paths/slide.json", &a, &err) !=
        IIR_OK)
        fail_msg("%s", err.msg);
    uint32_t moved = iir_scene_moved_light(s, &(iir_light){0});
    assert_int_equal(iir_anim_check_lights(a, s->lights, s->num_lights, moved, &err), IIR_OK);
    iir_light out[8];
    assert_true(s->num_lights <= 8);
    iir_anim_lights(a, s->lights, s->num_lights, moved, 3.0, out);
    assert_true(out[k].map == screen->map);
    assert_true(iir_length(iir_sub(out[k].position, screen->position)) > 0.5f);
    iir_anim_destroy(a);
    iir_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_lookup_and_flux),
        cmocka_unit_test(test_screen_lights_the_wall),
        cmocka_unit_test(test_sidecar_refusals),
        cmocka_unit_test(test_shipped_screen),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

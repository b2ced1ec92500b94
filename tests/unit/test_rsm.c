/* test_rsm.c -- reflective shadow maps (method "rsm") against independent answers:
 *  - where nothing occludes (the inside of an open box corner: every surface point sees every
 *    other), RSM's missing visibility is no approximation, so with the whole map gathered it
 *    converges to pt --bounces 2 for every kind of light (the map's parameterisation of each
 *    domain and the texels' flux are right);
 *  - where a wall separates two rooms, pt's second room is black and RSM lights it: the leak
 *    that RSM is known for exists where expected;
 *  - on the Cornell box, RSM's error against pt stays within a bound set by its known failure, and
 *    screen-space interpolation is close to gathering at every pixel while gathering again at a
 *    minority of pixels. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "testutil.h"

#include "iir/method.h"
#include "iir/render.h"
#include "iir/scene.h"

/* Where the frame stats keep rsm's `recomputed` counter (iir_method_counters). */
static int counter_of(const char *method, const char *name)
{
    int i = iir_method_counter_index(method, name);
    assert_true(i >= 0);
    return i;
}
#define RECOMPUTED counter_of("rsm", "recomputed")

typedef iir_test_cornell loaded; /* a scene and its rays */

static iir_image *render(const char *method, const loaded *l, const iir_view *v, int w, int h,
                         const iir_params *p, iir_frame_stats *fs)
{
    iir_image *img = iir_image_create(w, h);
    iir_method *m = NULL;
    iir_error err = {0};
    if (iir_method_create(method, l->scene, l->rt, p, &m, &err) != IIR_OK) fail_msg("%s", err.msg);
    if (iir_method_render(m, v, img, fs, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_method_destroy(m);
    return img;
}

/* relMSE of a against b over the smooth pixels of the G-buffer of view v (luminance), and the two
 * means. */
typedef struct compared {
    double rel, mean_a, mean_b;
    int n;
} compared;

static compared compare(const loaded *l, const iir_view *v, iir_image *a, iir_image *b)
{
    iir_renderer *r = iir_renderer_create(l->scene, l->rt);
    iir_indirect_params ind = iir_indirect_params_default();
    iir_image *direct = iir_image_create(a->width, a->height);
    iir_error err = {0};
    iir_render_input in = {&v->camera, v->lights, v->num_lights, NULL, 0, 1, NULL};
    assert_int_equal(iir_renderer_frame(r, &in, &ind, direct, NULL, NULL, &err), IIR_OK);
    const iir_gbuffer *gb = iir_renderer_gbuffer(r);
    compared c = {0};
    for (int y = 0; y < a->height; y++)
        for (int x = 0; x < a->width; x++) {
            if (!iir_test_smooth_pixel(gb, x, y)) continue;
            double la = iir_luminance(*iir_image_at(a, x, y));
            double lb = iir_luminance(*iir_image_at(b, x, y));
            c.rel += (la - lb) * (la - lb) / (lb * lb + 0.01);
            c.mean_a += la, c.mean_b += lb;
            c.n++;
        }
    assert_true(c.n > 0);
    c.rel /= c.n, c.mean_a /= c.n, c.mean_b /= c.n;
    iir_image_destroy(direct);
    iir_renderer_destroy(r);
    return c;
}

/* ---- an open box corner: floor, back wall, left wall (nothing occludes anything) ---- */

static loaded load_corner_of(const char *name, const char *mtl)
{
    const char *dir = iir_test_tmpdir(name);
    iir_test_corner_obj(dir, mtl, "grey", "grey", "red");
    iir_test_write_file(dir, "corner.scene.json",
                        "{\"camera\": {\"position\": [3, 3.5, 6], \"target\": [-0.5, 0.8, -0.5],"
                        " \"fov_y\": 50}, \"lights\": []}");
    return iir_test_load(dir, "corner");
}

static loaded load_corner(void)
{
    return load_corner_of("rsm-corner",
                          "newmtl grey\nKd 0.6 0.6 0.6\nnewmtl red\nKd 0.7 0.2 0.2\n");
}

/* One light of each kind over the corner, lighting the floor and the walls. */
static iir_light corner_light(iir_light_type type, iir_spot_profile profile)
{
    iir_light l = {.type = type, .profile = profile, .up = iir_v3(0, 0, -1)};
    snprintf(l.name, sizeof l.name, "light");
    l.position = iir_v3(0.8f, 3.f, 0.6f);
    l.direction = iir_normalize(iir_v3(-0.4f, -1.f, -0.3f));
    l.intensity = iir_v3s(4.f);
    l.cone_angle = iir_radians(50.f);
    l.inner_angle = iir_radians(20.f);
    if (type == IIR_LIGHT_SUN) l.intensity = iir_v3s(1.f);
    if (type == IIR_LIGHT_AREA) {
        l.size = iir_v2(0.8f, 0.5f);
        l.intensity = iir_v3s(6.f);
    }
    return l;
}

/* `method` gathering the whole map (128^2 texels, 4096 samples, no clamp, every pixel) against
 * pt --bounces 2 at spp samples, over view v at 48 x 40. */
static compared against_pt(const loaded *c, const iir_view *v, const char *method, int spp,
                           iir_frame_stats *fs)
{
    enum { W = 48, H = 40 };
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", spp);
    iir_test_set(&p, "bounces", 2);
    iir_test_set(&p, "jitter", 0);
    iir_image *ref = render("pt", c, v, W, H, &p, fs);
    iir_test_set(&p, "rsm_res", 128);
    iir_test_set(&p, "rsm_samples", 4096);
    iir_test_set(&p, "rsm_radius", 2);
    iir_test_set(&p, "rsm_lowres", 1);
    iir_test_set(&p, "clamp", 0);
    iir_image *img = render(method, c, v, W, H, &p, fs);
    compared k = compare(c, v, img, ref);
    iir_image_destroy(img);
    iir_image_destroy(ref);
    return k;
}

static void check_corner_kind(const loaded *c, iir_light light)
{
    iir_light_fit_sun(&light, c->scene);
    iir_view v = {&light, 1, c->scene->camera};
    iir_frame_stats fs;
    compared k = against_pt(c, &v, "rsm", 1024, &fs);
    print_message(
        "%-9s rsm vs pt (nothing occludes): relMSE %.2e on %d pixels, means %.4f / %.4f\n",
        iir_light_kind(&light), k.rel, k.n, k.mean_a, k.mean_b);
    assert_true(k.rel < 5e-3);
    assert_true(fabs(k.mean_a - k.mean_b) < 0.03 * k.mean_b);
    assert_true(fs.vpl.count > 0);
}

static void test_corner_matches_pt(void **state)
{
    (void)state;
    loaded c = load_corner();
    check_corner_kind(&c, corner_light(IIR_LIGHT_SPOT, IIR_SPOT_COSINE));
    check_corner_kind(&c, corner_light(IIR_LIGHT_SPOT, IIR_SPOT_GLTF));
    check_corner_kind(&c, corner_light(IIR_LIGHT_POINT, IIR_SPOT_COSINE));
    check_corner_kind(&c, corner_light(IIR_LIGHT_SUN, IIR_SPOT_COSINE));
    check_corner_kind(&c, corner_light(IIR_LIGHT_AREA, IIR_SPOT_COSINE));
    iir_test_unload(&c);
}

/* The corner with its floor and back wall of brass (a metal of roughness 0.35), the left wall
 * red and diffuse: every receiver and every texel on the brass reflects by its BSDF (a metal has no
 * diffuse albedo: shaded as diffuse it would be black). Nothing occludes, so rsm and hier gathering
 * the whole map converge to pt --bounces 2 as in the diffuse corner only if the glossy receivers'
 * BSDF and the texels' lobes are right. */
static void check_glossy_corner(const loaded *c, const char *method, double max_rel)
{
    iir_light light = corner_light(IIR_LIGHT_SPOT, IIR_SPOT_COSINE);
    iir_view v = {&light, 1, c->scene->camera};
    iir_frame_stats fs;
    compared k = against_pt(c, &v, method, 2048, &fs);
    print_message("%s vs pt, glossy corner: relMSE %.2e on %d pixels, means %.4f / %.4f\n", method,
                  k.rel, k.n, k.mean_a, k.mean_b);
    assert_true(k.rel < max_rel);
    assert_true(fabs(k.mean_a - k.mean_b) < 0.03 * k.mean_b);
}

static void test_glossy_corner_matches_pt(void **state)
{
    (void)state;
    loaded c = load_corner_of("rsm-glossy-corner", "newmtl grey\nKd 0.9 0.7 0.45\nPm 1\nPr 0.35\n"
                                                   "newmtl red\nKd 0.7 0.2 0.2\n");
    check_glossy_corner(&c, "rsm", 5e-3);
    check_glossy_corner(&c, "hier", 5e-3);
    iir_test_unload(&c);
}

/* ---- two closed rooms side by side; the spot is in the left one ---- */

static loaded load_rooms(void)
{
    const char *dir = iir_test_tmpdir("rsm-rooms");
    iir_test_write_file(dir, "rooms.mtl", "newmtl grey\nKd 0.7 0.7 0.7\n");
    char path[1200];
    snprintf(path, sizeof path, "%s/rooms.obj", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "mtllib rooms.mtl\n");
    const iir_vec3 X = iir_v3(2, 0, 0), Y = iir_v3(0, 1, 0), Z = iir_v3(0, 0, 1);
    iir_test_write_quad(f, "grey", iir_v3(0, 0, 0), X, Z);  /* floor */
    iir_test_write_quad(f, "grey", iir_v3(0, 2, 0), X, Z);  /* ceiling */
    iir_test_write_quad(f, "grey", iir_v3(0, 1, -1), X, Y); /* back */
    iir_test_write_quad(f, "grey", iir_v3(0, 1, 1), X, Y);  /* front */
    iir_test_write_quad(f, "grey", iir_v3(-2, 1, 0), Y, Z); /* left */
    iir_test_write_quad(f, "grey", iir_v3(2, 1, 0), Y, Z);  /* right */
    iir_test_write_quad(f, "grey", iir_v3(0, 1, 0), Y, Z);  /* the wall between the rooms */
    fclose(f);
    iir_test_write_file(
        dir, "rooms.scene.json",
        "{\"camera\": {\"position\": [1.9, 1.6, 0.9], \"target\": [0.5, 0.2, -0.5],"
        " \"fov_y\": 70},"
        " \"lights\": [{\"type\": \"spot\", \"name\": \"s\", \"position\": [-1, 1.9, 0],"
        " \"direction\": [0, -1, 0], \"cone_angle\": 75, \"intensity\": 3}]}");
    return iir_test_load(dir, "rooms");
}

static double mean_luminance(const iir_image *img)
{
    double s = 0;
    for (int i = 0; i < img->width * img->height; i++) s += iir_luminance(img->pixels[i]);
    return s / (img->width * img->height);
}

static void test_leak_through_a_wall(void **state)
{
    (void)state;
    enum { W = 32, H = 24 };
    loaded r = load_rooms();
    iir_view right = {r.scene->lights, 1, r.scene->camera};
    iir_view left = right;
    left.camera.position = iir_v3(-0.1f, 1.6f, 0.9f);
    left.camera.target = iir_v3(-1.5f, 0.2f, -0.5f);
    iir_params p = iir_params_default();
    iir_frame_stats fs;
    iir_test_set(&p, "spp", 64);
    iir_test_set(&p, "bounces", 2);
    iir_image *pt_right = render("pt", &r, &right, W, H, &p, &fs);
    iir_image *pt_left = render("pt", &r, &left, W, H, &p, &fs);
    iir_test_set(&p, "rsm_radius", 2);
    iir_image *rsm_right = render("rsm", &r, &right, W, H, &p, &fs);
    double lit = mean_luminance(pt_left), dark = mean_luminance(pt_right);
    double leak = mean_luminance(rsm_right);
    print_message("two rooms: pt left %.4f, pt right %.2e, rsm right (the leak) %.4f\n", lit, dark,
                  leak);
    assert_true(lit > 0.01);
    assert_true(dark == 0.0);       /* no path reaches the right room */
    assert_true(leak > 0.01 * lit); /* RSM lights it through the wall */
    iir_image_destroy(pt_left);
    iir_image_destroy(pt_right);
    iir_image_destroy(rsm_right);
    iir_test_unload(&r);
}

/* ---- the Cornell box ---- */

/* RSM against pt --bounces 2 with its defaults. Its error is its missing visibility: the boxes
 * cast no shadow in the bounced light, and what they hide is lit, so the image is brighter than
 * pt's (+5% in mean, relMSE 2.2e-3 measured, against 1.5e-3 for ir's 256 VPLs with shadow maps).
 * Bounds: relMSE 1e-2 and the mean within 10%, and brighter. */
static void test_cornell_bound(void **state)
{
    const iir_test_cornell *f = *state;
    enum { W = 48, H = 48 };
    loaded c = {f->scene, f->rt};
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_params p = iir_params_default();
    iir_frame_stats fs;
    iir_test_set(&p, "spp", 1024);
    iir_test_set(&p, "bounces", 2);
    iir_test_set(&p, "jitter", 0);
    iir_image *ref = render("pt", &c, &v, W, H, &p, &fs);
    iir_image *img = render("rsm", &c, &v, W, H, &p, &fs);
    compared k = compare(&c, &v, img, ref);
    iir_test_set(&p, "vpls", 256);
    iir_image *ir = render("ir", &c, &v, W, H, &p, &fs);
    compared kir = compare(&c, &v, ir, ref);
    print_message("cornell: rsm vs pt relMSE %.2e (ir at 256 VPLs %.2e), means %.4f / %.4f\n",
                  k.rel, kir.rel, k.mean_a, k.mean_b);
    assert_true(k.rel < 1e-2);
    assert_true(fabs(k.mean_a - k.mean_b) < 0.1 * k.mean_b);
    assert_true(k.mean_a > k.mean_b); /* the leaks add light */
    iir_image_destroy(ir);
    iir_image_destroy(img);
    iir_image_destroy(ref);
}

/* Screen-space interpolation: close to gathering everywhere, at a fraction of the gathers. */
static void test_interpolation(void **state)
{
    const iir_test_cornell *f = *state;
    enum { W = 128, H = 96 };
    loaded c = {f->scene, f->rt};
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_params p = iir_params_default();
    iir_frame_stats full, interp;
    iir_test_set(&p, "rsm_lowres", 1);
    iir_image *a = render("rsm", &c, &v, W, H, &p, &full);
    iir_test_set(&p, "rsm_lowres", 4);
    iir_image *b = render("rsm", &c, &v, W, H, &p, &interp);
    compared k = compare(&c, &v, b, a);
    print_message("interpolation: relMSE %.2e against every pixel gathering; gathered again %.1f%% "
                  "(every pixel: %.1f%%)\n",
                  k.rel, 100 * interp.counter[RECOMPUTED], 100 * full.counter[RECOMPUTED]);
    assert_true(full.counter[RECOMPUTED] > 0.5); /* every pixel that sees a surface */
    assert_true(interp.counter[RECOMPUTED] > 0.01 &&
                interp.counter[RECOMPUTED] < 0.5 * full.counter[RECOMPUTED]);
    assert_true(k.rel < 5e-3);
    iir_image_destroy(a);
    iir_image_destroy(b);
}

/* shading = multires: close to gathering at every pixel, at a fraction of the gathers. */
static void test_multires(void **state)
{
    const iir_test_cornell *f = *state;
    enum { W = 256, H = 192 };
    loaded c = {f->scene, f->rt};
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_params p = iir_params_default();
    iir_frame_stats full, mr;
    iir_test_set(&p, "rsm_lowres", 1);
    iir_image *a = render("rsm", &c, &v, W, H, &p, &full);
    iir_test_set(&p, "shading", 1);
    iir_image *b = render("rsm", &c, &v, W, H, &p, &mr);
    compared k = compare(&c, &v, b, a);
    print_message("multires: relMSE %.2e against every pixel gathering; %.1fx fewer gather "
                  "samples, %.1f%% of the pixels gathered\n",
                  k.rel, (double)full.vpl_evals / (double)mr.vpl_evals,
                  100 * mr.counter[RECOMPUTED]);
    assert_true(k.rel < 5e-3);
    assert_true(mr.vpl_evals * 4 < full.vpl_evals);
    iir_image_destroy(a);
    iir_image_destroy(b);
}

/* The same frame twice is the same; a live parameter keeps the method. */
static void test_deterministic_and_live(void **state)
{
    const iir_test_cornell *f = *state;
    enum { W = 40, H = 30 };
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_params p = iir_params_default();
    iir_method *m = iir_test_method(f, "rsm", &p);
    iir_image *a = iir_image_create(W, H), *b = iir_image_create(W, H);
    iir_frame_stats fs;
    iir_test_render(m, &v, a, &fs);
    iir_test_render(m, &v, b, &fs);
    assert_memory_equal(a->pixels, b->pixels, sizeof(iir_vec3) * W * H);
    iir_test_set(&p, "rsm_samples", 50);
    bool restarted = true;
    iir_error err = {0};
    assert_int_equal(iir_method_set_params(m, &p, &restarted, &err), IIR_OK);
    assert_false(restarted);
    iir_test_render(m, &v, b, &fs);
    assert_memory_not_equal(a->pixels, b->pixels, sizeof(iir_vec3) * W * H);
    assert_false(iir_method_can_refine(m));
    iir_method_destroy(m);
    iir_image_destroy(a);
    iir_image_destroy(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_corner_matches_pt),
        cmocka_unit_test(test_glossy_corner_matches_pt),
        cmocka_unit_test(test_leak_through_a_wall),
        cmocka_unit_test(test_cornell_bound),
        cmocka_unit_test(test_interpolation),
        cmocka_unit_test(test_multires),
        cmocka_unit_test(test_deterministic_and_live),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

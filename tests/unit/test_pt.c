/* test_pt.c -- the reference path tracer against independent answers: the white furnace
 * (Le / (1 - rho)), a point light over a diffuse plane (analytic irradiance), and the one-bounce
 * part (bounces 2 minus bounces 1) against a numeric quadrature of the rendering equation; plus
 * determinism and progressive refinement. Scenes are written as OBJ + sidecar and loaded for real.
 */
#include <omp.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/method.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "testutil.h"

/* ---- writing small scenes ---- */

typedef iir_test_cornell loaded; /* a scene and its rays */

static iir_image *render_pt(const loaded *l, int w, int h, int spp, int bounces, uint64_t seed)
{
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", spp);
    iir_test_set(&p, "bounces", bounces);
    iir_test_set(&p, "seed", seed);
    iir_method *m = NULL;
    iir_error err = {0};
    iir_image *img = iir_image_create(w, h);
    iir_frame_stats fs;
    iir_view view = {l->scene->lights, l->scene->num_lights, l->scene->camera};
    if (iir_method_create("pt", l->scene, l->rt, &p, &m, &err) != IIR_OK) fail_msg("%s", err.msg);
    if (iir_method_render(m, &view, img, &fs, &err) != IIR_OK) fail_msg("%s", err.msg);
    assert_int_equal(fs.samples_per_pixel, (uint64_t)spp);
    assert_true(iir_raystats_total(&fs.rays) > 0);
    iir_method_destroy(m);
    return img;
}

/* ---- white furnace ---- */

static void write_furnace(const char *dir, float rho)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/furnace.mtl", dir);
    FILE *f = fopen(path, "w");
    fprintf(f, "newmtl wall\nKd %g %g %g\nKe 1 1 1\n", rho, rho, rho);
    fclose(f);
    snprintf(path, sizeof path, "%s/furnace.obj", dir);
    f = fopen(path, "w");
    fprintf(f, "mtllib furnace.mtl\n");
    iir_vec3 ax[3] = {iir_v3(1, 0, 0), iir_v3(0, 1, 0), iir_v3(0, 0, 1)};
    for (int k = 0; k < 3; k++)
        for (int s = -1; s <= 1; s += 2) {
            iir_vec3 n = iir_scale(ax[k], (float)-s); /* inward */
            iir_vec3 a = ax[(k + 1) % 3], b = iir_cross(n, a);
            iir_test_write_quad(f, "wall", iir_scale(ax[k], (float)s), a, b);
        }
    fclose(f);
    iir_test_write_file(dir, "furnace.scene.json",
                        "{\"camera\": {\"position\": [0.1, -0.2, 0.05], \"target\": [0.3, 0.1, 1],"
                        " \"up\": [0, 1, 0], \"fov_y\": 100}}");
}

static void check_furnace(float rho)
{
    const char *dir = iir_test_tmpdir(rho < 0.6f ? "pt-furnace-a" : "pt-furnace-b");
    write_furnace(dir, rho);
    loaded l = iir_test_load(dir, "furnace");
    enum { W = 24, H = 24 };
    iir_image *img = render_pt(&l, W, H, 64, 1000, 3);
    double expect = 1.0 / (1.0 - rho), mean = 0;
    for (int by = 0; by < H; by += 8)
        for (int bx = 0; bx < W; bx += 8) {
            double block = 0;
            for (int y = by; y < by + 8; y++)
                for (int x = bx; x < bx + 8; x++) block += iir_luminance(*iir_image_at(img, x, y));
            block /= 64;
            mean += block / 9;
            if (fabs(block - expect) > 0.03 * expect)
                fail_msg("furnace rho %.2f: block (%d,%d) = %.4f, expected %.4f", rho, bx, by,
                         block, expect);
        }
    if (fabs(mean - expect) > 0.01 * expect)
        fail_msg("furnace rho %.2f: mean %.4f, expected %.4f (1%%)", rho, mean, expect);
    iir_image_destroy(img);
    iir_test_unload(&l);
}

static void test_white_furnace(void **state)
{
    (void)state;
    check_furnace(0.5f);
    check_furnace(0.8f);
}

/* ---- a point light over a diffuse plane ---- */

/* Radiance rho/pi * I cos / d^2 of the plane under a unit point light at height 1, averaged over
 * the pixel's footprint (the path tracer box-filters the pixel) with 16 x 16 sub-samples. */
static double plane_pixel_radiance(const iir_camera_frame *cf, int x, int y)
{
    enum { SUB = 16 };
    double sum = 0;
    for (int j = 0; j < SUB; j++)
        for (int i = 0; i < SUB; i++) {
            iir_vec3 d = iir_camera_dir(cf, x + (i + 0.5f) / SUB, y + (j + 0.5f) / SUB);
            iir_vec3 p = iir_madd(cf->origin, d, -cf->origin.y / d.y);
            double r2 = 1.0 + p.x * p.x + p.z * p.z;
            sum += 0.5 / IIR_PI * (1.0 / sqrt(r2)) / r2;
        }
    return sum / (SUB * SUB);
}

static void test_point_light_plane(void **state)
{
    (void)state;
    const char *dir = iir_test_tmpdir("pt-plane");
    iir_test_write_file(dir, "plane.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
    char path[1200];
    snprintf(path, sizeof path, "%s/plane.obj", dir);
    FILE *f = fopen(path, "w");
    fprintf(f, "mtllib plane.mtl\n");
    iir_test_write_quad(f, "grey", iir_v3(0, 0, 0), iir_v3(0, 0, 20),
                        iir_v3(20, 0, 0)); /* normal +y */
    fclose(f);
    iir_test_write_file(dir, "plane.scene.json",
                        "{\"camera\": {\"position\": [0, 2.5, 0], \"target\": [0, 0, 0],"
                        " \"up\": [0, 0, -1], \"fov_y\": 90},"
                        " \"lights\": [{\"type\": \"point\", \"name\": \"bulb\","
                        " \"position\": [0, 1, 0], \"intensity\": [1, 1, 1]}]}");
    loaded l = iir_test_load(dir, "plane");
    enum { W = 64, H = 64 };
    iir_image *direct = render_pt(&l, W, H, 256, 1, 5);
    iir_image *bounce = render_pt(&l, W, H, 256, 2, 5);
    iir_camera_frame cf = iir_camera_setup(&l.scene->camera, W, H);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double expect = plane_pixel_radiance(&cf, x, y);
            double got = direct->pixels[y * W + x].y;
            if (fabs(got - expect) > 0.01 * expect)
                fail_msg("pixel (%d,%d): %.6f, expected %.6f", x, y, got, expect);
            /* A plane cannot light itself: one more bounce adds nothing. */
            assert_true(fabs(bounce->pixels[y * W + x].y - got) <= 1e-6 * expect);
        }
    iir_image_destroy(direct);
    iir_image_destroy(bounce);
    iir_test_unload(&l);
}

/* ---- one bounce against quadrature ---- */

/* Floor A (y = 0), wall B (x = 1), and a small downward panel light (albedo 0): emissive
 * triangles, which the sidecar's "lights": [] keeps static (not an area light). Seen on B,
 * bounces 2 - bounces 1 is light that reflected once, off A. */
static const float RHO = 0.5f, LE = 10.f;
static const iir_vec3 PANEL_C = {-0.4f, 1.5f, 0.f};
static const float PANEL_H = 0.2f; /* half size */

static void write_bounce_scene(const char *dir)
{
    iir_test_write_file(dir, "bounce.mtl",
                        "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 10 10 10\n");
    char path[1200];
    snprintf(path, sizeof path, "%s/bounce.obj", dir);
    FILE *f = fopen(path, "w");
    fprintf(f, "mtllib bounce.mtl\n");
    iir_test_write_quad(f, "grey", iir_v3(0, 0, 0), iir_v3(0, 0, 1), iir_v3(1, 0, 0)); /* A: +y */
    iir_test_write_quad(f, "grey", iir_v3(1, 1, 0), iir_v3(0, 0, 1), iir_v3(0, 1, 0)); /* B: -x */
    iir_test_write_quad(f, "lamp", PANEL_C, iir_v3(PANEL_H, 0, 0), iir_v3(0, 0, PANEL_H)); /* -y */
    fclose(f);
    iir_test_write_file(dir, "bounce.scene.json",
                        "{\"camera\": {\"position\": [-0.9, 0.8, 0], \"target\": [1, 0.8, 0],"
                        " \"up\": [0, 1, 0], \"fov_y\": 70}, \"lights\": []}");
}

/* Irradiance at p (normal n) from the panel, midpoint rule over NL x NL cells. */
static double panel_irradiance(iir_vec3 p, iir_vec3 n)
{
    enum { NL = 8 };
    double E = 0, cell = 2.0 * PANEL_H / NL;
    for (int i = 0; i < NL; i++)
        for (int j = 0; j < NL; j++) {
            iir_vec3 q = iir_v3(PANEL_C.x - PANEL_H + (float)((i + 0.5) * cell), PANEL_C.y,
                                PANEL_C.z - PANEL_H + (float)((j + 0.5) * cell));
            iir_vec3 d = iir_sub(q, p);
            double r2 = iir_length_sq(d), r = sqrt(r2);
            double cos_p = iir_dot(n, d) / r, cos_l = d.y / r; /* panel normal is -y */
            if (cos_p > 0 && cos_l > 0) E += LE * cos_p * cos_l / r2 * cell * cell;
        }
    return E;
}

enum { NA = 120 };

/* Radiance leaving floor cells: rho/pi * E. */
static void floor_radiance(double *Lf)
{
    for (int i = 0; i < NA; i++)
        for (int j = 0; j < NA; j++) {
            iir_vec3 y = iir_v3(-1.f + (float)((i + 0.5) * 2.0 / NA), 0.f,
                                -1.f + (float)((j + 0.5) * 2.0 / NA));
            Lf[i * NA + j] = RHO / IIR_PI * panel_irradiance(y, iir_v3(0, 1, 0));
        }
}

/* Radiance leaving x on B after one bounce off A. */
static double one_bounce_at(iir_vec3 x, const double *Lf)
{
    double E = 0, cell = 2.0 / NA;
    for (int i = 0; i < NA; i++)
        for (int j = 0; j < NA; j++) {
            iir_vec3 y =
                iir_v3(-1.f + (float)((i + 0.5) * cell), 0.f, -1.f + (float)((j + 0.5) * cell));
            iir_vec3 d = iir_sub(y, x);
            double r2 = iir_length_sq(d), r = sqrt(r2);
            double cos_x = -d.x / r, cos_y = -d.y / r; /* B's normal -x, A's +y */
            if (cos_x > 0 && cos_y > 0) E += Lf[i * NA + j] * cos_x * cos_y / r2 * cell * cell;
        }
    return RHO / IIR_PI * E;
}

static void test_one_bounce_matches_quadrature(void **state)
{
    (void)state;
    const char *dir = iir_test_tmpdir("pt-bounce");
    write_bounce_scene(dir);
    loaded l = iir_test_load(dir, "bounce");
    enum { W = 32, H = 32 };
    iir_image *b1 = render_pt(&l, W, H, 256, 1, 11);
    iir_image *b2 = render_pt(&l, W, H, 256, 2, 11);
    double *Lf = malloc(sizeof(double) * NA * NA);
    floor_radiance(Lf);
    iir_camera_frame cf = iir_camera_setup(&l.scene->camera, W, H);
    double got_ind = 0, want_ind = 0, got_dir = 0, want_dir = 0;
    int n = 0;
    for (int py = 0; py < H; py++)
        for (int px = 0; px < W; px++) {
            iir_vec3 d = iir_camera_dir(&cf, px + 0.5f, py + 0.5f);
            iir_vec3 x = iir_madd(cf.origin, d, (1.f - cf.origin.x) / d.x);
            if (x.y < 0.3f || x.y > 1.2f || fabsf(x.z) > 0.7f) continue;
            got_dir += b1->pixels[py * W + px].x;
            want_dir += RHO / IIR_PI * panel_irradiance(x, iir_v3(-1, 0, 0));
            got_ind += b2->pixels[py * W + px].x - b1->pixels[py * W + px].x;
            want_ind += one_bounce_at(x, Lf);
            n++;
        }
    assert_true(n > 100);
    if (fabs(got_dir - want_dir) > 0.02 * want_dir)
        fail_msg("direct: path tracer %.5f, quadrature %.5f", got_dir / n, want_dir / n);
    if (fabs(got_ind - want_ind) > 0.03 * want_ind)
        fail_msg("one bounce: path tracer %.5f, quadrature %.5f", got_ind / n, want_ind / n);
    free(Lf);
    iir_image_destroy(b1);
    iir_image_destroy(b2);
    iir_test_unload(&l);
}

/* ---- determinism and progressive refinement ---- */

static void test_deterministic_and_progressive(void **state)
{
    const iir_test_cornell *f = *state;
    loaded l = {f->scene, f->rt};
    iir_error err = {0};
    omp_set_num_threads(2);
    iir_image *a = render_pt(&l, 40, 30, 4, 3, 42);
    omp_set_num_threads(1);
    iir_image *b = render_pt(&l, 40, 30, 4, 3, 42);
    omp_set_num_threads(2);
    iir_image *c = render_pt(&l, 40, 30, 4, 3, 43);
    assert_memory_equal(a->pixels, b->pixels, sizeof(iir_vec3) * 40 * 30);
    assert_memory_not_equal(a->pixels, c->pixels, sizeof(iir_vec3) * 40 * 30);

    /* render(4 spp) + refine(4 spp) == render(8 spp) up to summation order. */
    iir_image *eight = render_pt(&l, 40, 30, 8, 3, 42);
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", 4);
    iir_test_set(&p, "bounces", 3);
    iir_test_set(&p, "seed", 42);
    iir_method *m = NULL;
    iir_frame_stats fs;
    iir_view view = {l.scene->lights, l.scene->num_lights, l.scene->camera};
    assert_int_equal(iir_method_create("pt", l.scene, l.rt, &p, &m, &err), IIR_OK);
    assert_true(iir_method_can_refine(m));
    assert_int_equal(iir_method_refine(m, a, &fs, &err), IIR_ERR_INVALID); /* nothing yet */
    assert_int_equal(iir_method_render(m, &view, a, &fs, &err), IIR_OK);
    assert_int_equal(iir_method_refine(m, a, &fs, &err), IIR_OK);
    assert_int_equal(fs.samples_per_pixel, 8);
    for (int i = 0; i < 40 * 30; i++)
        assert_true(iir_length(iir_sub(a->pixels[i], eight->pixels[i])) <=
                    1e-5f * (1.f + iir_length(eight->pixels[i])));
    iir_method_destroy(m);
    iir_image_destroy(a);
    iir_image_destroy(b);
    iir_image_destroy(c);
    iir_image_destroy(eight);
}

static void test_bad_requests(void **state)
{
    const iir_test_cornell *f = *state;
    loaded l = {f->scene, f->rt};
    iir_error err = {0};
    iir_params p = iir_params_default();
    iir_method *m = NULL;
    assert_int_equal(iir_method_create("nope", l.scene, l.rt, &p, &m, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "pt"));
    assert_int_equal(iir_method_param_set(&p, "bounces", 0, &err), IIR_ERR_INVALID);
    assert_int_equal(iir_method_create("pt", l.scene, l.rt, &p, &m, &err), IIR_OK);
    iir_method_destroy(m);
    m = NULL;
    assert_null(m);
    p = iir_params_default();
    assert_int_equal(iir_method_create("pt", l.scene, l.rt, &p, &m, &err), IIR_OK);
    iir_light bad = l.scene->lights[0];
    bad.cone_angle = NAN;
    iir_view view = {&bad, 1, l.scene->camera};
    iir_image *img = iir_image_create(8, 8);
    iir_frame_stats fs;
    assert_int_equal(iir_method_render(m, &view, img, &fs, &err), IIR_ERR_INVALID);
    iir_image_destroy(img);
    iir_method_destroy(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_white_furnace),
        cmocka_unit_test(test_point_light_plane),
        cmocka_unit_test(test_one_bounce_matches_quadrature),
        cmocka_unit_test_setup_teardown(test_deterministic_and_progressive, iir_test_cornell_setup,
                                        iir_test_cornell_teardown),
        cmocka_unit_test_setup_teardown(test_bad_requests, iir_test_cornell_setup,
                                        iir_test_cornell_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* test_area_noise.c -- the noise of direct light from an area light in one interactive frame
 * (render_direct.c: area_samples stratified samples per pixel), against a converged reference
 * (the same frame with 1024 samples), on the built-in Cornell box lit by a ceiling panel that
 * casts the blocks' penumbrae. ir with bounces 1 renders exactly the direct pass.
 *
 * The bound. With N independent samples a pixel's error has standard deviation sigma_1 / sqrt(N)
 * (sigma_1: one sample's); stratified samples (a scrambled net) do better wherever the integrand
 * is piecewise smooth, which the penumbrae are. So the frame's relative RMSE at the default N must
 * be at most half of N = 1's divided by sqrt(N) (the i.i.d. rate, halved for the stratification:
 * on the cornell_area orbit it was a quarter), and below 5% of the mean, the salt-and-pepper
 * threshold: one sample per pixel (the old sampling) gives 14-20%, every pixel of a penumbra
 * either lit or black. The test checks that N = 1 indeed fails the 5% bound. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>

#include <cmocka.h>

#include "iir/image.h"
#include "iir/light.h"
#include "iir/method.h"
#include "testutil.h"

enum { W = 96, H = 96, REF_SAMPLES = 1024 };

#define MAX_REL_RMSE 0.05 /* see the top of the file */

/* A panel under the middle of the box's ceiling, facing down, a fifth of the box wide. */
static iir_light ceiling_panel(const iir_scene *s, bool disc)
{
    iir_vec3 lo = s->bounds_min, hi = s->bounds_max, ext = iir_sub(hi, lo);
    iir_light l = {.type = IIR_LIGHT_AREA, .up = iir_v3(0, 0, 1)};
    snprintf(l.name, sizeof l.name, "panel");
    l.position = iir_v3(lo.x + 0.5f * ext.x, hi.y - 0.02f * ext.y, lo.z + 0.5f * ext.z);
    l.direction = iir_v3(0, -1, 0);
    l.size = iir_v2(0.25f * ext.x, 0.2f * ext.z);
    l.intensity = iir_v3(17.f, 12.f, 4.f);
    if (disc) iir_test_disc_shape(&l.shape, 16);
    return l;
}

/* The frame of ir, direct light only, at n area samples per pixel. */
static iir_image *frame(const iir_test_cornell *f, const iir_light *l, int n)
{
    iir_params p = iir_params_default();
    iir_test_set(&p, "bounces", 1);
    iir_test_set(&p, "area_samples", n);
    iir_method *m = iir_test_method(f, "ir", &p);
    iir_view v = {l, 1, f->scene->camera};
    iir_image *img = iir_image_create(W, H);
    assert_non_null(img);
    iir_frame_stats fs;
    iir_test_render(m, &v, img, &fs);
    iir_method_destroy(m);
    return img;
}

/* RMSE of a's luminance against ref's, over ref's mean luminance. */
static double rel_rmse(iir_image *a, iir_image *ref)
{
    double se = 0.0, sum = 0.0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double la = iir_luminance(*iir_image_at(a, x, y));
            double lr = iir_luminance(*iir_image_at(ref, x, y));
            se += (la - lr) * (la - lr);
            sum += lr;
        }
    assert_true(sum > 0.0);
    return sqrt(se / (W * H)) / (sum / (W * H));
}

static double noise_at(const iir_test_cornell *f, const iir_light *l, int n, iir_image *ref)
{
    iir_image *img = frame(f, l, n);
    double e = rel_rmse(img, ref);
    iir_image_destroy(img);
    return e;
}

static void check_panel(const iir_test_cornell *f, bool disc)
{
    iir_light l = ceiling_panel(f->scene, disc);
    int n = (int)iir_test_get(&(iir_params){0}, "area_samples");
    iir_image *ref = frame(f, &l, REF_SAMPLES);
    double e1 = noise_at(f, &l, 1, ref), en = noise_at(f, &l, n, ref);
    print_message("%s: relRMSE 1 sample %.4f, %d samples %.4f (bound %.4f)\n",
                  disc ? "disc" : "rectangle", e1, n, en,
                  fmin(MAX_REL_RMSE, 0.5 * e1 / sqrt((double)n)));
    assert_true(n > 1);
    assert_true(e1 > MAX_REL_RMSE); /* the old sampling fails the bound */
    assert_true(en <= MAX_REL_RMSE);
    assert_true(en <= 0.5 * e1 / sqrt((double)n));
    iir_image_destroy(ref);
}

static void test_rectangle_noise_bounded(void **state)
{
    check_panel(*state, false);
}

static void test_disc_noise_bounded(void **state)
{
    check_panel(*state, true);
}

/* Same seed, same frame: byte-identical, whatever the threads did. */
static void test_deterministic(void **state)
{
    const iir_test_cornell *f = *state;
    iir_light l = ceiling_panel(f->scene, false);
    iir_image *a = frame(f, &l, 8), *b = frame(f, &l, 8);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            iir_vec3 pa = *iir_image_at(a, x, y), pb = *iir_image_at(b, x, y);
            assert_true(pa.x == pb.x && pa.y == pb.y && pa.z == pb.z);
        }
    iir_image_destroy(a);
    iir_image_destroy(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rectangle_noise_bounded),
        cmocka_unit_test(test_disc_noise_bounded),
        cmocka_unit_test(test_deterministic),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

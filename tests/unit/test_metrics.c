/* test_metrics.c -- RMSE, relative MSE, SSIM and flicker on hand-computed cases; not files. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>

#include "iir/metrics.h"

#define C1 (0.01 * 0.01)
#define C2 (0.03 * 0.03)

/* ---- helpers -------------------------------------------------------------------------------- */

static void assert_near_at(double got, double want, double tol, const char *file, int line)
{
    if (!(fabs(got - want) <= tol))
        fail_msg("%s:%d: got %.12g, want %.12g (tolerance %g)", file, line, got, want, tol);
}
#define assert_near(got, want, tol) assert_near_at((got), (want), (tol), __FILE__, __LINE__)

static iir_image *constant(int w, int h, iir_vec3 c)
{
    iir_image *img = iir_image_create(w, h);
    assert_non_null(img);
    for (int i = 0; i < w * h; i++) img->pixels[i] = c;
    return img;
}

/* A smooth, structured grey test pattern in [0.1, 0.9]. */
static iir_image *pattern(int w, int h)
{
    iir_image *img = iir_image_create(w, h);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            *iir_image_at(img, x, y) =
                iir_v3s(0.5f + 0.4f * sinf(0.3f * (float)x) * cosf(0.2f * (float)y));
    return img;
}

/* src plus deterministic uniform noise in [-amp, amp] (a fixed LCG, no global state). */
static iir_image *noisy_copy(const iir_image *src, float amp, uint32_t seed)
{
    iir_image *img = iir_image_create(src->width, src->height);
    for (int i = 0; i < src->width * src->height; i++) {
        seed = seed * 1664525u + 1013904223u;
        float u = (float)(seed >> 8) / 16777216.f; /* [0, 1) */
        img->pixels[i] = iir_add(src->pixels[i], iir_v3s(amp * (2.f * u - 1.f)));
    }
    return img;
}

/* ---- RMSE and relative MSE ------------------------------------------------------------------ */

static void test_rmse_constant_offset(void **state)
{
    (void)state;
    iir_image *a = constant(7, 5, iir_v3s(0.75f)), *b = constant(7, 5, iir_v3s(0.25f));
    assert_near(iir_metric_rmse(a, b), 0.5, 1e-12);
    assert_near(iir_metric_rmse(b, a), 0.5, 1e-12);
    iir_image_destroy(a);
    iir_image_destroy(b);
}

static void test_rmse_single_channel(void **state)
{
    (void)state;
    /* one channel of one pixel off by 1 among 2 pixels x 3 channels: sqrt(1/6) */
    iir_image *a = constant(2, 1, iir_v3s(0.f)), *b = constant(2, 1, iir_v3s(0.f));
    a->pixels[1].y = 1.f;
    assert_near(iir_metric_rmse(a, b), sqrt(1.0 / 6.0), 1e-12);
    iir_image_destroy(a);
    iir_image_destroy(b);
}

static void test_relmse_hand_values(void **state)
{
    (void)state;
    iir_image *a = constant(3, 2, iir_v3s(2.f)), *ref = constant(3, 2, iir_v3s(1.f));
    assert_near(iir_metric_relmse(a, ref), 1.0 / 1.01, 1e-12);
    /* against black the denominator is 0.01: (0.1)^2 / 0.01 = 1 on one channel of three */
    iir_image *c = constant(1, 1, iir_v3(0.1f, 0.f, 0.f)), *black = constant(1, 1, iir_v3s(0.f));
    assert_near(iir_metric_relmse(c, black), 1.0 / 3.0, 1e-6);
    iir_image_destroy(a);
    iir_image_destroy(ref);
    iir_image_destroy(c);
    iir_image_destroy(black);
}

static void test_identical_images(void **state)
{
    (void)state;
    iir_image *a = pattern(40, 30), *b = pattern(40, 30);
    assert_true(iir_metric_rmse(a, b) == 0.0);
    assert_true(iir_metric_relmse(a, b) == 0.0);
    assert_near(iir_metric_ssim(a, b), 1.0, 1e-12);
    assert_true(iir_metric_flicker(a, b, a, b) == 0.0);
    iir_image_destroy(a);
    iir_image_destroy(b);
}

/* ---- SSIM ----------------------------------------------------------------------------------- */

static void test_ssim_decreases_with_noise(void **state)
{
    (void)state;
    iir_image *ref = pattern(64, 48);
    iir_image *mild = noisy_copy(ref, 0.05f, 1u), *strong = noisy_copy(ref, 0.2f, 1u);
    double s_mild = iir_metric_ssim(mild, ref), s_strong = iir_metric_ssim(strong, ref);
    if (!(s_mild < 1.0 && s_mild > 0.0)) fail_msg("mild noise: ssim %.9g", s_mild);
    if (!(s_strong < s_mild && s_strong > 0.0))
        fail_msg("strong noise: ssim %.9g, mild %.9g", s_strong, s_mild);
    /* symmetric in its arguments */
    assert_near(iir_metric_ssim(ref, mild), s_mild, 1e-9);
    iir_image_destroy(ref);
    iir_image_destroy(mild);
    iir_image_destroy(strong);
}

/* Constants: no variance, so the structure term is C2/C2 = 1 and SSIM is the luminance term
 * (2ab + C1) / (a^2 + b^2 + C1), whatever the image size (also smaller than the window). */
static void test_ssim_constants_closed_form(void **state)
{
    (void)state;
    const double a = 0.3, b = 0.6;
    const double want = (2 * a * b + C1) / (a * a + b * b + C1);
    const int sizes[2][2] = {{32, 24}, {5, 4}};
    for (int s = 0; s < 2; s++) {
        iir_image *x = constant(sizes[s][0], sizes[s][1], iir_v3s((float)a));
        iir_image *y = constant(sizes[s][0], sizes[s][1], iir_v3s((float)b));
        assert_near(iir_metric_ssim(x, y), want, 1e-5);
        iir_image_destroy(x);
        iir_image_destroy(y);
    }
}

/* SSIM sees luminance: a colour shift that keeps Y keeps SSIM at 1. */
static void test_ssim_uses_luminance(void **state)
{
    (void)state;
    iir_image *grey = constant(16, 16, iir_v3s(0.5f));
    /* same Rec. 709 luminance 0.5: 0.2126 r + 0.7152 g + 0.0722 b with g = b = 0.5 - d */
    float r = 0.5f + 0.1f, g = 0.5f - 0.1f * 0.2126f / (0.7152f + 0.0722f);
    iir_image *tinted = constant(16, 16, iir_v3(r, g, g));
    assert_near(iir_metric_ssim(tinted, grey), 1.0, 1e-6);
    iir_image_destroy(grey);
    iir_image_destroy(tinted);
}

/* A checkerboard against its inverse: equal means and variances, covariance -variance, so SSIM is
 * close to -1 (not just low): checks the sign of the structure term. */
static void test_ssim_inverted_structure(void **state)
{
    (void)state;
    iir_image *c = iir_image_create(32, 32), *inv = iir_image_create(32, 32);
    for (int y = 0; y < 32; y++)
        for (int x = 0; x < 32; x++) {
            float v = (float)((x + y) & 1);
            *iir_image_at(c, x, y) = iir_v3s(v);
            *iir_image_at(inv, x, y) = iir_v3s(1.f - v);
        }
    double s = iir_metric_ssim(c, inv);
    if (!(s < -0.9 && s >= -1.0)) fail_msg("ssim of inverted checkerboard %.9g", s);
    iir_image_destroy(c);
    iir_image_destroy(inv);
}

/* ---- flicker -------------------------------------------------------------------------------- */

static void test_flicker_hand_values(void **state)
{
    (void)state;
    /* a changes exactly as the reference does: no flicker beyond the truth */
    iir_image *a_prev = constant(4, 3, iir_v3s(0.25f)), *a_t = constant(4, 3, iir_v3s(0.75f));
    iir_image *r_prev = constant(4, 3, iir_v3s(1.0f)), *r_t = constant(4, 3, iir_v3s(1.5f));
    assert_true(iir_metric_flicker(a_t, a_prev, r_t, r_prev) == 0.0);

    /* a rises by 0.5, the reference by 0.25: RMS of 0.25 everywhere */
    iir_image *r_t2 = constant(4, 3, iir_v3s(1.25f));
    assert_near(iir_metric_flicker(a_t, a_prev, r_t2, r_prev), 0.25, 1e-12);

    /* static reference, one channel of one of 12 pixels jumps by 0.5: sqrt(0.25 / 36) */
    iir_image *a_jump = constant(4, 3, iir_v3s(0.25f));
    a_jump->pixels[5].z = 0.75f;
    assert_near(iir_metric_flicker(a_jump, a_prev, r_prev, r_prev), sqrt(0.25 / 36.0), 1e-12);

    iir_image *imgs[] = {a_prev, a_t, r_prev, r_t, r_t2, a_jump};
    for (size_t i = 0; i < sizeof imgs / sizeof imgs[0]; i++) iir_image_destroy(imgs[i]);
}

/* ---- size mismatch -------------------------------------------------------------------------- */

static void test_mismatched_sizes_are_nan(void **state)
{
    (void)state;
    iir_image *a = constant(4, 3, iir_v3s(0.5f)), *b = constant(3, 4, iir_v3s(0.5f));
    assert_true(isnan(iir_metric_rmse(a, b)));
    assert_true(isnan(iir_metric_relmse(a, b)));
    assert_true(isnan(iir_metric_ssim(a, b)));
    assert_true(isnan(iir_metric_flicker(a, a, a, b)));
    assert_true(isnan(iir_metric_flicker(a, b, a, a)));
    assert_true(isnan(iir_metric_flicker(a, a, b, a)));
    iir_image_destroy(a);
    iir_image_destroy(b);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rmse_constant_offset),
        cmocka_unit_test(test_rmse_single_channel),
        cmocka_unit_test(test_relmse_hand_values),
        cmocka_unit_test(test_identical_images),
        cmocka_unit_test(test_ssim_decreases_with_noise),
        cmocka_unit_test(test_ssim_constants_closed_form),
        cmocka_unit_test(test_ssim_uses_luminance),
        cmocka_unit_test(test_ssim_inverted_structure),
        cmocka_unit_test(test_flicker_hand_values),
        cmocka_unit_test(test_mismatched_sizes_are_nan),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

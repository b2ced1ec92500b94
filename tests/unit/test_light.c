/* test_light.c -- spot and point lights: the disk-domain mapping (round trip, cosine
 * distribution), flux against numeric integration of the intensity, emission sampling, and
 * validation of nonsense lights. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/light.h"
#include "iir/rng.h"

static iir_light make_spot(float alpha_deg, float smooth_deg)
{
    iir_light l = {.type = IIR_LIGHT_SPOT, .name = "spot"};
    l.position = iir_v3(0.3f, 1.7f, -0.2f);
    l.direction = iir_normalize(iir_v3(0.2f, -1.f, 0.1f));
    l.up = iir_v3(0, 1, 0);
    l.cone_angle = iir_radians(alpha_deg);
    l.smooth = iir_radians(smooth_deg);
    l.intensity = iir_v3(2.f, 1.f, 0.5f);
    return l;
}

static void test_disk_round_trip(void **state)
{
    (void)state;
    iir_light l = make_spot(70.f, 0.f);
    iir_frame fr = iir_spot_frame(&l);
    iir_rng rng = iir_rng_make(7, 0);
    for (int i = 0; i < 10000; i++) {
        /* disk -> direction -> disk */
        float r = sqrtf(iir_rng_uniform(&rng)), phi = 2.f * IIR_PI * iir_rng_uniform(&rng);
        iir_vec2 s = iir_v2(r * cosf(phi), r * sinf(phi));
        iir_vec3 w = iir_spot_disk_to_dir(&fr, s);
        assert_true(fabsf(iir_length(w) - 1.f) < 1e-5f);
        assert_true(iir_dot(w, fr.f) >= 0.f);
        iir_vec2 back = iir_spot_dir_to_disk(&fr, w);
        assert_true(fabsf(back.x - s.x) < 1e-5f && fabsf(back.y - s.y) < 1e-5f);
        /* direction -> disk -> direction (front hemisphere) */
        iir_vec3 d = iir_normalize(iir_v3(iir_rng_uniform(&rng) - .5f, iir_rng_uniform(&rng) - .5f,
                                          iir_rng_uniform(&rng) - .5f));
        if (iir_dot(d, fr.f) < 0.f) d = iir_sub(d, iir_scale(fr.f, 2.f * iir_dot(d, fr.f)));
        iir_vec3 d2 = iir_spot_disk_to_dir(&fr, iir_spot_dir_to_disk(&fr, d));
        assert_true(iir_length(iir_sub(d, d2)) < 1e-3f);
    }
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Uniform points on the unit disk must give directions with pdf cos(theta)/pi: then
 * P(cos^2 theta <= c) = c, and the azimuth is uniform. Kolmogorov-Smirnov at the 1% level. */
static void test_uniform_disk_is_cosine_lobe(void **state)
{
    (void)state;
    enum { N = 20000 };
    iir_light l = make_spot(90.f, 0.f);
    iir_frame fr = iir_spot_frame(&l);
    float *c2 = malloc(sizeof(float) * N), *az = malloc(sizeof(float) * N);
    iir_rng rng = iir_rng_make(1234, 5);
    for (int i = 0; i < N; i++) {
        float x, y; /* rejection sampling: independent of the library's disk warps */
        do {
            x = 2.f * iir_rng_uniform(&rng) - 1.f;
            y = 2.f * iir_rng_uniform(&rng) - 1.f;
        } while (x * x + y * y >= 1.f);
        iir_vec3 w = iir_spot_disk_to_dir(&fr, iir_v2(x, y));
        float c = iir_dot(w, fr.f);
        c2[i] = c * c;
        az[i] = (atan2f(iir_dot(w, fr.u), iir_dot(w, fr.r)) + IIR_PI) / (2.f * IIR_PI);
    }
    qsort(c2, N, sizeof(float), cmp_float);
    qsort(az, N, sizeof(float), cmp_float);
    double d_c = 0, d_az = 0;
    for (int i = 0; i < N; i++) {
        double lo = (double)i / N, hi = (double)(i + 1) / N;
        d_c = fmax(d_c, fmax(fabs(c2[i] - lo), fabs(hi - c2[i])));
        d_az = fmax(d_az, fmax(fabs(az[i] - lo), fabs(hi - az[i])));
    }
    double crit = 1.63 / sqrt((double)N);
    assert_true(d_c < crit);
    assert_true(d_az < crit);
    free(c2);
    free(az);
}

/* Flux by integrating the intensity over the sphere with a (theta, phi) midpoint rule. */
static iir_vec3 integrate_intensity(const iir_light *l)
{
    enum { NT = 2000, NP = 64 };
    double sum[3] = {0, 0, 0};
    iir_frame fr = iir_frame_from_forward(l->direction, iir_v3(0, 1, 0));
    double dt = IIR_PI / NT, dp = 2 * IIR_PI / NP;
    for (int i = 0; i < NT; i++) {
        double th = (i + 0.5) * dt;
        for (int j = 0; j < NP; j++) {
            double ph = (j + 0.5) * dp;
            iir_vec3 w =
                iir_frame_to_world(&fr, iir_v3((float)(sin(th) * cos(ph)),
                                               (float)(sin(th) * sin(ph)), (float)cos(th)));
            iir_vec3 I = iir_light_intensity(l, w);
            double dw = sin(th) * dt * dp;
            sum[0] += I.x * dw, sum[1] += I.y * dw, sum[2] += I.z * dw;
        }
    }
    return iir_v3((float)sum[0], (float)sum[1], (float)sum[2]);
}

static void test_spot_flux(void **state)
{
    (void)state;
    const float angles[] = {10.f, 30.f, 45.f, 60.f, 89.f, 90.f};
    for (size_t k = 0; k < sizeof angles / sizeof angles[0]; k++) {
        iir_light l = make_spot(angles[k], 0.f);
        float s = sinf(l.cone_angle);
        iir_vec3 phi = iir_light_flux(&l), num = integrate_intensity(&l);
        float expect = IIR_PI * l.intensity.x * s * s; /* Phi = pi I0 sin^2(alpha) */
        assert_true(fabsf(phi.x - expect) < 1e-4f * expect);
        assert_true(fabsf(num.x - expect) < 5e-3f * expect);
        assert_true(fabsf(phi.y / phi.x - 0.5f) < 1e-6f);
    }
    /* A smooth edge removes flux; the closed form no longer holds but the integral does. */
    iir_light l = make_spot(50.f, 15.f);
    iir_vec3 phi = iir_light_flux(&l), num = integrate_intensity(&l);
    assert_true(fabsf(phi.x - num.x) < 5e-3f * num.x);
    assert_true(phi.x < IIR_PI * l.intensity.x * iir_sqr(sinf(l.cone_angle)));
}

static void test_point_flux(void **state)
{
    (void)state;
    iir_light l = {.type = IIR_LIGHT_POINT, .intensity = iir_v3(3, 3, 3)};
    assert_true(fabsf(iir_light_flux(&l).x - 12.f * IIR_PI) < 1e-4f);
    assert_true(fabsf(integrate_intensity(&l).x - 12.f * IIR_PI) < 1e-2f);
}

/* Emission samples carry the flux on average, and land in the cone. */
static void test_emission_sampling(void **state)
{
    (void)state;
    iir_light l = make_spot(40.f, 10.f);
    iir_frame fr = iir_spot_frame(&l);
    iir_rng rng = iir_rng_make(99, 1);
    double sum = 0;
    enum { N = 200000 };
    for (int i = 0; i < N; i++) {
        iir_light_ray r = iir_light_sample_emission(&l, iir_rng_uniform2(&rng));
        assert_true(iir_dot(r.dir, fr.f) >= cosf(l.cone_angle) - 1e-5f);
        sum += r.beta.x;
    }
    double phi = iir_light_flux(&l).x;
    assert_true(fabs(sum / N - phi) < 0.01 * phi);
}

static void test_validation(void **state)
{
    (void)state;
    iir_error err = {0};
    iir_light l = make_spot(45.f, 0.f);
    assert_int_equal(iir_light_validate(&l, &err), IIR_OK);
    l.direction = iir_v3(0, 0, 0);
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "direction"));
    l = make_spot(0.f, 0.f);
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "cone angle"));
    l = make_spot(120.f, 0.f);
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
    l = make_spot(30.f, 40.f);
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
    l = make_spot(30.f, 0.f);
    l.intensity.y = NAN;
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
    l = make_spot(30.f, 0.f);
    l.position.x = INFINITY;
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_disk_round_trip),
        cmocka_unit_test(test_uniform_disk_is_cosine_lobe),
        cmocka_unit_test(test_spot_flux),
        cmocka_unit_test(test_point_flux),
        cmocka_unit_test(test_emission_sampling),
        cmocka_unit_test(test_validation),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

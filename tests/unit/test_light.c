/* test_light.c -- spot, glTF spot, point, sun and area lights: the disk-domain mappings (round
 * trip, cosine distribution; the equal-area cap map's round trip and area), glTF's profile, flux
 * against numeric integration of the intensity, emission sampling (mean beta = flux), fitting a
 * sun to the scene, the light set's sun sample, validation of nonsense lights; the area light's
 * ray-rectangle test, its next-event samples against the closed-form irradiance of a rectangle on
 * a parallel plane, and its MIS pdf (consistent with the samples, integrating to one); the
 * 8-lane delta-light sampler against the scalar one. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/isa.h"
#include "iir/light.h"
#include "iir/rng.h"
#include "iir/scene.h"
#include "testutil.h"

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

/* The set's sample at a point x in space (no surface, no offsets). */
static iir_light_sample sample_at(const iir_lightset *set, iir_vec3 x, float u_pick, iir_vec2 u)
{
    iir_light_ctx ctx = {x, {0.f, 0.f, 0.f}, 0.f};
    return iir_lightset_sample_li(set, &ctx, u_pick, u);
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

/* ---- the glTF spot ---- */

static iir_light make_gltf_spot(float outer_deg, float inner_deg)
{
    iir_light l = make_spot(outer_deg, 0.f);
    snprintf(l.name, sizeof l.name, "gspot");
    l.profile = IIR_SPOT_GLTF;
    l.inner_angle = iir_radians(inner_deg);
    return l;
}

/* glTF's t^2 in double precision, straight from the specification. */
static double gltf_t2(double cos_theta, double outer, double inner)
{
    double co = cos(outer), t = (cos_theta - co) / fmax(1e-3, cos(inner) - co);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return t * t;
}

/* Disk -> direction -> disk for the equal-area map, w.f = 1 - |s|^2 / 2, and the map preserves
 * area: a polar cell [rho0, rho1] x [phi0, phi1] of the disk becomes a band of solid angle
 * (phi1 - phi0) (cos theta0 - cos theta1), equal to its area (phi1 - phi0) (rho1^2 - rho0^2) / 2.
 */
static void test_cap_map(void **state)
{
    (void)state;
    iir_light l = make_gltf_spot(70.f, 10.f);
    iir_frame fr = iir_spot_frame(&l);
    iir_rng rng = iir_rng_make(11, 0);
    for (int i = 0; i < 10000; i++) {
        float r = 2.f * sqrtf(iir_rng_uniform(&rng)), phi = 2.f * IIR_PI * iir_rng_uniform(&rng);
        iir_vec2 s = iir_v2(r * cosf(phi), r * sinf(phi));
        iir_vec3 w = iir_cap_disk_to_dir(&fr, s);
        assert_true(fabsf(iir_length(w) - 1.f) < 1e-5f);
        assert_true(fabsf(iir_dot(w, fr.f) - (1.f - 0.5f * r * r)) < 1e-5f);
        if (r < 1.9f) { /* near the antipode, 1 + w.f loses the azimuth */
            iir_vec2 back = iir_cap_dir_to_disk(&fr, w);
            assert_true(fabsf(back.x - s.x) < 1e-4f && fabsf(back.y - s.y) < 1e-4f);
        }
        iir_vec3 d = iir_normalize(iir_v3(iir_rng_uniform(&rng) - .5f, iir_rng_uniform(&rng) - .5f,
                                          iir_rng_uniform(&rng) - .5f));
        iir_vec3 d2 = iir_cap_disk_to_dir(&fr, iir_cap_dir_to_disk(&fr, d));
        if (iir_dot(d, fr.f) > -0.99f) assert_true(iir_length(iir_sub(d, d2)) < 1e-3f);
    }
    /* the cone's edge is the disk's rim */
    float R = iir_gltf_spot_radius(&l);
    iir_vec3 rim = iir_cap_disk_to_dir(&fr, iir_v2(R, 0.f));
    assert_true(fabsf(iir_dot(rim, fr.f) - cosf(l.cone_angle)) < 1e-5f);
    /* area: bands of the disk against the solid angle of their images */
    enum { NR = 16 };
    for (int i = 0; i < NR; i++) {
        float rho0 = 2.f * i / NR, rho1 = 2.f * (i + 1) / NR;
        double c0 = iir_dot(iir_cap_disk_to_dir(&fr, iir_v2(0.f, rho0)), fr.f);
        double c1 = iir_dot(iir_cap_disk_to_dir(&fr, iir_v2(0.f, rho1)), fr.f);
        double omega = 2.0 * IIR_PI * (c0 - c1), area = IIR_PI * (rho1 * rho1 - rho0 * rho0);
        assert_true(fabs(omega - area) < 1e-5 * fmax(area, 1e-3));
        /* the azimuth is kept: a quarter of the band is a quarter of its solid angle */
        iir_vec3 q = iir_cap_disk_to_dir(&fr, iir_v2(0.5f * (rho0 + rho1), 0.f));
        assert_true(iir_dot(q, fr.u) == 0.f || fabsf(iir_dot(q, fr.u)) < 1e-6f);
    }
}

/* Uniform points on the equal-area disk are uniform in solid angle: cos(theta) is uniform on
 * [cos alpha, 1]. Kolmogorov-Smirnov at the 1% level. */
static void test_cap_map_uniform_solid_angle(void **state)
{
    (void)state;
    enum { N = 20000 };
    iir_light l = make_gltf_spot(60.f, 0.f);
    iir_frame fr = iir_spot_frame(&l);
    float R = iir_gltf_spot_radius(&l), ca = cosf(l.cone_angle);
    float *u = malloc(sizeof(float) * N);
    iir_rng rng = iir_rng_make(4321, 2);
    for (int i = 0; i < N; i++) {
        float x, y;
        do {
            x = 2.f * iir_rng_uniform(&rng) - 1.f;
            y = 2.f * iir_rng_uniform(&rng) - 1.f;
        } while (x * x + y * y >= 1.f);
        iir_vec3 w = iir_cap_disk_to_dir(&fr, iir_v2(R * x, R * y));
        u[i] = (iir_dot(w, fr.f) - ca) / (1.f - ca);
    }
    qsort(u, N, sizeof(float), cmp_float);
    double d = 0;
    for (int i = 0; i < N; i++)
        d = fmax(d, fmax(fabs(u[i] - (double)i / N), fabs((double)(i + 1) / N - u[i])));
    assert_true(d < 1.63 / sqrt((double)N));
    free(u);
}

/* I(w) = I0 t^2: I0 inside the inner cone (no cosine lobe), 0 outside the outer one. */
static void test_gltf_spot_profile(void **state)
{
    (void)state;
    iir_light l = make_gltf_spot(40.f, 20.f);
    iir_frame fr = iir_spot_frame(&l);
    iir_light_eval e = iir_light_prepare(&l);
    assert_true(fabsf(e.cos_outer - cosf(l.cone_angle)) < 1e-7f);
    for (int i = 0; i <= 100; i++) {
        double th = iir_radians(60.f) * i / 100.0;
        iir_vec3 w = iir_frame_to_world(&fr, iir_v3((float)sin(th), 0.f, (float)cos(th)));
        float I = iir_light_intensity(&l, w).x;
        double expect = l.intensity.x * gltf_t2(cos(th), l.cone_angle, l.inner_angle);
        assert_true(fabs(I - expect) < 2e-4 * l.intensity.x);
        assert_true(fabsf(iir_gltf_spot_attenuation(&e, (float)cos(th)) - I / l.intensity.x) <
                    1e-5f);
        if (th < l.inner_angle - 1e-3) assert_true(I == l.intensity.x);
        if (th > l.cone_angle + 1e-3) assert_true(I == 0.f);
    }
    /* behind the light: nothing */
    assert_true(iir_is_black(iir_light_intensity(&l, iir_neg(fr.f))));
    assert_string_equal(iir_light_kind(&l), "gltf_spot");
}

/* Flux by a fine 1D quadrature of the (axially symmetric) intensity: 2 pi int I sin dtheta. */
static double integrate_axial(const iir_light *l)
{
    enum { N = 400000 };
    iir_frame fr = iir_spot_frame(l);
    double sum = 0, dt = 0.5 * IIR_PI / N;
    for (int i = 0; i < N; i++) {
        double th = (i + 0.5) * dt;
        iir_vec3 w = iir_frame_to_world(&fr, iir_v3((float)sin(th), 0.f, (float)cos(th)));
        sum += iir_light_intensity(l, w).x * sin(th) * dt;
    }
    return 2 * IIR_PI * sum;
}

/* The same in double precision from the specification's formula alone: 2 pi I0 int t^2 dcos. */
static double gltf_flux_exact(const iir_light *l)
{
    enum { N = 400000 };
    double co = cos(l->cone_angle), sum = 0, dc = (1 - co) / N;
    for (int i = 0; i < N; i++) sum += gltf_t2(co + (i + 0.5) * dc, l->cone_angle, l->inner_angle);
    return 2 * IIR_PI * l->intensity.x * sum * dc;
}

static void test_gltf_spot_flux(void **state)
{
    (void)state;
    /* outer, inner: no ramp, a wide ramp, a ramp narrower than 1e-3 in cos (the clamp), a tiny
     * cone, the hemisphere */
    const float cases[][2] = {{45, 45}, {45, 0},  {30, 20}, {60, 59.99f}, {3, 2},
                              {90, 0},  {90, 90}, {89, 10}, {1.5f, 0}};
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        iir_light l = make_gltf_spot(cases[k][0], cases[k][1]);
        double phi = iir_light_flux(&l).x, exact = gltf_flux_exact(&l);
        double num = integrate_axial(&l), sph = integrate_intensity(&l).x;
        print_message("gltf spot %g/%g: flux %.6g, exact %.6g, 1D %.6g, sphere %.6g\n",
                      (double)cases[k][0], (double)cases[k][1], phi, exact, num, sph);
        assert_true(fabs(phi - exact) < 1e-4 * exact);
        /* iir_light_intensity in float resolves 1 - cos(theta) to ~1e-7: 1e-4 of a 3 degree cap */
        assert_true(fabs(phi - num) < (cases[k][0] >= 10.f ? 1e-4 : 1e-3) * num);
        if (cases[k][0] >= 30.f) assert_true(fabs(phi - sph) < 5e-3 * num);
        assert_true(fabsf(iir_light_flux(&l).y / (float)phi - 0.5f) < 1e-6f);
        /* inner = outer: I0 times the cone's solid angle, less the ramp of width 1e-3 in cos
         * that the specification's max(1e-3, ...) leaves (t^2 over it keeps a third) */
        if (cases[k][0] == cases[k][1])
            assert_true(fabs(phi - l.intensity.x * 2 * IIR_PI *
                                       (1 - cos(l.cone_angle) - 2.0 / 3.0 * 1e-3)) < 1e-5 * phi);
    }
}

/* Emission samples of a glTF spot: in the cone, beta = I(dir) 2 pi (1 - cos outer), mean = flux;
 * and their directions follow I: the flux inside the inner cone is I0 2 pi (1 - cos inner). */
static void test_gltf_emission_sampling(void **state)
{
    (void)state;
    iir_light l = make_gltf_spot(50.f, 25.f);
    iir_frame fr = iir_spot_frame(&l);
    iir_rng rng = iir_rng_make(77, 3);
    double sum = 0, inner = 0, cap = 2 * IIR_PI * (1 - cos(l.cone_angle));
    enum { N = 400000 };
    for (int i = 0; i < N; i++) {
        iir_light_ray r = iir_light_sample_emission(&l, iir_rng_uniform2(&rng));
        float c = iir_dot(r.dir, fr.f);
        assert_true(c >= cosf(l.cone_angle) - 1e-5f);
        assert_true(fabs(r.beta.x - iir_light_intensity(&l, r.dir).x * cap) < 1e-3 * cap);
        assert_true(iir_length(iir_sub(r.origin, l.position)) == 0.f);
        sum += r.beta.x;
        if (c > cosf(l.inner_angle)) inner += r.beta.x;
    }
    double phi = iir_light_flux(&l).x,
           phi_in = l.intensity.x * 2 * IIR_PI * (1 - cos(l.inner_angle));
    print_message("gltf emission: mean %.5g flux %.5g; inner %.5g expected %.5g\n", sum / N, phi,
                  inner / N, phi_in);
    assert_true(fabs(sum / N - phi) < 0.005 * phi);
    assert_true(fabs(inner / N - phi_in) < 0.01 * phi_in);
}

/* ---- the sun ---- */

static iir_light make_sun(void)
{
    iir_light l = {.type = IIR_LIGHT_SUN, .name = "sun"};
    l.direction = iir_normalize(iir_v3(0.3f, -1.f, 0.2f));
    l.up = iir_v3(0, 1, 0);
    l.intensity = iir_v3(3.f, 2.f, 1.f);
    iir_scene sc;
    memset(&sc, 0, sizeof sc);
    sc.bounds_min = iir_v3(-1.f, 0.f, -2.f);
    sc.bounds_max = iir_v3(1.f, 2.f, 2.f);
    iir_light_fit_sun(&l, &sc);
    return l;
}

static void test_sun_fit_and_flux(void **state)
{
    (void)state;
    iir_light l = make_sun();
    iir_error err = {0};
    assert_int_equal(iir_light_validate(&l, &err), IIR_OK);
    assert_true(iir_length(iir_sub(l.position, iir_v3(0, 1, 0))) < 1e-6f);
    float r = 0.5f * 1.001f * sqrtf(4.f + 4.f + 16.f);
    assert_true(fabsf(l.radius - r) < 1e-5f);
    assert_true(fabsf(iir_light_flux(&l).x - 3.f * IIR_PI * r * r) < 1e-4f);
    assert_true(iir_is_black(iir_light_intensity(&l, iir_neg(l.direction))));
    assert_string_equal(iir_light_kind(&l), "sun");
    /* other lights are left alone; a point scene still gets a disk of at least 1e-3 */
    iir_light spot = make_spot(30.f, 0.f), before = spot;
    iir_scene sc;
    memset(&sc, 0, sizeof sc);
    iir_light_fit_sun(&spot, &sc);
    assert_memory_equal(&spot, &before, sizeof spot);
    iir_light_fit_sun(&l, &sc);
    assert_true(l.radius == 1e-3f);
}

/* Sun emission: origins uniform on its disk, on the plane `radius` behind the centre, all along
 * `direction`, each carrying E pi r^2: the mean is the flux and the origins' spread is the disk's.
 */
static void test_sun_emission_sampling(void **state)
{
    (void)state;
    iir_light l = make_sun();
    iir_frame fr = iir_spot_frame(&l);
    iir_rng rng = iir_rng_make(5, 5);
    enum { N = 100000 };
    double sum = 0, m2 = 0, mx = 0, my = 0;
    for (int i = 0; i < N; i++) {
        iir_light_ray r = iir_light_sample_emission(&l, iir_rng_uniform2(&rng));
        assert_true(iir_length(iir_sub(r.dir, fr.f)) < 1e-6f);
        iir_vec3 d = iir_sub(r.origin, l.position);
        assert_true(fabsf(iir_dot(d, fr.f) + l.radius) < 1e-4f * l.radius);
        float x = iir_dot(d, fr.r) / l.radius, y = iir_dot(d, fr.u) / l.radius;
        assert_true(x * x + y * y <= 1.f + 1e-4f);
        sum += r.beta.x;
        mx += x, my += y, m2 += x * x + y * y;
    }
    double phi = iir_light_flux(&l).x;
    assert_true(fabs(sum / N - phi) < 1e-4 * phi);
    assert_true(fabs(mx / N) < 0.01 && fabs(my / N) < 0.01);
    assert_true(fabs(m2 / N - 0.5) < 0.01); /* E|s|^2 = 1/2 on the unit disk */
}

/* The light set's sample of a sun: from -direction, at no finite distance, Li = E, pdf the pmf. */
static void test_lightset_sun(void **state)
{
    (void)state;
    iir_scene sc;
    memset(&sc, 0, sizeof sc);
    iir_light lights[2] = {make_sun(), make_spot(30.f, 0.f)};
    lights[0].direction = iir_v3(0.f, -2.f, 0.f); /* not unit: wi is */
    iir_lightset *set = iir_lightset_create(&sc, lights, 2);
    assert_non_null(set);
    double f0 = iir_luminance(iir_light_flux(&lights[0]));
    double f1 = iir_luminance(iir_light_flux(&lights[1]));
    iir_light_sample ls = sample_at(set, iir_v3(0.5f, 0.f, 0.f), 0.f, iir_v2(0.5f, 0.5f));
    assert_true(ls.is_delta);
    assert_true(isinf(ls.dist) && ls.dist > 0.f);
    assert_true(iir_length(iir_sub(ls.wi, iir_v3(0, 1, 0))) < 1e-6f);
    assert_true(iir_length(iir_sub(ls.Li, lights[0].intensity)) < 1e-6f);
    assert_true(fabs(ls.pdf - f0 / (f0 + f1)) < 1e-5);
    iir_lightset_destroy(set);
}

static void test_gltf_and_sun_validation(void **state)
{
    (void)state;
    iir_error err = {0};
    iir_light l = make_gltf_spot(40.f, 40.f);
    assert_int_equal(iir_light_validate(&l, &err), IIR_OK);
    l = make_gltf_spot(40.f, 41.f);
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "inner angle"));
    assert_non_null(strstr(err.msg, "gspot"));
    l = make_gltf_spot(40.f, 10.f);
    l.inner_angle = -0.1f;
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
    l.inner_angle = NAN;
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
    l = make_gltf_spot(100.f, 10.f);
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "cone angle"));
    l = make_gltf_spot(40.f, 10.f);
    l.profile = (iir_spot_profile)7;
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "profile"));

    iir_light sun = make_sun();
    sun.cone_angle = 0.f; /* a sun has no cone */
    assert_int_equal(iir_light_validate(&sun, &err), IIR_OK);
    sun.radius = 0.f;
    assert_int_equal(iir_light_validate(&sun, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "radius"));
    sun.radius = INFINITY;
    assert_int_equal(iir_light_validate(&sun, &err), IIR_ERR_INVALID);
    sun.radius = NAN;
    assert_int_equal(iir_light_validate(&sun, &err), IIR_ERR_INVALID);
    sun = make_sun();
    sun.direction = iir_v3s(0.f);
    assert_int_equal(iir_light_validate(&sun, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "direction"));
    sun = make_sun();
    sun.intensity.x = -1.f;
    assert_int_equal(iir_light_validate(&sun, &err), IIR_ERR_INVALID);
    sun = make_sun();
    sun.type = (iir_light_type)9;
    assert_int_equal(iir_light_validate(&sun, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "type"));

    iir_light point = {.type = IIR_LIGHT_POINT}, cos_spot = make_spot(30.f, 0.f);
    assert_string_equal(iir_light_kind(&point), "point");
    assert_string_equal(iir_light_kind(&cos_spot), "spot");
}

/* ---- the area light ---- */

static iir_light make_area(void)
{
    iir_light l = {.type = IIR_LIGHT_AREA, .name = "panel"};
    l.position = iir_v3(0.2f, 1.5f, -0.3f);
    l.direction = iir_normalize(iir_v3(0.3f, -1.f, 0.2f));
    l.up = iir_v3(0.f, 0.f, 1.f);
    l.size = iir_v2(0.6f, 0.25f);
    l.intensity = iir_v3(4.f, 3.f, 2.f);
    return l;
}

/* make_area's light, emitting from the 32-gon inscribed in its rectangle (an ellipse-like lamp). */
static iir_light make_disc(void)
{
    iir_light l = make_area();
    iir_test_disc_shape(&l.shape, 32);
    return l;
}

/* Light-local coordinates of world point x on area light l (q in [-1/2, 1/2]^2 on it) and its
 * height above the plane along f. */
static iir_vec3 area_local(const iir_light *l, iir_vec3 x)
{
    iir_frame fr = iir_spot_frame(l);
    iir_vec3 d = iir_sub(x, l->position);
    return iir_v3(iir_dot(d, fr.r) / l->size.x, iir_dot(d, fr.u) / l->size.y, iir_dot(d, fr.f));
}

static void test_area_validation_flux_intensity(void **state)
{
    (void)state;
    iir_error err = {0};
    iir_light l = make_area();
    assert_int_equal(iir_light_validate(&l, &err), IIR_OK);
    assert_string_equal(iir_light_kind(&l), "area");
    const float bad[] = {0.f, -1.f, NAN, INFINITY};
    for (int k = 0; k < 4; k++) {
        l = make_area();
        l.size.y = bad[k];
        assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
        assert_non_null(strstr(err.msg, "size"));
        assert_non_null(strstr(err.msg, "panel"));
        l = make_area();
        l.size.x = bad[k];
        assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
    }
    l = make_area();
    l.direction = iir_v3s(0.f);
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "direction"));
    l = make_area();
    l.intensity.z = -1.f;
    assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);

    /* Phi = pi L w h, and the far-field lobe L w h cos integrates to it */
    l = make_area();
    float A = l.size.x * l.size.y;
    iir_vec3 phi = iir_light_flux(&l), num = integrate_intensity(&l);
    assert_true(fabsf(phi.x - IIR_PI * 4.f * A) < 1e-5f * phi.x);
    assert_true(fabsf(phi.z - IIR_PI * 2.f * A) < 1e-5f * phi.z);
    assert_true(fabsf(num.x - phi.x) < 5e-3f * phi.x);
    iir_frame fr = iir_spot_frame(&l);
    assert_true(fabsf(iir_light_intensity(&l, fr.f).y - 3.f * A) < 1e-5f);
    iir_vec3 w60 = iir_add(iir_scale(fr.f, 0.5f), iir_scale(fr.r, sqrtf(0.75f)));
    assert_true(fabsf(iir_light_intensity(&l, w60).y - 1.5f * A) < 1e-5f);
    assert_true(iir_is_black(iir_light_intensity(&l, iir_neg(fr.f))));
}

/* Emission: origins uniform on the rectangle (E q = 0, E q^2 = 1/12), directions the cosine lobe
 * about f (E cos = 2/3, E cos^2 = 1/2), beta = pi L w h, so the mean is the flux; the 2-D call's
 * hashed origins are as uniform and uncorrelated with the directions. */
static void check_area_emission(const iir_light *l, bool hashed)
{
    iir_frame fr = iir_spot_frame(l);
    iir_rng rng = iir_rng_make(17, hashed);
    enum { N = 200000 };
    double m[2] = {0, 0}, m2[2] = {0, 0}, c1 = 0, c2 = 0, corr = 0, sum = 0;
    for (int i = 0; i < N; i++) {
        iir_vec2 u = iir_rng_uniform2(&rng);
        iir_light_ray r = hashed ? iir_light_sample_emission(l, u)
                                 : iir_light_sample_emission_from(l, u, iir_rng_uniform2(&rng));
        iir_vec3 q = area_local(l, r.origin);
        assert_true(fabsf(q.x) <= 0.5f + 1e-5f && fabsf(q.y) <= 0.5f + 1e-5f);
        assert_true(fabsf(q.z) < 1e-5f);
        float c = iir_dot(r.dir, fr.f);
        assert_true(c >= 0.f && fabsf(iir_length(r.dir) - 1.f) < 1e-5f);
        m[0] += q.x, m[1] += q.y, m2[0] += q.x * q.x, m2[1] += q.y * q.y;
        c1 += c, c2 += c * c, corr += q.x * iir_dot(r.dir, fr.r);
        sum += r.beta.x;
    }
    for (int k = 0; k < 2; k++) {
        assert_true(fabs(m[k] / N) < 0.003);
        assert_true(fabs(m2[k] / N - 1.0 / 12) < 0.002);
    }
    assert_true(fabs(c1 / N - 2.0 / 3) < 0.003 && fabs(c2 / N - 0.5) < 0.003);
    assert_true(fabs(corr / N) < 0.003); /* E[q.x w.r] = 0 for independent origin and direction */
    double phi = iir_light_flux(l).x;
    assert_true(fabs(sum / N - phi) < 1e-5 * phi);
}

static void test_area_emission_sampling(void **state)
{
    (void)state;
    iir_light l = make_area();
    check_area_emission(&l, false);
    check_area_emission(&l, true);
    /* u_origin is the corner-to-corner map q = u_origin - 1/2 */
    iir_frame fr = iir_spot_frame(&l);
    iir_light_ray r = iir_light_sample_emission_from(&l, iir_v2(0.5f, 0.5f), iir_v2(0.f, 1.f));
    iir_vec3 corner = iir_madd(iir_madd(l.position, fr.r, -0.3f), fr.u, 0.125f);
    assert_true(iir_length(iir_sub(r.origin, corner)) < 1e-5f);
    assert_true(iir_length(iir_sub(r.dir, fr.f)) < 1e-5f); /* the disk's centre is the normal */
}

/* Rays aimed at points of the rectangle's plane, inside and outside it, from both sides. */
static void test_area_hit(void **state)
{
    (void)state;
    iir_light l = make_area();
    iir_frame fr = iir_spot_frame(&l);
    iir_rng rng = iir_rng_make(3, 3);
    int hits = 0;
    for (int i = 0; i < 20000; i++) {
        float qx = 1.4f * iir_rng_uniform(&rng) - 0.7f, qy = 1.4f * iir_rng_uniform(&rng) - 0.7f;
        iir_vec3 x = iir_area_light_point(&l, &fr, iir_v2(qx, qy));
        iir_vec3 w = iir_normalize(iir_v3(iir_rng_uniform(&rng) - .5f, iir_rng_uniform(&rng) - .5f,
                                          iir_rng_uniform(&rng) - .5f));
        float t0 = 0.1f + 3.f * iir_rng_uniform(&rng), len = 0.5f + iir_rng_uniform(&rng);
        iir_vec3 d = iir_scale(w, len), o = iir_madd(x, d, -t0 / len);
        float tmax = i % 4 == 0 ? 0.9f * t0 / len : INFINITY;
        float t = iir_area_light_hit(&l, o, d, tmax);
        bool inside = fabsf(qx) < 0.4999f && fabsf(qy)<0.4999f, outside = fabsf(qx)> 0.5001f ||
                      fabsf(qy) > 0.5001f;
        bool front = iir_dot(w, fr.f)<-1e-3f, behind = iir_dot(w, fr.f)> 1e-3f;
        if (inside && front && i % 4) {
            assert_true(fabsf(t * len - t0) < 1e-4f * (1.f + t0));
            hits++;
        }
        if (outside || behind || i % 4 == 0) assert_true(isinf(t));
    }
    assert_true(hits > 2000);
    /* parallel to the plane, and starting on its far side */
    assert_true(isinf(iir_area_light_hit(&l, iir_madd(l.position, fr.f, 0.1f), fr.r, INFINITY)));
    assert_true(
        isinf(iir_area_light_hit(&l, iir_madd(l.position, fr.f, -0.1f), iir_neg(fr.f), 1.f)));
    assert_true(fabsf(iir_area_light_hit(&l, iir_madd(l.position, fr.f, 0.1f), iir_neg(fr.f), 1.f) -
                      0.1f) < 1e-5f);
}

/* The form factor from a point to a parallel rectangle [0, a] x [0, b] (a, b signed) at height c
 * whose corner lies straight above it; F is odd in a and in b, so signed corners add up any
 * rectangle in the plane. E = pi L F. */
static double corner_form_factor(double a, double b, double c)
{
    double A = a / c, B = b / c, sa = sqrt(1 + A * A), sb = sqrt(1 + B * B);
    return (A / sa * atan(B / sa) + B / sb * atan(A / sb)) / (2 * M_PI);
}

/* Irradiance at x from area light l when x lies on a plane parallel to it and faces it. */
static double area_irradiance(const iir_light *l, iir_vec3 x, double L)
{
    iir_vec3 q = area_local(l, x);
    double c = -q.z, x0 = (-0.5 - q.x) * l->size.x, x1 = (0.5 - q.x) * l->size.x;
    double y0 = (-0.5 - q.y) * l->size.y, y1 = (0.5 - q.y) * l->size.y;
    double F = corner_form_factor(x1, y1, c) - corner_form_factor(x0, y1, c) -
               corner_form_factor(x1, y0, c) + corner_form_factor(x0, y0, c);
    return M_PI * L * F;
}

/* NEE of an area light through the set: points on the rectangle, pdf d^2 / (A cos) times the pick
 * probability, equal to what iir_lightset_hit_light reports for a BSDF ray to the same point; the
 * estimate of the irradiance on a parallel plane matches the form factor; nothing from behind. */
static void test_lightset_area(void **state)
{
    (void)state;
    iir_scene sc;
    memset(&sc, 0, sizeof sc);
    iir_light lights[2] = {make_area(), make_spot(30.f, 0.f)};
    iir_lightset *set = iir_lightset_create(&sc, lights, 2);
    assert_non_null(set);
    assert_true(iir_lightset_has_area_lights(set));
    assert_int_equal(iir_lightset_num_lights(set), 2);
    double f0 = iir_luminance(iir_light_flux(&lights[0]));
    double pmf = f0 / (f0 + iir_luminance(iir_light_flux(&lights[1])));
    iir_frame fr = iir_spot_frame(&lights[0]);
    const iir_vec2 offsets[] = {{0.f, 0.f}, {0.4f, -0.2f}, {1.5f, 1.f}};
    for (int k = 0; k < 3; k++) {
        iir_vec3 x = iir_madd(iir_area_light_point(&lights[0], &fr, offsets[k]), fr.f, 0.7f);
        iir_rng rng = iir_rng_make(11, (uint64_t)k);
        enum { N = 100000 };
        double E = 0;
        for (int i = 0; i < N; i++) {
            iir_light_sample ls = sample_at(set, x, 0.f, iir_rng_uniform2(&rng));
            assert_false(ls.is_delta);
            assert_true(ls.pdf > 0.f);
            assert_true(fabsf(area_local(&lights[0], iir_madd(x, ls.wi, ls.dist)).z) < 1e-4f);
            iir_emitter_hit h = iir_lightset_hit_light(set, 0, x, ls.wi, INFINITY);
            assert_true(fabsf(h.t - ls.dist) < 1e-4f * ls.dist);
            assert_true(fabsf(h.pdf - ls.pdf) < 1e-3f * ls.pdf);
            assert_true(fabs(ls.pdf / pmf - iir_area_light_pdf(&lights[0], ls.wi, ls.dist)) <
                        1e-3f * ls.pdf / pmf);
            E += ls.Li.x * iir_dot(ls.wi, iir_neg(fr.f)) / ls.pdf * pmf; /* one light's share */
        }
        double expect = area_irradiance(&lights[0], x, lights[0].intensity.x);
        print_message("area light irradiance at offset %d: %.5f, form factor %.5f\n", k, E / N,
                      expect);
        assert_true(fabs(E / N - expect) < 0.01 * expect);
    }
    /* behind the light: no sample, and a BSDF ray from there meets nothing */
    iir_vec3 back = iir_madd(lights[0].position, fr.f, -0.5f);
    iir_light_sample ls = sample_at(set, back, 0.f, iir_v2(0.3f, 0.6f));
    assert_true(ls.pdf == 0.f);
    assert_true(isinf(iir_lightset_hit_light(set, 0, back, fr.f, INFINITY).t));
    assert_true(isinf(iir_lightset_hit_light(set, 1, back, fr.f, INFINITY).t)); /* a spot: never */
    iir_lightset_destroy(set);
}

static void check_pdf_integrates_to_one(const iir_scene *scp, const iir_light *lp);

/* The MIS pdf is a density: over directions uniform on the sphere (pdf 1 / 4 pi), the mean of
 * pdf / (1 / 4 pi) is 1, within 4 standard errors (and 2%). */
static void test_area_pdf_integrates_to_one(void **state)
{
    (void)state;
    iir_scene sc;
    memset(&sc, 0, sizeof sc);
    for (int disc = 0; disc < 2; disc++) {
        iir_light l = disc ? make_disc() : make_area();
        check_pdf_integrates_to_one(&sc, &l);
    }
}

/* ======================== shaped area lights ======================== */

/* Whether light-local q lies in the regular n-gon of iir_test_disc_shape (corners at radius 1/2,
 * angles 2 pi k / n), by its own polar test: inside when q's distance along the normal of the edge
 * of its sector is at most the apothem. */
static bool in_ngon(int n, double x, double y)
{
    double t = atan2(y, x), step = 2 * M_PI / n;
    if (t < 0) t += 2 * M_PI;
    double mid = (floor(t / step) + 0.5) * step;
    return x * cos(mid) + y * sin(mid) <= 0.5 * cos(M_PI / n);
}

/* The L-shaped panel: the rectangle without its (+x, +y) quarter, as 6 triangles. */
static iir_light make_l_panel(void)
{
    iir_light l = make_area();
    static const float quads[3][2] = {{-0.5f, -0.5f}, {0.f, -0.5f}, {-0.5f, 0.f}};
    for (int k = 0; k < 3; k++) {
        float x = quads[k][0], y = quads[k][1];
        iir_vec2 a = {x, y}, b = {x + 0.5f, y}, c = {x + 0.5f, y + 0.5f}, d = {x, y + 0.5f};
        iir_vec2 *t = l.shape.tri[2 * k];
        t[0] = a, t[1] = b, t[2] = c;
        t = l.shape.tri[2 * k + 1];
        t[0] = a, t[1] = c, t[2] = d;
    }
    l.shape.num_triangles = 6;
    return l;
}

static bool in_l_panel(iir_vec2 q)
{
    return fabsf(q.x) <= 0.5f && fabsf(q.y) <= 0.5f && !(q.x > 0.f && q.y > 0.f);
}

/* A shape's area and flux: Phi = pi L w h a with a = n sin(2 pi / n) / 8 for the n-gon (the
 * closed form, not the triangles' sum), 3/4 for the L; the far-field lobe integrates to it; every
 * broken shape is refused, naming it. */
static void test_area_shape_flux_and_check(void **state)
{
    (void)state;
    iir_error err = {0};
    iir_light l = make_disc();
    assert_int_equal(iir_light_validate(&l, &err), IIR_OK);
    double a = 32 * sin(2 * M_PI / 32) / 8, A = a * l.size.x * l.size.y;
    assert_true(fabs(iir_area_light_area(&l) - A) < 1e-5 * A);
    iir_vec3 phi = iir_light_flux(&l), num = integrate_intensity(&l);
    assert_true(fabs(phi.x - M_PI * 4.0 * A) < 1e-5 * phi.x);
    assert_true(fabsf(num.x - phi.x) < 5e-3f * phi.x);
    l = make_l_panel();
    assert_int_equal(iir_light_validate(&l, &err), IIR_OK);
    assert_true(fabsf(iir_area_shape_fraction(&l.shape) - 0.75f) < 1e-6f);
    assert_true(fabsf(iir_light_flux(&l).y - IIR_PI * 3.f * 0.75f * 0.15f) < 1e-5f);
    /* broken shapes */
    static const char *const problems[] = {"more than 64", "outside",     "outside",
                                           "degenerate",   "overlapping", "overlapping"};
    for (int k = 0; k < 6; k++) {
        l = make_disc();
        iir_vec2 *t = l.shape.tri[3];
        if (k == 0) l.shape.num_triangles = IIR_AREA_MAX_TRIANGLES + 1;
        if (k == 1) t[1].x = 0.51f;
        if (k == 2) t[2].y = NAN;
        if (k == 3) t[2] = iir_v2(0.5f * t[1].x, 0.5f * t[1].y);      /* on the edge t0 t1 */
        if (k == 4) memcpy(l.shape.tri[4], t, sizeof l.shape.tri[4]); /* the same twice */
        if (k == 5) t[0] = iir_v2(-0.2f * t[1].x, -0.2f * t[1].y); /* reaches into its neighbours */
        assert_int_equal(iir_light_validate(&l, &err), IIR_ERR_INVALID);
        print_message("%s\n", err.msg);
        assert_non_null(strstr(err.msg, "light 'panel': its shape"));
        assert_non_null(strstr(err.msg, problems[k]));
    }
}

/* Emission from the disc: origins on the n-gon only and uniform by area over it (an 8 x 8
 * histogram of q against the cells' shares of the n-gon, measured by the test's own polygon test
 * on a fine grid; each within 5 standard deviations), beta = the flux; from the L: no origin in
 * the missing quarter, a third in each other one. */
static void test_area_shape_sampling(void **state)
{
    (void)state;
    enum { N = 200000, G = 8, SUB = 64 };
    iir_light l = make_disc();
    double want[G][G] = {{0}}, got[G][G] = {{0}}, beta = 0, inside = 0;
    for (int j = 0; j < G * SUB; j++)
        for (int i = 0; i < G * SUB; i++) {
            double x = (i + 0.5) / (G * SUB) - 0.5, y = (j + 0.5) / (G * SUB) - 0.5;
            bool in = in_ngon(32, x, y);
            want[j / SUB][i / SUB] += in, inside += in;
        }
    iir_rng rng = iir_rng_make(31, 0);
    for (int n = 0; n < N; n++) {
        iir_light_ray r = iir_light_sample_emission(&l, iir_rng_uniform2(&rng));
        iir_vec3 q = area_local(&l, r.origin);
        assert_true(in_ngon(32, q.x * 0.9999, q.y * 0.9999));
        int i = (int)floor((q.x + 0.5) * G), j = (int)floor((q.y + 0.5) * G);
        got[j < 0 ? 0 : j >= G ? G - 1 : j][i < 0 ? 0 : i >= G ? G - 1 : i] += 1;
        beta += r.beta.x;
    }
    int bad = 0;
    for (int j = 0; j < G; j++)
        for (int i = 0; i < G; i++) {
            double e = N * want[j][i] / inside;
            bad += fabs(got[j][i] - e) > 5 * sqrt(e) + 1;
        }
    assert_int_equal(bad, 0);
    assert_true(fabs(beta / N - iir_light_flux(&l).x) < 1e-5 * iir_light_flux(&l).x);
    l = make_l_panel();
    double quarter[3] = {0};
    for (int n = 0; n < N; n++) {
        iir_light_ray r =
            iir_light_sample_emission_from(&l, iir_rng_uniform2(&rng), iir_rng_uniform2(&rng));
        iir_vec3 q = area_local(&l, r.origin);
        assert_true(fabsf(q.x) <= 0.5f + 1e-5f && fabsf(q.y) <= 0.5f + 1e-5f);
        assert_false(q.x > 1e-5f && q.y > 1e-5f); /* not in the missing quarter */
        quarter[q.y < 0 ? (q.x < 0 ? 0 : 1) : 2] += 1;
    }
    for (int k = 0; k < 3; k++) assert_true(fabs(quarter[k] - N / 3.0) < 5 * sqrt(N * 2.0 / 9));
}

/* Rays at points in and around the L: they meet it exactly where the test's own test puts the
 * point on it (away from its edges), never in the missing quarter. */
static void test_area_shape_hit(void **state)
{
    (void)state;
    iir_light l = make_l_panel();
    iir_frame fr = iir_spot_frame(&l);
    iir_rng rng = iir_rng_make(5, 5);
    int hits = 0, checked = 0;
    for (int i = 0; i < 20000; i++) {
        iir_vec2 q =
            iir_v2(1.4f * iir_rng_uniform(&rng) - 0.7f, 1.4f * iir_rng_uniform(&rng) - 0.7f);
        float edge = fminf(fminf(fabsf(fabsf(q.x) - 0.5f), fabsf(fabsf(q.y) - 0.5f)),
                           q.x > 0.f && q.y > 0.f ? fminf(q.x, q.y) : 1.f);
        if (edge < 1e-3f) continue;
        iir_vec3 x = iir_area_light_point(&l, &fr, q);
        iir_vec3 o = iir_madd(x, fr.f, 0.5f + iir_rng_uniform(&rng));
        o = iir_madd(o, fr.r, iir_rng_uniform(&rng) - 0.5f);
        float t = iir_area_light_hit(&l, o, iir_sub(x, o), INFINITY);
        bool on = in_l_panel(q);
        assert_int_equal(on, !isinf(t));
        assert_int_equal(on, iir_area_light_contains(&l, q));
        if (on) assert_true(fabsf(t - 1.f) < 1e-4f);
        hits += on, checked++;
    }
    assert_true(hits > checked / 3);
}

/* NEE of the disc through the set against the irradiance integrated over the n-gon by the test
 * (midpoint rule on a 400 x 400 grid of the rectangle, the test's own polygon test), within 1%. */
static void test_lightset_disc(void **state)
{
    (void)state;
    iir_scene sc;
    memset(&sc, 0, sizeof sc);
    iir_light l = make_disc();
    iir_lightset *set = iir_lightset_create(&sc, &l, 1);
    iir_frame fr = iir_spot_frame(&l);
    const iir_vec2 offsets[] = {{0.f, 0.f}, {0.45f, -0.3f}, {1.2f, 0.8f}};
    for (int k = 0; k < 3; k++) {
        iir_vec3 x = iir_madd(iir_area_light_point(&l, &fr, offsets[k]), fr.f, 0.35f);
        iir_vec3 n = iir_neg(fr.f);
        enum { G = 400 };
        double want = 0, dA = l.size.x * l.size.y / (double)(G * G);
        for (int j = 0; j < G; j++)
            for (int i = 0; i < G; i++) {
                double qx = (i + 0.5) / G - 0.5, qy = (j + 0.5) / G - 0.5;
                if (!in_ngon(32, qx, qy)) continue;
                iir_vec3 p = iir_area_light_point(&l, &fr, iir_v2((float)qx, (float)qy));
                iir_vec3 d = iir_sub(p, x);
                double d2 = iir_length_sq(d), c = iir_dot(d, n) / sqrt(d2);
                want += l.intensity.x * c * c / d2 * dA; /* cos at x = cos at the light here */
            }
        iir_rng rng = iir_rng_make(41, (uint64_t)k);
        enum { N = 200000 };
        double E = 0;
        for (int i = 0; i < N; i++) {
            iir_light_sample ls = sample_at(set, x, 0.5f, iir_rng_uniform2(&rng));
            assert_true(ls.pdf > 0.f);
            iir_emitter_hit h = iir_lightset_hit_light(set, 0, x, ls.wi, INFINITY);
            assert_true(fabsf(h.pdf - ls.pdf) < 1e-3f * ls.pdf);
            E += ls.Li.x * iir_dot(ls.wi, n) / ls.pdf;
        }
        print_message("disc irradiance at offset %d: %.5f, integrated %.5f\n", k, E / N, want);
        assert_true(fabs(E / N - want) < 0.01 * want);
    }
    iir_lightset_destroy(set);
}

/* (the rectangle's and the disc's: the pdf over the sphere of directions has mean 1) */
static void check_pdf_integrates_to_one(const iir_scene *scp, const iir_light *lp)
{
    iir_scene sc = *scp;
    iir_light l = *lp;
    iir_lightset *set = iir_lightset_create(&sc, &l, 1);
    iir_frame fr = iir_spot_frame(&l);
    iir_vec3 x = iir_madd(iir_area_light_point(&l, &fr, iir_v2(0.3f, 0.1f)), fr.f, 0.4f);
    iir_rng rng = iir_rng_make(21, 0);
    enum { N = 2000000 };
    double sum = 0, sum2 = 0;
    for (int i = 0; i < N; i++) {
        iir_vec2 u = iir_rng_uniform2(&rng);
        float z = 1.f - 2.f * u.x, r = sqrtf(fmaxf(0.f, 1.f - z * z)), ph = 2.f * IIR_PI * u.y;
        iir_vec3 w = iir_v3(r * cosf(ph), r * sinf(ph), z);
        double v = iir_lightset_hit_light(set, 0, x, w, INFINITY).pdf * 4.0 * M_PI;
        sum += v, sum2 += v * v;
    }
    double mean = sum / N, se = sqrt((sum2 / N - mean * mean) / N);
    print_message("area light: integral of the MIS pdf %.4f +- %.4f\n", mean, se);
    assert_true(fabs(mean - 1.0) < 4 * se && fabs(mean - 1.0) < 0.02);
    iir_lightset_destroy(set);
}

/* The 8-lane delta-light sampler (the direct-light kernel) against iir_light_sample_li lane by
 * lane (and the 16-lane one against two 8-lane calls, bit for bit), for every delta kind (a spot
 * with and without a smooth edge, a glTF spot, a point, a sun), at receivers around and behind each
 * light: the same light and the same shadow segment up to float rounding (FMA, vector reciprocal
 * square roots with a Newton step: 1e-5 relative, the light's to its intensity over d^2), nothing
 * where the scalar path gives nothing. */
static void test_delta_lanes_match_scalar(void **state)
{
    (void)state;
    if (!iir_isa_supported(IIR_ISA_AVX2)) {
        print_message("no AVX2 on this machine: the lanes are not run\n");
        return;
    }
    iir_light point = {.type = IIR_LIGHT_POINT, .name = "point"};
    point.position = iir_v3(0.1f, 1.2f, 0.3f);
    point.intensity = iir_v3(1.f, 2.f, 3.f);
    iir_light lights[] = {make_spot(40.f, 0.f), make_spot(50.f, 15.f), make_gltf_spot(45.f, 20.f),
                          point, make_sun()};
    const float eps = 1e-4f;
    iir_rng rng = iir_rng_make(7, 0);
    int lit = 0, tested = 0;
    for (size_t li = 0; li < sizeof lights / sizeof lights[0]; li++) {
        iir_light_eval e = iir_light_prepare(&lights[li]);
        for (int round = 0; round < 200; round++) {
            iir_light_lanes in;
            iir_light_ctx ctx[8];
            for (int k = 0; k < 8; k++) {
                iir_vec3 x =
                    iir_v3(4.f * iir_rng_uniform(&rng) - 2.f, 2.f * iir_rng_uniform(&rng) - 1.f,
                           4.f * iir_rng_uniform(&rng) - 2.f);
                iir_vec3 n =
                    iir_normalize(iir_v3(iir_rng_uniform(&rng) - 0.5f, iir_rng_uniform(&rng) - 0.2f,
                                         iir_rng_uniform(&rng) - 0.5f));
                if (k == 7 && round == 0) x = lights[li].position; /* at the light */
                in.px[k] = x.x, in.py[k] = x.y, in.pz[k] = x.z;
                in.nx[k] = n.x, in.ny[k] = n.y, in.nz[k] = n.z;
                ctx[k] = (iir_light_ctx){x, n, eps};
            }
            iir_light_delta_lanes out;
            iir_light_sample_delta8_avx2(&e, eps, &in, &out);
            /* 32 lanes: the same bits as four times 8 (the odd sets: the lanes reversed) */
            iir_light_lanes sets[4] = {in, in, in, in};
            float *planes[6] = {sets[1].px, sets[1].py, sets[1].pz,
                                sets[1].nx, sets[1].ny, sets[1].nz};
            const float *from[6] = {in.px, in.py, in.pz, in.nx, in.ny, in.nz};
            for (int q = 0; q < 6; q++)
                for (int k = 0; k < 8; k++) planes[q][k] = from[q][7 - k];
            sets[3] = sets[1];
            iir_light_delta_lanes wide[4], second;
            iir_light_sample_delta32_avx2(&e, eps, sets, wide);
            iir_light_sample_delta8_avx2(&e, eps, &sets[1], &second);
            for (int h = 0; h < 4; h++)
                assert_memory_equal(&wide[h], h % 2 ? &second : &out, sizeof out);
            for (int k = 0; k < 8; k++, tested++) {
                iir_light_sample ls = iir_light_sample_li(&e, &ctx[k], iir_v2(0.f, 0.f));
                float cos_x = iir_dot(ctx[k].n, ls.wi);
                bool arrives = ls.pdf > 0.f && !iir_is_black(ls.Li) && cos_x > 0.f;
                iir_vec3 E = iir_v3(out.Ex[k], out.Ey[k], out.Ez[k]);
                if (!arrives) {
                    assert_true(iir_is_black(E));
                    continue;
                }
                lit++;
                /* relative to the light without its profile and the cosine: a spot's smooth
                   edge is steep (slope 1.5 / (R - R_in) per unit of disk radius), and a dot
                   product's rounding is absolute (an ulp of |n| |wi|), so a few ulps move a
                   nearly dark edge's or a grazing receiver's value by much of itself */
                iir_vec3 want = iir_scale(ls.Li, cos_x);
                float peak =
                    iir_length(lights[li].intensity) / (isinf(ls.dist) ? 1.f : ls.dist * ls.dist);
                assert_true(iir_length(iir_sub(E, want)) <= 1e-5f * peak);
                assert_true(iir_length(iir_sub(iir_v3(out.wx[k], out.wy[k], out.wz[k]), ls.wi)) <
                            1e-5f);
                const iir_light_segment *seg = &ls.shadow;
                if (!(seg->tmax > 0.f)) {
                    assert_true(out.tmax[k] == 0.f);
                    continue;
                }
                assert_true(isinf(seg->tmax) ? isinf(out.tmax[k])
                                             : fabsf(out.tmax[k] - seg->tmax) <= 1e-5f * seg->tmax);
                assert_true(iir_length(iir_sub(iir_v3(out.ox[k], out.oy[k], out.oz[k]), seg->org)) <
                            1e-5f);
                assert_true(iir_length(iir_sub(iir_v3(out.dx[k], out.dy[k], out.dz[k]), seg->dir)) <
                            1e-5f);
            }
        }
    }
    print_message("delta lanes: %d of %d receivers lit, all as the scalar path\n", lit, tested);
    assert_true(lit > tested / 5 && lit < tested);
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
        cmocka_unit_test(test_cap_map),
        cmocka_unit_test(test_cap_map_uniform_solid_angle),
        cmocka_unit_test(test_gltf_spot_profile),
        cmocka_unit_test(test_gltf_spot_flux),
        cmocka_unit_test(test_gltf_emission_sampling),
        cmocka_unit_test(test_sun_fit_and_flux),
        cmocka_unit_test(test_sun_emission_sampling),
        cmocka_unit_test(test_lightset_sun),
        cmocka_unit_test(test_gltf_and_sun_validation),
        cmocka_unit_test(test_area_validation_flux_intensity),
        cmocka_unit_test(test_area_emission_sampling),
        cmocka_unit_test(test_area_hit),
        cmocka_unit_test(test_lightset_area),
        cmocka_unit_test(test_area_pdf_integrates_to_one),
        cmocka_unit_test(test_area_shape_flux_and_check),
        cmocka_unit_test(test_area_shape_sampling),
        cmocka_unit_test(test_area_shape_hit),
        cmocka_unit_test(test_lightset_disc),
        cmocka_unit_test(test_delta_lanes_match_scalar),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

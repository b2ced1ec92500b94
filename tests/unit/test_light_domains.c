/* test_light_domains.c -- every light kind's VPL domain (light_domain.h) through the incremental
 * step, in the built-in Cornell box (the area light both as a rectangular panel and as a disc lamp
 * of 32 triangles), against answers that share no code with the domains:
 *   - flux conservation: after 200 frames of random motion, the VPLs' fluxes sum to the flux the
 *     light sends onto reflecting surfaces times their albedo, measured by the test's own dense
 *     sampling of the light's emission (iir_light_sample_emission, light.c; escaping rays and rays
 *     onto emitters count zero, as null samples do), with Voronoi weights right after the motion
 *     and with both Voronoi and uniform weights after the light rests; for an area light also the
 *     same cells carrying the mean over fresh points of the emitter (where its bias comes from);
 *   - one bounce: ir and iir with 16k VPLs and exact visibility against pt with one bounce (same
 *     light), with the bound test_methods.c uses for the spot;
 *   - the disc lamp's emitter strata and its VPLs' origins lie on the disc, spread by area. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/incremental.h"
#include "iir/light.h"
#include "iir/light_domain.h"
#include "iir/method.h"
#include "iir/render.h"
#include "iir/rng.h"
#include "iir/scene.h"
#include "lights/domain_sites.h"
#include "surface.h"
#include "testutil.h"

typedef iir_test_cornell fixture;

/* ---- the lights ---- */

enum kind { COSINE_SPOT, GLTF_SPOT, POINT, SUN, AREA, DISC, KINDS };
static const char *const kind_name[KINDS] = {"cosine spot", "glTF spot", "point",
                                             "sun",         "area",      "disc"};

/* A point inside the box's bounds, t in [0, 1]^3 mapped to the middle 70% of each axis. */
static iir_vec3 inside(const fixture *f, iir_vec3 t)
{
    iir_vec3 lo = f->scene->bounds_min, ext = iir_sub(f->scene->bounds_max, lo);
    return iir_v3(lo.x + ext.x * (0.15f + 0.7f * t.x), lo.y + ext.y * (0.15f + 0.7f * t.y),
                  lo.z + ext.z * (0.15f + 0.7f * t.z));
}

/* The light of this kind at pose u (u = 0.5 everywhere: its rest pose). Spots hang under the
 * ceiling aiming down and turning up to ~40 degrees, and so do the area lights (the panel and a
 * disc lamp); the point wanders
 * the box; the sun shines in through the open front from above, turning by up to ~25 degrees. */
static iir_light light_of(const fixture *f, enum kind k, iir_vec3 u)
{
    iir_light l = {.name = "test", .up = iir_v3(0, 0, -1), .intensity = iir_v3(3, 2.2f, 1.4f)};
    iir_vec3 tilt = iir_v3(1.4f * (u.x - 0.5f), 0.f, 1.4f * (u.z - 0.5f));
    switch (k) {
    case COSINE_SPOT:
    case GLTF_SPOT:
        l.type = IIR_LIGHT_SPOT;
        l.position = inside(f, iir_v3(u.x, 0.95f + 0.05f * u.y, u.z));
        l.direction = iir_normalize(iir_add(iir_v3(0, -1, 0), tilt));
        l.cone_angle = iir_radians(k == GLTF_SPOT ? 55.f : 60.f);
        l.profile = k == GLTF_SPOT ? IIR_SPOT_GLTF : IIR_SPOT_COSINE;
        l.inner_angle = iir_radians(20.f);
        break;
    case POINT:
        l.type = IIR_LIGHT_POINT;
        l.position = inside(f, u);
        l.intensity = iir_scale(l.intensity, 0.3f);
        break;
    case SUN:
        l.type = IIR_LIGHT_SUN;
        l.direction = iir_normalize(iir_add(iir_v3(0.15f, -0.55f, -1.f), iir_scale(tilt, 0.5f)));
        l.up = iir_v3(0, 1, 0);
        l.intensity = iir_scale(l.intensity, 0.5f);
        iir_light_fit_sun(&l, f->scene);
        break;
    case AREA: /* the Cornell box's panel, 0.47 x 0.38, turning with the tilt */
        l.type = IIR_LIGHT_AREA;
        l.position = inside(f, iir_v3(u.x, 0.97f, u.z));
        l.direction = iir_normalize(iir_add(iir_v3(0, -1, 0), tilt));
        l.size = iir_v2(0.47f, 0.38f);
        l.intensity = iir_scale(l.intensity, 5.f);
        break;
    case DISC: /* a disc lamp of 32 triangles, 0.5 across, where the panel is */
        l.type = IIR_LIGHT_AREA;
        l.position = inside(f, iir_v3(u.x, 0.97f, u.z));
        l.direction = iir_normalize(iir_add(iir_v3(0, -1, 0), tilt));
        l.size = iir_v2(0.5f, 0.5f);
        iir_test_disc_shape(&l.shape, 32);
        l.intensity = iir_scale(l.intensity, 5.f);
        break;
    case KINDS:
        break;
    }
    return l;
}

/* ---- the test's own measure of the flux onto reflecting surfaces ---- */

/* The albedo of the reflecting surface the ray from o along unit w reaches facing it, or NULL when
 * it escapes or reaches an emitter or a back face (what a null sample is). */
static const iir_vec3 *reflector(const fixture *f, iir_vec3 o, iir_vec3 w, iir_raystats *st)
{
    iir_ray ray = iir_make_ray(o, w, 0.f, INFINITY);
    iir_hit hit;
    if (!iir_rt_intersect(f->rt, &ray, &hit, st, IIR_RAYS_BENCH)) return NULL;
    iir_surface sf = iir_surface_at(f->scene, &hit, iir_neg(w));
    if (!iir_is_black(sf.mat->emission) || !(iir_dot(sf.ns, iir_neg(w)) > 0.f)) return NULL;
    return &sf.mat->albedo;
}

/* E[beta rho] over M emission samples: the flux a perfect VPL set carries, per channel. */
static iir_vec3 dense_reflected(const fixture *f, const iir_light *l, int M)
{
    double sum[3] = {0, 0, 0};
    iir_rng rng = iir_rng_make(99, 1);
    iir_raystats st = {{0}};
    for (int i = 0; i < M; i++) {
        iir_light_ray r = iir_light_sample_emission(l, iir_rng_uniform2(&rng));
        const iir_vec3 *rho = reflector(f, r.origin, r.dir, &st);
        if (!rho) continue;
        sum[0] += (double)r.beta.x * rho->x;
        sum[1] += (double)r.beta.y * rho->y;
        sum[2] += (double)r.beta.z * rho->z;
    }
    return iir_v3((float)(sum[0] / M), (float)(sum[1] / M), (float)(sum[2] / M));
}

static iir_vec3 set_flux(iir_incr *inc)
{
    uint32_t n;
    const iir_vpl *v = iir_incr_vpls(inc, &n);
    double sum[3] = {0, 0, 0};
    for (uint32_t i = 0; i < n; i++)
        sum[0] += v[i].flux.x, sum[1] += v[i].flux.y, sum[2] += v[i].flux.z;
    return iir_v3((float)sum[0], (float)sum[1], (float)sum[2]);
}

static iir_incr *make_set(const fixture *f, iir_weights w)
{
    iir_incr_params p = iir_incr_params_default();
    p.target = 1024;
    p.k_min = 8;
    p.k_max = 32;
    p.weights = w;
    iir_incr *inc = NULL;
    iir_error err = {0};
    if (iir_incr_create(f->scene, f->rt, &p, &inc, &err) != IIR_OK) fail_msg("create: %s", err.msg);
    return inc;
}

static void step(iir_incr *inc, const iir_light *l)
{
    iir_error err = {0};
    if (iir_incr_update(inc, l, NULL, &err) != IIR_OK) fail_msg("update: %s", err.msg);
}

/* Bounds, from runs of this test (N = 1024, 400k dense samples, whose own noise is ~0.3%):
 * - Voronoi weights right after 200 frames of motion (the last jump 30 frames before): within 1%
 *   on the lights with one origin (spots, point, sun). Area lights: +2.9% on the panel, +3.8% on
 *   the disc lamp; bound 5%. The cause, measured by area_oracle below: a VPL of an area light is a
 *   sample of (q, w), its own point q of the emitter and a direction, but its cell is a cell of
 *   directions only; where whether w reaches a reflecting surface depends on q (the band of
 *   directions past the box's open front, or past a block's edge), the Voronoi weight is right
 *   only when the q of the VPLs there are spread like fresh ones. Motion skews them: a VPL on a
 *   surface moves in the domain with that surface and dies only when occluded, while a null sample
 *   keeps its direction and dies when the surface's edge sweeps over it from its q, so the band
 *   keeps its VPLs and loses its null samples (null samples' share of the cells: 0.19 against
 *   0.20 fresh, 0.27 against 0.29 after a jump). The same cells with each VPL's albedo replaced
 *   by the mean over 64 fresh q (area_oracle) give the dense flux within 0.3%: the domain and the
 *   weights are exact, the bias is in which q survived. After 150 frames of rest: +1.3% (panel),
 *   +2.4% (disc), bound 3%.
 * - Surface-aware weights (the default) right after motion: within 0.7% on the lights with one
 *   origin, -1.1% (panel) and +0.3% (disc) on the area lights; bound 2%. Their pattern traces each
 *   ray from an emitter point of its own, not from its cell's VPL's, so a cell whose survivors'
 *   points see its directions reach a surface more often than fresh points would hands the rays
 *   that escape from fresh points to null samples: with the owner's point (the rule before) the
 *   panel and the disc were +3.1% and +2.8%.
 * - Uniform weights after rest: within 1.2% on the point and area lights and the cosine spot, -3.1%
 *   on the sun and -7.3% on the glTF spot: the largest empty circle counts a whole circle at the
 *   disk's rim where half of it lies outside, so the rim gets more sites than its area, and the
 *   glTF profile is smallest there. Bound 10%: uniform weights are the paper's approximation,
 *   Voronoi weights the exact one.
 * A wrong Jacobian is far outside: weighing the glTF spot's equal-area disk as if it were the
 * cosine disk, or the sun's disk in the wrong units, is off by 15% to orders of magnitude. */
static void check_close(const char *what, enum kind k, iir_vec3 got, iir_vec3 want, double tol)
{
    const float *g = &got.x, *w = &want.x;
    for (int c = 0; c < 3; c++) {
        double rel = (g[c] - w[c]) / w[c];
        print_message("%s %s ch%d: VPLs %.5f, dense %.5f (rel %+.3f%%)\n", kind_name[k], what, c,
                      (double)g[c], (double)w[c], 100 * rel);
        assert_true(w[c] > 0.f);
        if (fabs(rel) > tol)
            fail_msg("%s %s: off by %.2f%% (bound %.1f%%)", kind_name[k], what, 100 * rel,
                     100 * tol);
    }
}

/* Whether light-local q lies in the 32-gon of iir_test_disc_shape, by the test's own polar test
 * (within a float's rounding of its edge). */
static bool in_disc(iir_vec2 q)
{
    double t = atan2(q.y, q.x), step = 2 * M_PI / 32;
    if (t < 0) t += 2 * M_PI;
    double mid = (floor(t / step) + 0.5) * step;
    return q.x * cos(mid) + q.y * sin(mid) <= 0.5 * cos(M_PI / 32) + 1e-6;
}

/* Every VPL of a disc lamp's set was born on the disc (its kept origin q), none in the corners of
 * its bounding square. */
static void check_origins_on_disc(iir_incr *inc)
{
    uint32_t n;
    const iir_vpl *v = iir_incr_vpls(inc, &n);
    for (uint32_t i = 0; i < n; i++)
        if (!in_disc(v[i].emit))
            fail_msg("VPL %u born off the disc at (%g, %g)", v[i].id, (double)v[i].emit.x,
                     (double)v[i].emit.y);
}

/* What the VPLs' cells of an area light carry, channel 0, when each cell's reflected flux is
 * averaged over M fresh points q of the emitter along its direction instead of the VPL's own q:
 * sum over cells of A profile E_q[I(q) rho(hit)], null samples and emitters counting zero. */
static double area_oracle(const fixture *f, iir_incr *inc, const iir_light *l)
{
    enum { M = 64 };
    iir_light_domain ps;
    iir_error err = {0};
    assert_int_equal(iir_light_domain_make(l, &ps, &err), IIR_OK);
    iir_sites s = iir_sites_view(iir_incr_tri(inc), iir_incr_stri(inc));
    uint32_t n;
    iir_incr_vpls(inc, &n);
    uint32_t *ids = malloc(n * sizeof *ids);
    double *A = malloc(n * sizeof *A), sum = 0;
    size_t m = 0;
    assert_true(ids && A);
    assert_int_equal(iir_sites_cell_areas(&s, ids, A, n, &m), IIR_TRI_OK);
    assert_int_equal(m, n);
    iir_rng rng = iir_rng_make(5, 5);
    iir_raystats st = {{0}};
    for (size_t i = 0; i < m; i++) {
        double p[3], e = 0;
        assert_int_equal(iir_sites_position(&s, ids[i], p), IIR_TRI_OK);
        for (int k = 0; k < M; k++) {
            iir_vec2 q = iir_area_light_sample_q(l, iir_rng_uniform2(&rng));
            iir_light_domain at = iir_domain_at_emitter(&ps, q);
            iir_vec3 o, w;
            iir_domain_ray(&at, p, &o, &w);
            const iir_vec3 *rho = reflector(f, o, w, &st);
            if (rho) e += (double)iir_light_emission_at(l, q).x * rho->x;
        }
        sum += A[i] * iir_domain_profile(&ps, p) * e / M;
    }
    free(ids);
    free(A);
    return sum;
}

static void conservation(const fixture *f, enum kind k)
{
    iir_incr *vor = make_set(f, IIR_WEIGHTS_VORONOI), *uni = make_set(f, IIR_WEIGHTS_UNIFORM);
    iir_incr *sur = make_set(f, IIR_WEIGHTS_SURFACE);
    uint64_t seed = 7 + (uint64_t)k;
    iir_light l = light_of(f, k, iir_v3s(0.5f));
    for (int frame = 0; frame < 200; frame++) { /* a random walk, jumping at frames 20, 70, ... */
        iir_rng rng = iir_rng_make(seed, (uint64_t)frame);
        iir_vec3 u = iir_v3(iir_rng_uniform(&rng), iir_rng_uniform(&rng), iir_rng_uniform(&rng));
        iir_light next = light_of(f, k, u);
        float a = frame % 50 == 20 ? 1.f : 0.08f;
        l.position = iir_add(iir_scale(l.position, 1 - a), iir_scale(next.position, a));
        l.direction =
            iir_normalize(iir_add(iir_scale(l.direction, 1 - a), iir_scale(next.direction, a)));
        if (k == SUN) iir_light_fit_sun(&l, f->scene);
        step(vor, &l);
        step(uni, &l);
        step(sur, &l);
    }
    iir_vec3 dense = dense_reflected(f, &l, 400000);
    check_close("voronoi", k, set_flux(vor), dense, 0.05);
    check_close("surface", k, set_flux(sur), dense, 0.02);
    if (k == AREA || k == DISC) /* the cells are exact: the bias is the survivors' q (above) */
        check_close("voronoi cells, fresh q", k, iir_v3s((float)area_oracle(f, vor, &l)),
                    iir_v3s(dense.x), 0.01);
    /* uniform weights are exact only for a uniform set: right after motion the point light's set
     * is denser where surfaces moved into view than where nulls are (+28% here); k_min's churn
     * evens it out while the light rests */
    for (int frame = 0; frame < 150; frame++) step(vor, &l), step(uni, &l);
    check_close("voronoi, then still", k, set_flux(vor), dense, 0.03);
    check_close("uniform, then still", k, set_flux(uni), dense, 0.10);
    if (k == DISC) check_origins_on_disc(vor), check_origins_on_disc(uni);
    iir_incr_destroy(vor);
    iir_incr_destroy(uni);
    iir_incr_destroy(sur);
}

static void test_conservation_cosine_spot(void **state)
{
    conservation(*state, COSINE_SPOT);
}
static void test_conservation_gltf_spot(void **state)
{
    conservation(*state, GLTF_SPOT);
}
static void test_conservation_point(void **state)
{
    conservation(*state, POINT);
}
static void test_conservation_sun(void **state)
{
    conservation(*state, SUN);
}
static void test_conservation_area(void **state)
{
    conservation(*state, AREA);
}
static void test_conservation_disc(void **state)
{
    conservation(*state, DISC);
}

/* The emitter strata of a disc lamp (iir_domain_emitter_stratum, the Halton points mapped through
 * the shape's area CDF): all on the disc, and spread over it by area, the first 4096 of them
 * within 1% of each quarter's and of the inner half's (radius 1/(2 sqrt 2)) share, measured by the
 * test's own polygon test on a fine grid; random points would be off by ~2%. */
static void test_disc_strata(void **state)
{
    const fixture *f = *state;
    iir_light l = light_of(f, DISC, iir_v3s(0.5f));
    iir_light_domain d;
    iir_error err = {0};
    assert_int_equal(iir_light_domain_make(&l, &d, &err), IIR_OK);
    enum { N = 4096, G = 1024 };
    double want[5] = {0}, got[5] = {0}, all = 0;
    for (int j = 0; j < G; j++)
        for (int i = 0; i < G; i++) {
            iir_vec2 q = iir_v2((i + 0.5f) / G - 0.5f, (j + 0.5f) / G - 0.5f);
            if (!in_disc(q)) continue;
            want[(q.x > 0) + 2 * (q.y > 0)] += 1, want[4] += q.x * q.x + q.y * q.y < 0.125f;
            all += 1;
        }
    for (uint32_t i = 0; i < N; i++) {
        iir_vec2 q = iir_domain_emitter_stratum(&d, i);
        assert_true(in_disc(q));
        got[(q.x > 0) + 2 * (q.y > 0)] += 1, got[4] += q.x * q.x + q.y * q.y < 0.125f;
    }
    for (int k = 0; k < 5; k++) {
        print_message("disc strata, part %d: %.4f of them, %.4f of the area\n", k, got[k] / N,
                      want[k] / all);
        assert_true(fabs(got[k] / N - want[k] / all) < 0.01);
    }
}

/* ---- one bounce against pt ---- */

enum { W = 32, H = 32 };

/* relMSE of img against ref over smooth pixels; *means gets the two mean luminances. */
static double rel_mse(const iir_gbuffer *gb, const iir_image *img, const iir_image *ref,
                      double means[2])
{
    double rel = 0;
    int n = 0;
    means[0] = means[1] = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            if (!iir_test_smooth_pixel(gb, x, y)) continue;
            const float *a = &iir_image_at((iir_image *)img, x, y)->x;
            const float *b = &iir_image_at((iir_image *)ref, x, y)->x;
            for (int c = 0; c < 3; c++) rel += iir_sqr(a[c] - b[c]) / (b[c] * b[c] + 0.01f) / 3;
            means[0] += iir_luminance(*iir_image_at((iir_image *)img, x, y));
            means[1] += iir_luminance(*iir_image_at((iir_image *)ref, x, y));
            n++;
        }
    assert_true(n > W * H / 3);
    means[0] /= n, means[1] /= n;
    return rel / n;
}

/* One frame; an area light's direct light from area_samples stratified points per pixel
 * (one_bounce sets 64: within 0.002 relRMSE of a converged still, docs/architecture.md), so no
 * refinement passes are needed to average it. */
static void render_with(const fixture *f, const char *method, const iir_params *p,
                        const iir_view *v, iir_image *img)
{
    iir_frame_stats fs;
    iir_method *m = iir_test_method(f, method, p);
    iir_test_render(m, v, img, &fs);
    if (strcmp(method, "pt")) assert_true(fs.vpl.count > 8000);
    iir_method_destroy(m);
}

/* The bound of test_methods.c: relMSE < 5e-3 on smooth pixels, means within 2%. */
static void one_bounce(const fixture *f, enum kind k)
{
    iir_light l = light_of(f, k, iir_v3(0.35f, 0.5f, 0.6f));
    iir_view v = {&l, 1, f->scene->camera};
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", 2048);
    iir_test_set(&p, "bounces", 2);
    iir_test_set(&p, "seed", 5);
    iir_test_set(&p, "jitter", 0); /* the VPL methods shade pixel centres; so does the reference */
    iir_image *ref = iir_image_create(W, H), *img = iir_image_create(W, H);
    render_with(f, "pt", &p, &v, ref);
    iir_test_set(&p, "vpls", 16384);
    iir_test_set(&p, "visibility", 1);
    iir_test_set(&p, "clamp", 0.f);
    iir_test_set(&p, "interleave", 1);
    iir_test_set(&p, "area_samples", 64);
    iir_renderer *r = iir_renderer_create(f->scene, f->rt);
    iir_render_timing t;
    iir_error err = {0};
    iir_indirect_params ind = iir_indirect_params_default();
    assert_int_equal(iir_renderer_frame(r, &(iir_render_input){&v.camera, &l, 1, NULL, 0, 1, NULL},
                                        &ind, img, &t, NULL, &err),
                     IIR_OK);
    const char *methods[] = {"ir", "iir"};
    for (int i = 0; i < 2; i++) {
        render_with(f, methods[i], &p, &v, img);
        double means[2], rel = rel_mse(iir_renderer_gbuffer(r), img, ref, means);
        print_message("%s, %s vs pt: relMSE %.2e, means %.4f vs %.4f\n", kind_name[k], methods[i],
                      rel, means[0], means[1]);
        assert_true(rel < 5e-3);
        assert_true(fabs(means[0] - means[1]) < 0.02 * means[1]);
    }
    iir_renderer_destroy(r);
    iir_image_destroy(ref);
    iir_image_destroy(img);
}

static void test_one_bounce_gltf_spot(void **state)
{
    one_bounce(*state, GLTF_SPOT);
}
static void test_one_bounce_point(void **state)
{
    one_bounce(*state, POINT);
}
static void test_one_bounce_sun(void **state)
{
    one_bounce(*state, SUN);
}
static void test_one_bounce_area(void **state)
{
    one_bounce(*state, AREA);
}
static void test_one_bounce_disc(void **state)
{
    one_bounce(*state, DISC);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_conservation_cosine_spot),
        cmocka_unit_test(test_conservation_gltf_spot),
        cmocka_unit_test(test_conservation_point),
        cmocka_unit_test(test_conservation_sun),
        cmocka_unit_test(test_one_bounce_gltf_spot),
        cmocka_unit_test(test_one_bounce_point),
        cmocka_unit_test(test_one_bounce_sun),
        cmocka_unit_test(test_conservation_area),
        cmocka_unit_test(test_one_bounce_area),
        cmocka_unit_test(test_disc_strata),
        cmocka_unit_test(test_conservation_disc),
        cmocka_unit_test(test_one_bounce_disc),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

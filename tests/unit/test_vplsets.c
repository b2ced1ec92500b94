/* test_vplsets.c -- several lights' VPL sets (vplsets.h) in the built-in Cornell box: budgets in
 * proportion to the flux each light sends onto surfaces (measured by the test's own emission
 * sampling), a light switched off hands its budget to the other within N / k_max frames without
 * regenerating it, and over 400 frames of random motion with three lights of different kinds the
 * sets keep their invariants (counts add up, targets sum to N, ids unique, every VPL lit by its
 * own light by the test's own occlusion ray). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/rng.h"
#include "iir/scene.h"
#include "iir/vplsets.h"
#include "surface.h"
#include "testutil.h"

typedef iir_test_cornell fixture;

static iir_light spot(iir_vec3 p, iir_vec3 dir, float I)
{
    iir_light l = {.type = IIR_LIGHT_SPOT,
                   .name = "spot",
                   .position = p,
                   .direction = iir_normalize(dir),
                   .up = iir_v3(0, 0, -1),
                   .cone_angle = iir_radians(50.f),
                   .intensity = iir_v3s(I)};
    return l;
}

static iir_vplsets *make(const fixture *f, uint32_t N, uint32_t kmax)
{
    iir_incr_params p = iir_incr_params_default();
    p.target = N, p.k_max = kmax, p.k_min = 4;
    iir_vplsets *g = NULL;
    iir_error err = {0};
    if (iir_vplsets_create(f->scene, f->rt, &p, &g, &err) != IIR_OK) fail_msg("%s", err.msg);
    return g;
}

static iir_incr_stats update(iir_vplsets *g, const iir_light *l, uint32_t n)
{
    iir_incr_stats st;
    iir_error err = {0};
    if (iir_vplsets_update(g, l, n, &st, &err) != IIR_OK) fail_msg("update: %s", err.msg);
    return st;
}

/* The luminance of the flux light l sends onto reflecting surfaces, by 200k emission samples. */
static double flux_onto_surfaces(const fixture *f, const iir_light *l)
{
    double sum = 0;
    iir_rng rng = iir_rng_make(3, 4);
    iir_raystats st = {{0}};
    enum { M = 200000 };
    for (int i = 0; i < M; i++) {
        iir_light_ray r = iir_light_sample_emission(l, iir_rng_uniform2(&rng));
        iir_ray ray = iir_make_ray(r.origin, r.dir, 0.f, INFINITY);
        iir_hit hit;
        if (!iir_rt_intersect(f->rt, &ray, &hit, &st, IIR_RAYS_BENCH)) continue;
        iir_surface sf = iir_surface_at(f->scene, &hit, iir_neg(r.dir));
        if (iir_is_black(sf.mat->emission)) sum += iir_luminance(r.beta);
    }
    return sum / M;
}

/* A bright spot aimed at the floor and a dim one aimed at the back wall's corner: budgets follow
 * the flux onto surfaces (shares within 0.04 of the measured ones: the floors of 16 VPLs a light
 * shift a share of 0.8 by 0.02 at N = 512). */
static void test_budget_in_proportion(void **state)
{
    const fixture *f = *state;
    iir_light l[2] = {spot(iir_v3(-0.3f, 1.8f, 0.2f), iir_v3(0, -1, 0), 4.f),
                      spot(iir_v3(0.4f, 1.6f, 0.3f), iir_v3(0.5f, -0.3f, -1), 1.f)};
    iir_vplsets *g = make(f, 512, 16);
    for (int i = 0; i < 20; i++) update(g, l, 2);
    double F0 = flux_onto_surfaces(f, &l[0]), F1 = flux_onto_surfaces(f, &l[1]);
    double want = F0 / (F0 + F1), got = iir_vplsets_target(g, 0) / 512.0;
    print_message("targets %u and %u; share of light 0 %.3f, by its flux onto surfaces %.3f\n",
                  iir_vplsets_target(g, 0), iir_vplsets_target(g, 1), got, want);
    assert_int_equal(iir_vplsets_target(g, 0) + iir_vplsets_target(g, 1), 512);
    assert_true(fabs(got - want) < 0.04);
    assert_true(want > 0.7); /* the lights do differ */
    iir_vplsets_destroy(g);
}

/* Light 1 switched off: its set goes at once, light 0 fills to N within N / k_max frames (it grows
 * by k_max - k_min a frame while still), without a regeneration. */
static void test_switch_off_moves_budget(void **state)
{
    const fixture *f = *state;
    iir_light l[2] = {spot(iir_v3(-0.3f, 1.8f, 0.2f), iir_v3(0, -1, 0), 1.f),
                      spot(iir_v3(0.4f, 1.8f, 0.3f), iir_v3(0, -1, 0), 1.f)};
    iir_vplsets *g = make(f, 256, 8);
    for (int i = 0; i < 10; i++) update(g, l, 2);
    uint32_t before = iir_vplsets_target(g, 0);
    assert_true(before > 100 && before < 156);
    l[1].intensity = iir_v3s(0.f);
    int frames = 0;
    uint32_t n = 0;
    do {
        iir_incr_stats st = update(g, l, 2);
        assert_int_equal(st.vpl.regenerated, 0);
        iir_incr_vpls(iir_vplsets_set(g, 0), &n);
        frames++;
    } while (n < 256 && frames < 100);
    print_message("light 0: target %u -> %u, full after %d frames\n", before,
                  iir_vplsets_target(g, 0), frames);
    assert_null(iir_vplsets_set(g, 1));
    assert_int_equal(iir_vplsets_target(g, 0), 256);
    assert_true(frames <= 256 / 8); /* the bound, N / k_max; net k_max - k_min a frame */
    iir_vplsets_destroy(g);
}

/* Whether the test's own ray from l reaches x. */
static bool lit_by(const fixture *f, const iir_light *l, iir_vec3 x)
{
    iir_vec3 o =
        l->type == IIR_LIGHT_SUN ? iir_madd(x, l->direction, -4.f * l->radius) : l->position;
    iir_vec3 d = iir_sub(x, o);
    iir_ray ray = iir_make_ray(o, d, 0.f, 1.f - 1e-3f / iir_length(d));
    iir_raystats st = {{0}};
    return !iir_rt_occluded(f->rt, &ray, &st, IIR_RAYS_BENCH);
}

static void check_invariants(const fixture *f, iir_vplsets *g, const iir_light *l, uint32_t nl,
                             uint32_t prev, const iir_incr_stats *st)
{
    assert_int_equal(prev - st->vpl.invalidated - st->vpl.deleted + st->vpl.inserted,
                     st->vpl.count);
    uint32_t n = 0, sum = 0, targets = 0;
    const iir_vpl *all = iir_vplsets_gather(g, &n);
    assert_int_equal(n, st->vpl.count);
    for (uint32_t k = 0; k < nl; k++) {
        uint32_t m = 0;
        iir_incr *set = iir_vplsets_set(g, k);
        if (!set) continue; /* off */
        const iir_vpl *v = iir_incr_vpls(set, &m);
        assert_true(m <= iir_vplsets_target(g, k));
        for (uint32_t i = 0; i < m; i++)
            if (!v[i].null_sample && !lit_by(f, &l[k], v[i].position))
                fail_msg("light %u's VPL %u is not lit by it", k, v[i].id);
        sum += m, targets += iir_vplsets_target(g, k);
    }
    assert_int_equal(sum, n);
    assert_int_equal(targets, 384);
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = i + 1; j < n && j < i + 64; j++) assert_true(all[i].id != all[j].id);
}

static void test_three_kinds_random_path(void **state)
{
    const fixture *f = *state;
    iir_light l[3] = {spot(iir_v3(-0.3f, 1.8f, 0.2f), iir_v3(0, -1, 0), 2.f),
                      spot(iir_v3(0.4f, 1.8f, 0.3f), iir_v3(0, -1, 0), 1.f),
                      {.type = IIR_LIGHT_SUN,
                       .name = "sun",
                       .up = iir_v3(0, 1, 0),
                       .direction = iir_normalize(iir_v3(0.1f, -0.5f, -1.f)),
                       .intensity = iir_v3s(0.5f)}};
    l[1].profile = IIR_SPOT_GLTF;
    l[1].inner_angle = iir_radians(20.f);
    iir_light_fit_sun(&l[2], f->scene);
    iir_vplsets *g = make(f, 384, 12);
    uint32_t prev = 0;
    iir_rng rng = iir_rng_make(11, 0);
    for (int frame = 0; frame < 400; frame++) {
        for (int k = 0; k < 2; k++) {
            l[k].position.x =
                iir_clampf(l[k].position.x + 0.1f * (iir_rng_uniform(&rng) - 0.5f), -0.8f, 0.8f);
            l[k].direction = iir_normalize(
                iir_add(l[k].direction, iir_v3(0.2f * (iir_rng_uniform(&rng) - 0.5f), 0,
                                               0.2f * (iir_rng_uniform(&rng) - 0.5f))));
            if (l[k].direction.y > -0.3f) l[k].direction = iir_v3(0, -1, 0);
        }
        l[2].intensity = iir_v3s(frame % 100 < 80 ? 0.5f : 0.f); /* the sun sets now and then */
        iir_incr_stats st = update(g, l, 3);
        check_invariants(f, g, l, 3, prev, &st);
        prev = st.vpl.count;
    }
    iir_vplsets_destroy(g);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_budget_in_proportion),
        cmocka_unit_test(test_switch_off_moves_budget),
        cmocka_unit_test(test_three_kinds_random_path),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

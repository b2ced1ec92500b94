/* test_rt.c -- the Embree wrapper: hits at known distances and primitives, occlusion honouring
 * tfar, packets agreeing with single rays, ray counting by kind, and the raw-rate benchmark
 * never missing inside a closed box. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <string.h>

#include <cmocka.h>

#include "testutil.h"

#include "iir/raybench.h"
#include "iir/rng.h"
#include "iir/rt.h"
#include "iir/scene.h"

typedef iir_test_cornell fixture;

static void test_known_hits(void **state)
{
    fixture *f = *state;
    iir_raystats st = {0};
    iir_hit hit;
    /* Straight down from (0.5, 1, 0.5): the floor lies at y = 0 there (no box below it). */
    iir_ray down = iir_make_ray(iir_v3(0.8f, 1.f, 0.8f), iir_v3(0, -1, 0), 0.f, INFINITY);
    assert_true(iir_rt_intersect(f->rt, &down, &hit, &st, IIR_RAYS_CAMERA));
    assert_true(fabsf(hit.t - 1.f) < 1e-5f);
    assert_true(fabsf(f->scene->normals[hit.prim].y - 1.f) < 1e-4f);
    /* Towards -x: the red wall at x ~ -1. */
    iir_ray left = iir_make_ray(iir_v3(0.f, 1.5f, 0.5f), iir_v3(-2, 0, 0), 0.f, INFINITY);
    assert_true(iir_rt_intersect(f->rt, &left, &hit, &st, IIR_RAYS_SHADOW));
    assert_true(fabsf(hit.t * 2.f - 1.01f) < 0.02f); /* t in units of |dir| = 2 */
    assert_true(f->scene->material_list[f->scene->materials[hit.prim]].albedo.x > 0.6f);
    /* Out through the open front: a miss. */
    iir_ray out = iir_make_ray(iir_v3(0.f, 1.f, 0.f), iir_v3(0, 0, 1), 0.f, INFINITY);
    assert_false(iir_rt_intersect(f->rt, &out, &hit, &st, IIR_RAYS_CAMERA));
    assert_int_equal(hit.prim, IIR_NO_HIT);
    /* Occlusion stops at tfar. */
    down.tfar = 0.9f;
    assert_false(iir_rt_occluded(f->rt, &down, &st, IIR_RAYS_SHADOW));
    down.tfar = 1.1f;
    assert_true(iir_rt_occluded(f->rt, &down, &st, IIR_RAYS_SHADOW));
    assert_int_equal(st.n[IIR_RAYS_CAMERA], 2);
    assert_int_equal(st.n[IIR_RAYS_SHADOW], 3);
    assert_int_equal(iir_raystats_total(&st), 5);
}

static void test_packets_match_single_rays(void **state)
{
    fixture *f = *state;
    iir_rng rng = iir_rng_make(3, 3);
    iir_raystats st = {0};
    for (int round = 0; round < 200; round++) {
        iir_ray8 p;
        iir_ray single[8];
        for (int i = 0; i < 8; i++) {
            iir_vec3 o =
                iir_v3(iir_rng_uniform(&rng) * 1.8f - 0.9f, iir_rng_uniform(&rng) * 1.8f + 0.1f,
                       iir_rng_uniform(&rng) * 1.8f - 0.9f);
            iir_vec3 d = iir_v3(iir_rng_uniform(&rng) - .5f, iir_rng_uniform(&rng) - .5f,
                                iir_rng_uniform(&rng) - .5f);
            single[i] = iir_make_ray(o, d, 0.f, i == 3 ? 0.2f : INFINITY);
            p.ox[i] = o.x, p.oy[i] = o.y, p.oz[i] = o.z;
            p.dx[i] = d.x, p.dy[i] = d.y, p.dz[i] = d.z;
            p.tnear[i] = 0.f, p.tfar[i] = single[i].tfar;
            p.valid[i] = i != 5;
        }
        iir_hit hits[8];
        bool occ[8];
        iir_rt_intersect8(f->rt, &p, hits, &st, IIR_RAYS_CAMERA);
        iir_rt_occluded8(f->rt, &p, occ, &st, IIR_RAYS_SHADOW);
        for (int i = 0; i < 8; i++) {
            iir_hit h;
            bool any = iir_rt_intersect(f->rt, &single[i], &h, NULL, IIR_RAYS_CAMERA);
            if (i == 5) {
                assert_int_equal(hits[i].prim, IIR_NO_HIT);
                assert_false(occ[i]);
                continue;
            }
            if (hits[i].prim != h.prim)
                fail_msg("lane %d: packet prim %u t %.7g, single prim %u t %.7g", i, hits[i].prim,
                         hits[i].t, h.prim, h.t);
            if (any) assert_true(fabsf(hits[i].t - h.t) <= 1e-5f * h.t);
            assert_int_equal(occ[i], iir_rt_occluded(f->rt, &single[i], NULL, IIR_RAYS_SHADOW));
        }
    }
    assert_int_equal(st.n[IIR_RAYS_CAMERA], 200 * 7); /* invalid lanes are not counted */
    assert_int_equal(st.n[IIR_RAYS_SHADOW], 200 * 7);
}

static void test_raybench(void **state)
{
    fixture *f = *state;
    iir_raybench_result r;
    iir_error err = {0};
    assert_int_equal(iir_raybench_run(f->scene, f->rt, 20000, 1, &r, &err), IIR_OK);
    assert_int_equal(r.rays, 20000);
    assert_true(r.closest_per_s > 0 && r.occluded_per_s > 0);
    /* The box is open at the front, so some rays leave, most do not. */
    assert_true(r.hit_fraction > 0.5 && r.hit_fraction < 1.0);
    assert_int_equal(iir_raybench_run(f->scene, f->rt, 0, 1, &r, &err), IIR_ERR_INVALID);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_known_hits),
        cmocka_unit_test(test_packets_match_single_rays),
        cmocka_unit_test(test_raybench),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

/* test_shadowmap.c -- VPL paraboloid shadow maps: the parametrisation's round trips, a map's depths
 * against the known Cornell box geometry, lookups against exact rays, and which maps
 * iir_smaps_build renders, and the AVX2 rays against the scalar ones. Agreement over whole frames
 * is in test_render.c. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <omp.h>

#include "iir/isa.h"
#include "iir/rng.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "iir/shadowmap.h"
#include "iir/vpl.h"
#include "testutil.h"

static iir_vpl vpl_at(uint32_t id, iir_vec3 p, iir_vec3 n)
{
    iir_vpl v = {0};
    v.id = id;
    v.position = p;
    iir_vpl_set_normal(&v, iir_normalize(n));
    v.albedo = iir_v3s(0.5f);
    v.flux = iir_v3s(1.f);
    return v;
}

/* ---- the parametrisation ---- */

static void test_paraboloid_round_trip(void **state)
{
    (void)state;
    /* uv -> dir -> uv over the disk of the parametrisation. */
    for (int j = 0; j < 64; j++)
        for (int i = 0; i < 64; i++) {
            iir_vec2 uv = iir_v2((i + 0.5f) / 64.f, (j + 0.5f) / 64.f);
            float x = 2.f * uv.x - 1.f, y = 2.f * uv.y - 1.f;
            if (x * x + y * y > 1.f) continue;
            iir_vec3 d = iir_paraboloid_dir(uv);
            assert_true(fabsf(iir_length(d) - 1.f) < 1e-5f);
            assert_true(d.z >= -1e-6f);
            iir_vec2 back = iir_paraboloid_uv(d);
            if (fabsf(back.x - uv.x) > 1e-5f || fabsf(back.y - uv.y) > 1e-5f)
                fail_msg("uv (%g, %g) -> (%g, %g)", uv.x, uv.y, back.x, back.y);
        }
    /* dir -> uv -> dir over random hemisphere directions. */
    iir_rng rng = iir_rng_make(7, 0);
    for (int k = 0; k < 1000; k++) {
        float z = iir_rng_uniform(&rng), phi = 2.f * IIR_PI * iir_rng_uniform(&rng);
        float s = sqrtf(1.f - z * z);
        iir_vec3 d = iir_v3(s * cosf(phi), s * sinf(phi), z);
        iir_vec2 uv = iir_paraboloid_uv(d);
        assert_true(uv.x >= 0.f && uv.x <= 1.f && uv.y >= 0.f && uv.y <= 1.f);
        assert_true(iir_length(iir_sub(iir_paraboloid_dir(uv), d)) < 1e-5f);
    }
    /* Straight up is the centre; the horizon is the unit circle. */
    iir_vec2 c = iir_paraboloid_uv(iir_v3(0, 0, 1));
    assert_true(fabsf(c.x - 0.5f) < 1e-7f && fabsf(c.y - 0.5f) < 1e-7f);
    iir_vec2 e = iir_paraboloid_uv(iir_v3(1, 0, 0));
    assert_true(fabsf(e.x - 1.f) < 1e-7f && fabsf(e.y - 0.5f) < 1e-7f);
}

/* ---- one map ---- */

/* A VPL on the Cornell floor, away from the boxes and the ceiling patch: straight up it sees the
 * ceiling (y = 1.99) at 1.99 minus the origin's lift. */
static void test_floor_vpl_sees_ceiling(void **state)
{
    const iir_test_cornell *c = *state;
    iir_vpl v = vpl_at(1, iir_v3(-0.5f, 0.f, 0.6f), iir_v3(0, 1, 0));
    float eps = iir_rt_epsilon(c->rt);
    for (int res = 64; res <= 128; res += 36) { /* 64, 100 (not a multiple of 8) */
        iir_raystats st = {0};
        assert_true(iir_smap_render(&v.smap, c->rt, &v, res, &st));
        assert_int_equal(v.smap.res, res);
        assert_int_equal(st.n[IIR_RAYS_SHADOWMAP], (uint64_t)res * (uint64_t)res);
        assert_int_equal(iir_raystats_total(&st), (uint64_t)res * (uint64_t)res);
        /* The texels around the centre look within a texel of straight up. */
        for (int j = res / 2 - 1; j <= res / 2; j++)
            for (int i = res / 2 - 1; i <= res / 2; i++) {
                float depth = iir_smap_depth_at(&v.smap, i, j);
                iir_vec3 dir = iir_paraboloid_dir(iir_v2((i + 0.5f) / res, (j + 0.5f) / res));
                float expect = (1.99f - eps) / dir.z;
                /* 1e-4 for the ray, and half a half float's step (2^-11 relative) for storing */
                if (fabsf(depth - expect) > 1e-4f + 0x1p-11f * expect)
                    fail_msg("res %d texel (%d,%d): depth %g, expected %g", res, i, j, depth,
                             expect);
            }
        /* The box is open only towards +z: a texel whose ray escaped looks that way. */
        int escaped = 0;
        for (int j = 0; j < res; j++)
            for (int i = 0; i < res; i++) {
                if (isfinite(iir_smap_depth_at(&v.smap, i, j))) continue;
                escaped++;
                float x = 2.f * (i + 0.5f) / res - 1.f, y = 2.f * (j + 0.5f) / res - 1.f;
                iir_vec3 d = iir_frame_to_world(&v.frame, iir_normalize(iir_v3(x, y, 0.f)));
                if (x * x + y * y <= 1.f)
                    d = iir_frame_to_world(
                        &v.frame, iir_paraboloid_dir(iir_v2((i + 0.5f) / res, (j + 0.5f) / res)));
                assert_true(d.z > 0.f);
            }
        print_message("res %d: %d of %d texels escape through the open side\n", res, escaped,
                      res * res);
        assert_true(escaped > 0 && escaped < res * res / 2);
    }
    iir_smap_release(&v.smap);
    assert_null(v.smap.depth);
    assert_int_equal(v.smap.res, 0);
}

/* Lookups: the ceiling above is lit, a point beyond the ceiling and points behind the VPL are not,
 * and points around the scene agree with exact occlusion rays away from shadow edges. */
static void test_lookup_matches_rays(void **state)
{
    const iir_test_cornell *c = *state;
    float eps = iir_rt_epsilon(c->rt);
    iir_vpl v = vpl_at(2, iir_v3(0.5f, 0.f, -0.5f), iir_v3(0, 1, 0));
    assert_true(iir_smap_render(&v.smap, c->rt, &v, 128, NULL));
    iir_vec3 down = iir_v3(0, -1, 0);
    assert_true(iir_smap_visibility(&v.smap, &v, iir_v3(0.5f, 1.99f, -0.5f), down, 0.01f, eps) ==
                1.f);
    assert_true(iir_smap_visibility(&v.smap, &v, iir_v3(0.5f, 2.5f, -0.5f), down, 0.01f, eps) ==
                0.f);
    assert_true(iir_smap_visibility(&v.smap, &v, iir_v3(0.5f, -0.5f, -0.5f), down, 0.01f, eps) ==
                0.f);

    /* Random points on the walls' inner sides: map and ray agree where the ray's verdict holds
     * for the point's whole neighbourhood (a shadow edge within a few texels is left out). */
    iir_rng rng = iir_rng_make(3, 1);
    int agree = 0, total = 0;
    for (int k = 0; k < 4000; k++) {
        iir_vec3 q = iir_v3(-1.f + 2.f * iir_rng_uniform(&rng), 1.99f * iir_rng_uniform(&rng),
                            -1.04f + 2.03f * iir_rng_uniform(&rng));
        iir_vec3 w = iir_normalize(iir_sub(q, v.position));
        if (w.y <= 0.05f) continue;
        iir_ray ray = iir_make_ray(iir_madd(v.position, v.normal, eps), w, 0.f, INFINITY);
        iir_hit hit;
        if (!iir_rt_intersect(c->rt, &ray, &hit, NULL, IIR_RAYS_BENCH)) continue;
        iir_vec3 n = c->scene->normals[hit.prim];
        if (iir_dot(n, w) > 0.f) n = iir_neg(n);
        iir_vec3 x = iir_madd(ray.org, w, hit.t);
        /* The first hit is visible; a point 5% further along the ray is not (it is behind that
         * surface) where the bias is below those 5%. */
        agree += iir_smap_visibility(&v.smap, &v, x, n, 0.01f, eps) > 0.5f;
        total++;
        float cx = -iir_dot(n, w), tan_x = iir_safe_sqrt(1.f - cx * cx) / cx;
        if (iir_smap_bias(hit.t, w.y, tan_x, 128, 0.01f, eps) > 0.04f * hit.t) continue;
        iir_vec3 behind = iir_madd(x, w, 0.05f * hit.t);
        agree += iir_smap_visibility(&v.smap, &v, behind, n, 0.01f, eps) < 0.5f;
        total++;
    }
    assert_true(total > 3000);
    if (agree < (int)(0.98 * total))
        fail_msg("map and rays agree on %d of %d lookups", agree, total);
    iir_smap_release(&v.smap);
}

/* ---- a set of maps ---- */

static void test_build_only_what_is_missing(void **state)
{
    const iir_test_cornell *c = *state;
    enum { N = 6 };
    iir_vpl vpls[N];
    for (uint32_t i = 0; i < N; i++)
        vpls[i] = vpl_at(i, iir_v3(-0.8f + 0.3f * (float)i, 0.f, 0.5f), iir_v3(0, 1, 0));
    vpls[3].null_sample = true;
    iir_raystats st = {0};
    assert_int_equal(iir_smaps_build(vpls, N, c->rt, 32, &st), N - 1);
    assert_int_equal(st.n[IIR_RAYS_SHADOWMAP], (uint64_t)(N - 1) * 32 * 32);
    assert_int_equal(vpls[3].smap.res, 0);
    assert_null(vpls[3].smap.depth);
    /* Nothing new: nothing rendered, no rays. */
    assert_int_equal(iir_smaps_build(vpls, N, c->rt, 32, &st), 0);
    assert_int_equal(st.n[IIR_RAYS_SHADOWMAP], (uint64_t)(N - 1) * 32 * 32);
    /* A VPL dies and another is born in its slot: only that one is rendered. */
    iir_smap_release(&vpls[1].smap);
    vpls[1] = vpl_at(17, iir_v3(0.2f, 0.f, 0.7f), iir_v3(0, 1, 0));
    assert_int_equal(iir_smaps_build(vpls, N, c->rt, 32, NULL), 1);
    /* Same result as rendering alone (the threads do not interfere). */
    iir_smap alone = {0};
    assert_true(iir_smap_render(&alone, c->rt, &vpls[1], 32, NULL));
    assert_memory_equal(alone.depth, vpls[1].smap.depth, sizeof(uint16_t) * 32 * 32);
    iir_smap_release(&alone);
    /* Another resolution re-renders every non-null map. */
    assert_int_equal(iir_smaps_build(vpls, N, c->rt, 16, NULL), N - 1);
    for (int i = 0; i < N; i++) assert_int_equal(vpls[i].smap.res, i == 3 ? 0 : 16);
    for (int i = 0; i < N; i++) iir_smap_release(&vpls[i].smap);
}

/* A budget of maps (iir's refill): the first `full` missing maps in array order at the asked
 * resolution, the other missing ones at a quarter of it and marked coarse; a later call with
 * nothing missing renders the first coarse ones again at full resolution, the same texels as a
 * map rendered alone, and leaves the rest; the same result on one thread as on two. */
static void test_budget(void **state)
{
    const iir_test_cornell *c = *state;
    enum { N = 12, FULL = 4, RES = 32 };
    iir_vpl a[N], b[N];
    for (uint32_t i = 0; i < N; i++)
        a[i] = vpl_at(i, iir_v3(-0.9f + 0.15f * (float)i, 0.f, 0.4f), iir_v3(0, 1, 0));
    a[2].null_sample = true;
    memcpy(b, a, sizeof a);
    assert_int_equal(iir_smaps_build_budget(a, N, c->rt, RES, FULL, NULL, NULL, NULL), N - 1);
    for (uint32_t i = 0; i < N; i++) {
        bool full = i != 2 && i <= FULL; /* the null sample holds no place in the budget */
        assert_int_equal(a[i].smap.res, i == 2 ? 0 : full ? RES : RES / 4);
        assert_int_equal(a[i].smap.coarse, i != 2 && !full);
    }
    /* nothing missing: the first FULL coarse ones come back at RES, exactly as rendered alone */
    assert_int_equal(iir_smaps_build_budget(a, N, c->rt, RES, FULL, NULL, NULL, NULL), FULL);
    for (uint32_t i = 0; i < N; i++) {
        bool full = i != 2 && i <= 2 * FULL;
        assert_int_equal(a[i].smap.res, i == 2 ? 0 : full ? RES : RES / 4);
        if (i == 2 || !full) continue;
        iir_smap alone = {0};
        assert_true(iir_smap_render(&alone, c->rt, &a[i], RES, NULL));
        assert_memory_equal(alone.depth, a[i].smap.depth, sizeof(uint16_t) * RES * RES);
        iir_smap_release(&alone);
    }
    /* one thread: the same resolutions */
    int threads = omp_get_max_threads();
    omp_set_num_threads(1);
    iir_smaps_build_budget(b, N, c->rt, RES, FULL, NULL, NULL, NULL);
    iir_smaps_build_budget(b, N, c->rt, RES, FULL, NULL, NULL, NULL);
    omp_set_num_threads(threads);
    for (uint32_t i = 0; i < N; i++) {
        assert_int_equal(a[i].smap.res, b[i].smap.res);
        iir_smap_release(&a[i].smap), iir_smap_release(&b[i].smap);
    }
}

/* The maps' rays with AVX2 (iir_smap_texel_rays_avx2) are the scalar ones to the bit, so a map is
 * the same whichever set renders it: VPLs facing every axis and between, resolutions that are and
 * are not multiples of the 8 lanes, IIR_ISA capping the choice to scalar for the reference. */
static void test_avx2_rays_are_scalar(void **state)
{
    const iir_test_cornell *c = *state;
    if (!iir_isa_supported(IIR_ISA_AVX2)) {
        print_message("no AVX2 here: nothing to compare\n");
        return;
    }
    const int res_list[] = {1, 5, 32, 37, 128};
    const iir_vec3 normals[] = {iir_v3(0, 1, 0),  iir_v3(0, -1, 0), iir_v3(1, 0, 0),
                                iir_v3(0, 0, -1), iir_v3(1, 2, -3), iir_v3(-0.3f, 0.2f, 0.9f)};
    const char *cap = getenv("IIR_ISA");
    char *saved = cap ? strdup(cap) : NULL;
    for (size_t r = 0; r < sizeof res_list / sizeof *res_list; r++)
        for (size_t k = 0; k < sizeof normals / sizeof *normals; k++) {
            int res = res_list[r];
            iir_vpl v = vpl_at(7, iir_v3(0.1f, 1.f, -0.4f), normals[k]);
            iir_smap scalar = {0}, avx2 = {0};
            setenv("IIR_ISA", "scalar", 1);
            assert_true(iir_smap_render(&scalar, c->rt, &v, res, NULL));
            unsetenv("IIR_ISA");
            assert_true(iir_smap_render(&avx2, c->rt, &v, res, NULL));
            assert_memory_equal(scalar.depth, avx2.depth,
                                sizeof *scalar.depth * (size_t)res * (size_t)res);
            /* and the rays themselves, lane by lane */
            for (int j = 0; j < res; j += 3)
                for (int i0 = 0; i0 < res; i0 += 8) {
                    iir_ray8 rays;
                    iir_smap_texel_rays_avx2(&v.frame, v.position, i0, j, res, &rays);
                    for (int q = 0; q < 8; q++) assert_int_equal(rays.valid[q] != 0, i0 + q < res);
                }
            iir_smap_release(&scalar), iir_smap_release(&avx2);
        }
    if (saved) setenv("IIR_ISA", saved, 1);
    free(saved);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_budget),
        cmocka_unit_test(test_paraboloid_round_trip),
        cmocka_unit_test(test_floor_vpl_sees_ceiling),
        cmocka_unit_test(test_lookup_matches_rays),
        cmocka_unit_test(test_build_only_what_is_missing),
        cmocka_unit_test(test_avx2_rays_are_scalar),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

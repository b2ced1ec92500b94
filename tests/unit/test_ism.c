/* test_ism.c -- imperfect shadow maps (ism.h) and the visibility=ism backend: the point set is
 * area-uniform and on the triangles; ISM visibility agrees with exact occlusion rays on the Cornell
 * box, better with more points per VPL; memory estimates count ISMs and points; iir builds a
 * VPL's ISM at its birth only; ir with visibility=ism and the ism method render the box close to
 * pt, and no better than ir with exact maps. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/ism.h"
#include "iir/method.h"
#include "iir/render.h"
#include "iir/rng.h"
#include "iir/scene.h"
#include "iir/shadowmap.h"
#include "testutil.h"

typedef iir_test_cornell fixture;

/* ---- the point set ---- */

/* Four triangles of areas 0.02, 0.5, 2 and 50 (right triangles with legs a, 2 at z = t). */
static iir_scene *four_triangles(void)
{
    static iir_vec3 pos[12];
    static uint32_t idx[12];
    static float areas[4];
    static iir_scene s;
    const float legs[4] = {0.02f, 0.5f, 2.f, 50.f};
    for (int t = 0; t < 4; t++) {
        pos[3 * t + 0] = iir_v3(0, 0, (float)t);
        pos[3 * t + 1] = iir_v3(legs[t], 0, (float)t);
        pos[3 * t + 2] = iir_v3(0, 2, (float)t);
        for (int k = 0; k < 3; k++) idx[3 * t + k] = (uint32_t)(3 * t + k);
        areas[t] = legs[t];
    }
    memset(&s, 0, sizeof s);
    s.num_vertices = 12, s.positions = pos;
    s.num_triangles = 4, s.indices = idx, s.areas = areas;
    return &s;
}

/* Stratified selection gives triangle t n A_t / A samples up to one (the bound: 1.5); the
 * barycentrics are valid, each position is their combination (and so on its triangle's plane and
 * inside it), their means on the big triangle are 1/3 (uniform over it: the standard error at its
 * 95k samples is ~0.001), the order is shuffled, the positions follow a moved mesh, and the set
 * is the same for the same seed. */
static void test_points_area_uniform(void **state)
{
    (void)state;
    const iir_scene *s = four_triangles();
    const uint32_t n = 100000;
    iir_ism_points *pts = NULL;
    iir_error err = {0};
    assert_int_equal(iir_ism_points_create(s, n, 7, &pts, &err), IIR_OK);
    assert_int_equal(pts->n, n);
    double total = 0.02 + 0.5 + 2 + 50, count[4] = {0}, mean_b[2] = {0};
    for (uint32_t k = 0; k < n; k++) {
        iir_ism_sample q = pts->sample[k];
        assert_true(q.tri < 4);
        assert_true(q.b1 >= 0.f && q.b2 >= 0.f && q.b1 + q.b2 <= 1.f + 1e-6f);
        count[q.tri]++;
        const iir_vec3 *v = &s->positions[3 * q.tri];
        iir_vec3 want = iir_add(iir_add(iir_scale(v[0], 1.f - q.b1 - q.b2), iir_scale(v[1], q.b1)),
                                iir_scale(v[2], q.b2));
        assert_true(iir_length(iir_sub(pts->p[k], want)) < 1e-5f);
        assert_true(fabsf(pts->p[k].z - (float)q.tri) < 1e-6f);
        if (q.tri == 3) mean_b[0] += q.b1, mean_b[1] += q.b2;
    }
    for (int t = 0; t < 4; t++) {
        double want = n * (double)s->areas[t] / total;
        print_message("triangle %d: %.0f samples, expected %.1f\n", t, count[t], want);
        assert_true(fabs(count[t] - want) <= 1.5);
    }
    assert_true(fabs(mean_b[0] / count[3] - 1.0 / 3) < 0.01);
    assert_true(fabs(mean_b[1] / count[3] - 1.0 / 3) < 0.01);
    /* the order is shuffled: in CDF order the first 4.8k samples lie on the small triangles; the
       first thousand after shuffling fall on the triangles as the areas say */
    double first_big = 0;
    for (uint32_t k = 0; k < 1000; k++) first_big += pts->sample[k].tri == 3;
    assert_true(first_big > 930 && first_big < 990); /* 952 expected, sd ~7 */
    /* the samples follow the triangles: move the mesh, and the positions move with it */
    iir_scene *moved = four_triangles();
    for (uint32_t i = 0; i < moved->num_vertices; i++)
        moved->positions[i] = iir_add(moved->positions[i], iir_v3(1.f, -2.f, 0.5f));
    iir_vec3 before = pts->p[17];
    iir_ism_points_update(pts, moved);
    assert_true(iir_length(iir_sub(pts->p[17], iir_add(before, iir_v3(1.f, -2.f, 0.5f)))) < 1e-4f);
    /* deterministic from the seed */
    iir_ism_points *again = NULL;
    assert_int_equal(iir_ism_points_create(s, n, 7, &again, &err), IIR_OK);
    assert_memory_equal(again->sample, pts->sample, n * sizeof *pts->sample);
    iir_ism_points_destroy(again);
    iir_ism_points_destroy(pts);
}

/* ---- ISM visibility against exact rays ---- */

/* n VPLs of one-bounce ir from the box's spot (visibility rays: no maps built), copied. */
static iir_vpl *cornell_vpls(const fixture *f, int n, uint32_t *count)
{
    iir_params p = iir_params_default();
    iir_test_set(&p, "vpls", n);
    iir_test_set(&p, "visibility", IIR_VIS_RAYS);
    iir_method *ir = iir_test_method(f, "ir", &p);
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_image *img = iir_image_create(8, 6);
    iir_frame_stats fs;
    iir_test_render(ir, &v, img, &fs);
    const iir_vpl *src = iir_method_vpls(ir, count);
    iir_vpl *vpls = calloc(*count, sizeof *vpls);
    memcpy(vpls, src, *count * sizeof *vpls);
    for (uint32_t i = 0; i < *count; i++) vpls[i].smap = (iir_smap){0};
    iir_method_destroy(ir);
    iir_image_destroy(img);
    return vpls;
}

typedef struct agreement {
    int pairs;         /* (VPL, receiver) pairs with G > 0 */
    double ism, exact; /* share of pairs whose map verdict (V >= 1/2) is the ray's */
    double ism_g;      /* the same weighted by G: 1 - sum G |V_ism - V_ray| / sum G */
    double acne, leak; /* ISM: share of lit pairs it shadows, of occluded pairs it lights */
} agreement;

/* A receiver's verdicts: the ray's (lit), the ISM's and the exact map's. */
typedef struct verdicts {
    bool lit;
    float v_ism, v_exact;
} verdicts;

static verdicts judge(const fixture *f, const iir_vpl *v, const iir_smap *ism,
                      const iir_smap *exact, iir_vec3 x, iir_vec3 n, float eps)
{
    float bias = iir_indirect_params_default().sm_bias;
    iir_vec3 o = iir_madd(v->position, v->normal, eps), to = iir_sub(x, o);
    float len = iir_length(to);
    iir_ray ray = iir_make_ray(o, iir_scale(to, 1.f / len), 0.f, len - 2.f * eps);
    verdicts r = {!iir_rt_occluded(f->rt, &ray, NULL, IIR_RAYS_BENCH),
                  iir_smap_visibility(ism, v, x, n, bias, eps),
                  iir_smap_visibility(exact, v, x, n, bias, eps)};
    return r;
}

/* Over every VPL and receiver (1500 area-uniform points of another seed, normals turned to the
 * VPL) with G > 0: how often a res^2 ISM from per_vpl of 16k points (and an exact 128^2 map)
 * agrees with an occlusion ray, at the default bias. G is capped at 8 (about the default clamp,
 * 100 / D^2, on the box). */
static agreement measure(const fixture *f, iir_vpl *vpls, uint32_t nv, int res, uint32_t per_vpl)
{
    iir_error err = {0};
    iir_ism_points *pts = NULL, *recv = NULL;
    assert_int_equal(iir_ism_points_create(f->scene, 16384, 11, &pts, &err), IIR_OK);
    assert_int_equal(iir_ism_points_create(f->scene, 1500, 12, &recv, &err), IIR_OK);
    float eps = iir_rt_epsilon(f->rt);
    iir_ism_params ip = {.res = res, .points_per_vpl = per_vpl, .key = 3};
    float *scratch = malloc(iir_ism_scratch_floats(res) * sizeof(float));
    agreement a = {0};
    double ism_ok = 0, exact_ok = 0, lit = 0, acne = 0, leak = 0, g_sum = 0, g_err = 0;
    for (uint32_t i = 0; i < nv; i++) {
        iir_vpl *v = &vpls[i];
        iir_smap ism = {0}, exact = {0};
        if (v->null_sample) continue;
        assert_true(iir_ism_render(&ism, pts, v, &ip, eps, scratch));
        assert_true(iir_smap_render(&exact, f->rt, v, 128, NULL));
        for (uint32_t k = 0; k < recv->n; k++) {
            iir_vec3 x = recv->p[k], w = iir_sub(x, v->position);
            iir_vec3 n = f->scene->normals[recv->sample[k].tri];
            if (iir_dot(n, w) > 0.f) n = iir_neg(n);
            float d = iir_length(w);
            if (!(iir_dot(w, v->normal) > 0.f) || d < 1e-3f) continue;
            verdicts r = judge(f, v, &ism, &exact, x, n, eps);
            bool ism_lit = r.v_ism >= 0.5f;
            float G = fminf(iir_dot(w, v->normal) * -iir_dot(w, n) / iir_sqr(d * d), 8.f);
            a.pairs++;
            ism_ok += ism_lit == r.lit, exact_ok += (r.v_exact >= 0.5f) == r.lit;
            lit += r.lit, acne += r.lit && !ism_lit, leak += !r.lit && ism_lit;
            g_sum += G, g_err += G * fabsf(r.v_ism - (r.lit ? 1.f : 0.f));
        }
        iir_smap_release(&ism);
        iir_smap_release(&exact);
    }
    a.ism = ism_ok / a.pairs, a.exact = exact_ok / a.pairs, a.ism_g = 1 - g_err / g_sum;
    a.acne = acne / lit, a.leak = leak / (a.pairs - lit);
    free(scratch);
    iir_ism_points_destroy(recv);
    iir_ism_points_destroy(pts);
    return a;
}

/* Measured (96 VPLs, ~90k pairs): at 32^2 ISMs agree on 71%, 79% and 86% of the pairs with 256,
 * 1024 (the default) and 4096 points per VPL (G-weighted: 81% at 1024); the exact 128^2 map on
 * 96%, an exact 32^2 map on 90%. What ISMs get wrong is leaks -- half the occluded pairs at 1024
 * points, where a texel behind an occluder got a farther point and no occluder point -- while
 * only ~5% of the lit pairs are shadowed (acne): more bias would only add leaks (sm_bias 0.05
 * shadows 3.6% of the lit pairs but lights 53% of the occluded), so ISMs use sm_bias as it is
 * (its slope term already grows with the texel: 4x at 32^2 against 128^2). The bounds leave a few
 * points' margin; the image-level cost of these leaks is small (test_frames_against_pt). */
static void test_ism_agrees_with_rays(void **state)
{
    const fixture *f = *state;
    uint32_t nv = 0;
    iir_vpl *vpls = cornell_vpls(f, 96, &nv);
    const uint32_t per_vpl[] = {256, 1024, 4096};
    agreement a[3];
    for (int k = 0; k < 3; k++) {
        a[k] = measure(f, vpls, nv, 32, per_vpl[k]);
        print_message("ISM 32^2, %4u points per VPL: %.1f%% of %d pairs agree with rays "
                      "(G-weighted %.1f%%; acne %.1f%% of lit, leaks %.1f%% of occluded), "
                      "exact 128^2 map %.1f%%\n",
                      per_vpl[k], 100 * a[k].ism, a[k].pairs, 100 * a[k].ism_g, 100 * a[k].acne,
                      100 * a[k].leak, 100 * a[k].exact);
    }
    assert_true(a[0].pairs > 50000);
    assert_true(a[1].ism >= 0.75 && a[1].ism_g >= 0.77);
    assert_true(a[1].acne < 0.07);
    assert_true(a[0].ism < a[1].ism && a[1].ism < a[2].ism);
    assert_true(a[0].ism_g < a[1].ism_g && a[1].ism_g < a[2].ism_g);
    assert_true(a[2].ism < a[2].exact);
    free(vpls);
}

/* ---- iir keeps a VPL's ISM for its life ---- */

/* With a moving light iir builds ISMs only for the VPLs born in a frame (null samples get none),
 * every live VPL holds an ism_res^2 map, and a live switch to exact maps of the same resolution
 * rebuilds every map (ray-traced: shadow-map rays are counted). */
static void test_iir_keeps_isms(void **state)
{
    const fixture *f = *state;
    iir_params p = iir_params_default();
    iir_test_set(&p, "vpls", 64);
    iir_test_set(&p, "visibility", IIR_VIS_ISM);
    iir_test_set(&p, "ism_res", 32);
    iir_test_set(&p, "sm_res", 32);
    iir_method *m = iir_test_method(f, "iir", &p);
    iir_light l = f->scene->lights[0];
    iir_view v = {&l, 1, f->scene->camera};
    iir_image *img = iir_image_create(16, 12);
    iir_frame_stats fs;
    for (int frame = 0; frame < 6; frame++) {
        l.position.x = f->scene->lights[0].position.x + 0.03f * (float)frame;
        iir_test_render(m, &v, img, &fs);
        uint32_t n = 0, born = 0;
        const iir_vpl *vpls = iir_method_vpls(m, &n);
        for (uint32_t i = 0; i < n; i++)
            born += !vpls[i].null_sample && vpls[i].birth == (uint32_t)frame;
        assert_int_equal(fs.vpl.shadowmaps, born);
        assert_int_equal(fs.rays.n[IIR_RAYS_SHADOWMAP], 0);
    }
    assert_true(fs.vpl.inserted > 0 && fs.vpl.inserted < fs.vpl.count);
    uint32_t n = 0;
    const iir_vpl *vpls = iir_method_vpls(m, &n);
    for (uint32_t i = 0; i < n; i++) assert_true(vpls[i].null_sample || vpls[i].smap.res == 32);
    bool restarted = true;
    iir_error err = {0};
    iir_test_set(&p, "visibility", IIR_VIS_SHADOWMAP);
    assert_int_equal(iir_method_set_params(m, &p, &restarted, &err), IIR_OK);
    assert_false(restarted);
    iir_test_render(m, &v, img, &fs);
    assert_true(fs.vpl.shadowmaps + fs.vpl.null_samples >= fs.vpl.count);
    assert_true(fs.rays.n[IIR_RAYS_SHADOWMAP] >= 32 * 32 * (uint64_t)fs.vpl.shadowmaps);
    iir_image_destroy(img);
    iir_method_destroy(m);
}

/* The memory estimate counts the ISMs (4 ism_res^2 bytes per VPL, instead of the exact maps') and
 * the point set (triangle, barycentrics and position: 24 bytes a point). */
static void test_memory(void **state)
{
    (void)state;
    iir_params a = iir_params_default(), b;
    iir_test_set(&a, "visibility", IIR_VIS_ISM);
    b = a;
    iir_test_set(&b, "ism_res", 64);
    uint64_t n = 1024; /* the ism method's VPLs */
    assert_true(iir_method_memory("ism", &b, 64, 48) - iir_method_memory("ism", &a, 64, 48) ==
                n * sizeof(uint16_t) * (64 * 64 - 32 * 32)); /* half-float texels */
    b = a;
    iir_test_set(&b, "ism_points", 32768);
    assert_true(iir_method_memory("iir", &b, 64, 48) - iir_method_memory("iir", &a, 64, 48) ==
                16384 * 24);
    iir_params sm = iir_params_default(); /* 256 exact 128^2 maps against 256 ISMs of 32^2 */
    assert_true(iir_method_memory("ir", &sm, 64, 48) - iir_method_memory("ir", &a, 64, 48) ==
                256 * sizeof(uint16_t) * (128 * 128 - 32 * 32) - 16384 * 24);
}

/* ---- images against pt ---- */

enum { W = 48, H = 36 };

/* relMSE of img against ref over smooth pixels (test_methods.c's measure). */
static double rel_mse(const iir_gbuffer *gb, const iir_image *img, const iir_image *ref)
{
    double rel = 0;
    int n = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            if (!iir_test_smooth_pixel(gb, x, y)) continue;
            const float *a = &iir_image_at((iir_image *)img, x, y)->x;
            const float *b = &iir_image_at((iir_image *)ref, x, y)->x;
            for (int c = 0; c < 3; c++) rel += iir_sqr(a[c] - b[c]) / (b[c] * b[c] + 0.01f) / 3;
            n++;
        }
    assert_true(n > W * H / 3);
    return rel / n;
}

/* The mean relMSE of `frames` frames of method m (a new light path set each) against ref. */
static double frames_error(const fixture *f, const char *method, const iir_params *p,
                           const iir_image *ref, const iir_gbuffer *gb, int frames)
{
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_method *m = iir_test_method(f, method, p);
    iir_image *img = iir_image_create(W, H);
    iir_frame_stats fs;
    double rel = 0;
    for (int k = 0; k < frames; k++) {
        iir_test_render(m, &v, img, &fs);
        rel += rel_mse(gb, img, ref) / frames;
    }
    iir_image_destroy(img);
    iir_method_destroy(m);
    return rel;
}

/* One-bounce frames (4 each, default interleaving, filter and clamp) against pt at 1024 spp.
 * Measured: the direct light alone is at relMSE 6.0e-2 (a missing bounce); ir with 256 VPLs at
 * 1.86e-3 with exact maps, 1.93e-3 with ISMs (1.04x; over seeds 1..6 ISMs were 1.01-1.04x the
 * exact maps' error, never below it), 1.87e-3 with rays: the VPLs' noise dominates and ISM leaks
 * average out over many VPLs, as Ritschel et al. argue. The ism method (1024 VPLs) is at 8.4e-4.
 * Bounds: ISMs within 1.3x of exact maps, ir+ism below 4e-3 and ism below 2e-3 (both a
 * fifteenth of the missing bounce and ~2x what was measured). */
static void test_frames_against_pt(void **state)
{
    const fixture *f = *state;
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", 1024);
    iir_test_set(&p, "bounces", 2);
    iir_test_set(&p, "jitter", 0); /* the VPL methods shade pixel centres; so does the reference */
    iir_image *ref = iir_image_create(W, H), *direct = iir_image_create(W, H);
    iir_frame_stats fs;
    iir_method *pt = iir_test_method(f, "pt", &p);
    iir_test_render(pt, &v, ref, &fs);
    iir_method_destroy(pt);
    iir_renderer *r = iir_renderer_create(f->scene, f->rt);
    iir_indirect_params ind = iir_indirect_params_default();
    iir_render_timing t;
    iir_error err = {0};
    assert_int_equal(
        iir_renderer_frame(r,
                           &(iir_render_input){&v.camera, v.lights, v.num_lights, NULL, 0, 1, NULL},
                           &ind, direct, &t, NULL, &err),
        IIR_OK);
    const iir_gbuffer *gb = iir_renderer_gbuffer(r);
    double e_direct = rel_mse(gb, direct, ref);
    iir_params q = iir_params_default();
    double e_sm = frames_error(f, "ir", &q, ref, gb, 4);
    iir_test_set(&q, "visibility", IIR_VIS_ISM);
    double e_ism = frames_error(f, "ir", &q, ref, gb, 4);
    double e_method = frames_error(f, "ism", &(iir_params){0}, ref, gb, 4);
    print_message("relMSE against pt: direct only %.2e; ir (256 VPLs) with exact maps %.2e, with "
                  "ISMs %.2e; ism (1024 VPLs) %.2e\n",
                  e_direct, e_sm, e_ism, e_method);
    assert_true(e_direct > 2e-2);
    assert_true(e_sm <= e_ism && e_ism < 1.3 * e_sm);
    assert_true(e_ism < 4e-3);
    assert_true(e_method < 2e-3);
    iir_image_destroy(direct);
    iir_renderer_destroy(r);
    iir_image_destroy(ref);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_points_area_uniform),
        cmocka_unit_test_setup_teardown(test_ism_agrees_with_rays, iir_test_cornell_setup,
                                        iir_test_cornell_teardown),
        cmocka_unit_test(test_memory),
        cmocka_unit_test_setup_teardown(test_iir_keeps_isms, iir_test_cornell_setup,
                                        iir_test_cornell_teardown),
        cmocka_unit_test_setup_teardown(test_frames_against_pt, iir_test_cornell_setup,
                                        iir_test_cornell_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

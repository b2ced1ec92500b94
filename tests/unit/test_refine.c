/* test_refine.c -- progressive refinement of the VPL methods (refine.h) through the method
 * interface, against independent answers on the built-in Cornell box: one sweep of n^2 passes
 * equals the all-VPL exact-visibility frame of the same set; refining moves the frame towards a
 * path-traced reference; refining leaves the live VPL set exactly as it was; passes are counted and
 * convergence stops the work; results do not depend on the thread count. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <omp.h>

#include "testutil.h"

#include "iir/method.h"
#include "iir/metrics.h"
#include "iir/refine.h"
#include "iir/render.h"
#include "iir/scene.h"
#include "iir/timer.h"

typedef iir_test_cornell fixture;
enum { W = 64, H = 48 };

static void refine(iir_method *m, iir_image *img, iir_frame_stats *fs)
{
    iir_error err = {0};
    if (iir_method_refine(m, img, fs, &err) != IIR_OK) fail_msg("%s", err.msg);
}

static iir_view still_view(const fixture *f)
{
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    return v;
}

/* The spot moved sideways a little: a view the incremental step has work in. */
static iir_light moved(const iir_light *base, float dx)
{
    iir_light l = *base;
    l.position = iir_add(base->position, iir_v3(dx, 0.f, 0.f));
    return l;
}

/* Largest |a - b| / (|b| + 1e-3) over pixels and channels. */
static double max_rel_diff(const iir_image *a, const iir_image *b)
{
    double worst = 0.0;
    for (int i = 0; i < a->width * a->height; i++) {
        const float *pa = &a->pixels[i].x, *pb = &b->pixels[i].x;
        for (int c = 0; c < 3; c++) {
            double d = fabs((double)pa[c] - pb[c]) / (fabs((double)pb[c]) + 1e-3);
            if (d > worst) worst = d;
        }
    }
    return worst;
}

/* The all-VPL frame of the method's current VPL set: interleave 1, exact rays, pixel centres, at
 * the size of out. */
static void full_sum_frame(const fixture *f, iir_method *m, const iir_params *p, iir_image *out)
{
    uint32_t n = 0;
    const iir_vpl *vpls = iir_method_vpls(m, &n);
    iir_renderer *r = iir_renderer_create(f->scene, f->rt);
    iir_indirect_params ind = iir_indirect_params_default();
    ind.visibility = IIR_VIS_RAYS, ind.interleave = 1, ind.clamp = (float)iir_test_get(p, "clamp");
    iir_view v = still_view(f);
    iir_error err = {0};
    if (iir_renderer_frame(r,
                           &(iir_render_input){&v.camera, v.lights, v.num_lights, vpls, n, 0, NULL},
                           &ind, out, NULL, NULL, &err) != IIR_OK)
        fail_msg("%s", err.msg);
    iir_renderer_destroy(r);
}

/* Whether the VPLs in use fall unevenly into the n^2 subsets: then a subset weighted by N/|S_k|
 * instead of n^2 would change the sweep's mean, so the equality below can see it. */
static bool subsets_uneven(iir_method *m, uint32_t n2)
{
    uint32_t n = 0, count[64] = {0};
    const iir_vpl *v = iir_method_vpls(m, &n);
    for (uint32_t i = 0; i < n; i++)
        if (!v[i].null_sample && !iir_is_black(v[i].flux)) count[iir_vpl_subset(v[i].id, n2)]++;
    for (uint32_t k = 1; k < n2; k++)
        if (count[k] != count[0]) return true;
    return false;
}

/* (a) Without jitter, n^2 passes of one VPL set are exactly the all-VPL frame of that set: a
 * skipped subset (checked with n^2 - 1 passes) or a subset weighted by N/|S_k| (the subsets are
 * uneven) would differ by a few % where the subsets' light differs. */
static void test_sweep_is_full_sum(void **state)
{
    fixture *f = *state;
    const char *names[] = {"iir", "ir"};
    for (int k = 0; k < 2; k++) {
        iir_params p = iir_params_default();
        iir_test_set(&p, "jitter", false);
        iir_test_set(&p, "refine_passes", 16);
        iir_test_set(&p, "sm_res", 32); /* the maps only serve the interactive frame */
        iir_method *m = iir_test_method(f, names[k], &p);
        iir_image *img = iir_image_create(W, H), *ref = iir_image_create(W, H);
        iir_frame_stats fs;
        iir_view v = still_view(f);
        iir_test_render(m, &v, img, &fs);
        assert_true(subsets_uneven(m, 16));
        full_sum_frame(f, m, &p, ref);
        for (int i = 0; i < 15; i++) refine(m, img, &fs);
        double partial = max_rel_diff(img, ref);
        refine(m, img, &fs);
        double full = max_rel_diff(img, ref);
        print_message("%s: after 15 passes max rel diff %.2e, after 16 %.2e\n", names[k], partial,
                      full);
        assert_int_equal(fs.samples_per_pixel, 16);
        assert_true(fs.converged);
        assert_true(full < 1e-4);
        assert_true(partial > 1e-2);
        iir_method_destroy(m);
        iir_image_destroy(img);
        iir_image_destroy(ref);
    }
}

/* With jitter, 16 passes see each pixel through 16 points: against the box-filtered frame (the
 * frame at 8x8 the resolution, averaged down) they are much closer than the pixel-centre frame,
 * whose error is all at edges. Direct light only (ir with one bounce has no VPLs), so the
 * comparison sees the antialiasing alone, not the VPL subsets' noise. */
static void test_jitter_antialiases(void **state)
{
    fixture *f = *state;
    enum { S = 8 };
    iir_params p = iir_params_default();
    iir_test_set(&p, "refine_passes", 16);
    iir_test_set(&p, "bounces", 1);
    iir_method *m = iir_test_method(f, "ir", &p);
    iir_image *img = iir_image_create(W, H), *centre = iir_image_create(W, H);
    iir_image *fine = iir_image_create(S * W, S * H), *box = iir_image_create(W, H);
    iir_frame_stats fs;
    iir_view v = still_view(f);
    iir_test_render(m, &v, img, &fs);
    full_sum_frame(f, m, &p, centre);
    full_sum_frame(f, m, &p, fine);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            iir_vec3 sum = iir_v3s(0.f);
            for (int j = 0; j < S * S; j++)
                sum = iir_add(sum, *iir_image_at(fine, S * x + j % S, S * y + j / S));
            *iir_image_at(box, x, y) = iir_scale(sum, 1.f / (S * S));
        }
    assert_int_equal(fs.vpl.count, 0);
    for (int i = 0; i < 16; i++) refine(m, img, &fs);
    double e_jitter = iir_metric_rmse(img, box), e_centre = iir_metric_rmse(centre, box);
    print_message("against the box-filtered frame: jittered sweep RMSE %.3e, centres %.3e\n",
                  e_jitter, e_centre);
    assert_true(e_jitter < 0.3 * e_centre);
    iir_image_destroy(fine);
    iir_image_destroy(box);
    /* pass 0 is the pixel centre, the others are not */
    assert_float_equal(iir_refine_jitter(0).x, 0.5f, 0.f);
    assert_float_equal(iir_refine_jitter(0).y, 0.5f, 0.f);
    assert_true(iir_refine_jitter(1).x != 0.5f);
    iir_method_destroy(m);
    iir_image_destroy(img);
    iir_image_destroy(centre);
}

/* (b) Against pt with one bounce (box-filtered pixels, 256 spp), the converged refinement (64
 * passes: 4 VPL sets, 64 positions per pixel, exact visibility) has a smaller relative MSE than
 * the interactive frame (one set of 128, 64^2 shadow maps, interleaving filter, pixel centres). */
static void test_converges_towards_pt(void **state)
{
    fixture *f = *state;
    iir_view v = still_view(f);
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", 256);
    iir_test_set(&p, "bounces", 2);
    iir_test_set(&p, "seed", 3);
    iir_test_set(&p, "vpls", 128);
    iir_test_set(&p, "sm_res", 64);
    iir_image *ref = iir_image_create(W, H), *img = iir_image_create(W, H);
    iir_frame_stats fs;
    iir_method *pt = iir_test_method(f, "pt", &p);
    iir_test_render(pt, &v, ref, &fs);
    iir_method_destroy(pt);
    const char *names[] = {"iir", "ir"};
    for (int k = 0; k < 2; k++) {
        iir_method *m = iir_test_method(f, names[k], &p);
        iir_test_render(m, &v, img, &fs);
        double interactive = iir_metric_relmse(img, ref);
        int passes = 0;
        for (; passes < 1000 && !fs.converged; passes++) refine(m, img, &fs);
        double refined = iir_metric_relmse(img, ref);
        print_message("%s vs pt: relMSE interactive %.3e, refined (%d passes) %.3e\n", names[k],
                      interactive, passes, refined);
        assert_int_equal(passes, iir_test_get(&p, "refine_passes"));
        assert_true(refined < 0.5 * interactive);
        iir_method_destroy(m);
    }
    iir_image_destroy(ref);
    iir_image_destroy(img);
}

/* The VPL set as a comparable value: everything but the shadow-map pointers and stamps (which
 * rendering a map is: every rendering has its own). */
static void assert_same_vpls(iir_method *a, iir_method *b)
{
    uint32_t na = 0, nb = 0;
    const iir_vpl *va = iir_method_vpls(a, &na), *vb = iir_method_vpls(b, &nb);
    assert_int_equal(na, nb);
    for (uint32_t i = 0; i < na; i++) {
        iir_vpl x = va[i], y = vb[i];
        assert_int_equal(x.smap.res, y.smap.res);
        x.smap.depth = y.smap.depth = NULL;
        x.smap.stamp = y.smap.stamp = 0;
        assert_memory_equal(&x, &y, sizeof x);
    }
}

/* (c) Refining (into a second sweep, so fresh sets were made) leaves the live set and every later
 * frame bit-identical to a twin that never refined. */
static void test_live_set_untouched(void **state)
{
    fixture *f = *state;
    const char *names[] = {"iir", "ir"};
    for (int k = 0; k < 2; k++) {
        iir_params p = iir_params_default();
        iir_test_set(&p, "vpls", 64);
        iir_test_set(&p, "sm_res", 32);
        iir_method *a = iir_test_method(f, names[k], &p), *b = iir_test_method(f, names[k], &p);
        iir_image *ia = iir_image_create(W, H), *ib = iir_image_create(W, H);
        iir_frame_stats fs;
        iir_view v = still_view(f);
        iir_test_render(a, &v, ia, &fs);
        iir_test_render(b, &v, ib, &fs);
        for (int i = 0; i < 20; i++) refine(a, ia, &fs);
        assert_int_equal(fs.samples_per_pixel, 20);
        assert_true(fs.phase_ms[IIR_PHASE_VPLS] >= 0.0);
        assert_same_vpls(a, b);
        for (int frame = 0; frame < 3; frame++) {
            iir_light l = moved(&f->scene->lights[0], 0.05f * (float)frame);
            iir_view w = {&l, 1, f->scene->camera};
            iir_test_render(a, &w, ia, &fs);
            iir_test_render(b, &w, ib, &fs);
            assert_memory_equal(ia->pixels, ib->pixels, sizeof(iir_vec3) * W * H);
            assert_same_vpls(a, b);
        }
        iir_method_destroy(a);
        iir_method_destroy(b);
        iir_image_destroy(ia);
        iir_image_destroy(ib);
    }
}

/* (d) Passes are counted from each render; converged exactly at refine_passes; after that a call
 * is cheap and changes nothing; bad calls and parameters are refused with the field named. */
static void test_counting_and_convergence(void **state)
{
    fixture *f = *state;
    iir_params p = iir_params_default();
    iir_test_set(&p, "refine_passes", 5);
    iir_test_set(&p, "vpls", 64);
    iir_test_set(&p, "sm_res", 32);
    iir_method *m = iir_test_method(f, "iir", &p);
    iir_image *img = iir_image_create(W, H), *kept = iir_image_create(W, H);
    iir_image *small = iir_image_create(W / 2, H);
    iir_frame_stats fs;
    iir_error err = {0};
    iir_view v = still_view(f);
    assert_true(iir_method_can_refine(m));
    assert_int_equal(iir_method_refine(m, img, &fs, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "before any frame"));
    iir_test_render(m, &v, img, &fs);
    assert_int_equal(fs.samples_per_pixel, 0);
    assert_false(fs.converged);
    assert_int_equal(iir_method_refine(m, small, &fs, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "64x48"));
    for (int i = 1; i <= 5; i++) {
        refine(m, img, &fs);
        assert_int_equal(fs.samples_per_pixel, (uint64_t)i);
        assert_int_equal(fs.converged, i == 5);
        assert_true(fs.rays.n[IIR_RAYS_VISIBILITY] > 0);
    }
    iir_image_copy(kept, img);
    iir_image_clear(img);
    double t0 = iir_now_ms();
    refine(m, img, &fs);
    double idle_ms = iir_now_ms() - t0;
    assert_true(fs.converged);
    assert_int_equal(fs.samples_per_pixel, 5);
    assert_int_equal(iir_raystats_total(&fs.rays), 0);
    assert_memory_equal(img->pixels, kept->pixels, sizeof(iir_vec3) * W * H);
    print_message("a converged refine call took %.3f ms\n", idle_ms);
    iir_test_render(m, &v, img, &fs); /* a new view starts over */
    refine(m, img, &fs);
    assert_int_equal(fs.samples_per_pixel, 1);

    iir_method *bad = NULL;
    assert_int_equal(iir_method_param_set(&p, "refine_passes", 0, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "refine_passes"));
    assert_int_equal(iir_method_param_set(&p, "refine_passes", 4097, &err), IIR_ERR_INVALID);
    assert_null(bad);

    /* pt: converged once it holds refine_passes samples per pixel, rounded up to whole frames of
       spp (iir_method_converged_at says so too), and still adds samples when asked */
    p = iir_params_default();
    iir_test_set(&p, "spp", 2);
    iir_test_set(&p, "refine_passes", 5);
    assert_int_equal(iir_method_converged_at("pt", &p), 6);
    iir_method *pt = iir_test_method(f, "pt", &p);
    iir_test_render(pt, &v, img, &fs);
    assert_false(fs.converged);
    refine(pt, img, &fs);
    assert_false(fs.converged);
    assert_int_equal(fs.samples_per_pixel, 4);
    refine(pt, img, &fs);
    assert_true(fs.converged);
    assert_int_equal(fs.samples_per_pixel, 6);
    refine(pt, img, &fs);
    assert_true(fs.converged);
    assert_int_equal(fs.samples_per_pixel, 8);
    /* one frame of more samples than refine_passes is converged at once */
    iir_test_set(&p, "spp", 8);
    assert_int_equal(iir_method_converged_at("pt", &p), 8);
    iir_method_destroy(pt);
    pt = iir_test_method(f, "pt", &p);
    iir_test_render(pt, &v, img, &fs);
    assert_true(fs.converged);
    /* ir and iir converge after refine_passes passes; a method that does not exist never does */
    assert_int_equal(iir_method_converged_at("iir", &p), 5);
    assert_int_equal(iir_method_converged_at("ir", &p), 5);
    assert_int_equal(iir_method_converged_at("nope", &p), 0);
    iir_method_destroy(pt);
    iir_method_destroy(m);
    iir_image_destroy(img);
    iir_image_destroy(kept);
    iir_image_destroy(small);
}

/* Renders and refines 20 passes (into the second sweep) with `threads` OpenMP threads. */
static void run_refined(const fixture *f, const char *name, int threads, iir_image *out)
{
    omp_set_num_threads(threads);
    iir_params p = iir_params_default();
    iir_test_set(&p, "seed", 11);
    iir_test_set(&p, "vpls", 64);
    iir_test_set(&p, "sm_res", 32);
    iir_method *m = iir_test_method(f, name, &p);
    iir_frame_stats fs;
    iir_view v = still_view(f);
    iir_test_render(m, &v, out, &fs);
    for (int i = 0; i < 20; i++) refine(m, out, &fs);
    iir_method_destroy(m);
}

/* (e) The refined frame does not depend on the thread count. */
static void test_threads(void **state)
{
    fixture *f = *state;
    const char *names[] = {"iir", "ir"};
    int saved = omp_get_max_threads();
    for (int k = 0; k < 2; k++) {
        iir_image *a = iir_image_create(W, H), *b = iir_image_create(W, H);
        run_refined(f, names[k], 1, a);
        run_refined(f, names[k], 2, b);
        assert_memory_equal(a->pixels, b->pixels, sizeof(iir_vec3) * W * H);
        iir_image_destroy(a);
        iir_image_destroy(b);
    }
    omp_set_num_threads(saved);
}

/* A stop hook that says "stop" from its `after`-th call on. */
typedef struct stop_after {
    int calls, after;
} stop_after;

static bool stop_after_fn(void *ctx)
{
    stop_after *s = ctx;
    bool stop;
#pragma omp critical(test_stop_after)
    stop = ++s->calls > s->after;
    return stop;
}

/* (f) A stopped pass fails with IIR_ERR_INTERRUPTED, counts nothing and leaves no trace: refining
 * on afterwards gives exactly the frame of a twin that was never stopped. */
static void test_stop_early(void **state)
{
    fixture *f = *state;
    const char *names[] = {"iir", "ir"};
    for (int k = 0; k < 2; k++) {
        iir_params p = iir_params_default();
        iir_test_set(&p, "seed", 5);
        iir_test_set(&p, "vpls", 64);
        iir_test_set(&p, "sm_res", 32);
        iir_method *a = iir_test_method(f, names[k], &p), *b = iir_test_method(f, names[k], &p);
        iir_image *ia = iir_image_create(W, H), *ib = iir_image_create(W, H);
        iir_frame_stats fa, fb;
        iir_view v = still_view(f);
        iir_test_render(a, &v, ia, &fa);
        iir_test_render(b, &v, ib, &fb);
        for (int i = 0; i < 3; i++) refine(a, ia, &fa), refine(b, ib, &fb);
        for (int after = 0; after < 2; after++) { /* before the direct light, at the first tile */
            stop_after s = {0, after};
            iir_method_set_stop(a, stop_after_fn, &s);
            iir_error err = {0};
            assert_int_equal(iir_method_refine(a, ia, &fa, &err), IIR_ERR_INTERRUPTED);
            assert_true(s.calls > after);
        }
        iir_method_set_stop(a, NULL, NULL);
        for (int i = 0; i < 14; i++) refine(a, ia, &fa), refine(b, ib, &fb);
        assert_int_equal(fa.samples_per_pixel, fb.samples_per_pixel);
        assert_memory_equal(ia->pixels, ib->pixels, sizeof(iir_vec3) * W * H);
        iir_image_destroy(ia);
        iir_image_destroy(ib);
        iir_method_destroy(a);
        iir_method_destroy(b);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sweep_is_full_sum),
        cmocka_unit_test(test_jitter_antialiases),
        cmocka_unit_test(test_converges_towards_pt),
        cmocka_unit_test(test_live_set_untouched),
        cmocka_unit_test(test_counting_and_convergence),
        cmocka_unit_test(test_threads),
        cmocka_unit_test(test_stop_early),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

/* test_lineage.c -- multi-bounce incremental VPLs (lineage.h, iir --bounces) in the built-in
 * Cornell box: a kept parent keeps its descendants as they are (positions, shadow maps) while only
 * their flux follows the parent's; descendants die and are born with their parents; lineages are
 * deterministic; and the light they add is right against an independent answer, pt with the same
 * bounces: iir's mean brightness matches pt's where one bounce falls measurably short, and its
 * error at equal N and bounces is near ir's. */
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
#include "iir/lineage.h"
#include "iir/method.h"
#include "iir/metrics.h"
#include "iir/scene.h"
#include "testutil.h"

typedef iir_test_cornell fixture;

static iir_incr *make_set(const fixture *f, uint32_t N, uint32_t k_min)
{
    iir_incr_params p = iir_incr_params_default();
    p.target = N, p.k_min = k_min;
    iir_incr *inc = NULL;
    iir_error err = {0};
    if (iir_incr_create(f->scene, f->rt, &p, &inc, &err) != IIR_OK) fail_msg("%s", err.msg);
    return inc;
}

static void step(iir_incr *inc, const iir_light *l)
{
    iir_error err = {0};
    if (iir_incr_update(inc, l, NULL, &err) != IIR_OK) fail_msg("%s", err.msg);
}

static iir_lineage_stats grow(iir_lineage *L, iir_incr *inc, int bounces)
{
    uint32_t n = 0;
    const iir_vpl *v = iir_incr_vpls(inc, &n);
    iir_lineage_stats st;
    iir_error err = {0};
    if (iir_lineage_update(L, v, n, bounces, 7, NULL, &st, &err) != IIR_OK) fail_msg("%s", err.msg);
    return st;
}

/* Over 40 frames of a moving spot: every descendant carried over is where it was, with its
 * (marked) shadow map; counts add up (kept + born = count, the orphans died, their maps freed). */
static void test_survivors_keep_descendants(void **state)
{
    const fixture *f = *state;
    iir_light l = f->scene->lights[0];
    iir_incr *inc = make_set(f, 128, 4);
    iir_lineage *L = iir_lineage_create(f->scene, f->rt);
    step(inc, &l);
    iir_lineage_stats st = grow(L, inc, 5);
    assert_true(st.count > 64 && st.born == st.count && st.kept == 0);
    int kept_checked = 0;
    for (int frame = 1; frame < 40; frame++) {
        /* mark every descendant's map, remember positions, fluxes and parents' fluxes */
        uint32_t nd = 0;
        iir_vpl *d = iir_lineage_vpls(L, &nd);
        iir_vpl *before = malloc((nd ? nd : 1) * sizeof *before);
        for (uint32_t k = 0; k < nd; k++) {
            if (!d[k].smap.depth) d[k].smap.depth = malloc(sizeof(uint16_t)), d[k].smap.res = 1;
            d[k].smap.depth[0] = (uint16_t)k; /* this frame's index */
            before[k] = d[k];
        }
        l.position = iir_add(l.position, iir_v3(0.01f, 0, 0));
        step(inc, &l);
        uint32_t before_count = nd;
        st = grow(L, inc, 5);
        assert_int_equal(st.kept + st.born, st.count);
        assert_int_equal(before_count - st.kept, st.died);
        /* every descendant now carrying a marked map is a kept one, unchanged in place */
        d = iir_lineage_vpls(L, &nd);
        for (uint32_t k = 0; k < nd; k++) {
            if (!d[k].smap.depth) continue;
            uint32_t was = (uint32_t)d[k].smap.depth[0];
            assert_true(was < before_count);
            assert_memory_equal(&d[k].position, &before[was].position, sizeof(iir_vec3));
            kept_checked++;
        }
        free(before);
    }
    print_message("descendants carried over with their maps: %d\n", kept_checked);
    assert_true(kept_checked > 1000);
    iir_lineage_destroy(L); /* frees the marked maps: ASan checks none leaked */
    iir_incr_destroy(inc);
}

/* Flux follows the parent: with the light still and no forced churn every parent survives with
 * its cell, so the light twice as bright doubles every parent's flux and every descendant's. */
static void test_flux_follows_parent(void **state)
{
    const fixture *f = *state;
    iir_light l = f->scene->lights[0];
    iir_incr *inc = make_set(f, 64, 0); /* no forced churn: a still light keeps every VPL */
    iir_lineage *L = iir_lineage_create(f->scene, f->rt);
    step(inc, &l);
    grow(L, inc, 6);
    uint32_t nd = 0;
    const iir_vpl *d = iir_lineage_vpls(L, &nd);
    iir_vec3 *flux = malloc(nd * sizeof *flux);
    for (uint32_t k = 0; k < nd; k++) flux[k] = d[k].flux;
    l.intensity = iir_scale(l.intensity, 2.f);
    step(inc, &l); /* the light still: every VPL survives, its flux doubles */
    iir_lineage_stats st = grow(L, inc, 6);
    d = iir_lineage_vpls(L, &nd);
    int same = 0;
    for (uint32_t k = 0; k < nd; k++) {
        if (fabsf(d[k].flux.x - 2.f * flux[k].x) <= 1e-4f * d[k].flux.x + 1e-12f) same++;
    }
    print_message("light doubled: %d of %u descendants doubled (%u kept)\n", same, nd, st.kept);
    assert_true(nd > 0 && st.kept == nd && st.born == 0);
    assert_int_equal(same, nd);
    free(flux);
    iir_lineage_destroy(L);
    iir_incr_destroy(inc);
}

/* The same parents and seed give the same descendants. */
static void test_deterministic(void **state)
{
    const fixture *f = *state;
    iir_light l = f->scene->lights[0];
    iir_incr *inc = make_set(f, 64, 4);
    step(inc, &l);
    iir_lineage *a = iir_lineage_create(f->scene, f->rt), *b = iir_lineage_create(f->scene, f->rt);
    grow(a, inc, 8);
    grow(b, inc, 8);
    uint32_t na = 0, nb = 0;
    const iir_vpl *da = iir_lineage_vpls(a, &na), *db = iir_lineage_vpls(b, &nb);
    assert_int_equal(na, nb);
    for (uint32_t k = 0; k < na; k++) {
        assert_int_equal(da[k].id, db[k].id);
        assert_memory_equal(&da[k].position, &db[k].position, sizeof(iir_vec3));
        assert_memory_equal(&da[k].flux, &db[k].flux, sizeof(iir_vec3));
    }
    iir_lineage_destroy(a), iir_lineage_destroy(b);
    iir_incr_destroy(inc);
}

/* ---- against pt ---- */

static iir_image *frame(const fixture *f, const char *method, const iir_params *p, int w, int h,
                        int frames)
{
    iir_method *m = iir_test_method(f, method, p);
    iir_image *img = iir_image_create(w, h);
    iir_view view = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_frame_stats fs;
    for (int k = 0; k < frames; k++) iir_test_render(m, &view, img, &fs);
    iir_method_destroy(m);
    return img;
}

static double mean_lum(const iir_image *img)
{
    double s = 0;
    for (int i = 0; i < img->width * img->height; i++) s += iir_luminance(img->pixels[i]);
    return s / (img->width * img->height);
}

/* At bounces 4, iir's mean brightness matches pt's within 3% where bounces 2 is measurably darker
 * (the Cornell box keeps ~10% of its light past the first bounce), and its relMSE is within 1.5x
 * of ir's at the same N and bounces. */
static void test_against_pt(void **state)
{
    const fixture *f = *state;
    enum { W = 96, H = 72 };
    iir_params pp = iir_params_default(), p2 = iir_params_default(), p4 = iir_params_default();
    iir_test_set(&pp, "spp", 512);
    iir_test_set(&pp, "bounces", 4);
    iir_test_set(&pp, "jitter", 0);
    iir_test_set(&p4, "bounces", 4);
    iir_test_set(&p4, "vpls", 1024);
    iir_test_set(&p2, "vpls", 1024);
    iir_image *ref = frame(f, "pt", &pp, W, H, 1);
    iir_image *one = frame(f, "iir", &p2, W, H, 3);
    iir_image *iir4 = frame(f, "iir", &p4, W, H, 3);
    iir_image *ir4 = frame(f, "ir", &p4, W, H, 1);
    double m_ref = mean_lum(ref), m1 = mean_lum(one), m4 = mean_lum(iir4);
    double e_iir = iir_metric_relmse(iir4, ref), e_ir = iir_metric_relmse(ir4, ref);
    print_message("mean luminance: pt (4 bounces) %.5f, iir bounces 2 %.5f (%.1f%%), bounces 4 "
                  "%.5f (%.1f%%); relMSE iir %.5f, ir %.5f\n",
                  m_ref, m1, 100 * (m1 / m_ref - 1), m4, 100 * (m4 / m_ref - 1), e_iir, e_ir);
    assert_true(m1 < 0.95 * m_ref);
    assert_true(fabs(m4 / m_ref - 1) < 0.03);
    assert_true(e_iir < 1.5 * e_ir);
    iir_image_destroy(ref), iir_image_destroy(one), iir_image_destroy(iir4), iir_image_destroy(ir4);
}

/* At bounces 4 the descendants' shadow maps are half the set's resolution (sm_res 128: parents
 * 128^2, descendants 64^2), and every VPL with light has one. */
static void test_descendant_maps_half(void **state)
{
    const fixture *f = *state;
    iir_params p = iir_params_default();
    iir_test_set(&p, "bounces", 4);
    iir_method *m = iir_test_method(f, "iir", &p);
    iir_image *img = iir_image_create(48, 36);
    iir_view view = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_frame_stats fs;
    for (int k = 0; k < 3; k++) iir_test_render(m, &view, img, &fs);
    uint32_t n = 0, parents = 0, descendants = 0;
    const iir_vpl *v = iir_method_vpls(m, &n);
    for (uint32_t i = 0; i < n; i++) {
        if (v[i].null_sample || iir_is_black(v[i].flux)) continue;
        int want = v[i].generation ? 64 : 128;
        if (v[i].smap.res != want)
            fail_msg("VPL %u of generation %u: a %d^2 map, not %d^2", v[i].id, v[i].generation,
                     v[i].smap.res, want);
        v[i].generation ? descendants++ : parents++;
    }
    print_message("%u parents with 128^2 maps, %u descendants with 64^2\n", parents, descendants);
    assert_true(parents > 100 && descendants > 50);
    iir_image_destroy(img);
    iir_method_destroy(m);
}

/* A kept glossy parent's lineage follows its light: the first step was sampled from its lobe for
 * the old wi; when wi turns, the same descendants stay and their flux becomes the parent's times
 * f(wi', d0) / f(wi, d0) of what it was (d0 toward the first descendant; the BRDF from glTF
 * appendix B, testutil), the rest of the path unchanged. */
static void test_glossy_parent_reweighs(void **state)
{
    const fixture *f = *state;
    const double base = 0.8, rough = 0.3;
    iir_vpl parents[64];
    for (uint32_t i = 0; i < 64; i++) { /* on the Cornell box's floor, a metal of base 0.8 */
        iir_vpl v = {.id = 100 + i, .albedo = iir_v3s((float)base), .flux = iir_v3s(1.f)};
        v.position = iir_v3(0.1f + 0.012f * (float)i, 0.f, 0.3f);
        v.lobe = (iir_vpl_lobe){.glossy = true,
                                .metallic = 1.f,
                                .roughness = (float)rough,
                                .f0 = 0.04f,
                                .base = iir_v3s((float)base)};
        v.wi = iir_normalize(iir_v3(0.4f, 1.f, 0.2f));
        iir_vpl_set_normal(&v, iir_v3(0.f, 1.f, 0.f));
        parents[i] = v;
    }
    iir_lineage *L = iir_lineage_create(f->scene, f->rt);
    iir_lineage_stats st;
    iir_error err = {0};
    assert_int_equal(iir_lineage_update(L, parents, 64, 3, 7, NULL, &st, &err), IIR_OK);
    uint32_t nd = 0;
    const iir_vpl *d = iir_lineage_vpls(L, &nd);
    iir_vpl first[64];
    memcpy(first, d, nd * sizeof *d);
    iir_vec3 wi2 = iir_normalize(iir_v3(-0.5f, 1.f, -0.1f));
    for (int i = 0; i < 64; i++) parents[i].wi = wi2;
    assert_int_equal(iir_lineage_update(L, parents, 64, 3, 7, NULL, &st, &err), IIR_OK);
    d = iir_lineage_vpls(L, &nd);
    assert_true(nd > 32 && st.kept == nd && st.born == 0);
    double worst = 0;
    int turned = 0;
    for (uint32_t k = 0; k < nd; k++) {
        uint32_t i = 0; /* its parent: lineage.c names the first descendant of parent p so */
        while (i < 64 && (uint32_t)iir_hash3(parents[i].id, 1, 0x11ea9e) != d[k].id) i++;
        assert_true(i < 64 && first[k].id == d[k].id);
        assert_true(iir_length_sq(iir_sub(d[k].position, first[k].position)) == 0.f);
        iir_vec3 o = iir_madd(parents[i].position, parents[i].normal, iir_rt_epsilon(f->rt));
        iir_vec3 d0 = iir_normalize(iir_sub(d[k].position, o)); /* the path's ray left from o */
        const double w[3] = {d0.x, d0.y, d0.z}, a[3] = {0.4, 1.0, 0.2}, b[3] = {-0.5, 1.0, -0.1};
        double na = sqrt(0.4 * 0.4 + 1 + 0.2 * 0.2), nb = sqrt(0.25 + 1 + 0.01);
        const double wa[3] = {a[0] / na, a[1] / na, a[2] / na};
        const double wb[3] = {b[0] / nb, b[1] / nb, b[2] / nb};
        double want =
            iir_test_gltf_brdf(base, 1, rough, wb, w) / iir_test_gltf_brdf(base, 1, rough, wa, w);
        double got = d[k].flux.x / first[k].flux.x;
        worst = fmax(worst, fabs(got / want - 1));
        turned += fabs(want - 1) > 0.1;
    }
    print_message("glossy parents turned: %u descendants kept, %d of them re-weighed by more than "
                  "10%%, worst %.2e off f(wi', d0) / f(wi, d0)\n",
                  nd, turned, worst);
    assert_true(turned > (int)nd / 4);
    assert_true(worst < 1e-4);
    iir_lineage_destroy(L);
}

/* ---- light paths through a glossy surface ---- */

/* The mean luminance of method's image of f with p, refined to convergence (exact visibility, no
 * filter: refine.h). */
static double refined_mean(const fixture *f, const char *method, const iir_params *p, int w, int h)
{
    iir_method *m = iir_test_method(f, method, p);
    iir_image *img = iir_image_create(w, h);
    iir_view view = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_frame_stats fs;
    iir_error err = {0};
    iir_test_render(m, &view, img, &fs);
    do
        if (iir_method_refine(m, img, &fs, &err) != IIR_OK) fail_msg("%s", err.msg);
    while (!fs.converged);
    double mean = mean_lum(img);
    iir_image_destroy(img);
    iir_method_destroy(m);
    return mean;
}

/* The second bounce's light (the mean of bounces 3 less bounces 2) in the brass corner: light
 * paths leave the brass by its BSDF, so ir's and iir's match pt's within 5%. Leaving it
 * cosine-distributed, as the build before did, they kept 0.62 of it (most of the metal's
 * reflection went up into the open sky instead of into the walls). */
static void test_glossy_paths_against_pt(void **state)
{
    (void)state;
    enum { W = 64, H = 48 };
    fixture c = iir_test_brass_corner();
    double pt[2], got[2][2];
    static const char *const methods[] = {"ir", "iir"};
    for (int b = 0; b < 2; b++) {
        iir_params p = iir_params_default();
        iir_test_set(&p, "bounces", 2 + b);
        iir_test_set(&p, "spp", 1024);
        iir_test_set(&p, "jitter", 0);
        pt[b] = refined_mean(&c, "pt", &p, W, H);
        iir_test_set(&p, "clamp", 0);
        iir_test_set(&p, "vpls", 1024);
        iir_test_set(&p, "refine_passes", 64);
        for (int m = 0; m < 2; m++) got[m][b] = refined_mean(&c, methods[m], &p, W, H);
    }
    double want = pt[1] - pt[0];
    print_message("second bounce off brass: pt %.5f (of %.5f)\n", want, pt[1]);
    for (int m = 0; m < 2; m++) {
        double second = got[m][1] - got[m][0];
        print_message("  %-3s %.5f (%.3f of pt's); bounces 2 %.3f, 3 %.3f of pt's\n", methods[m],
                      second, second / want, got[m][0] / pt[0], got[m][1] / pt[1]);
        assert_true(want > 0.1 * pt[1]); /* the second bounce is measurable */
        if (fabs(second / want - 1) > 0.05)
            fail_msg("%s: second bounce %.3f of pt's", methods[m], second / want);
    }
    iir_test_unload(&c);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_survivors_keep_descendants),
        cmocka_unit_test(test_flux_follows_parent),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_against_pt),
        cmocka_unit_test(test_descendant_maps_half),
        cmocka_unit_test(test_glossy_parent_reweighs),
        cmocka_unit_test(test_glossy_paths_against_pt),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

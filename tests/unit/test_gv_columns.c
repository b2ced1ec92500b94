/* test_gv_columns.c -- the kept VPLs' columns (render/gv_columns.h): a renderer that keeps them
 * from frame to frame gives, to the bit, the frames of a renderer that evaluates every pixel-VPL
 * pair anew -- while an iir set follows a moving light (Cornell box, interleave 3, a brass corner
 * with glossy receivers and VPLs, virtual spherical lights, multires shading), after VPLs' maps are
 * rendered again, a VPL moved under its old map, the camera moved, fluxes changed and a frame
 * stopped half-way -- and it does read most pairs from them once the set is kept. The columns are
 * the AVX2 kernel's: on a machine without AVX2 the tests are skipped. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "testutil.h"

#include "iir/isa.h"
#include "iir/method.h"
#include "iir/render.h"
#include "iir/scene.h"
#include "iir/shadowmap.h"

enum { W = 96, H = 72 };

/* One frame of vpls by r into out; its timing. */
static iir_render_timing frame_with(iir_renderer *r, const iir_view *v, const iir_vpl *vpls,
                                    uint32_t n, const iir_indirect_params *p, iir_image *out)
{
    iir_error err = {0};
    iir_render_timing t = {0};
    iir_render_input in = {&v->camera, v->lights, v->num_lights, vpls, n, 1, NULL};
    if (iir_renderer_frame(r, &in, p, out, &t, NULL, &err) != IIR_OK) fail_msg("%s", err.msg);
    return t;
}

/* The frame of the renderer `kept` against a new renderer's: the same floats. Returns kept's
 * share of pairs read from columns. */
static double same_as_fresh(const iir_test_cornell *f, iir_renderer *kept, const iir_view *v,
                            const iir_vpl *vpls, uint32_t n, const iir_indirect_params *p)
{
    iir_image *a = iir_image_create(W, H), *b = iir_image_create(W, H);
    iir_render_timing t = frame_with(kept, v, vpls, n, p, a);
    iir_renderer *fresh = iir_renderer_create(f->scene, f->rt);
    iir_render_timing u = frame_with(fresh, v, vpls, n, p, b);
    assert_int_equal(u.vpl_reused, 0);
    assert_int_equal(t.vpl_evals, u.vpl_evals);
    assert_true(t.vpl_evals > 0);
    assert_memory_equal(a->pixels, b->pixels, sizeof(iir_vec3) * W * H);
    iir_renderer_destroy(fresh);
    iir_image_destroy(a);
    iir_image_destroy(b);
    return (double)t.vpl_reused / (double)t.vpl_evals;
}

static bool have_avx2(void)
{
    if (iir_isa_supported(IIR_ISA_AVX2)) return true;
    print_message("no AVX2 on this machine: the columns are the AVX2 kernel's\n");
    return false;
}

/* iir's set over 8 frames of a light moving 5 cm a frame, each frame rendered by one kept renderer
 * and by a fresh one. From the third frame on (written the second; then a new VPL's in its first)
 * most pairs come from columns. */
static void follow_light(const iir_test_cornell *f, const iir_indirect_params *p, const char *what)
{
    iir_params mp = iir_params_default();
    iir_method *m = iir_test_method(f, "iir", &mp);
    iir_renderer *kept = iir_renderer_create(f->scene, f->rt);
    iir_image *img = iir_image_create(W, H);
    iir_light light = f->scene->lights[0];
    for (int frame = 0; frame < 8; frame++) {
        light.position = iir_add(f->scene->lights[0].position, iir_v3(0.05f * frame, 0.f, 0.f));
        iir_view v = {&light, 1, f->scene->camera};
        iir_frame_stats fs;
        iir_test_render(m, &v, img, &fs);
        uint32_t n = 0;
        const iir_vpl *vpls = iir_method_vpls(m, &n);
        double share = same_as_fresh(f, kept, &v, vpls, n, p);
        print_message("%s, frame %d: %.1f%% of the pairs from columns\n", what, frame, 100 * share);
        if (frame < 2) assert_true(share == 0.0);
        if (frame >= 3) assert_true(share > 0.5);
    }
    iir_image_destroy(img);
    iir_renderer_destroy(kept);
    iir_method_destroy(m);
}

static void test_cornell(void **state)
{
    if (!have_avx2()) skip();
    iir_indirect_params p = iir_indirect_params_default();
    follow_light(*state, &p, "cornell");
    p.interleave = 3; /* lattices that do not tile the 64-pixel tiles */
    follow_light(*state, &p, "cornell, interleave 3");
}

/* Multires: the columns run over the hierarchy's work items (its coarse texels and the pixels it
 * leaves at full resolution). */
static void test_multires(void **state)
{
    if (!have_avx2()) skip();
    iir_indirect_params p = iir_indirect_params_default();
    p.shading = IIR_SHADING_MULTIRES;
    follow_light(*state, &p, "cornell, multires");
    iir_test_cornell f = iir_test_brass_corner();
    follow_light(&f, &p, "brass corner, multires");
    iir_test_unload(&f);
}

static void test_glossy(void **state)
{
    (void)state;
    if (!have_avx2()) skip();
    iir_test_cornell f = iir_test_brass_corner();
    iir_indirect_params p = iir_indirect_params_default();
    follow_light(&f, &p, "brass corner");
    p.vpl_kind = IIR_VPL_SPHERE; /* radii follow the set */
    p.receiver_bsdf = IIR_RECEIVER_ALL;
    follow_light(&f, &p, "brass corner, spheres, all receivers");
    iir_test_unload(&f);
}

/* A warm iir set (3 frames) and its VPLs copied (their maps shared, owned by the method), with a
 * renderer that keeps columns and the default shading. Not to be moved: view.lights is &light. */
typedef struct warm {
    iir_method *m;
    iir_light light;
    iir_view view;
    uint32_t n;
    iir_vpl *vpls;
    iir_indirect_params p;
    iir_renderer *kept;
} warm;

static void warm_up(const iir_test_cornell *f, warm *w)
{
    iir_params mp = iir_params_default();
    w->m = iir_test_method(f, "iir", &mp);
    iir_image *img = iir_image_create(W, H);
    w->light = f->scene->lights[0];
    w->view = (iir_view){&w->light, 1, f->scene->camera};
    iir_frame_stats fs;
    for (int frame = 0; frame < 3; frame++) iir_test_render(w->m, &w->view, img, &fs);
    iir_image_destroy(img);
    const iir_vpl *vpls = iir_method_vpls(w->m, &w->n);
    w->vpls = malloc(sizeof *w->vpls * w->n);
    memcpy(w->vpls, vpls, sizeof *w->vpls * w->n);
    w->p = iir_indirect_params_default();
    w->kept = iir_renderer_create(f->scene, f->rt);
}

static void warm_free(warm *w)
{
    free(w->vpls);
    iir_renderer_destroy(w->kept);
    iir_method_destroy(w->m);
}

/* same_as_fresh on w's renderer, view and VPLs. */
static double warm_frame(const iir_test_cornell *f, warm *w)
{
    return same_as_fresh(f, w->kept, &w->view, w->vpls, w->n, &w->p);
}

/* The lit VPLs k with k % every == 0. */
static bool picked(const iir_vpl *v, uint32_t k, uint32_t every)
{
    return k % every == 0 && !v->null_sample && v->smap.res > 1;
}

/* What a column depends on changes under a kept renderer that has every column ready. */
static void test_invalidation(void **state)
{
    if (!have_avx2()) skip();
    const iir_test_cornell *f = *state;
    warm w;
    warm_up(f, &w);
    iir_vpl *vpls = w.vpls;
    for (int k = 0; k < 2; k++) warm_frame(f, &w);
    assert_true(warm_frame(f, &w) > 0.99);

    for (uint32_t k = 0; k < w.n; k++) /* flux is not in a column: still read */
        vpls[k].flux = iir_scale(vpls[k].flux, 1.f + 0.1f * (float)(k % 3));
    assert_true(warm_frame(f, &w) > 0.99);

    /* maps rendered again, at another resolution: new stamps */
    iir_smap maps[64] = {{0}};
    uint32_t remapped = 0;
    for (uint32_t k = 0; k < w.n && remapped < 64; k++)
        if (picked(&vpls[k], k, 5)) {
            assert_true(iir_smap_render(&maps[remapped], f->rt, &vpls[k], 32, NULL));
            vpls[k].smap = maps[remapped++];
        }
    assert_true(remapped > 10);
    double share = warm_frame(f, &w);
    print_message("after %u maps rendered again: %.1f%% from columns\n", remapped, 100 * share);
    assert_true(share < 0.95);

    /* VPLs moved 1 cm along their normals under the same maps (a stale map: no column fits) */
    for (uint32_t k = 0; k < w.n; k++)
        if (picked(&vpls[k], k, 7))
            vpls[k].position = iir_madd(vpls[k].position, vpls[k].normal, 0.01f);
    warm_frame(f, &w);

    /* the camera moves: a new G-buffer, every column dropped */
    w.view.camera.position = iir_add(w.view.camera.position, iir_v3(0.1f, 0.f, 0.f));
    assert_true(warm_frame(f, &w) == 0.0);
    for (uint32_t k = 0; k < remapped; k++) iir_smap_release(&maps[k]);
    warm_free(&w);
}

/* A stop that says stop after `limit` polls, counting them. */
typedef struct polls {
    int calls, limit;
} polls;
static bool stop_after(void *ctx)
{
    polls *q = ctx;
    return ++q->calls > q->limit;
}

/* The polls of a second frame (its G-buffer kept): the last ones are the VPL sum's tiles. */
static int polls_of_frame(const iir_test_cornell *f, const iir_view *v, const iir_vpl *vpls,
                          uint32_t n, const iir_indirect_params *p)
{
    iir_renderer *r = iir_renderer_create(f->scene, f->rt);
    iir_image *img = iir_image_create(W, H);
    polls q = {0, 1 << 30};
    frame_with(r, v, vpls, n, p, img);
    iir_renderer_set_stop(r, stop_after, &q);
    frame_with(r, v, vpls, n, p, img);
    iir_image_destroy(img);
    iir_renderer_destroy(r);
    return q.calls;
}

/* A frame stopped half-way through the VPL sum while it writes columns (its last two tiles
 * skipped): they are written again, never read. */
static void test_stopped_frame(void **state)
{
    if (!have_avx2()) skip();
    const iir_test_cornell *f = *state;
    warm w;
    warm_up(f, &w);
    int total = polls_of_frame(f, &w.view, w.vpls, w.n, &w.p);
    warm_frame(f, &w); /* first sight: no column */
    polls q = {0, total - 2};
    iir_renderer_set_stop(w.kept, stop_after, &q);
    iir_image *img = iir_image_create(W, H);
    iir_error err = {0};
    iir_render_input in = {&w.view.camera, w.view.lights, 1, w.vpls, w.n, 1, NULL};
    assert_int_equal(iir_renderer_frame(w.kept, &in, &w.p, img, NULL, NULL, &err),
                     IIR_ERR_INTERRUPTED);
    iir_renderer_set_stop(w.kept, NULL, NULL);
    assert_true(warm_frame(f, &w) == 0.0); /* written again */
    assert_true(warm_frame(f, &w) > 0.99);
    iir_image_destroy(img);
    warm_free(&w);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell),       cmocka_unit_test(test_glossy),
        cmocka_unit_test(test_multires),      cmocka_unit_test(test_invalidation),
        cmocka_unit_test(test_stopped_frame),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

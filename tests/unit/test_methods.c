/* test_methods.c -- the VPL methods through the method interface, against independent answers:
 * one-bounce ir with exact visibility and many VPLs converges to pt --bounces 2; a still light's
 * iir frame equals a frame rendered from the same VPLs with freshly built shadow maps (caching is
 * exact); same seed and path give identical frames, whatever the thread count (iir's step runs
 * beside the direct light on one thread of its team); nonsense is refused. */
#include <omp.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "testutil.h"

#include "iir/method.h"
#include "iir/render.h"
#include "iir/scene.h"
#include "iir/shadowmap.h"
#include "method_internal.h"

typedef iir_test_cornell fixture;

static iir_view still_view(const fixture *f)
{
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    return v;
}

/* A light that moves a little every frame, jumping now and then. */
static iir_light moved(const iir_light *base, int frame)
{
    iir_light l = *base;
    float a = 0.05f * (float)frame + (frame % 7 == 6 ? 1.f : 0.f);
    l.position = iir_add(base->position, iir_v3(0.4f * cosf(a), 0.f, 0.4f * sinf(a)));
    l.direction = iir_normalize(iir_v3(-0.3f * cosf(a), -1.f, -0.3f * sinf(a)));
    return l;
}

/* One-bounce ir with exact visibility, no clamping and 16k VPLs against pt with one bounce.
 * Bound: pt at 2048 spp has per-pixel relative noise of a few % in the indirect-only regions; ir
 * with 16k VPLs is within ~1-2%; so relMSE on smooth pixels of ~1e-3 is expected and 5e-3 is the
 * bound. A missing or doubled bounce gives relMSE > 2e-2 (checked: the direct-only image fails). */
static void test_ir_converges_to_pt(void **state)
{
    fixture *f = *state;
    enum { W = 40, H = 40 };
    iir_view v = still_view(f);
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", 2048);
    iir_test_set(&p, "bounces", 2);
    iir_test_set(&p, "seed", 5);
    iir_image *ref = iir_image_create(W, H), *img = iir_image_create(W, H);
    iir_frame_stats fs;
    iir_method *pt = iir_test_method(f, "pt", &p);
    iir_test_render(pt, &v, ref, &fs);
    iir_method_destroy(pt);

    iir_test_set(&p, "vpls", 16384);
    iir_test_set(&p, "visibility", 1);
    iir_test_set(&p, "clamp", 0.f);
    iir_test_set(&p, "interleave", 1);
    iir_method *ir = iir_test_method(f, "ir", &p);
    iir_test_render(ir, &v, img, &fs);
    assert_true(fs.vpl.count > 10000);
    iir_method_destroy(ir);

    iir_renderer *r = iir_renderer_create(f->scene, f->rt);
    iir_indirect_params ind = iir_indirect_params_default();
    iir_render_timing t;
    iir_image *direct = iir_image_create(W, H);
    iir_error err = {0};
    assert_int_equal(
        iir_renderer_frame(r,
                           &(iir_render_input){&v.camera, v.lights, v.num_lights, NULL, 0, 1, NULL},
                           &ind, direct, &t, NULL, &err),
        IIR_OK);
    const iir_gbuffer *gb = iir_renderer_gbuffer(r);
    double rel = 0, rel_direct = 0, sum_img = 0, sum_ref = 0;
    int n = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            if (!iir_test_smooth_pixel(gb, x, y)) continue;
            iir_vec3 a = *iir_image_at(img, x, y), b = *iir_image_at(ref, x, y);
            iir_vec3 d = *iir_image_at(direct, x, y);
            rel += (iir_sqr(a.x - b.x) / (b.x * b.x + 0.01f) +
                    iir_sqr(a.y - b.y) / (b.y * b.y + 0.01f) +
                    iir_sqr(a.z - b.z) / (b.z * b.z + 0.01f)) /
                   3;
            rel_direct +=
                iir_sqr(iir_luminance(d) - iir_luminance(b)) / (iir_sqr(iir_luminance(b)) + 0.01f);
            sum_img += iir_luminance(a), sum_ref += iir_luminance(b);
            n++;
        }
    assert_true(n > W * H / 2);
    print_message(
        "ir vs pt: relMSE %.2e on %d smooth pixels (direct only: %.2e), means %.4f vs %.4f\n",
        rel / n, n, rel_direct / n, sum_img / n, sum_ref / n);
    assert_true(rel / n < 5e-3);
    assert_true(rel_direct / n > 2e-2); /* the bound can tell a missing bounce */
    assert_true(fabs(sum_img - sum_ref) < 0.02 * sum_ref);
    iir_renderer_destroy(r);
    iir_image_destroy(direct);
    iir_image_destroy(ref);
    iir_image_destroy(img);
}

/* After warm-up with a still light, iir's frame equals the frame rendered from the same VPLs with
 * every shadow map built afresh: the maps cached across frames are exactly the maps of the VPLs. */
static void test_still_light_matches_fresh_maps(void **state)
{
    fixture *f = *state;
    enum { W = 64, H = 48 };
    iir_params p = iir_params_default();
    iir_method *m = iir_test_method(f, "iir", &p);
    iir_image *img = iir_image_create(W, H), *again = iir_image_create(W, H);
    iir_frame_stats fs;
    iir_light light = f->scene->lights[0];
    for (int frame = 0; frame < 40; frame++) {
        iir_light l = frame < 20 ? moved(&f->scene->lights[0], frame) : light;
        iir_view v = {&l, 1, f->scene->camera};
        iir_test_render(m, &v, img, &fs);
    }
    assert_int_equal(fs.vpl.count, (uint32_t)iir_test_get(&p, "vpls"));
    uint32_t n = 0;
    const iir_vpl *vpls = iir_method_vpls(m, &n);
    iir_vpl *copy = malloc(sizeof(iir_vpl) * n);
    memcpy(copy, vpls, sizeof(iir_vpl) * n);
    for (uint32_t i = 0; i < n; i++) copy[i].smap = (iir_smap){0};
    iir_smaps_build(copy, n, f->rt, iir_test_get(&p, "sm_res"), NULL);
    iir_renderer *r = iir_renderer_create(f->scene, f->rt);
    iir_indirect_params ind = iir_indirect_params_default(); /* p holds only defaults */
    iir_render_timing t;
    iir_error err = {0};
    /* the method's last frame was its 40th (index 39): same seed derivation for the direct part */
    iir_view v = {&light, 1, f->scene->camera};
    assert_int_equal(
        iir_renderer_frame(r, &(iir_render_input){&v.camera, v.lights, 1, copy, n, 0, NULL}, &ind,
                           again, &t, NULL, &err),
        IIR_OK);
    /* Direct light from a spot has no randomness, so the frames match exactly. */
    assert_memory_equal(img->pixels, again->pixels, sizeof(iir_vec3) * W * H);
    for (uint32_t i = 0; i < n; i++) iir_smap_release(&copy[i].smap);
    free(copy);
    iir_renderer_destroy(r);
    iir_method_destroy(m);
    iir_image_destroy(img);
    iir_image_destroy(again);
}

static void run_path(const fixture *f, const char *name, uint64_t seed, iir_image *out)
{
    iir_params p = iir_params_default();
    iir_test_set(&p, "seed", seed);
    iir_method *m = iir_test_method(f, name, &p);
    iir_frame_stats fs;
    for (int frame = 0; frame < 12; frame++) {
        iir_light l = moved(&f->scene->lights[0], frame);
        iir_view v = {&l, 1, f->scene->camera};
        iir_test_render(m, &v, out, &fs);
    }
    iir_method_destroy(m);
}

static void test_deterministic(void **state)
{
    fixture *f = *state;
    const char *names[] = {"iir", "ir"};
    for (int k = 0; k < 2; k++) {
        iir_image *a = iir_image_create(48, 36), *b = iir_image_create(48, 36),
                  *c = iir_image_create(48, 36);
        run_path(f, names[k], 9, a);
        run_path(f, names[k], 9, b);
        run_path(f, names[k], 10, c);
        assert_memory_equal(a->pixels, b->pixels, sizeof(iir_vec3) * 48 * 36);
        assert_memory_not_equal(a->pixels, c->pixels, sizeof(iir_vec3) * 48 * 36);
        int saved = omp_get_max_threads();
        for (int threads = 1; threads <= 3; threads += 2) {
            omp_set_num_threads(threads);
            run_path(f, names[k], 9, b);
            assert_memory_equal(a->pixels, b->pixels, sizeof(iir_vec3) * 48 * 36);
        }
        omp_set_num_threads(saved);
        iir_image_destroy(a);
        iir_image_destroy(b);
        iir_image_destroy(c);
    }
}

static void test_refusals(void **state)
{
    fixture *f = *state;
    iir_params p = iir_params_default();
    iir_error err = {0};
    iir_method *m = NULL;
    iir_test_set(&p, "kmin", 9);
    iir_test_set(&p, "kmax", 8);
    assert_int_equal(iir_method_create("iir", f->scene, f->rt, &p, &m, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "kmin"));
    p = iir_params_default();
    assert_int_equal(iir_method_param_set(&p, "interleave", 9, &err), IIR_ERR_INVALID);
    assert_non_null(strstr(err.msg, "interleave must be in [1, 8]"));
    p = iir_params_default();
    m = iir_test_method(f, "iir", &p);
    iir_light point = {.type = IIR_LIGHT_POINT,
                       .name = "bulb",
                       .position = iir_v3(0, 1.5f, 0),
                       .intensity = iir_v3s(1)};
    iir_view v = {&point, 0, f->scene->camera}; /* no light to keep VPLs for */
    iir_image *img = iir_image_create(16, 16);
    iir_frame_stats fs;
    assert_int_equal(iir_method_render(m, &v, img, &fs, &err), IIR_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "spot, point, sun or area light"));
    iir_light bad = f->scene->lights[0];
    bad.position.y = NAN;
    v.lights = &bad;
    v.num_lights = 1;
    assert_int_equal(iir_method_render(m, &v, img, &fs, &err), IIR_ERR_INVALID);
    v.lights = f->scene->lights; /* still usable after refusals */
    assert_int_equal(iir_method_render(m, &v, img, &fs, &err), IIR_OK);
    iir_image_destroy(img);
    iir_method_destroy(m);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_ir_converges_to_pt),
        cmocka_unit_test(test_still_light_matches_fresh_maps),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_refusals),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

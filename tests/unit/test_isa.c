/* test_isa.c -- the shading kernels of every instruction set this machine runs (isa.h) give the
 * scalar reference's frame up to float rounding: the same VPLs and G-buffer rendered once per set,
 * on the Cornell box (diffuse) and on a brass corner (glossy receivers and glossy VPLs, virtual
 * spherical lights), in full and multires shading, at 96x72 and at 99x74 (lanes past the image's
 * edges); and the half floats the maps are stored in, converted as the scalar kernels do and as
 * F16C does. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "testutil.h"

#include "iir/half.h"
#include "iir/isa.h"
#include "iir/method.h"
#include "iir/rng.h"
#include "iir/render.h"
#include "iir/scene.h"

enum { W = 96, H = 72 };

/* Runs iir over a few frames of a moving light so that its set holds VPLs of several ages (and
 * generations: 3 bounces); returns the method, whose VPLs and maps stay valid until it renders
 * again or is destroyed. */
static iir_method *warm_iir(const iir_test_cornell *f, iir_view *v, iir_light *light)
{
    iir_params p = iir_params_default();
    iir_test_set(&p, "bounces", 3);
    iir_method *m = iir_test_method(f, "iir", &p);
    iir_image *img = iir_image_create(W, H);
    iir_frame_stats fs;
    *light = f->scene->lights[0];
    for (int frame = 0; frame < 6; frame++) {
        light->position = iir_add(f->scene->lights[0].position, iir_v3(0.05f * frame, 0.f, 0.f));
        *v = (iir_view){light, 1, f->scene->camera};
        iir_test_render(m, v, img, &fs);
    }
    iir_image_destroy(img);
    return m;
}

static void render_with(iir_renderer *r, iir_isa isa, const iir_view *v, const iir_vpl *vpls,
                        uint32_t n, const iir_indirect_params *p, iir_image *out)
{
    assert_int_equal(iir_renderer_set_isa(r, isa), isa);
    /* NaN everywhere first: a pixel the frame does not write fails the comparison */
    memset(out->pixels, 0xff, sizeof *out->pixels * (size_t)out->width * (size_t)out->height);
    iir_error err = {0};
    iir_render_input in = {&v->camera, v->lights, v->num_lights, vpls, n, 1, NULL};
    if (iir_renderer_frame(r, &in, p, out, NULL, NULL, &err) != IIR_OK) fail_msg("%s", err.msg);
}

/* How a vector kernel may differ from the scalar one. Its arithmetic rounds differently (FMA, the
 * order of a dot product), which moves every pair's light by a few ulps: 1e-5 relative per pixel
 * is a hundred float ulps of headroom over the sum of a few hundred VPLs. A shadow-map texel test
 * d - bias <= depth whose two sides are within rounding of each other may also go the other way,
 * which changes that pair's visibility by up to one bilinear weight: rare (a receiver exactly at
 * an occluder's depth), so at most 0.2% of the pixels may differ by more, and the image's mean
 * by no more than 1e-5 relative. */
static void compare(const iir_image *ref, const iir_image *img, const char *what)
{
    size_t n = (size_t)ref->width * (size_t)ref->height, off = 0;
    double sum_ref = 0, sum = 0, worst = 0;
    for (size_t i = 0; i < n; i++) {
        iir_vec3 a = ref->pixels[i], b = img->pixels[i];
        sum_ref += a.x + a.y + a.z, sum += b.x + b.y + b.z;
        float d = fmaxf(fabsf(a.x - b.x), fmaxf(fabsf(a.y - b.y), fabsf(a.z - b.z)));
        float scale = fmaxf(a.x, fmaxf(a.y, a.z)) + 1e-6f;
        worst = fmax(worst, d / scale);
        if (!(d <= 1e-5f * scale)) off++; /* NaN too */
    }
    print_message("%s: %zu of %zu pixels beyond 1e-5 relative (worst %.2e), mean %.7g vs %.7g\n",
                  what, off, n, worst, sum / (double)n, sum_ref / (double)n);
    assert_true(sum_ref > 0);
    assert_true((double)off <= 0.002 * (double)n);
    assert_true(fabs(sum - sum_ref) <= 1e-5 * sum_ref);
}

static void compare_size(const iir_test_cornell *f, const char *scene_name, const iir_view *v,
                         const iir_vpl *vpls, uint32_t n, int w, int h)
{
    iir_renderer *r = iir_renderer_create(f->scene, f->rt);
    iir_image *ref = iir_image_create(w, h), *img = iir_image_create(w, h);
    struct {
        const char *name;
        iir_shading shading;
        iir_vpl_kind kind;
        iir_receiver_bsdf receivers;
    } cases[] = {{"full", IIR_SHADING_FULL, IIR_VPL_POINT, IIR_RECEIVER_GLOSSY},
                 {"multires", IIR_SHADING_MULTIRES, IIR_VPL_POINT, IIR_RECEIVER_GLOSSY},
                 {"spheres, all receivers", IIR_SHADING_FULL, IIR_VPL_SPHERE, IIR_RECEIVER_ALL}};
    int tested = 0;
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        iir_indirect_params p = iir_indirect_params_default();
        p.shading = cases[c].shading;
        p.vpl_kind = cases[c].kind;
        p.receiver_bsdf = cases[c].receivers;
        render_with(r, IIR_ISA_SCALAR, v, vpls, n, &p, ref);
        for (int isa = IIR_ISA_SCALAR + 1; isa < IIR_ISA_COUNT; isa++) {
            if (!iir_isa_supported((iir_isa)isa)) continue;
            render_with(r, (iir_isa)isa, v, vpls, n, &p, img);
            char what[160];
            snprintf(what, sizeof what, "%s %dx%d, %s, %s", scene_name, w, h, cases[c].name,
                     iir_isa_name((iir_isa)isa));
            compare(ref, img, what);
            tested++;
        }
    }
    if (!tested) print_message("%s: only the scalar kernels run on this machine\n", scene_name);
    iir_image_destroy(ref);
    iir_image_destroy(img);
    iir_renderer_destroy(r);
}

static void compare_isas(const iir_test_cornell *f, const char *scene_name)
{
    iir_view v;
    iir_light light;
    iir_method *m = warm_iir(f, &v, &light);
    uint32_t n = 0;
    const iir_vpl *vpls = iir_method_vpls(m, &n);
    assert_true(n > 100);
    /* and an image whose width is no multiple of 8 (nor 4) and height no multiple of 4: the lean
       direct blocks', the filter's and the compose's partial lanes */
    for (int size = 0; size < 2; size++)
        compare_size(f, scene_name, &v, vpls, n, W + 3 * size, H + 2 * size);
    iir_method_destroy(m);
}

static void test_cornell(void **state)
{
    compare_isas(*state, "cornell");
}

static void test_brass_corner(void **state)
{
    (void)state;
    iir_test_cornell f = iir_test_brass_corner();
    compare_isas(&f, "brass corner");
    iir_test_unload(&f);
}

#if defined(__x86_64__)
#include <immintrin.h>
__attribute__((target("f16c"))) static uint16_t f16c_from(float f)
{
    return (uint16_t)_cvtss_sh(f, _MM_FROUND_TO_NEAREST_INT);
}
__attribute__((target("f16c"))) static float f16c_to(uint16_t h)
{
    return _cvtsh_ss(h);
}
#endif

/* half.h's conversions, which the scalar and SSE2 kernels read the maps with, against F16C's,
 * which the AVX2 kernel reads them with: every non-negative half to float, and floats across the
 * whole range (subnormal halves, ties, overflow) to half. Without F16C: the round trip alone. */
static void test_half_floats(void **state)
{
    (void)state;
    bool f16c = false;
#if defined(__x86_64__)
    f16c = __builtin_cpu_supports("f16c");
#endif
    for (uint32_t h = 0; h <= 0x7c00u; h++) {
        float f = iir_half_to_float((uint16_t)h);
        assert_int_equal(iir_half_from_float(f), h);
#if defined(__x86_64__)
        if (f16c) assert_true(f == f16c_to((uint16_t)h));
#endif
    }
    assert_int_equal(iir_half_from_float(INFINITY), IIR_HALF_INF);
    assert_int_equal(iir_half_from_float(65519.f), 0x7bffu);
    assert_int_equal(iir_half_from_float(65520.f), IIR_HALF_INF);
    if (!f16c) return;
#if defined(__x86_64__)
    iir_rng rng = iir_rng_make(11, 0);
    for (int k = 0; k < 1000000; k++) {
        /* exponents from far below the subnormal halves to beyond their range */
        float f = ldexpf(1.f + iir_rng_uniform(&rng), (int)(iir_rng_uniform(&rng) * 48.f) - 30);
        if (k % 4 == 0) f = iir_half_to_float((uint16_t)(k % 0x7c00)) * 1.0004882f; /* near ties */
        assert_int_equal(iir_half_from_float(f), f16c_from(f));
    }
#endif
}

static void test_names(void **state)
{
    (void)state;
    for (int isa = 0; isa < IIR_ISA_COUNT; isa++)
        assert_int_equal(iir_isa_parse(iir_isa_name((iir_isa)isa)), isa);
    assert_int_equal(iir_isa_parse("avx512"), IIR_ISA_COUNT);
    assert_int_equal(iir_isa_parse(NULL), IIR_ISA_COUNT);
    assert_true(iir_isa_supported(IIR_ISA_SCALAR));
    assert_true(iir_isa_supported(iir_isa_default()));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_names),
        cmocka_unit_test(test_half_floats),
        cmocka_unit_test(test_cornell),
        cmocka_unit_test(test_brass_corner),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

/* test_multires.c -- multiresolution shading (multires.h) against answers worked out from its
 * definition: the discontinuity marks of a synthetic G-buffer (a depth step, a shallow crease,
 * a background row) at every level and every pixel's level; multires shading of one plane seen
 * head-on equals full-resolution shading to the bilinear interpolation error; on the Cornell box
 * multires stays close to full shading and to pt while evaluating at least 4x fewer pixel-VPL
 * pairs at 512x384; refinement ignores it; frames do not depend on the thread count; shading
 * switches live. Timing is not a test (`iird bench` reports it). */
#include <math.h>
#include <omp.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/metrics.h"
#include "iir/multires.h"
#include "iir/render.h"
#include "iir/rng.h"
#include "iir/scene.h"
#include "testutil.h"

/* ---- a synthetic G-buffer ----
 *
 * W x H pixels of a surface seen from a camera at z = 10 looking down -z, pixel (x, y) at world
 * (x, y) * 0.01 (so depth = 10 - z):
 *   x <  STEP:          plane z = 0, normal +z;
 *   STEP <= x < CREASE: plane z = 1, normal +z (a depth step of 1 at depth ~10);
 *   x >= CREASE:        z = 1 + SLOPE (X - Xc), normal (-SLOPE, 0, 1) normalised: continuous with
 *                       the step's top, turned by atan(SLOPE) ~ 2.9 degrees (a shallow crease);
 *   y == H - 1:         background. */
enum { W = 64, H = 32, STEP = 24, CREASE = 44 };
static const float SLOPE = 0.05f;

typedef struct synthetic {
    iir_gbuffer gb;
    iir_vec3 pos[W * H], nrm[W * H], alb[W * H], emi[W * H];
    float depth[W * H];
    uint32_t prim[W * H];
} synthetic;

static void make_synthetic(synthetic *s)
{
    float xc = ((float)CREASE - 0.5f) * 0.01f;
    iir_vec3 tilted = iir_normalize(iir_v3(-SLOPE, 0.f, 1.f));
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            int i = y * W + x;
            float X = (float)x * 0.01f, z = x < STEP ? 0.f : 1.f;
            if (x >= CREASE) z = 1.f + SLOPE * (X - xc);
            s->pos[i] = iir_v3(X, (float)y * 0.01f, z);
            s->nrm[i] = x >= CREASE ? tilted : iir_v3(0, 0, 1);
            s->alb[i] = iir_v3s(0.5f);
            s->emi[i] = iir_v3s(0.f);
            s->depth[i] = y == H - 1 ? INFINITY : 10.f - z;
            s->prim[i] = y == H - 1 ? IIR_NO_HIT : 0;
        }
    s->gb = (iir_gbuffer){.width = W,
                          .height = H,
                          .position = s->pos,
                          .normal = s->nrm,
                          .albedo = s->alb,
                          .base = s->alb,
                          .mr = NULL, /* multires reads none of the BSDF's fields */
                          .emission = s->emi,
                          .depth = s->depth,
                          .prim = s->prim};
}

/* The marks the definition gives, for the three threshold settings of the test. The step is a
 * tangent-plane offset of 1 at depth ~9-10 (any depth threshold below 0.1 sees it); the crease
 * offsets a neighbour by ~0.025 (under 0.01 * 9 = 0.09) with normals at cos 0.99875; every
 * other neighbour lies in the pixel's own tangent plane. */
typedef enum { BOTH, DEPTH_ONLY, NORMAL_ONLY } which;

static bool expected_pixel(which w, int x, int y)
{
    if (y >= H - 2) return true; /* background, and the row beside it */
    bool step = x == STEP - 1 || x == STEP, crease = x == CREASE - 1 || x == CREASE;
    return (w != NORMAL_ONLY && step) || (w != DEPTH_ONLY && crease);
}

static bool expected_texel(which w, int l, int i, int j)
{
    int s = 1 << l;
    for (int y = j * s; y < (j + 1) * s && y < H; y++)
        for (int x = i * s; x < (i + 1) * s && x < W; x++)
            if (expected_pixel(w, x, y)) return true;
    return false;
}

static void check_marks(iir_multires *mr, which w, int L)
{
    for (int l = 0; l <= L; l++) {
        int lw, lh;
        iir_multires_level_size(mr, l, &lw, &lh);
        assert_int_equal(lw, (W + (1 << l) - 1) >> l);
        assert_int_equal(lh, (H + (1 << l) - 1) >> l);
        for (int j = 0; j < lh; j++)
            for (int i = 0; i < lw; i++)
                if (iir_multires_marked(mr, l, i, j) != expected_texel(w, l, i, j))
                    fail_msg("setting %d level %d texel (%d, %d): marked %d, expected %d", (int)w,
                             l, i, j, iir_multires_marked(mr, l, i, j), expected_texel(w, l, i, j));
    }
    /* every pixel takes the coarsest level <= L whose texel is unmarked, 0 if level 1's is */
    const uint8_t *level = iir_multires_levels(mr);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            int want = 0;
            while (want < L && !expected_texel(w, want + 1, x >> (want + 1), y >> (want + 1)))
                want++;
            if (level[y * W + x] != want)
                fail_msg("setting %d pixel (%d, %d): level %d, expected %d", (int)w, x, y,
                         level[y * W + x], want);
        }
}

static void test_discontinuities(void **state)
{
    (void)state;
    synthetic *s = malloc(sizeof *s);
    make_synthetic(s);
    iir_multires *mr = iir_multires_create();
    iir_error err = {0};
    struct {
        which w;
        float depth, normal;
    } cases[] = {{BOTH, 0.01f, 0.999f}, {DEPTH_ONLY, 0.01f, -1.f}, {NORMAL_ONLY, 1e6f, 0.999f}};
    for (int c = 0; c < 3; c++) {
        iir_mr_params p = {.mr_levels = 4,
                           .mr_depth = cases[c].depth,
                           .mr_normal = cases[c].normal,
                           .mr_window = 1};
        assert_int_equal(iir_multires_build(mr, &s->gb, (uint64_t)c, &p, 1, &err), IIR_OK);
        check_marks(mr, cases[c].w, p.mr_levels);
    }
    /* the default normal threshold (0.95) does not see a 3 degree crease */
    iir_mr_params p = {.mr_levels = 4, .mr_depth = 0.01f, .mr_normal = 0.95f, .mr_window = 1};
    assert_int_equal(iir_multires_build(mr, &s->gb, 9, &p, 1, &err), IIR_OK);
    check_marks(mr, DEPTH_ONLY, 4);
    p.mr_levels = 0;
    assert_int_equal(iir_multires_build(mr, &s->gb, 10, &p, 1, &err), IIR_ERR_INVALID);
    p.mr_levels = 4;
    assert_int_equal(iir_multires_build(mr, &s->gb, 11, &p, 9, &err), IIR_ERR_INVALID);
    iir_multires_destroy(mr);
    free(s);
}

/* ---- one plane seen head-on: multires = full to the interpolation error ---- */

/* A 40 x 40 grey floor at y = 0 seen from straight above (image plane parallel to it, so world
 * position is affine in the pixel coordinates and a texel's mean sample is its centre's point). */
static void load_floor(iir_scene **scene, iir_rt **rt)
{
    const char *dir = iir_test_tmpdir("multires-floor");
    FILE *f = iir_test_open_obj(dir, "floor", "newmtl grey\nKd 0.5 0.5 0.5\n");
    iir_test_write_quad(f, "grey", iir_v3(0, 0, 0), iir_v3(0, 0, 20), iir_v3(20, 0, 0));
    fclose(f);
    iir_test_write_file(dir, "floor.scene.json",
                        "{\"camera\": {\"position\": [0, 2.5, 0], \"target\": [0, 0, 0],"
                        " \"up\": [0, 0, -1], \"fov_y\": 90}, \"lights\": []}");
    iir_error err = {0};
    if (iir_test_load_obj(dir, "floor", scene, rt, &err) != IIR_OK) fail_msg("%s", err.msg);
}

/* n VPLs 1 above the floor facing down, Halton-spread over [-2, 2]^2, flux summing to 4. */
static void floor_vpls(uint32_t n, iir_vpl *out)
{
    for (uint32_t i = 0; i < n; i++) {
        iir_vpl v = {0};
        v.id = i;
        v.position = iir_v3(-2.f + 4.f * iir_radical_inverse(2, i + 1), 1.f,
                            -2.f + 4.f * iir_radical_inverse(3, i + 1));
        iir_vpl_set_normal(&v, iir_v3(0, -1, 0));
        v.albedo = iir_v3s(0.5f);
        v.flux = iir_v3s(4.f / (float)n);
        out[i] = v;
    }
}

static float lum_at(const iir_image *img, int x, int y)
{
    return iir_luminance(img->pixels[(size_t)y * (size_t)img->width + (size_t)x]);
}

/* max over the image of |f(x+1) - 2 f(x) + f(x-1)| along x (dx) or y, and of |f(x+1) - f(x)|. */
static void derivative_bounds(const iir_image *f, float *dxx, float *dyy, float *dx, float *dy)
{
    *dxx = *dyy = *dx = *dy = 0.f;
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++) {
            float c = lum_at(f, x, y);
            if (x + 1 < f->width) *dx = fmaxf(*dx, fabsf(lum_at(f, x + 1, y) - c));
            if (y + 1 < f->height) *dy = fmaxf(*dy, fabsf(lum_at(f, x, y + 1) - c));
            if (x > 0 && x + 1 < f->width)
                *dxx = fmaxf(*dxx, fabsf(lum_at(f, x + 1, y) - 2 * c + lum_at(f, x - 1, y)));
            if (y > 0 && y + 1 < f->height)
                *dyy = fmaxf(*dyy, fabsf(lum_at(f, x, y + 1) - 2 * c + lum_at(f, x, y - 1)));
        }
}

/* Interleave 1 and exact rays, so full shading is the VPL sum f at every pixel centre and
 * multires (every pixel at level L, texels of h = 2^L pixels) is the bilinear interpolation of f
 * at the texel centres. Linear interpolation over a spacing h errs by at most h^2 / 8 max|f''|
 * per axis, and bilinear (linear in x, then in y) by the sum of the two; in the outer half texel
 * of the image the interpolation is clamped to the border texel's value, an error of at most
 * (h / 2) max|f'| for that axis. f'' and f' are taken as the largest second and first
 * differences of the full image (per pixel^2 and per pixel), with 25% slack for the differences
 * underestimating the true maxima; the bound is asserted pixel by pixel. */
static void test_plane_matches_full(void **state)
{
    (void)state;
    iir_scene *scene = NULL;
    iir_rt *rt = NULL;
    load_floor(&scene, &rt);
    enum { S = 128, N = 32, L = 4 };
    iir_vpl vpls[N];
    floor_vpls(N, vpls);
    iir_renderer *r = iir_renderer_create(scene, rt);
    iir_image *full = iir_image_create(S, S), *mr = iir_image_create(S, S);
    iir_indirect_params p = iir_indirect_params_default();
    p.visibility = IIR_VIS_RAYS;
    p.interleave = 1;
    p.clamp = 0.f;
    p.mr.mr_levels = L;
    iir_render_timing tf, tm;
    iir_error err = {0};
    iir_render_input in = {&scene->camera, NULL, 0, vpls, N, 1, NULL};
    assert_int_equal(iir_renderer_frame(r, &in, &p, full, &tf, NULL, &err), IIR_OK);
    p.shading = IIR_SHADING_MULTIRES;
    assert_int_equal(iir_renderer_frame(r, &in, &p, mr, &tm, NULL, &err), IIR_OK);
    /* every pixel at level L: (S / 2^L)^2 texels of N evaluations each */
    assert_int_equal(tf.vpl_evals, (uint64_t)S * S * N);
    assert_int_equal(tm.vpl_evals, (uint64_t)(S >> L) * (S >> L) * N);

    float dxx, dyy, dx, dy, h = (float)(1 << L);
    derivative_bounds(full, &dxx, &dyy, &dx, &dy);
    double worst = 0;
    for (int y = 0; y < S; y++)
        for (int x = 0; x < S; x++) {
            bool edge_x = x < h / 2 || x >= S - h / 2, edge_y = y < h / 2 || y >= S - h / 2;
            float bx = edge_x ? h / 2 * dx : h * h / 8 * dxx;
            float by = edge_y ? h / 2 * dy : h * h / 8 * dyy;
            float f = lum_at(full, x, y), bound = 1.25f * (bx + by) + 1e-5f * f;
            float e = fabsf(lum_at(mr, x, y) - f);
            worst = fmax(worst, e / bound);
            if (e > bound)
                fail_msg("pixel (%d, %d): multires %g, full %g, |e| %g > bound %g", x, y,
                         lum_at(mr, x, y), f, e, bound);
        }
    print_message("plane: worst error / bound %.2f (f'' <= %.2e, %.2e per px^2)\n", worst, dxx,
                  dyy);
    iir_image_destroy(full);
    iir_image_destroy(mr);
    iir_renderer_destroy(r);
    iir_rt_destroy(rt);
    iir_scene_destroy(scene);
}

/* ---- the Cornell box through iir ---- */

static double relmse_smooth(const iir_gbuffer *gb, const iir_image *a, const iir_image *b)
{
    double rel = 0;
    int n = 0;
    for (int y = 0; y < a->height; y++)
        for (int x = 0; x < a->width; x++) {
            if (!iir_test_smooth_pixel(gb, x, y)) continue;
            size_t i = (size_t)y * (size_t)a->width + (size_t)x;
            iir_vec3 u = a->pixels[i], v = b->pixels[i];
            rel += (iir_sqr(u.x - v.x) / (v.x * v.x + 0.01f) +
                    iir_sqr(u.y - v.y) / (v.y * v.y + 0.01f) +
                    iir_sqr(u.z - v.z) / (v.z * v.z + 0.01f)) /
                   3;
            n++;
        }
    assert_true(n > a->width * a->height / 2);
    return rel / n;
}

/* iir's still frame with shading full and multires (the same VPL set: same seed), w x h. */
static void render_both(const iir_test_cornell *f, const iir_params *base, iir_image *full,
                        iir_image *mr, iir_frame_stats *fs_full, iir_frame_stats *fs_mr)
{
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    for (int k = 0; k < 2; k++) {
        iir_params p = *base;
        iir_test_set(&p, "shading", k);
        iir_method *m = iir_test_method(f, "iir", &p);
        iir_test_render(m, &v, k ? mr : full, k ? fs_mr : fs_full);
        iir_method_destroy(m);
    }
}

/* At 512x384 (the target): multires evaluates >= 4x fewer pixel-VPL pairs than full
 * shading, and differs from it by interpolation and per-level filtering only. Measured (default
 * mr_window 16): 4.7x fewer, relMSE(multires, full) ~2e-4 on smooth pixels, against ~9e-4 for
 * full against pt: the bound 1e-3 is what full shading's own error would be; a broken level
 * choice or upsampling (e.g. light from the wrong texels) gives > 1e-2. */
static void test_cornell_evaluations(void **state)
{
    const iir_test_cornell *f = *state;
    enum { CW = 512, CH = 384 };
    iir_image *full = iir_image_create(CW, CH), *mr = iir_image_create(CW, CH);
    iir_frame_stats a, b;
    iir_params defaults = iir_params_default();
    render_both(f, &defaults, full, mr, &a, &b);
    iir_renderer *r = iir_renderer_create(f->scene, f->rt);
    iir_indirect_params ind = iir_indirect_params_default();
    iir_image *tmp = iir_image_create(CW, CH);
    iir_error err = {0};
    iir_render_input in = {&f->scene->camera, NULL, 0, NULL, 0, 1, NULL};
    assert_int_equal(iir_renderer_frame(r, &in, &ind, tmp, NULL, NULL, &err), IIR_OK);
    double rel = relmse_smooth(iir_renderer_gbuffer(r), mr, full);
    double ratio = (double)a.vpl_evals / (double)b.vpl_evals;
    print_message("cornell 512x384: evaluations full %llu, multires %llu (%.2fx); relMSE "
                  "multires vs full %.2e\n",
                  (unsigned long long)a.vpl_evals, (unsigned long long)b.vpl_evals, ratio, rel);
    assert_true(a.vpl_evals > 0);
    assert_true(ratio >= 4.0);
    assert_true(rel < 1e-3);
    iir_image_destroy(tmp);
    iir_renderer_destroy(r);
    iir_image_destroy(full);
    iir_image_destroy(mr);
}

/* Against pt (one bounce, through pixel centres as the G-buffer, 1024 spp) at 128x96, on smooth
 * pixels, with mr_levels 2 and mr_window 4: texels as large in the scene as the defaults' at
 * 512x384 (at 128x96 the defaults' 16-pixel texels would span an eighth of the box). pt's own
 * noise at 1024 spp and iir's VPL error make full shading's relMSE ~2e-3; multires adds its
 * interpolation and filter error, which at 512x384 is about half of full's error against pt
 * (test_cornell_evaluations): the bounds are full < 5e-3 (test_methods' bound for ir against pt)
 * and multires < 1.5 x full + 5e-4. A dropped level (black texels) or light upsampled from the
 * wrong texels gives > 1e-2. */
static void test_cornell_against_pt(void **state)
{
    const iir_test_cornell *f = *state;
    enum { CW = 128, CH = 96 };
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_params pp = iir_params_default();
    iir_test_set(&pp, "spp", 1024);
    iir_test_set(&pp, "bounces", 2);
    iir_test_set(&pp, "jitter", 0);
    iir_image *ref = iir_image_create(CW, CH), *full = iir_image_create(CW, CH),
              *mr = iir_image_create(CW, CH);
    iir_frame_stats fs, a, b;
    iir_method *pt = iir_test_method(f, "pt", &pp);
    iir_test_render(pt, &v, ref, &fs);
    iir_method_destroy(pt);
    iir_params scaled = iir_params_default(); /* the defaults' texels at 512x384, in the scene */
    iir_test_set(&scaled, "mr_levels", 2);
    iir_test_set(&scaled, "mr_window", 4);
    render_both(f, &scaled, full, mr, &a, &b);
    iir_renderer *r = iir_renderer_create(f->scene, f->rt);
    iir_indirect_params ind = iir_indirect_params_default();
    iir_image *tmp = iir_image_create(CW, CH);
    iir_error err = {0};
    iir_render_input in = {&f->scene->camera, NULL, 0, NULL, 0, 1, NULL};
    assert_int_equal(iir_renderer_frame(r, &in, &ind, tmp, NULL, NULL, &err), IIR_OK);
    const iir_gbuffer *gb = iir_renderer_gbuffer(r);
    double e_full = relmse_smooth(gb, full, ref), e_mr = relmse_smooth(gb, mr, ref);
    print_message("cornell 128x96 vs pt: relMSE full %.2e, multires %.2e (evaluations %llu vs "
                  "%llu)\n",
                  e_full, e_mr, (unsigned long long)a.vpl_evals, (unsigned long long)b.vpl_evals);
    assert_true(e_full < 5e-3);
    assert_true(e_mr < 1.5 * e_full + 5e-4);
    iir_image_destroy(tmp);
    iir_renderer_destroy(r);
    iir_image_destroy(ref);
    iir_image_destroy(full);
    iir_image_destroy(mr);
}

/* Refinement passes stay full resolution: with shading=multires a converged still is the same
 * image as with full shading (the passes ignore shading). */
static void test_refine_ignores_multires(void **state)
{
    const iir_test_cornell *f = *state;
    enum { CW = 32, CH = 24 };
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_image *img[2] = {iir_image_create(CW, CH), iir_image_create(CW, CH)};
    for (int k = 0; k < 2; k++) {
        iir_params p = iir_params_default();
        iir_test_set(&p, "shading", k);
        iir_test_set(&p, "refine_passes", 16);
        iir_method *m = iir_test_method(f, "iir", &p);
        iir_frame_stats fs;
        iir_test_render(m, &v, img[k], &fs);
        iir_error err = {0};
        for (int i = 0; i < 16; i++)
            assert_int_equal(iir_method_refine(m, img[k], &fs, &err), IIR_OK);
        assert_true(fs.converged);
        iir_method_destroy(m);
    }
    assert_memory_equal(img[0]->pixels, img[1]->pixels, sizeof(iir_vec3) * CW * CH);
    iir_image_destroy(img[0]);
    iir_image_destroy(img[1]);
}

/* The same multires frame with 1 and 2 threads, bit for bit; and shading is a live parameter: a
 * running iir switches to multires and back without starting over. */
static void test_threads_and_live_switch(void **state)
{
    const iir_test_cornell *f = *state;
    enum { CW = 160, CH = 120 };
    iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
    iir_image *img[2] = {iir_image_create(CW, CH), iir_image_create(CW, CH)};
    iir_params p = iir_params_default();
    iir_test_set(&p, "shading", 1);
    iir_frame_stats fs;
    int threads = omp_get_max_threads();
    for (int k = 0; k < 2; k++) {
        omp_set_num_threads(k + 1);
        iir_method *m = iir_test_method(f, "iir", &p);
        iir_test_render(m, &v, img[k], &fs);
        iir_method_destroy(m);
    }
    omp_set_num_threads(threads);
    assert_memory_equal(img[0]->pixels, img[1]->pixels, sizeof(iir_vec3) * CW * CH);

    iir_params q = iir_params_default();
    iir_method *m = iir_test_method(f, "iir", &q);
    iir_test_render(m, &v, img[0], &fs);
    uint64_t full = fs.vpl_evals;
    bool restarted = true;
    iir_error err = {0};
    assert_int_equal(iir_method_set_params(m, &p, &restarted, &err), IIR_OK);
    assert_false(restarted);
    iir_test_render(m, &v, img[1], &fs);
    print_message("live switch: %llu -> %llu evaluations\n", (unsigned long long)full,
                  (unsigned long long)fs.vpl_evals);
    assert_true(fs.vpl_evals > 0 && fs.vpl_evals < full);
    iir_method_destroy(m);
    iir_image_destroy(img[0]);
    iir_image_destroy(img[1]);
}

/* ---- mr_direct tree: the delta lights' direct light on the light tree ---- */

/* The built-in box's direct light alone (no VPLs) at 256x192, full shading and multires with
 * mr_direct tree at light_split t; the shadow rays traced into *rays. */
static void direct_frame(const iir_test_cornell *f, iir_renderer *r, bool tree, float t,
                         iir_image *img, uint64_t *rays)
{
    iir_indirect_params p = iir_indirect_params_default();
    p.shading = tree ? IIR_SHADING_MULTIRES : IIR_SHADING_FULL;
    p.mr.mr_direct = IIR_MR_DIRECT_TREE;
    p.mr.light_split = t;
    iir_render_input in = {
        &f->scene->camera, f->scene->lights, f->scene->num_lights, NULL, 0, 1, NULL};
    iir_raystats st = {0};
    iir_error err = {0};
    assert_int_equal(iir_renderer_frame(r, &in, &p, img, NULL, &st, &err), IIR_OK);
    *rays = st.n[IIR_RAYS_SHADOW];
}

/* Pixels of a whose luminance differs from b's by more than rel of b's (plus 1e-6), and their
 * mean luminances' relative difference. */
static int pixels_off(const iir_image *a, const iir_image *b, float rel, double *mean_rel)
{
    int off = 0;
    double sa = 0, sb = 0;
    for (int y = 0; y < a->height; y++)
        for (int x = 0; x < a->width; x++) {
            float u = lum_at(a, x, y), v = lum_at(b, x, y);
            off += fabsf(u - v) > rel * v + 1e-6f;
            sa += u, sb += v;
        }
    *mean_rel = fabs(sa - sb) / sb;
    return off;
}

/* At the default light_split (0.02) the tree traces under 40% of full shading's shadow rays, and
 * errs where the light bends inside a block by less than 2% of the brightest, or where a shadow
 * thinner than a block's corners' spacing falls between them (blocks of 2 x 2 pixels have no
 * probe). Measured: 30% of the rays, 3 of 49152 pixels off by more than 5%, the mean 0.19% high
 * (1/r^2 is convex: its chords lie above it); at light_split 0, 41% of the rays, 1 pixel off
 * and the mean 0.016% off. Bounds: a tenth of a percent of the pixels off by 5%, the mean within
 * 0.5%. */
static void test_direct_tree(void **state)
{
    const iir_test_cornell *f = *state;
    enum { W = 256, H = 192 };
    iir_renderer *r = iir_renderer_create(f->scene, f->rt);
    iir_image *full = iir_image_create(W, H), *exact = iir_image_create(W, H),
              *tree = iir_image_create(W, H);
    uint64_t rays_full, rays_exact, rays_tree;
    direct_frame(f, r, false, 0.f, full, &rays_full);
    direct_frame(f, r, true, 0.f, exact, &rays_exact);
    direct_frame(f, r, true, 0.02f, tree, &rays_tree);
    double mean_exact, mean_tree;
    int off_exact = pixels_off(exact, full, 0.05f, &mean_exact);
    int off_tree = pixels_off(tree, full, 0.05f, &mean_tree);
    print_message("direct tree, pixels off by 5%%, mean off, rays: split 0 %d, %.2e, %.1f%%; "
                  "split 0.02 %d, %.2e, %.1f%%\n",
                  off_exact, mean_exact, 100.0 * (double)rays_exact / (double)rays_full, off_tree,
                  mean_tree, 100.0 * (double)rays_tree / (double)rays_full);
    assert_true(rays_tree < rays_full * 2 / 5 && rays_tree <= rays_exact);
    assert_true(mean_tree < 0.005 && mean_exact < 0.005);
    assert_true(off_tree < W * H / 1000 && off_exact < W * H / 1000);
    iir_image_destroy(full);
    iir_image_destroy(exact);
    iir_image_destroy(tree);
    iir_renderer_destroy(r);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_discontinuities),
        cmocka_unit_test(test_plane_matches_full),
        cmocka_unit_test(test_cornell_evaluations),
        cmocka_unit_test(test_cornell_against_pt),
        cmocka_unit_test(test_refine_ignores_multires),
        cmocka_unit_test(test_threads_and_live_switch),
        cmocka_unit_test(test_direct_tree),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

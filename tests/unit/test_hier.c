/* test_hier.c -- the hierarchical method (hier) against independent answers:
 *  - an area light over a bare plane (no bounce: a plane cannot light itself): hier's K point
 *    samples on the hierarchy agree with pt's direct light;
 *  - an occluder between the light and the plane: the voxel grid's shadow is where pt's is (3DDA
 *    and the probing option), and without visibility the light leaks under it;
 *  - the Cornell box lit by its ceiling panel: hier against pt --bounces 2 within a bound set by
 *    its approximations, at fewer evaluations than one per pixel;
 *  - the Cornell box on its spot's orbit: the direct light's tree resolves the cone's and the
 *    blocks' shadow edges that the hierarchy of geometry alone smeared (issue 26 item 7). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "testutil.h"

#include "iir/anim.h"
#include "iir/method.h"
#include "iir/metrics.h"
#include "iir/render.h"
#include "iir/scene.h"

typedef iir_test_cornell loaded; /* a scene and its rays */

/* The plane y = 0 (8 x 8), optionally a square occluder at height 0.5 over (0, 0), an area light
 * 1.5 above it facing down, the camera looking down from 3. */
static loaded load_plane(bool occluder)
{
    const char *dir = iir_test_tmpdir(occluder ? "hier-occluder" : "hier-plane");
    iir_test_write_file(dir, "p.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
    char path[1200];
    snprintf(path, sizeof path, "%s/p.obj", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "mtllib p.mtl\n");
    iir_test_write_quad(f, "grey", iir_v3(0, 0, 0), iir_v3(0, 0, 4), iir_v3(4, 0, 0));
    if (occluder)
        iir_test_write_quad(f, "grey", iir_v3(0, 0.5f, 0), iir_v3(0, 0, 0.4f), iir_v3(0.4f, 0, 0));
    fclose(f);
    iir_test_write_file(dir, "p.scene.json",
                        "{\"camera\": {\"position\": [0, 3, 0.001], \"target\": [0, 0, 0],"
                        " \"up\": [0, 0, -1], \"fov_y\": 80},"
                        " \"lights\": [{\"type\": \"area\", \"name\": \"panel\","
                        " \"position\": [0, 1.5, 0], \"direction\": [0, -1, 0], \"up\": [0, 0, 1],"
                        " \"size\": [0.5, 0.5], \"intensity\": 20}]}");
    return iir_test_load(dir, "p");
}

static iir_image *render(const char *method, const loaded *l, int w, int h, const iir_params *p,
                         iir_frame_stats *fs)
{
    iir_view v = {l->scene->lights, l->scene->num_lights, l->scene->camera};
    iir_image *img = iir_image_create(w, h);
    iir_method *m = NULL;
    iir_error err = {0};
    if (iir_method_create(method, l->scene, l->rt, p, &m, &err) != IIR_OK) fail_msg("%s", err.msg);
    if (iir_method_render(m, &v, img, fs, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_method_destroy(m);
    return img;
}

/* Mean luminance over the pixels whose centre lies within r of the image centre (the plane
 * under the light and the occluder), or outside R (r < 0: between R and the rim). */
static double mean_disk(const iir_image *img, float r_in, float r_out)
{
    double sum = 0;
    int n = 0;
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++) {
            float dx = (float)x + 0.5f - 0.5f * img->width,
                  dy = (float)y + 0.5f - 0.5f * img->height;
            float r = sqrtf(dx * dx + dy * dy) / (0.5f * img->width);
            if (r < r_in || r >= r_out) continue;
            sum += iir_luminance(img->pixels[y * img->width + x]);
            n++;
        }
    assert_true(n > 0);
    return sum / n;
}

static double relmse(const iir_image *a, const iir_image *b)
{
    double rel = 0;
    for (int i = 0; i < a->width * a->height; i++) {
        double la = iir_luminance(a->pixels[i]), lb = iir_luminance(b->pixels[i]);
        rel += (la - lb) * (la - lb) / (lb * lb + 0.01);
    }
    return rel / (a->width * a->height);
}

/* The plane's direct light: K = 256 points against pt's 512 samples per pixel, on the finest
 * hierarchy (2 x 2 texels) and on the default one (texels up to 16 x 16 pixels, interpolated: the
 * inverse-square fall-off is curved, so coarse texels cost some error, and fewer evaluations). */
static void test_plane_matches_pt(void **state)
{
    (void)state;
    enum { W = 96, H = 96 };
    loaded l = load_plane(false);
    iir_params p = iir_params_default();
    iir_frame_stats fs, fine;
    iir_test_set(&p, "spp", 512);
    iir_test_set(&p, "bounces", 2);
    iir_test_set(&p, "jitter", 0);
    iir_image *ref = render("pt", &l, W, H, &p, &fs);
    iir_test_set(&p, "area_samples", 256);
    iir_image *img = render("hier", &l, W, H, &p, &fs);
    iir_test_set(&p, "mr_levels", 1);
    iir_image *img1 = render("hier", &l, W, H, &p, &fine);
    double rel = relmse(img, ref), rel1 = relmse(img1, ref);
    double a = mean_disk(img, 0, 2), b = mean_disk(ref, 0, 2);
    print_message("plane: hier vs pt relMSE %.2e (finest level: %.2e), means %.4f / %.4f; %.1f "
                  "light points per pixel (finest: %.1f)\n",
                  rel, rel1, a, b, (double)fs.vpl_evals / (W * H),
                  (double)fine.vpl_evals / (W * H));
    assert_true(rel1 < 2e-3);
    assert_true(rel < 1e-2);
    assert_true(fabs(a - b) < 0.03 * b);
    assert_true(fs.vpl_evals * 8 < fine.vpl_evals);
    iir_image_destroy(img);
    iir_image_destroy(img1);
    iir_image_destroy(ref);
    iir_test_unload(&l);
}

static iir_image *render_from(const char *method, const loaded *l, iir_vec3 eye, int w, int h,
                              const iir_params *p)
{
    iir_view v = {l->scene->lights, l->scene->num_lights, l->scene->camera};
    v.camera.position = eye;
    iir_image *img = iir_image_create(w, h);
    iir_method *m = NULL;
    iir_error err = {0};
    iir_frame_stats fs;
    if (iir_method_create(method, l->scene, l->rt, p, &m, &err) != IIR_OK) fail_msg("%s", err.msg);
    if (iir_method_render(m, &v, img, &fs, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_method_destroy(m);
    return img;
}

/* The occluder (0.8 wide at height 0.5) hides the whole panel (0.5 wide at 1.5) from the plane
 * within 0.47 of the centre: a camera under the occluder at 0.3 sees only that umbra (0.25 around
 * the centre). pt is black there; hier's 3DDA darkens it as much, and so do probes closer than a
 * cell (32 over the ~1.2 of a shadow ray, cells of 1/16); 4 probes step over the occluder's cells,
 * the cheap option's known failure, and without visibility it is lit. From the usual camera, the
 * plane 1.25..1.75 from the centre is outside the penumbra. */
static void test_occluder_shadow(void **state)
{
    (void)state;
    enum { W = 32, H = 32 };
    loaded l = load_plane(true);
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", 64);
    iir_test_set(&p, "bounces", 1);
    const iir_vec3 low = iir_v3(0, 0.3f, 0.001f), high = l.scene->camera.position;
    iir_test_set(&p, "mr_levels", 1); /* visibility alone: the finest hierarchy */
    const char *const modes[] = {"pt", "voxels", "points", "none", "32 points"};
    double umbra[5], lit[5];
    for (int k = 0; k < 5; k++) {
        if (k > 0) iir_test_set(&p, "hier_visibility", k < 4 ? k - 1 : 1);
        if (k == 4) iir_test_set(&p, "vis_points", 32);
        const char *method = k == 0 ? "pt" : "hier";
        iir_image *a = render_from(method, &l, low, W, H, &p);
        iir_image *b = render_from(method, &l, high, W, H, &p);
        umbra[k] = mean_disk(a, 0, 2);
        lit[k] = mean_disk(b, 0.5f, 0.7f);
        print_message("%-6s umbra %.4f, lit ring %.4f\n", modes[k], umbra[k], lit[k]);
        iir_image_destroy(a);
        iir_image_destroy(b);
    }
    assert_true(lit[0] > 0.01);
    assert_true(umbra[0] < 1e-6);
    for (int k = 1; k < 5; k++) assert_true(fabs(lit[k] - lit[0]) < 0.05 * lit[0]);
    assert_true(umbra[1] < 0.02 * lit[0]); /* 3DDA */
    assert_true(umbra[4] < 0.02 * lit[0]); /* probes closer than a cell */
    assert_true(umbra[2] > 0.5 * lit[0]);  /* 4 probes step over the occluder's cells */
    assert_true(umbra[3] > 0.5 * lit[0]);  /* the leak without visibility */
    iir_test_unload(&l);
}

/* The Cornell box with its panel as an area light instead of the spot. Bound: hier's direct light
 * is close to exact but for voxel-wide penumbrae; its bounce light is RSM's (+5% in mean on the
 * box: test_rsm), so relMSE 2e-2 and the mean within 10%. */
static void test_cornell_panel(void **state)
{
    const iir_test_cornell *f = *state;
    enum { W = 48, H = 48 };
    iir_light panel = {.type = IIR_LIGHT_AREA,
                       .position = iir_v3(0.f, 0.f, 0.f),
                       .direction = iir_v3(0, -1, 0),
                       .up = iir_v3(0, 0, 1),
                       .size = iir_v2(0.5f, 0.4f),
                       .intensity = iir_v3s(15.f)};
    snprintf(panel.name, sizeof panel.name, "panel");
    iir_vec3 c = iir_scale(iir_add(f->scene->bounds_min, f->scene->bounds_max), 0.5f);
    panel.position = iir_v3(c.x, f->scene->bounds_max.y - 0.01f, c.z);
    loaded l = {f->scene, f->rt};
    iir_view v = {&panel, 1, f->scene->camera};
    iir_params p = iir_params_default();
    iir_frame_stats fs;
    iir_test_set(&p, "spp", 512);
    iir_test_set(&p, "bounces", 2);
    iir_test_set(&p, "jitter", 0);
    iir_image *ref = iir_image_create(W, H), *img = iir_image_create(W, H);
    iir_method *m = iir_test_method(f, "pt", &p);
    iir_test_render(m, &v, ref, &fs);
    iir_method_destroy(m);
    m = iir_test_method(f, "hier", &p);
    iir_test_render(m, &v, img, &fs);
    iir_method_destroy(m);
    (void)l;
    double rel = relmse(img, ref), a = mean_disk(img, 0, 2), b = mean_disk(ref, 0, 2);
    print_message("cornell panel: hier vs pt relMSE %.2e, means %.4f / %.4f; %.1f evaluations per "
                  "pixel\n",
                  rel, a, b, (double)fs.vpl_evals / (W * H));
    assert_true(rel < 2e-2);
    assert_true(fabs(a - b) < 0.1 * b);
    iir_image_destroy(img);
    iir_image_destroy(ref);
}

/* Renders the built-in box with its spot where the Cornell orbit (scenes/cornell_box/paths/
 * orbit.json, as `iird bench --anim orbit`) puts it at frame f, by `method`. */
static iir_image *render_orbit(const iir_test_cornell *f, const iir_anim *a, int frame,
                               const char *method, const iir_params *p, int w, int h)
{
    const iir_scene *sc = f->scene;
    iir_light lights[8], base;
    uint32_t moved = iir_scene_moved_light(sc, &base);
    assert_true(moved < sc->num_lights && sc->num_lights <= 8);
    iir_anim_lights(a, sc->lights, sc->num_lights, moved, iir_anim_frame_time(a, frame), lights);
    iir_view v = {lights, sc->num_lights, sc->camera};
    iir_image *img = iir_image_create(w, h);
    iir_frame_stats fs;
    iir_method *m = iir_test_method(f, method, p);
    iir_test_render(m, &v, img, &fs);
    iir_method_destroy(m);
    return img;
}

/* Issue 26 item 7: hier against pt (one bounce, through pixel centres) on three poses of the
 * Cornell orbit, relative MSE as `iird bench` measures it. The spot's cone edges on the walls and
 * the blocks' hard shadows are where the light changes inside a smooth surface: the hierarchy of
 * geometry alone interpolated them over 16-pixel texels (stair-stepped edges, smeared shadows);
 * the direct light's tree splits there down to pixels. Measured at 127 x 95 against 64 spp (whose
 * own noise is about 3e-3 of it: two seeds differ by 6.2e-3), mean of the three poses: 7.5e-3
 * with the tree, 2.3e-2 with the hierarchy of geometry alone (light_split 1), 1.5e-2 for the code
 * before the tree (4b12fc0, which had no light_split). The bound, 1e-2, lies a third above the
 * first and a third below the last. */
static void test_cornell_orbit_edges(void **state)
{
    const iir_test_cornell *f = *state;
    enum { W = 127, H = 95, POSES = 3 }; /* odd: blocks cut by the image edge */
    const int frames[POSES] = {0, 67, 133};
    iir_anim *a = NULL;
    iir_error err = {0};
    if (iir_anim_load(IIR_SOURCE_DIR "/scenes/cornell_box/paths/orbit.json", &a, &err) != IIR_OK)
        fail_msg("%s", err.msg);
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", 64);
    iir_test_set(&p, "bounces", 2);
    iir_test_set(&p, "jitter", 0);
    iir_params coarse = p;
    iir_test_set(&coarse, "light_split", 1);
    double rel = 0, rel_coarse = 0;
    for (int k = 0; k < POSES; k++) {
        iir_image *ref = render_orbit(f, a, frames[k], "pt", &p, W, H);
        iir_image *img = render_orbit(f, a, frames[k], "hier", &p, W, H);
        iir_image *geo = render_orbit(f, a, frames[k], "hier", &coarse, W, H);
        double r = iir_metric_relmse(img, ref), rc = iir_metric_relmse(geo, ref);
        print_message("orbit frame %3d: hier vs pt relMSE %.2e (geometry alone: %.2e)\n", frames[k],
                      r, rc);
        rel += r / POSES, rel_coarse += rc / POSES;
        iir_image_destroy(ref);
        iir_image_destroy(img);
        iir_image_destroy(geo);
    }
    print_message("orbit mean: %.2e (geometry alone: %.2e)\n", rel, rel_coarse);
    assert_true(rel < 1e-2);
    assert_true(rel_coarse > 1e-2); /* the case tests the light's refinement */
    iir_anim_destroy(a);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plane_matches_pt),
        cmocka_unit_test(test_occluder_shadow),
        cmocka_unit_test(test_cornell_panel),
        cmocka_unit_test(test_cornell_orbit_edges),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

/* test_hybrid.c -- the two-pass method against independent answers on the shipped cornell_spheres
 * scene: a mirror shows the radiosity-lit room (each mirror pixel is the mirror's reflectance times
 * what the radiosity method sees from the bounce point along the reflected ray, traced here), the
 * diffuse pixels are radiosity's, the image is nearer pt's (8 bounces) than whitted's or
 * radiosity's alone, and progressive refinement converges to the Gauss-Seidel frame. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <string.h>

#include <cmocka.h>

#include "iir/method.h"
#include "iir/metrics.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "testutil.h"

enum { W = 64, H = 48 };

typedef iir_test_cornell loaded;

static loaded load_spheres(void)
{
    return iir_test_load(IIR_SOURCE_DIR "/scenes/cornell_spheres", "cornell_spheres");
}

static iir_image *render(const loaded *l, const char *method, const iir_params *p,
                         const iir_camera *cam, int w, int h)
{
    iir_method *m = iir_test_method(l, method, p);
    iir_image *img = iir_image_create(w, h);
    iir_view view = {l->scene->lights, l->scene->num_lights, cam ? *cam : l->scene->camera};
    iir_frame_stats fs;
    iir_test_render(m, &view, img, &fs);
    iir_method_destroy(m);
    return img;
}

static const iir_material *material_of(const loaded *l, uint32_t prim)
{
    return &l->scene->material_list[l->scene->materials[prim]];
}

/* Where pixel (x, y)'s centre ray first meets the scene. */
static bool first_hit(const loaded *l, const iir_camera_frame *cf, int x, int y, iir_ray *ray,
                      iir_hit *hit)
{
    *ray = iir_make_ray(cf->origin, iir_camera_dir(cf, x + 0.5f, y + 0.5f), 0.f, INFINITY);
    return iir_rt_intersect(l->rt, ray, hit, NULL, IIR_RAYS_BENCH);
}

/* Radiosity's value along the mirror's reflection of the pixel's ray: a 1 x 1 radiosity frame from
 * the bounce point looking along R = V - 2 (V.N) N (its one pixel centre is the view direction). */
static iir_vec3 room_in_mirror(const loaded *l, const iir_params *p, const iir_ray *ray,
                               const iir_hit *hit)
{
    iir_vec3 n = l->scene->normals[hit->prim];
    if (iir_dot(n, ray->dir) > 0.f) n = iir_neg(n);
    iir_vec3 R = iir_sub(ray->dir, iir_scale(n, 2.f * iir_dot(ray->dir, n)));
    iir_vec3 p0 = iir_madd(iir_madd(ray->org, ray->dir, hit->t), n, 1e-4f);
    iir_vec3 up = fabsf(R.y) < 0.9f ? iir_v3(0, 1, 0) : iir_v3(1, 0, 0);
    iir_camera cam = {p0, iir_add(p0, R), up, 10.f};
    iir_image *img = render(l, "radiosity", p, &cam, 1, 1);
    iir_vec3 L = img->pixels[0];
    iir_image_destroy(img);
    return L;
}

/* Every mirror pixel whose reflection lands on a diffuse surface: hybrid = specular x radiosity's
 * value there; every diffuse pixel: hybrid = radiosity. And the mirror shows more than whitted's
 * (direct light only) mirror. */
static void test_mirror_shows_radiosity(void **state)
{
    (void)state;
    loaded l = load_spheres();
    iir_params p = iir_params_default();
    iir_image *hy = render(&l, "hybrid", &p, NULL, W, H);
    iir_image *rad = render(&l, "radiosity", &p, NULL, W, H);
    iir_image *wh = render(&l, "whitted", &p, NULL, W, H);
    iir_camera_frame cf = iir_camera_setup(&l.scene->camera, W, H);
    int mirror = 0, mirror_ok = 0, diffuse = 0, diffuse_ok = 0;
    double hy_sum = 0, wh_sum = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            iir_ray ray;
            iir_hit hit;
            if (!first_hit(&l, &cf, x, y, &ray, &hit)) continue;
            const iir_material *m = material_of(&l, hit.prim);
            iir_vec3 got = *iir_image_at(hy, x, y), want;
            if (m->kind == IIR_MATERIAL_MIRROR) {
                want = iir_mul(m->specular, room_in_mirror(&l, &p, &ray, &hit));
                hy_sum += iir_luminance(got), wh_sum += iir_luminance(*iir_image_at(wh, x, y));
            } else if (m->kind == IIR_MATERIAL_DIFFUSE)
                want = *iir_image_at(rad, x, y);
            else
                continue;
            bool ok = iir_length(iir_sub(got, want)) <= 0.02f * iir_length(want) + 1e-4f;
            if (m->kind == IIR_MATERIAL_MIRROR)
                mirror++, mirror_ok += ok;
            else
                diffuse++, diffuse_ok += ok;
        }
    print_message("hybrid: %d/%d mirror pixels and %d/%d diffuse pixels as radiosity says; the "
                  "mirror's light %.4f against whitted's %.4f\n",
                  mirror_ok, mirror, diffuse_ok, diffuse, hy_sum, wh_sum);
    assert_true(mirror > 50 && diffuse > W * H / 2);
    /* pixel-sized slivers: a sphere facet's edge, a shadow boundary seen at another angle */
    assert_true(mirror_ok >= 0.95 * mirror);
    assert_true(diffuse_ok >= 0.98 * diffuse);
    assert_true(hy_sum > 1.2 * wh_sum); /* the room's indirect light, in the mirror */
    iir_image_destroy(hy), iir_image_destroy(rad), iir_image_destroy(wh);
    iir_test_unload(&l);
}

/* Against pt with 8 bounces (through pixel centres): hybrid has what whitted lacks (indirect
 * diffuse light) and what radiosity lacks (mirror and glass), so its error is the smallest. */
static void test_nearer_pt_than_either_pass(void **state)
{
    (void)state;
    loaded l = load_spheres();
    iir_params p = iir_params_default(), pp = iir_params_default();
    iir_test_set(&pp, "spp", 256);
    iir_test_set(&pp, "bounces", 8);
    iir_test_set(&pp, "jitter", 0);
    iir_image *ref = render(&l, "pt", &pp, NULL, W, H);
    const char *methods[] = {"hybrid", "whitted", "radiosity"};
    double err[3];
    for (int k = 0; k < 3; k++) {
        iir_image *img = render(&l, methods[k], &p, NULL, W, H);
        err[k] = iir_metric_relmse(img, ref);
        iir_image_destroy(img);
    }
    print_message("relMSE against pt (8 bounces): hybrid %.4f, whitted %.4f, radiosity %.4f\n",
                  err[0], err[1], err[2]);
    assert_true(err[0] < 0.7 * err[1]);
    assert_true(err[0] < 0.7 * err[2]);
    iir_image_destroy(ref);
    iir_test_unload(&l);
}

/* Progressive: the first frame has unshot power; refinement re-traces with each batch until it
 * converges, to the Gauss-Seidel frame within the tolerances. */
static void test_progressive_converges(void **state)
{
    (void)state;
    loaded l = load_spheres();
    iir_params gs = iir_params_default(), pr = iir_params_default();
    iir_test_set(&pr, "solver", 2); /* progressive */
    iir_test_set(&pr, "shoot_batch", 64);
    iir_test_set(&pr, "tolerance", 1e-5);
    iir_test_set(&gs, "tolerance", 1e-6);
    iir_image *want = render(&l, "hybrid", &gs, NULL, W, H);
    iir_method *m = iir_test_method(&l, "hybrid", &pr);
    iir_image *img = iir_image_create(W, H);
    iir_view view = {l.scene->lights, l.scene->num_lights, l.scene->camera};
    iir_frame_stats fs;
    iir_error err;
    iir_test_render(m, &view, img, &fs);
    assert_false(fs.converged);
    int passes = 0;
    while (!fs.converged && passes < 10000) {
        if (iir_method_refine(m, img, &fs, &err) != IIR_OK) fail_msg("%s", err.msg);
        passes++;
    }
    assert_true(fs.converged);
    double rel = iir_metric_relmse(img, want);
    print_message(
        "progressive hybrid: converged after %d passes, relMSE %.2g against gauss_seidel\n", passes,
        rel);
    assert_true(passes > 1);
    assert_true(rel < 1e-4);
    iir_method_destroy(m);
    iir_image_destroy(img), iir_image_destroy(want);
    iir_test_unload(&l);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_mirror_shows_radiosity),
        cmocka_unit_test(test_nearer_pt_than_either_pass),
        cmocka_unit_test(test_progressive_converges),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

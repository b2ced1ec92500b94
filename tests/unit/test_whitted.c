/* test_whitted.c -- mirrors and glass against independent answers: the optics helpers (Snell, total
 * internal reflection, Fresnel, energy along random branch chains), whitted's mirror image against
 * a bounce point computed here, total internal reflection rendered inside a glass slab, the
 * adaptive depth control's error bound and ray saving on the shipped cornell_spheres scene, pt
 * through a glass slab against (1 - R)^2 / (1 - R^2), and the VPL methods' notes. Scenes are
 * written as OBJ + MTL + sidecar and loaded for real. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/method.h"
#include "iir/rng.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "specular.h"
#include "testutil.h"

/* Where the frame stats keep whitted's `branches_cut` counter (iir_method_counters). */
static int counter_of(const char *method, const char *name)
{
    int i = iir_method_counter_index(method, name);
    assert_true(i >= 0);
    return i;
}
#define BRANCHES_CUT counter_of("whitted", "branches_cut")

/* ---- small scenes ---- */

typedef iir_test_cornell loaded; /* a scene and its rays */

static loaded load_path(const char *path)
{
    loaded l = {0};
    iir_error err = {0};
    if (iir_scene_open(path, NULL, &l.scene, &l.rt, &err) != IIR_OK) fail_msg("%s", err.msg);
    return l;
}

/* An axis-aligned box of half-sizes h about c, wound outward. */
static void write_box(FILE *f, const char *mtl, iir_vec3 c, iir_vec3 h)
{
    const float hv[3] = {h.x, h.y, h.z};
    for (int k = 0; k < 3; k++)
        for (int s = -1; s <= 1; s += 2) {
            iir_vec3 e[3] = {iir_v3(1, 0, 0), iir_v3(0, 1, 0), iir_v3(0, 0, 1)};
            iir_vec3 a = iir_scale(e[(k + 1) % 3], hv[(k + 1) % 3]);
            iir_vec3 b = iir_scale(e[(k + 2) % 3], hv[(k + 2) % 3]);
            iir_vec3 centre = iir_madd(c, e[k], (float)s * hv[k]);
            if (s > 0)
                iir_test_write_quad(f, mtl, centre, a, b);
            else
                iir_test_write_quad(f, mtl, centre, b, a);
        }
}

static FILE *open_obj(const char *dir, const char *name, const char *mtl_text)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.mtl", dir, name);
    FILE *f = fopen(path, "w");
    fputs(mtl_text, f);
    fclose(f);
    snprintf(path, sizeof path, "%s/%s.obj", dir, name);
    f = fopen(path, "w");
    fprintf(f, "mtllib %s.mtl\n", name);
    return f;
}

/* A sidecar with no lights (emitters stay geometry) and this camera. */
static void write_sidecar(const char *dir, const char *name, iir_vec3 eye, iir_vec3 at, float fov)
{
    char text[512], file[256];
    snprintf(text, sizeof text,
             "{\"lights\": [], \"camera\": {\"position\": [%g, %g, %g], \"target\": [%g, %g, %g], "
             "\"up\": [0, 1, 0], \"fov_y\": %g}}",
             eye.x, eye.y, eye.z, at.x, at.y, at.z, fov);
    snprintf(file, sizeof file, "%s.scene.json", name);
    iir_test_write_file(dir, file, text);
}

static iir_image *render(const loaded *l, const char *method, const iir_params *p, int w, int h,
                         iir_frame_stats *fs)
{
    iir_method *m = NULL;
    iir_error err = {0};
    iir_image *img = iir_image_create(w, h);
    iir_view view = {l->scene->lights, l->scene->num_lights, l->scene->camera};
    if (iir_method_create(method, l->scene, l->rt, p, &m, &err) != IIR_OK) fail_msg("%s", err.msg);
    if (iir_method_render(m, &view, img, fs, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_method_destroy(m);
    return img;
}

/* ---- the optics helpers ---- */

static void test_snell_and_tir(void **state)
{
    (void)state;
    const float n = 1.5f, critical = asinf(1.f / n);
    iir_vec3 up = iir_v3(0, 1, 0); /* the glass's outward normal; glass below y = 0 */
    for (int k = 1; k < 90; k++) {
        float theta = iir_radians((float)k);
        /* inside, travelling up towards the surface at theta from the normal */
        iir_vec3 V = iir_v3(sinf(theta), cosf(theta), 0);
        iir_glass_split g = iir_glass_at(V, up, n);
        assert_false(g.entering);
        if (theta > critical + 1e-3f) {
            assert_false(g.has_t); /* past the critical angle: no refracted branch */
            assert_true(g.F == 1.f);
        } else if (theta < critical - 1e-3f) {
            assert_true(g.has_t);
            float sin_t = sqrtf(g.wt.x * g.wt.x + g.wt.z * g.wt.z);
            assert_float_equal(n * sinf(theta), sin_t, 1e-4); /* Snell */
            assert_true(g.wt.y > 0.f);                        /* out through the top */
            assert_true(g.F > 0.f && g.F < 1.f);
        }
        /* reflection: same angle, mirrored about the normal */
        assert_float_equal(g.wr.x, V.x, 1e-6);
        assert_float_equal(g.wr.y, -V.y, 1e-6);
    }
    /* from outside at normal incidence: F = ((n - 1) / (n + 1))^2 */
    iir_glass_split g = iir_glass_at(iir_v3(0, -1, 0), up, n);
    assert_true(g.entering && g.has_t);
    assert_float_equal(g.F, iir_sqr((n - 1.f) / (n + 1.f)), 1e-6);
    assert_float_equal(g.wt.y, -1.f, 1e-6);
}

/* Along random chains of random specular events the product of branch weights never exceeds 1,
 * nor does the sum of a split's two weights (pt's throughput takes one of them divided by its
 * probability: 1, the tint or the mirror's specular, each <= 1). */
static void test_energy_never_grows(void **state)
{
    (void)state;
    iir_rng rng = iir_rng_make(7, 1);
    for (int chain = 0; chain < 2000; chain++) {
        iir_vec3 w = iir_v3s(1.f);
        for (int depth = 0; depth < 12; depth++) {
            iir_vec3 V =
                iir_normalize(iir_v3(iir_rng_uniform(&rng) - 0.5f, iir_rng_uniform(&rng) - 0.5f,
                                     iir_rng_uniform(&rng) - 0.5f));
            iir_vec3 n =
                iir_normalize(iir_v3(iir_rng_uniform(&rng) - 0.5f, iir_rng_uniform(&rng) - 0.5f,
                                     iir_rng_uniform(&rng) - 0.5f));
            iir_vec3 tint =
                iir_v3(iir_rng_uniform(&rng), iir_rng_uniform(&rng), iir_rng_uniform(&rng));
            float ior = 1.f + 2.f * iir_rng_uniform(&rng);
            iir_glass_split g = iir_glass_at(V, n, ior);
            assert_true(g.F >= 0.f && g.F <= 1.f);
            iir_vec3 kt = iir_scale(tint, g.has_t ? 1.f - g.F : 0.f);
            assert_true(iir_max_comp(iir_add(iir_v3s(g.F), kt)) <= 1.f + 1e-6f);
            assert_float_equal(iir_length(g.wr), 1.f, 1e-4);
            if (g.has_t) assert_float_equal(iir_length(g.wt), 1.f, 1e-4);
            bool mirror = iir_rng_uniform(&rng) < 0.3f;
            iir_vec3 f = mirror ? tint : iir_rng_uniform(&rng) < 0.5f ? iir_v3s(g.F) : kt;
            w = iir_mul(w, f);
            assert_true(iir_max_comp(w) <= 1.f + 1e-6f);
        }
    }
}

/* ---- a mirror shows what the bounce point says ---- */

enum { MW = 64, MH = 48 };

/* A mirror floor (y = 0, |x|, |z| <= 2, reflectance 0.9) before an emissive wall at z = -2 facing
 * +z: red for x < 0, green for x > 0, y in [0, 3]. */
static loaded mirror_scene(void)
{
    const char *dir = iir_test_tmpdir("whitted-mirror");
    FILE *f = open_obj(dir, "mirror",
                       "newmtl mirror\nillum 3\nKd 0 0 0\nKs 0.9 0.9 0.9\n"
                       "newmtl red\nKd 0 0 0\nKe 1 0 0\nnewmtl green\nKd 0 0 0\nKe 0 1 0\n");
    iir_test_write_quad(f, "mirror", iir_v3(0, 0, 0), iir_v3(0, 0, 2), iir_v3(2, 0, 0));
    iir_test_write_quad(f, "red", iir_v3(-1, 1.5f, -2), iir_v3(1, 0, 0), iir_v3(0, 1.5f, 0));
    iir_test_write_quad(f, "green", iir_v3(1, 1.5f, -2), iir_v3(1, 0, 0), iir_v3(0, 1.5f, 0));
    fclose(f);
    write_sidecar(dir, "mirror", iir_v3(0.3f, 1.2f, 1.5f), iir_v3(0.2f, 0.f, -1.f), 50.f);
    char path[1200];
    snprintf(path, sizeof path, "%s/mirror.obj", dir);
    return load_path(path);
}

/* What pixel (x, y) should show, by this test's own ray math: the camera ray meets y = 0 at p,
 * R = (d.x, -d.y, d.z) meets z = -2 at q; 0.9 Le(q). *sure is false near the red/green seam and
 * the wall's and floor's edges. */
static iir_vec3 expected_mirror_pixel(const iir_camera_frame *cf, int x, int y, bool *sure)
{
    iir_vec3 d = iir_camera_dir(cf, x + 0.5f, y + 0.5f), o = cf->origin;
    *sure = false;
    if (d.y >= -1e-3f) return iir_v3s(0.f);
    iir_vec3 p = iir_madd(o, d, -o.y / d.y);
    if (fabsf(p.x) > 1.9f || fabsf(p.z) > 1.9f) return iir_v3s(0.f);
    iir_vec3 R = iir_v3(d.x, -d.y, d.z);
    *sure = true;
    if (R.z >= 0.f) return iir_v3s(0.f);
    iir_vec3 q = iir_madd(p, R, (-2.f - p.z) / R.z);
    if (fabsf(q.x) < 0.05f || fabsf(q.x) > 1.95f || fabsf(q.y - 1.5f) > 1.45f) *sure = false;
    if (q.y > 3.05f) *sure = true; /* over the wall: nothing */
    bool on_wall = fabsf(q.x) <= 2.f && q.y >= 0.f && q.y <= 3.f;
    if (!on_wall) return iir_v3s(0.f);
    return q.x < 0.f ? iir_v3(0.9f, 0, 0) : iir_v3(0, 0.9f, 0);
}

static void check_mirror_image(const loaded *l, const char *method, const iir_params *p);

/* whitted, and pt through pixel centres (a mirror bounce is deterministic, so every sample is the
 * same): both show at every pixel what the bounce point says. */
static void test_mirror_shows_bounce_point(void **state)
{
    (void)state;
    for (int pass = 0; pass < 2; pass++) {
        loaded l = mirror_scene();
        iir_params p = iir_params_default();
        if (pass == 1) {
            iir_test_set(&p, "jitter", 0);
            iir_test_set(&p, "spp", 2);
            iir_test_set(&p, "bounces", 4);
        }
        check_mirror_image(&l, pass ? "pt" : "whitted", &p);
        iir_test_unload(&l);
    }
}

static void check_mirror_image(const loaded *lp, const char *method, const iir_params *pp)
{
    const loaded l = *lp;
    iir_params p = *pp;
    iir_frame_stats fs;
    iir_image *img = render(&l, method, &p, MW, MH, &fs);
    iir_camera_frame cf = iir_camera_setup(&l.scene->camera, MW, MH);
    int checked = 0, red = 0, green = 0;
    for (int y = 0; y < MH; y++)
        for (int x = 0; x < MW; x++) {
            bool sure;
            iir_vec3 want = expected_mirror_pixel(&cf, x, y, &sure);
            if (!sure) continue;
            iir_vec3 got = *iir_image_at(img, x, y);
            if (iir_length(iir_sub(got, want)) > 1e-4f)
                fail_msg("%s: pixel (%d, %d): (%g, %g, %g), the bounce point says (%g, %g, %g)",
                         method, x, y, got.x, got.y, got.z, want.x, want.y, want.z);
            checked++;
            red += want.x > 0.f, green += want.y > 0.f;
        }
    assert_true(checked > MW * MH / 3);
    assert_true(red > 50 && green > 50); /* both halves seen in the mirror */
    iir_image_destroy(img);
}

/* ---- total internal reflection inside a glass slab ---- */

/* The camera sits inside a wide glass slab (y in [-5, 5]); a green emitter lies inside on its
 * floor facing up, a red one above the slab facing down. Looking up at theta from the vertical,
 * past the critical angle only the reflection (green) is seen; below it the red light comes
 * through. */
static loaded slab_scene(float theta_deg)
{
    const char *dir = iir_test_tmpdir(theta_deg > 40.f ? "whitted-tir-a" : "whitted-tir-b");
    FILE *f = open_obj(dir, "slab",
                       "newmtl glass\nillum 7\nNi 1.5\nKd 0 0 0\n"
                       "newmtl red\nKd 0 0 0\nKe 1 0 0\nnewmtl green\nKd 0 0 0\nKe 0 1 0\n");
    write_box(f, "glass", iir_v3(0, 0, 0), iir_v3(60, 5, 60));
    iir_test_write_quad(f, "green", iir_v3(0, -4.9f, 0), iir_v3(0, 0, 59), iir_v3(59, 0, 0));
    iir_test_write_quad(f, "red", iir_v3(0, 8, 0), iir_v3(200, 0, 0), iir_v3(0, 0, 200));
    fclose(f);
    float t = iir_radians(theta_deg);
    write_sidecar(dir, "slab", iir_v3(0, 0, 0), iir_v3(sinf(t), cosf(t), 0), 10.f);
    char path[1200];
    snprintf(path, sizeof path, "%s/slab.obj", dir);
    return load_path(path);
}

static void test_total_internal_reflection_rendered(void **state)
{
    (void)state;
    iir_params p = iir_params_default();
    iir_test_set(&p, "min_weight", 0);
    for (int pass = 0; pass < 2; pass++) {
        float theta = pass == 0 ? 60.f : 20.f; /* critical angle: 41.8 degrees */
        loaded l = slab_scene(theta);
        iir_frame_stats fs;
        iir_image *img = render(&l, "whitted", &p, 16, 16, &fs);
        for (int i = 0; i < 16 * 16; i++) {
            iir_vec3 L = img->pixels[i];
            if (pass == 0) { /* all reflection: green, not a trace of red */
                assert_true(L.x == 0.f);
                assert_float_equal(L.y, 1.f, 1e-4);
            } else { /* refracted red (1 - F) and reflected green F */
                assert_true(L.x > 0.8f && L.x < 1.f);
                assert_float_equal(L.x + L.y, 1.f, 1e-3);
            }
        }
        iir_image_destroy(img);
        iir_test_unload(&l);
    }
}

/* ---- adaptive depth on the sphere scene ---- */

/* An upper bound of any radiance in a scene lit by its point-like lights alone (no emitters, no
 * ambient): max rho / pi times the most irradiance a light gives, max over directions w of
 * I(w) / t(w)^2 with t the distance to what the light's ray along w meets (64 x 128 directions). */
static float scene_max_radiance(const loaded *l)
{
    float rho = 0.f, E = 0.f;
    for (uint32_t m = 0; m < l->scene->num_materials; m++)
        rho = fmaxf(rho, iir_max_comp(l->scene->material_list[m].albedo));
    for (uint32_t k = 0; k < l->scene->num_lights; k++)
        for (int i = 0; i < 64; i++)
            for (int j = 0; j < 128; j++) {
                float z = 1.f - 2.f * (i + 0.5f) / 64.f, r = sqrtf(1.f - z * z);
                float phi = 2.f * IIR_PI * (j + 0.5f) / 128.f;
                iir_vec3 w = iir_v3(r * cosf(phi), z, r * sinf(phi));
                iir_vec3 I = iir_light_intensity(&l->scene->lights[k], w);
                iir_ray ray = iir_make_ray(l->scene->lights[k].position, w, 0.f, INFINITY);
                iir_hit hit;
                if (iir_is_black(I) || !iir_rt_intersect(l->rt, &ray, &hit, NULL, IIR_RAYS_BENCH))
                    continue;
                E = fmaxf(E, iir_max_comp(I) / (hit.t * hit.t));
            }
    return rho * IIR_INV_PI * E;
}

static void test_adaptive_depth(void **state)
{
    (void)state;
    loaded l = load_path(IIR_SOURCE_DIR "/scenes/cornell_spheres");
    enum { W = 96, H = 96 };
    const float min_weight = 0.05f;
    iir_params full = iir_params_default(), cut = iir_params_default();
    iir_test_set(&full, "min_weight", 0);
    iir_test_set(&cut, "min_weight", min_weight);
    iir_frame_stats fs_full, fs_cut;
    iir_image *a = render(&l, "whitted", &full, W, H, &fs_full);
    iir_image *b = render(&l, "whitted", &cut, W, H, &fs_cut);
    float L_max = scene_max_radiance(&l), diff_max = 0.f;
    for (int i = 0; i < W * H; i++) assert_true(iir_max_comp(a->pixels[i]) <= L_max);
    for (int i = 0; i < W * H; i++) {
        iir_vec3 d = iir_sub(a->pixels[i], b->pixels[i]);
        diff_max = fmaxf(diff_max, fmaxf(fabsf(d.x), fmaxf(fabsf(d.y), fabsf(d.z))));
    }
    uint64_t rays_full = iir_raystats_total(&fs_full.rays),
             rays_cut = iir_raystats_total(&fs_cut.rays);
    print_message(
        "adaptive depth (min_weight %.2f): max pixel change %.5f of bound %.5f; rays %llu "
        "-> %llu (%.1f%% saved), %llu branches cut\n",
        min_weight, diff_max, min_weight * L_max, (unsigned long long)rays_full,
        (unsigned long long)rays_cut, 100.0 * (double)(rays_full - rays_cut) / rays_full,
        (unsigned long long)fs_cut.counter[BRANCHES_CUT]);
    assert_true(L_max > 0.f && diff_max > 0.f);
    assert_true(diff_max < min_weight * L_max);
    assert_int_equal(fs_full.counter[BRANCHES_CUT], 0);
    assert_true(fs_cut.counter[BRANCHES_CUT] > 0);
    assert_true(rays_cut < rays_full);
    assert_true(rays_full - rays_cut >=
                fs_cut.counter[BRANCHES_CUT]); /* each cut saves its own ray */
    iir_image_destroy(a);
    iir_image_destroy(b);
    iir_test_unload(&l);
}

/* Deterministic: the same frame twice. */
static void test_deterministic(void **state)
{
    (void)state;
    loaded l = load_path(IIR_SOURCE_DIR "/scenes/cornell_spheres");
    iir_params p = iir_params_default();
    iir_frame_stats fs;
    iir_image *a = render(&l, "whitted", &p, 48, 40, &fs);
    iir_image *b = render(&l, "whitted", &p, 48, 40, &fs);
    assert_memory_equal(a->pixels, b->pixels, sizeof(iir_vec3) * 48 * 40);
    iir_image_destroy(a);
    iir_image_destroy(b);
    iir_test_unload(&l);
}

/* ---- pt through a glass slab ---- */

/* pt at normal incidence through a glass pane (n = 1.5, 0.2 thick) in front of an emitter of
 * radiance 1: every pixel (a 1 degree view) sees T = (1 - R)^2 / (1 - R^2), R = ((n-1)/(n+1))^2,
 * summing the light's internal reflections; and the same view of a mirror of 0.9 in front of the
 * emitter behind the camera sees 0.9. */
static void test_pt_glass_slab(void **state)
{
    (void)state;
    const char *dir = iir_test_tmpdir("pt-glass-slab");
    FILE *f = open_obj(dir, "pane",
                       "newmtl glass\nillum 5\nNi 1.5\nKd 0 0 0\n"
                       "newmtl lamp\nKd 0 0 0\nKe 1 1 1\n");
    write_box(f, "glass", iir_v3(0, 0, 0), iir_v3(3, 3, 0.1f));
    iir_test_write_quad(f, "lamp", iir_v3(0, 0, -2), iir_v3(10, 0, 0), iir_v3(0, 10, 0));
    fclose(f);
    write_sidecar(dir, "pane", iir_v3(0, 0, 5), iir_v3(0, 0, 0), 1.f);
    char path[1200];
    snprintf(path, sizeof path, "%s/pane.obj", dir);
    loaded l = load_path(path);
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", 1024);
    iir_test_set(&p, "bounces", 64);
    iir_frame_stats fs;
    iir_image *img = render(&l, "pt", &p, 8, 8, &fs);
    double R = iir_sqr(0.5f / 2.5f), T = (1 - R) * (1 - R) / (1 - R * R), mean = 0;
    for (int i = 0; i < 64; i++) mean += iir_luminance(img->pixels[i]) / 64;
    print_message("pt through glass: %.5f, expected (1-R)^2/(1-R^2) = %.5f\n", mean, T);
    assert_float_equal(mean, T, 0.005); /* 65536 samples of 0 or 1: sigma 0.001 */
    iir_image_destroy(img);
    /* whitted's full tree sums the same series */
    iir_test_set(&p, "min_weight", 0);
    iir_test_set(&p, "max_depth", 64);
    img = render(&l, "whitted", &p, 8, 8, &fs);
    for (int i = 0; i < 64; i++) assert_float_equal(iir_luminance(img->pixels[i]), T, 1e-3);
    iir_image_destroy(img);
    iir_test_unload(&l);
}

/* ---- the VPL methods' notes ---- */

static void test_vpl_methods_note_specular(void **state)
{
    (void)state;
    loaded l = load_path(IIR_SOURCE_DIR "/scenes/cornell_spheres");
    /* the VPL and map methods follow mirrors and glass (no caustics); radiosity renders them
       black */
    const char *methods[] = {"ir", "iir", "rsm", "ism", "hier", "radiosity"};
    const char *says[] = {"shows what it reflects", "shows what it reflects",
                          "shows what it reflects", "shows what it reflects",
                          "shows what it reflects", "black"};
    for (size_t k = 0; k < sizeof methods / sizeof methods[0]; k++) {
        iir_dropped d[32];
        uint32_t n =
            iir_method_dropped(methods[k], l.scene, l.scene->lights, l.scene->num_lights, d, 32);
        bool glass = false, mirror = false;
        for (uint32_t i = 0; i < n && i < 32; i++) {
            if (strcmp(d[i].method, methods[k]) != 0 || strstr(d[i].what, says[k]) == NULL)
                continue;
            glass |= strcmp(d[i].name, "glass") == 0;
            mirror |= strcmp(d[i].name, "mirror") == 0;
        }
        if (!glass || !mirror) fail_msg("%s: no note for the glass and the mirror", methods[k]);
    }
    iir_dropped d[32];
    uint32_t n =
        iir_method_dropped("whitted", l.scene, l.scene->lights, l.scene->num_lights, d, 32);
    for (uint32_t i = 0; i < n && i < 32; i++) assert_string_not_equal(d[i].method, "whitted");
    iir_test_unload(&l);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_snell_and_tir),
        cmocka_unit_test(test_energy_never_grows),
        cmocka_unit_test(test_mirror_shows_bounce_point),
        cmocka_unit_test(test_total_internal_reflection_rendered),
        cmocka_unit_test(test_adaptive_depth),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_pt_glass_slab),
        cmocka_unit_test(test_vpl_methods_note_specular),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

/* test_lights_pt.c -- the glTF spot and the sun against independent answers: pt's direct light on
 * a diffuse plane with an occluder against the analytic radiance (glTF spot: rho/pi I0 t^2 cos /
 * d^2, a bound the cosine lobe fails; sun: rho/pi E cos, shadows cast along parallel rays), and
 * one-bounce ir with exact visibility and many VPLs against pt --bounces 2 in the Cornell box, with
 * the bound test_methods uses. The glTF spot comes from a sidecar ("gltf_spot"), the sun is made
 * here and fitted to the scene (iir_light_fit_sun). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/light.h"
#include "iir/method.h"
#include "iir/render.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "testutil.h"

/* ---- the plane, its occluder and the analytic answer ---- */

static const float RHO = 0.5f;
static const iir_vec3 OCC_C = {0.45f, 0.5f, 0.3f}; /* occluder: a square at y = 0.5 */
static const float OCC_H = 0.15f;                  /* its half size */
static const iir_vec3 SPOT_P = {0.f, 1.f, 0.f};    /* the glTF spot, aimed straight down */
static const float OUTER = 40.f, INNER = 20.f;     /* degrees */

typedef iir_test_cornell loaded; /* a scene and its rays */

static bool in_occluder(iir_vec3 q)
{
    return fabsf(q.x - OCC_C.x) <= OCC_H && fabsf(q.z - OCC_C.z) <= OCC_H;
}

/* The plane y = 0 (20 x 20) and the occluder, grey, with a gltf_spot in the sidecar. */
static loaded load_plane(void)
{
    const char *dir = iir_test_tmpdir("lights-pt-plane");
    iir_test_write_file(dir, "plane.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
    char path[1200];
    snprintf(path, sizeof path, "%s/plane.obj", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "mtllib plane.mtl\n");
    iir_test_write_quad(f, "grey", iir_v3(0, 0, 0), iir_v3(0, 0, 10), iir_v3(10, 0, 0));
    iir_test_write_quad(f, "grey", OCC_C, iir_v3(0, 0, OCC_H), iir_v3(OCC_H, 0, 0));
    fclose(f);
    char json[1024];
    snprintf(json, sizeof json,
             "{\"camera\": {\"position\": [0, 2.5, 0], \"target\": [0, 0, 0], \"up\": [0, 0, -1],"
             " \"fov_y\": 90},"
             " \"lights\": [{\"type\": \"gltf_spot\", \"name\": \"g\", \"position\": [%g, %g, %g],"
             " \"direction\": [0, -1, 0], \"cone_angle\": %g, \"inner_angle\": %g,"
             " \"intensity\": 1}]}",
             (double)SPOT_P.x, (double)SPOT_P.y, (double)SPOT_P.z, (double)OUTER, (double)INNER);
    iir_test_write_file(dir, "plane.scene.json", json);
    return iir_test_load(dir, "plane");
}

/* glTF's t^2 in double precision, from the specification. */
static double gltf_t2(double cos_theta)
{
    double co = cos(OUTER * IIR_PI / 180), ci = cos(INNER * IIR_PI / 180);
    double t = (cos_theta - co) / fmax(1e-3, ci - co);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return t * t;
}

/* The first surface a camera ray meets: the occluder's top or the plane (both face +y). */
static iir_vec3 first_hit(iir_vec3 o, iir_vec3 d)
{
    iir_vec3 q = iir_madd(o, d, (OCC_C.y - o.y) / d.y);
    return in_occluder(q) ? q : iir_madd(o, d, -o.y / d.y);
}

/* Whether the segment from p (on the plane) along wi for length t_max passes the occluder. */
static bool shadowed(iir_vec3 p, iir_vec3 wi, double t_max)
{
    if (p.y >= OCC_C.y - 1e-6f || wi.y <= 0.f) return false;
    double t = (OCC_C.y - p.y) / wi.y;
    return t < t_max && in_occluder(iir_madd(p, wi, (float)t));
}

/* Radiance at p: `lobe` false for glTF's profile, true for a cosine lobe on top of it (what a
 * wrong profile gives; the test must tell them apart). */
static double spot_radiance(iir_vec3 p, bool lobe)
{
    iir_vec3 d = iir_sub(SPOT_P, p);
    double dist = iir_length(d), cos_t = d.y / dist; /* at the light and at the surface */
    if (cos_t <= 0 || shadowed(p, iir_scale(d, (float)(1 / dist)), dist)) return 0;
    return RHO / IIR_PI * gltf_t2(cos_t) * (lobe ? cos_t : 1.0) * cos_t / (dist * dist);
}

static double sun_radiance(iir_vec3 p, iir_vec3 wi, double E)
{
    return wi.y <= 0.f || shadowed(p, wi, INFINITY) ? 0 : RHO / IIR_PI * E * wi.y;
}

typedef struct pixel_stat {
    double mean, var;
} pixel_stat;

/* Mean and variance of the radiance over pixel (x, y) (pt box-filters with jittered samples), on
 * SUB x SUB sub-pixels; kind 0 = glTF spot, 1 = the spot with a cosine lobe, 2 = sun. */
static pixel_stat pixel_radiance(const iir_camera_frame *cf, int x, int y, int kind, iir_vec3 wi,
                                 double E)
{
    enum { SUB = 32 };
    double s = 0, s2 = 0;
    for (int j = 0; j < SUB; j++)
        for (int i = 0; i < SUB; i++) {
            iir_vec3 d = iir_camera_dir(cf, x + (i + 0.5f) / SUB, y + (j + 0.5f) / SUB);
            iir_vec3 p = first_hit(cf->origin, d);
            double L = kind == 2 ? sun_radiance(p, wi, E) : spot_radiance(p, kind == 1);
            s += L, s2 += L * L;
        }
    pixel_stat st = {s / (SUB * SUB), 0};
    st.var = fmax(0.0, s2 / (SUB * SUB) - st.mean * st.mean);
    return st;
}

static iir_image *render(const char *method, const iir_scene *scene, const iir_rt *rt,
                         const iir_light *lights, uint32_t n, int w, int h, iir_params *p)
{
    iir_method *m = NULL;
    iir_error err = {0};
    iir_image *img = iir_image_create(w, h);
    iir_frame_stats fs;
    iir_view view = {lights, n, scene->camera};
    if (iir_method_create(method, scene, rt, p, &m, &err) != IIR_OK) fail_msg("%s", err.msg);
    if (iir_method_render(m, &view, img, &fs, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_method_destroy(m);
    return img;
}

enum { W = 64, H = 64, SPP = 256 };

/* pt at SPP jittered samples per pixel estimates the pixel's mean with standard deviation
 * sqrt(var / SPP) (a delta light: no other noise); the bound is 5 of those plus 0.5% of the
 * brightest pixel (the sub-pixel rule's own error at edges). Returns the pixels over it. */
static int count_bad(const iir_image *img, const iir_camera_frame *cf, int kind, iir_vec3 wi,
                     double E, double L_max, bool report)
{
    int bad = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            pixel_stat ps = pixel_radiance(cf, x, y, kind, wi, E);
            double got = img->pixels[y * W + x].y;
            double tol = 0.005 * L_max + 5 * sqrt(ps.var / SPP);
            if (fabs(got - ps.mean) <= tol) continue;
            if (report && bad < 5)
                print_message("pixel (%d,%d): %.6f, expected %.6f (tol %.2e)\n", x, y, got, ps.mean,
                              tol);
            bad++;
        }
    return bad;
}

/* ---- pt against the analytic answers ---- */

static void test_gltf_spot_plane(void **state)
{
    (void)state;
    loaded l = load_plane();
    assert_int_equal(l.scene->num_lights, 1);
    const iir_light *g = &l.scene->lights[0];
    assert_int_equal(g->type, IIR_LIGHT_SPOT);
    assert_int_equal(g->profile, IIR_SPOT_GLTF);
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", SPP);
    iir_test_set(&p, "bounces", 1);
    iir_test_set(&p, "seed", 9);
    iir_image *img = render("pt", l.scene, l.rt, g, 1, W, H, &p);
    iir_camera_frame cf = iir_camera_setup(&l.scene->camera, W, H);
    double L_max = RHO / IIR_PI * 1.0 / (SPOT_P.y * SPOT_P.y);
    int bad = count_bad(img, &cf, 0, iir_v3s(0.f), 0, L_max, true);
    int bad_lobe = count_bad(img, &cf, 1, iir_v3s(0.f), 0, L_max, false);
    print_message("glTF spot over a plane: %d of %d pixels off glTF's profile, %d off a cosine "
                  "lobe\n",
                  bad, W * H, bad_lobe);
    assert_int_equal(bad, 0);
    assert_true(bad_lobe > 100); /* the bound tells the profiles apart */
    iir_image_destroy(img);
    iir_test_unload(&l);
}

static void test_sun_plane(void **state)
{
    (void)state;
    loaded l = load_plane();
    iir_light sun = {.type = IIR_LIGHT_SUN, .name = "sun", .up = {0, 1, 0}};
    sun.direction = iir_normalize(iir_v3(-0.8f, -1.f, 0.5f)); /* shadow beside the occluder */
    sun.intensity = iir_v3s(2.f);
    iir_light_fit_sun(&sun, l.scene);
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", SPP);
    iir_test_set(&p, "bounces", 1);
    iir_test_set(&p, "seed", 4);
    iir_image *img = render("pt", l.scene, l.rt, &sun, 1, W, H, &p);
    iir_camera_frame cf = iir_camera_setup(&l.scene->camera, W, H);
    iir_vec3 wi = iir_neg(sun.direction);
    double L_max = RHO / IIR_PI * 2.0 * wi.y;
    int bad = count_bad(img, &cf, 2, wi, 2.0, L_max, true);
    int dark = 0;
    for (int i = 0; i < W * H; i++) dark += img->pixels[i].y < 0.5 * L_max;
    print_message("sun over a plane: %d pixels off, %d in shadow\n", bad, dark);
    assert_int_equal(bad, 0);
    assert_true(dark > 8); /* the occluder's shadow is in view */
    iir_image_destroy(img);
    iir_test_unload(&l);
}

/* ---- the area light over a plane ---- */

static const iir_vec3 AREA_P = {0.2f, 0.6f, -0.1f}; /* its centre, facing down (-y) */
static const float AREA_W = 0.8f, AREA_H = 0.4f, AREA_L = 2.f, AREA_TURN = 30.f; /* degrees */

/* The area light's sides, from its up hint turned AREA_TURN degrees about -y (computed here, not
 * by iir_spot_frame): u = (sin, 0, cos), r = u x f with f = -y. */
static void area_sides(iir_vec3 *r, iir_vec3 *u)
{
    float a = iir_radians(AREA_TURN);
    *u = iir_v3(sinf(a), 0.f, cosf(a));
    *r = iir_cross(*u, iir_v3(0.f, -1.f, 0.f));
}

/* The bare plane y = 0 (20 x 20, grey), the camera 2.5 above it looking down through the area
 * light's back, and the area light from the sidecar (type "area"). */
static loaded load_bare_plane(void)
{
    const char *dir = iir_test_tmpdir("lights-pt-area");
    iir_test_write_file(dir, "bare.mtl", "newmtl grey\nKd 0.5 0.5 0.5\n");
    char path[1200];
    snprintf(path, sizeof path, "%s/bare.obj", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "mtllib bare.mtl\n");
    iir_test_write_quad(f, "grey", iir_v3(0, 0, 0), iir_v3(0, 0, 10), iir_v3(10, 0, 0));
    fclose(f);
    iir_vec3 r, u;
    area_sides(&r, &u);
    char json[1024];
    snprintf(json, sizeof json,
             "{\"camera\": {\"position\": [0, 2.5, 0], \"target\": [0, 0, 0], \"up\": [0, 0, -1],"
             " \"fov_y\": 90},"
             " \"lights\": [{\"type\": \"area\", \"name\": \"panel\", \"position\": [%g, %g, %g],"
             " \"direction\": [0, -1, 0], \"up\": [%.9g, 0, %.9g], \"size\": [%g, %g],"
             " \"intensity\": %g}]}",
             (double)AREA_P.x, (double)AREA_P.y, (double)AREA_P.z, (double)u.x, (double)u.z,
             (double)AREA_W, (double)AREA_H, (double)AREA_L);
    iir_test_write_file(dir, "bare.scene.json", json);
    return iir_test_load(dir, "bare");
}

/* The form factor from a point to a parallel rectangle [0, a] x [0, b] (a, b signed) at height c
 * whose corner lies straight above it (the classic closed form); odd in a and in b, so four
 * signed corners give any rectangle of the plane. */
static double corner_form_factor(double a, double b, double c)
{
    double A = a / c, B = b / c, sa = sqrt(1 + A * A), sb = sqrt(1 + B * B);
    return (A / sa * atan(B / sa) + B / sb * atan(A / sb)) / (2 * M_PI);
}

/* rho / pi E at point p of the plane y = 0: E = pi L F from the rectangle above it, or (far) the
 * far-field lobe L w h cos^2 / d^2 from its centre, what a light treated as a point would give. */
static double area_radiance(iir_vec3 p, bool far)
{
    iir_vec3 r, u;
    area_sides(&r, &u);
    iir_vec3 d = iir_sub(p, AREA_P);
    double x = iir_dot(d, r), y = iir_dot(d, u), c = AREA_P.y - p.y, d2 = x * x + y * y + c * c;
    if (far) return RHO / IIR_PI * AREA_L * AREA_W * AREA_H * c * c / (d2 * d2);
    double x0 = -0.5 * AREA_W - x, x1 = 0.5 * AREA_W - x, y0 = -0.5 * AREA_H - y,
           y1 = 0.5 * AREA_H - y;
    double F = corner_form_factor(x1, y1, c) - corner_form_factor(x0, y1, c) -
               corner_form_factor(x1, y0, c) + corner_form_factor(x0, y0, c);
    return RHO / IIR_PI * M_PI * AREA_L * F;
}

/* The mean of area_radiance over pixel (x, y) on SUB x SUB sub-pixels (pt box-filters). */
static double area_pixel(const iir_camera_frame *cf, int x, int y, bool far)
{
    enum { SUB = 8 };
    double s = 0;
    for (int j = 0; j < SUB; j++)
        for (int i = 0; i < SUB; i++) {
            iir_vec3 d = iir_camera_dir(cf, x + (i + 0.5f) / SUB, y + (j + 0.5f) / SUB);
            s += area_radiance(iir_madd(cf->origin, d, -cf->origin.y / d.y), far);
        }
    return s / (SUB * SUB);
}

enum { BLOCK = 4 }; /* pixels compared as BLOCK x BLOCK means */

/* Blocks of img whose mean is off the answer's by more than 3% plus 0.1% of the brightest
 * pixel; worst is the largest error as a fraction of that bound. */
static int count_bad_blocks(const iir_image *img, const iir_camera_frame *cf, bool far,
                            double L_max, bool report, double *worst)
{
    int bad = 0;
    *worst = 0;
    for (int by = 0; by < H; by += BLOCK)
        for (int bx = 0; bx < W; bx += BLOCK) {
            double got = 0, want = 0;
            for (int y = by; y < by + BLOCK; y++)
                for (int x = bx; x < bx + BLOCK; x++) {
                    got += img->pixels[y * W + x].y / (BLOCK * BLOCK);
                    want += area_pixel(cf, x, y, far) / (BLOCK * BLOCK);
                }
            double err = fabs(got - want) / (0.03 * want + 0.001 * L_max);
            *worst = fmax(*worst, err);
            if (err > 1.0 && report && bad < 5)
                print_message("block at (%d,%d): %.6f, expected %.6f\n", bx, by, got, want);
            bad += err > 1.0;
        }
    return bad;
}

/* pt's direct light from the area light on the plane against the form factor. The camera looks
 * at the light's back, which neither shows nor hides anything. Light samples of a pixel a metre
 * beside the light vary by a factor 10 (d^4), so single pixels at 256 spp are 5% noisy: the test
 * compares 4 x 4 blocks (3%: about 4 standard deviations) and the whole image's mean (0.5%); the
 * far-field lobe of a point at the centre fails the same bound. */
static void test_area_light_plane(void **state)
{
    (void)state;
    loaded l = load_bare_plane();
    assert_int_equal(l.scene->num_lights, 1);
    const iir_light *a = &l.scene->lights[0];
    assert_int_equal(a->type, IIR_LIGHT_AREA);
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", SPP);
    iir_test_set(&p, "bounces", 1);
    iir_test_set(&p, "seed", 12);
    iir_image *img = render("pt", l.scene, l.rt, a, 1, W, H, &p);
    iir_camera_frame cf = iir_camera_setup(&l.scene->camera, W, H);
    double L_max = area_radiance(iir_v3(AREA_P.x, 0.f, AREA_P.z), false), worst, worst_far;
    int bad = count_bad_blocks(img, &cf, false, L_max, true, &worst);
    int bad_far = count_bad_blocks(img, &cf, true, L_max, false, &worst_far);
    double sum = 0, sum_ref = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            sum += img->pixels[y * W + x].y, sum_ref += area_pixel(&cf, x, y, false);
    print_message("area light over a plane: %d of %d blocks off (worst at %.2f of the bound), %d "
                  "off the far field; mean %.6f vs %.6f\n",
                  bad, W * H / (BLOCK * BLOCK), worst, bad_far, sum / (W * H), sum_ref / (W * H));
    assert_int_equal(bad, 0);
    assert_true(bad_far > 20);
    assert_true(fabs(sum - sum_ref) < 0.005 * sum_ref);
    iir_image_destroy(img);
    iir_test_unload(&l);
}

/* Whether the camera ray o + t d meets the area light from its front (below), by the test's own
 * geometry. */
static bool sees_area(iir_vec3 o, iir_vec3 d)
{
    if (d.y <= 0.f) return false;
    iir_vec3 r, u;
    area_sides(&r, &u);
    iir_vec3 q = iir_sub(iir_madd(o, d, (AREA_P.y - o.y) / d.y), AREA_P);
    return fabsf(iir_dot(q, r)) <= 0.5f * AREA_W && fabsf(iir_dot(q, u)) <= 0.5f * AREA_H;
}

/* Renders the direct-light frame of `light` with renderer r (pixel centres). */
static void direct_frame(iir_renderer *r, const iir_camera *cam, const iir_light *light,
                         iir_image *out, iir_render_timing *t)
{
    iir_indirect_params ind = iir_indirect_params_default();
    iir_error err = {0};
    iir_render_input in = {cam, light, 1, NULL, 0, 3, NULL};
    if (iir_renderer_frame(r, &in, &ind, out, t, NULL, &err) != IIR_OK) fail_msg("%s", err.msg);
}

/* Pixels whose centre ray sees the light's front show L, others nothing (nothing else is in
 * view), in pt and in the direct-light frame alike; after the light moves the frame shows it at
 * its new place from the same (cached) G-buffer. */
static void test_area_light_seen(void **state)
{
    (void)state;
    loaded l = load_bare_plane();
    iir_light a = l.scene->lights[0];
    iir_camera cam = {iir_v3(0.2f, 0.05f, -0.1f), iir_v3(0.2f, 1.f, -0.1f), iir_v3(0, 0, -1), 90.f};
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", 4);
    iir_test_set(&p, "bounces", 2);
    iir_test_set(&p, "jitter", 0);
    iir_method *m = NULL;
    iir_error err = {0};
    iir_image *img = iir_image_create(W, H), *direct = iir_image_create(W, H);
    iir_frame_stats fs;
    iir_view view = {&a, 1, cam};
    if (iir_method_create("pt", l.scene, l.rt, &p, &m, &err) != IIR_OK) fail_msg("%s", err.msg);
    if (iir_method_render(m, &view, img, &fs, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_renderer *r = iir_renderer_create(l.scene, l.rt);
    iir_render_timing t;
    direct_frame(r, &cam, &a, direct, &t);
    iir_camera_frame cf = iir_camera_setup(&cam, W, H);
    int lit = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            bool seen = sees_area(cf.origin, iir_camera_dir(&cf, x + 0.5f, y + 0.5f));
            float want = seen ? AREA_L : 0.f;
            assert_float_equal(img->pixels[y * W + x].y, want, 1e-5f);
            assert_float_equal(direct->pixels[y * W + x].y, want, 1e-5f);
            lit += seen;
        }
    print_message("area light seen from below: %d of %d pixels show L\n", lit, W * H);
    assert_true(lit > W * H / 8 && lit < W * H / 2);

    /* moved 0.3 along x: the G-buffer is kept, the light is drawn where it now is */
    a.position.x += 0.3f;
    direct_frame(r, &cam, &a, direct, &t);
    assert_true(t.gbuffer_cached);
    int moved = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            iir_vec3 d = iir_camera_dir(&cf, x + 0.5f, y + 0.5f);
            bool seen = sees_area(iir_madd(cf.origin, iir_v3(1, 0, 0), -0.3f), d);
            assert_float_equal(direct->pixels[y * W + x].y, seen ? AREA_L : 0.f, 1e-5f);
            moved += seen != sees_area(cf.origin, d);
        }
    assert_true(moved > 50);
    iir_renderer_destroy(r);
    iir_method_destroy(m);
    iir_image_destroy(img);
    iir_image_destroy(direct);
    iir_test_unload(&l);
}

/* ---- the disc lamp: a shaped area light against its own emissive triangles ---- */

static const iir_vec3 DISC_P = {0.2f, 0.6f, -0.1f}; /* its centre, facing down (-y) */
static const float DISC_R = 0.3f;                   /* its corners' radius */
enum { DISC_SIDES = 32, DISC_SPP = 1024 };

/* The bare plane y = 0 and a disc lamp of DISC_SIDES triangles (material "disc", Kd 0, Ke 2),
 * seen from the side (the region under the lamp in view); the sidecar's "lights" is `lights`. */
static loaded load_disc(const char *lights)
{
    const char *dir = iir_test_tmpdir("lights-pt-disc");
    iir_test_write_file(dir, "disc.mtl",
                        "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl disc\nKd 0 0 0\nKe 2 2 2\n");
    char path[1200];
    snprintf(path, sizeof path, "%s/disc.obj", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "mtllib disc.mtl\n");
    iir_test_write_quad(f, "grey", iir_v3(0, 0, 0), iir_v3(0, 0, 10), iir_v3(10, 0, 0));
    iir_test_write_disc(f, "disc", DISC_P, iir_v3(DISC_R, 0, 0), iir_v3(0, 0, DISC_R), DISC_SIDES);
    fclose(f);
    char json[1024];
    snprintf(json, sizeof json,
             "{\"camera\": {\"position\": [-1.2, 1.5, 1.2], \"target\": [0.4, 0, -0.4],"
             " \"up\": [0, 1, 0], \"fov_y\": 70}, \"lights\": %s}",
             lights);
    iir_test_write_file(dir, "disc.scene.json", json);
    return iir_test_load(dir, "disc");
}

/* Whether pixel (x, y) may see the lamp itself (its ray crosses the lamp's plane within 1.2 R of
 * its centre, before the floor): the triangles hide the floor behind them, the light does not. */
static bool near_disc(const iir_camera_frame *cf, int x, int y)
{
    iir_vec3 d = iir_camera_dir(cf, x + 0.5f, y + 0.5f);
    if (!(d.y < 0.f)) return false;
    iir_vec3 p = iir_madd(cf->origin, d, (DISC_P.y - cf->origin.y) / d.y);
    return iir_length(iir_sub(p, DISC_P)) < 1.2f * DISC_R;
}

/* pt's direct light from the disc as a shaped area light (sampled uniformly on its 32-gon, hit by
 * the plane-then-shape test, pdf by the shape's area) against pt's from the same 32 triangles as
 * emissive triangles of the geometry (the light set's per-triangle sampling and the BVH's hits):
 * two independent paths to one answer. 4 x 4 blocks off the lamp agree within 4% (each image's
 * block is about 0.6% noisy at 1024 spp: over 4 standard deviations of the difference) plus 0.1%
 * of the brightest block, the image means within 0.5%. */
static void test_disc_light_against_triangles(void **state)
{
    (void)state;
    loaded a = load_disc("[{\"type\": \"area\", \"name\": \"disc\", \"material\": \"disc\"}]");
    assert_int_equal(a.scene->num_lights, 1);
    assert_int_equal(a.scene->lights[0].shape.num_triangles, DISC_SIDES);
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", DISC_SPP);
    iir_test_set(&p, "bounces", 1);
    iir_test_set(&p, "seed", 3);
    iir_image *img_a = render("pt", a.scene, a.rt, a.scene->lights, 1, W, H, &p);
    iir_camera_frame cf = iir_camera_setup(&a.scene->camera, W, H);
    iir_test_unload(&a);
    loaded b = load_disc("[]");
    assert_int_equal(b.scene->num_lights, 0);
    iir_test_set(&p, "seed", 4);
    iir_image *img_b = render("pt", b.scene, b.rt, NULL, 0, W, H, &p);
    iir_test_unload(&b);
    double blocks[W * H / (BLOCK * BLOCK)][2], top = 0, sum_a = 0, sum_b = 0;
    int n = 0, bad = 0, skipped = 0;
    for (int by = 0; by < H; by += BLOCK)
        for (int bx = 0; bx < W; bx += BLOCK) {
            double ga = 0, gb = 0;
            bool lamp = false;
            for (int y = by; y < by + BLOCK; y++)
                for (int x = bx; x < bx + BLOCK; x++) {
                    lamp |= near_disc(&cf, x, y);
                    ga += img_a->pixels[y * W + x].y / (BLOCK * BLOCK);
                    gb += img_b->pixels[y * W + x].y / (BLOCK * BLOCK);
                }
            if (lamp) {
                skipped++;
                continue;
            }
            blocks[n][0] = ga, blocks[n][1] = gb, n++;
            top = fmax(top, gb), sum_a += ga, sum_b += gb;
        }
    double worst = 0;
    for (int i = 0; i < n; i++) {
        double err = fabs(blocks[i][0] - blocks[i][1]) / (0.04 * blocks[i][1] + 0.001 * top);
        worst = fmax(worst, err);
        if (err > 1.0 && bad++ < 5)
            print_message("block %d: light %.6f, triangles %.6f\n", i, blocks[i][0], blocks[i][1]);
    }
    print_message("disc as light vs as triangles: %d of %d blocks off (worst at %.2f of the bound; "
                  "%d blocks see the lamp), means %.6f vs %.6f (%+.3f%%)\n",
                  bad, n, worst, skipped, sum_a / n, sum_b / n, 100 * (sum_a - sum_b) / sum_b);
    assert_true(n > W * H / (BLOCK * BLOCK) / 2);
    assert_int_equal(bad, 0);
    assert_true(fabs(sum_a - sum_b) < 0.005 * sum_b);
    iir_image_destroy(img_a);
    iir_image_destroy(img_b);
}

/* ---- ir against pt in the Cornell box ---- */

/* ir's frame and `passes` - 1 refinement passes (each with fresh paths and a fresh light sample
 * per pixel for an area light's direct light), averaged. */
static iir_image *render_ir(const iir_test_cornell *f, const iir_light *light, int w, int h,
                            iir_params *p, int passes)
{
    iir_method *m = NULL;
    iir_error err = {0};
    iir_image *img = iir_image_create(w, h);
    iir_frame_stats fs;
    iir_view view = {light, 1, f->scene->camera};
    if (iir_method_create("ir", f->scene, f->rt, p, &m, &err) != IIR_OK) fail_msg("%s", err.msg);
    if (iir_method_render(m, &view, img, &fs, &err) != IIR_OK) fail_msg("%s", err.msg);
    for (int i = 1; i < passes; i++)
        if (iir_method_refine(m, img, &fs, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_method_destroy(m);
    return img;
}

/* One-bounce ir (exact visibility, no clamping, 16k paths per pass) against pt --bounces 2 at 2048
 * spp, both through pixel centres (jitter off, so shadow edges fall on the same pixels): relMSE on
 * smooth pixels below 5e-3 and means within 2%, as test_methods.c's test_ir_converges_to_pt. */
static void check_ir_matches_pt(const iir_test_cornell *f, const iir_light *light, int passes)
{
    enum { CW = 40, CH = 40 };
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", 2048);
    iir_test_set(&p, "bounces", 2);
    iir_test_set(&p, "seed", 5);
    iir_test_set(&p, "jitter", 0);
    iir_image *ref = render("pt", f->scene, f->rt, light, 1, CW, CH, &p);
    iir_test_set(&p, "vpls", 16384);
    iir_test_set(&p, "visibility", 1);
    iir_test_set(&p, "clamp", 0.f);
    iir_test_set(&p, "interleave", 1);
    iir_test_set(&p, "area_samples", 64); /* area lights only: converged direct light */
    iir_image *img = render_ir(f, light, CW, CH, &p, passes);

    iir_renderer *r = iir_renderer_create(f->scene, f->rt);
    iir_indirect_params ind = iir_indirect_params_default();
    iir_render_timing t;
    iir_image *direct = iir_image_create(CW, CH);
    iir_error err = {0};
    iir_render_input in = {&f->scene->camera, light, 1, NULL, 0, 1, NULL};
    assert_int_equal(iir_renderer_frame(r, &in, &ind, direct, &t, NULL, &err), IIR_OK);
    const iir_gbuffer *gb = iir_renderer_gbuffer(r);
    double rel = 0, rel_direct = 0, sum_img = 0, sum_ref = 0;
    int n = 0;
    for (int y = 0; y < CH; y++)
        for (int x = 0; x < CW; x++) {
            if (!iir_test_smooth_pixel(gb, x, y)) continue;
            iir_vec3 a = *iir_image_at(img, x, y), b = *iir_image_at(ref, x, y);
            double la = iir_luminance(a), lb = iir_luminance(b);
            double ld = iir_luminance(*iir_image_at(direct, x, y));
            rel += iir_sqr((float)(la - lb)) / (lb * lb + 0.01);
            rel_direct += iir_sqr((float)(ld - lb)) / (lb * lb + 0.01);
            sum_img += la, sum_ref += lb;
            n++;
        }
    print_message("%s: ir vs pt relMSE %.2e on %d smooth pixels (direct only %.2e), means %.4f vs "
                  "%.4f\n",
                  iir_light_kind(light), rel / n, n, rel_direct / n, sum_img / n, sum_ref / n);
    assert_true(n > CW * CH / 2);
    assert_true(rel / n < 5e-3);
    assert_true(rel_direct / n > 2e-2); /* the bound can tell a missing bounce */
    assert_true(fabs(sum_img - sum_ref) < 0.02 * sum_ref);
    iir_renderer_destroy(r);
    iir_image_destroy(direct);
    iir_image_destroy(ref);
    iir_image_destroy(img);
}

static void test_ir_gltf_spot_cornell(void **state)
{
    const iir_test_cornell *f = *state;
    iir_light g = f->scene->lights[0]; /* the box's spot, under the ceiling, aimed down */
    snprintf(g.name, sizeof g.name, "gspot");
    g.profile = IIR_SPOT_GLTF;
    g.cone_angle = iir_radians(55.f);
    g.inner_angle = iir_radians(25.f);
    g.smooth = 0.f;
    iir_error err = {0};
    assert_int_equal(iir_light_validate(&g, &err), IIR_OK);
    check_ir_matches_pt(f, &g, 1);
}

/* A sun shining in through the box's open side (+z) onto the floor and the back wall. */
static void test_ir_sun_cornell(void **state)
{
    const iir_test_cornell *f = *state;
    iir_light sun = {.type = IIR_LIGHT_SUN, .name = "sun", .up = {0, 1, 0}};
    sun.direction = iir_normalize(iir_v3(-0.35f, -0.6f, -1.f));
    sun.intensity = iir_v3(6.f, 5.5f, 5.f);
    iir_light_fit_sun(&sun, f->scene);
    iir_error err = {0};
    assert_int_equal(iir_light_validate(&sun, &err), IIR_OK);
    check_ir_matches_pt(f, &sun, 1);
}

/* An area light the size of the box's ceiling panel just under it, facing down, seen by the camera
 * (its pixels show L in front of the ceiling). ir's direct light takes area_samples stratified
 * light samples per pixel: 64 here (check_ir_matches_pt) stand for the 8 refinement passes of one
 * sample each that this test once needed. */
static void test_ir_area_cornell(void **state)
{
    const iir_test_cornell *f = *state;
    iir_light a = {.type = IIR_LIGHT_AREA, .name = "panel", .up = {0, 0, -1}};
    a.position = iir_v3(-0.005f, 1.97f, -0.03f);
    a.direction = iir_v3(0.f, -1.f, 0.f);
    a.size = iir_v2(0.47f, 0.38f);
    a.intensity = iir_v3(17.f, 12.f, 4.f);
    iir_error err = {0};
    assert_int_equal(iir_light_validate(&a, &err), IIR_OK);
    check_ir_matches_pt(f, &a, 1);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gltf_spot_plane),
        cmocka_unit_test(test_sun_plane),
        cmocka_unit_test(test_area_light_plane),
        cmocka_unit_test(test_area_light_seen),
        cmocka_unit_test(test_disc_light_against_triangles),
        cmocka_unit_test_setup_teardown(test_ir_gltf_spot_cornell, iir_test_cornell_setup,
                                        iir_test_cornell_teardown),
        cmocka_unit_test_setup_teardown(test_ir_sun_cornell, iir_test_cornell_setup,
                                        iir_test_cornell_teardown),
        cmocka_unit_test_setup_teardown(test_ir_area_cornell, iir_test_cornell_setup,
                                        iir_test_cornell_teardown),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

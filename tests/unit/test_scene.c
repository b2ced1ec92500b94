/* test_scene.c -- scenes: the built-in Cornell box and its shipped twin, OBJ/MTL and glTF loading
 * (materials, KHR_lights_punctual spot, point and directional lights, cameras), the JSON sidecar
 * (its spot, gltf_spot, point, sun and area lights, an area light taken from a material's
 * rectangle), degenerate triangles, resolving names, the camera frame, and every refusal (each
 * must name the file and the problem). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#include "iir/camera.h"
#include "iir/light.h"
#include "iir/scene.h"
#include "testutil.h"

/* ======================== helpers ======================== */

static char tmp[512]; /* this executable's scratch folder */

/* Writes dir/name and copies the full path into out. */
static void write_file(const char *name, const char *text, char *out, size_t n)
{
    const char *p = iir_test_write_file(tmp, name, text);
    assert_non_null(p);
    snprintf(out, n, "%s", p);
}

static void assert_contains(const char *msg, const char *needle)
{
    if (!strstr(msg, needle)) {
        print_message("message \"%s\" lacks \"%s\"\n", msg, needle);
        fail();
    }
}

/* Loading must fail with a message that contains both needles. */
static void assert_load_fails(const char *path, const char *needle1, const char *needle2)
{
    iir_scene *s = (iir_scene *)1;
    iir_error err = {0};
    iir_status st = iir_scene_load(path, &s, &err);
    if (st == IIR_OK) print_message("%s loaded, expected a failure\n", path);
    assert_int_not_equal(st, IIR_OK);
    assert_null(s);
    assert_int_equal(err.status, st);
    assert_contains(err.msg, needle1);
    if (needle2) assert_contains(err.msg, needle2);
}

static iir_scene *load_ok(const char *path)
{
    iir_scene *s = NULL;
    iir_error err = {0};
    iir_status st = iir_scene_load(path, &s, &err);
    if (st != IIR_OK) print_message("loading %s failed: %s\n", path, err.msg);
    assert_int_equal(st, IIR_OK);
    assert_non_null(s);
    return s;
}

static bool near(float a, float b, float tol)
{
    return fabsf(a - b) <= tol;
}

static void assert_vec_near(iir_vec3 a, iir_vec3 b, float tol)
{
    if (!(near(a.x, b.x, tol) && near(a.y, b.y, tol) && near(a.z, b.z, tol))) {
        print_message("(%g, %g, %g) != (%g, %g, %g)\n", (double)a.x, (double)a.y, (double)a.z,
                      (double)b.x, (double)b.y, (double)b.z);
        fail();
    }
}

static const iir_material *find_material(const iir_scene *s, const char *name)
{
    for (uint32_t i = 0; i < s->num_materials; i++)
        if (strcmp(s->material_list[i].name, name) == 0) return &s->material_list[i];
    return NULL;
}

static float material_area(const iir_scene *s, const char *name)
{
    double sum = 0.0;
    for (uint32_t t = 0; t < s->num_triangles; t++)
        if (strcmp(s->material_list[s->materials[t]].name, name) == 0) sum += s->areas[t];
    return (float)sum;
}

/* Every triangle: valid indices, unit normal along the winding-order cross product, area > 0. */
static void assert_triangles_sane(const iir_scene *s)
{
    for (uint32_t t = 0; t < s->num_triangles; t++) {
        const uint32_t *ix = s->indices + 3 * t;
        assert_true(ix[0] < s->num_vertices && ix[1] < s->num_vertices && ix[2] < s->num_vertices);
        assert_true(s->materials[t] < s->num_materials);
        iir_vec3 p0 = s->positions[ix[0]], p1 = s->positions[ix[1]], p2 = s->positions[ix[2]];
        iir_vec3 c = iir_cross(iir_sub(p1, p0), iir_sub(p2, p0));
        assert_true(s->areas[t] > 0.f);
        assert_true(near(iir_length(s->normals[t]), 1.f, 1e-5f));
        assert_true(iir_dot(c, s->normals[t]) > 0.f);
    }
}

/* ======================== the built-in box ======================== */

static const float PANEL_FLUX_RED = IIR_PI * 17.f * 0.47f * 0.38f; /* pi Ke A, red channel */

static void test_cornell_builtin(void **state)
{
    (void)state;
    iir_scene *s = iir_scene_create_cornell_box();
    assert_non_null(s);
    assert_string_equal(s->name, "cornell_box");
    assert_string_equal(s->source, "");
    assert_int_equal(s->num_triangles, 32);
    assert_int_equal(s->num_materials, 8);
    assert_int_equal(s->skipped_degenerate, 0);
    assert_int_equal(s->skipped_duplicate, 0);
    assert_null(s->paths_json);
    assert_triangles_sane(s);

    /* the red left wall faces +x, into the room; the panel faces down and emits nothing */
    const iir_material *red = find_material(s, "leftWall");
    assert_non_null(red);
    assert_vec_near(red->albedo, iir_v3(0.63f, 0.065f, 0.05f), 1e-6f);
    assert_vec_near(find_material(s, "rightWall")->albedo, iir_v3(0.14f, 0.45f, 0.091f), 1e-6f);
    assert_vec_near(find_material(s, "light")->albedo, iir_v3s(0.78f), 1e-6f);
    for (uint32_t i = 0; i < s->num_materials; i++)
        assert_true(iir_is_black(s->material_list[i].emission));
    for (uint32_t t = 0; t < s->num_triangles; t++) {
        const char *m = s->material_list[s->materials[t]].name;
        if (strcmp(m, "leftWall") == 0) assert_true(s->normals[t].x > 0.99f);
        if (strcmp(m, "rightWall") == 0) assert_true(s->normals[t].x < -0.99f);
        if (strcmp(m, "light") == 0) assert_true(s->normals[t].y < -0.99f);
    }
    assert_true(near(material_area(s, "light"), 0.47f * 0.38f, 1e-4f));

    /* one spot under the ceiling, aimed down, with the panel's flux */
    assert_int_equal(s->num_lights, 1);
    const iir_light *l = &s->lights[0];
    iir_error err;
    assert_int_equal(iir_light_validate(l, &err), IIR_OK);
    assert_int_equal(l->type, IIR_LIGHT_SPOT);
    assert_string_equal(l->name, "spot");
    assert_vec_near(l->position, iir_v3(0.f, 1.9f, 0.f), 1e-6f);
    assert_vec_near(l->direction, iir_v3(0.f, -1.f, 0.f), 1e-6f);
    assert_true(near(iir_degrees(l->cone_angle), 60.f, 1e-4f));
    assert_true(l->smooth == 0.f);
    assert_true(near(iir_light_flux(l).x, PANEL_FLUX_RED, 1e-3f * PANEL_FLUX_RED));
    assert_true(near(l->intensity.y / l->intensity.x, 12.f / 17.f, 1e-6f));

    /* the classic camera; bounds of the OBJ */
    assert_int_equal(iir_camera_validate(&s->camera, &err), IIR_OK);
    assert_vec_near(s->camera.position, iir_v3(0.f, 1.f, 3.9f), 1e-6f);
    assert_vec_near(s->camera.target, iir_v3(0.f, 1.f, 0.f), 1e-6f);
    assert_true(near(s->camera.fov_y, 39.3f, 1e-5f));
    assert_vec_near(s->bounds_min, iir_v3(-1.02f, 0.f, -1.04f), 1e-6f);
    assert_vec_near(s->bounds_max, iir_v3(1.f, 1.99f, 0.99f), 1e-6f);

    char text[256];
    iir_scene_describe(s, text, sizeof text);
    assert_string_equal(
        text,
        "cornell_box: 32 triangles, 8 materials, 1 light, skipped 0 degenerate and 0 duplicate");
    iir_scene_destroy(s);
}

/* scenes/cornell_box (OBJ + sidecar) must be the built-in box. */
static void test_cornell_shipped_equals_builtin(void **state)
{
    (void)state;
    iir_scene *a = iir_scene_create_cornell_box();
    iir_scene *b = load_ok(IIR_SOURCE_DIR "/scenes/cornell_box");
    assert_string_equal(b->name, "cornell_box");
    assert_int_equal(b->num_triangles, a->num_triangles);
    assert_int_equal(b->num_materials, a->num_materials);
    assert_int_equal(b->skipped_degenerate, 0);
    /* the OBJ's two "bottom" box faces repeat a side face: 2 quads, 4 triangles */
    assert_int_equal(b->skipped_duplicate, 4);
    assert_triangles_sane(b);
    for (uint32_t i = 0; i < a->num_materials; i++) {
        const iir_material *ma = &a->material_list[i];
        const iir_material *mb = find_material(b, ma->name);
        assert_non_null(mb);
        assert_vec_near(mb->albedo, ma->albedo, 1e-6f);
        assert_vec_near(mb->emission, ma->emission, 0.f);
        assert_true(near(material_area(b, ma->name), material_area(a, ma->name), 1e-4f));
    }
    assert_vec_near(b->bounds_min, a->bounds_min, 1e-6f);
    assert_vec_near(b->bounds_max, a->bounds_max, 1e-6f);
    assert_int_equal(b->num_lights, 1);
    const iir_light *la = &a->lights[0], *lb = &b->lights[0];
    assert_string_equal(lb->name, la->name);
    assert_int_equal(lb->type, la->type);
    assert_vec_near(lb->position, la->position, 1e-6f);
    assert_vec_near(lb->direction, la->direction, 1e-6f);
    assert_vec_near(lb->up, la->up, 1e-6f);
    assert_true(near(lb->cone_angle, la->cone_angle, 1e-6f));
    assert_true(near(lb->smooth, la->smooth, 1e-6f));
    assert_vec_near(lb->intensity, la->intensity, 1e-5f);
    assert_vec_near(b->camera.position, a->camera.position, 1e-6f);
    assert_vec_near(b->camera.target, a->camera.target, 1e-6f);
    assert_vec_near(b->camera.up, a->camera.up, 1e-6f);
    assert_true(near(b->camera.fov_y, a->camera.fov_y, 1e-5f));
    iir_scene_destroy(a);
    iir_scene_destroy(b);
}

/* ======================== the camera ======================== */

static void test_camera(void **state)
{
    (void)state;
    iir_camera cam = {iir_v3(0, 1, 3.9f), iir_v3(0, 1, 0), iir_v3(0, 1, 0), 39.3f};
    iir_error err;
    assert_int_equal(iir_camera_validate(&cam, &err), IIR_OK);
    iir_camera_frame cf = iir_camera_setup(&cam, 640, 480);
    assert_vec_near(cf.basis.f, iir_v3(0, 0, -1), 1e-6f);
    assert_vec_near(cf.basis.r, iir_v3(1, 0, 0), 1e-6f); /* red wall (-x) on the left */
    assert_vec_near(cf.basis.u, iir_v3(0, 1, 0), 1e-6f);
    assert_true(near(cf.aspect, 4.f / 3.f, 1e-6f));
    assert_true(near(cf.tan_half_y, tanf(iir_radians(19.65f)), 1e-6f));
    assert_vec_near(iir_camera_dir(&cf, 320.f, 240.f), iir_v3(0, 0, -1), 1e-6f);
    /* the top edge of the image is fov_y / 2 above the axis */
    iir_vec3 top = iir_camera_dir(&cf, 320.f, 0.f);
    assert_true(near(iir_degrees(acosf(-top.z)), 19.65f, 1e-3f) && top.y > 0.f);

    iir_camera bad = cam;
    bad.target = bad.position;
    assert_int_equal(iir_camera_validate(&bad, &err), IIR_ERR_INVALID);
    assert_contains(err.msg, "target");
    bad = cam;
    bad.up = iir_v3(0, 0, -2);
    assert_int_equal(iir_camera_validate(&bad, &err), IIR_ERR_INVALID);
    assert_contains(err.msg, "parallel");
    bad = cam;
    bad.fov_y = 180.f;
    assert_int_equal(iir_camera_validate(&bad, &err), IIR_ERR_INVALID);
    assert_contains(err.msg, "fov");
    bad = cam;
    bad.position.x = NAN;
    assert_int_equal(iir_camera_validate(&bad, &err), IIR_ERR_INVALID);
    assert_contains(err.msg, "position");
}

/* ======================== OBJ/MTL ======================== */

static const char *const GLOW_MTL = "newmtl glow\nKd 0.5 0.6 0.7\nKe 1 2 3\n"
                                    "newmtl unused\nKd 1 1 1\n";

static void test_obj_emissive(void **state)
{
    (void)state;
    char path[1024];
    write_file("glow.mtl", GLOW_MTL, path, sizeof path);
    write_file("glow.obj",
               "mtllib glow.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nusemtl glow\nf 1 2 3 4\n",
               path, sizeof path);
    iir_scene *s = load_ok(path);
    assert_string_equal(s->name, "glow");
    assert_string_equal(s->source, path);
    assert_int_equal(s->num_triangles, 2);
    assert_int_equal(s->num_materials, 1); /* unused and default materials are dropped */
    assert_string_equal(s->material_list[0].name, "glow");
    assert_vec_near(s->material_list[0].albedo, iir_v3(0.5f, 0.6f, 0.7f), 1e-6f);
    assert_vec_near(s->material_list[0].emission, iir_v3(1.f, 2.f, 3.f), 1e-6f);
    assert_int_equal(s->num_lights, 0);
    assert_triangles_sane(s);
    assert_vec_near(s->normals[0], iir_v3(0, 0, 1), 1e-6f);
    iir_error err;
    assert_int_equal(iir_camera_validate(&s->camera, &err), IIR_OK); /* the default camera */
    iir_scene_destroy(s);
}

/* Albedo is clamped to [0, 1], negative emission to 0. */
static void test_obj_colours_clamped(void **state)
{
    (void)state;
    char path[1024];
    write_file("hot.mtl", "newmtl hot\nKd 1.5 -0.2 0.5\nKe -1 0 2\n", path, sizeof path);
    write_file("hot.obj", "mtllib hot.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl hot\nf 1 2 3\n", path,
               sizeof path);
    iir_scene *s = load_ok(path);
    assert_vec_near(s->material_list[0].albedo, iir_v3(1.f, 0.f, 0.5f), 0.f);
    assert_vec_near(s->material_list[0].emission, iir_v3(0.f, 0.f, 2.f), 0.f);
    iir_scene_destroy(s);
}

/* MTL illum 3 is a mirror of colour Ks; illum 5 and 7 are glass of index Ni (tinted by Tf); other
 * models with a highlight Ks are glTF's dielectric as Blender reads them (reflectance 0.08
 * mean(Ks), roughness 1 - sqrt(Ns / 1000): 1 without Ns), whatever their Ni says
 * (docs/scene-format.md). */
static void test_obj_specular_materials(void **state)
{
    (void)state;
    char path[1024];
    write_file("spec.mtl",
               "newmtl wall\nillum 2\nKd 0.5 0.5 0.5\nKs 1 1 1\nNi 1.5\n"
               "newmtl silver\nillum 3\nKd 0.2 0.2 0.2\nKs 0.9 0.8 0.7\n"
               "newmtl window\nillum 5\nNi 1.33\n"
               "newmtl bottle\nillum 7\nNi 1.7\nTf 0.9 1 0.8\nd 0.2\n",
               path, sizeof path);
    write_file("spec.obj",
               "mtllib spec.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nv 0 0 1\nv 1 0 1\n"
               "usemtl wall\nf 1 2 3\nusemtl silver\nf 2 4 3\nusemtl window\nf 1 5 2\n"
               "usemtl bottle\nf 2 5 6\n",
               path, sizeof path);
    iir_scene *s = load_ok(path);
    const iir_material *wall = find_material(s, "wall"), *silver = find_material(s, "silver");
    const iir_material *window = find_material(s, "window"), *bottle = find_material(s, "bottle");
    assert_int_equal(wall->kind, IIR_MATERIAL_METAL_ROUGH);
    assert_vec_near(wall->albedo, iir_v3s(0.5f), 1e-6f);
    assert_float_equal(wall->specular_f0, 0.08f, 1e-6);
    assert_float_equal(wall->roughness, 1.f, 1e-6);
    assert_float_equal(wall->metallic, 0.f, 0);
    assert_int_equal(silver->kind, IIR_MATERIAL_MIRROR);
    assert_vec_near(silver->specular, iir_v3(0.9f, 0.8f, 0.7f), 1e-6f);
    assert_vec_near(silver->albedo, iir_v3s(0.f), 0.f); /* no diffuse part */
    assert_int_equal(window->kind, IIR_MATERIAL_GLASS);
    assert_float_equal(window->ior, 1.33f, 1e-6);
    assert_vec_near(window->specular, iir_v3s(1.f), 0.f);
    assert_int_equal(bottle->kind, IIR_MATERIAL_GLASS);
    assert_float_equal(bottle->ior, 1.7f, 1e-6);
    assert_vec_near(bottle->specular, iir_v3(0.9f, 1.f, 0.8f), 1e-6f);
    for (uint32_t i = 0; i < s->num_dropped; i++) /* glass's "d" is not "transparency" */
        assert_string_not_equal(s->dropped[i].name, "bottle");
    assert_string_equal(iir_material_kind_name(IIR_MATERIAL_GLASS), "glass");
    iir_scene_destroy(s);
    write_file("badior.mtl", "newmtl dense\nillum 7\nNi 4.2\n", path, sizeof path);
    write_file("badior.obj",
               "mtllib badior.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl dense\nf 1 2 3\n", path,
               sizeof path);
    assert_load_fails(path, "material 'dense'", "ior 4.2 must be a finite number in [1, 3]");
}

/* The sidecar's "kind", "specular" and "ior", and clear errors for bad ones. */
static void test_sidecar_specular_materials(void **state)
{
    (void)state;
    char path[1024];
    write_file("side.mtl", "newmtl a\nKd 0.5 0.5 0.5\nnewmtl b\nKd 0.5 0.5 0.5\n", path,
               sizeof path);
    write_file("side.obj",
               "mtllib side.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl a\nf 1 2 3\n"
               "usemtl b\nf 2 4 3\n",
               path, sizeof path);
    write_file("side.scene.json",
               "{\"materials\": {\"a\": {\"kind\": \"mirror\", \"specular\": [0.9, 0.9, 0.8]},"
               " \"b\": {\"kind\": \"glass\", \"ior\": 1.33}}}",
               path, sizeof path);
    iir_scene *s = load_ok(path);
    const iir_material *a = find_material(s, "a"), *b = find_material(s, "b");
    assert_int_equal(a->kind, IIR_MATERIAL_MIRROR);
    assert_vec_near(a->specular, iir_v3(0.9f, 0.9f, 0.8f), 1e-6f);
    assert_vec_near(a->albedo, iir_v3s(0.f), 0.f);
    assert_int_equal(b->kind, IIR_MATERIAL_GLASS);
    assert_float_equal(b->ior, 1.33f, 1e-6);
    assert_vec_near(b->specular, iir_v3s(1.f), 0.f); /* clear unless tinted */
    iir_scene_destroy(s);
    static const struct {
        const char *json, *needle1, *needle2;
    } bad[] = {
        {"{\"materials\": {\"b\": {\"kind\": \"glass\", \"ior\": 3.5}}}", "materials.b.ior",
         "must be in [1, 3], got 3.5"},
        {"{\"materials\": {\"b\": {\"kind\": \"glass\", \"ior\": 0.5}}}", "materials.b.ior",
         "must be in [1, 3], got 0.5"},
        {"{\"materials\": {\"b\": {\"kind\": \"metal\"}}}", "materials.b.kind",
         "not a material kind"},
        {"{\"materials\": {\"a\": {\"kind\": \"mirror\", \"specular\": 1.2}}}",
         "materials.a.specular", "must be in [0, 1]"},
        {"{\"materials\": {\"a\": {\"kind\": \"mirror\", \"ior\": 1.5}}}", "materials.a.ior",
         "a mirror has no ior"},
        {"{\"materials\": {\"a\": {\"kind\": \"mirror\", \"albedo\": 0.5}}}", "materials.a",
         "has no diffuse albedo"},
        {"{\"materials\": {\"a\": {\"ior\": 1.5}}}", "materials.a",
         "ior is only for a mirror or glass"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        write_file("side.scene.json", bad[i].json, path, sizeof path);
        assert_load_fails(path, bad[i].needle1, bad[i].needle2);
    }
}

static void test_degenerate_triangles(void **state)
{
    (void)state;
    char path[1024];
    /* two good triangles, one with a repeated vertex, one collinear, one with two vertices at
     * the same position */
    write_file("degen.obj",
               "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 2 0 0\nv 0 0 0\n"
               "f 1 2 3\nf 1 3 4\nf 1 1 2\nf 1 2 5\nf 1 6 3\n",
               path, sizeof path);
    iir_scene *s = load_ok(path);
    assert_int_equal(s->num_triangles, 2);
    assert_int_equal(s->skipped_degenerate, 3);
    assert_triangles_sane(s);
    assert_vec_near(s->bounds_min, iir_v3(0, 0, 0), 0.f);
    assert_vec_near(s->bounds_max, iir_v3(1, 1, 0), 0.f); /* (2, 0, 0) only in a dropped one */
    char text[256];
    iir_scene_describe(s, text, sizeof text);
    assert_string_equal(
        text, "degen: 2 triangles, 1 material, 0 lights, skipped 3 degenerate and 0 duplicate");
    iir_scene_destroy(s);

    /* the same triangle again, reversed and from other vertex indices, is a duplicate; a triangle
     * sharing two of its vertices is not */
    write_file("dup.obj",
               "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 0\nv 0 0 0\nv 1 1 0\n"
               "f 1 2 3\nf 3 5 4\nf 2 3 6\nf 2 6 3\n",
               path, sizeof path);
    s = load_ok(path);
    assert_int_equal(s->num_triangles, 2);
    assert_int_equal(s->skipped_duplicate, 2);
    assert_int_equal(s->skipped_degenerate, 0);
    assert_triangles_sane(s);
    iir_scene_destroy(s);

    write_file("alldegen.obj", "v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\nf 1 1 2\n", path, sizeof path);
    assert_load_fails(path, "alldegen.obj", "degenerate");
}

/* ======================== glTF 2.0 ======================== */

/* A 2x2 floor quad (facing +y, material "glow": base colour and emissive factor), a spot light
 * on a rotated node under a translated parent (world position (1, 2, 0), aimed down, inner 0.4
 * and outer 0.6 rad), a point light, a directional light on a node turned -45 degrees about x
 * (shining along (0, -1, -1) / sqrt 2), and a camera at (0, 1, 5) looking down -z with yfov
 * 0.8 rad and aspect 1.5. */
static const char *const GLTF =
    "{\"asset\": {\"version\": \"2.0\"},\n"
    " \"extensionsUsed\": [\"KHR_lights_punctual\"],\n"
    " \"extensions\": {\"KHR_lights_punctual\": {\"lights\": [\n"
    "   {\"type\": \"spot\", \"name\": \"key\", \"color\": [1, 0.5, 0.25], \"intensity\": 6830,\n"
    "    \"spot\": {\"innerConeAngle\": 0.4, \"outerConeAngle\": 0.6}},\n"
    "   {\"type\": \"point\", \"name\": \"fill\", \"color\": [1, 1, 1], \"intensity\": 1366},\n"
    "   {\"type\": \"directional\", \"name\": \"sky\", \"color\": [1, 0.9, 0.8], \"intensity\": "
    "2049}]}},\n"
    " \"scene\": 0, \"scenes\": [{\"nodes\": [0, 1, 3, 4, 5]}],\n"
    " \"nodes\": [\n"
    "   {\"mesh\": 0, \"name\": \"floor\"},\n"
    "   {\"name\": \"rig\", \"translation\": [1, 0, 0], \"children\": [2]},\n"
    "   {\"name\": \"keynode\", \"translation\": [0, 2, 0],\n"
    "    \"rotation\": [-0.70710678, 0, 0, 0.70710678],\n"
    "    \"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}},\n"
    "   {\"name\": \"cam\", \"translation\": [0, 1, 5], \"camera\": 0},\n"
    "   {\"name\": \"fillnode\", \"translation\": [0, 1.5, 0.5],\n"
    "    \"extensions\": {\"KHR_lights_punctual\": {\"light\": 1}}},\n"
    "   {\"name\": \"sunnode\", \"translation\": [5, 5, 5],\n"
    "    \"rotation\": [-0.38268343, 0, 0, 0.92387953],\n"
    "    \"extensions\": {\"KHR_lights_punctual\": {\"light\": 2}}}],\n"
    " \"cameras\": [{\"type\": \"perspective\",\n"
    "   \"perspective\": {\"yfov\": 0.8, \"aspectRatio\": 1.5, \"znear\": 0.1}}],\n"
    " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1,\n"
    "   \"material\": 0}]}],\n"
    " \"materials\": [{\"name\": \"glow\",\n"
    "   \"pbrMetallicRoughness\": {\"baseColorFactor\": [0.8, 0.2, 0.1, 1]},\n"
    "   \"emissiveFactor\": [1, 2, 3]}],\n" IIR_TEST_GLTF_QUAD_DATA;

static const iir_light *find_light(const iir_scene *s, const char *name)
{
    for (uint32_t i = 0; i < s->num_lights; i++)
        if (strcmp(s->lights[i].name, name) == 0) return &s->lights[i];
    return NULL;
}

static void test_gltf_lights_and_camera(void **state)
{
    (void)state;
    char path[1024];
    write_file("lit.gltf", GLTF, path, sizeof path);
    iir_scene *s = load_ok(path);
    assert_int_equal(s->num_triangles, 2);
    assert_triangles_sane(s);
    assert_vec_near(s->normals[0], iir_v3(0, 1, 0), 1e-6f);
    assert_int_equal(s->num_materials, 1);
    assert_vec_near(s->material_list[0].albedo, iir_v3(0.8f, 0.2f, 0.1f), 1e-6f);
    assert_vec_near(s->material_list[0].emission, iir_v3(1.f, 2.f, 3.f), 1e-6f);

    assert_int_equal(s->num_lights, 3);
    const iir_light *spot = find_light(s, "keynode"), *point = find_light(s, "fillnode");
    assert_non_null(spot);
    assert_non_null(point);
    iir_error err;
    assert_int_equal(iir_light_validate(spot, &err), IIR_OK);
    assert_int_equal(spot->type, IIR_LIGHT_SPOT);
    assert_vec_near(spot->position, iir_v3(1.f, 2.f, 0.f), 1e-5f);
    assert_vec_near(spot->direction, iir_v3(0.f, -1.f, 0.f), 1e-5f);
    assert_int_equal(spot->profile, IIR_SPOT_GLTF); /* glTF's own profile, no cosine lobe */
    assert_true(near(spot->cone_angle, 0.6f, 1e-6f));
    assert_true(near(spot->inner_angle, 0.4f, 1e-6f));
    assert_true(spot->smooth == 0.f);
    /* KHR_lights_punctual's candela (lux for the sun) at 683 lm/W: the file's 6830 cd is 10 W/sr */
    assert_vec_near(spot->intensity, iir_v3(10.f, 5.f, 2.5f), 1e-5f);
    assert_int_equal(point->type, IIR_LIGHT_POINT);
    assert_vec_near(point->position, iir_v3(0.f, 1.5f, 0.5f), 1e-6f);
    assert_vec_near(point->intensity, iir_v3s(2.f), 1e-6f);

    assert_int_equal(iir_camera_validate(&s->camera, &err), IIR_OK);
    assert_vec_near(s->camera.position, iir_v3(0.f, 1.f, 5.f), 1e-5f);
    assert_vec_near(iir_normalize(iir_sub(s->camera.target, s->camera.position)),
                    iir_v3(0.f, 0.f, -1.f), 1e-5f);
    assert_vec_near(s->camera.up, iir_v3(0.f, 1.f, 0.f), 1e-5f);
    assert_true(near(s->camera.fov_y, iir_degrees(0.8f), 1e-3f));
    iir_scene_destroy(s);
}

/* text with the first `from` replaced by `to`, into out */
static void replace_once(const char *text, const char *from, const char *to, char *out, size_t n)
{
    const char *at = strstr(text, from);
    assert_non_null(at);
    snprintf(out, n, "%.*s%s%s", (int)(at - text), text, to, at + strlen(from));
}

/* glTF: KHR_materials_transmission is glass of index KHR_materials_ior tinted by the base colour;
 * metallic 1 with roughness 0 is a mirror of the base colour; rough metal stays diffuse. */
static void test_gltf_specular_materials(void **state)
{
    (void)state;
    static const char *const MATS =
        "\"materials\": [{\"name\": \"glass\", \"extensions\": {\n"
        "   \"KHR_materials_transmission\": {\"transmissionFactor\": 1},\n"
        "   \"KHR_materials_ior\": {\"ior\": 1.45}},\n"
        "   \"pbrMetallicRoughness\": {\"baseColorFactor\": [0.9, 0.95, 1, 1]}}],\n";
    static const char *const MIRROR =
        "\"materials\": [{\"name\": \"chrome\", \"pbrMetallicRoughness\": {\n"
        "   \"baseColorFactor\": [0.8, 0.8, 0.7, 1], \"metallicFactor\": 1, \"roughnessFactor\": "
        "0}}],\n";
    const char *from = strstr(GLTF, "\"materials\"");
    const char *to = strstr(GLTF, "\"buffers\"");
    char text[8192], path[1024];
    for (int pass = 0; pass < 2; pass++) {
        char joined[8192];
        snprintf(joined, sizeof joined, "%.*s%s %s", (int)(from - GLTF), GLTF, pass ? MIRROR : MATS,
                 to);
        replace_once(joined, "[\"KHR_lights_punctual\"]",
                     "[\"KHR_lights_punctual\", \"KHR_materials_transmission\", "
                     "\"KHR_materials_ior\"]",
                     text, sizeof text);
        write_file(pass ? "chrome.gltf" : "glass.gltf", text, path, sizeof path);
        iir_scene *s = load_ok(path);
        const iir_material *m = &s->material_list[0];
        if (pass == 0) {
            assert_int_equal(m->kind, IIR_MATERIAL_GLASS);
            assert_float_equal(m->ior, 1.45f, 1e-5);
            assert_vec_near(m->specular, iir_v3(0.9f, 0.95f, 1.f), 1e-6f);
        } else {
            assert_int_equal(m->kind, IIR_MATERIAL_MIRROR);
            assert_vec_near(m->specular, iir_v3(0.8f, 0.8f, 0.7f), 1e-6f);
        }
        assert_vec_near(m->albedo, iir_v3s(0.f), 0.f);
        iir_scene_destroy(s);
    }
}

/* The directional light is a sun: its direction is the node's -z, its intensity colour times
 * intensity (as W/m^2), its disk the scene's bounding sphere (the node's translation is ignored),
 * and nothing notes it as dropped. */
static void test_gltf_sun(void **state)
{
    (void)state;
    char path[1024];
    write_file("sunlit.gltf", GLTF, path, sizeof path);
    iir_scene *s = load_ok(path);
    const iir_light *sun = find_light(s, "sunnode");
    assert_non_null(sun);
    iir_error err;
    assert_int_equal(iir_light_validate(sun, &err), IIR_OK);
    assert_int_equal(sun->type, IIR_LIGHT_SUN);
    assert_string_equal(iir_light_kind(sun), "sun");
    assert_vec_near(sun->direction, iir_v3(0.f, -0.70710678f, -0.70710678f), 1e-5f);
    assert_vec_near(sun->intensity, iir_v3(3.f, 2.7f, 2.4f), 1e-5f);
    /* the floor quad [-1, 1] x {0} x [-1, 1]: centre 0, radius 1.001 sqrt(2) */
    assert_vec_near(sun->position, iir_v3(0.f, 0.f, 0.f), 1e-6f);
    assert_true(near(sun->radius, 1.001f * sqrtf(2.f), 1e-5f));
    for (uint32_t i = 0; i < s->num_dropped; i++)
        assert_string_not_equal(s->dropped[i].kind, "light");
    iir_scene_destroy(s);
}

/* A glTF spot without angles gets the specification's defaults (outer pi/4, inner 0); an inner
 * cone wider than the outer one is clamped to it. */
static void test_gltf_spot_defaults(void **state)
{
    (void)state;
    static char text[8192];
    char path[1024];
    replace_once(GLTF, "\"spot\": {\"innerConeAngle\": 0.4, \"outerConeAngle\": 0.6}",
                 "\"spot\": {}", text, sizeof text);
    write_file("defspot.gltf", text, path, sizeof path);
    iir_scene *s = load_ok(path);
    const iir_light *spot = find_light(s, "keynode");
    assert_non_null(spot);
    assert_int_equal(spot->profile, IIR_SPOT_GLTF);
    assert_true(near(spot->cone_angle, 0.25f * IIR_PI, 1e-6f));
    assert_true(spot->inner_angle == 0.f);
    iir_scene_destroy(s);
    replace_once(GLTF, "\"innerConeAngle\": 0.4", "\"innerConeAngle\": 0.9", text, sizeof text);
    write_file("widein.gltf", text, path, sizeof path);
    s = load_ok(path);
    spot = find_light(s, "keynode");
    assert_true(near(spot->inner_angle, 0.6f, 1e-6f) && near(spot->cone_angle, 0.6f, 1e-6f));
    iir_scene_destroy(s);
}

/* What assimp 5.2 drops, read from the file's JSON (scene_gltf_ext.c): Blender writes the emissive
 * factor normalised to 1 and the rest as KHR_materials_emissive_strength; an extension the file
 * requires and iir does not read is refused by name, one it only uses is noted by name. */
static void test_gltf_extensions(void **state)
{
    (void)state;
    static char text[8192], text2[8192];
    char path[1024];
    replace_once(GLTF, "\"emissiveFactor\": [1, 2, 3]}",
                 "\"emissiveFactor\": [1, 0.5, 0.25], \"extensions\": "
                 "{\"KHR_materials_emissive_strength\": {\"emissiveStrength\": 8}}}",
                 text, sizeof text);
    replace_once(text, "\"extensionsUsed\": [\"KHR_lights_punctual\"]",
                 "\"extensionsUsed\": [\"KHR_lights_punctual\", "
                 "\"KHR_materials_emissive_strength\", \"KHR_materials_sheen\"]",
                 text2, sizeof text2);
    write_file("strength.gltf", text2, path, sizeof path);
    iir_scene *s = load_ok(path);
    assert_vec_near(s->material_list[0].emission, iir_v3(8.f, 4.f, 2.f), 1e-5f);
    bool noted = false;
    for (uint32_t i = 0; i < s->num_dropped; i++) {
        assert_string_not_equal(s->dropped[i].name, "KHR_materials_emissive_strength");
        noted |= strcmp(s->dropped[i].name, "KHR_materials_sheen") == 0;
    }
    assert_true(noted);
    iir_scene_destroy(s);
    replace_once(GLTF, "\"extensionsUsed\": [\"KHR_lights_punctual\"]",
                 "\"extensionsUsed\": [\"KHR_lights_punctual\", \"KHR_draco_mesh_compression\"], "
                 "\"extensionsRequired\": [\"KHR_draco_mesh_compression\"]",
                 text, sizeof text);
    write_file("draco.gltf", text, path, sizeof path);
    iir_error err = {0};
    iir_scene *bad = NULL;
    assert_int_equal(iir_scene_load(path, &bad, &err), IIR_ERR_UNSUPPORTED);
    assert_null(bad);
    assert_non_null(strstr(err.msg, "KHR_draco_mesh_compression"));
    assert_non_null(strstr(err.msg, "draco.gltf"));
}

/* A glTF spot wider than a hemisphere is refused, naming the file and the light. */
static void test_gltf_bad_light(void **state)
{
    (void)state;
    static char text[8192];
    char path[1024];
    replace_once(GLTF, "\"outerConeAngle\": 0.6", "\"outerConeAngle\": 2.0", text, sizeof text);
    write_file("wide.gltf", text, path, sizeof path);
    assert_load_fails(path, "wide.gltf", "keynode");
    assert_load_fails(path, "wide.gltf", "cone angle");
}

/* ======================== refusals of mesh files ======================== */

static void test_missing_file(void **state)
{
    (void)state;
    char path[1024];
    snprintf(path, sizeof path, "%s/nope.obj", tmp);
    assert_load_fails(path, "nope.obj", "No such file");
}

/* Loads path in a child process as user and group nobody (65534) when this one is root, which
 * reads a chmod 000 file anyway; returns the child's error message ("" when it loaded). */
static void load_as_nobody(const char *path, char *msg, size_t n)
{
    int fd[2];
    assert_int_equal(pipe(fd), 0);
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) {
        close(fd[0]);
        if (setgid(65534) != 0 || setuid(65534) != 0) _exit(2);
        iir_scene *s = NULL;
        iir_error err = {0};
        const char *out = iir_scene_load(path, &s, &err) == IIR_OK ? "" : err.msg;
        ssize_t w = write(fd[1], out, strlen(out));
        _exit(w < 0 ? 3 : 0);
    }
    close(fd[1]);
    ssize_t got = read(fd[0], msg, n - 1);
    msg[got > 0 ? got : 0] = '\0';
    close(fd[0]);
    int status = 0;
    assert_int_equal(waitpid(pid, &status, 0), pid);
    assert_true(WIFEXITED(status) && WEXITSTATUS(status) == 0);
}

static void test_unreadable_file(void **state)
{
    (void)state;
    char path[1024];
    write_file("secret.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", path, sizeof path);
    assert_int_equal(chmod(path, 0), 0);
    if (geteuid() == 0) { /* root reads it anyway: as nobody, who may enter the folder */
        assert_int_equal(chmod(tmp, 0755), 0);
        char msg[512];
        load_as_nobody(path, msg, sizeof msg);
        print_message("as nobody: %s\n", msg);
        assert_contains(msg, "secret.obj");
        assert_contains(msg, "Permission denied");
    } else {
        assert_load_fails(path, "secret.obj", "Permission denied");
    }
    chmod(path, 0644);
}

static void test_unknown_format(void **state)
{
    (void)state;
    char path[1024];
    write_file("mesh.xyz", "hello, I am not a mesh\n", path, sizeof path);
    assert_load_fails(path, "mesh.xyz", "assimp");
    write_file("broken.gltf", "{\"asset\": ", path, sizeof path);
    assert_load_fails(path, "broken.gltf", "assimp");
}

static void test_no_triangles(void **state)
{
    (void)state;
    char path[1024];
    write_file("points.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\np 3\n", path, sizeof path);
    assert_load_fails(path, "points.obj", "no triangles");
    write_file("empty.obj", "# nothing but a comment, long enough for assimp\n", path, sizeof path);
    assert_load_fails(path, "empty.obj", NULL);
}

static void test_nan_inf_vertices(void **state)
{
    (void)state;
    char path[1024];
    write_file("nan.obj", "v 0 0 0\nv 1 nan 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n", path,
               sizeof path);
    assert_load_fails(path, "nan.obj", "not finite");
    write_file("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 -inf 0\nf 1 2 3\n", path, sizeof path);
    assert_load_fails(path, "inf.obj", "not finite");
    write_file("huge.obj", "v 0 0 0\nv 1 0 0\nv 0 1e39 0\nf 1 2 3\n", path, sizeof path);
    assert_load_fails(path, "huge.obj", "not finite");
}

/* ======================== the sidecar ======================== */

static const char *const BOX_OBJ = "mtllib glow.mtl\n"
                                   "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                   "usemtl glow\nf 1 2 3 4\n";

/* Writes box.obj and NAME with the given sidecar text; returns the sidecar path in out. */
static void write_sidecar(const char *name, const char *json, char *out, size_t n)
{
    char path[1024];
    write_file("glow.mtl", GLOW_MTL, path, sizeof path);
    write_file("box.obj", BOX_OBJ, path, sizeof path);
    write_file(name, json, out, n);
}

static void test_sidecar_applied(void **state)
{
    (void)state;
    char path[1024], sc[1024];
    write_file("glow.mtl", GLOW_MTL, path, sizeof path);
    write_file("room.obj", BOX_OBJ, path, sizeof path);
    write_file("room.scene.json",
               "{\"unit_scale\": 2,\n"
               " \"camera\": {\"position\": [1, 1, 5], \"target\": [1, 1, 0], \"fov_y\": 50},\n"
               " \"lights\": [{\"type\": \"spot\", \"name\": \"key\", \"position\": [1, 1, 3],\n"
               "   \"target\": [1, 1, 0], \"cone_angle\": 30, \"smooth\": 10, \"intensity\": 5},\n"
               "   {\"type\": \"point\", \"position\": [0.5, 0.5, 1], \"intensity\": [1, 2, 3]}],\n"
               " \"materials\": {\"glow\": {\"albedo\": [0.1, 0.2, 0.3], \"emission\": 0}},\n"
               " \"paths\": {\"orbit\": {\"keys\": [[0, 1, 2]]}}}\n",
               sc, sizeof sc);
    /* applied automatically next to room.obj */
    iir_scene *s = load_ok(path);
    assert_string_equal(s->name, "room");
    assert_vec_near(s->bounds_max, iir_v3(2.f, 2.f, 0.f), 1e-6f); /* geometry scaled */
    assert_vec_near(s->camera.position, iir_v3(1, 1, 5), 0.f);    /* sidecar: world units */
    assert_true(s->camera.fov_y == 50.f);
    assert_int_equal(s->num_lights, 2);
    const iir_light *key = &s->lights[0];
    assert_string_equal(key->name, "key");
    assert_vec_near(key->position, iir_v3(1, 1, 3), 0.f);
    assert_vec_near(key->direction, iir_v3(0, 0, -1), 1e-6f);
    assert_true(near(key->cone_angle, iir_radians(30.f), 1e-6f));
    assert_true(near(key->smooth, iir_radians(10.f), 1e-6f));
    assert_vec_near(key->intensity, iir_v3s(5.f), 0.f);
    assert_string_equal(s->lights[1].name, "light1");
    assert_int_equal(s->lights[1].type, IIR_LIGHT_POINT);
    assert_vec_near(s->lights[1].intensity, iir_v3(1, 2, 3), 0.f);
    assert_vec_near(s->material_list[0].albedo, iir_v3(0.1f, 0.2f, 0.3f), 1e-6f);
    assert_true(iir_is_black(s->material_list[0].emission));
    assert_non_null(s->paths_json);
    assert_string_equal(s->paths_json, "{\"orbit\":{\"keys\":[[0,1,2]]}}");
    iir_scene_destroy(s);

    /* a standalone sidecar naming its mesh; an empty lights array removes all lights */
    write_sidecar("named.scene.json", "{\"file\": \"box.obj\", \"lights\": []}", sc, sizeof sc);
    s = load_ok(sc);
    assert_string_equal(s->name, "named");
    assert_string_equal(s->source, sc);
    assert_int_equal(s->num_triangles, 2);
    assert_int_equal(s->num_lights, 0);
    iir_scene_destroy(s);
}

/* The sidecar's "gltf_spot" (cone_angle = glTF's outer angle, inner_angle) and "sun" (direction,
 * up, intensity as irradiance; its disk fitted to the scene). */
static void test_sidecar_gltf_spot_and_sun(void **state)
{
    (void)state;
    char sc[1024];
    write_sidecar(
        "newkinds.scene.json",
        "{\"file\": \"box.obj\", \"lights\": [\n"
        " {\"type\": \"gltf_spot\", \"name\": \"g\", \"position\": [0.5, 0.5, 2],\n"
        "  \"target\": [0.5, 0.5, 0], \"up\": [1, 0, 0], \"cone_angle\": 40,\n"
        "  \"inner_angle\": 15, \"intensity\": [1, 2, 3]},\n"
        " {\"type\": \"gltf_spot\", \"position\": [0, 0, 1], \"direction\": [0, 0, -1],\n"
        "  \"cone_angle\": 10, \"intensity\": 1},\n"
        " {\"type\": \"sun\", \"name\": \"sky\", \"direction\": [0, -2, -2], \"up\": [0, 0, 1],\n"
        "  \"intensity\": 4}]}",
        sc, sizeof sc);
    iir_scene *s = load_ok(sc);
    assert_int_equal(s->num_lights, 3);
    iir_error err;
    for (uint32_t i = 0; i < 3; i++) assert_int_equal(iir_light_validate(&s->lights[i], &err), 0);
    const iir_light *g = &s->lights[0], *g2 = &s->lights[1], *sun = &s->lights[2];
    assert_int_equal(g->type, IIR_LIGHT_SPOT);
    assert_int_equal(g->profile, IIR_SPOT_GLTF);
    assert_string_equal(iir_light_kind(g), "gltf_spot");
    assert_vec_near(g->position, iir_v3(0.5f, 0.5f, 2.f), 0.f);
    assert_vec_near(g->direction, iir_v3(0, 0, -1), 1e-6f);
    assert_vec_near(g->up, iir_v3(1, 0, 0), 0.f);
    assert_true(near(g->cone_angle, iir_radians(40.f), 1e-6f));
    assert_true(near(g->inner_angle, iir_radians(15.f), 1e-6f));
    assert_true(g->smooth == 0.f);
    assert_vec_near(g->intensity, iir_v3(1, 2, 3), 0.f);
    assert_int_equal(g2->profile, IIR_SPOT_GLTF);
    assert_true(g2->inner_angle == 0.f); /* default */
    assert_string_equal(sun->name, "sky");
    assert_int_equal(sun->type, IIR_LIGHT_SUN);
    assert_vec_near(sun->direction, iir_v3(0.f, -0.70710678f, -0.70710678f), 1e-6f);
    assert_vec_near(sun->up, iir_v3(0, 0, 1), 0.f);
    assert_vec_near(sun->intensity, iir_v3s(4.f), 0.f);
    /* box.obj is the unit square at z = 0 */
    assert_vec_near(sun->position, iir_v3(0.5f, 0.5f, 0.f), 1e-6f);
    assert_true(near(sun->radius, 0.5f * 1.001f * sqrtf(2.f), 1e-6f));
    iir_scene_destroy(s);
}

/* A folder with one mesh loads it; with a sidecar named after the folder, that. */
static void test_folder(void **state)
{
    (void)state;
    char dir[600], path[700];
    snprintf(dir, sizeof dir, "%s/onemesh", tmp);
    mkdir(dir, 0755);
    snprintf(path, sizeof path, "%s/only.obj", dir);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fputs("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", f);
    fclose(f);
    iir_scene *s = load_ok(dir);
    assert_string_equal(s->name, "only");
    assert_int_equal(s->num_triangles, 1);
    iir_scene_destroy(s);

    snprintf(dir, sizeof dir, "%s/nomesh", tmp);
    mkdir(dir, 0755);
    assert_load_fails(dir, "nomesh", "no *.scene.json");
}

static void test_sidecar_malformed(void **state)
{
    (void)state;
    char sc[1024];
    write_sidecar("bad.scene.json", "{\"file\": \"box.obj\",\n \"camera\": {\"position\": [1, 2,",
                  sc, sizeof sc);
    assert_load_fails(sc, "bad.scene.json", "malformed JSON at line 2");
    write_sidecar("nanjson.scene.json", "{\"file\": \"box.obj\", \"unit_scale\": NaN}", sc,
                  sizeof sc);
    assert_load_fails(sc, "nanjson.scene.json", "malformed JSON");
    write_sidecar("list.scene.json", "[1, 2]", sc, sizeof sc);
    assert_load_fails(sc, "list.scene.json", "JSON object");
}

static void test_sidecar_unknown_field(void **state)
{
    (void)state;
    char sc[1024];
    write_sidecar("typo.scene.json", "{\"file\": \"box.obj\", \"lihgts\": []}", sc, sizeof sc);
    assert_load_fails(sc, "typo.scene.json", "lihgts: unknown field");
    write_sidecar("typo2.scene.json",
                  "{\"file\": \"box.obj\", \"lights\": [{\"type\": \"point\", \"position\": "
                  "[0, 1, 0], \"intensity\": 1, \"colour\": [1, 1, 1]}]}",
                  sc, sizeof sc);
    assert_load_fails(sc, "typo2.scene.json", "lights[0].colour: unknown field");
    write_sidecar("twice.scene.json", "{\"file\": \"box.obj\", \"file\": \"box.obj\"}", sc,
                  sizeof sc);
    assert_load_fails(sc, "twice.scene.json", "given twice");
    write_sidecar("nomat.scene.json",
                  "{\"file\": \"box.obj\", \"materials\": {\"gloww\": {\"albedo\": 0.5}}}", sc,
                  sizeof sc);
    assert_load_fails(sc, "nomat.scene.json", "materials.gloww");
}

static void test_sidecar_bad_values(void **state)
{
    (void)state;
    static const struct {
        const char *json, *field, *problem;
    } cases[] = {
        {"\"lights\": [{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": [0, 0, 0], "
         "\"cone_angle\": 30, \"intensity\": 1}]",
         "lights[0].direction", "zero"},
        {"\"lights\": [{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
         "\"cone_angle\": 0, \"intensity\": 1}]",
         "lights[0].cone_angle", "(0, 90]"},
        {"\"lights\": [{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
         "\"cone_angle\": 120, \"intensity\": 1}]",
         "lights[0].cone_angle", "(0, 90]"},
        {"\"lights\": [{\"type\": \"spot\", \"position\": [0, 1, 0], \"target\": [0, 1, 0], "
         "\"cone_angle\": 30, \"intensity\": 1}]",
         "lights[0].target", "position"},
        {"\"lights\": [{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
         "\"target\": [0, 0, 0], \"cone_angle\": 30, \"intensity\": 1}]",
         "lights[0]", "exactly one"},
        {"\"lights\": [{\"type\": \"point\", \"position\": [0, 1e7, 0], \"intensity\": 1}]",
         "lights[0].position[1]", "must be in [-1000000, 1000000]"},
        {"\"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"intensity\": -1}]",
         "lights[0].intensity", "must be in [0, 1000000000]"},
        {"\"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"intensity\": 1, "
         "\"cone_angle\": 30}]",
         "lights[0].cone_angle", "only spot"},
        {"\"lights\": [{\"type\": \"tube\", \"position\": [0, 1, 0], \"intensity\": 1}]",
         "lights[0].type", "\"spot\", \"gltf_spot\", \"point\", \"sun\" or \"area\""},
        {"\"lights\": [{\"type\": \"area\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
         "\"intensity\": 1}]",
         "lights[0].size", "required"},
        {"\"lights\": [{\"type\": \"area\", \"position\": [0, 1, 0], \"size\": [1, 1], "
         "\"intensity\": 1}]",
         "lights[0]", "an area light needs exactly one of"},
        {"\"lights\": [{\"type\": \"area\", \"direction\": [0, -1, 0], \"size\": [1, 1], "
         "\"intensity\": 1}]",
         "lights[0].position", "required"},
        {"\"lights\": [{\"type\": \"area\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
         "\"size\": [1], \"intensity\": 1}]",
         "lights[0].size", "2 numbers"},
        {"\"lights\": [{\"type\": \"area\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
         "\"size\": [1, 0], \"intensity\": 1}]",
         "lights[0].size[1]", "> 0"},
        {"\"lights\": [{\"type\": \"area\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
         "\"size\": [-1, 1], \"intensity\": 1}]",
         "lights[0].size[0]", "must be in [0, 1000000]"},
        {"\"lights\": [{\"type\": \"area\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
         "\"size\": [1, 1], \"cone_angle\": 30, \"intensity\": 1}]",
         "lights[0].cone_angle", "an area light has no cone"},
        {"\"lights\": [{\"type\": \"area\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
         "\"size\": [1, 1]}]",
         "lights[0].intensity", "required"},
        {"\"lights\": [{\"type\": \"area\", \"material\": \"glow\", \"size\": [1, 1]}]",
         "lights[0].size", "from the material's triangles"},
        {"\"lights\": [{\"type\": \"area\", \"material\": \"\"}]", "lights[0].material",
         "must not be empty"},
        {"\"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"size\": [1, 1], "
         "\"intensity\": 1}]",
         "lights[0].size", "only area lights"},
        {"\"lights\": [{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
         "\"cone_angle\": 30, \"material\": \"glow\", \"intensity\": 1}]",
         "lights[0].material", "only area lights"},
        {"\"lights\": [{\"type\": \"sun\", \"direction\": [0, -1, 0], \"size\": [1, 1], "
         "\"intensity\": 1}]",
         "lights[0].size", "only area lights"},
        {"\"lights\": [{\"type\": \"gltf_spot\", \"position\": [0, 1, 0], \"direction\": [0, -1, "
         "0], "
         "\"cone_angle\": 30, \"smooth\": 5, \"intensity\": 1}]",
         "lights[0].smooth", "no smooth edge"},
        {"\"lights\": [{\"type\": \"gltf_spot\", \"position\": [0, 1, 0], \"direction\": [0, -1, "
         "0], "
         "\"cone_angle\": 30, \"inner_angle\": 31, \"intensity\": 1}]",
         "lights[0].inner_angle", "must be in [0, 30]"},
        {"\"lights\": [{\"type\": \"gltf_spot\", \"position\": [0, 1, 0], \"direction\": [0, -1, "
         "0], "
         "\"inner_angle\": 10, \"intensity\": 1}]",
         "lights[0].cone_angle", "required"},
        {"\"lights\": [{\"type\": \"spot\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
         "\"cone_angle\": 30, \"inner_angle\": 10, \"intensity\": 1}]",
         "lights[0].inner_angle", "only glTF spots"},
        {"\"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0], \"inner_angle\": 10, "
         "\"intensity\": 1}]",
         "lights[0].inner_angle", "only glTF spots"},
        {"\"lights\": [{\"type\": \"sun\", \"position\": [0, 1, 0], \"direction\": [0, -1, 0], "
         "\"intensity\": 1}]",
         "lights[0].position", "a sun has no position"},
        {"\"lights\": [{\"type\": \"sun\", \"target\": [0, 0, 0], \"intensity\": 1}]",
         "lights[0].target", "\"direction\""},
        {"\"lights\": [{\"type\": \"sun\", \"direction\": [0, -1, 0], \"cone_angle\": 30, "
         "\"intensity\": 1}]",
         "lights[0].cone_angle", "a sun has no cone"},
        {"\"lights\": [{\"type\": \"sun\", \"direction\": [0, -1, 0], \"inner_angle\": 3, "
         "\"intensity\": 1}]",
         "lights[0].inner_angle", "a sun has no cone"},
        {"\"lights\": [{\"type\": \"sun\", \"intensity\": 1}]", "lights[0].direction", "required"},
        {"\"lights\": [{\"type\": \"sun\", \"direction\": [0, 0, 0], \"intensity\": 1}]",
         "lights[0].direction", "zero"},
        {"\"lights\": [{\"type\": \"sun\", \"direction\": [0, -1, 0], \"intensity\": -2}]",
         "lights[0].intensity", "must be in [0, 1000000000]"},
        {"\"camera\": {\"position\": [0, 1, 2], \"target\": [0, 1, 2]}", "camera.target",
         "equals camera.position"},
        {"\"camera\": {\"position\": [0, 1, 2], \"target\": [0, 1, 0], \"fov_y\": 0}",
         "camera.fov_y", "(0, 180)"},
        {"\"camera\": {\"position\": [0, 1, 2], \"target\": [0, 1, 0], \"up\": [0, 0, 1]}",
         "camera.up", "parallel"},
        {"\"camera\": {\"position\": [0, \"1\", 2], \"target\": [0, 1, 0]}", "camera.position[1]",
         "number"},
        {"\"camera\": {\"target\": [0, 1, 0]}", "camera.position", "required"},
        {"\"unit_scale\": 0", "unit_scale", "positive"},
        {"\"unit_scale\": \"mm\"", "unit_scale", "number"},
        {"\"unit_scale\": 1e999", "unit_scale",
         "must be a finite number (got one that overflows a double)"},
        {"\"materials\": {\"glow\": {\"albedo\": [1.5, 0, 0]}}", "materials.glow.albedo[0]",
         "must be in [0, 1]"},
        {"\"paths\": [1, 2]", "paths", "object"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        char json[1024], sc[1024];
        snprintf(json, sizeof json, "{\"file\": \"box.obj\", %s}", cases[i].json);
        write_sidecar("values.scene.json", json, sc, sizeof sc);
        print_message("case %zu: %s\n", i, cases[i].field);
        assert_load_fails(sc, "values.scene.json", cases[i].field);
        assert_load_fails(sc, cases[i].field, cases[i].problem);
    }
}

/* ======================== area lights ======================== */

/* The sidecar's "area" light by its pose: centre, normal (target or direction), up, size. */
static void test_sidecar_area(void **state)
{
    (void)state;
    char sc[1024];
    write_sidecar("area.scene.json",
                  "{\"file\": \"box.obj\", \"lights\": [\n"
                  " {\"type\": \"area\", \"name\": \"panel\", \"position\": [0.5, 0.5, 2],\n"
                  "  \"target\": [0.5, 0.5, 0], \"up\": [1, 0, 0], \"size\": [0.4, 0.25],\n"
                  "  \"intensity\": [1, 2, 3]},\n"
                  " {\"type\": \"area\", \"position\": [0, 0, 1], \"direction\": [0, 0, -3],\n"
                  "  \"size\": [1, 2], \"intensity\": 4}]}",
                  sc, sizeof sc);
    iir_scene *s = load_ok(sc);
    assert_int_equal(s->num_lights, 2);
    const iir_light *a = &s->lights[0], *b = &s->lights[1];
    iir_error err;
    assert_int_equal(iir_light_validate(a, &err), IIR_OK);
    assert_int_equal(a->type, IIR_LIGHT_AREA);
    assert_string_equal(iir_light_kind(a), "area");
    assert_string_equal(a->name, "panel");
    assert_vec_near(a->position, iir_v3(0.5f, 0.5f, 2.f), 0.f);
    assert_vec_near(a->direction, iir_v3(0, 0, -1), 1e-6f);
    assert_vec_near(a->up, iir_v3(1, 0, 0), 0.f);
    assert_true(a->size.x == 0.4f && a->size.y == 0.25f);
    assert_vec_near(a->intensity, iir_v3(1, 2, 3), 0.f);
    assert_vec_near(b->direction, iir_v3(0, 0, -1), 1e-6f);
    assert_vec_near(b->up, iir_v3(0, 1, 0), 0.f); /* the default */
    assert_true(b->size.x == 1.f && b->size.y == 2.f);
    assert_true(near(iir_light_flux(b).x, IIR_PI * 4.f * 2.f, 1e-5f));
    assert_int_equal(s->num_triangles, 2); /* a light by its pose takes nothing from the mesh */
    iir_scene_destroy(s);
}

/* lamp.obj: a grey floor (4 x 4 at y = 0) and a lamp (material "lamp", Ke 5 4 3): a 0.6 x 0.3
 * rectangle centred at LAMP_C, facing down, its long side turned 30 degrees from x towards z, as
 * 2 x 2 quads. Variants: 0 as said, 1 without one quad (an L), 2 with one quad raised 0.05, 3 with
 * one quad wound the other way. */
static const iir_vec3 LAMP_C = {0.3f, 1.9f, -0.2f};

static iir_vec3 lamp_point(float s, float t)
{
    float c = cosf(iir_radians(30.f)), n = sinf(iir_radians(30.f));
    iir_vec3 a = iir_v3(0.6f * c, 0.f, 0.6f * n), b = iir_v3(-0.3f * n, 0.f, 0.3f * c);
    return iir_add(LAMP_C, iir_add(iir_scale(a, s - 0.5f), iir_scale(b, t - 0.5f)));
}

static void write_lamp(const char *name, int variant, char *out, size_t n)
{
    char path[1024], text[4096];
    write_file("lamp.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0.8 0.8 0.8\nKe 5 4 3\n",
               path, sizeof path);
    int len = snprintf(text, sizeof text,
                       "mtllib lamp.mtl\nv -2 0 -2\nv -2 0 2\nv 2 0 2\nv 2 0 -2\nusemtl grey\n"
                       "f 1 2 3 4\nusemtl lamp\n");
    for (int q = 0; q < 4; q++) {
        if (variant == 1 && q == 3) continue;
        float s = 0.5f * (q % 2), t = 0.5f * (q / 2);
        iir_vec3 v[4] = {lamp_point(s, t), lamp_point(s + .5f, t), lamp_point(s + .5f, t + .5f),
                         lamp_point(s, t + .5f)};
        for (int k = 0; k < 4; k++) {
            float lift = variant == 2 && q == 3 ? 0.05f : 0.f;
            len += snprintf(text + len, sizeof text - (size_t)len, "v %.9g %.9g %.9g\n",
                            (double)v[k].x, (double)(v[k].y + lift), (double)v[k].z);
        }
        bool flip = variant == 3 && q == 3;
        len += snprintf(text + len, sizeof text - (size_t)len, "%s\n",
                        flip ? "f -1 -2 -3 -4" : "f -4 -3 -2 -1");
    }
    write_file(name, text, out, n);
}

/* An area light taken from the lamp's material: its pose, size and emission; the lamp's
 * triangles leave the mesh and its material stops emitting. */
static void test_sidecar_area_from_material(void **state)
{
    (void)state;
    char obj[1024], sc[1024];
    write_lamp("lamp.obj", 0, obj, sizeof obj);
    write_file(
        "lamp.scene.json",
        "{\"lights\": [{\"type\": \"area\", \"material\": \"lamp\"},\n"
        " {\"type\": \"area\", \"name\": \"dim\", \"material\": \"lamp\", \"intensity\": 1}]}",
        sc, sizeof sc);
    assert_load_fails(obj, "lights[1].material", "material 'lamp' has no triangles");
    write_file("lamp.scene.json", "{\"lights\": [{\"type\": \"area\", \"material\": \"lamp\"}]}",
               sc, sizeof sc);
    iir_scene *s = load_ok(obj);
    assert_int_equal(s->num_lights, 1);
    const iir_light *l = &s->lights[0];
    iir_error err;
    assert_int_equal(iir_light_validate(l, &err), IIR_OK);
    assert_int_equal(l->type, IIR_LIGHT_AREA);
    assert_vec_near(l->position, LAMP_C, 1e-5f);
    assert_vec_near(l->direction, iir_v3(0, -1, 0), 1e-6f);
    assert_vec_near(l->up, iir_normalize(iir_sub(lamp_point(0.5f, 1.f), LAMP_C)), 1e-5f);
    assert_true(near(l->size.x, 0.6f, 1e-5f) && near(l->size.y, 0.3f, 1e-5f));
    assert_vec_near(l->intensity, iir_v3(5, 4, 3), 0.f);
    /* its rectangle is the lamp's: the corners are where the mesh had them */
    iir_frame fr = iir_spot_frame(l);
    assert_vec_near(iir_area_light_point(l, &fr, iir_v2(0.5f, 0.5f)), lamp_point(1.f, 1.f), 1e-5f);
    assert_vec_near(iir_area_light_point(l, &fr, iir_v2(-0.5f, 0.5f)), lamp_point(0.f, 1.f), 1e-5f);
    assert_int_equal(s->num_triangles, 2);
    assert_true(material_area(s, "lamp") == 0.f);
    const iir_material *lamp = find_material(s, "lamp");
    assert_true(!lamp || iir_is_black(lamp->emission));
    assert_true(s->bounds_max.y < 1e-6f); /* the floor alone */
    iir_scene_destroy(s);

    /* a name and an intensity of its own */
    write_file("lamp.scene.json",
               "{\"lights\": [{\"type\": \"area\", \"name\": \"dim\", \"material\": \"lamp\", "
               "\"intensity\": [1, 0.5, 0.25]}]}",
               sc, sizeof sc);
    s = load_ok(obj);
    assert_string_equal(s->lights[0].name, "dim");
    assert_vec_near(s->lights[0].intensity, iir_v3(1, 0.5f, 0.25f), 0.f);
    iir_scene_destroy(s);
}

/* The lamp without one quad (an L) is no rectangle any more: it keeps the rectangle as its pose
 * and size and gets a shape, 3/4 of it, whose points are where the mesh had the L. */
static void test_sidecar_area_l_shape(void **state)
{
    (void)state;
    char obj[1024], sc[1024];
    write_lamp("llamp.obj", 1, obj, sizeof obj);
    write_file("llamp.scene.json", "{\"lights\": [{\"type\": \"area\", \"material\": \"lamp\"}]}",
               sc, sizeof sc);
    iir_scene *s = load_ok(obj);
    assert_int_equal(s->num_lights, 1);
    const iir_light *l = &s->lights[0];
    iir_error err;
    assert_int_equal(iir_light_validate(l, &err), IIR_OK);
    assert_vec_near(l->position, LAMP_C, 1e-5f);
    assert_true(near(l->size.x, 0.6f, 1e-5f) && near(l->size.y, 0.3f, 1e-5f));
    assert_int_equal(l->shape.num_triangles, 6);
    assert_true(near(iir_area_shape_fraction(&l->shape), 0.75f, 1e-5f));
    assert_true(near(iir_light_flux(l).x, IIR_PI * 5.f * 0.75f * 0.18f, 1e-4f));
    /* its shape holds the three quads' centres and not the missing one's; q maps back onto them */
    iir_frame fr = iir_spot_frame(l);
    for (int q = 0; q < 4; q++) {
        iir_vec3 c = lamp_point(0.25f + 0.5f * (q % 2), 0.25f + 0.5f * (q / 2));
        iir_vec3 d = iir_sub(c, l->position);
        iir_vec2 ql = iir_v2(iir_dot(d, fr.r) / l->size.x, iir_dot(d, fr.u) / l->size.y);
        assert_true(iir_area_light_contains(l, ql) == (q != 3));
        assert_vec_near(iir_area_light_point(l, &fr, ql), c, 1e-5f);
    }
    assert_int_equal(s->num_triangles, 2); /* the floor alone */
    iir_scene_destroy(s);
}

/* disc.obj: a grey floor and a disc lamp (material "disc", Ke 5 4 3) of n triangles, radius 0.3,
 * centred at DISC_C, facing down. */
static const iir_vec3 DISC_C = {0.1f, 1.8f, 0.2f};

static void write_disc_obj(const char *name, int n, char *out, size_t size)
{
    char path[1024];
    write_file("disc.mtl", "newmtl grey\nKd 0.5 0.5 0.5\nnewmtl disc\nKd 0.8 0.8 0.8\nKe 5 4 3\n",
               path, sizeof path);
    snprintf(out, size, "%s/%s", tmp, name);
    FILE *f = fopen(out, "w");
    assert_non_null(f);
    fprintf(f, "mtllib disc.mtl\n");
    iir_test_write_quad(f, "grey", iir_v3(0, 0, 0), iir_v3(0, 0, 2), iir_v3(2, 0, 0));
    iir_test_write_disc(f, "disc", DISC_C, iir_v3(0.3f, 0, 0), iir_v3(0, 0, 0.3f), n);
    fclose(f);
}

/* A disc lamp of 32 triangles from its material: a shaped light of 32 triangles whose flux is
 * pi L times the 32-gon's area (n R^2 sin(2 pi / n) / 2), facing down, around the disc. */
static void test_sidecar_area_disc(void **state)
{
    (void)state;
    char obj[1024], sc[1024];
    write_disc_obj("disc.obj", 32, obj, sizeof obj);
    write_file("disc.scene.json",
               "{\"lights\": [{\"type\": \"area\", \"name\": \"lamp\", \"material\": \"disc\"}]}",
               sc, sizeof sc);
    iir_scene *s = load_ok(obj);
    assert_int_equal(s->num_lights, 1);
    const iir_light *l = &s->lights[0];
    assert_string_equal(l->name, "lamp");
    assert_int_equal(l->shape.num_triangles, 32);
    assert_vec_near(l->position, DISC_C, 1e-5f);
    assert_vec_near(l->direction, iir_v3(0, -1, 0), 1e-6f);
    assert_true(near(l->size.x, l->size.y, 1e-5f) && l->size.x > 0.59f &&
                l->size.x <= 0.6f + 1e-5f);
    double area = 32 * 0.09 * sin(2 * M_PI / 32) / 2;
    assert_true(fabs(iir_area_light_area(l) - area) < 1e-5 * area);
    assert_true(fabs(iir_light_flux(l).y - M_PI * 4.0 * area) < 1e-4 * M_PI * 4.0 * area);
    assert_true(material_area(s, "disc") == 0.f);
    assert_int_equal(s->num_triangles, 2);
    iir_scene_destroy(s);
    /* 80 triangles: more than a shape takes */
    write_disc_obj("bigdisc.obj", 80, obj, sizeof obj);
    write_file("bigdisc.scene.json", "{\"lights\": [{\"type\": \"area\", \"material\": \"disc\"}]}",
               sc, sizeof sc);
    assert_load_fails(obj, "lights[0].material: material 'disc' has 80 triangles",
                      "a shaped area light has at most 64");
}

/* A light by its pose with a "shape" (as the scene writer saves one) loads it as given; a broken
 * shape is refused naming the field and the problem. */
static void test_sidecar_area_shape_field(void **state)
{
    (void)state;
    char sc[1024];
    write_sidecar(
        "shape.scene.json",
        "{\"file\": \"box.obj\", \"lights\": [{\"type\": \"area\", \"position\": [0.5, "
        "0.5, 1], \"direction\": [0, 0, -1], \"size\": [0.4, 0.2], \"intensity\": 2,\n"
        " \"shape\": [[[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5]], [[-0.5, -0.5], [0.5, 0.5], "
        "[-0.25, 0.125]]]}]}",
        sc, sizeof sc);
    iir_scene *s = load_ok(sc);
    const iir_light *l = &s->lights[0];
    assert_int_equal(l->shape.num_triangles, 2);
    assert_true(l->shape.tri[1][2].x == -0.25f && l->shape.tri[1][2].y == 0.125f);
    assert_true(near(iir_area_shape_fraction(&l->shape), 0.5f + 0.1875f, 1e-6f));
    iir_scene_destroy(s);
    static const struct {
        const char *shape, *field, *problem;
    } cases[] = {
        {"[[[-0.5, -0.5], [0.6, -0.5], [0.5, 0.5]]]", "lights[0].shape[0][1][0]",
         "must be in [-0.5, 0.5], got 0.6"},
        {"[[[0, 0], [0.5, 0.5], [0.25, 0.25]]]", "lights[0].shape", "degenerate"},
        {"[[[-0.5, -0.5], [0.5, -0.5], [0.5, 0.5]], [[-0.5, -0.5], [0.5, 0.5], [0.5, -0.4]]]",
         "lights[0].shape", "overlapping"},
        {"[]", "lights[0].shape", "1 to 64 triangles"},
        {"[[[0, 0], [0.5, 0.5]]]", "lights[0].shape[0]", "3 corners"},
        {"[[0, 0, 0.5, 0.5, 0.5, 0]]", "lights[0].shape[0]", "3 corners"},
        {"[[[0, 0], [0.5, 0.5], \"x\"]]", "lights[0].shape[0][2]", "2 numbers"},
        {"{}", "lights[0].shape", "triangles"},
    };
    char text[1024];
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        snprintf(text, sizeof text,
                 "{\"file\": \"box.obj\", \"lights\": [{\"type\": \"area\", \"position\": [0, "
                 "0, 1], \"direction\": [0, 0, -1], \"size\": [1, 1], \"intensity\": 1, \"shape\": "
                 "%s}]}",
                 cases[i].shape);
        write_sidecar("badshape.scene.json", text, sc, sizeof sc);
        assert_load_fails(sc, cases[i].field, cases[i].problem);
    }
    /* 65 triangles */
    int len = snprintf(text, sizeof text,
                       "{\"file\": \"box.obj\", \"lights\": [{\"type\": "
                       "\"area\", \"position\": [0, 0, 1], \"direction\": [0, 0, -1], "
                       "\"size\": [1, 1], \"intensity\": 1, \"shape\": [");
    char big[8192];
    snprintf(big, sizeof big, "%s", text);
    for (int t = 0; t < 65; t++)
        len += snprintf(big + len, sizeof big - (size_t)len, "%s[[0, 0], [0.1, 0], [0, 0.1]]",
                        t ? ", " : "");
    snprintf(big + len, sizeof big - (size_t)len, "]}]}");
    write_sidecar("badshape.scene.json", big, sc, sizeof sc);
    assert_load_fails(sc, "lights[0].shape", "1 to 64 triangles");
    /* a shape on a light taken from a material, or on a spot */
    write_sidecar("badshape.scene.json",
                  "{\"file\": \"box.obj\", \"lights\": [{\"type\": \"area\", \"material\": "
                  "\"glow\", \"shape\": [[[0, 0], [0.5, 0], [0, 0.5]]]}]}",
                  sc, sizeof sc);
    assert_load_fails(sc, "lights[0].shape", "gets its pose, size and shape from the material");
    write_sidecar("badshape.scene.json",
                  "{\"file\": \"box.obj\", \"lights\": [{\"type\": \"point\", \"position\": [0, "
                  "0, 1], \"intensity\": 1, \"shape\": [[[0, 0], [0.5, 0], [0, 0.5]]]}]}",
                  sc, sizeof sc);
    assert_load_fails(sc, "lights[0].shape", "only area lights");
}

/* A material that is not flat, or not facing one way, or that the mesh lacks, is refused. */
static void test_sidecar_area_material_refused(void **state)
{
    (void)state;
    static const struct {
        int variant;
        const char *problem;
    } cases[] = {{2, "is not flat"}, {3, "facing different ways (two-sided or mixed facing)"}};
    char obj[1024], sc[1024];
    write_file("badlamp.scene.json", "{\"lights\": [{\"type\": \"area\", \"material\": \"lamp\"}]}",
               sc, sizeof sc);
    for (size_t i = 0; i < sizeof cases / sizeof *cases; i++) {
        write_lamp("badlamp.obj", cases[i].variant, obj, sizeof obj);
        print_message("variant %d\n", cases[i].variant);
        assert_load_fails(obj, "lights[0].material: material 'lamp'", cases[i].problem);
    }
    write_file("badlamp.scene.json",
               "{\"lights\": [{\"type\": \"area\", \"material\": \"lammp\"}]}", sc, sizeof sc);
    write_lamp("badlamp.obj", 0, obj, sizeof obj);
    assert_load_fails(obj, "no material 'lammp'", "grey, lamp");
}

static void test_sidecar_file_escapes(void **state)
{
    (void)state;
    char sc[1024];
    write_sidecar("up.scene.json", "{\"file\": \"../x.obj\"}", sc, sizeof sc);
    assert_load_fails(sc, "up.scene.json", "inside the sidecar's folder");
    write_sidecar("deep.scene.json", "{\"file\": \"a/../../x.obj\"}", sc, sizeof sc);
    assert_load_fails(sc, "deep.scene.json", "file");
    write_sidecar("abs.scene.json", "{\"file\": \"/etc/passwd\"}", sc, sizeof sc);
    assert_load_fails(sc, "abs.scene.json", "inside the sidecar's folder");
    write_sidecar("gone.scene.json", "{\"file\": \"gone.obj\"}", sc, sizeof sc);
    assert_load_fails(sc, "gone.scene.json", "gone.obj");
    write_sidecar("orphan.scene.json", "{\"lights\": []}", sc, sizeof sc);
    assert_load_fails(sc, "orphan.scene.json", "names no mesh");
}

/* ======================== resolving names ======================== */

static void test_resolve(void **state)
{
    (void)state;
    char out[1024], cwd[1024];
    iir_error err;
    const char *scenes = IIR_SOURCE_DIR "/scenes";
    assert_int_equal(iir_scene_resolve("cornell_box", scenes, out, sizeof out, &err), IIR_OK);
    assert_string_equal(out, IIR_SOURCE_DIR "/scenes/cornell_box");
    /* an existing path is taken as is */
    assert_int_equal(iir_scene_resolve(scenes, NULL, out, sizeof out, &err), IIR_OK);
    assert_string_equal(out, scenes);

    /* relative names are judged from the scratch folder, where ../etc does not exist */
    assert_non_null(getcwd(cwd, sizeof cwd));
    assert_int_equal(chdir(tmp), 0);
    /* a missing path is a file that cannot be read (exit 3, as a missing name), not bad input */
    assert_int_equal(iir_scene_resolve("../etc", scenes, out, sizeof out, &err), IIR_ERR_IO);
    assert_contains(err.msg, "'../etc'");
    assert_contains(err.msg, "'..'");
    assert_int_equal(iir_scene_resolve("a/b", scenes, out, sizeof out, &err), IIR_ERR_IO);
    assert_contains(err.msg, "'a/b'");
    assert_int_equal(iir_scene_resolve("up..name", scenes, out, sizeof out, &err), IIR_ERR_INVALID);
    assert_int_equal(iir_scene_resolve("my scene", scenes, out, sizeof out, &err), IIR_ERR_INVALID);
    assert_contains(err.msg, "letters, digits");
    assert_int_equal(iir_scene_resolve("", scenes, out, sizeof out, &err), IIR_ERR_INVALID);
    /* a missing name says where it looked, and lists nothing */
    assert_int_equal(iir_scene_resolve("no_such_scene", scenes, out, sizeof out, &err), IIR_ERR_IO);
    assert_contains(err.msg, "no_such_scene");
    assert_contains(err.msg, scenes);
    assert_null(strstr(err.msg, "cornell_box"));
    assert_int_equal(chdir(cwd), 0);

    char tiny[8];
    assert_int_equal(iir_scene_resolve("cornell_box", scenes, tiny, sizeof tiny, &err),
                     IIR_ERR_INVALID);
}

/* ======================== opening a scene with its ray tracer ======================== */

/* Opening must succeed with a scene of the given name and a ray tracer that hits it. */
static void assert_opens(const char *name_or_path, const char *scenes_dir, const char *want_name)
{
    iir_scene *s = NULL;
    iir_rt *rt = NULL;
    iir_error err = {0};
    iir_status st = iir_scene_open(name_or_path, scenes_dir, &s, &rt, &err);
    if (st != IIR_OK) print_message("opening %s failed: %s\n", name_or_path, err.msg);
    assert_int_equal(st, IIR_OK);
    assert_non_null(s);
    assert_non_null(rt);
    assert_string_equal(s->name, want_name);
    iir_vec3 c = iir_scale(iir_add(s->bounds_min, s->bounds_max), 0.5f);
    iir_ray up = iir_make_ray(c, iir_v3(0.f, 1.f, 0.f), 0.f, INFINITY);
    iir_hit h;
    assert_true(iir_rt_intersect(rt, &up, &h, NULL, IIR_RAYS_BENCH)); /* the ceiling */
    iir_rt_destroy(rt);
    iir_scene_destroy(s);
}

/* Opening must fail with both outputs NULL (even when they held something) and a message. */
static void assert_open_fails(const char *name_or_path, const char *scenes_dir, iir_status want,
                              const char *needle)
{
    iir_scene *s = (iir_scene *)1;
    iir_rt *rt = (iir_rt *)1;
    iir_error err = {0};
    assert_int_equal(iir_scene_open(name_or_path, scenes_dir, &s, &rt, &err), want);
    assert_null(s);
    assert_null(rt);
    assert_int_equal(err.status, want);
    assert_contains(err.msg, needle);
}

static void test_open(void **state)
{
    (void)state;
    assert_opens(NULL, NULL, "cornell_box");
    assert_opens("builtin", NULL, "cornell_box");
    assert_opens("cornell_box", IIR_SOURCE_DIR "/scenes", "cornell_box");
    assert_opens(IIR_SOURCE_DIR "/scenes/cornell_box", NULL, "cornell_box");

    /* every step can fail: the name, the lookup, the file */
    assert_open_fails("no_such_scene", IIR_SOURCE_DIR "/scenes", IIR_ERR_IO, "no_such_scene");
    assert_open_fails("a/b", IIR_SOURCE_DIR "/scenes", IIR_ERR_IO,
                      "'a/b'"); /* a missing path: exit 3 */
    assert_open_fails("cornell_box", NULL, IIR_ERR_IO, "no scenes folder");
    char path[1024];
    write_file("open_broken.obj", "v 0 0 0\nv 1 0 0\n", path, sizeof path);
    iir_scene *s = NULL;
    iir_error load_err = {0};
    iir_status st = iir_scene_load(path, &s, &load_err);
    assert_int_not_equal(st, IIR_OK);
    assert_open_fails(path, NULL, st, "open_broken.obj");
}

/* ======================== the big shipped scenes ======================== */

static double seconds_since(const struct timespec *t0)
{
    struct timespec t1;
    clock_gettime(CLOCK_MONOTONIC, &t1);
    return (double)(t1.tv_sec - t0->tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0->tv_nsec);
}

/* The light and camera must be inside the bounds, the camera must validate. */
static void assert_inside(const iir_scene *s, iir_vec3 p)
{
    assert_true(p.x > s->bounds_min.x && p.y > s->bounds_min.y && p.z > s->bounds_min.z);
    assert_true(p.x < s->bounds_max.x && p.y < s->bounds_max.y && p.z < s->bounds_max.z);
}

static void check_shipped_room(const iir_scene *s)
{
    iir_error err;
    assert_int_equal(iir_camera_validate(&s->camera, &err), IIR_OK);
    assert_inside(s, s->camera.position);
    assert_int_equal(s->num_lights, 1);
    assert_int_equal(iir_light_validate(&s->lights[0], &err), IIR_OK);
    assert_inside(s, s->lights[0].position);
}

static void test_conference(void **state)
{
    (void)state;
    struct timespec t0;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    iir_scene *s = load_ok(IIR_SOURCE_DIR "/scenes/conference");
    print_message("conference: %u triangles (%u skipped), %.2f s\n", s->num_triangles,
                  s->skipped_degenerate, seconds_since(&t0));
    assert_true(s->num_triangles + s->skipped_degenerate == 331179);
    assert_true(s->num_triangles > 300000);
    /* metres: about 8.1 x 2 x 5.2 m */
    assert_true(near(s->bounds_min.x, -3.06f, 0.01f) && near(s->bounds_max.x, 5.06f, 0.01f));
    assert_true(near(s->bounds_min.y, -0.008f, 0.01f) && near(s->bounds_max.y, 1.95f, 0.01f));
    assert_true(near(s->bounds_min.z, -3.17f, 0.01f) && near(s->bounds_max.z, 2.01f, 0.01f));
    check_shipped_room(s);
    iir_scene_destroy(s);
}

static void test_living_room(void **state)
{
    (void)state;
    iir_scene *s = load_ok(IIR_SOURCE_DIR "/scenes/living_room");
    assert_true(s->num_triangles + s->skipped_degenerate == 143163);
    assert_true(near(s->bounds_max.y, 2.88f, 0.01f));
    check_shipped_room(s);
    iir_scene_destroy(s);
}

/* ======================== main ======================== */

int main(void)
{
    snprintf(tmp, sizeof tmp, "%s", iir_test_tmpdir("test_scene"));
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_builtin),
        cmocka_unit_test(test_cornell_shipped_equals_builtin),
        cmocka_unit_test(test_camera),
        cmocka_unit_test(test_obj_emissive),
        cmocka_unit_test(test_obj_colours_clamped),
        cmocka_unit_test(test_degenerate_triangles),
        cmocka_unit_test(test_gltf_lights_and_camera),
        cmocka_unit_test(test_gltf_bad_light),
        cmocka_unit_test(test_gltf_sun),
        cmocka_unit_test(test_gltf_spot_defaults),
        cmocka_unit_test(test_gltf_extensions),
        cmocka_unit_test(test_obj_specular_materials),
        cmocka_unit_test(test_gltf_specular_materials),
        cmocka_unit_test(test_sidecar_specular_materials),
        cmocka_unit_test(test_missing_file),
        cmocka_unit_test(test_unreadable_file),
        cmocka_unit_test(test_unknown_format),
        cmocka_unit_test(test_no_triangles),
        cmocka_unit_test(test_nan_inf_vertices),
        cmocka_unit_test(test_sidecar_applied),
        cmocka_unit_test(test_folder),
        cmocka_unit_test(test_sidecar_malformed),
        cmocka_unit_test(test_sidecar_unknown_field),
        cmocka_unit_test(test_sidecar_bad_values),
        cmocka_unit_test(test_sidecar_gltf_spot_and_sun),
        cmocka_unit_test(test_sidecar_area),
        cmocka_unit_test(test_sidecar_area_from_material),
        cmocka_unit_test(test_sidecar_area_material_refused),
        cmocka_unit_test(test_sidecar_area_l_shape),
        cmocka_unit_test(test_sidecar_area_disc),
        cmocka_unit_test(test_sidecar_area_shape_field),
        cmocka_unit_test(test_sidecar_file_escapes),
        cmocka_unit_test(test_resolve),
        cmocka_unit_test(test_open),
        cmocka_unit_test(test_conference),
        cmocka_unit_test(test_living_room),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

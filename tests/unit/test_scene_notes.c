/* test_scene_notes.c -- what iir says about scenes users bring (issue 16): the camera a scene
 * without one gets (inside a closed room, from outside otherwise, never inside furniture), the
 * aspect a scene's camera was framed for, the lights and materials the loader ignores and each
 * method leaves out (iir_method_dropped), and why a view renders black (iir_scene_explain_dark).
 * Every scene is written here: OBJ rooms with and without a wall, a closed box, a glTF file. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/method.h"
#include "iir/scene.h"
#include "testutil.h"

static char tmp[512];

/* ======================== scenes ======================== */

enum { ROOM_WALLS = 1, ROOM_FRONT = 2, ROOM_LAMP = 4, ROOM_BOX = 8, BIG_BOX = 16, LAMP_BOX = 32 };

static const char *const MTL = "newmtl white\nKd 0.75 0.75 0.75\n"
                               "newmtl red\nKd 0.7 0.1 0.1\n"
                               "newmtl lamp\nKd 0.8 0.8 0.8\nKe 20 18 15\n";

/* A closed box of half size h at c in material m, faces outwards (a solid object). */
static void write_box(FILE *f, iir_vec3 c, float h, const char *m)
{
    iir_vec3 x = iir_v3(h, 0, 0), y = iir_v3(0, h, 0), z = iir_v3(0, 0, h);
    iir_test_write_quad(f, m, iir_add(c, y), z, x);
    iir_test_write_quad(f, m, iir_sub(c, y), x, z);
    iir_test_write_quad(f, m, iir_add(c, x), y, z);
    iir_test_write_quad(f, m, iir_sub(c, x), z, y);
    iir_test_write_quad(f, m, iir_add(c, z), x, y);
    iir_test_write_quad(f, m, iir_sub(c, z), y, x);
}

/* dir/name.obj: a room 4 x 2.5 x 3 (walls facing in; the +z wall only with ROOM_FRONT), a lamp
 * under the ceiling facing down, a box on the floor, a big closed box around its centre, or a
 * glowing cube (material "lamp") hanging in a corner. */
static void write_scene(const char *name, int parts)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s.obj", tmp, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "mtllib scene.mtl\n");
    const float W = 2.f, H = 2.5f, D = 1.5f;
    if (parts & ROOM_WALLS) {
        iir_test_write_quad(f, "white", iir_v3(0, 0, 0), iir_v3(0, 0, D), iir_v3(W, 0, 0));
        iir_test_write_quad(f, "white", iir_v3(0, H, 0), iir_v3(W, 0, 0), iir_v3(0, 0, D));
        iir_test_write_quad(f, "red", iir_v3(-W, H / 2, 0), iir_v3(0, H / 2, 0), iir_v3(0, 0, D));
        iir_test_write_quad(f, "white", iir_v3(W, H / 2, 0), iir_v3(0, 0, D), iir_v3(0, H / 2, 0));
        iir_test_write_quad(f, "white", iir_v3(0, H / 2, -D), iir_v3(W, 0, 0), iir_v3(0, H / 2, 0));
    }
    if (parts & ROOM_FRONT)
        iir_test_write_quad(f, "white", iir_v3(0, H / 2, D), iir_v3(0, H / 2, 0), iir_v3(W, 0, 0));
    if (parts & ROOM_LAMP)
        iir_test_write_quad(f, "lamp", iir_v3(0, H - 0.01f, 0), iir_v3(0.4f, 0, 0),
                            iir_v3(0, 0, 0.3f));
    if (parts & ROOM_BOX) write_box(f, iir_v3(0.5f, 0.4f, 0.f), 0.4f, "white");
    if (parts & BIG_BOX) write_box(f, iir_v3(0.f, 1.25f, 0.f), 0.6f, "white");
    if (parts & LAMP_BOX) write_box(f, iir_v3(-1.f, 2.f, 0.f), 0.1f, "lamp");
    fclose(f);
    iir_test_write_file(tmp, "scene.mtl", MTL);
}

typedef struct opened {
    iir_scene *scene;
    iir_rt *rt;
} opened;

static opened open_obj(const char *name)
{
    opened o = {0};
    iir_error err = {0};
    if (iir_test_load_obj(tmp, name, &o.scene, &o.rt, &err) != IIR_OK) fail_msg("%s", err.msg);
    return o;
}

static void close_scene(opened *o)
{
    iir_rt_destroy(o->rt);
    iir_scene_destroy(o->scene);
}

static bool inside_box(iir_vec3 p, iir_vec3 lo, iir_vec3 hi)
{
    return p.x > lo.x && p.y > lo.y && p.z > lo.z && p.x < hi.x && p.y < hi.y && p.z < hi.z;
}

/* Mean luminance of a pt render of the scene's own view at 32x24, 16 samples. */
static double mean_luminance(const opened *o)
{
    iir_params p = iir_params_default();
    iir_test_set(&p, "spp", 16);
    iir_method *m = NULL;
    iir_error err = {0};
    if (iir_method_create("pt", o->scene, o->rt, &p, &m, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_image *img = iir_image_create(32, 24);
    iir_view v = {o->scene->lights, o->scene->num_lights, o->scene->camera};
    iir_frame_stats fs;
    iir_test_render(m, &v, img, &fs);
    double sum = 0;
    for (int i = 0; i < 32 * 24; i++) sum += iir_luminance(img->pixels[i]);
    iir_image_destroy(img);
    iir_method_destroy(m);
    return sum / (32 * 24);
}

/* ======================== the camera of a scene without one ======================== */

/* A closed OBJ room lit by an emissive lamp: framed from inside (it used to be framed from
 * outside: a black image); the camera stands inside the room and the image is lit. */
static void test_closed_room_inside(void **state)
{
    (void)state;
    write_scene("room", ROOM_WALLS | ROOM_FRONT | ROOM_LAMP | ROOM_BOX);
    opened o = open_obj("room");
    assert_int_equal(o.scene->camera_origin, IIR_CAMERA_INSIDE);
    assert_true(inside_box(o.scene->camera.position, o.scene->bounds_min, o.scene->bounds_max));
    assert_true(o.scene->camera.fov_y == 60.f);
    assert_true(mean_luminance(&o) > 0.05);
    char text[400];
    iir_scene_describe_camera(o.scene, text, sizeof text);
    assert_non_null(strstr(text, "framed from inside"));
    close_scene(&o);
}

/* The same room with its front wall missing is not closed: framed from outside (+z), looking at
 * the bounds' centre, and the image is lit through the opening. */
static void test_open_room_outside(void **state)
{
    (void)state;
    write_scene("open", ROOM_WALLS | ROOM_LAMP | ROOM_BOX);
    opened o = open_obj("open");
    assert_int_equal(o.scene->camera_origin, IIR_CAMERA_OUTSIDE);
    assert_true(o.scene->camera.position.z > o.scene->bounds_max.z);
    assert_true(mean_luminance(&o) > 0.01);
    char text[400];
    iir_scene_describe_camera(o.scene, text, sizeof text);
    assert_non_null(strstr(text, "framed from outside"));
    close_scene(&o);
}

/* A closed object is not a room: without lights its faces point away from its centre; with a
 * light outside it (a sidecar's point light), the light is not enclosed. Both from outside. */
static void test_closed_object_outside(void **state)
{
    (void)state;
    write_scene("statue", ROOM_BOX);
    opened o = open_obj("statue");
    assert_int_equal(o.scene->camera_origin, IIR_CAMERA_OUTSIDE);
    close_scene(&o);
    write_scene("lit_statue", ROOM_BOX);
    iir_test_write_file(tmp, "lit_statue.scene.json",
                        "{\"lights\": [{\"type\": \"point\", \"position\": [0, 3, 3], "
                        "\"intensity\": 5}]}");
    o = open_obj("lit_statue");
    assert_int_equal(o.scene->camera_origin, IIR_CAMERA_OUTSIDE);
    assert_true(mean_luminance(&o) > 0.01);
    close_scene(&o);
}

/* A room whose centre lies inside a closed box (a big cabinet): still a room, and the camera is
 * put at the most open point, not inside the box. */
static void test_room_camera_not_in_furniture(void **state)
{
    (void)state;
    write_scene("cabinet", ROOM_WALLS | ROOM_FRONT | ROOM_LAMP | BIG_BOX);
    opened o = open_obj("cabinet");
    assert_int_equal(o.scene->camera_origin, IIR_CAMERA_INSIDE);
    iir_vec3 p = o.scene->camera.position;
    assert_false(inside_box(p, iir_v3(-0.6f, 0.65f, -0.6f), iir_v3(0.6f, 1.85f, 0.6f)));
    assert_true(inside_box(p, o.scene->bounds_min, o.scene->bounds_max));
    assert_true(mean_luminance(&o) > 0.02);
    close_scene(&o);
}

/* The sidecar's camera and the built-in box's are theirs, said so. */
static void test_camera_origins(void **state)
{
    (void)state;
    write_scene("posed", ROOM_WALLS | ROOM_FRONT | ROOM_LAMP);
    iir_test_write_file(tmp, "posed.scene.json",
                        "{\"camera\": {\"position\": [0, 1, 1], \"target\": [0, 1, 0], "
                        "\"aspect\": 2}}");
    opened o = open_obj("posed");
    assert_int_equal(o.scene->camera_origin, IIR_CAMERA_SIDECAR);
    assert_true(o.scene->aspect == 2.f);
    assert_true(o.scene->camera.position.z == 1.f);
    close_scene(&o);
    iir_scene *box = iir_scene_create_cornell_box();
    assert_int_equal(box->camera_origin, IIR_CAMERA_BUILTIN);
    assert_true(box->aspect == 1.f);
    iir_scene_destroy(box);
    /* an aspect outside [0.01, 100] is refused, naming the field */
    iir_test_write_file(tmp, "posed.scene.json",
                        "{\"camera\": {\"position\": [0, 1, 1], \"target\": [0, 1, 0], "
                        "\"aspect\": 0}}");
    iir_error err = {0};
    assert_int_not_equal(iir_test_load_obj(tmp, "posed", &o.scene, &o.rt, &err), IIR_OK);
    assert_non_null(strstr(err.msg, "camera.aspect"));
}

/* ======================== glTF: aspect, ignored lights and materials ======================== */

/* A 2x2 floor quad facing +y (material "paint", with a colour texture) and a copy 0.5 above it
 * (material "steel": metallic); a spot "key" aimed down, a point light "fill", a directional light
 * "sun" and a spot no node places; a camera with aspectRatio 1.5. */
static const char *const GLTF =
    "{\"asset\": {\"version\": \"2.0\"},\n"
    " \"extensionsUsed\": [\"KHR_lights_punctual\"],\n"
    " \"extensions\": {\"KHR_lights_punctual\": {\"lights\": [\n"
    "   {\"type\": \"spot\", \"name\": \"key\", \"color\": [1, 1, 1], \"intensity\": 10,\n"
    "    \"spot\": {\"innerConeAngle\": 0.4, \"outerConeAngle\": 0.6}},\n"
    "   {\"type\": \"point\", \"name\": \"fill\", \"color\": [1, 1, 1], \"intensity\": 2},\n"
    "   {\"type\": \"directional\", \"name\": \"sun\", \"color\": [1, 1, 1], \"intensity\": "
    "3}]}},\n"
    " \"scene\": 0, \"scenes\": [{\"nodes\": [0, 1, 2, 3, 4, 5]}],\n"
    " \"nodes\": [\n"
    "   {\"mesh\": 0, \"name\": \"floor\"},\n"
    "   {\"mesh\": 1, \"name\": \"plate\", \"translation\": [0, 0.5, 0]},\n"
    "   {\"name\": \"keynode\", \"translation\": [0, 2, 0],\n"
    "    \"rotation\": [-0.70710678, 0, 0, 0.70710678],\n"
    "    \"extensions\": {\"KHR_lights_punctual\": {\"light\": 0}}},\n"
    "   {\"name\": \"fillnode\", \"translation\": [0, 1.5, 0.5],\n"
    "    \"extensions\": {\"KHR_lights_punctual\": {\"light\": 1}}},\n"
    "   {\"name\": \"sunnode\", \"translation\": [0, 3, 0],\n"
    "    \"extensions\": {\"KHR_lights_punctual\": {\"light\": 2}}},\n"
    "   {\"name\": \"cam\", \"translation\": [0, 1, 5], \"camera\": 0}],\n"
    " \"cameras\": [{\"type\": \"perspective\",\n"
    "   \"perspective\": {\"yfov\": 0.8, \"aspectRatio\": 1.5, \"znear\": 0.1}}],\n"
    " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1,\n"
    "   \"material\": 0}]}, {\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1,\n"
    "   \"material\": 1}]}],\n"
    " \"materials\": [{\"name\": \"paint\", \"pbrMetallicRoughness\": {\"metallicFactor\": 0,\n"
    "   \"baseColorFactor\": [0.8, 0.8, 0.8, 1], \"baseColorTexture\": {\"index\": 0}}},\n"
    "   {\"name\": \"steel\", \"pbrMetallicRoughness\": {\"metallicFactor\": 1,\n"
    "   \"baseColorFactor\": [0.5, 0.5, 0.5, 1]}}],\n"
    " \"textures\": [{\"source\": 0}], \"images\": [{\"uri\": "
    "\"paint.png\"}],\n" IIR_TEST_GLTF_QUAD_DATA;

/* Index of the entry about `name` whose text holds `needle` (and, unless NULL, of method m). */
static int find(const iir_dropped *d, uint32_t n, const char *m, const char *name,
                const char *needle)
{
    for (uint32_t i = 0; i < n; i++)
        if (!strcmp(d[i].name, name) && strstr(d[i].what, needle) &&
            (!m || !strcmp(d[i].method, m)))
            return (int)i;
    return -1;
}

static void test_gltf_aspect_and_dropped(void **state)
{
    (void)state;
    const char *path = iir_test_write_file(tmp, "lamp.gltf", GLTF);
    iir_scene *s = NULL;
    iir_rt *rt = NULL;
    iir_error err = {0};
    if (iir_scene_open(path, NULL, &s, &rt, &err) != IIR_OK) fail_msg("%s", err.msg);
    assert_int_equal(s->camera_origin, IIR_CAMERA_FILE);
    assert_true(s->aspect == 1.5f);
    assert_int_equal(s->num_lights, 3); /* key, fill and the sun */

    /* the loader's notes: every method gets them, with method "" */
    iir_dropped d[16];
    uint32_t n = iir_method_dropped("pt", s, s->lights, s->num_lights, d, 16);
    assert_int_equal(n, s->num_dropped);
    assert_true(find(d, n, "", "sunnode", "") < 0);         /* a sun now */
    assert_true(find(d, n, "", "paint", "paint.png") >= 0); /* its texture cannot be read */
    /* pt renders the metal by its BSDF: nothing said; the VPL methods shade it diffuse, and say so
     */
    assert_true(find(d, n, NULL, "steel", "") < 0);
    /* what is left out is a warning (issue 26 item 8): none of these is a note */
    for (uint32_t i = 0; i < n; i++) assert_false(d[i].note);
    assert_true(find(d, n, "", "floor", "") < 0);
    assert_true(find(d, n, NULL, "fillnode", "") < 0); /* pt renders the point light */

    /* iir keeps VPLs for every light: nothing of the lights is left out; the metal's specular
       lobe is (the rough dielectric paint's 4% is not worth a warning) */
    uint32_t k = iir_method_dropped("iir", s, s->lights, s->num_lights, d, 16);
    assert_int_equal(k, n + 1);
    assert_true(find(d, k, "iir", "fillnode", "") < 0);
    assert_true(find(d, k, "iir", "steel", "is glossy (a metal") >= 0);
    /* ir renders every punctual light's indirect light */
    assert_int_equal(iir_method_dropped("ir", s, s->lights, s->num_lights, d, 16), n + 1);
    /* a short buffer gets what fits, the count says how many there are */
    assert_int_equal(iir_method_dropped("iir", s, s->lights, s->num_lights, d, 1), k);
    assert_int_equal(iir_method_dropped("iir", s, s->lights, s->num_lights, NULL, 0), k);
    assert_int_equal(iir_method_dropped("nope", s, s->lights, s->num_lights, d, 16), 0);
    iir_rt_destroy(rt);
    iir_scene_destroy(s);
}

/* A sidecar's lights replace the file's: the notes on the file's lights go with them. */
static void test_sidecar_lights_clear_light_notes(void **state)
{
    (void)state;
    iir_test_write_file(tmp, "relit.gltf", GLTF);
    const char *path = iir_test_write_file(
        tmp, "relit.scene.json",
        "{\"file\": \"relit.gltf\", \"lights\": [{\"type\": \"point\", \"name\": \"bulb\", "
        "\"position\": [0, 1, 0], \"intensity\": 1}]}");
    iir_scene *s = NULL;
    iir_error err = {0};
    if (iir_scene_load(path, &s, &err) != IIR_OK) fail_msg("%s", err.msg);
    assert_true(find(s->dropped, s->num_dropped, "", "sunnode", "") < 0);
    assert_true(find(s->dropped, s->num_dropped, "", "paint", "paint.png") >= 0);
    assert_true(s->aspect == 1.5f); /* the file's camera stays, with its aspect */
    iir_scene_destroy(s);
}

/* Emissive materials kept static (a sidecar with a "lights" array): ir and iir take VPLs from
 * lights only and say so. */
static void test_emitters_dropped(void **state)
{
    (void)state;
    write_scene("glow", ROOM_WALLS | ROOM_FRONT | ROOM_LAMP);
    iir_test_write_file(tmp, "glow.scene.json", "{\"lights\": []}");
    opened o = open_obj("glow");
    assert_int_equal(o.scene->num_lights, 0);
    iir_dropped d[8];
    assert_int_equal(iir_method_dropped("pt", o.scene, NULL, 0, d, 8), 0);
    assert_int_equal(iir_method_dropped("ir", o.scene, NULL, 0, d, 8), 1);
    assert_string_equal(d[0].method, "ir");
    assert_string_equal(d[0].kind, "material");
    assert_string_equal(d[0].name, "lamp");
    close_scene(&o);
}

/* The triangles of material `name` and their total area. */
static uint32_t material_triangles(const iir_scene *s, const char *name, double *area)
{
    uint32_t n = 0;
    *area = 0;
    for (uint32_t t = 0; t < s->num_triangles; t++)
        if (!strcmp(s->material_list[s->materials[t]].name, name)) n++, *area += s->areas[t];
    return n;
}

/* One frame of method `name` of the scene's own view and lights at 32 x 24; its mean luminance. */
static double render_mean(const opened *o, const char *name)
{
    iir_params p = iir_params_default();
    iir_test_set(&p, "vpls", 64);
    iir_test_set(&p, "sm_res", 16);
    iir_method *m = iir_test_method(&(iir_test_cornell){o->scene, o->rt}, name, &p);
    iir_image *img = iir_image_create(32, 24);
    iir_view v = {o->scene->lights, o->scene->num_lights, o->scene->camera};
    iir_frame_stats fs;
    iir_test_render(m, &v, img, &fs);
    double sum = 0;
    for (int i = 0; i < 32 * 24; i++) sum += iir_luminance(img->pixels[i]);
    iir_image_destroy(img);
    iir_method_destroy(m);
    return sum / (32 * 24);
}

/* An OBJ whose lamp is an emissive quad, without a sidecar: the lamp becomes a movable area light
 * named after its material (its triangles gone, its radiance the material's emission, the quad's
 * pose and size), the scene's notes say so, and iir renders it (it used to refuse emitters); a
 * sidecar with "lights": [] keeps the lamp static emissive triangles; a lamp that is no one-sided
 * planar set (a glowing cube) stays static with a note saying why. */
static void test_emitter_becomes_area_light(void **state)
{
    (void)state;
    write_scene("lamproom", ROOM_WALLS | ROOM_FRONT | ROOM_LAMP);
    opened o = open_obj("lamproom");
    const iir_scene *s = o.scene;
    assert_int_equal(s->num_lights, 1);
    const iir_light *l = &s->lights[0];
    assert_int_equal(l->type, IIR_LIGHT_AREA);
    assert_string_equal(l->name, "lamp");
    assert_true(l->intensity.x == 20.f && l->intensity.y == 18.f && l->intensity.z == 15.f);
    assert_true(fabsf(l->position.y - 2.49f) < 1e-5f && fabsf(l->position.x) < 1e-5f);
    assert_true(fabsf(l->direction.y + 1.f) < 1e-6f);
    assert_true(fabsf(l->size.x * l->size.y - 0.48f) < 1e-5f);
    assert_int_equal(l->shape.num_triangles, 0); /* a rectangle */
    double area;
    assert_int_equal(material_triangles(s, "lamp", &area), 0);
    int at = find(s->dropped, s->num_dropped, "", "lamp",
                  "emits light: became the movable area light 'lamp'");
    assert_true(at >= 0);
    assert_true(s->dropped[at].note); /* rendered: a note, not a warning (issue 26 item 8) */
    /* the method's own entry on the lamp (ir: its indirect light) stays a warning */
    iir_dropped d[16];
    uint32_t n = iir_method_dropped("ir", s, s->lights, s->num_lights, d, 16);
    for (uint32_t i = 0; i < n && i < 16; i++) assert_true(d[i].note == !d[i].method[0]);
    double mean_iir = render_mean(&o, "iir"), mean_pt = render_mean(&o, "pt");
    print_message("lamp room: iir mean %.4f, pt mean %.4f\n", mean_iir, mean_pt);
    assert_true(mean_iir > 0.05 && mean_pt > 0.05);
    close_scene(&o);

    iir_test_write_file(tmp, "lamproom.scene.json", "{\"lights\": []}");
    o = open_obj("lamproom");
    assert_int_equal(o.scene->num_lights, 0);
    assert_int_equal(material_triangles(o.scene, "lamp", &area), 2);
    assert_true(fabs(area - 0.48) < 1e-5);
    assert_true(find(o.scene->dropped, o.scene->num_dropped, "", "lamp", "") < 0);
    close_scene(&o);

    write_scene("cuberoom", ROOM_WALLS | ROOM_FRONT | LAMP_BOX);
    o = open_obj("cuberoom");
    assert_int_equal(o.scene->num_lights, 0);
    assert_int_equal(material_triangles(o.scene, "lamp", &area), 12);
    at = find(o.scene->dropped, o.scene->num_dropped, "", "lamp",
              "emits light: stays static emissive triangles, not a movable area light: it "
              "has triangles facing different ways");
    assert_true(at >= 0);
    assert_true(o.scene->dropped[at].note);
    close_scene(&o);
}

/* The same rule for glTF: the file's plate (material "steel" made emissive, emissiveFactor) becomes
 * an area light after the file's own lights, facing up as its winding does, and leaves the mesh. */
static void test_gltf_emitter_becomes_area_light(void **state)
{
    (void)state;
    static const char *const steel = "{\"name\": \"steel\", \"pbrMetallicRoughness\"";
    const char *at = strstr(GLTF, steel);
    assert_non_null(at);
    char text[8192];
    snprintf(text, sizeof text,
             "%.*s{\"name\": \"glowplate\", \"emissiveFactor\": [1, 0.5, 0.25], "
             "\"pbrMetallicRoughness\"%s",
             (int)(at - GLTF), GLTF, at + strlen(steel));
    const char *path = iir_test_write_file(tmp, "glowplate.gltf", text);
    iir_scene *s = NULL;
    iir_error err = {0};
    if (iir_scene_load(path, &s, &err) != IIR_OK) fail_msg("%s", err.msg);
    const iir_light *l = &s->lights[s->num_lights - 1];
    assert_int_equal(l->type, IIR_LIGHT_AREA);
    assert_string_equal(l->name, "glowplate");
    assert_true(l->intensity.x == 1.f && l->intensity.y == 0.5f && l->intensity.z == 0.25f);
    assert_true(fabsf(l->position.y - 0.5f) < 1e-6f && fabsf(fabsf(l->direction.y) - 1.f) < 1e-6f);
    assert_true(fabsf(l->size.x - 2.f) < 1e-5f && fabsf(l->size.y - 2.f) < 1e-5f);
    double area;
    assert_int_equal(material_triangles(s, "glowplate", &area), 0);
    assert_int_equal(s->num_triangles, 2); /* the floor alone */
    assert_true(find(s->dropped, s->num_dropped, "", "glowplate",
                     "became the movable area light 'glowplate'") >= 0);
    iir_scene_destroy(s);
}

/* ======================== why a view is black ======================== */

static void explain(const opened *o, iir_camera cam, char *why, size_t n)
{
    iir_scene_explain_dark(o->scene, o->rt, o->scene->lights, o->scene->num_lights, &cam, why, n);
}

static void test_explain_dark(void **state)
{
    (void)state;
    char why[400];
    iir_camera out = {iir_v3(0, 1.2f, 8), iir_v3(0, 1.2f, 0), iir_v3(0, 1, 0), 45};
    iir_camera away = {iir_v3(0, 1.2f, 8), iir_v3(0, 1.2f, 20), iir_v3(0, 1, 0), 45};

    write_scene("unlit", ROOM_WALLS | ROOM_FRONT | ROOM_BOX);
    opened o = open_obj("unlit");
    explain(&o, o.scene->camera, why, sizeof why);
    assert_non_null(strstr(why, "no lights"));
    close_scene(&o);

    write_scene("shut", ROOM_WALLS | ROOM_FRONT | ROOM_LAMP | BIG_BOX);
    o = open_obj("shut");
    explain(&o, out, why, sizeof why);
    assert_non_null(strstr(why, "lights are inside a closed room and the camera is outside"));
    explain(&o, away, why, sizeof why);
    assert_non_null(strstr(why, "sees no geometry"));
    iir_camera in_box = {iir_v3(0.1f, 1.2f, 0.1f), iir_v3(0, 1.2f, 0), iir_v3(0, 1, 0), 45};
    explain(&o, in_box, why, sizeof why);
    assert_non_null(strstr(why, "inside geometry"));
    close_scene(&o);
}

/* pt at too few bounces for glass or a mirror renders it black and says which bounces show it
 * (issue 26, item 11a); at enough bounces, and for methods without the parameter, nothing. */
static void test_pt_bounces_through_glass(void **state)
{
    (void)state;
    iir_test_cornell l = iir_test_load(IIR_SOURCE_DIR "/scenes/cornell_spheres", "cornell_spheres");
    iir_dropped d[8];
    iir_params p = {0};
    uint32_t n = iir_method_dropped_by_params("pt", l.scene, &p, d, 8); /* bounces 2: glass */
    int g = find(d, n, "pt", "glass", "bounces 3 shows the direct light through it, 4 as");
    assert_int_equal(n, 1);
    assert_true(g >= 0 && !d[g].note && !strcmp(d[g].kind, "material"));
    iir_test_set(&p, "bounces", 1); /* the mirror too */
    n = iir_method_dropped_by_params("pt", l.scene, &p, d, 8);
    assert_int_equal(n, 2);
    assert_true(find(d, n, "pt", "mirror", "bounces 2 shows the direct light in it") >= 0);
    iir_test_set(&p, "bounces", 3);
    assert_int_equal(iir_method_dropped_by_params("pt", l.scene, &p, d, 8), 0);
    assert_int_equal(iir_method_dropped_by_params("whitted", l.scene, &p, d, 8), 0);
    assert_int_equal(iir_method_dropped_by_params("nope", l.scene, &p, d, 8), 0);
    iir_test_unload(&l);
}

int main(void)
{
    snprintf(tmp, sizeof tmp, "%s", iir_test_tmpdir("test_scene_notes"));
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_closed_room_inside),
        cmocka_unit_test(test_open_room_outside),
        cmocka_unit_test(test_closed_object_outside),
        cmocka_unit_test(test_room_camera_not_in_furniture),
        cmocka_unit_test(test_camera_origins),
        cmocka_unit_test(test_gltf_aspect_and_dropped),
        cmocka_unit_test(test_sidecar_lights_clear_light_notes),
        cmocka_unit_test(test_emitters_dropped),
        cmocka_unit_test(test_emitter_becomes_area_light),
        cmocka_unit_test(test_gltf_emitter_becomes_area_light),
        cmocka_unit_test(test_explain_dark),
        cmocka_unit_test(test_pt_bounces_through_glass),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

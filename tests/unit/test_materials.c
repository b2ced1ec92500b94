/* test_materials.c -- glTF metallic-roughness materials end to end, against independent answers:
 * the glTF reader on the generated material_room (every field by name, as its .gltf writes it), an
 * OBJ/MTL map_Kd read into the same model (a texture with alpha is a MASK cut-out, a missing one a
 * warning), a leaf card's cut-outs as holes in its shadow for every method with visibility (the
 * lit fraction of the shadow against the texture's own fraction of alpha below the cutoff), and pt
 * on a GGX plane against the BRDF of the glTF specification's appendix B written out here in double
 * (point light, sun, and an area light by quadrature). Scenes are written here (the room is read
 * from scenes/) and loaded for real. Figures are printed for the release notes. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/image.h"
#include "iir/method.h"
#include "iir/scene.h"
#include "iir/texture.h"
#include "radiosity/radiosity.h"
#include "surface.h"
#include "testutil.h"

static char tmp[512];

/* ======================== helpers ======================== */

static const iir_material *material_named(const iir_scene *s, const char *name)
{
    for (uint32_t i = 0; i < s->num_materials; i++)
        if (!strcmp(s->material_list[i].name, name)) return &s->material_list[i];
    fail_msg("no material named %s", name);
    return NULL;
}

static uint32_t material_index(const iir_scene *s, const char *name)
{
    return (uint32_t)(material_named(s, name) - s->material_list);
}

static bool near(double a, double b, double tol)
{
    return fabs(a - b) <= tol;
}

static bool near3(iir_vec3 a, double x, double y, double z, double tol)
{
    return near(a.x, x, tol) && near(a.y, y, tol) && near(a.z, z, tol);
}

static const iir_texture *tex_of(const iir_scene *s, const iir_texref *r)
{
    assert_true(r->texture >= 1 && r->texture <= s->num_textures);
    return s->textures[r->texture - 1];
}

static bool is_srgb(const iir_texture *t)
{
    char d[200];
    iir_texture_describe(t, d, sizeof d);
    return strstr(d, "sRGB") != NULL;
}

/* Copies file `from` to dir/name. */
static void copy_file(const char *from, const char *dir, const char *name)
{
    char to[1200];
    snprintf(to, sizeof to, "%s/%s", dir, name);
    FILE *in = fopen(from, "rb"), *out = fopen(to, "wb");
    assert_non_null(in);
    assert_non_null(out);
    char buf[8192];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, in)) > 0) assert_int_equal(fwrite(buf, 1, n, out), n);
    fclose(in);
    fclose(out);
}

#define LEAF_PNG IIR_SOURCE_DIR "/scenes/material_room/textures/leaf_basecolor.png"

/* Appends an OBJ quad c +- a +- b (normal a x b) in material mtl with texture coordinates: corner
 * c + s a + t b (s, t = +-1) gets vt ((s + 1) / 2, (t + 1) / 2), which is glTF's uv
 * ((s + 1) / 2, (1 - t) / 2) (OBJ's v grows up the image, glTF's down). */
static void write_uv_quad(FILE *f, const char *mtl, iir_vec3 c, iir_vec3 a, iir_vec3 b)
{
    static const int st[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
    fprintf(f, "usemtl %s\n", mtl);
    for (int k = 0; k < 4; k++) {
        iir_vec3 p =
            iir_add(c, iir_add(iir_scale(a, (float)st[k][0]), iir_scale(b, (float)st[k][1])));
        fprintf(f, "v %.9g %.9g %.9g\nvt %g %g\n", p.x, p.y, p.z, (st[k][0] + 1) / 2.0,
                (st[k][1] + 1) / 2.0);
    }
    fprintf(f, "f -4/-4 -3/-3 -2/-2 -1/-1\n");
}

/* Writes tmp/name.obj: mtllib name.mtl and one quad (c, a, b) per material, the k-th centred at
 * (2k, 0, 0). */
static void write_quad_row(const char *name, const char *const *mtls, int n, iir_vec3 a, iir_vec3 b)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.obj", tmp, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "mtllib %s.mtl\n", name);
    for (int k = 0; k < n; k++) write_uv_quad(f, mtls[k], iir_v3(2.f * (float)k, 0, 0), a, b);
    fclose(f);
}

/* glTF uv of point p on the quad (c, a, b) of write_uv_quad, a and b orthogonal. */
static iir_vec2 quad_uv(iir_vec3 p, iir_vec3 c, iir_vec3 a, iir_vec3 b)
{
    iir_vec3 d = iir_sub(p, c);
    double s = iir_dot(d, a) / iir_dot(a, a), t = iir_dot(d, b) / iir_dot(b, b);
    return iir_v2((float)((s + 1) / 2), (float)((1 - t) / 2));
}

/* Barycentrics (w1, w2) of uv in the texture-space triangle prim of s; false when outside. */
static bool uv_barycentrics(const iir_scene *s, uint32_t prim, iir_vec2 uv, float *u, float *v)
{
    const uint32_t *i = &s->indices[3 * (size_t)prim];
    iir_vec2 a = s->texcoords[i[0]], b = s->texcoords[i[1]], c = s->texcoords[i[2]];
    double e1x = b.x - a.x, e1y = b.y - a.y, e2x = c.x - a.x, e2y = c.y - a.y;
    double dx = uv.x - a.x, dy = uv.y - a.y, det = e1x * e2y - e2x * e1y;
    if (fabs(det) < 1e-12) return false;
    double w1 = (dx * e2y - e2x * dy) / det, w2 = (e1x * dy - dx * e1y) / det;
    *u = (float)w1, *v = (float)w2;
    return w1 >= -1e-6 && w2 >= -1e-6 && w1 + w2 <= 1 + 1e-6;
}

/* One frame of `method` with p at w x h, from the scene's own camera and lights (*ms: its time). */
static iir_image *render(const char *method, const iir_scene *s, const iir_rt *rt,
                         const iir_params *p, int w, int h, double *ms)
{
    iir_method *m = NULL;
    iir_error err = {0};
    if (iir_method_create(method, s, rt, p, &m, &err) != IIR_OK)
        fail_msg("%s: %s", method, err.msg);
    iir_image *img = iir_image_create(w, h);
    iir_view v = {s->lights, s->num_lights, s->camera};
    iir_frame_stats fs;
    iir_test_render(m, &v, img, &fs);
    if (ms) *ms = fs.total_ms;
    iir_method_destroy(m);
    return img;
}

/* ======================== 1. the glTF reader on material_room ======================== */

static void test_gltf_material_room(void **state)
{
    (void)state;
    iir_scene *s = NULL;
    iir_error err = {0};
    if (iir_scene_load(IIR_SOURCE_DIR "/scenes/material_room", &s, &err) != IIR_OK)
        fail_msg("%s", err.msg);
    const float tol = 1e-6f;

    /* floor_wood: no baseColorFactor (the spec's default 1), roughness 0.6, metallic 0, its
       texture scaled 3 x 3 by KHR_texture_transform, sampler REPEAT with LINEAR_MIPMAP_LINEAR */
    const iir_material *floor = material_named(s, "floor_wood");
    assert_int_equal(floor->kind, IIR_MATERIAL_METAL_ROUGH);
    assert_true(floor->base_tex.texture != 0);
    assert_true(near3(floor->albedo, 1, 1, 1, tol));
    assert_true(near(floor->roughness, 0.6, tol));
    assert_true(near(floor->metallic, 0, tol));
    assert_true(near(floor->base_tex.transform.scale.x, 3, tol));
    assert_true(near(floor->base_tex.transform.scale.y, 3, tol));
    assert_true(near(floor->base_tex.transform.offset.x, 0, tol));
    assert_true(near(floor->base_tex.transform.offset.y, 0, tol));
    assert_true(near(floor->base_tex.transform.rotation, 0, tol));
    assert_int_equal(floor->base_tex.sampler.wrap_s, IIR_WRAP_REPEAT);
    assert_int_equal(floor->base_tex.sampler.wrap_t, IIR_WRAP_REPEAT);
    assert_false(floor->base_tex.sampler.min_no_mip);
    assert_false(floor->base_tex.sampler.mag_nearest);
    assert_int_equal(floor->alpha_mode, IIR_ALPHA_OPAQUE);
    assert_true(is_srgb(tex_of(s, &floor->base_tex)));

    /* brick_wall: base colour and a normal map of scale 1; the mesh gives tangents */
    const iir_material *brick = material_named(s, "brick_wall");
    assert_int_equal(brick->kind, IIR_MATERIAL_METAL_ROUGH);
    assert_true(brick->normal_tex.texture != 0);
    assert_true(brick->base_tex.texture != 0);
    assert_true(near(brick->normal_scale, 1, tol));
    assert_true(near(brick->roughness, 0.85, tol));
    assert_false(is_srgb(tex_of(s, &brick->normal_tex)));
    assert_true(is_srgb(tex_of(s, &brick->base_tex)));
    assert_non_null(s->tangents);

    /* leaves: MASK at 0.5, an RGBA texture */
    const iir_material *leaves = material_named(s, "leaves");
    assert_int_equal(leaves->alpha_mode, IIR_ALPHA_MASK);
    assert_true(near(leaves->alpha_cutoff, 0.5, tol));
    assert_true(near(leaves->roughness, 0.7, tol));
    assert_true(iir_texture_has_alpha(tex_of(s, &leaves->base_tex)));
    assert_true(iir_scene_has_cutouts(s));

    /* sign: emissiveFactor 1 x KHR_materials_emissive_strength 5, an sRGB emissive texture */
    const iir_material *sign = material_named(s, "sign");
    assert_true(sign->emission_tex.texture != 0);
    assert_true(near3(sign->emission, 5, 5, 5, 1e-5));
    assert_true(near3(sign->albedo, 0.02, 0.02, 0.02, tol));
    assert_true(is_srgb(tex_of(s, &sign->emission_tex)));

    /* the copper spheres: metallic 1, base (0.95, 0.64, 0.54); the red dielectrics metallic 0 */
    static const char *const metals[] = {"metal_r0.05", "metal_r0.25", "metal_r0.50", "metal_r0.75",
                                         "metal_r1.00"};
    static const double rough[] = {0.05, 0.25, 0.5, 0.75, 1.0};
    for (int k = 0; k < 5; k++) {
        const iir_material *m = material_named(s, metals[k]);
        assert_int_equal(m->kind, IIR_MATERIAL_METAL_ROUGH);
        assert_true(near(m->metallic, 1, tol));
        assert_true(near(m->roughness, rough[k], tol));
        assert_true(near3(m->albedo, 0.95, 0.64, 0.54, tol));
        char name[32];
        snprintf(name, sizeof name, "dielectric_r%.2f", rough[k]);
        const iir_material *d = material_named(s, name);
        assert_true(near(d->metallic, 0, tol));
        assert_true(near(d->roughness, rough[k], tol));
        assert_true(near3(d->albedo, 0.8, 0.1, 0.1, tol));
    }

    /* the striped box: a linear metallic-roughness texture under factors 1, base 0.8 */
    const iir_material *stripes = material_named(s, "metal_rough_stripes");
    assert_true(stripes->mr_tex.texture != 0);
    assert_false(is_srgb(tex_of(s, &stripes->mr_tex)));
    assert_true(near(stripes->metallic, 1, tol) && near(stripes->roughness, 1, tol));
    assert_true(near3(stripes->albedo, 0.8, 0.8, 0.8, tol));

    assert_non_null(s->texcoords);
    assert_non_null(s->vertex_normals);

    /* Six (image, colour space) pairs: floor, brick, leaf and sign colour (sRGB), the brick
       normals and the stripes (linear); every one used by some material, none twice. */
    bool used[64] = {false};
    assert_true(s->num_textures <= 64);
    for (uint32_t i = 0; i < s->num_materials; i++) {
        const iir_material *m = &s->material_list[i];
        const iir_texref *r[4] = {&m->base_tex, &m->mr_tex, &m->normal_tex, &m->emission_tex};
        for (int k = 0; k < 4; k++)
            if (r[k]->texture) {
                assert_true(r[k]->texture <= s->num_textures);
                used[r[k]->texture - 1] = true;
            }
    }
    uint32_t n_used = 0;
    for (uint32_t i = 0; i < s->num_textures; i++) n_used += used[i];
    assert_int_equal(n_used, s->num_textures);
    assert_int_equal(s->num_textures, 6);
    const iir_texture *ids[6] = {tex_of(s, &floor->base_tex),   tex_of(s, &brick->base_tex),
                                 tex_of(s, &brick->normal_tex), tex_of(s, &stripes->mr_tex),
                                 tex_of(s, &leaves->base_tex),  tex_of(s, &sign->emission_tex)};
    for (int a = 0; a < 6; a++)
        for (int b = a + 1; b < 6; b++) assert_ptr_not_equal(ids[a], ids[b]);

    /* nothing the loader could not read */
    for (uint32_t i = 0; i < s->num_dropped; i++)
        assert_null(strstr(s->dropped[i].what, "cannot be read"));

    print_message("material_room: %u triangles, %u materials, %u textures, %u notes\n",
                  s->num_triangles, s->num_materials, s->num_textures, s->num_dropped);
    for (uint32_t i = 0; i < s->num_textures; i++) {
        char d[200];
        iir_texture_describe(s->textures[i], d, sizeof d);
        print_message("  texture %u: %s\n", i + 1, d);
    }
    for (uint32_t i = 0; i < s->num_dropped; i++)
        print_message("  note on %s %s: %s\n", s->dropped[i].kind, s->dropped[i].name,
                      s->dropped[i].what);
    iir_scene_destroy(s);
}

/* ======================== 2. OBJ/MTL map_Kd into the same model ======================== */

static void test_obj_map_kd(void **state)
{
    (void)state;
    copy_file(LEAF_PNG, tmp, "leaf_basecolor.png");
    copy_file(IIR_SOURCE_DIR "/scenes/material_room/textures/brick_normal.png", tmp,
              "brick_normal.png");
    iir_test_write_file(tmp, "cards.mtl",
                        "newmtl leaf\nKd 1 1 1\nmap_Kd leaf_basecolor.png\n"
                        "newmtl missing\nKd 0.5 0.5 0.5\nmap_Kd missing.png\n"
                        "newmtl brass\nKd 0.9 0.7 0.3\nPr 0.35\nPm 1\n"
                        "newmtl phong\nKd 0.5 0.5 0.5\nKs 0.2 0.2 0.2\nNs 40\n"
                        "newmtl bumpy\nKd 0.7 0.7 0.7\nmap_Bump -bm 0.5 brick_normal.png\n");
    const iir_vec3 c = iir_v3(0, 0, 0), a = iir_v3(0, 0, 0.5f), b = iir_v3(0.5f, 0, 0);
    static const char *const mtls[] = {"leaf", "missing", "brass", "phong", "bumpy"};
    write_quad_row("cards", mtls, 5, a, b);
    iir_test_cornell l = iir_test_load(tmp, "cards");
    const iir_scene *s = l.scene;

    const iir_material *leaf = material_named(s, "leaf");
    assert_true(leaf->base_tex.texture != 0);
    assert_int_equal(leaf->alpha_mode, IIR_ALPHA_MASK);
    assert_true(near(leaf->alpha_cutoff, 0.5, 1e-6));
    assert_true(near3(leaf->albedo, 1, 1, 1, 1e-6));
    const iir_texture *tex = tex_of(s, &leaf->base_tex);
    assert_true(iir_texture_has_alpha(tex));
    assert_true(is_srgb(tex));

    /* MTL's PBR extension (Pr, Pm) is glTF's model with base colour Kd; plain Phong stays Lambert
     */
    const iir_material *brass = material_named(s, "brass");
    assert_int_equal(brass->kind, IIR_MATERIAL_METAL_ROUGH);
    assert_true(near(brass->roughness, 0.35, 1e-6) && near(brass->metallic, 1, 1e-6));
    assert_true(near3(brass->albedo, 0.9, 0.7, 0.3, 1e-6));
    /* a Phong highlight as Blender's importer reads it: Ks 0.2, Ns 40 -> reflectance 0.08 x 0.2
       at normal incidence, roughness 1 - sqrt(40 / 1000) = 0.8 */
    const iir_material *phong = material_named(s, "phong");
    assert_int_equal(phong->kind, IIR_MATERIAL_METAL_ROUGH);
    assert_true(near(phong->specular_f0, 0.016, 1e-6) && near(phong->metallic, 0, 0));
    assert_true(near(phong->roughness, 0.8, 1e-6));
    assert_true(near3(phong->albedo, 0.5, 0.5, 0.5, 1e-6));
    assert_true(near(brass->specular_f0, 0.04, 1e-6)); /* Pr/Pm: glTF's dielectric */
    /* map_Bump as Blender writes it: a tangent-space normal map (linear) of strength -bm */
    const iir_material *bumpy = material_named(s, "bumpy");
    assert_true(bumpy->normal_tex.texture != 0);
    assert_false(is_srgb(tex_of(s, &bumpy->normal_tex)));
    assert_true(near(bumpy->normal_scale, 0.5, 1e-6));

    const iir_material *missing = material_named(s, "missing");
    assert_int_equal(missing->base_tex.texture, 0);
    assert_int_equal(missing->alpha_mode, IIR_ALPHA_OPAQUE);
    int noted = -1;
    for (uint32_t i = 0; i < s->num_dropped; i++) {
        const iir_dropped *d = &s->dropped[i];
        if (!strcmp(d->kind, "material") && !strcmp(d->name, "missing") &&
            strstr(d->what, "missing.png"))
            noted = (int)i;
    }
    if (noted < 0) fail_msg("no note on material 'missing' naming missing.png");
    print_message("missing texture: \"%s\"\n", s->dropped[noted].what);

    /* texture coordinates in glTF's convention: vt (x, y) becomes (x, 1 - y) */
    assert_non_null(s->texcoords);
    uint32_t mleaf = material_index(s, "leaf");
    for (uint32_t t = 0; t < s->num_triangles; t++) {
        if (s->materials[t] != mleaf) continue;
        for (int k = 0; k < 3; k++) {
            uint32_t i = s->indices[3 * t + k];
            iir_vec2 want = quad_uv(s->positions[i], c, a, b), got = s->texcoords[i];
            assert_true(near(got.x, want.x, 1e-6) && near(got.y, want.y, 1e-6));
        }
    }

    /* Coverage at texel centres well inside a region of alpha 0 (a hole) and of alpha 1: every
       8th texel whose 5x5 neighbourhood is all 0 or all 1, mapped to the quad's barycentrics. */
    int w = iir_texture_width(tex), h = iir_texture_height(tex);
    int holes = 0, solid = 0, wrong = 0;
    for (int y = 2; y < h - 2; y += 8)
        for (int x = 2; x < w - 2; x += 8) {
            float lo = 1.f, hi = 0.f;
            for (int dy = -2; dy <= 2; dy++)
                for (int dx = -2; dx <= 2; dx++) {
                    float al = iir_texture_texel(tex, 0, x + dx, y + dy).a;
                    lo = fminf(lo, al), hi = fmaxf(hi, al);
                }
            if (!(hi == 0.f || lo == 1.f)) continue;
            iir_vec2 uv = iir_v2((x + 0.5f) / (float)w, (y + 0.5f) / (float)h);
            bool found = false;
            for (uint32_t t = 0; t < s->num_triangles && !found; t++) {
                float u, v;
                if (s->materials[t] != mleaf || !uv_barycentrics(s, t, uv, &u, &v)) continue;
                found = true;
                bool covers = iir_surface_covers(s, t, u, v);
                if (covers != (lo == 1.f)) wrong++;
            }
            assert_true(found);
            if (hi == 0.f)
                holes++;
            else
                solid++;
        }
    print_message("leaf quad coverage: %d hole texels, %d solid texels, %d wrong\n", holes, solid,
                  wrong);
    assert_true(holes >= 20 && solid >= 20);
    assert_int_equal(wrong, 0);
    /* the missing texture's quad is opaque everywhere */
    uint32_t mmiss = material_index(s, "missing");
    for (uint32_t t = 0; t < s->num_triangles; t++)
        if (s->materials[t] == mmiss) assert_true(iir_surface_covers(s, t, 0.3f, 0.3f));
    iir_test_unload(&l);
}

/* ======================== 3. cut-outs are holes for every ray ======================== */

/* A 4 x 4 floor (Kd 0.8), a 0.5 x 0.5 horizontal card at height CARD_Y (the leaf texture, or a
 * flat opaque material), a point light LIGHT to one side so the card's shadow falls beside it, and
 * a camera straight above the shadow. */
#define CARD_Y 0.5f
#define CARD_H 0.25f
#define FLOOR_RHO 0.8
#define LIGHT_I 2.0
static const iir_vec3 LIGHT = {-1.5f, 1.5f, 0.f};

static void write_card_scene(const char *name, const char *card_mtl)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.obj", tmp, name);
    FILE *f = fopen(path, "w");
    assert_non_null(f);
    fprintf(f, "mtllib card.mtl\n");
    iir_test_write_quad(f, "floor", iir_v3(0.5f, 0, 0), iir_v3(0, 0, 2), iir_v3(2, 0, 0));
    write_uv_quad(f, card_mtl, iir_v3(0, CARD_Y, 0), iir_v3(0, 0, CARD_H), iir_v3(CARD_H, 0, 0));
    fclose(f);
    char sidecar[200], text[600];
    snprintf(sidecar, sizeof sidecar, "%s.scene.json", name);
    snprintf(text, sizeof text,
             "{\"camera\": {\"position\": [0.75, 2.5, 0], \"target\": [0.75, 0, 0], "
             "\"up\": [0, 0, -1], \"fov_y\": 30},\n"
             " \"lights\": [{\"type\": \"point\", \"name\": \"bulb\", \"position\": [%g, %g, %g], "
             "\"intensity\": %g}]}\n",
             LIGHT.x, LIGHT.y, LIGHT.z, LIGHT_I);
    iir_test_write_file(tmp, sidecar, text);
}

/* The floor point below card point p as seen from the light, and back. */
static iir_vec3 to_floor(iir_vec3 p)
{
    return iir_madd(LIGHT, iir_sub(p, LIGHT), LIGHT.y / (LIGHT.y - p.y));
}
static iir_vec3 to_card(iir_vec3 x)
{
    return iir_madd(LIGHT, iir_sub(x, LIGHT), (LIGHT.y - CARD_Y) / LIGHT.y);
}

typedef struct shadow_geo {
    int w, h;
    float lo_x, hi_x, lo_z, hi_z; /* the shadow rectangle on the floor */
    signed char *region;          /* per pixel: 1 inside the shadow, 0 unshadowed floor, -1 skip */
    double *direct;               /* per pixel: unshadowed direct radiance at its floor point */
    bool *blocked;                /* per pixel: the card's alpha >= 0.5 at its shadow point */
    float margin;                 /* pixels this close to the shadow's edge are not counted */
    int n_shadow, n_lit;
} shadow_geo;

/* Classifies the pixel centres of the scene's camera: inside the shadow rectangle shrunk by a
 * margin, or floor outside it grown by the margin and not behind the card. */
static shadow_geo shadow_geometry(const iir_scene *s, const iir_texture *leaf, int w, int h)
{
    shadow_geo g = {w, h, 1e9f, -1e9f, 1e9f, -1e9f, NULL, NULL, NULL, 0.03f, 0, 0};
    for (int k = 0; k < 4; k++) {
        iir_vec3 corner = iir_v3(k & 1 ? CARD_H : -CARD_H, CARD_Y, k & 2 ? CARD_H : -CARD_H);
        iir_vec3 x = to_floor(corner);
        g.lo_x = fminf(g.lo_x, x.x), g.hi_x = fmaxf(g.hi_x, x.x);
        g.lo_z = fminf(g.lo_z, x.z), g.hi_z = fmaxf(g.hi_z, x.z);
    }
    g.region = malloc((size_t)w * h);
    g.direct = malloc(sizeof(double) * w * h);
    g.blocked = malloc(sizeof(bool) * w * h);
    iir_camera_frame cf = iir_camera_setup(&s->camera, w, h);
    const float margin = g.margin;
    const iir_vec3 c = iir_v3(0, CARD_Y, 0), a = iir_v3(0, 0, CARD_H), b = iir_v3(CARD_H, 0, 0);
    for (int py = 0; py < h; py++)
        for (int px = 0; px < w; px++) {
            int i = py * w + px;
            iir_vec3 d = iir_camera_dir(&cf, px + 0.5f, py + 0.5f);
            iir_vec3 x = iir_madd(cf.origin, d, -cf.origin.y / d.y);
            iir_vec3 on_card = iir_madd(cf.origin, d, (CARD_Y - cf.origin.y) / d.y);
            double r2 = iir_length_sq(iir_sub(x, LIGHT)), cos_x = LIGHT.y / sqrt(r2);
            g.direct[i] = FLOOR_RHO / M_PI * LIGHT_I * cos_x / r2;
            iir_vec2 uv = quad_uv(to_card(x), c, a, b);
            g.blocked[i] = iir_texture_bilinear(leaf, NULL, uv, 0).a >= 0.5f;
            bool in = x.x > g.lo_x + margin && x.x < g.hi_x - margin && x.z > g.lo_z + margin &&
                      x.z < g.hi_z - margin;
            bool out = x.x < g.lo_x - margin || x.x > g.hi_x + margin || x.z < g.lo_z - margin ||
                       x.z > g.hi_z + margin;
            bool behind_card =
                fabsf(on_card.x) < CARD_H + margin && fabsf(on_card.z) < CARD_H + margin;
            g.region[i] = behind_card ? -1 : in ? 1 : out ? 0 : -1;
            g.n_shadow += g.region[i] == 1;
            g.n_lit += g.region[i] == 0;
        }
    return g;
}

static void shadow_geo_free(shadow_geo *g)
{
    free(g->region);
    free(g->direct);
    free(g->blocked);
}

/* What a render shows of the shadow: the fraction of shadow pixels lit -- brighter (relative to
 * the unshadowed direct light at the pixel) than half the unshadowed floor's mean of the same
 * measure (gain) -- and how many shadow pixels disagree with the texture at their centres. */
typedef struct shadow_measure {
    double lit, gain;
    int mismatched;
} shadow_measure;

static shadow_measure measure_shadow(const shadow_geo *g, const iir_image *img)
{
    shadow_measure r = {0, 0, 0};
    for (int i = 0; i < g->w * g->h; i++)
        if (g->region[i] == 0) r.gain += iir_luminance(img->pixels[i]) / g->direct[i];
    r.gain /= g->n_lit;
    int lit = 0;
    for (int i = 0; i < g->w * g->h; i++) {
        if (g->region[i] != 1) continue;
        bool is_lit = iir_luminance(img->pixels[i]) / g->direct[i] > 0.5 * r.gain;
        lit += is_lit;
        r.mismatched += is_lit == g->blocked[i];
    }
    r.lit = (double)lit / g->n_shadow;
    return r;
}

/* The fraction of the card's part s in [s0, s1], t in [t0, t1] (write_uv_quad's coordinates)
 * where the texture's alpha is below 0.5: a 1024 x 1024 grid of bilinear lookups. */
static double open_fraction(const iir_texture *leaf, double s0, double s1, double t0, double t1)
{
    enum { G = 1024 };
    int open = 0;
    for (int j = 0; j < G; j++)
        for (int i = 0; i < G; i++) {
            double s = s0 + (s1 - s0) * (i + 0.5) / G, t = t0 + (t1 - t0) * (j + 0.5) / G;
            iir_vec2 uv = iir_v2((float)((s + 1) / 2), (float)((1 - t) / 2));
            open += iir_texture_bilinear(leaf, NULL, uv, 0).a < 0.5f;
        }
    return (double)open / (G * G);
}

static void test_cutout_shadows(void **state)
{
    (void)state;
    copy_file(LEAF_PNG, tmp, "leaf_basecolor.png");
    iir_test_write_file(tmp, "card.mtl",
                        "newmtl floor\nKd 0.8 0.8 0.8\n"
                        "newmtl leaf\nKd 1 1 1\nmap_Kd leaf_basecolor.png\n"
                        "newmtl solid\nKd 0.8 0.8 0.8\n");
    write_card_scene("leafcard", "leaf");
    write_card_scene("solidcard", "solid");

    iir_texture *leaf = NULL;
    iir_error err = {0};
    if (iir_texture_read(LEAF_PNG, true, &leaf, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_test_cornell lc = iir_test_load(tmp, "leafcard"), sc = iir_test_load(tmp, "solidcard");
    assert_int_equal(material_named(lc.scene, "leaf")->alpha_mode, IIR_ALPHA_MASK);
    assert_int_equal(material_named(sc.scene, "solid")->alpha_mode, IIR_ALPHA_OPAQUE);
    /* radiosity's cached form factors are keyed by what they see through: the cut-out's cutoff
       and texture; the same geometry without cut-outs keeps its geometry-only key */
    {
        iir_material *leafm = (iir_material *)material_named(lc.scene, "leaf");
        uint64_t k0 = rad_ff_key(lc.scene, 0.01f, 16);
        leafm->alpha_cutoff = 0.25f;
        uint64_t k1 = rad_ff_key(lc.scene, 0.01f, 16);
        leafm->alpha_cutoff = 0.5f;
        assert_true(k0 != k1);
        assert_true(rad_ff_key(lc.scene, 0.01f, 16) == k0);
        leafm->alpha_mode = IIR_ALPHA_OPAQUE;
        uint64_t opaque = rad_ff_key(lc.scene, 0.01f, 16);
        leafm->alpha_mode = IIR_ALPHA_MASK;
        assert_true(opaque != k0);
        assert_true(opaque == rad_ff_key(sc.scene, 0.01f, 16)); /* positions alike, no cut-out */
    }
    enum { W = 96, H = 96 };
    shadow_geo g = shadow_geometry(lc.scene, leaf, W, H);
    /* The expected lit fraction: the card's area where the texture's alpha is below 0.5, over the
       whole card and over the part whose shadow the counted pixels cover (the projection from the
       light onto the parallel floor keeps area fractions). */
    double expect_card = open_fraction(leaf, -1, 1, -1, 1);
    iir_vec3 lo = to_card(iir_v3(g.lo_x + g.margin, 0, g.lo_z + g.margin));
    iir_vec3 hi = to_card(iir_v3(g.hi_x - g.margin, 0, g.hi_z - g.margin));
    double expect = open_fraction(leaf, lo.z / CARD_H, hi.z / CARD_H, lo.x / CARD_H, hi.x / CARD_H);
    int blocked = 0;
    for (int i = 0; i < W * H; i++) blocked += g.region[i] == 1 && g.blocked[i];
    double expect_px = 1.0 - (double)blocked / g.n_shadow;
    print_message("leaf card: shadow [%.3f, %.3f] x [%.3f, %.3f]; %d shadow pixels (%.2f from "
                  "its edges) and %d unshadowed; lit fraction expected %.4f (alpha < 0.5 on the "
                  "card's part they see; %.4f on the whole card; %.4f at the pixel centres)\n",
                  g.lo_x, g.hi_x, g.lo_z, g.hi_z, g.n_shadow, g.margin, g.n_lit, expect,
                  expect_card, expect_px);
    assert_true(g.n_shadow > 1500 && g.n_lit > 1500);
    assert_true(expect > 0.2 && expect < 0.95); /* a card with holes and leaves */

    static const char *const methods[] = {"pt",        "whitted", "ir",  "iir", "rsm",
                                          "radiosity", "hybrid",  "ism", "hier"};
    enum { NM = sizeof methods / sizeof methods[0] };
    shadow_measure got[NM], opaque[NM];
    for (int k = 0; k < NM; k++) {
        iir_params p = iir_params_default();
        if (!strcmp(methods[k], "pt")) {
            iir_test_set(&p, "spp", 16);
            iir_test_set(&p, "bounces", 1);
        }
        double ms_leaf, ms_solid;
        iir_image *img = render(methods[k], lc.scene, lc.rt, &p, W, H, &ms_leaf);
        got[k] = measure_shadow(&g, img);
        iir_image_destroy(img);
        img = render(methods[k], sc.scene, sc.rt, &p, W, H, &ms_solid);
        opaque[k] = measure_shadow(&g, img);
        iir_image_destroy(img);
        print_message("  %-9s lit fraction %.4f (expected %.4f, diff %+.4f; %d of %d pixels "
                      "disagree with the texture); opaque card %.4f; unshadowed floor / direct "
                      "light %.3f; %.0f + %.0f ms\n",
                      methods[k], got[k].lit, expect, got[k].lit - expect, got[k].mismatched,
                      g.n_shadow, opaque[k].lit, got[k].gain, ms_leaf, ms_solid);
    }
    for (int k = 0; k < NM; k++) {
        /* every method lights the unshadowed floor as the direct light alone (nothing bounces
           back to a floor under an open sky but off the card's underside) */
        if (fabs(got[k].gain - 1) > 0.05 || fabs(opaque[k].gain - 1) > 0.05)
            fail_msg("%s: unshadowed floor %.3f and %.3f times its direct light", methods[k],
                     got[k].gain, opaque[k].gain);
        if (opaque[k].lit >= 0.05)
            fail_msg("%s: lit fraction %.4f under an opaque card", methods[k], opaque[k].lit);
        /* ism's ISMs serve only the bounce (its direct light has shadow rays): as exact as pt.
           hier's direct light is shadowed by its voxel grid (voxel_res 128: cells of 3 cm), whose
           cut-out cells are solid where the card covers half of them, and a shadow segment
           crossing the card's layer obliquely meets two or three cells: holes at cell
           resolution, narrowed; 0.15 bounds that (0 would mean no holes). */
        double tol = !strcmp(methods[k], "hier") ? 0.15 : 0.08;
        if (fabs(got[k].lit - expect) > tol)
            fail_msg("%s: lit fraction %.4f of the leaf card's shadow, expected %.4f", methods[k],
                     got[k].lit, expect);
    }
    iir_texture_destroy(leaf);
    shadow_geo_free(&g);
    iir_test_unload(&lc);
    iir_test_unload(&sc);
}

/* ======================== 4. pt on a GGX plane ======================== */

/* glTF 2.0 specification, appendix B, independently of bsdf.c (testutil.h). n = +y. */
typedef struct ggx_mat {
    double base, metallic, roughness; /* grey base colour */
} ggx_mat;

static double brdf(const ggx_mat *m, const double wo[3], const double wi[3])
{
    return iir_test_gltf_brdf(m->base, m->metallic, m->roughness, wo, wi);
}

/* A 20 x 20 plane at y = 0 facing +y, one metallic-roughness material (no textures). */
static void write_plane(const char *name, const ggx_mat *m, const char *light)
{
    char text[4096], file[128];
    snprintf(
        text, sizeof text,
        "{\"asset\": {\"version\": \"2.0\"},\n"
        " \"scene\": 0, \"scenes\": [{\"nodes\": [0]}],\n"
        " \"nodes\": [{\"mesh\": 0, \"name\": \"plane\", \"scale\": [10, 1, 10]}],\n"
        " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1,\n"
        "   \"material\": 0}]}],\n"
        " \"materials\": [{\"name\": \"ggx\", \"pbrMetallicRoughness\": {\n"
        "   \"baseColorFactor\": [%g, %g, %g, 1], \"metallicFactor\": %g, \"roughnessFactor\": "
        "%g}}],\n" IIR_TEST_GLTF_QUAD_DATA,
        m->base, m->base, m->base, m->metallic, m->roughness);
    snprintf(file, sizeof file, "%s.gltf", name);
    iir_test_write_file(tmp, file, text);
    snprintf(text, sizeof text,
             "{\"file\": \"%s.gltf\",\n"
             " \"camera\": {\"position\": [0, 1.5, 3], \"target\": [0, 0, 0.3], \"fov_y\": 40},\n"
             " \"lights\": [%s]}\n",
             name, light);
    snprintf(file, sizeof file, "%s.scene.json", name);
    iir_test_write_file(tmp, file, text);
}

enum { PW = 24, PH = 24 };

/* Renders tmp/name.scene.json with method (pt: direct light only; every method at pixel
 * centres). A single plane reflects no light onto itself: a VPL method's indirect light is 0. */
static iir_image *render_plane(const char *method, const char *name, const ggx_mat *m, int spp,
                               iir_scene **scene)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/%s.scene.json", tmp, name);
    iir_scene *s = NULL;
    iir_rt *rt = NULL;
    iir_error err = {0};
    if (iir_scene_open(path, NULL, &s, &rt, &err) != IIR_OK) fail_msg("%s", err.msg);
    const iir_material *mat = material_named(s, "ggx");
    assert_int_equal(mat->kind, IIR_MATERIAL_METAL_ROUGH);
    assert_true(near(mat->metallic, m->metallic, 1e-6) && near(mat->roughness, m->roughness, 1e-6));
    iir_params p = iir_params_default();
    if (!strcmp(method, "pt")) {
        iir_test_set(&p, "spp", spp);
        iir_test_set(&p, "bounces", 1);
    }
    iir_test_set(&p, "jitter", 0);
    iir_test_set(&p, "seed", 7);
    iir_image *img = render(method, s, rt, &p, PW, PH, NULL);
    iir_rt_destroy(rt);
    *scene = s;
    return img;
}

/* The light a lamp sends to the camera from the plane at pixel (px, py)'s centre. */
typedef double (*lamp_fn)(const ggx_mat *m, const double x[3], const double wo[3]);

static double point_lamp(const ggx_mat *m, const double x[3], const double wo[3])
{
    const double P[3] = {0.2, 1.0, -1.0}, I = 3.0;
    double d[3] = {P[0] - x[0], P[1] - x[1], P[2] - x[2]};
    double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], r = sqrt(r2);
    double wi[3] = {d[0] / r, d[1] / r, d[2] / r};
    return brdf(m, wo, wi) * I * wi[1] / r2;
}

static double sun_lamp(const ggx_mat *m, const double x[3], const double wo[3])
{
    (void)x;
    const double E = 2.0, t[3] = {0.3, -1.0, 0.4}; /* the way the light travels */
    double l = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    double wi[3] = {-t[0] / l, -t[1] / l, -t[2] / l};
    return brdf(m, wo, wi) * E * wi[1];
}

/* A 0.6 x 0.6 square of radiance 4 at height 1, centred at (0.2, 1, -0.8), facing down:
 * integral of f L cos_x cos_l / d^2 over it, 200 x 200 midpoint rule. */
static double area_lamp(const ggx_mat *m, const double x[3], const double wo[3])
{
    enum { Q = 200 };
    const double L = 4.0, side = 0.6, c[3] = {0.2, 1.0, -0.8}, dA = (side / Q) * (side / Q);
    double sum = 0;
    for (int j = 0; j < Q; j++)
        for (int i = 0; i < Q; i++) {
            double y[3] = {c[0] - side / 2 + (i + 0.5) * side / Q, c[1],
                           c[2] - side / 2 + (j + 0.5) * side / Q};
            double d[3] = {y[0] - x[0], y[1] - x[1], y[2] - x[2]};
            double r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2], r = sqrt(r2);
            double wi[3] = {d[0] / r, d[1] / r, d[2] / r};
            sum += brdf(m, wo, wi) * L * wi[1] * wi[1] / r2 * dA; /* cos_l = wi.y too */
        }
    return sum;
}

/* pt against the lamp's expected radiance within 2%: every pixel (a deterministic estimate for a
 * point light or sun, whose light is one shadow ray) and the mean over the image (for an area
 * light only the mean: MIS of light and BSDF samples is noisy per pixel). */
static void check_plane(const char *method, const char *name, const ggx_mat *m,
                        const char *light_json, lamp_fn lamp, int spp, bool per_pixel)
{
    write_plane(name, m, light_json);
    iir_scene *s = NULL;
    iir_image *img = render_plane(method, name, m, spp, &s);
    iir_camera_frame cf = iir_camera_setup(&s->camera, PW, PH);
    double worst = 0, sum_got = 0, sum_want = 0, peak = 0;
    for (int py = 0; py < PH; py++)
        for (int px = 0; px < PW; px++) {
            iir_vec3 d = iir_camera_dir(&cf, px + 0.5f, py + 0.5f);
            assert_true(d.y < 0.f);
            double t = -(double)cf.origin.y / d.y;
            double x[3] = {cf.origin.x + t * d.x, 0.0, cf.origin.z + t * d.z};
            double dl = sqrt((double)d.x * d.x + (double)d.y * d.y + (double)d.z * d.z);
            double wo[3] = {-d.x / dl, -d.y / dl, -d.z / dl};
            double want = lamp(m, x, wo), got = img->pixels[py * PW + px].x;
            /* grey: every channel alike */
            assert_true(near(img->pixels[py * PW + px].y, got, 1e-5 * (1 + got)));
            sum_got += got, sum_want += want;
            peak = fmax(peak, want);
            double rel = fabs(got - want) / fmax(want, 1e-12);
            if (per_pixel && rel > worst) worst = rel;
            if (per_pixel && rel > 0.02)
                fail_msg("%s %s: pixel (%d, %d): %.6g, appendix B %.6g (%.2f%%)", method, name, px,
                         py, got, want, 100 * rel);
        }
    double rel_mean = fabs(sum_got - sum_want) / sum_want;
    char worst_text[64] = "";
    if (per_pixel) snprintf(worst_text, sizeof worst_text, ", worst pixel %.4f%%", 100 * worst);
    print_message("  %-7s %-12s metallic %g base %g roughness %g: mean %.6f, expected %.6f "
                  "(%.3f%%), peak %.4f%s\n",
                  method, name, m->metallic, m->base, m->roughness, sum_got / (PW * PH),
                  sum_want / (PW * PH), 100 * rel_mean, peak, worst_text);
    if (rel_mean > 0.02)
        fail_msg("%s %s: mean %.6f, expected %.6f", method, name, sum_got / (PW * PH),
                 sum_want / (PW * PH));
    iir_image_destroy(img);
    iir_scene_destroy(s);
}

static void test_ggx_plane(void **state)
{
    (void)state;
    const ggx_mat metal = {0.9, 1.0, 0.3}, plastic = {0.5, 0.0, 0.5};
    const char *point = "{\"type\": \"point\", \"position\": [0.2, 1, -1], \"intensity\": 3}";
    const char *sun = "{\"type\": \"sun\", \"direction\": [0.3, -1, 0.4], \"intensity\": 2}";
    const char *area = "{\"type\": \"area\", \"position\": [0.2, 1, -0.8], \"direction\": [0, -1, "
                       "0], \"up\": [0, 0, 1], \"size\": [0.6, 0.6], \"intensity\": 4}";
    check_plane("pt", "metal_point", &metal, point, point_lamp, 1, true);
    check_plane("pt", "plastic_point", &plastic, point, point_lamp, 1, true);
    check_plane("pt", "metal_sun", &metal, sun, sun_lamp, 1, true);
    check_plane("pt", "plastic_sun", &plastic, sun, sun_lamp, 1, true);
    check_plane("pt", "metal_area", &metal, area, area_lamp, 512, false);
    check_plane("pt", "plastic_area", &plastic, area, area_lamp, 512, false);
    /* the classic and VPL methods' direct light by the full BSDF (glossy highlights included) */
    static const char *const direct[] = {"whitted", "hybrid", "ir", "iir", "ism", "rsm"};
    for (size_t k = 0; k < sizeof direct / sizeof *direct; k++) {
        check_plane(direct[k], "metal_point", &metal, point, point_lamp, 1, true);
        check_plane(direct[k], "plastic_sun", &plastic, sun, sun_lamp, 1, true);
    }
}

/* A 4 x 4 PNG of one colour whose bytes are rgb (written through the sRGB encoder: the linear
 * values are the bytes decoded, so the file holds the bytes exactly). */
static void write_flat_png(const char *name, const int rgb[3])
{
    iir_image *img = iir_image_create(4, 4);
    assert_non_null(img);
    float lin[3];
    for (int k = 0; k < 3; k++) {
        double c = rgb[k] / 255.0;
        lin[k] = (float)(c <= 0.04045 ? c / 12.92 : pow((c + 0.055) / 1.055, 2.4));
    }
    for (int i = 0; i < 16; i++) img->pixels[i] = iir_v3(lin[0], lin[1], lin[2]);
    char path[1200];
    snprintf(path, sizeof path, "%s/%s", tmp, name);
    iir_error err = {0};
    assert_int_equal(iir_image_write_png(img, path, 0.f, &err), IIR_OK);
    iir_image_destroy(img);
}

/* The normal map's frame: a texel (x, y, z) tilts the shading normal towards +x along the
 * texture's u (dp/du) and +y up the image (glTF's convention: the bitangent points to decreasing
 * v), scaled by the map's strength; here on a quad lying in y = 0, u along +x, up the image -z. */
static void test_normal_map_frame(void **state)
{
    (void)state;
    const int tilt_u[3] = {191, 128, 255}, tilt_up[3] = {128, 191, 255};
    write_flat_png("tilt_u.png", tilt_u);
    write_flat_png("tilt_up.png", tilt_up);
    iir_test_write_file(tmp, "tilt.mtl",
                        "newmtl u\nKd 0.5 0.5 0.5\nnorm tilt_u.png\n"
                        "newmtl up\nKd 0.5 0.5 0.5\nnorm tilt_up.png\n"
                        "newmtl half\nKd 0.5 0.5 0.5\nmap_Bump -bm 0.5 tilt_u.png\n");
    const iir_vec3 a = iir_v3(0.5f, 0, 0), b = iir_v3(0, 0, -0.5f); /* normal a x b = +y */
    static const char *const mtls[] = {"u", "up", "half"};
    write_quad_row("tilt", mtls, 3, a, b);
    iir_test_cornell l = iir_test_load(tmp, "tilt");
    const iir_scene *s = l.scene;
    /* the texel (191, 128, 255): tangent-space (0.498, 0.004, 1) */
    const double x = 2 * 191 / 255.0 - 1, y0 = 2 * 128 / 255.0 - 1;
    struct {
        const char *mtl;
        double tx, ty; /* expected tangent-space x, y */
    } cases[] = {{"u", x, y0}, {"up", y0, x}, {"half", 0.5 * x, 0.5 * y0}};
    for (int c = 0; c < 3; c++) {
        uint32_t m = material_index(s, cases[c].mtl), prim = UINT32_MAX;
        for (uint32_t t = 0; t < s->num_triangles && prim == UINT32_MAX; t++)
            if (s->materials[t] == m) prim = t;
        assert_true(prim != UINT32_MAX);
        iir_hit hit = {1.f, prim, 1.f / 3.f, 1.f / 3.f};
        iir_surface sf = iir_surface_at(s, &hit, iir_v3(0, 1, 0));
        /* tangent space to world: x along +x (u), y along -z (up the image), z along +y */
        double len = sqrt(cases[c].tx * cases[c].tx + cases[c].ty * cases[c].ty + 1);
        iir_vec3 want =
            iir_v3((float)(cases[c].tx / len), (float)(1 / len), (float)(-cases[c].ty / len));
        print_message(
            "  normal map '%s': shading normal (%.4f, %.4f, %.4f), expected (%.4f, %.4f, %.4f)\n",
            cases[c].mtl, sf.sn.x, sf.sn.y, sf.sn.z, want.x, want.y, want.z);
        assert_true(near3(sf.sn, want.x, want.y, want.z, 2e-3));
        assert_true(near3(sf.ns, 0, 1, 0, 1e-6)); /* the geometric normal is untouched */
    }
    iir_test_unload(&l);

    /* a glTF's TANGENT (w = handedness, through assimp's bitangent) gives the frame its texture
       coordinates give: the material room's brick wall shaded with the file's tangents and with
       tangents from its uvs agrees */
    iir_scene *room = NULL;
    iir_error err = {0};
    if (iir_scene_load(IIR_SOURCE_DIR "/scenes/material_room", &room, &err) != IIR_OK)
        fail_msg("%s", err.msg);
    assert_non_null(room->tangents);
    uint32_t brick = material_index(room, "brick_wall"), checked = 0, bent = 0;
    static const float at[4][2] = {{0.3f, 0.3f}, {0.1f, 0.7f}, {0.6f, 0.2f}, {0.45f, 0.45f}};
    for (uint32_t t = 0; t < room->num_triangles; t++) {
        if (room->materials[t] != brick) continue;
        for (int k = 0; k < 4; k++) {
            iir_hit hit = {1.f, t, at[k][0], at[k][1]};
            iir_vec3 wo = room->normals[t];
            iir_surface with = iir_surface_at(room, &hit, wo);
            float *tangents = room->tangents;
            room->tangents = NULL;
            iir_surface without = iir_surface_at(room, &hit, wo);
            room->tangents = tangents;
            assert_true(near3(with.sn, without.sn.x, without.sn.y, without.sn.z, 1e-3));
            bent += iir_dot(with.sn, with.ns) < 0.9999f; /* the map does bend it somewhere */
            checked++;
        }
    }
    assert_true(checked >= 8 && bent > 0);
    iir_scene_destroy(room);
}

/* A floor and, 1 above it, a BLEND veil of alpha `alpha` (no texture). */
static void write_veil(const char *name, double alpha)
{
    char text[4096], file[128];
    snprintf(text, sizeof text,
             "{\"asset\": {\"version\": \"2.0\"},\n"
             " \"scene\": 0, \"scenes\": [{\"nodes\": [0, 1]}],\n"
             " \"nodes\": [{\"mesh\": 0, \"name\": \"floor\", \"scale\": [10, 1, 10]},\n"
             "   {\"mesh\": 1, \"name\": \"veil\", \"translation\": [0, 1, 0]}],\n"
             " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0}, "
             "\"indices\": 1, \"material\": 0}]},\n"
             "   {\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"indices\": 1, "
             "\"material\": 1}]}],\n"
             " \"materials\": [{\"name\": \"floor\"},\n"
             "   {\"name\": \"veil\", \"alphaMode\": \"BLEND\", \"doubleSided\": true,\n"
             "    \"pbrMetallicRoughness\": {\"baseColorFactor\": [1, 1, 1, "
             "%g]}}],\n" IIR_TEST_GLTF_QUAD_DATA,
             alpha);
    snprintf(file, sizeof file, "%s.gltf", name);
    iir_test_write_file(tmp, file, text);
}

/* alphaMode BLEND: pt's queries (iir_rt_occluded_blend) let a ray through with probability
 * 1 - alpha; the other queries treat it as a cut-out at 0.5. */
static void test_blend_veil(void **state)
{
    (void)state;
    static const double alphas[] = {0.3, 0.7};
    for (int a = 0; a < 2; a++) {
        char name[32], path[1200];
        snprintf(name, sizeof name, "veil%d", a);
        write_veil(name, alphas[a]);
        snprintf(path, sizeof path, "%s/%s.gltf", tmp, name);
        iir_scene *s = NULL;
        iir_rt *rt = NULL;
        iir_error err = {0};
        if (iir_scene_open(path, NULL, &s, &rt, &err) != IIR_OK) fail_msg("%s", err.msg);
        assert_int_equal(material_named(s, "veil")->alpha_mode, IIR_ALPHA_BLEND);
        iir_ray up = iir_make_ray(iir_v3(0.1f, 0.01f, 0.2f), iir_v3(0, 1, 0), 0.f, 5.f);
        enum { N = 20000 };
        int blocked = 0;
        for (uint64_t k = 0; k < N; k++)
            blocked += iir_rt_occluded_blend(rt, &up, k, NULL, IIR_RAYS_SHADOW);
        double frac = (double)blocked / N, sigma = sqrt(alphas[a] * (1 - alphas[a]) / N);
        print_message(
            "  BLEND alpha %.1f: %.4f of %d stochastic shadow rays blocked (4 sigma %.4f); "
            "the cut-out query: %s\n",
            alphas[a], frac, N, 4 * sigma,
            iir_rt_occluded(rt, &up, NULL, IIR_RAYS_SHADOW) ? "blocked" : "through");
        assert_true(fabs(frac - alphas[a]) < 4 * sigma);
        assert_int_equal(iir_rt_occluded(rt, &up, NULL, IIR_RAYS_SHADOW), alphas[a] >= 0.5);
        /* closest hits alike: the veil or the floor */
        int veil = 0;
        iir_ray down = iir_make_ray(iir_v3(0.1f, 2.f, 0.2f), iir_v3(0, -1, 0), 0.f, 5.f);
        for (uint64_t k = 0; k < N; k++) {
            iir_hit hit;
            assert_true(iir_rt_intersect_blend(rt, &down, k, &hit, NULL, IIR_RAYS_CAMERA));
            veil += fabsf(hit.t - 1.f) < 1e-3f;
        }
        assert_true(fabs((double)veil / N - alphas[a]) < 4 * sigma);
        iir_rt_destroy(rt);
        iir_scene_destroy(s);
    }
}

int main(void)
{
    snprintf(tmp, sizeof tmp, "%s", iir_test_tmpdir("materials"));
    char cache[700];
    snprintf(cache, sizeof cache, "%s/ffcache", tmp);
    setenv("IIR_CACHE_DIR", cache, 1); /* radiosity's form factors stay in the scratch folder */
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_gltf_material_room), cmocka_unit_test(test_obj_map_kd),
        cmocka_unit_test(test_cutout_shadows),     cmocka_unit_test(test_ggx_plane),
        cmocka_unit_test(test_blend_veil),         cmocka_unit_test(test_normal_map_frame),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

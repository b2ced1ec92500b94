/* scene_build.c -- the scene builder shared by every source: growing arrays, validation of what is
 * appended, and the finishing pass (degenerates, normals, areas, bounds, default camera); not file
 * formats (scene_assimp.c, scene_sidecar.c) and not the built-in box (scene_cornell.c). */
#include "scene_build.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A triangle is degenerate when its area is below this fraction of the squared bounding-box
 * diagonal: far below anything a renderer resolves (the conference room's smallest triangles,
 * real detail, are at 3e-13 and are kept), while a collapsed triangle, its cross product taken in
 * double from float vertices, comes out at or very near zero. */
#define DEGENERATE_REL_AREA 1e-14

/* ======================== growing arrays ======================== */

/* Ensures room for `need` elements of size `elem` in *p (capacity *cap). False on overflow or
 * allocation failure, with *p and *cap unchanged. */
static bool grow(void **p, uint32_t *cap, uint64_t need, size_t elem)
{
    if (need <= *cap) return true;
    if (need > UINT32_MAX) return false;
    uint64_t n = *cap ? *cap : 64;
    while (n < need) n *= 2;
    if (n > UINT32_MAX) n = UINT32_MAX;
    void *q = realloc(*p, (size_t)n * elem);
    if (!q) return false;
    *p = q;
    *cap = (uint32_t)n;
    return true;
}

static bool grow_triangles(iir_scene_builder *b, uint64_t need)
{
    if (need <= b->cap_triangles) return true;
    uint32_t cap_idx = b->cap_triangles, cap_mat = b->cap_triangles;
    /* indices hold 3 per triangle: grow them as triangles of 12 bytes */
    if (!grow((void **)&b->indices, &cap_idx, need, 3 * sizeof(uint32_t))) return false;
    if (!grow((void **)&b->tri_materials, &cap_mat, need, sizeof(uint32_t))) return false;
    b->cap_triangles = cap_idx < cap_mat ? cap_idx : cap_mat;
    return true;
}

static iir_status no_memory(const iir_scene_builder *b, iir_error *err)
{
    return iir_fail(err, IIR_ERR_NOMEM, "%s: out of memory while building the scene", b->source);
}

/* ======================== appending ======================== */

void iir_builder_init(iir_scene_builder *b, const char *name, const char *source)
{
    memset(b, 0, sizeof *b);
    iir_scene_strcpy(b->name, sizeof b->name, name);
    iir_scene_strcpy(b->source, sizeof b->source, source);
}

void iir_builder_free(iir_scene_builder *b)
{
    free(b->positions);
    free(b->vertex_normals);
    free(b->texcoords);
    free(b->tangents);
    b->vertex_normals = NULL;
    b->texcoords = NULL;
    b->tangents = NULL;
    for (uint32_t i = 0; i < b->num_textures; i++) iir_texture_destroy(b->textures[i]);
    free(b->textures);
    b->textures = NULL;
    b->num_textures = 0;
    free(b->indices);
    free(b->tri_materials);
    free(b->materials);
    free(b->lights);
    free(b->dropped);
    free(b->paths_json);
    for (uint32_t i = 0; i < b->num_maps; i++) iir_emission_map_free(b->maps[i]);
    free(b->maps);
    b->maps = NULL;
    b->num_maps = 0;
    b->positions = NULL;
    b->indices = b->tri_materials = NULL;
    b->materials = NULL;
    b->lights = NULL;
    b->dropped = NULL;
    b->paths_json = NULL;
    b->num_dropped = b->cap_dropped = 0;
    b->num_vertices = b->cap_vertices = 0;
    b->num_triangles = b->cap_triangles = 0;
    b->num_materials = b->cap_materials = 0;
    b->num_lights = b->cap_lights = 0;
}

/* Resizes an attribute array (if it exists) from old to cap vertices of elem bytes, zeroing the
 * new part. */
static bool resize_attr(void **p, uint32_t old, uint32_t cap, size_t elem)
{
    if (!*p) return true;
    void *q = realloc(*p, (size_t)cap * elem);
    if (!q) return false;
    if (cap > old) memset((char *)q + (size_t)old * elem, 0, (size_t)(cap - old) * elem);
    *p = q;
    return true;
}

static bool grow_vertices(iir_scene_builder *b, uint64_t need)
{
    uint32_t old = b->cap_vertices;
    if (!grow((void **)&b->positions, &b->cap_vertices, need, sizeof(iir_vec3))) return false;
    return resize_attr((void **)&b->vertex_normals, old, b->cap_vertices, sizeof(iir_vec3)) &&
           resize_attr((void **)&b->texcoords, old, b->cap_vertices, sizeof(iir_vec2)) &&
           resize_attr((void **)&b->tangents, old, b->cap_vertices, 4 * sizeof(float));
}

iir_status iir_builder_reserve(iir_scene_builder *b, uint32_t more_vertices,
                               uint32_t more_triangles, iir_error *err)
{
    if (!grow_vertices(b, (uint64_t)b->num_vertices + more_vertices) ||
        !grow_triangles(b, (uint64_t)b->num_triangles + more_triangles))
        return no_memory(b, err);
    return IIR_OK;
}

iir_status iir_builder_add_vertex(iir_scene_builder *b, iir_vec3 p, uint32_t *index, iir_error *err)
{
    return iir_builder_add_vertex_attr(b, p, NULL, index, err);
}

/* *p as a zeroed array of cap_vertices elements, created on first use. */
static bool ensure_attr(const iir_scene_builder *b, void **p, size_t elem)
{
    if (!*p) *p = calloc(b->cap_vertices ? b->cap_vertices : 1, elem);
    return *p != NULL;
}

static bool finite_n(const float *v, int n)
{
    for (int i = 0; i < n; i++)
        if (!isfinite(v[i])) return false;
    return true;
}

static iir_status store_attr(iir_scene_builder *b, uint32_t v, const iir_vertex_attr *a,
                             iir_error *err)
{
    if ((a->normal && !finite_n(&a->normal->x, 3)) || (a->uv && !finite_n(&a->uv->x, 2)) ||
        (a->tangent && !finite_n(a->tangent, 4)))
        return iir_fail(err, IIR_ERR_FORMAT,
                        "%s: vertex %u has a non-finite normal, texture "
                        "coordinate or tangent",
                        b->source, v);
    if ((a->normal && !ensure_attr(b, (void **)&b->vertex_normals, sizeof(iir_vec3))) ||
        (a->uv && !ensure_attr(b, (void **)&b->texcoords, sizeof(iir_vec2))) ||
        (a->tangent && !ensure_attr(b, (void **)&b->tangents, 4 * sizeof(float))))
        return no_memory(b, err);
    if (a->normal) b->vertex_normals[v] = *a->normal;
    if (a->uv) b->texcoords[v] = *a->uv;
    if (a->tangent) memcpy(b->tangents + 4 * (size_t)v, a->tangent, 4 * sizeof(float));
    return IIR_OK;
}

iir_status iir_builder_add_vertex_attr(iir_scene_builder *b, iir_vec3 p,
                                       const iir_vertex_attr *attr, uint32_t *index, iir_error *err)
{
    if (!iir_is_finite3(p))
        return iir_fail(err, IIR_ERR_FORMAT, "%s: vertex %u is not finite (%g, %g, %g)", b->source,
                        b->num_vertices, (double)p.x, (double)p.y, (double)p.z);
    if (!grow_vertices(b, (uint64_t)b->num_vertices + 1)) return no_memory(b, err);
    if (attr) {
        iir_status st = store_attr(b, b->num_vertices, attr, err);
        if (st != IIR_OK) return st;
    }
    if (index) *index = b->num_vertices;
    b->positions[b->num_vertices++] = p;
    return IIR_OK;
}

iir_status iir_builder_add_texture(iir_scene_builder *b, iir_texture *tex, uint32_t *ref,
                                   iir_error *err)
{
    iir_texture **grown = realloc(b->textures, sizeof *grown * (b->num_textures + 1));
    if (!grown) {
        iir_texture_destroy(tex);
        return no_memory(b, err);
    }
    b->textures = grown;
    b->textures[b->num_textures++] = tex;
    *ref = b->num_textures;
    return IIR_OK;
}

iir_status iir_builder_take_textures(iir_scene_builder *b, iir_scene *scene, iir_error *err)
{
    iir_status st = IIR_OK;
    for (uint32_t i = 0; i < scene->num_textures; i++) {
        uint32_t ref;
        iir_status s = iir_builder_add_texture(b, scene->textures[i], &ref, err);
        if (st == IIR_OK) st = s;
    }
    free(scene->textures);
    scene->textures = NULL;
    scene->num_textures = 0;
    return st;
}

iir_status iir_builder_add_triangle(iir_scene_builder *b, uint32_t i0, uint32_t i1, uint32_t i2,
                                    uint32_t material, iir_error *err)
{
    uint32_t nv = b->num_vertices;
    if (i0 >= nv || i1 >= nv || i2 >= nv)
        return iir_fail(err, IIR_ERR_FORMAT,
                        "%s: triangle %u refers to vertex (%u, %u, %u) but there are only %u",
                        b->source, b->num_triangles, i0, i1, i2, nv);
    if (material >= b->num_materials)
        return iir_fail(err, IIR_ERR_FORMAT,
                        "%s: triangle %u refers to material %u but there are only %u", b->source,
                        b->num_triangles, material, b->num_materials);
    if (!grow_triangles(b, (uint64_t)b->num_triangles + 1)) return no_memory(b, err);
    uint32_t *t = b->indices + 3 * (size_t)b->num_triangles;
    t[0] = i0;
    t[1] = i1;
    t[2] = i2;
    b->tri_materials[b->num_triangles++] = material;
    return IIR_OK;
}

static bool in_unit_range(iir_vec3 c)
{
    return c.x >= 0.f && c.x <= 1.f && c.y >= 0.f && c.y <= 1.f && c.z >= 0.f && c.z <= 1.f;
}

static bool non_negative(iir_vec3 c)
{
    return iir_is_finite3(c) && c.x >= 0.f && c.y >= 0.f && c.z >= 0.f;
}

iir_status iir_builder_add_material(iir_scene_builder *b, const iir_material *m, uint32_t *index,
                                    iir_error *err)
{
    if (!in_unit_range(m->albedo))
        return iir_fail(err, IIR_ERR_INVALID,
                        "%s: material '%s': albedo (%g, %g, %g) must be in [0, 1]", b->source,
                        m->name, (double)m->albedo.x, (double)m->albedo.y, (double)m->albedo.z);
    if (!non_negative(m->emission))
        return iir_fail(err, IIR_ERR_INVALID,
                        "%s: material '%s': emission (%g, %g, %g) must be finite and >= 0",
                        b->source, m->name, (double)m->emission.x, (double)m->emission.y,
                        (double)m->emission.z);
    char why[160];
    if (iir_material_check(m, why, sizeof why))
        return iir_fail(err, IIR_ERR_INVALID, "%s: material '%s': %s", b->source, m->name, why);
    if (!grow((void **)&b->materials, &b->cap_materials, (uint64_t)b->num_materials + 1,
              sizeof(iir_material)))
        return no_memory(b, err);
    if (index) *index = b->num_materials;
    b->materials[b->num_materials++] = *m;
    return IIR_OK;
}

int64_t iir_builder_find_material(const iir_scene_builder *b, const char *name)
{
    for (uint32_t i = 0; i < b->num_materials; i++)
        if (strcmp(b->materials[i].name, name) == 0) return i;
    return -1;
}

iir_status iir_builder_add_light(iir_scene_builder *b, const iir_light *light, iir_error *err)
{
    iir_error e;
    iir_status st = iir_light_validate(light, &e);
    if (st != IIR_OK) return iir_fail(err, st, "%s: %s", b->source, e.msg);
    if (!grow((void **)&b->lights, &b->cap_lights, (uint64_t)b->num_lights + 1, sizeof(iir_light)))
        return no_memory(b, err);
    b->lights[b->num_lights++] = *light;
    return IIR_OK;
}

/* A copied material's texture references, shifted past the builder's t0 textures (the scene's
 * textures are taken over after them: iir_builder_take_textures). */
static void shift_textures(iir_material *m, uint32_t t0)
{
    iir_texref *refs[] = {&m->base_tex, &m->mr_tex, &m->normal_tex, &m->emission_tex};
    for (size_t k = 0; k < sizeof refs / sizeof *refs; k++)
        if (refs[k]->texture) refs[k]->texture += t0;
}

iir_status iir_builder_add_scene(iir_scene_builder *b, const iir_scene *scene, iir_error *err)
{
    uint32_t v0 = b->num_vertices, m0 = b->num_materials;
    iir_status st = iir_builder_reserve(b, scene->num_vertices, scene->num_triangles, err);
    for (uint32_t i = 0; st == IIR_OK && i < scene->num_materials; i++)
        st = iir_builder_add_material(b, &scene->material_list[i], NULL, err);
    uint32_t t0 = b->num_textures;
    for (uint32_t i = 0; st == IIR_OK && i < scene->num_materials; i++)
        shift_textures(&b->materials[m0 + i], t0);
    for (uint32_t i = 0; st == IIR_OK && i < scene->num_vertices; i++) {
        iir_vertex_attr a = {scene->vertex_normals ? &scene->vertex_normals[i] : NULL,
                             scene->texcoords ? &scene->texcoords[i] : NULL,
                             scene->tangents ? &scene->tangents[4 * (size_t)i] : NULL};
        st = iir_builder_add_vertex_attr(b, scene->positions[i], &a, NULL, err);
    }
    for (uint32_t i = 0; st == IIR_OK && i < scene->num_triangles; i++) {
        const uint32_t *t = scene->indices + 3 * (size_t)i;
        st = iir_builder_add_triangle(b, v0 + t[0], v0 + t[1], v0 + t[2], m0 + scene->materials[i],
                                      err);
    }
    for (uint32_t i = 0; st == IIR_OK && i < scene->num_lights; i++)
        st = iir_builder_add_light(b, &scene->lights[i], err);
    for (uint32_t i = 0; st == IIR_OK && i < scene->num_dropped; i++)
        if (!scene->dropped[i].method[0])
            (scene->dropped[i].note ? iir_builder_note : iir_builder_drop)(
                b, scene->dropped[i].kind, scene->dropped[i].name, "%s", scene->dropped[i].what);
    if (st == IIR_OK) {
        iir_builder_set_camera(b, &scene->camera);
        iir_builder_set_camera_origin(b, scene->camera_origin, scene->aspect);
    }
    return st;
}

void iir_builder_clear_lights(iir_scene_builder *b)
{
    b->num_lights = 0;
    uint32_t kept = 0;
    for (uint32_t i = 0; i < b->num_dropped; i++)
        if (strcmp(b->dropped[i].kind, "light") != 0) b->dropped[kept++] = b->dropped[i];
    b->num_dropped = kept;
}

void iir_builder_set_camera(iir_scene_builder *b, const iir_camera *cam)
{
    b->camera = *cam;
    b->has_camera = true;
    b->camera_origin = IIR_CAMERA_FILE;
    b->aspect = 0.f;
}

void iir_builder_set_camera_origin(iir_scene_builder *b, iir_camera_origin origin, float aspect)
{
    b->camera_origin = origin;
    b->aspect = aspect;
}

/* One more entry of b->dropped: a warning, or a note (iir_dropped.note). */
static void add_dropped(iir_scene_builder *b, bool note, const char *kind, const char *name,
                        const char *fmt, va_list ap)
{
    if (!grow((void **)&b->dropped, &b->cap_dropped, (uint64_t)b->num_dropped + 1,
              sizeof(iir_dropped)))
        return;
    iir_dropped *d = &b->dropped[b->num_dropped++];
    memset(d, 0, sizeof *d);
    iir_scene_strcpy(d->kind, sizeof d->kind, kind);
    iir_scene_strcpy(d->name, sizeof d->name, name);
    vsnprintf(d->what, sizeof d->what, fmt, ap);
    d->note = note;
}

void iir_builder_drop(iir_scene_builder *b, const char *kind, const char *name, const char *fmt,
                      ...)
{
    va_list ap;
    va_start(ap, fmt);
    add_dropped(b, false, kind, name, fmt, ap);
    va_end(ap);
}

void iir_builder_note(iir_scene_builder *b, const char *kind, const char *name, const char *fmt,
                      ...)
{
    va_list ap;
    va_start(ap, fmt);
    add_dropped(b, true, kind, name, fmt, ap);
    va_end(ap);
}

void iir_builder_scale(iir_scene_builder *b, float s)
{
    for (uint32_t i = 0; i < b->num_vertices; i++) b->positions[i] = iir_scale(b->positions[i], s);
    for (uint32_t i = 0; i < b->num_lights; i++)
        b->lights[i].position = iir_scale(b->lights[i].position, s);
    b->camera.position = iir_scale(b->camera.position, s);
    b->camera.target = iir_scale(b->camera.target, s);
}

/* ======================== finishing ======================== */

typedef struct bounds {
    iir_vec3 lo, hi;
} bounds;

static bounds bounds_empty(void)
{
    bounds bb = {iir_v3s(INFINITY), iir_v3s(-INFINITY)};
    return bb;
}

static void bounds_add(bounds *bb, iir_vec3 p)
{
    bb->lo = iir_v3(fminf(bb->lo.x, p.x), fminf(bb->lo.y, p.y), fminf(bb->lo.z, p.z));
    bb->hi = iir_v3(fmaxf(bb->hi.x, p.x), fmaxf(bb->hi.y, p.y), fmaxf(bb->hi.z, p.z));
}

/* Bounds of the vertices of the first n triangles. */
static bounds triangle_bounds(const iir_scene_builder *b, uint32_t n)
{
    bounds bb = bounds_empty();
    for (size_t k = 0; k < 3 * (size_t)n; k++) bounds_add(&bb, b->positions[b->indices[k]]);
    return bb;
}

/* Twice the area vector of triangle t, in double so that a collapsed triangle gives ~0. */
static void cross_double(const iir_scene_builder *b, const uint32_t *t, double c[3])
{
    iir_vec3 p0 = b->positions[t[0]], p1 = b->positions[t[1]], p2 = b->positions[t[2]];
    double e1[3] = {(double)p1.x - p0.x, (double)p1.y - p0.y, (double)p1.z - p0.z};
    double e2[3] = {(double)p2.x - p0.x, (double)p2.y - p0.y, (double)p2.z - p0.z};
    c[0] = e1[1] * e2[2] - e1[2] * e2[1];
    c[1] = e1[2] * e2[0] - e1[0] * e2[2];
    c[2] = e1[0] * e2[1] - e1[1] * e2[0];
}

/* Compacts the non-degenerate triangles to the front, filling normals and areas for them.
 * Returns how many were kept. */
static uint32_t keep_good_triangles(iir_scene_builder *b, double min_area, iir_vec3 *normals,
                                    float *areas)
{
    uint32_t kept = 0;
    for (uint32_t i = 0; i < b->num_triangles; i++) {
        const uint32_t *t = b->indices + 3 * (size_t)i;
        if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
        double c[3];
        cross_double(b, t, c);
        double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        if (!(0.5 * len > min_area)) continue;
        uint32_t *dst = b->indices + 3 * (size_t)kept;
        memmove(dst, t, 3 * sizeof(uint32_t));
        b->tri_materials[kept] = b->tri_materials[i];
        normals[kept] = iir_v3((float)(c[0] / len), (float)(c[1] / len), (float)(c[2] / len));
        areas[kept] = (float)(0.5 * len);
        kept++;
    }
    return kept;
}

/* A triangle's three positions in a canonical (sorted) order, so the same triangle listed twice,
 * in any vertex order or winding, gives the same key. */
typedef struct tri_key {
    iir_vec3 p[3];
    uint32_t tri;
} tri_key;

static int cmp_vec3(const iir_vec3 *a, const iir_vec3 *b)
{
    if (a->x != b->x) return a->x < b->x ? -1 : 1;
    if (a->y != b->y) return a->y < b->y ? -1 : 1;
    if (a->z != b->z) return a->z < b->z ? -1 : 1;
    return 0;
}

static int cmp_key_points(const tri_key *a, const tri_key *b)
{
    for (int k = 0; k < 3; k++) {
        int c = cmp_vec3(&a->p[k], &b->p[k]);
        if (c) return c;
    }
    return 0;
}

/* Points first, then the triangle's index, so the earliest of equal triangles comes first. */
static int cmp_key(const void *va, const void *vb)
{
    const tri_key *a = va, *b = vb;
    int c = cmp_key_points(a, b);
    return c ? c : (a->tri > b->tri) - (a->tri < b->tri);
}

static tri_key make_key(const iir_scene_builder *b, uint32_t t)
{
    tri_key k = {{b->positions[b->indices[3 * (size_t)t]],
                  b->positions[b->indices[3 * (size_t)t + 1]],
                  b->positions[b->indices[3 * (size_t)t + 2]]},
                 t};
    for (int i = 0; i < 2; i++) /* sort three points */
        for (int j = 0; j < 2 - i; j++)
            if (cmp_vec3(&k.p[j], &k.p[j + 1]) > 0) {
                iir_vec3 tmp = k.p[j];
                k.p[j] = k.p[j + 1];
                k.p[j + 1] = tmp;
            }
    return k;
}

/* Drops every triangle whose three positions equal an earlier triangle's (coplanar duplicates
 * make hits ambiguous and double the area light sampling sees), compacting triangles, normals and
 * areas in order. Returns how many remain, or UINT32_MAX when out of memory. */
static uint32_t drop_duplicates(iir_scene_builder *b, uint32_t n, iir_vec3 *normals, float *areas)
{
    tri_key *keys = malloc(sizeof(tri_key) * (n ? n : 1));
    uint8_t *dup = calloc(n ? n : 1, 1);
    if (!keys || !dup) {
        free(keys);
        free(dup);
        return UINT32_MAX;
    }
    for (uint32_t t = 0; t < n; t++) keys[t] = make_key(b, t);
    qsort(keys, n, sizeof(tri_key), cmp_key);
    for (uint32_t i = 1; i < n; i++)
        if (cmp_key_points(&keys[i - 1], &keys[i]) == 0) dup[keys[i].tri] = 1;
    uint32_t kept = 0;
    for (uint32_t t = 0; t < n; t++) {
        if (dup[t]) continue;
        memmove(b->indices + 3 * (size_t)kept, b->indices + 3 * (size_t)t, 3 * sizeof(uint32_t));
        b->tri_materials[kept] = b->tri_materials[t];
        normals[kept] = normals[t];
        areas[kept] = areas[t];
        kept++;
    }
    free(keys);
    free(dup);
    return kept;
}

/* Looks at the centre of the bounds from +z, far enough for the bounding sphere to fit the
 * vertical field of view. */
static iir_camera default_camera(bounds bb)
{
    iir_camera cam;
    iir_vec3 centre = iir_scale(iir_add(bb.lo, bb.hi), 0.5f);
    float radius = 0.5f * iir_length(iir_sub(bb.hi, bb.lo));
    cam.fov_y = 45.f;
    cam.target = centre;
    cam.position = iir_add(centre, iir_v3(0.f, 0.f, radius / sinf(iir_radians(0.5f * cam.fov_y))));
    cam.up = iir_v3(0.f, 1.f, 0.f);
    return cam;
}

static iir_status check_camera(const iir_scene_builder *b, const iir_camera *cam, iir_error *err)
{
    iir_error e;
    iir_status st = iir_camera_validate(cam, &e);
    if (st != IIR_OK) return iir_fail(err, st, "%s: camera: %s", b->source, e.msg);
    return IIR_OK;
}

/* Moves the builder's arrays into s and empties the builder. */
static void move_into_scene(iir_scene_builder *b, iir_scene *s)
{
    iir_scene_strcpy(s->name, sizeof s->name, b->name);
    iir_scene_strcpy(s->source, sizeof s->source, b->source);
    s->num_vertices = b->num_vertices;
    s->positions = b->positions;
    s->vertex_normals = b->vertex_normals;
    s->texcoords = b->texcoords;
    s->tangents = b->tangents;
    s->textures = b->textures;
    s->num_textures = b->num_textures;
    b->vertex_normals = NULL;
    b->texcoords = NULL;
    b->tangents = NULL;
    b->textures = NULL;
    b->num_textures = 0;
    s->num_triangles = b->num_triangles;
    s->indices = b->indices;
    s->materials = b->tri_materials;
    s->num_materials = b->num_materials;
    s->material_list = b->materials;
    s->num_lights = b->num_lights;
    s->lights = b->lights;
    s->camera = b->camera;
    s->camera_origin = b->camera_origin;
    s->aspect = b->aspect;
    s->num_dropped = b->num_dropped;
    s->dropped = b->dropped;
    s->paths_json = b->paths_json;
    s->maps = b->maps;
    s->num_maps = b->num_maps;
    b->maps = NULL;
    b->num_maps = 0;
    b->positions = NULL;
    b->indices = b->tri_materials = NULL;
    b->materials = NULL;
    b->lights = NULL;
    b->dropped = NULL;
    b->paths_json = NULL;
    iir_builder_free(b);
}

/* A zeroed scene with room for n normals and areas, or NULL. */
static iir_scene *alloc_scene(uint32_t n)
{
    iir_scene *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->normals = malloc(sizeof(iir_vec3) * n);
    s->areas = malloc(sizeof(float) * n);
    if (s->normals && s->areas) return s;
    iir_scene_destroy(s);
    return NULL;
}

iir_status iir_builder_finish(iir_scene_builder *b, iir_scene **out, iir_error *err)
{
    *out = NULL;
    if (b->num_triangles == 0) return iir_fail(err, IIR_ERR_FORMAT, "%s: no triangles", b->source);
    if (b->has_camera) {
        iir_status st = check_camera(b, &b->camera, err);
        if (st != IIR_OK) return st;
    }
    iir_scene *s = alloc_scene(b->num_triangles);
    if (!s) return no_memory(b, err);
    bounds all = triangle_bounds(b, b->num_triangles);
    double min_area = DEGENERATE_REL_AREA * iir_length_sq(iir_sub(all.hi, all.lo));
    uint32_t total = b->num_triangles;
    uint32_t kept = keep_good_triangles(b, min_area, s->normals, s->areas);
    if (kept == 0) {
        iir_scene_destroy(s);
        return iir_fail(err, IIR_ERR_FORMAT, "%s: no triangles left: all %u are degenerate",
                        b->source, total);
    }
    uint32_t unique = drop_duplicates(b, kept, s->normals, s->areas);
    if (unique == UINT32_MAX) {
        iir_scene_destroy(s);
        return no_memory(b, err);
    }
    b->num_triangles = unique;
    bounds bb = triangle_bounds(b, unique);
    if (!b->has_camera) {
        /* validated too: a scene a few 1e-23 across has no camera distance a float can hold */
        iir_camera cam = default_camera(bb);
        iir_status st = check_camera(b, &cam, err);
        if (st != IIR_OK) {
            iir_scene_destroy(s);
            return st;
        }
        iir_builder_set_camera(b, &cam);
        iir_builder_set_camera_origin(b, IIR_CAMERA_OUTSIDE, 0.f);
    }
    s->bounds_min = bb.lo;
    s->bounds_max = bb.hi;
    s->skipped_degenerate = total - kept;
    s->skipped_duplicate = kept - unique;
    move_into_scene(b, s);
    for (uint32_t i = 0; i < s->num_lights; i++) iir_light_fit_sun(&s->lights[i], s);
    *out = s;
    return IIR_OK;
}

iir_status iir_builder_add_map(iir_scene_builder *b, iir_emission_map *map, iir_error *err)
{
    iir_emission_map **grown = realloc(b->maps, sizeof *grown * (b->num_maps + 1));
    if (!grown) {
        iir_emission_map_free(map);
        return iir_fail(err, IIR_ERR_NOMEM, "%s: out of memory for an emission map", b->source);
    }
    b->maps = grown;
    b->maps[b->num_maps++] = map;
    return IIR_OK;
}

iir_status iir_builder_take_maps(iir_scene_builder *b, iir_scene *scene, iir_error *err)
{
    iir_status st = IIR_OK;
    for (uint32_t i = 0; i < scene->num_maps; i++) {
        iir_status s = iir_builder_add_map(b, scene->maps[i], err);
        if (st == IIR_OK) st = s;
    }
    free(scene->maps);
    scene->maps = NULL;
    scene->num_maps = 0;
    return st;
}

/* scene.c -- the public scene API: from what a user typed to a path (resolve), from a path to a
 * loaded scene (file, folder or sidecar dispatch), describing and destroying it; not file formats
 * (scene_assimp.c, scene_sidecar.c), not the builder (scene_build.c). */
#include "scene_build.h"

#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#define SIDECAR_EXT ".scene.json"
#define PATH_MAX_LEN 1024
#define MAX_BASE_DEPTH 8 /* sidecars based on sidecars: a longer chain is taken for a cycle */

static const char *const MESH_EXTS[] = {".obj", ".gltf", ".glb", NULL};

/* ======================== destroy, describe ======================== */

void iir_scene_destroy(iir_scene *scene)
{
    if (!scene) return;
    free(scene->positions);
    free(scene->vertex_normals);
    free(scene->texcoords);
    free(scene->tangents);
    for (uint32_t i = 0; i < scene->num_textures; i++) iir_texture_destroy(scene->textures[i]);
    free(scene->textures);
    free(scene->indices);
    free(scene->materials);
    free(scene->normals);
    free(scene->areas);
    free(scene->material_list);
    free(scene->lights);
    free(scene->dropped);
    free(scene->paths_json);
    for (uint32_t i = 0; i < scene->num_maps; i++) iir_emission_map_free(scene->maps[i]);
    free(scene->maps);
    free(scene);
}

uint64_t iir_scene_bytes(const iir_scene *s)
{
    uint64_t v = s->num_vertices, t = s->num_triangles;
    uint64_t b = sizeof *s + v * sizeof(iir_vec3) +
                 t * (3 * sizeof(uint32_t) + sizeof(uint32_t) + sizeof(iir_vec3) + sizeof(float));
    if (s->vertex_normals) b += v * sizeof(iir_vec3);
    if (s->texcoords) b += v * sizeof(iir_vec2);
    if (s->tangents) b += v * 4 * sizeof(float);
    b += (uint64_t)s->num_materials * sizeof(iir_material) +
         (uint64_t)s->num_lights * sizeof(iir_light);
    for (uint32_t i = 0; i < s->num_textures; i++) b += iir_texture_bytes(s->textures[i]);
    return b;
}

static const char *plural(uint32_t n)
{
    return n == 1 ? "" : "s";
}

void iir_scene_describe(const iir_scene *s, char *buf, size_t n)
{
    snprintf(buf, n,
             "%s: %u triangle%s, %u material%s, %u light%s, skipped %u degenerate and %u duplicate",
             s->name, s->num_triangles, plural(s->num_triangles), s->num_materials,
             plural(s->num_materials), s->num_lights, plural(s->num_lights), s->skipped_degenerate,
             s->skipped_duplicate);
}

/* ======================== path helpers ======================== */

static bool ends_with(const char *s, const char *suffix, bool fold_case)
{
    size_t ls = strlen(s), lx = strlen(suffix);
    if (lx > ls) return false;
    return fold_case ? strcasecmp(s + ls - lx, suffix) == 0 : strcmp(s + ls - lx, suffix) == 0;
}

static bool is_mesh_name(const char *name)
{
    for (const char *const *e = MESH_EXTS; *e; e++)
        if (ends_with(name, *e, true)) return true;
    return false;
}

static const char *base_name(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? slash + 1 : path;
}

/* The scene's short name: the base name without ".scene.json" or the last extension. */
static void scene_name(const char *path, char *out, size_t n)
{
    const char *base = base_name(path);
    size_t len = strlen(base);
    if (ends_with(base, SIDECAR_EXT, false)) {
        len -= strlen(SIDECAR_EXT);
    } else {
        const char *dot = strrchr(base, '.');
        if (dot && dot != base) len = (size_t)(dot - base);
    }
    snprintf(out, n, "%.*s", (int)len, base);
}

static bool is_regular_file(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 && S_ISREG(st.st_mode);
}

static bool same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev &&
           sa.st_ino == sb.st_ino;
}

/* ======================== resolve ======================== */

static bool is_bare_name(const char *name)
{
    for (const char *p = name; *p; p++) {
        char ch = *p;
        bool ok = (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') ||
                  (ch >= '0' && ch <= '9') || ch == '_' || ch == '-' || ch == '.';
        if (!ok) return false;
    }
    return true;
}

static iir_status copy_out(const char *path, char *out, size_t n, iir_error *err)
{
    if (strlen(path) >= n)
        return iir_fail(err, IIR_ERR_INVALID, "scene path %s is too long (%zu characters max)",
                        path, n - 1);
    memcpy(out, path, strlen(path) + 1);
    return IIR_OK;
}

iir_status iir_scene_resolve(const char *name, const char *scenes_dir, char *out, size_t n,
                             iir_error *err)
{
    if (!name || !*name) return iir_fail(err, IIR_ERR_INVALID, "no scene name given");
    struct stat st;
    if (stat(name, &st) == 0) return copy_out(name, out, n, err);
    if (strchr(name, '/')) /* a path to a file that is not there: cannot be read (exit 3) */
        return iir_fail(err, IIR_ERR_IO,
                        "scene '%s' does not exist, and only bare names (letters, digits, '_', "
                        "'-', '.'; no '/' or '..') are looked up in the scenes folder",
                        name);
    if (strstr(name, ".."))
        return iir_fail(err, IIR_ERR_INVALID,
                        "scene '%s' does not exist, and only bare names (letters, digits, '_', "
                        "'-', '.'; no '/' or '..') are looked up in the scenes folder",
                        name);
    if (!is_bare_name(name))
        return iir_fail(err, IIR_ERR_INVALID,
                        "scene name '%s' may only contain letters, digits, '_', '-' and '.'", name);
    if (!scenes_dir || !*scenes_dir)
        return iir_fail(err, IIR_ERR_IO, "no scene named '%s' (no scenes folder to look in)", name);
    char joined[PATH_MAX_LEN];
    if (snprintf(joined, sizeof joined, "%s/%s", scenes_dir, name) >= (int)sizeof joined)
        return iir_fail(err, IIR_ERR_INVALID, "scenes folder path %s is too long", scenes_dir);
    if (stat(joined, &st) != 0)
        return iir_fail(err, IIR_ERR_IO, "no scene named '%s' in %s", name, scenes_dir);
    return copy_out(joined, out, n, err);
}

/* ======================== picking the file in a folder ======================== */

typedef struct name_list {
    char **names;
    size_t count, cap;
} name_list;

static bool name_list_add(name_list *l, const char *name)
{
    if (l->count == l->cap) {
        size_t cap = l->cap ? 2 * l->cap : 8;
        char **p = realloc(l->names, cap * sizeof *p);
        if (!p) return false;
        l->names = p;
        l->cap = cap;
    }
    char *copy = strdup(name);
    if (!copy) return false;
    l->names[l->count++] = copy;
    return true;
}

static void name_list_free(name_list *l)
{
    for (size_t i = 0; i < l->count; i++) free(l->names[i]);
    free(l->names);
}

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static void name_list_join(const name_list *l, char *buf, size_t n)
{
    buf[0] = '\0';
    for (size_t i = 0; i < l->count; i++) {
        size_t used = strlen(buf);
        snprintf(buf + used, n - used, "%s%s", i ? ", " : "", l->names[i]);
    }
}

/* Sidecars and mesh files in dir, each list sorted. */
static iir_status list_folder(const char *dir, name_list *sidecars, name_list *meshes,
                              iir_error *err)
{
    DIR *d = opendir(dir);
    if (!d)
        return iir_fail(err, IIR_ERR_IO, "cannot read scene folder %s: %s", dir, strerror(errno));
    bool ok = true;
    for (struct dirent *e; ok && (e = readdir(d));) {
        if (e->d_name[0] == '.') continue;
        if (ends_with(e->d_name, SIDECAR_EXT, false))
            ok = name_list_add(sidecars, e->d_name);
        else if (is_mesh_name(e->d_name))
            ok = name_list_add(meshes, e->d_name);
    }
    closedir(d);
    if (!ok) return iir_fail(err, IIR_ERR_NOMEM, "out of memory listing %s", dir);
    if (sidecars->count) qsort(sidecars->names, sidecars->count, sizeof(char *), compare_names);
    if (meshes->count) qsort(meshes->names, meshes->count, sizeof(char *), compare_names);
    return IIR_OK;
}

/* The one sidecar; with several, the one named after the folder. NULL if none fits. */
static const char *pick_sidecar(const char *dir, const name_list *sidecars)
{
    if (sidecars->count == 1) return sidecars->names[0];
    char want[PATH_MAX_LEN + sizeof SIDECAR_EXT];
    char folder[PATH_MAX_LEN];
    snprintf(folder, sizeof folder, "%s", dir);
    size_t len = strlen(folder);
    while (len > 1 && folder[len - 1] == '/') folder[--len] = '\0';
    snprintf(want, sizeof want, "%s%s", base_name(folder), SIDECAR_EXT);
    for (size_t i = 0; i < sidecars->count; i++)
        if (strcmp(sidecars->names[i], want) == 0) return sidecars->names[i];
    return NULL;
}

/* A folder holds a scene as its *.scene.json, else as its only mesh file. */
static iir_status choose(const char *dir, const name_list *sidecars, const name_list *meshes,
                         const char **pick, iir_error *err)
{
    char names[400];
    if (sidecars->count > 0) {
        *pick = pick_sidecar(dir, sidecars);
        name_list_join(sidecars, names, sizeof names);
        if (*pick) return IIR_OK;
        return iir_fail(err, IIR_ERR_INVALID,
                        "scene folder %s has several sidecars (%s) and "
                        "none is named after the folder; load one of them",
                        dir, names);
    }
    if (meshes->count == 1) {
        *pick = meshes->names[0];
        return IIR_OK;
    }
    if (meshes->count == 0)
        return iir_fail(err, IIR_ERR_IO,
                        "scene folder %s has no *.scene.json, *.obj, *.gltf or "
                        "*.glb file",
                        dir);
    name_list_join(meshes, names, sizeof names);
    return iir_fail(err, IIR_ERR_INVALID,
                    "scene folder %s has several meshes (%s) and no "
                    "*.scene.json saying which to load",
                    dir, names);
}

static iir_status pick_in_folder(const char *dir, char *out, size_t n, iir_error *err)
{
    name_list sidecars = {0}, meshes = {0};
    const char *pick = NULL;
    iir_status st = list_folder(dir, &sidecars, &meshes, err);
    if (st == IIR_OK) st = choose(dir, &sidecars, &meshes, &pick, err);
    if (st == IIR_OK && snprintf(out, n, "%s/%s", dir, pick) >= (int)n)
        st = iir_fail(err, IIR_ERR_INVALID, "scene path %s/%s is too long", dir, pick);
    name_list_free(&sidecars);
    name_list_free(&meshes);
    return st;
}

/* ======================== loading ======================== */

/* NAME.obj / .gltf / .glb next to a sidecar NAME.scene.json, for a sidecar without "file". */
static bool sibling_mesh(const char *sidecar, char *out, size_t n)
{
    size_t stem = strlen(sidecar) - strlen(SIDECAR_EXT);
    for (const char *const *e = MESH_EXTS; *e; e++) {
        if (snprintf(out, n, "%.*s%s", (int)stem, sidecar, *e) >= (int)n) return false;
        if (is_regular_file(out)) return true;
    }
    return false;
}

/* Loads mesh into b, applies sc (may be NULL), turns its emissive materials into area lights
 * unless sc gives a "lights" array (iir_builder_emitters_to_lights), and finishes. Always frees
 * b. */
static iir_status build(iir_scene_builder *b, const char *mesh, iir_sidecar *sc, iir_scene **out,
                        iir_error *err)
{
    iir_status st = iir_assimp_load(mesh, b, err);
    if (st == IIR_OK && sc) st = iir_sidecar_apply(sc, b, err);
    if (st == IIR_OK && !(sc && sc->has_lights)) st = iir_builder_emitters_to_lights(b, err);
    if (st == IIR_OK) st = iir_builder_finish(b, out, err);
    iir_builder_free(b);
    return st;
}

static iir_status load_path(const char *path, int depth, iir_scene **out, iir_error *err);

/* The scene a sidecar's "base" names: the built-in box, or the folder of that name beside the
 * sidecar's own folder (a saved scene SCENES/NAME/NAME.scene.json names SCENES/BASE). */
static iir_status load_base(const iir_sidecar *sc, int depth, iir_scene **out, iir_error *err)
{
    if (!strcmp(sc->base, "builtin")) {
        *out = iir_scene_create_cornell_box();
        return *out ? IIR_OK : iir_fail(err, IIR_ERR_NOMEM, "%s: out of memory", sc->path);
    }
    if (depth >= MAX_BASE_DEPTH)
        return iir_fail(err, IIR_ERR_INVALID,
                        "%s: base: '%s' starts a chain of more than %d scenes based on each "
                        "other (a cycle?)",
                        sc->path, sc->base, MAX_BASE_DEPTH);
    const char *slash = strrchr(sc->path, '/');
    int dir_len = slash ? (int)(slash - sc->path) : 1;
    char path[PATH_MAX_LEN];
    if (snprintf(path, sizeof path, "%.*s/../%s", dir_len, slash ? sc->path : ".", sc->base) >=
        (int)sizeof path)
        return iir_fail(err, IIR_ERR_INVALID, "%s: base: path is too long", sc->path);
    struct stat sb;
    if (stat(path, &sb) != 0)
        return iir_fail(err, IIR_ERR_IO,
                        "%s: base: no scene '%s' beside the sidecar's folder (%s: %s)", sc->path,
                        sc->base, path, strerror(errno));
    return load_path(path, depth + 1, out, err);
}

/* A sidecar with "base": that scene (geometry, materials, lights, camera; not its paths) takes the
 * place of the mesh, then the sidecar applies as to a mesh. */
static iir_status load_on_base(const char *path, iir_sidecar *sc, int depth, iir_scene **out,
                               iir_error *err)
{
    iir_scene *base = NULL;
    iir_status st = load_base(sc, depth, &base, err);
    if (st != IIR_OK) return st;
    iir_scene_builder b;
    char name[128];
    scene_name(path, name, sizeof name);
    iir_builder_init(&b, name, path);
    st = iir_builder_add_scene(&b, base, err);
    if (st == IIR_OK) st = iir_builder_take_maps(&b, base, err);
    if (st == IIR_OK) st = iir_builder_take_textures(&b, base, err);
    if (st == IIR_OK) st = iir_sidecar_apply(sc, &b, err);
    if (st == IIR_OK) st = iir_builder_finish(&b, out, err);
    iir_builder_free(&b);
    if (st == IIR_OK) {
        (*out)->skipped_degenerate += base->skipped_degenerate;
        (*out)->skipped_duplicate += base->skipped_duplicate;
    }
    iir_scene_destroy(base);
    return st;
}

static iir_status load_sidecar(const char *path, int depth, iir_scene **out, iir_error *err)
{
    iir_sidecar sc;
    iir_status st = iir_sidecar_parse(path, &sc, err);
    if (st != IIR_OK) return st;
    char mesh[PATH_MAX_LEN];
    if (sc.base[0]) {
        st = load_on_base(path, &sc, depth, out, err);
        iir_sidecar_free(&sc);
        return st;
    }
    if (sc.file[0]) {
        snprintf(mesh, sizeof mesh, "%s", sc.file);
    } else if (!sibling_mesh(path, mesh, sizeof mesh)) {
        iir_sidecar_free(&sc);
        return iir_fail(err, IIR_ERR_INVALID,
                        "%s names no mesh: add a \"file\" field, or put "
                        "NAME.obj, NAME.gltf or NAME.glb next to it",
                        path);
    }
    iir_scene_builder b;
    char name[128];
    scene_name(path, name, sizeof name);
    iir_builder_init(&b, name, path);
    st = build(&b, mesh, &sc, out, err);
    iir_sidecar_free(&sc);
    return st;
}

/* A mesh file, with NAME.scene.json applied when it sits next to NAME.ext. */
static iir_status load_mesh(const char *path, iir_scene **out, iir_error *err)
{
    char name[128], sidecar[PATH_MAX_LEN];
    scene_name(path, name, sizeof name);
    const char *slash = strrchr(path, '/');
    int dir_len = slash ? (int)(slash - path + 1) : 0;
    bool has_sidecar = snprintf(sidecar, sizeof sidecar, "%.*s%s%s", dir_len, path, name,
                                SIDECAR_EXT) < (int)sizeof sidecar &&
                       is_regular_file(sidecar);
    iir_sidecar sc;
    if (has_sidecar) {
        iir_status st = iir_sidecar_parse(sidecar, &sc, err);
        if (st != IIR_OK) return st;
        if (sc.base[0]) {
            st = iir_fail(err, IIR_ERR_INVALID,
                          "%s: base: a sidecar based on another scene is loaded by itself, not "
                          "applied to %s; load the sidecar",
                          sidecar, path);
            iir_sidecar_free(&sc);
            return st;
        }
        if (sc.file[0] && !same_file(sc.file, path)) {
            st = iir_fail(err, IIR_ERR_INVALID,
                          "%s: file names %s, but the sidecar sits next to "
                          "%s; load the sidecar itself",
                          sidecar, sc.file, path);
            iir_sidecar_free(&sc);
            return st;
        }
    }
    iir_scene_builder b;
    iir_builder_init(&b, name, path);
    iir_status st = build(&b, path, has_sidecar ? &sc : NULL, out, err);
    if (has_sidecar) iir_sidecar_free(&sc);
    return st;
}

static iir_status load_path(const char *path, int depth, iir_scene **out, iir_error *err)
{
    *out = NULL;
    if (!path || !*path) return iir_fail(err, IIR_ERR_INVALID, "no scene path given");
    struct stat st;
    if (stat(path, &st) != 0)
        return iir_fail(err, IIR_ERR_IO, "cannot open scene %s: %s", path, strerror(errno));
    char file[PATH_MAX_LEN];
    if (S_ISDIR(st.st_mode)) {
        iir_status s = pick_in_folder(path, file, sizeof file, err);
        if (s != IIR_OK) return s;
        path = file;
    }
    if (ends_with(path, SIDECAR_EXT, false)) return load_sidecar(path, depth, out, err);
    return load_mesh(path, out, err);
}

iir_status iir_scene_load(const char *path, iir_scene **out, iir_error *err)
{
    return load_path(path, 0, out, err);
}

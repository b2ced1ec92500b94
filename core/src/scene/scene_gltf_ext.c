/* scene_gltf_ext.c -- the glTF file's own JSON beside assimp (scene_gltf_ext.h): reading it, the
 * extensions it uses or requires, checked against what iir reads, and which of its materials an
 * assimp material is. Not the materials' fields (scene_gltf_material.c), not the meshes and lights
 * assimp reads (scene_assimp.c). */
#include "scene_gltf_ext.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* The extensions iir reads (assimp or this file): a file may require these. */
static const char *const KNOWN[] = {"KHR_lights_punctual",
                                    "KHR_materials_emissive_strength",
                                    "KHR_materials_transmission",
                                    "KHR_materials_ior",
                                    "KHR_mesh_quantization",
                                    "KHR_texture_transform",
                                    NULL};

enum { MAX_JSON = 1 << 30 };

static bool ends_with_glb(const char *path)
{
    size_t n = strlen(path);
    return n >= 4 && strcasecmp(path + n - 4, ".glb") == 0;
}

/* The JSON text of a .glb (its first chunk, type JSON) or a .gltf (the whole file), NUL-ended. */
static iir_status read_json(const char *path, char **out, iir_error *err)
{
    *out = NULL;
    FILE *f = fopen(path, "rb");
    if (!f) return iir_fail(err, IIR_ERR_IO, "cannot read %s: %s", path, strerror(errno));
    bool ok = fseek(f, 0, SEEK_END) == 0;
    long size = ok ? ftell(f) : -1;
    ok = size >= 0 && fseek(f, 0, SEEK_SET) == 0;
    size_t len = ok ? (size_t)size : 0;
    if (ok && ends_with_glb(path)) { /* its first chunk, which must be JSON and in the file */
        unsigned char h[20];
        ok = fread(h, 1, 20, f) == 20 && memcmp(h, "glTF", 4) == 0 &&
             iir_glb_le32(h + 16) == 0x4E4F534Au && iir_glb_le32(h + 12) <= len - 20;
        len = ok ? iir_glb_le32(h + 12) : 0;
    }
    char *buf = ok && len <= MAX_JSON ? malloc(len + 1) : NULL;
    ok = buf && fread(buf, 1, len, f) == len;
    fclose(f);
    if (!ok) {
        free(buf);
        return iir_fail(err, IIR_ERR_FORMAT, "%s: cannot read its glTF JSON", path);
    }
    buf[len] = '\0';
    *out = buf;
    return IIR_OK;
}

static bool known(const char *name)
{
    for (const char *const *k = KNOWN; *k; k++)
        if (strcmp(*k, name) == 0) return true;
    return false;
}

/* extensionsRequired: every one iir reads; extensionsUsed: a note for each it does not. */
static iir_status check_extensions(const char *path, const cJSON *root, iir_scene_builder *b,
                                   iir_error *err)
{
    const cJSON *e;
    cJSON_ArrayForEach(e, cJSON_GetObjectItemCaseSensitive(root, "extensionsRequired")) if (
        cJSON_IsString(e) &&
        !known(e->valuestring)) return iir_fail(err, IIR_ERR_UNSUPPORTED,
                                                "%s requires the glTF extension %s, which iir does "
                                                "not read",
                                                path, e->valuestring);
    cJSON_ArrayForEach(
        e, cJSON_GetObjectItemCaseSensitive(root, "extensionsUsed")) if (cJSON_IsString(e) &&
                                                                         !known(e->valuestring))
        iir_builder_drop(b, "extension", e->valuestring,
                         "not read: what it adds to the scene is not rendered");
    return IIR_OK;
}

iir_status iir_gltf_ext_read(const char *path, iir_scene_builder *b, iir_gltf_ext *out,
                             iir_error *err)
{
    memset(out, 0, sizeof *out);
    char *text;
    iir_status st = read_json(path, &text, err);
    if (st != IIR_OK) return st;
    cJSON *root = cJSON_Parse(text);
    free(text);
    if (!root) return iir_fail(err, IIR_ERR_FORMAT, "%s: its glTF JSON does not parse", path);
    st = check_extensions(path, root, b, err);
    if (st != IIR_OK) {
        cJSON_Delete(root);
        return st;
    }
    out->path = path;
    out->root = root;
    const cJSON *images = cJSON_GetObjectItemCaseSensitive(root, "images");
    out->num_images = cJSON_IsArray(images) ? (uint32_t)cJSON_GetArraySize(images) : 0;
    out->image_refs = calloc(2 * (size_t)out->num_images + 1, sizeof *out->image_refs);
    if (!out->image_refs) {
        iir_gltf_ext_free(out);
        return iir_fail(err, IIR_ERR_NOMEM, "%s: out of memory", path);
    }
    return IIR_OK;
}

void iir_gltf_ext_free(iir_gltf_ext *e)
{
    cJSON_Delete(e->root);
    free(e->bin);
    free(e->image_refs);
    memset(e, 0, sizeof *e);
}

static const char *material_name(const cJSON *m)
{
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(m, "name");
    return cJSON_IsString(name) && name->valuestring ? name->valuestring : "";
}

int iir_gltf_ext_material_index(const iir_gltf_ext *e, uint32_t index, const char *name)
{
    const cJSON *mats = e->root ? cJSON_GetObjectItemCaseSensitive(e->root, "materials") : NULL;
    int n = cJSON_IsArray(mats) ? cJSON_GetArraySize(mats) : 0;
    if ((int)index < n) {
        const char *own = material_name(cJSON_GetArrayItem(mats, (int)index));
        if (!own[0] || strcmp(own, name) == 0) return (int)index;
    }
    for (int i = 0; i < n; i++) {
        const char *own = material_name(cJSON_GetArrayItem(mats, i));
        if (own[0] && strcmp(own, name) == 0) return i;
    }
    return -1;
}

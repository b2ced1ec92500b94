/* scene_assimp.c -- mesh files through the assimp C API (OBJ/MTL, glTF 2.0 and whatever else assimp
 * reads) into the scene builder: triangles, used materials, punctual lights, the first camera;
 * not the sidecar, not degenerate triangles (the builder counts those).
 *
 * Design. assimp imports with Triangulate and RemoveComponent (colours, bones, animations and
 * embedded textures are not used; vertex normals, the first UV set and tangents are kept, so
 * JoinIdenticalVertices welds on all of them). Vertices are checked
 * for NaN/Inf *before* JoinIdenticalVertices runs (aiApplyPostProcessing), because that step
 * silently welds a NaN vertex onto another one. FindDegenerates is not used: the builder counts
 * degenerate triangles itself. PreTransformVertices is not used either: in assimp 5.2 it applies a
 * glTF camera node's translation twice (the importer already copies it into aiCamera::mPosition)
 * and dereferences NULL for a light or camera that no node places. Instead this file walks the
 * node tree and applies each node's world transform to its meshes (instances included), lights
 * and camera.
 *
 * Conventions (docs/scene-format.md): a glTF light or camera sits at its node's origin looking
 * down its node's -z with +y up (the spec's rule; assimp's own pose fields are ignored for glTF).
 * KHR_lights_punctual intensity (candela for point/spot, lux for directional) times colour is
 * photometric: divided by 683 lm/W it is I0 in W/sr (a directional light's: its irradiance E in
 * W/m^2), as Blender's importer reads it, so a Blender user's lamps keep their balance with the
 * scene's emissive surfaces (a sidecar's lights are radiometric and replace them); a spot keeps
 * glTF's own profile (IIR_SPOT_GLTF: outer and inner cone angles), a directional light becomes a
 * sun. Area and ambient lights are ignored, noted by name in the scene (iir_scene.dropped) for the
 * commands' warnings. A glTF's materials come from its own JSON (scene_gltf_material.c); an OBJ's
 * from assimp's keys: Kd/map_Kd, norm or map_Bump, Ke/map_Ke, Pr/Pm, mirrors and glass
 * (convert_kind), and what is not read is noted.
 *
 * assimp's C API keeps the last error message in one process-wide string, so imports run under a
 * mutex (the only shared state here; it guards the library, not ours). */
#include "scene_build.h"
#include "scene_gltf_ext.h"
#include "scene_objtext.h"

#include <assimp/cimport.h>
#include <assimp/config.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <assimp/version.h>

#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

static pthread_mutex_t assimp_lock = PTHREAD_MUTEX_INITIALIZER;

/* ======================== small helpers ======================== */

typedef struct mat4 {
    double m[4][4]; /* row-major, column vectors: p' = M p, translation in m[i][3] */
} mat4;

static mat4 mat4_from_ai(const struct aiMatrix4x4 *a)
{
    mat4 r = {{{a->a1, a->a2, a->a3, a->a4},
               {a->b1, a->b2, a->b3, a->b4},
               {a->c1, a->c2, a->c3, a->c4},
               {a->d1, a->d2, a->d3, a->d4}}};
    return r;
}

static mat4 mat4_mul(const mat4 *a, const mat4 *b)
{
    mat4 r;
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++) s += a->m[i][k] * b->m[k][j];
            r.m[i][j] = s;
        }
    return r;
}

static iir_vec3 mat4_point(const mat4 *M, iir_vec3 p)
{
    double v[3];
    for (int i = 0; i < 3; i++)
        v[i] = M->m[i][0] * p.x + M->m[i][1] * p.y + M->m[i][2] * p.z + M->m[i][3];
    return iir_v3((float)v[0], (float)v[1], (float)v[2]);
}

static iir_vec3 mat4_vector(const mat4 *M, iir_vec3 d)
{
    double v[3];
    for (int i = 0; i < 3; i++) v[i] = M->m[i][0] * d.x + M->m[i][1] * d.y + M->m[i][2] * d.z;
    return iir_v3((float)v[0], (float)v[1], (float)v[2]);
}

static double mat4_det3(const mat4 *M)
{
    const double(*m)[4] = M->m;
    return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
           m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
           m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

/* The inverse transpose of M's 3x3 part (normals), up to a positive scale: its cofactor matrix
 * times the sign of the determinant. */
static mat4 normal_matrix(const mat4 *M)
{
    const double(*m)[4] = M->m;
    mat4 C = {{{0}}};
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            int i1 = (i + 1) % 3, i2 = (i + 2) % 3, j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            C.m[i][j] = m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1];
        }
    double sign = mat4_det3(M) < 0.0 ? -1.0 : 1.0;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) C.m[i][j] *= sign;
    return C;
}

static iir_vec3 v3_from_ai(struct aiVector3D v)
{
    return iir_v3(v.x, v.y, v.z);
}

static const char *file_extension(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    return dot && (!slash || dot > slash) ? dot : "";
}

static bool is_gltf(const char *path)
{
    const char *ext = file_extension(path);
    return strcasecmp(ext, ".gltf") == 0 || strcasecmp(ext, ".glb") == 0;
}

static bool is_known_extension(const char *path)
{
    return is_gltf(path) || strcasecmp(file_extension(path), ".obj") == 0;
}

/* World transform of a node: the product of its ancestors' transforms and its own. */
static mat4 node_world(const struct aiNode *node)
{
    mat4 M = mat4_from_ai(&node->mTransformation);
    for (const struct aiNode *p = node->mParent; p; p = p->mParent) {
        mat4 P = mat4_from_ai(&p->mTransformation);
        M = mat4_mul(&P, &M);
    }
    return M;
}

/* First node (depth first) called name, or NULL. */
static const struct aiNode *find_node(const struct aiNode *node, const char *name)
{
    if (strcmp(node->mName.data, name) == 0) return node;
    for (unsigned i = 0; i < node->mNumChildren; i++) {
        const struct aiNode *hit = find_node(node->mChildren[i], name);
        if (hit) return hit;
    }
    return NULL;
}

/* ======================== importing ======================== */

static iir_status check_readable(const char *path, iir_error *err)
{
    struct stat st;
    if (stat(path, &st) != 0)
        return iir_fail(err, IIR_ERR_IO, "cannot open scene file %s: %s", path, strerror(errno));
    if (!S_ISREG(st.st_mode))
        return iir_fail(err, IIR_ERR_IO, "cannot load %s: not a regular file", path);
    FILE *f = fopen(path, "rb");
    if (!f)
        return iir_fail(err, IIR_ERR_IO, "cannot read scene file %s: %s", path, strerror(errno));
    fclose(f);
    return IIR_OK;
}

/* NaN/Inf anywhere in the raw meshes, before vertex welding can hide it. */
static iir_status check_finite(const struct aiScene *s, const char *path, iir_error *err)
{
    for (unsigned m = 0; m < s->mNumMeshes; m++) {
        const struct aiMesh *mesh = s->mMeshes[m];
        for (unsigned v = 0; v < mesh->mNumVertices; v++) {
            iir_vec3 p = v3_from_ai(mesh->mVertices[v]);
            if (!iir_is_finite3(p))
                return iir_fail(err, IIR_ERR_FORMAT,
                                "%s: vertex %u of mesh '%s' is not finite (%g, %g, %g)", path, v,
                                mesh->mName.data, (double)p.x, (double)p.y, (double)p.z);
        }
    }
    return IIR_OK;
}

static iir_status import_failed(const char *path, const char *what, iir_error *err)
{
    const char *hint =
        is_known_extension(path) ? "" : " (iir reads .obj, .gltf, .glb and NAME.scene.json)";
    return iir_fail(err, IIR_ERR_FORMAT, "cannot load %s: assimp: %s%s", path, what, hint);
}

/* Imports, checks vertices, then welds identical vertices. On error *out is NULL. */
static iir_status import_scene(const char *path, const struct aiScene **out, iir_error *err)
{
    struct aiPropertyStore *props = aiCreatePropertyStore();
    aiSetImportPropertyInteger(props, AI_CONFIG_PP_RVC_FLAGS,
                               aiComponent_COLORS | aiComponent_BONEWEIGHTS |
                                   aiComponent_ANIMATIONS | aiComponent_TEXTURES);
    iir_status st = iir_objtext_check(path, err);
    if (st != IIR_OK) {
        aiReleasePropertyStore(props);
        *out = NULL;
        return st;
    }
    pthread_mutex_lock(&assimp_lock);
    const struct aiScene *s = aiImportFileExWithProperties(
        path, aiProcess_Triangulate | aiProcess_RemoveComponent, NULL, props);
    if (!s) st = import_failed(path, aiGetErrorString(), err);
    if (s) st = check_finite(s, path, err);
    if (s && st == IIR_OK) {
        /* on failure assimp has already released the scene */
        s = aiApplyPostProcessing(s, aiProcess_JoinIdenticalVertices);
        if (!s) st = import_failed(path, aiGetErrorString(), err);
    }
    if (s && st != IIR_OK) aiReleaseImport(s);
    pthread_mutex_unlock(&assimp_lock);
    aiReleasePropertyStore(props);
    *out = st == IIR_OK ? s : NULL;
    return st;
}

/* ======================== materials ======================== */

static iir_vec3 color3(const struct aiMaterial *mat, const char *key, unsigned type, unsigned idx,
                       iir_vec3 fallback)
{
    struct aiColor4D c;
    if (aiGetMaterialColor(mat, key, type, idx, &c) != aiReturn_SUCCESS) return fallback;
    return iir_v3(c.r, c.g, c.b);
}

static iir_vec3 clamp01(iir_vec3 c)
{
    return iir_v3(iir_clampf(c.x, 0.f, 1.f), iir_clampf(c.y, 0.f, 1.f), iir_clampf(c.z, 0.f, 1.f));
}

static iir_vec3 clamp0(iir_vec3 c)
{
    return iir_v3(fmaxf(c.x, 0.f), fmaxf(c.y, 0.f), fmaxf(c.z, 0.f));
}

static float float_key(const struct aiMaterial *mat, const char *key, unsigned type, unsigned idx,
                       float fallback)
{
    float f = fallback;
    return aiGetMaterialFloat(mat, key, type, idx, &f) == aiReturn_SUCCESS ? f : fallback;
}

/* The MTL illumination model (assimp's "$mat.illum"), -1 when the file gives none. */
static int mtl_illum(const struct aiMaterial *mat)
{
    int illum = -1;
    return aiGetMaterialInteger(mat, "$mat.illum", 0, 0, &illum) == aiReturn_SUCCESS ? illum : -1;
}

/* The kind of a material (docs/scene-format.md, section 3). MTL: illum 3 is a mirror of colour Ks;
 * illum 5 or 7 is glass of index Ni tinted by Tf (white without one). glTF: a transmission factor
 * above 0 (KHR_materials_transmission) is glass of index KHR_materials_ior (1.5 without it) tinted
 * by the base colour; metallic 1 with roughness 0 is a mirror of the base colour. The colours are
 * clamped to [0, 1]; the ior is checked by the builder. */
/* glTF's model for an MTL material that asks for more than Lambert: with the PBR extension's Pr
 * (roughness) or Pm (metallic), base colour Kd (metallic 0 and roughness 1 unless given); else a
 * Phong highlight, Ks with exponent Ns, as Blender's OBJ importer reads it: a dielectric of
 * reflectance 0.08 mean(Ks) at normal incidence (Principled's specular = mean(Ks)) and roughness
 * 1 - sqrt(Ns / 1000). Ks 0 stays Lambertian. */
static void pbr_kind(const struct aiMaterial *mat, iir_material *m)
{
    float f;
    bool pr = aiGetMaterialFloat(mat, AI_MATKEY_ROUGHNESS_FACTOR, &f) == aiReturn_SUCCESS;
    bool pm = aiGetMaterialFloat(mat, AI_MATKEY_METALLIC_FACTOR, &f) == aiReturn_SUCCESS;
    iir_vec3 ks = color3(mat, AI_MATKEY_COLOR_SPECULAR, iir_v3s(0.f));
    float spec = (ks.x + ks.y + ks.z) / 3.f;
    if (!pr && !pm && !(spec > 0.f)) return;
    m->kind = IIR_MATERIAL_METAL_ROUGH;
    m->specular_f0 = 0.04f;
    if (pr || pm) {
        m->roughness = iir_clampf(float_key(mat, AI_MATKEY_ROUGHNESS_FACTOR, 1.f), 0.f, 1.f);
        m->metallic = iir_clampf(float_key(mat, AI_MATKEY_METALLIC_FACTOR, 0.f), 0.f, 1.f);
        return;
    }
    float ns = iir_clampf(float_key(mat, AI_MATKEY_SHININESS, 0.f), 0.f, 1000.f);
    m->roughness = 1.f - sqrtf(ns / 1000.f);
    m->metallic = 0.f;
    m->specular_f0 = iir_clampf(0.08f * spec, 0.f, 1.f);
}

static void convert_kind(const struct aiMaterial *mat, iir_vec3 base, iir_material *m)
{
    int illum = mtl_illum(mat);
    float transmission = float_key(mat, AI_MATKEY_TRANSMISSION_FACTOR, 0.f);
    float metallic = float_key(mat, AI_MATKEY_METALLIC_FACTOR, 0.f);
    float roughness = float_key(mat, AI_MATKEY_ROUGHNESS_FACTOR, 1.f);
    if (illum == 5 || illum == 7 || transmission > 0.f) {
        m->kind = IIR_MATERIAL_GLASS;
        m->ior = float_key(mat, AI_MATKEY_REFRACTI, 1.5f);
        m->specular = illum >= 0 ? color3(mat, AI_MATKEY_COLOR_TRANSPARENT, iir_v3s(1.f)) : base;
    } else if (illum == 3) {
        m->kind = IIR_MATERIAL_MIRROR;
        m->specular = color3(mat, AI_MATKEY_COLOR_SPECULAR, iir_v3s(0.f));
    } else if (metallic >= 1.f && roughness <= 0.f) {
        m->kind = IIR_MATERIAL_MIRROR;
        m->specular = base;
    } else {
        pbr_kind(mat, m);
        return;
    }
    m->specular = clamp01(m->specular);
    m->albedo = iir_v3s(0.f); /* no diffuse part */
}

/* Diffuse colour -> albedo (clamped to [0, 1]), emissive colour -> emission (negatives to 0;
 * NaN stays NaN and is refused by the builder); a mirror or glass as convert_kind says. */
static iir_material convert_material(const struct aiMaterial *mat, unsigned index)
{
    iir_material m;
    memset(&m, 0, sizeof m);
    struct aiString name;
    name.length = 0;
    name.data[0] = '\0';
    if (aiGetMaterialString(mat, AI_MATKEY_NAME, &name) == aiReturn_SUCCESS && name.data[0])
        iir_scene_strcpy(m.name, sizeof m.name, name.data);
    else
        snprintf(m.name, sizeof m.name, "material%u", index);
    iir_vec3 kd = color3(mat, AI_MATKEY_COLOR_DIFFUSE, iir_v3s(0.8f));
    iir_vec3 ke = color3(mat, AI_MATKEY_COLOR_EMISSIVE, iir_v3s(0.f));
    m.albedo = isnan(kd.x) || isnan(kd.y) || isnan(kd.z) ? kd : clamp01(kd);
    m.emission = isnan(ke.x) || isnan(ke.y) || isnan(ke.z) ? ke : clamp0(ke);
    iir_vec3 base = color3(mat, AI_MATKEY_BASE_COLOR, kd);
    if (!isnan(kd.x + kd.y + kd.z)) convert_kind(mat, base, &m);
    return m;
}

/* Notes what a material has that iir does not render (iir_scene.dropped): a colour texture,
 * transparency, metal. Specular colours (OBJ Ks, which exporters write by default) are not noted:
 * every surface is diffuse (docs/scene-format.md, section 3). */
static void note_material(iir_scene_builder *b, const struct aiMaterial *mat, const iir_material *m)
{
    const char *name = m->name;
    float f = 0.f;
    if (aiGetMaterialTextureCount(mat, aiTextureType_HEIGHT) &&
        aiGetMaterialTextureCount(mat, aiTextureType_NORMALS))
        iir_builder_drop(b, "material", name, "map_Bump beside norm: norm is the normal map");
    if (aiGetMaterialTextureCount(mat, aiTextureType_OPACITY) && !m->alpha_mode)
        iir_builder_drop(b, "material", name,
                         "an opacity map (map_d) apart from map_Kd: not rendered, opaque");
    if (m->kind != IIR_MATERIAL_GLASS && !m->alpha_mode &&
        aiGetMaterialFloat(mat, AI_MATKEY_OPACITY, &f) == aiReturn_SUCCESS && f < 0.999f)
        iir_builder_drop(b, "material", name, "transparency (opacity %g): rendered opaque",
                         (double)f);
    if (aiGetMaterialFloat(mat, AI_MATKEY_TRANSMISSION_FACTOR, &f) == aiReturn_SUCCESS && f > 0.f &&
        f < 1.f)
        iir_builder_drop(b, "material", name, "transmission %g: rendered as clear glass",
                         (double)f);
    if (aiGetMaterialTextureCount(mat, aiTextureType_DIFFUSE_ROUGHNESS) +
        aiGetMaterialTextureCount(mat, aiTextureType_METALNESS))
        iir_builder_drop(b, "material", name,
                         "a roughness or metallic map (map_Pr, map_Pm): not read, its factors are "
                         "used");
    if (m->kind != IIR_MATERIAL_METAL_ROUGH &&
        aiGetMaterialFloat(mat, AI_MATKEY_METALLIC_FACTOR, &f) == aiReturn_SUCCESS && f > 0.f &&
        !(f >= 1.f && float_key(mat, AI_MATKEY_ROUGHNESS_FACTOR, 1.f) <= 0.f) &&
        float_key(mat, AI_MATKEY_TRANSMISSION_FACTOR, 0.f) <= 0.f)
        iir_builder_drop(b, "material", name,
                         "metallic %g: rendered as a diffuse surface of its base colour",
                         (double)f);
}

typedef struct loader {
    const char *path;
    const struct aiScene *s;
    iir_scene_builder *b;
    uint32_t *material_map; /* assimp material -> builder material, UINT32_MAX until used */
    iir_gltf_ext gltf;      /* a glTF's own JSON: what assimp drops (empty for other formats) */
} loader;

/* One of an OBJ/MTL material's texture maps (assimp's type) as a texture of the builder, read
 * relative to the file's folder; 0 when it has none, a warning naming it when it cannot be read. */
static iir_status obj_map(loader *L, const struct aiMaterial *am, enum aiTextureType type,
                          bool srgb, const char *material, iir_texref *ref, iir_error *err)
{
    memset(ref, 0, sizeof *ref);
    ref->transform = iir_tex_transform_identity();
    struct aiString file;
    if (aiGetMaterialTextureCount(am, type) == 0 ||
        aiGetMaterialTexture(am, type, 0, &file, NULL, NULL, NULL, NULL, NULL, NULL) !=
            aiReturn_SUCCESS)
        return IIR_OK;
    char path[2048];
    const char *slash = strrchr(L->path, '/');
    int dir = slash ? (int)(slash - L->path + 1) : 0;
    for (char *c = file.data; *c; c++)
        if (*c == '\\') *c = '/';
    if (file.data[0] == '/' || strstr(file.data, "..")) {
        iir_builder_drop(L->b, "material", material, "texture %s: not beside the file, not read",
                         file.data);
        return IIR_OK;
    }
    snprintf(path, sizeof path, "%.*s%s", dir, L->path, file.data);
    iir_texture *tex = NULL;
    iir_error why = {0};
    iir_status st = iir_texture_read(path, srgb, &tex, &why);
    if (st == IIR_ERR_NOMEM) return iir_fail(err, st, "%s", why.msg);
    if (st != IIR_OK) {
        iir_builder_drop(L->b, "material", material,
                         "a texture cannot be read (%s): its flat colour is used", why.msg);
        return IIR_OK;
    }
    return iir_builder_add_texture(L->b, tex, &ref->texture, err);
}

/* map_Kd (its alpha, or map_d naming the same file, is the cut-out), the normal map and map_Ke.
 * The normal map is `norm`, else `map_Bump`/`bump` as Blender's exporter writes and its importer
 * reads it: a tangent-space normal map of strength -bm (assimp's "$tex.bumpmult"; 1 without one).
 */
static iir_status obj_textures(loader *L, const struct aiMaterial *am, iir_material *m,
                               iir_error *err)
{
    if (m->kind != IIR_MATERIAL_DIFFUSE && m->kind != IIR_MATERIAL_METAL_ROUGH) return IIR_OK;
    iir_status st = obj_map(L, am, aiTextureType_DIFFUSE, true, m->name, &m->base_tex, err);
    bool norm = aiGetMaterialTextureCount(am, aiTextureType_NORMALS) > 0;
    if (st == IIR_OK)
        st = obj_map(L, am, norm ? aiTextureType_NORMALS : aiTextureType_HEIGHT, false, m->name,
                     &m->normal_tex, err);
    if (st == IIR_OK)
        st = obj_map(L, am, aiTextureType_EMISSIVE, true, m->name, &m->emission_tex, err);
    m->normal_scale = norm ? 1.f : float_key(am, "$tex.bumpmult", aiTextureType_HEIGHT, 0, 1.f);
    if (!isfinite(m->normal_scale)) m->normal_scale = 1.f;
    m->opacity = 1.f;
    m->alpha_cutoff = 0.5f;
    if (st == IIR_OK && m->base_tex.texture &&
        iir_texture_has_alpha(L->b->textures[m->base_tex.texture - 1]))
        m->alpha_mode = IIR_ALPHA_MASK;
    /* a texture colour is multiplied by Kd, which exporters often leave at 0.8: MTL's rule */
    return st;
}

/* Builder index of assimp material i, adding it on first use (unused materials are dropped). */
static iir_status use_material(loader *L, unsigned i, uint32_t *out, iir_error *err)
{
    if (i >= L->s->mNumMaterials)
        return iir_fail(err, IIR_ERR_FORMAT, "%s: a mesh refers to material %u of %u", L->path, i,
                        L->s->mNumMaterials);
    if (L->material_map[i] == UINT32_MAX) {
        const struct aiMaterial *am = L->s->mMaterials[i];
        iir_material m = convert_material(am, i);
        /* a glTF's own material, as the spec writes it (assimp 5.2 drops much of it) */
        int g = L->gltf.root ? iir_gltf_ext_material_index(&L->gltf, i, m.name) : -1;
        iir_status st = IIR_OK;
        if (g >= 0) {
            memset(&m, 0, sizeof m);
            snprintf(m.name, sizeof m.name, "material%u", i);
            st = iir_gltf_ext_material(&L->gltf, g, L->b, &m, err);
        } else {
            st = obj_textures(L, am, &m, err);
            if (st == IIR_OK) note_material(L->b, am, &m);
        }
        if (st == IIR_OK) st = iir_builder_add_material(L->b, &m, &L->material_map[i], err);
        if (st != IIR_OK) return st;
    }
    *out = L->material_map[i];
    return IIR_OK;
}

/* ======================== meshes ======================== */

static iir_status add_faces(loader *L, const struct aiMesh *mesh, uint32_t first, uint32_t mat,
                            bool flip, iir_error *err)
{
    for (unsigned f = 0; f < mesh->mNumFaces; f++) {
        const struct aiFace *face = &mesh->mFaces[f];
        if (face->mNumIndices != 3) continue; /* points and lines */
        const unsigned *ix = face->mIndices;
        if (ix[0] >= mesh->mNumVertices || ix[1] >= mesh->mNumVertices ||
            ix[2] >= mesh->mNumVertices)
            return iir_fail(err, IIR_ERR_FORMAT,
                            "%s: face %u of mesh '%s' has a vertex index "
                            "out of range",
                            L->path, f, mesh->mName.data);
        uint32_t a = first + ix[0], b = first + ix[flip ? 2 : 1], c = first + ix[flip ? 1 : 2];
        iir_status st = iir_builder_add_triangle(L->b, a, b, c, mat, err);
        if (st != IIR_OK) return st;
    }
    return IIR_OK;
}

/* Appends one instance of mesh under world transform M. A mirroring transform flips the winding
 * so that normals keep their side. */
static iir_status add_mesh(loader *L, const struct aiMesh *mesh, const mat4 *M, iir_error *err)
{
    uint32_t mat = 0, first = L->b->num_vertices;
    iir_status st = use_material(L, mesh->mMaterialIndex, &mat, err);
    if (st == IIR_OK) st = iir_builder_reserve(L->b, mesh->mNumVertices, mesh->mNumFaces, err);
    mat4 N = normal_matrix(M);
    float hand = mat4_det3(M) < 0.0 ? -1.f : 1.f;
    for (unsigned v = 0; st == IIR_OK && v < mesh->mNumVertices; v++) {
        iir_vec3 n, t;
        iir_vec2 uv;
        float tan4[4];
        iir_vertex_attr a = {NULL, NULL, NULL};
        if (mesh->mNormals) {
            n = mat4_vector(&N, v3_from_ai(mesh->mNormals[v]));
            if (iir_length_sq(n) > 0.f && isfinite(iir_length_sq(n))) a.normal = &n;
            if (a.normal) n = iir_normalize(n);
        }
        if (mesh->mTextureCoords[0]) {
            /* assimp gives v up (OpenGL); iir keeps glTF's: (0, 0) the image's top left */
            uv = iir_v2(mesh->mTextureCoords[0][v].x, 1.f - mesh->mTextureCoords[0][v].y);
            a.uv = &uv;
        }
        if (mesh->mTangents && mesh->mBitangents && mesh->mNormals) {
            iir_vec3 tl = v3_from_ai(mesh->mTangents[v]), bl = v3_from_ai(mesh->mBitangents[v]);
            float w = iir_dot(iir_cross(v3_from_ai(mesh->mNormals[v]), tl), bl) < 0.f ? -1.f : 1.f;
            t = mat4_vector(M, tl);
            if (iir_length_sq(t) > 0.f && isfinite(iir_length_sq(t))) {
                t = iir_normalize(t);
                tan4[0] = t.x, tan4[1] = t.y, tan4[2] = t.z, tan4[3] = w * hand;
                a.tangent = tan4;
            }
        }
        st = iir_builder_add_vertex_attr(L->b, mat4_point(M, v3_from_ai(mesh->mVertices[v])), &a,
                                         NULL, err);
    }
    if (st != IIR_OK) return st;
    return add_faces(L, mesh, first, mat, mat4_det3(M) < 0.0, err);
}

static iir_status add_node(loader *L, const struct aiNode *node, const mat4 *parent, iir_error *err)
{
    mat4 local = mat4_from_ai(&node->mTransformation);
    mat4 M = mat4_mul(parent, &local);
    for (unsigned i = 0; i < node->mNumMeshes; i++) {
        unsigned m = node->mMeshes[i];
        if (m >= L->s->mNumMeshes)
            return iir_fail(err, IIR_ERR_FORMAT, "%s: node '%s' refers to mesh %u of %u", L->path,
                            node->mName.data, m, L->s->mNumMeshes);
        iir_status st = add_mesh(L, L->s->mMeshes[m], &M, err);
        if (st != IIR_OK) return st;
    }
    for (unsigned c = 0; c < node->mNumChildren; c++) {
        iir_status st = add_node(L, node->mChildren[c], &M, err);
        if (st != IIR_OK) return st;
    }
    return IIR_OK;
}

/* ======================== lights and camera ======================== */

/* A light's pose in its node's space: glTF fixes it (origin, -z, +y); other formats say it. */
static void light_local_pose(const loader *L, const struct aiLight *al, iir_vec3 *p, iir_vec3 *d,
                             iir_vec3 *u)
{
    if (is_gltf(L->path)) {
        *p = iir_v3(0.f, 0.f, 0.f);
        *d = iir_v3(0.f, 0.f, -1.f);
        *u = iir_v3(0.f, 1.f, 0.f);
    } else {
        *p = v3_from_ai(al->mPosition);
        *d = v3_from_ai(al->mDirection);
        *u = v3_from_ai(al->mUp);
    }
}

/* iir's type for an assimp light that add_lights keeps (area and ambient ones it drops). */
static iir_light_type light_type(enum aiLightSourceType t)
{
    return t == aiLightSource_SPOT          ? IIR_LIGHT_SPOT
           : t == aiLightSource_DIRECTIONAL ? IIR_LIGHT_SUN
                                            : IIR_LIGHT_POINT;
}

/* A spot with glTF's profile: assimp gives glTF's half-angles as they are (outerConeAngle,
 * default pi/4; innerConeAngle, default 0). A sun gets a placeholder disk that
 * iir_builder_finish refits to the scene's bounds (iir_light_fit_sun). */
/* The luminous efficacy glTF's photometric light units are converted with (KHR_lights_punctual:
 * candela, lux), Blender's figure for its lamps' watts. */
#define IIR_LUMENS_PER_WATT 683.f

static iir_light convert_light(const loader *L, const struct aiLight *al, const mat4 *M)
{
    iir_light l;
    memset(&l, 0, sizeof l);
    l.type = light_type(al->mType);
    iir_scene_strcpy(l.name, sizeof l.name, al->mName.data);
    iir_vec3 p, d, u;
    light_local_pose(L, al, &p, &d, &u);
    l.position = l.type == IIR_LIGHT_SUN ? iir_v3s(0.f) : mat4_point(M, p);
    /* assimp gives colour times the file's intensity: in glTF candela (lux for a sun) */
    float to_watts = is_gltf(L->path) ? 1.f / IIR_LUMENS_PER_WATT : 1.f;
    l.intensity =
        iir_scale(iir_v3(al->mColorDiffuse.r, al->mColorDiffuse.g, al->mColorDiffuse.b), to_watts);
    if (l.type != IIR_LIGHT_POINT) {
        l.direction = iir_normalize(mat4_vector(M, d));
        l.up = iir_normalize(mat4_vector(M, u));
    }
    if (l.type == IIR_LIGHT_SPOT) {
        l.profile = IIR_SPOT_GLTF;
        l.cone_angle = al->mAngleOuterCone;
        l.inner_angle = iir_clampf(al->mAngleInnerCone, 0.f, l.cone_angle);
    }
    if (l.type == IIR_LIGHT_SUN) l.radius = 1.f;
    return l;
}

/* What happens to a light of type t that iir does not render; NULL for point, spot and
 * directional. */
static const char *unrendered_light(enum aiLightSourceType t)
{
    switch (t) {
    case aiLightSource_POINT:
    case aiLightSource_SPOT:
    case aiLightSource_DIRECTIONAL:
        return NULL;
    case aiLightSource_AREA:
        return "an area light: ignored; give its emitter an emissive material instead";
    case aiLightSource_AMBIENT:
        return "an ambient light: ignored";
    default:
        return "a light of a type iir does not know: ignored";
    }
}

/* Point, spot and directional lights that a node places; the others (area, ambient, unplaced)
 * are skipped and noted (iir_scene.dropped). */
static iir_status add_lights(loader *L, iir_error *err)
{
    for (unsigned i = 0; i < L->s->mNumLights; i++) {
        const struct aiLight *al = L->s->mLights[i];
        const char *why = unrendered_light(al->mType);
        const struct aiNode *node = find_node(L->s->mRootNode, al->mName.data);
        if (!why && !node) why = "placed by no node of the scene: ignored";
        if (why) {
            iir_builder_drop(L->b, "light", al->mName.data, "%s", why);
            continue;
        }
        mat4 M = node_world(node);
        iir_light l = convert_light(L, al, &M);
        iir_error e;
        if (iir_light_validate(&l, &e) != IIR_OK)
            return iir_fail(err, e.status, "%s: %s", L->path, e.msg);
        iir_status st = iir_builder_add_light(L->b, &l, err);
        if (st != IIR_OK) return st;
    }
    return IIR_OK;
}

/* Vertical field of view in degrees from assimp's horizontal one. assimp before 5.3 stores a glTF
 * camera's yfov * aspect (its issue #4435); 5.3 and later store the true horizontal angle, as
 * other importers do. An aspect of 0 means "unknown": the angle is then the vertical one. */
static float camera_fov_y(const loader *L, const struct aiCamera *cam)
{
    double h = cam->mHorizontalFOV, a = cam->mAspect;
    if (!(a > 0.0)) return iir_degrees((float)h);
    bool linear = is_gltf(L->path) && (aiGetVersionMajor() < 5 ||
                                       (aiGetVersionMajor() == 5 && aiGetVersionMinor() < 3));
    double v = linear ? h / a : 2.0 * atan(tan(0.5 * h) / a);
    return iir_degrees((float)v);
}

/* The first perspective camera that a node places, if any (assimp gives orthographic cameras a
 * zero field of view). */
static void set_camera(loader *L)
{
    for (unsigned i = 0; i < L->s->mNumCameras; i++) {
        const struct aiCamera *ac = L->s->mCameras[i];
        const struct aiNode *node = find_node(L->s->mRootNode, ac->mName.data);
        if (!node || !(ac->mHorizontalFOV > 0.f)) continue;
        mat4 M = node_world(node);
        bool gltf = is_gltf(L->path);
        iir_vec3 p = gltf ? iir_v3(0.f, 0.f, 0.f) : v3_from_ai(ac->mPosition);
        iir_vec3 d = gltf ? iir_v3(0.f, 0.f, -1.f) : v3_from_ai(ac->mLookAt);
        iir_vec3 u = gltf ? iir_v3(0.f, 1.f, 0.f) : v3_from_ai(ac->mUp);
        iir_camera cam;
        cam.position = mat4_point(&M, p);
        cam.target = iir_add(cam.position, iir_normalize(mat4_vector(&M, d)));
        cam.up = iir_normalize(mat4_vector(&M, u));
        cam.fov_y = camera_fov_y(L, ac);
        iir_builder_set_camera(L->b, &cam);
        iir_builder_set_camera_origin(L->b, IIR_CAMERA_FILE, ac->mAspect > 0.f ? ac->mAspect : 0.f);
        return;
    }
}

/* ======================== the entry point ======================== */

static iir_status load_scene(loader *L, iir_error *err)
{
    uint32_t before = L->b->num_triangles;
    mat4 identity = {{{1, 0, 0, 0}, {0, 1, 0, 0}, {0, 0, 1, 0}, {0, 0, 0, 1}}};
    iir_status st = L->s->mRootNode ? add_node(L, L->s->mRootNode, &identity, err) : IIR_OK;
    if (st != IIR_OK) return st;
    if (L->b->num_triangles == before)
        return iir_fail(err, IIR_ERR_FORMAT,
                        "%s: no triangles (the file has no faces, or only "
                        "points and lines)",
                        L->path);
    st = add_lights(L, err);
    if (st == IIR_OK) set_camera(L);
    return st;
}

iir_status iir_assimp_load(const char *path, iir_scene_builder *b, iir_error *err)
{
    iir_status st = check_readable(path, err);
    if (st != IIR_OK) return st;
    const struct aiScene *s;
    st = import_scene(path, &s, err);
    if (st != IIR_OK) return st;
    loader L = {path, s, b, malloc(sizeof(uint32_t) * (s->mNumMaterials + 1)), {0}};
    if (!L.material_map) {
        st = iir_fail(err, IIR_ERR_NOMEM, "%s: out of memory", path);
    } else {
        for (unsigned i = 0; i < s->mNumMaterials; i++) L.material_map[i] = UINT32_MAX;
        if (is_gltf(path)) st = iir_gltf_ext_read(path, b, &L.gltf, err);
        if (st == IIR_OK) st = load_scene(&L, err);
    }
    iir_gltf_ext_free(&L.gltf);
    free(L.material_map);
    aiReleaseImport(s);
    return st;
}

/* scene_gltf_material.c -- a glTF 2.0 material as iir's material (scene_gltf_ext.h): the
 * metallic-roughness fields with the spec's defaults (section 3.9: factors 1, alphaMode OPAQUE,
 * cutoff 0.5), its textures with their samplers and KHR_texture_transform, emission with
 * KHR_materials_emissive_strength, KHR_materials_transmission + KHR_materials_ior as smooth glass;
 * images decoded from a file beside the glTF, a buffer, or a .glb's binary chunk. Values are read
 * with json_read.h's readers, so a bad one fails naming the material and the field. Not the
 * extensions check or the file's JSON (scene_gltf_ext.c), not meshes (scene_assimp.c). */
#include "scene_gltf_ext.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "iir/json_read.h"

/* ======================== images ======================== */

/* The whole of a file, or NULL (errno says why). */
static unsigned char *slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    unsigned char *buf = NULL;
    long n = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
    if (n >= 0 && fseek(f, 0, SEEK_SET) == 0 && (buf = malloc((size_t)n + 1)) &&
        fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
        errno = EIO;
    }
    fclose(f);
    *size = buf ? (size_t)n : 0;
    return buf;
}

/* A relative uri (percent-decoded) joined with the glTF's folder; false for absolute paths,
 * "..", schemes (data:, http:) and names too long. */
static bool uri_path(const char *gltf, const char *uri, char *out, size_t n)
{
    if (!uri[0] || uri[0] == '/' || strstr(uri, "..") || strchr(uri, ':')) return false;
    const char *slash = strrchr(gltf, '/');
    size_t dir = slash ? (size_t)(slash - gltf + 1) : 0;
    if (dir + strlen(uri) + 1 > n) return false;
    memcpy(out, gltf, dir);
    char *o = out + dir;
    for (const char *u = uri; *u; u++) {
        unsigned c;
        if (u[0] == '%' && sscanf(u + 1, "%2x", &c) == 1 && c != 0 && c != '/') {
            *o++ = (char)c;
            u += 2;
        } else {
            *o++ = *u;
        }
    }
    *o = '\0';
    return true;
}

/* A .glb's binary chunk (the chunk after the JSON one), read once. */
static const unsigned char *glb_bin(iir_gltf_ext *e, size_t *size)
{
    if (!e->bin) {
        size_t n;
        unsigned char *f = slurp(e->path, &n);
        if (!f || n < 20 || memcmp(f, "glTF", 4) != 0) {
            free(f);
            return NULL;
        }
        size_t at = 20 + (size_t)((iir_glb_le32(f + 12) + 3u) & ~3u);
        if (at + 8 > n || iir_glb_le32(f + at + 4) != 0x004E4942u ||
            iir_glb_le32(f + at) > n - at - 8) {
            free(f);
            return NULL;
        }
        e->bin_size = iir_glb_le32(f + at);
        memmove(f, f + at + 8, e->bin_size);
        e->bin = f;
    }
    *size = e->bin_size;
    return e->bin;
}

/* The bytes of bufferView `view` (malloc'ed copy), or NULL with a reason. */
static unsigned char *view_bytes(iir_gltf_ext *e, int view, size_t *size, const char **why)
{
    const cJSON *v =
        cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(e->root, "bufferViews"), view);
    const cJSON *bi = cJSON_GetObjectItemCaseSensitive(v, "buffer");
    const cJSON *off = cJSON_GetObjectItemCaseSensitive(v, "byteOffset");
    const cJSON *len = cJSON_GetObjectItemCaseSensitive(v, "byteLength");
    *why = "its bufferView is not valid";
    if (!cJSON_IsNumber(bi) || !cJSON_IsNumber(len) || len->valuedouble < 0) return NULL;
    double o = cJSON_IsNumber(off) ? off->valuedouble : 0.0;
    const cJSON *buf =
        cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(e->root, "buffers"), bi->valueint);
    const cJSON *uri = cJSON_GetObjectItemCaseSensitive(buf, "uri");
    size_t n = 0;
    unsigned char *file = NULL;
    const unsigned char *data;
    if (cJSON_IsString(uri)) {
        char path[1024];
        *why = "its buffer's uri is not a relative file name";
        if (!uri_path(e->path, uri->valuestring, path, sizeof path)) return NULL;
        *why = "its buffer cannot be read";
        data = file = slurp(path, &n);
    } else {
        *why = "the .glb has no binary chunk";
        data = glb_bin(e, &n);
    }
    unsigned char *out = NULL;
    if (data && o >= 0 && o + len->valuedouble <= (double)n) {
        *size = (size_t)len->valuedouble;
        out = malloc(*size + 1);
        if (out) memcpy(out, data + (size_t)o, *size);
        *why = out ? NULL : "out of memory";
    } else if (data) {
        *why = "its bufferView lies outside its buffer";
    }
    free(file);
    return out;
}

/* Decodes image `img` (from its uri or bufferView) into a texture. */
static iir_status decode_image(iir_gltf_ext *e, int img, bool srgb, iir_texture **tex,
                               iir_error *err)
{
    const cJSON *im = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(e->root, "images"), img);
    const cJSON *uri = cJSON_GetObjectItemCaseSensitive(im, "uri");
    const cJSON *view = cJSON_GetObjectItemCaseSensitive(im, "bufferView");
    char what[1100];
    if (cJSON_IsString(uri)) {
        char path[1024];
        if (!uri_path(e->path, uri->valuestring, path, sizeof path))
            return iir_fail(err, IIR_ERR_UNSUPPORTED,
                            "image %d's uri '%.200s' is not a relative file name beside the file",
                            img, uri->valuestring);
        return iir_texture_read(path, srgb, tex, err);
    }
    if (!cJSON_IsNumber(view))
        return iir_fail(err, IIR_ERR_FORMAT, "image %d has neither a uri nor a bufferView", img);
    size_t n = 0;
    const char *why = NULL;
    unsigned char *bytes = view_bytes(e, view->valueint, &n, &why);
    if (!bytes) return iir_fail(err, IIR_ERR_FORMAT, "image %d: %s", img, why);
    snprintf(what, sizeof what, "%s: image %d", e->path, img);
    iir_status st = iir_texture_decode(bytes, n, what, srgb, tex, err);
    free(bytes);
    return st;
}

/* The builder's ref for image img in the colour space asked for (decoded on first use); 0 with a
 * warning naming the material when it cannot be read. IIR_ERR_NOMEM only. */
static iir_status image_ref(iir_gltf_ext *e, int img, bool srgb, iir_scene_builder *b,
                            const char *material, uint32_t *ref, iir_error *err)
{
    *ref = 0;
    if (img < 0 || (uint32_t)img >= e->num_images) {
        iir_builder_drop(b, "material", material, "refers to image %d of %u: its factor is used",
                         img, e->num_images);
        return IIR_OK;
    }
    uint32_t *slot = &e->image_refs[2 * img + (srgb ? 1 : 0)];
    if (*slot == UINT32_MAX) return IIR_OK;
    if (*slot) {
        *ref = *slot;
        return IIR_OK;
    }
    iir_texture *tex = NULL;
    iir_error why = {0};
    iir_status st = decode_image(e, img, srgb, &tex, &why);
    if (st == IIR_ERR_NOMEM) return iir_fail(err, st, "%s", why.msg);
    if (st != IIR_OK) {
        *slot = UINT32_MAX;
        iir_builder_drop(b, "material", material,
                         "a texture cannot be read (%s): its factor is used", why.msg);
        return IIR_OK;
    }
    st = iir_builder_add_texture(b, tex, slot, err);
    *ref = *slot;
    return st;
}

/* ======================== fields ======================== */

typedef struct mat_reader {
    iir_gltf_ext *e;
    iir_scene_builder *b;
    iir_json_file jf;
    char path[IIR_JSON_PATH]; /* "materials[i]" */
    const char *name;
    bool ok;
} mat_reader;

static const cJSON *member(const cJSON *obj, const char *name)
{
    return cJSON_GetObjectItemCaseSensitive(obj, name);
}

/* An optional number in [lo, hi] at obj.name (fallback when absent). */
static float number(mat_reader *R, const cJSON *obj, const char *prefix, const char *name,
                    double lo, double hi, float fallback)
{
    const cJSON *v = member(obj, name);
    if (!v || !R->ok) return fallback;
    char path[IIR_JSON_PATH];
    iir_json_path(path, prefix, name);
    double d = fallback;
    iir_json_range range = {lo, hi, false, false, NULL};
    R->ok = iir_json_number(&R->jf.r, v, path, range, &d);
    return (float)d;
}

static iir_wrap wrap_mode(int gl)
{
    return gl == 33071 ? IIR_WRAP_CLAMP : gl == 33648 ? IIR_WRAP_MIRROR : IIR_WRAP_REPEAT;
}

static iir_tex_sampler sampler(const iir_gltf_ext *e, const cJSON *tex)
{
    iir_tex_sampler s = {IIR_WRAP_REPEAT, IIR_WRAP_REPEAT, false, false, false};
    const cJSON *si = member(tex, "sampler");
    const cJSON *sm =
        cJSON_IsNumber(si) ? cJSON_GetArrayItem(member(e->root, "samplers"), si->valueint) : NULL;
    const cJSON *mag = member(sm, "magFilter"), *min = member(sm, "minFilter");
    const cJSON *ws = member(sm, "wrapS"), *wt = member(sm, "wrapT");
    if (cJSON_IsNumber(ws)) s.wrap_s = wrap_mode(ws->valueint);
    if (cJSON_IsNumber(wt)) s.wrap_t = wrap_mode(wt->valueint);
    s.mag_nearest = cJSON_IsNumber(mag) && mag->valueint == 9728;
    if (cJSON_IsNumber(min)) {
        int f = min->valueint;
        s.min_no_mip = f == 9728 || f == 9729;
        s.min_nearest = f == 9728 || f == 9984 || f == 9986;
    }
    return s;
}

/* KHR_texture_transform of a textureInfo (identity without it). */
static iir_tex_transform transform(mat_reader *R, const cJSON *info, const char *prefix)
{
    iir_tex_transform t = iir_tex_transform_identity();
    const cJSON *x = member(member(info, "extensions"), "KHR_texture_transform");
    if (!x) return t;
    char path[IIR_JSON_PATH];
    iir_json_path(path, prefix, "extensions.KHR_texture_transform");
    double v[2];
    if (member(x, "offset") && R->ok) {
        char p[IIR_JSON_PATH];
        iir_json_path(p, path, "offset");
        R->ok = iir_json_numbers(&R->jf.r, member(x, "offset"), p, 2, -1e6, 1e6, v);
        t.offset = iir_v2((float)v[0], (float)v[1]);
    }
    if (member(x, "scale") && R->ok) {
        char p[IIR_JSON_PATH];
        iir_json_path(p, path, "scale");
        R->ok = iir_json_numbers(&R->jf.r, member(x, "scale"), p, 2, -1e6, 1e6, v);
        t.scale = iir_v2((float)v[0], (float)v[1]);
    }
    t.rotation = number(R, x, path, "rotation", -1e6, 1e6, 0.f);
    if (member(x, "texCoord"))
        iir_builder_drop(R->b, "material", R->name,
                         "%s.texCoord: a second texture coordinate set is not read; TEXCOORD_0 is "
                         "used",
                         path);
    return t;
}

/* A textureInfo at obj.name into *ref (texture 0 when absent or unreadable). */
static iir_status texture(mat_reader *R, const cJSON *obj, const char *prefix, const char *name,
                          bool srgb, iir_texref *ref, iir_error *err)
{
    memset(ref, 0, sizeof *ref);
    const cJSON *info = member(obj, name);
    if (!info || !R->ok) return IIR_OK;
    char path[IIR_JSON_PATH];
    iir_json_path(path, prefix, name);
    const cJSON *tc = member(info, "texCoord");
    if (cJSON_IsNumber(tc) && tc->valueint != 0)
        iir_builder_drop(R->b, "material", R->name,
                         "%s uses TEXCOORD_%d: only TEXCOORD_0 is read, which is used instead",
                         path, tc->valueint);
    const cJSON *ti = member(info, "index");
    const cJSON *tex = cJSON_IsNumber(ti)
                           ? cJSON_GetArrayItem(member(R->e->root, "textures"), ti->valueint)
                           : NULL;
    const cJSON *src = member(tex, "source");
    if (!cJSON_IsNumber(src)) {
        iir_builder_drop(R->b, "material", R->name, "%s names no texture image: its factor is used",
                         path);
        return IIR_OK;
    }
    ref->sampler = sampler(R->e, tex);
    ref->transform = transform(R, info, path);
    return image_ref(R->e, src->valueint, srgb, R->b, R->name, &ref->texture, err);
}

static iir_vec3 color(mat_reader *R, const cJSON *obj, const char *prefix, const char *name, int n,
                      iir_vec3 fallback, float *alpha)
{
    const cJSON *v = member(obj, name);
    if (!v || !R->ok) return fallback;
    char path[IIR_JSON_PATH];
    iir_json_path(path, prefix, name);
    double c[4] = {fallback.x, fallback.y, fallback.z, 1.0};
    R->ok = iir_json_numbers(&R->jf.r, v, path, n, 0.0, n == 4 ? 1.0 : 1e9, c);
    if (alpha) *alpha = (float)c[3];
    return iir_v3((float)c[0], (float)c[1], (float)c[2]);
}

/* ======================== the material ======================== */

/* What glTF materials can say that iir's model leaves out, noted by name. */
static void note_unsupported(mat_reader *R, const cJSON *mat)
{
    if (member(mat, "occlusionTexture"))
        iir_builder_drop(R->b, "material", R->name,
                         "occlusionTexture: not read (light transport computes occlusion)");
    const cJSON *x;
    cJSON_ArrayForEach(x, member(mat, "extensions"))
    {
        const char *k = x->string;
        if (strcmp(k, "KHR_materials_emissive_strength") &&
            strcmp(k, "KHR_materials_transmission") && strcmp(k, "KHR_materials_ior"))
            iir_builder_drop(R->b, "material", R->name, "%s: not rendered", k);
    }
}

static void read_alpha(mat_reader *R, const cJSON *mat, iir_material *m)
{
    static const char *const modes[] = {"OPAQUE", "MASK", "BLEND", NULL};
    const cJSON *mode = member(mat, "alphaMode");
    int k = 0;
    if (mode && R->ok) {
        char path[IIR_JSON_PATH];
        iir_json_path(path, R->path, "alphaMode");
        R->ok = iir_json_enum(&R->jf.r, mode, path, modes, &k);
    }
    m->alpha_mode = (iir_alpha_mode)k;
    m->alpha_cutoff = number(R, mat, R->path, "alphaCutoff", 0.0, 1.0, 0.5f);
    if (m->alpha_mode == IIR_ALPHA_BLEND)
        iir_builder_drop(R->b, "material", R->name,
                         "alphaMode BLEND: pt renders it as stochastic transparency, the other "
                         "methods as a cut-out at alpha 0.5");
}

/* transmission > 0: today's smooth glass of index ior (1.5), tinted by the base colour. */
static void read_glass(mat_reader *R, const cJSON *mat, iir_material *m)
{
    const cJSON *ext = member(mat, "extensions");
    const cJSON *tr = member(ext, "KHR_materials_transmission");
    char path[IIR_JSON_PATH];
    iir_json_path(path, R->path, "extensions.KHR_materials_transmission");
    float t = tr ? number(R, tr, path, "transmissionFactor", 0.0, 1.0, 0.f) : 0.f;
    if (!(t > 0.f)) return;
    if (t < 1.f)
        iir_builder_drop(R->b, "material", R->name, "transmission %g: rendered as clear glass",
                         (double)t);
    iir_json_path(path, R->path, "extensions.KHR_materials_ior");
    m->ior = number(R, member(ext, "KHR_materials_ior"), path, "ior", 1.0, 3.0, 1.5f);
    m->kind = IIR_MATERIAL_GLASS;
    m->specular = m->albedo;
    m->albedo = iir_v3s(0.f);
    memset(&m->base_tex, 0, sizeof m->base_tex);
    memset(&m->mr_tex, 0, sizeof m->mr_tex);
}

static iir_status read_pbr(mat_reader *R, const cJSON *mat, iir_material *m, iir_error *err)
{
    const cJSON *pbr = member(mat, "pbrMetallicRoughness");
    char path[IIR_JSON_PATH];
    iir_json_path(path, R->path, "pbrMetallicRoughness");
    m->albedo = color(R, pbr, path, "baseColorFactor", 4, iir_v3s(1.f), &m->opacity);
    m->metallic = number(R, pbr, path, "metallicFactor", 0.0, 1.0, 1.f);
    m->roughness = number(R, pbr, path, "roughnessFactor", 0.0, 1.0, 1.f);
    iir_status st = texture(R, pbr, path, "baseColorTexture", true, &m->base_tex, err);
    if (st == IIR_OK)
        st = texture(R, pbr, path, "metallicRoughnessTexture", false, &m->mr_tex, err);
    return st;
}

static iir_status read_material(mat_reader *R, const cJSON *mat, iir_material *m, iir_error *err)
{
    m->kind = IIR_MATERIAL_METAL_ROUGH;
    m->specular_f0 = 0.04f; /* the spec's dielectric */
    m->opacity = 1.f;
    iir_status st = read_pbr(R, mat, m, err);
    const cJSON *nt = member(mat, "normalTexture");
    if (st == IIR_OK) st = texture(R, mat, R->path, "normalTexture", false, &m->normal_tex, err);
    char path[IIR_JSON_PATH];
    iir_json_path(path, R->path, "normalTexture");
    m->normal_scale = nt ? number(R, nt, path, "scale", -1e3, 1e3, 1.f) : 1.f;
    m->emission = color(R, mat, R->path, "emissiveFactor", 3, iir_v3s(0.f), NULL);
    if (st == IIR_OK) st = texture(R, mat, R->path, "emissiveTexture", true, &m->emission_tex, err);
    iir_json_path(path, R->path, "extensions.KHR_materials_emissive_strength");
    const cJSON *es = member(member(mat, "extensions"), "KHR_materials_emissive_strength");
    m->emission =
        iir_scale(m->emission, es ? number(R, es, path, "emissiveStrength", 0.0, 1e9, 1.f) : 1.f);
    read_alpha(R, mat, m);
    read_glass(R, mat, m);
    /* metallic 1, roughness 0, untextured: the mirror it has always been */
    if (m->kind == IIR_MATERIAL_METAL_ROUGH && m->metallic >= 1.f && m->roughness <= 0.f &&
        !m->base_tex.texture && !m->mr_tex.texture && !m->normal_tex.texture) {
        m->kind = IIR_MATERIAL_MIRROR;
        m->specular = m->albedo;
        m->albedo = iir_v3s(0.f);
    }
    note_unsupported(R, mat);
    return st;
}

iir_status iir_gltf_ext_material(iir_gltf_ext *e, int i, iir_scene_builder *b, iir_material *m,
                                 iir_error *err)
{
    const cJSON *mat = cJSON_GetArrayItem(member(e->root, "materials"), i);
    mat_reader R;
    memset(&R, 0, sizeof R);
    R.e = e;
    R.b = b;
    R.ok = true;
    iir_json_file_init(&R.jf, e->path, err);
    iir_json_index(R.path, "materials", i);
    const char *name = cJSON_IsString(member(mat, "name")) ? member(mat, "name")->valuestring : "";
    if (name[0]) iir_scene_strcpy(m->name, sizeof m->name, name);
    R.name = m->name;
    iir_status st = read_material(&R, mat, m, err);
    if (st != IIR_OK) return st;
    return iir_json_file_status(&R.jf, R.ok);
}

/* scene_gltf_ext.h -- what a glTF file says that assimp 5.2 does not read, read from the file's own
 * JSON with cJSON beside assimp: the extensions it uses and requires, and its materials as glTF 2.0
 * writes them (metallic-roughness, textures with their samplers and KHR_texture_transform, alpha
 * modes, KHR_materials_emissive_strength / transmission / ior), their images decoded from files,
 * a .glb's binary chunk or a buffer. Internal to scene/. */
#ifndef IIR_SCENE_GLTF_EXT_H
#define IIR_SCENE_GLTF_EXT_H

#include <stdint.h>

#include "scene_build.h"

typedef struct cJSON cJSON;

/* A little-endian 32-bit word of a .glb's header or chunk header. */
static inline uint32_t iir_glb_le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

typedef struct iir_gltf_ext {
    const char *path;   /* the file */
    cJSON *root;        /* its JSON; NULL for other formats */
    unsigned char *bin; /* a .glb's binary chunk (read on first use), or NULL */
    size_t bin_size;
    uint32_t *image_refs; /* per image and colour space (2 i + srgb): its builder texture ref, 0
                             until decoded, UINT32_MAX when it failed */
    uint32_t num_images;
} iir_gltf_ext;

/* Reads path's JSON (a .gltf, or a .glb's JSON chunk). An extension in extensionsRequired that iir
 * does not read fails with IIR_ERR_UNSUPPORTED naming it; one in extensionsUsed that iir does not
 * read gets a note naming it (iir_builder_drop, kind "extension"). IIR_ERR_IO / IIR_ERR_FORMAT
 * naming the file. On success *out is filled (iir_gltf_ext_free it). */
iir_status iir_gltf_ext_read(const char *path, iir_scene_builder *b, iir_gltf_ext *out,
                             iir_error *err);
void iir_gltf_ext_free(iir_gltf_ext *e);

/* The file's material that assimp's material `index` named `name` came from: the file's material
 * `index` when its name agrees (assimp keeps the file's order), else the first of that name; -1
 * when none matches (assimp's default material). */
int iir_gltf_ext_material_index(const iir_gltf_ext *e, uint32_t index, const char *name);

/* The file's material i as iir's material (glTF 2.0 section 3.9 with its defaults), its textures
 * decoded into the builder (each image once per colour space); a texture that cannot be read is
 * a warning naming the file and the material, and the material keeps its factor. What the model
 * leaves out (occlusion, a second texture coordinate set, clearcoat, sheen, ...) is noted by name.
 * IIR_ERR_NOMEM only. */
iir_status iir_gltf_ext_material(iir_gltf_ext *e, int i, iir_scene_builder *b, iir_material *m,
                                 iir_error *err);

#endif

/* scene_gltf_ext.h -- what a glTF file says that assimp 5.2 does not read, read from the file's own
 * JSON with cJSON beside assimp: the extensions it uses and requires, and per material its
 * KHR_materials_emissive_strength. Internal to scene/. */
#ifndef IIR_SCENE_GLTF_EXT_H
#define IIR_SCENE_GLTF_EXT_H

#include <stdint.h>

#include "scene_build.h"

typedef struct iir_gltf_ext {
    uint32_t num_materials;   /* the file's materials array */
    float *emissive_strength; /* per material: KHR_materials_emissive_strength, 1 without it */
    char **material_names;    /* per material: its "name", "" without one */
} iir_gltf_ext;

/* Reads path's JSON (a .gltf, or a .glb's JSON chunk). An extension in extensionsRequired that iir
 * does not read fails with IIR_ERR_UNSUPPORTED naming it; one in extensionsUsed that iir does not
 * read gets a note naming it (iir_builder_drop, kind "extension"). IIR_ERR_IO / IIR_ERR_FORMAT
 * naming the file. On success *out is filled (iir_gltf_ext_free it). */
iir_status iir_gltf_ext_read(const char *path, iir_scene_builder *b, iir_gltf_ext *out,
                             iir_error *err);
void iir_gltf_ext_free(iir_gltf_ext *e);

/* The emissive strength of the glTF material that assimp's material `index` named `name` came
 * from: the file's material `index` when its name agrees (assimp keeps the file's order), else the
 * first of that name; 1 when none matches. */
float iir_gltf_ext_emissive_strength(const iir_gltf_ext *e, uint32_t index, const char *name);

#endif

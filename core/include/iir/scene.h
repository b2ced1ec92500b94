/* scene.h -- the static scene: triangle meshes with diffuse, mirror and glass materials, lights,
 * the camera, named light paths; loading it from OBJ/MTL or glTF 2.0 (assimp) plus a JSON sidecar,
 * the Cornell box built into the binary, and opening a scene with its ray tracer in one call. A
 * loaded scene is read-only and shared between threads. Not ray tracing (rt.h) and not light
 * sampling (light.h). Format: docs/scene-format.md. */
#ifndef IIR_SCENE_H
#define IIR_SCENE_H

#include <stddef.h>
#include <stdint.h>

#include "iir/camera.h"
#include "iir/light.h"
#include "iir/rt.h"
#include "iir/status.h"
#include "iir/texture.h"
#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

/* What a surface does with light. Zero (a zero-initialised material) is diffuse. */
typedef enum iir_material_kind {
    IIR_MATERIAL_DIFFUSE = 0, /* Lambertian: albedo */
    IIR_MATERIAL_MIRROR,      /* perfect mirror: reflects `specular` along R = V - 2 (V.N) N */
    IIR_MATERIAL_GLASS,       /* smooth dielectric of index `ior`: Fresnel-weighted reflection and
                                 refraction (Snell), transmission tinted by `specular` */
    IIR_MATERIAL_METAL_ROUGH  /* glTF 2.0's metallic-roughness model: base colour (albedo x
                                 base_tex), metallic, roughness; Lambert + GGX (bsdf.h) */
} iir_material_kind;

/* How a material's alpha (base colour alpha x texture alpha) covers its surface (glTF alphaMode).
 */
typedef enum iir_alpha_mode {
    IIR_ALPHA_OPAQUE = 0, /* alpha ignored */
    IIR_ALPHA_MASK,       /* a hole where alpha < alpha_cutoff: for every ray */
    IIR_ALPHA_BLEND       /* rendered as a cut-out at 0.5, with a note */
} iir_alpha_mode;

/* A texture a material samples: the scene's texture `texture - 1` (0: none), with its glTF sampler
 * and KHR_texture_transform. Zero is "no texture". */
typedef struct iir_texref {
    uint32_t texture; /* 1 + index into iir_scene.textures; 0 = none */
    iir_tex_sampler sampler;
    iir_tex_transform transform; /* KHR_texture_transform; the loaders set identity without one */
} iir_texref;

/* A two-sided material. Emissive materials are static emitting triangles, or, when a scene's
 * sidecar gives no "lights" array and their triangles are one-sided and planar, movable area
 * lights (iir_scene_load). A mirror or glass has no diffuse part: its albedo is 0 (the loaders
 * see to it), so every diffuse-only method renders it black (docs/scene-format.md, section 3). */
typedef struct iir_material {
    /* what every hit reads first, together (a cache line): */
    iir_material_kind kind; /* IIR_MATERIAL_DIFFUSE unless a file or sidecar says otherwise */
    iir_vec3 albedo;        /* diffuse reflectance rho (metal_rough: the base colour factor), each
                               channel in [0, 1]; 0 for a mirror or glass */
    iir_vec3 emission;      /* emitted radiance Le (W/sr/m^2), >= 0 (x emission_tex) */
    iir_vec3 specular;      /* mirror: reflectance; glass: transmission tint; each in [0, 1] */
    float ior;              /* glass: index of refraction, in [1, 3]; 0 otherwise */
    float metallic;         /* metal_rough: in [0, 1] (x the mr texture's B) */
    float roughness;        /* metal_rough: in [0, 1] (x the mr texture's G); alpha = roughness^2 */
    float specular_f0;      /* metal_rough: a dielectric's reflectance at normal incidence, in
                               [0, 1]: glTF's 0.04; an MTL's 0.08 mean(Ks), as Blender reads it */
    float opacity;          /* the base colour factor's alpha, in [0, 1] (1 - opacity is unused
                               when alpha_mode is OPAQUE) */
    iir_alpha_mode alpha_mode;
    float alpha_cutoff; /* MASK: alpha below it is a hole (glTF default 0.5) */
    float normal_scale; /* normal_tex: the tangent-space xy scale (glTF normalTexture.scale) */
    /* the textures, read only when one is set: */
    iir_texref base_tex;     /* sRGB base colour (diffuse albedo) and alpha */
    iir_texref mr_tex;       /* linear: G roughness, B metallic */
    iir_texref normal_tex;   /* linear tangent-space normal map */
    iir_texref emission_tex; /* sRGB emission colour */
    char name[64];
} iir_material;

/* "diffuse", "mirror" or "glass" (the sidecar's "kind"). */
const char *iir_material_kind_name(iir_material_kind kind);

/* The bounces a camera path spends on the material before it reaches a rough surface behind it: 0
 * for a diffuse one, 1 for a mirror (off it), 2 for glass (in and out of a closed body). */
int iir_material_specular_depth(const iir_material *m);

/* Whether a metal_rough material's specular lobe carries a share of its light that a diffuse-only
 * method visibly misses: any metal, or a dielectric smoother than roughness 0.6 (a rough
 * dielectric's 4% lobe is spread like its diffuse one). */
bool iir_material_is_glossy(const iir_material *m);

/* h extended by every field of the material that changes an image (not its name). */
uint64_t iir_material_hash(uint64_t h, const iir_material *m);

/* Something of a scene that is not rendered, for warnings (the CLI prints them; the daemon can send
 * them), or a note on what was made of it (`note`): a light or material by its name in the scene
 * that no method renders (the loader's list, iir_scene.dropped, method "") or that one method
 * leaves out (iir_method_dropped), and what happens to it. */
typedef struct iir_dropped {
    char method[16]; /* "" = no method renders it; else the method that leaves it out */
    char kind[16];   /* "light" or "material" */
    char name[64];   /* its name in the scene */
    char what[192];  /* e.g. "a directional light (sun): ignored; ..." */
    bool note;       /* informational: what was done to the scene (an emissive material became a
                        movable area light, or stays static emissive triangles), which is rendered;
                        false: a warning, something left out */
} iir_dropped;

/* Where a scene's camera comes from. Without one in the file or sidecar, iir_scene_open frames the
 * scene (scene_frame.c): from inside when it is a closed room with its lights inside, else from
 * outside looking at its centre (iir_scene_load alone always frames from outside). */
typedef enum iir_camera_origin {
    IIR_CAMERA_FILE,    /* the mesh file's (glTF) */
    IIR_CAMERA_SIDECAR, /* the sidecar's "camera" */
    IIR_CAMERA_BUILTIN, /* the built-in Cornell box's */
    IIR_CAMERA_OUTSIDE, /* none given: from +z outside the bounds, looking at their centre */
    IIR_CAMERA_INSIDE   /* none given: inside the closed room, looking along its longer side */
} iir_camera_origin;

typedef struct iir_scene {
    char name[128];    /* short name: "cornell_box", or the file's base name */
    char source[1024]; /* the file it came from; "" for the built-in box */

    uint32_t num_vertices;
    iir_vec3 *positions; /* world space, after unit scale */

    uint32_t num_triangles;
    uint32_t *indices;   /* 3 per triangle, into positions */
    uint32_t *materials; /* per triangle, into material_list */
    iir_vec3 *normals;   /* per triangle, unit geometric normal (winding order) */
    float *areas;        /* per triangle, world units^2 */
    /* Per vertex, each NULL when no mesh of the file gives it (zero where one mesh lacks it): */
    iir_vec3 *vertex_normals; /* unit shading normals, interpolated at a hit (smooth shading) */
    iir_vec2 *texcoords;      /* TEXCOORD_0 / vt, glTF convention: (0, 0) the image's top left */
    float *tangents;          /* 4 per vertex: unit tangent xyz and handedness w = +-1 (glTF) */

    uint32_t num_textures; /* decoded once, shared by every session (materials point at them) */
    iir_texture **textures;

    uint32_t num_materials;
    iir_material *material_list;

    uint32_t num_lights; /* the lights: point, spot, sun and area (light.h) */
    iir_light *lights;

    iir_camera camera;
    iir_camera_origin camera_origin;
    float aspect; /* width / height the camera was framed for (glTF aspectRatio, sidecar
                     camera.aspect, 1 for the Cornell box); 0 = not given */
    iir_vec3 bounds_min, bounds_max;

    uint32_t skipped_degenerate; /* triangles dropped at load: zero area or repeated vertices */
    uint32_t skipped_duplicate;  /* triangles dropped at load: same three positions as another */
    char *paths_json;            /* sidecar "paths" object as JSON text, or NULL */
    uint32_t num_maps;           /* the area lights' radiance images (lights point at them) */
    iir_emission_map **maps;
    uint32_t num_dropped; /* lights and materials of the file that nothing renders */
    iir_dropped *dropped;
} iir_scene;

/* Loads a scene from a file (.obj, .gltf, .glb, or a .scene.json sidecar naming one) or a folder
 * (its *.scene.json, else its only mesh file). A sidecar NAME.scene.json next to NAME.obj is
 * applied. Unless the sidecar gives a "lights" array, each emissive material whose triangles are
 * one-sided and planar (a rectangle, or at most 64 triangles) becomes a movable area light named
 * after it, its triangles leaving the mesh; `dropped` notes each emissive material's fate
 * (docs/scene-format.md, section 3). On error returns a status and a message naming the file and
 * the problem; *out is left NULL. */
iir_status iir_scene_load(const char *path, iir_scene **out, iir_error *err);

/* Maps what a user typed to a path: an existing file or folder is taken as is; otherwise a bare
 * name (letters, digits, '_', '-', '.') is looked up as scenes_dir/NAME. Names with '/' or ".."
 * that do not exist are refused. Writes the path into out (size n). */
iir_status iir_scene_resolve(const char *name_or_path, const char *scenes_dir, char *out, size_t n,
                             iir_error *err);

/* The classic Cornell box (McGuire's CornellBox-Original geometry and colours), lit by a spot light
 * under the ceiling, seen by the classic camera. The ceiling panel is kept as a white, non-emitting
 * patch so the spot is the only light. Returns NULL only on allocation failure. */
iir_scene *iir_scene_create_cornell_box(void);

void iir_scene_destroy(iir_scene *scene);

/* Bytes the scene holds: its arrays, materials, lights and decoded textures (mip chains). */
uint64_t iir_scene_bytes(const iir_scene *scene);

/* Opens a scene for rendering: NULL or "builtin" is the built-in Cornell box; anything else is
 * resolved as iir_scene_resolve does (a file or folder, else a bare name in scenes_dir) and loaded
 * as iir_scene_load does; then its ray tracer is built, and a scene without a camera that is a
 * closed room with its lights inside gets a camera inside it (IIR_CAMERA_INSIDE). The caller owns
 * both outputs and frees them with iir_rt_destroy, then iir_scene_destroy (the tracer refers to the
 * scene). On error returns the status of the step that failed with its message in err, and both
 * outputs are NULL (nothing is left allocated). */
iir_status iir_scene_open(const char *name_or_path, const char *scenes_dir, iir_scene **scene,
                          iir_rt **rt, iir_error *err);

/* One line saying which camera the scene has and where it came from, e.g. "no camera in the scene:
 * framed from inside (it is a closed room), at (0, 1, 2.4) looking at (0, 1, 0), fov_y 60". */
void iir_scene_describe_camera(const iir_scene *scene, char *buf, size_t n);

/* Why a view of the scene may render entirely black, as one clause for a warning ("the scene has
 * no lights", "the camera may be inside geometry: ...", "no light reaches what the camera sees:
 * ..."), found with a few hundred rays (scene_dark.c). */
void iir_scene_explain_dark(const iir_scene *scene, const iir_rt *rt, const iir_light *lights,
                            uint32_t num_lights, const iir_camera *camera, char *buf, size_t n);

/* Human-readable one-line summary ("cornell_box: 32 triangles, 8 materials, 1 light, skipped 0
 * degenerate and 0 duplicate").
 */
void iir_scene_describe(const iir_scene *scene, char *buf, size_t n);

#ifdef __cplusplus
}
#endif
#endif

/* scene_build.h -- the internal scene builder every scene source feeds (assimp files, the JSON
 * sidecar, the built-in Cornell box) and the entry points of those sources; not the public API
 * (iir/scene.h), not how a user's name becomes a path (scene.c).
 *
 * A source appends vertices, triangles, materials and lights to an iir_scene_builder, may set the
 * camera, and iir_builder_finish() turns it into an iir_scene: it drops and counts degenerate
 * triangles, computes unit normals (winding order), areas and bounds, and picks a default camera
 * when no source gave one. The builder lives on the caller's stack; every function leaves it in a
 * state iir_builder_free() can release, whatever it returns. */
#ifndef IIR_SCENE_BUILD_H
#define IIR_SCENE_BUILD_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/scene.h"

#include <string.h>

/* Copies src into dst (size n > 0), truncating, always NUL-terminated. */
static inline void iir_scene_strcpy(char *dst, size_t n, const char *src)
{
    size_t len = strlen(src);
    if (len >= n) len = n - 1;
    memcpy(dst, src, len);
    dst[len] = '\0';
}

/* ======================== the builder ======================== */

typedef struct iir_scene_builder {
    char name[128];    /* becomes iir_scene.name */
    char source[1024]; /* becomes iir_scene.source; every error message names it */

    iir_vec3 *positions;
    uint32_t num_vertices, cap_vertices;
    /* per-vertex attributes, allocated (zero-filled) when the first vertex gives one */
    iir_vec3 *vertex_normals;
    iir_vec2 *texcoords;
    float *tangents; /* 4 per vertex */

    uint32_t *indices;       /* 3 per triangle */
    uint32_t *tri_materials; /* 1 per triangle */
    uint32_t num_triangles, cap_triangles;

    iir_material *materials;
    uint32_t num_materials, cap_materials;

    iir_light *lights;
    uint32_t num_lights, cap_lights;

    iir_camera camera;
    bool has_camera;
    iir_camera_origin camera_origin;
    float aspect; /* the camera's width / height; 0 = not given */

    iir_dropped *dropped; /* what the file has and nothing renders; moved into the scene */
    uint32_t num_dropped, cap_dropped;

    char *paths_json; /* owned; moved into the scene */

    iir_emission_map **maps; /* owned; moved into the scene (lights point at them) */
    uint32_t num_maps;

    iir_texture **textures; /* owned; moved into the scene (materials point at them) */
    uint32_t num_textures;
} iir_scene_builder;

/* What a vertex may carry besides its position; a NULL member is "not given". */
typedef struct iir_vertex_attr {
    const iir_vec3 *normal; /* unit shading normal */
    const iir_vec2 *uv;     /* TEXCOORD_0 */
    const float *tangent;   /* xyz unit tangent, w handedness +-1 */
} iir_vertex_attr;

/* An empty builder; name and source are copied (truncated to fit). */
void iir_builder_init(iir_scene_builder *b, const char *name, const char *source);

/* Releases everything the builder still owns; safe after any other call, and twice. */
void iir_builder_free(iir_scene_builder *b);

/* Takes map over (the builder, then its scene, frees it). IIR_ERR_NOMEM (map then freed). */
iir_status iir_builder_add_map(iir_scene_builder *b, iir_emission_map *map, iir_error *err);
/* Takes every map of scene over (scene keeps none): for a scene whose lights the builder copied
 * (a sidecar's base), before the scene is destroyed. */
iir_status iir_builder_take_maps(iir_scene_builder *b, iir_scene *scene, iir_error *err);

/* Makes room for n more vertices and triangles (an optimisation; appending grows as needed). */
iir_status iir_builder_reserve(iir_scene_builder *b, uint32_t more_vertices,
                               uint32_t more_triangles, iir_error *err);

/* Appends a vertex and writes its index to *index (may be NULL). IIR_ERR_FORMAT for a NaN or
 * infinite coordinate, naming the source and the vertex. */
iir_status iir_builder_add_vertex(iir_scene_builder *b, iir_vec3 p, uint32_t *index,
                                  iir_error *err);

/* The same with a vertex's attributes (attr may be NULL). An attribute's array is created at the
 * first vertex that gives it, zero for the vertices before; a non-finite one is IIR_ERR_FORMAT. */
iir_status iir_builder_add_vertex_attr(iir_scene_builder *b, iir_vec3 p,
                                       const iir_vertex_attr *attr, uint32_t *index,
                                       iir_error *err);

/* Takes tex over and writes the iir_texref.texture value that names it (1 + its index) to *ref.
 * IIR_ERR_NOMEM (tex then freed). */
iir_status iir_builder_add_texture(iir_scene_builder *b, iir_texture *tex, uint32_t *ref,
                                   iir_error *err);
/* Takes every texture of scene over (scene keeps none), as iir_builder_take_maps. */
iir_status iir_builder_take_textures(iir_scene_builder *b, iir_scene *scene, iir_error *err);

/* Appends a triangle (vertex indices in winding order) with a material index. Indices must
 * refer to vertices and materials already added (IIR_ERR_FORMAT otherwise). Degenerate
 * triangles are accepted here and dropped (and counted) by iir_builder_finish. */
iir_status iir_builder_add_triangle(iir_scene_builder *b, uint32_t i0, uint32_t i1, uint32_t i2,
                                    uint32_t material, iir_error *err);

/* Appends a material and writes its index to *index (may be NULL). IIR_ERR_INVALID naming the
 * material when albedo is not in [0, 1], emission is negative or not finite, or the kind's fields
 * are not usable (iir_material_check); callers that promise to clamp (file colours) clamp before
 * calling. */
iir_status iir_builder_add_material(iir_scene_builder *b, const iir_material *m, uint32_t *index,
                                    iir_error *err);

/* Why material m's kind fields are not usable (written into why, size n, and returned), or NULL
 * when they are: a mirror or glass needs specular in [0, 1] and albedo 0, glass an ior in [1, 3]
 * (scene_material.c). */
const char *iir_material_check(const iir_material *m, char *why, size_t n);

/* Index of the first material called name, or -1. */
int64_t iir_builder_find_material(const iir_scene_builder *b, const char *name);

/* Appends a punctual light after iir_light_validate(); its message is prefixed with the source. */
iir_status iir_builder_add_light(iir_scene_builder *b, const iir_light *light, iir_error *err);

/* Drops every light added so far and the notes on lights (sidecar lights replace file lights). */
void iir_builder_clear_lights(iir_scene_builder *b);

/* Sets the camera (origin IIR_CAMERA_FILE, aspect not given). */
void iir_builder_set_camera(iir_scene_builder *b, const iir_camera *cam);
/* Says where the camera set last comes from and its width / height (0 = not given). */
void iir_builder_set_camera_origin(iir_scene_builder *b, iir_camera_origin origin, float aspect);

/* Notes a light or material of the file that nothing renders (kind "light" or "material", what
 * happens to it, printf-style); out of memory only loses the note. iir_builder_clear_lights
 * forgets the light notes (the sidecar's lights replace the file's). */
void iir_builder_drop(iir_scene_builder *b, const char *kind, const char *name, const char *fmt,
                      ...) __attribute__((format(printf, 4, 5)));
/* The same as a note (iir_dropped.note): what was made of it, which is rendered (an emissive
 * material that became an area light), not a warning. */
void iir_builder_note(iir_scene_builder *b, const char *kind, const char *name, const char *fmt,
                      ...) __attribute__((format(printf, 4, 5)));

/* Appends a loaded scene's vertices, triangles (same order), materials and lights, and sets its
 * camera: a sidecar's "base" scene becomes the mesh the sidecar applies to. Not its paths. */
iir_status iir_builder_add_scene(iir_scene_builder *b, const iir_scene *scene, iir_error *err);

/* Multiplies vertex positions, light positions and the camera's position and target by s > 0
 * (a unit scale). Directions, angles and intensities are unchanged. */
void iir_builder_scale(iir_scene_builder *b, float s);

/* Turns the builder into a scene: drops degenerate triangles (repeated indices, or area below
 * 1e-14 of the squared bounding-box diagonal) and counts them, computes normals, areas and
 * bounds, adds a default camera framing the bounds if none was set, and validates the camera.
 * On success *out owns all arrays and the builder is left empty; on error (no triangles left,
 * bad camera, no memory) *out is NULL and the builder still owns its data. */
iir_status iir_builder_finish(iir_scene_builder *b, iir_scene **out, iir_error *err);

/* scene_frame.c: a scene whose camera the builder made (IIR_CAMERA_OUTSIDE) gets one inside it
 * when it is a closed room with its lights inside (IIR_CAMERA_INSIDE); needs its ray tracer. */
void iir_scene_frame(iir_scene *s, const iir_rt *rt);

/* ======================== the sources ======================== */

/* scene_assimp.c: appends the meshes, used materials, lights and first camera of any file assimp
 * reads (OBJ/MTL and glTF 2.0 are the tested ones). Errors name the file: missing or unreadable,
 * a format assimp does not know (with assimp's message), NaN/Inf vertices, no triangles. */
iir_status iir_assimp_load(const char *path, iir_scene_builder *b, iir_error *err);

/* scene_sidecar.c: a parsed NAME.scene.json. Angles are stored in radians, positions in world
 * units (after unit_scale). */
typedef struct iir_sidecar_material {
    char name[64];
    bool has_albedo, has_emission, has_kind, has_specular, has_ior;
    iir_vec3 albedo, emission, specular;
    iir_material_kind kind;
    float ior;
} iir_sidecar_material;

typedef struct iir_sidecar {
    char path[1024]; /* the sidecar file itself */
    char file[1024]; /* the mesh it names, joined with the sidecar's folder; "" if it names none */
    char base[128];  /* the scene it is based on (a bare name: "builtin" or a sibling folder of the
                        sidecar's folder); "" if none. Exclusive with file. */
    float unit_scale;
    bool has_camera;
    iir_camera camera;
    float aspect;    /* camera.aspect; 0 when absent (the file camera's is then kept) */
    bool has_lights; /* a "lights" array was given (possibly empty: no lights at all) */
    uint32_t num_lights;
    iir_light *lights;
    uint32_t num_materials;
    iir_sidecar_material *materials;
    char *paths_json;  /* the "paths" object as compact JSON, or NULL */
    uint32_t num_maps; /* area lights' "emission_map"s, read (the lights point at them) */
    iir_emission_map **maps;
} iir_sidecar;

/* Reads and validates a sidecar. Errors (IIR_ERR_IO, IIR_ERR_FORMAT, IIR_ERR_INVALID) name the
 * file and the JSON field path ("lights[0].cone_angle"). On error *sc holds nothing to free. */
iir_status iir_sidecar_parse(const char *path, iir_sidecar *sc, iir_error *err);

/* The same from len bytes of text in memory (need not be NUL-terminated), as if read from path:
 * path names it in messages and "file" is joined with path's folder. */
iir_status iir_sidecar_parse_text(const char *path, const char *text, size_t len, iir_sidecar *sc,
                                  iir_error *err);

/* scene_area.c: area lights from the triangles of a material (the sidecar's "material" form, and
 * a scene's emissive materials). */
typedef struct iir_area_fit {
    uint32_t triangles; /* the material's triangles */
    double area, w, h;  /* the area they cover, their smallest bounding rectangle's sides */
    char why[160];      /* "" on success, else why not, a phrase that follows "material 'NAME' " */
} iir_area_fit;

/* Fits the triangles of material `name` (any material of that name): one-sided (all wound the
 * same way, within about 1 degree) and coplanar (within 1e-4 of the rectangle's larger side). On
 * success sets l's position, direction, up, size (the smallest bounding rectangle with a side along
 * one of the triangles' edges) and shape (none when they form that rectangle, else their
 * light-local triangles: at most IIR_AREA_MAX_TRIANGLES) and leaves the rest of *l alone.
 * IIR_ERR_INVALID with fit->why for no triangles, more than 1024, facing different ways, not flat,
 * overlapping, or more than 64 not forming a rectangle; IIR_ERR_NOMEM. The builder is not changed.
 */
iir_status iir_builder_fit_area_light(const iir_scene_builder *b, const char *name, iir_light *l,
                                      iir_area_fit *fit);

/* Removes material `name`'s triangles from the mesh (the rest keep their order) and zeroes its
 * emission: an area light took them. */
void iir_builder_take_emitter(iir_scene_builder *b, const char *name);

/* For a scene whose sidecar gives no "lights" array: every emissive material whose triangles fit
 * (iir_builder_fit_area_light) becomes a movable area light named after it (made unique among the
 * lights with "-2", "-3"...), of radiance its emission; its triangles leave the mesh, unless they
 * are all that is left. Each emissive material gets a note (iir_builder_drop, kind "material"):
 * which light it became, or why it stays static emissive triangles. IIR_ERR_NOMEM only. */
iir_status iir_builder_emitters_to_lights(iir_scene_builder *b, iir_error *err);

/* Applies a parsed sidecar to a builder that already holds the mesh: unit scale first, then
 * material overrides (an unknown material name is an error), camera, lights, paths (moved). */
iir_status iir_sidecar_apply(iir_sidecar *sc, iir_scene_builder *b, iir_error *err);

void iir_sidecar_free(iir_sidecar *sc);

#endif

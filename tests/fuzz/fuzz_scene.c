/* fuzz_scene.c -- libFuzzer target for mesh files as core reads them (assimp, then the scene
 * builder and a sidecar): iir_scene_load on files written to a scratch directory. Input layout:
 * byte 0 picks the mesh's extension (.obj, .gltf, .glb, by value mod 3); the rest is split at
 * "\n#~~\n" into the mesh f.EXT, a second file written as both m.mtl and m.bin (the OBJ's
 * `mtllib m.mtl`, a glTF's buffer "uri": "m.bin"), and f.scene.json (the sidecar, when present).
 * Inputs over 64 KiB are skipped; `make fuzz` caps the time per input. A loaded scene must keep
 * scene.h's promises (triangles, materials in range, valid camera and lights). */
#include <math.h>
#include <stdbool.h>
#include <string.h>
#include <unistd.h>

#include "fuzz.h"
#include "iir/scene.h"

#define MAX_INPUT (64 << 10)
#define SEPARATOR "\n#~~\n"

static const char *const EXTS[] = {"obj", "gltf", "glb"};

/* The next part of [*p, end): up to the separator or the end; advances *p past the separator and
 * sets *cut when there was one. */
static size_t next_part(const uint8_t **p, const uint8_t *end, const uint8_t **part, bool *cut)
{
    *part = *p;
    size_t left = (size_t)(end - *p), sep = sizeof SEPARATOR - 1;
    for (size_t i = 0; i + sep <= left; i++) {
        if (memcmp(*p + i, SEPARATOR, sep) == 0) {
            *p += i + sep;
            *cut = true;
            return i;
        }
    }
    *p = end;
    *cut = false;
    return left;
}

static void check_scene(const iir_scene *s)
{
    iir_error e;
    FUZZ_CHECK(s->num_triangles > 0 && s->num_materials > 0);
    for (uint32_t t = 0; t < s->num_triangles; t++) {
        FUZZ_CHECK(s->materials[t] < s->num_materials);
        for (int k = 0; k < 3; k++) FUZZ_CHECK(s->indices[3 * t + k] < s->num_vertices);
        FUZZ_CHECK(isfinite(s->areas[t]) && s->areas[t] > 0.f);
    }
    for (uint32_t m = 0; m < s->num_materials; m++) {
        iir_vec3 a = s->material_list[m].albedo, le = s->material_list[m].emission;
        FUZZ_CHECK(a.x >= 0.f && a.x <= 1.f && a.y >= 0.f && a.y <= 1.f && a.z >= 0.f &&
                   a.z <= 1.f);
        FUZZ_CHECK(iir_is_finite3(le) && le.x >= 0.f && le.y >= 0.f && le.z >= 0.f);
    }
    for (uint32_t i = 0; i < s->num_lights; i++)
        FUZZ_CHECK(iir_light_validate(&s->lights[i], &e) == IIR_OK);
    FUZZ_CHECK(iir_camera_validate(&s->camera, &e) == IIR_OK);
    char line[256];
    iir_scene_describe(s, line, sizeof line);
    fuzz_note("%s", line);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1 || size > MAX_INPUT) return 0;
    const char *dir = fuzz_temp_dir();
    FUZZ_CHECK(dir != NULL);
    const char *ext = EXTS[data[0] % 3];
    const uint8_t *p = data + 1, *end = data + size, *mesh, *side;
    bool cut, has_sidecar;
    size_t mesh_n = next_part(&p, end, &mesh, &cut);
    size_t side_n = next_part(&p, end, &side, &has_sidecar);
    const uint8_t *sidecar = p; /* the rest, separators and all */
    size_t sidecar_n = (size_t)(end - p);
    char name[16], path[1024];
    snprintf(name, sizeof name, "f.%s", ext);
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FUZZ_CHECK(fuzz_write_file(dir, name, mesh, mesh_n) == 0);
    FUZZ_CHECK(fuzz_write_file(dir, "m.mtl", side, side_n) == 0);
    FUZZ_CHECK(fuzz_write_file(dir, "m.bin", side, side_n) == 0);
    char sidecar_path[1024];
    snprintf(sidecar_path, sizeof sidecar_path, "%s/f.scene.json", dir);
    if (has_sidecar) FUZZ_CHECK(fuzz_write_file(dir, "f.scene.json", sidecar, sidecar_n) == 0);

    iir_scene *scene = (iir_scene *)1; /* must be set to NULL on error */
    iir_error e;
    e.msg[0] = '\0';
    iir_status st = iir_scene_load(path, &scene, &e);
    if (st != IIR_OK) {
        FUZZ_CHECK(scene == NULL);
        FUZZ_CHECK(e.status == st && e.msg[0] != '\0');
        fuzz_note("error: %s", e.msg);
    } else {
        FUZZ_CHECK(scene != NULL);
        check_scene(scene);
        iir_scene_destroy(scene);
    }
    unlink(path);
    unlink(sidecar_path);
    return 0;
}

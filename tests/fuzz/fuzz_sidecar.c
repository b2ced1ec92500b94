/* fuzz_sidecar.c -- libFuzzer target for the JSON scene sidecar (core/src/scene/scene_sidecar.c):
 * the bytes are a NAME.scene.json; iir_sidecar_parse_text must refuse it with a message or parse
 * it, and a parsed sidecar is applied to a small mesh with the Cornell box's material names and the
 * scene finished, as iir_scene_load would. The sidecar "sits" in a scratch directory holding
 * m.obj, so that a "file" field can name an existing mesh. */
#include <string.h>

#include "fuzz.h"
#include "scene/scene_build.h"

static const char *const MATERIALS[] = {"leftWall", "rightWall", "floor", "ceiling", "backWall",
                                        "shortBox", "tallBox",   "light", NULL};

/* A unit quad on the floor, one triangle per material pair; NULL builder state on failure. */
static iir_status build_mesh(iir_scene_builder *b, iir_error *e)
{
    iir_status st = IIR_OK;
    for (int i = 0; st == IIR_OK && MATERIALS[i]; i++) {
        iir_material m;
        memset(&m, 0, sizeof m);
        iir_scene_strcpy(m.name, sizeof m.name, MATERIALS[i]);
        m.albedo = iir_v3s(0.5f);
        st = iir_builder_add_material(b, &m, NULL, e);
    }
    const iir_vec3 v[4] = {{0, 0, 0}, {1, 0, 0}, {1, 0, 1}, {0, 0, 1}};
    for (int i = 0; st == IIR_OK && i < 4; i++) st = iir_builder_add_vertex(b, v[i], NULL, e);
    if (st == IIR_OK) st = iir_builder_add_triangle(b, 0, 1, 2, 0, e);
    if (st == IIR_OK) st = iir_builder_add_triangle(b, 0, 2, 3, 7, e);
    return st;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static char path[1024];
    if (!path[0]) {
        const char *dir = fuzz_temp_dir();
        static const char obj[] = "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n";
        FUZZ_CHECK(dir && fuzz_write_file(dir, "m.obj", (const uint8_t *)obj, sizeof obj - 1) == 0);
        snprintf(path, sizeof path, "%s/fuzz.scene.json", dir);
    }
    iir_sidecar sc;
    iir_error e;
    e.msg[0] = '\0';
    iir_status st = iir_sidecar_parse_text(path, (const char *)data, size, &sc, &e);
    if (st != IIR_OK) {
        FUZZ_CHECK(e.status == st && e.msg[0] != '\0');
        FUZZ_CHECK(!sc.lights && !sc.materials && !sc.paths_json);
        fuzz_note("error: %s", e.msg);
        return 0;
    }
    iir_scene_builder b;
    iir_builder_init(&b, "fuzz", path);
    st = build_mesh(&b, &e);
    FUZZ_CHECK(st == IIR_OK);
    st = iir_sidecar_apply(&sc, &b, &e);
    iir_scene *scene = NULL;
    if (st == IIR_OK) st = iir_builder_finish(&b, &scene, &e);
    if (st != IIR_OK) FUZZ_CHECK(e.msg[0] != '\0' && !scene);
    fuzz_note("parsed; %s", st == IIR_OK ? "applied" : e.msg);
    if (scene) {
        iir_error ce;
        FUZZ_CHECK(iir_camera_validate(&scene->camera, &ce) == IIR_OK);
        for (uint32_t i = 0; i < scene->num_lights; i++)
            FUZZ_CHECK(iir_light_validate(&scene->lights[i], &ce) == IIR_OK);
    }
    iir_scene_destroy(scene);
    iir_builder_free(&b);
    iir_sidecar_free(&sc);
    return 0;
}

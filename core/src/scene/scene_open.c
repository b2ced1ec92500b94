/* scene_open.c -- opening a scene for rendering: from what a user typed (or a resolved path) to a
 * loaded scene and its ray tracer (and a camera inside a closed room that has none, scene_frame.c),
 * with nothing left behind on failure; not loading files (scene.c) or building the BVH (rt.c). */
#include <string.h>

#include "iir/rt.h"
#include "iir/scene.h"
#include "scene_build.h"

/* The scene alone: the built-in box, or the resolved and loaded file. */
static iir_status open_scene(const char *name_or_path, const char *scenes_dir, iir_scene **scene,
                             iir_error *err)
{
    if (!name_or_path || strcmp(name_or_path, "builtin") == 0) {
        *scene = iir_scene_create_cornell_box();
        if (!*scene)
            return iir_fail(err, IIR_ERR_NOMEM, "out of memory building the built-in Cornell box");
        return IIR_OK;
    }
    char path[4096];
    iir_status st = iir_scene_resolve(name_or_path, scenes_dir, path, sizeof path, err);
    return st == IIR_OK ? iir_scene_load(path, scene, err) : st;
}

iir_status iir_scene_open(const char *name_or_path, const char *scenes_dir, iir_scene **scene,
                          iir_rt **rt, iir_error *err)
{
    *scene = NULL;
    *rt = NULL;
    iir_status st = open_scene(name_or_path, scenes_dir, scene, err);
    if (st == IIR_OK) st = iir_rt_create(*scene, rt, err);
    if (st == IIR_OK) iir_scene_frame(*scene, *rt);
    if (st != IIR_OK) {
        iir_rt_destroy(*rt);
        iir_scene_destroy(*scene);
        *rt = NULL;
        *scene = NULL;
    }
    return st;
}

/* fuzz_anim.c -- libFuzzer target for animation scripts (docs/animation-format.md): the bytes are
 * a script's text; iir_anim_parse must refuse it with a message or return a script, which is then
 * evaluated at a few times and frames from the built-in Cornell box's light and camera, and, when
 * iir_anim_check_lights accepts it, over five lights of every kind (named spot, gltf, point, sun,
 * area). Checks anim.h's promises: a valid base light stays valid, the camera's fov stays in
 * (0, 180). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "iir/anim.h"
#include "iir/scene.h"

static const iir_scene *default_scene(void)
{
    static iir_scene *box;
    if (!box) {
        box = iir_scene_create_cornell_box();
        FUZZ_CHECK(box && box->num_lights > 0);
    }
    return box;
}

/* One light of every kind, each valid, named as a script's "lights" tracks may name them. */
static const iir_light *every_kind(void)
{
    static iir_light L[5];
    if (L[0].name[0]) return L;
    const iir_scene *box = default_scene();
    const char *names[5] = {"spot", "gltf", "point", "sun", "area"};
    for (int i = 0; i < 5; i++) {
        L[i] = box->lights[0]; /* the box's spot: position, direction, cone */
        snprintf(L[i].name, sizeof L[i].name, "%s", names[i]);
    }
    L[1].profile = IIR_SPOT_GLTF, L[1].inner_angle = 0.2f;
    L[2].type = IIR_LIGHT_POINT;
    L[3].type = IIR_LIGHT_SUN;
    iir_light_fit_sun(&L[3], box);
    L[4].type = IIR_LIGHT_AREA, L[4].size = iir_v2(0.4f, 0.3f);
    return L;
}

/* Every light of every kind at t, when the script's tracks fit them: each stays valid. */
static void evaluate_kinds(const iir_anim *a, double t)
{
    const iir_light *L = every_kind();
    iir_light out[5];
    iir_error e;
    for (uint32_t moved = 0; moved <= 5; moved += 5) {
        if (iir_anim_check_lights(a, L, 5, moved, &e) != IIR_OK) {
            FUZZ_CHECK(e.msg[0] != '\0');
            continue;
        }
        iir_anim_lights(a, L, 5, moved, t, out);
        for (int i = 0; i < 5; i++) {
            if (iir_light_validate(&out[i], &e) != IIR_OK) {
                fprintf(stderr, "light '%s' at t = %g: %s\n", L[i].name, t, e.msg);
                FUZZ_CHECK(!"a valid light of every kind stays valid");
            }
            FUZZ_CHECK(out[i].type == L[i].type);
        }
    }
}

static void evaluate(const iir_anim *a, double t)
{
    evaluate_kinds(a, t);
    const iir_scene *box = default_scene();
    iir_light l = iir_anim_light(a, &box->lights[0], t);
    iir_error e;
    if (iir_light_validate(&l, &e) != IIR_OK) {
        fprintf(stderr, "light at t = %g: %s\n", t, e.msg);
        FUZZ_CHECK(!"a valid base light stays valid");
    }
    iir_camera c = iir_anim_camera(a, &box->camera, t);
    FUZZ_CHECK(c.fov_y > 0.f && c.fov_y < 180.f);
    FUZZ_CHECK(iir_is_finite3(c.position) && iir_is_finite3(c.target));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    char *text = malloc(size + 1);
    if (!text) return 0;
    memcpy(text, data, size);
    text[size] = '\0';
    iir_anim *a = (iir_anim *)1; /* must be set to NULL on error */
    iir_error e;
    e.msg[0] = '\0';
    iir_status st = iir_anim_parse(text, "fuzz.json", &a, &e);
    free(text);
    if (st != IIR_OK) {
        FUZZ_CHECK(a == NULL);
        FUZZ_CHECK(e.status == st && e.msg[0] != '\0');
        fuzz_note("error: %s", e.msg);
        return 0;
    }
    FUZZ_CHECK(a != NULL);
    double dur = iir_anim_duration(a), fps = iir_anim_fps(a);
    FUZZ_CHECK(isfinite(dur) && dur >= 0.0 && isfinite(fps) && fps > 0.0);
    fuzz_note("script of %g s at %g fps", dur, fps);
    int frames = iir_anim_frame_count(a);
    FUZZ_CHECK(frames >= 1);
    const double times[] = {-1.0, 0.0, dur * 0.25, dur * 0.5, dur * 0.999, dur, dur + 1.0};
    for (size_t i = 0; i < sizeof times / sizeof *times; i++) evaluate(a, times[i]);
    const int picks[] = {-1, 0, 1, frames / 2, frames - 1, frames};
    for (size_t i = 0; i < sizeof picks / sizeof *picks; i++) {
        double t = iir_anim_frame_time(a, picks[i]);
        FUZZ_CHECK(t >= 0.0 && t <= dur);
        evaluate(a, t);
    }
    iir_anim_destroy(a);
    return 0;
}

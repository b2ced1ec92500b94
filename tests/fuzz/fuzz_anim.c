/* fuzz_anim.c -- libFuzzer target for animation scripts (docs/animation-format.md): the bytes are
 * a script's text; iir_anim_parse must refuse it with a message or return a script, which is then
 * evaluated at a few times and frames from the built-in Cornell box's light and camera. Checks
 * anim.h's promises: a valid base light stays valid, the camera's fov stays in (0, 180). */
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

static void evaluate(const iir_anim *a, double t)
{
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

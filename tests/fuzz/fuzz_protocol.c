/* fuzz_protocol.c -- libFuzzer target for the live protocol's client messages: the bytes are one
 * WebSocket text message; iird_parse_message must accept or refuse it with a non-empty message, and
 * a parsed message is applied to a fresh session's state (the built-in Cornell box's light and
 * camera, the default settings) as the daemon would, then the replies are built. Nothing may
 * crash, leak or be undefined behaviour. */
#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "iir/scene.h"
#include "protocol.h"

/* The session's starting light and camera: the built-in box's, made once per process. */
static const iir_scene *default_scene(void)
{
    static iir_scene *box;
    if (!box) {
        box = iir_scene_create_cornell_box();
        FUZZ_CHECK(box && box->num_lights > 0);
    }
    return box;
}

/* An error as the daemon would send it: a code, a non-empty message, a reply that builds. */
static void check_error(const iird_proto_error *e)
{
    FUZZ_CHECK(e->code >= 0 && e->code < IIRD_E_COUNT);
    FUZZ_CHECK(e->message[0] != '\0');
    FUZZ_CHECK(memchr(e->field, '\0', sizeof e->field) != NULL);
    fuzz_note("error %s at '%s': %s", iird_err_name(e->code), e->field, e->message);
    free(iird_json_error(e));
}

static void apply(const iird_msg *m, const iird_limits *lim)
{
    const iir_scene *box = default_scene();
    iir_light light = box->lights[0];
    iir_camera camera = box->camera;
    iird_settings settings = iird_settings_default();
    iird_proto_error e;
    memset(&e, 0, sizeof e);
    e.seq = m->seq;
    bool ok = true;
    switch (m->type) {
    case IIRD_MSG_LIGHT:
        ok = iird_apply_light(&m->u.light, &light, &e);
        break;
    case IIRD_MSG_CAMERA:
        ok = iird_apply_camera(&m->u.camera, &camera, &e);
        break;
    case IIRD_MSG_PARAMS:
        ok = iird_apply_params(&m->u.params, lim, &settings, &e);
        break;
    case IIRD_MSG_PICK:
        ok = iird_check_pick(m, settings.width, settings.height, &e);
        break;
    default:
        break;
    }
    if (!ok) {
        check_error(&e);
        return;
    }
    fuzz_note("applied message type %d", (int)m->type);
    /* the state reply the session sends after a change */
    iird_state_view view = {.scene = "cornell_box",
                            .light = &light,
                            .camera = &camera,
                            .settings = &settings,
                            .generation = 1};
    free(iird_json_state(&view, m->seq));
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    iird_limits lim = iird_limits_default();
    iird_msg m;
    iird_proto_error e;
    memset(&e, 0, sizeof e);
    if (iird_parse_message((const char *)data, size, &lim, &m, &e))
        apply(&m, &lim);
    else
        check_error(&e);
    return 0;
}

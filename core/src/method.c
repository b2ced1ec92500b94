/* method.c -- the registry of methods and the dispatch of the method interface; parameters and
 * their ranges. Not any method's algorithm. */
#include <stdlib.h>
#include <string.h>

#include "iir/scene.h"
#include "method_internal.h"

static const iir_method_ops *const registry[] = {&iir_method_pt};
enum { NUM_METHODS = sizeof registry / sizeof registry[0] };

struct iir_method {
    const iir_method_ops *ops;
    void *state;
};

iir_params iir_params_default(void)
{
    iir_params p = {.spp = 16, .bounces = 2, .seed = 1};
    return p;
}

iir_status iir_params_validate(const iir_params *p, iir_error *err)
{
    if (p->spp < 1 || p->spp > (1 << 20))
        return iir_fail(err, IIR_ERR_INVALID, "spp %d is outside [1, 1048576]", p->spp);
    if (p->bounces < 1 || p->bounces > 1000)
        return iir_fail(err, IIR_ERR_INVALID, "bounces %d is outside [1, 1000]", p->bounces);
    return IIR_OK;
}

const char *iir_phase_name(iir_phase phase)
{
    static const char *names[IIR_PHASE_COUNT] = {"trace"};
    return phase < IIR_PHASE_COUNT ? names[phase] : "unknown";
}

const char *const *iir_method_names(void)
{
    static const char *names[NUM_METHODS + 1];
    for (int i = 0; i < NUM_METHODS; i++) names[i] = registry[i]->name;
    names[NUM_METHODS] = NULL;
    return names;
}

static const iir_method_ops *find_ops(const char *name)
{
    for (int i = 0; i < NUM_METHODS; i++)
        if (strcmp(registry[i]->name, name) == 0) return registry[i];
    return NULL;
}

static iir_status unknown_method(const char *name, iir_error *err)
{
    char list[256] = "";
    for (int i = 0; i < NUM_METHODS; i++) {
        if (i) strncat(list, ", ", sizeof list - strlen(list) - 1);
        strncat(list, registry[i]->name, sizeof list - strlen(list) - 1);
    }
    return iir_fail(err, IIR_ERR_INVALID, "unknown method '%s' (known: %s)", name, list);
}

iir_status iir_method_create(const char *name, const iir_scene *scene, const iir_rt *rt,
                             const iir_params *params, iir_method **out, iir_error *err)
{
    *out = NULL;
    const iir_method_ops *ops = find_ops(name);
    if (!ops) return unknown_method(name, err);
    iir_status st = iir_params_validate(params, err);
    if (st != IIR_OK) return st;
    iir_method *m = calloc(1, sizeof *m);
    if (!m) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating method '%s'", name);
    m->ops = ops;
    st = ops->create(scene, rt, params, &m->state, err);
    if (st != IIR_OK) {
        free(m);
        return st;
    }
    *out = m;
    return IIR_OK;
}

void iir_method_destroy(iir_method *m)
{
    if (!m) return;
    m->ops->destroy(m->state);
    free(m);
}

const char *iir_method_name(const iir_method *m)
{
    return m->ops->name;
}

iir_status iir_method_render(iir_method *m, const iir_view *view, iir_image *out,
                             iir_frame_stats *stats, iir_error *err)
{
    memset(stats, 0, sizeof *stats);
    return m->ops->render(m->state, view, out, stats, err);
}

bool iir_method_can_refine(const iir_method *m)
{
    return m->ops->refine != NULL;
}

iir_status iir_method_refine(iir_method *m, iir_image *out, iir_frame_stats *stats, iir_error *err)
{
    if (!m->ops->refine)
        return iir_fail(err, IIR_ERR_UNSUPPORTED, "method '%s' cannot refine a frame",
                        m->ops->name);
    memset(stats, 0, sizeof *stats);
    return m->ops->refine(m->state, out, stats, err);
}

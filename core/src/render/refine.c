/* refine.c -- progressive refinement (refine.h): the pass schedule (sweep, subset shift, jitter,
 * seed), the running average and convergence; not how a pass is shaded (render.c) nor how a method
 * makes its VPL sets (methods/ir.c, methods/iir.c). */
#include "iir/refine.h"

#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "iir/rng.h"
#include "iir/timer.h"

struct iir_refine {
    bool active; /* a frame was begun and not ended */
    iir_refine_params params;
    iir_camera camera;
    iir_light *lights; /* copy of the frame's lights, [light_cap] */
    uint32_t num_lights, light_cap;
    int width, height;
    uint32_t passes;    /* in the sum */
    uint32_t set_sweep; /* the sweep whose set `vpls` is; UINT32_MAX = none */
    const iir_vpl *vpls;
    uint32_t num_vpls;
    double *sum;     /* [3 width height] in buffers of size buf_w x buf_h */
    iir_image *pass; /* the pass being rendered */
    int buf_w, buf_h;
};

iir_refine *iir_refine_create(void)
{
    iir_refine *rf = calloc(1, sizeof *rf);
    if (rf) rf->set_sweep = UINT32_MAX;
    return rf;
}

void iir_refine_destroy(iir_refine *rf)
{
    if (!rf) return;
    free(rf->lights);
    free(rf->sum);
    iir_image_destroy(rf->pass);
    free(rf);
}

iir_status iir_refine_params_validate(const iir_refine_params *p, iir_error *err)
{
    if (p->interleave < 1 || p->interleave > 8)
        return iir_fail(err, IIR_ERR_INVALID, "refine interleave %d is outside [1, 8]",
                        p->interleave);
    if (p->max_passes < 1 || p->max_passes > IIR_REFINE_MAX_PASSES)
        return iir_fail(err, IIR_ERR_INVALID, "refine_passes %d is outside [1, %d]", p->max_passes,
                        IIR_REFINE_MAX_PASSES);
    if (!(p->clamp >= 0.f) || isinf(p->clamp))
        return iir_fail(err, IIR_ERR_INVALID, "refine clamp %g must be finite and >= 0",
                        (double)p->clamp);
    return IIR_OK;
}

iir_status iir_refine_begin(iir_refine *rf, const iir_camera *cam, const iir_light *lights,
                            uint32_t num_lights, int width, int height, const iir_refine_params *p,
                            iir_error *err)
{
    rf->active = false;
    if (num_lights > rf->light_cap) {
        iir_light *grown = realloc(rf->lights, sizeof(iir_light) * num_lights);
        if (!grown) return iir_fail(err, IIR_ERR_NOMEM, "refine: out of memory for the lights");
        rf->lights = grown;
        rf->light_cap = num_lights;
    }
    if (num_lights) memcpy(rf->lights, lights, sizeof(iir_light) * num_lights);
    rf->num_lights = num_lights;
    rf->camera = *cam;
    rf->params = *p;
    rf->width = width;
    rf->height = height;
    rf->passes = 0;
    rf->set_sweep = UINT32_MAX;
    rf->vpls = NULL;
    rf->num_vpls = 0;
    rf->active = true;
    return IIR_OK;
}

void iir_refine_end(iir_refine *rf)
{
    rf->active = false;
    rf->set_sweep = UINT32_MAX;
    rf->vpls = NULL;
}

const iir_light *iir_refine_lights(const iir_refine *rf, uint32_t *n)
{
    *n = rf->active ? rf->num_lights : 0;
    return rf->active ? rf->lights : NULL;
}

iir_vec2 iir_refine_jitter(uint32_t i)
{
    double a = (double)iir_radical_inverse(2, i) + 0.5, b = (double)iir_radical_inverse(3, i) + 0.5;
    a -= floor(a);
    b -= floor(b);
    return iir_v2(fminf((float)a, 0x1.fffffep-1f), fminf((float)b, 0x1.fffffep-1f));
}

/* ---- buffers and the average ---- */

/* The sum and pass image for the frame size, allocated when the size changed. */
static iir_status buffers(iir_refine *rf, iir_error *err)
{
    if (rf->sum && rf->buf_w == rf->width && rf->buf_h == rf->height) return IIR_OK;
    free(rf->sum);
    iir_image_destroy(rf->pass);
    size_t n = (size_t)rf->width * (size_t)rf->height;
    rf->sum = malloc(sizeof(double) * 3 * n);
    rf->pass = iir_image_create(rf->width, rf->height);
    if (!rf->sum || !rf->pass) {
        free(rf->sum);
        iir_image_destroy(rf->pass);
        rf->sum = NULL, rf->pass = NULL;
        rf->buf_w = rf->buf_h = 0;
        return iir_fail(err, IIR_ERR_NOMEM, "refine: out of memory for a %dx%d frame", rf->width,
                        rf->height);
    }
    rf->buf_w = rf->width;
    rf->buf_h = rf->height;
    return IIR_OK;
}

/* sum += pass (when add), out = sum / passes; OpenMP over rows, each pixel on its own. */
static void average(iir_refine *rf, bool add, iir_image *out)
{
    int h = rf->height, w = rf->width;
    double inv = 1.0 / (double)rf->passes;
#pragma omp parallel for schedule(static)
    for (int y = 0; y < h; y++) {
        size_t row = (size_t)y * (size_t)w;
        for (int x = 0; x < w; x++) {
            double *s = &rf->sum[3 * (row + (size_t)x)];
            if (add) {
                iir_vec3 L = rf->pass->pixels[row + (size_t)x];
                s[0] += L.x, s[1] += L.y, s[2] += L.z;
            }
            out->pixels[row + (size_t)x] =
                iir_v3((float)(s[0] * inv), (float)(s[1] * inv), (float)(s[2] * inv));
        }
    }
}

/* ---- one pass ---- */

static iir_status check_call(const iir_refine *rf, const iir_image *out, iir_error *err)
{
    if (!rf->active)
        return iir_fail(err, IIR_ERR_INVALID, "refine called before any frame was rendered");
    if (out->width != rf->width || out->height != rf->height)
        return iir_fail(err, IIR_ERR_INVALID, "refine needs a %dx%d image, got %dx%d", rf->width,
                        rf->height, out->width, out->height);
    return IIR_OK;
}

/* The VPL set of the sweep of the next pass, asked for once per sweep. */
static iir_status sweep_set(iir_refine *rf, uint32_t sweep, iir_refine_vpls_fn fn, void *ctx,
                            iir_refine_stats *st, iir_error *err)
{
    if (rf->set_sweep == sweep) return IIR_OK;
    double t0 = iir_now_ms();
    rf->set_sweep = UINT32_MAX;
    iir_status s = fn(ctx, sweep, &rf->vpls, &rf->num_vpls, &st->rays, err);
    if (s == IIR_OK) rf->set_sweep = sweep;
    st->vpls_ms = iir_now_ms() - t0;
    return s;
}

iir_status iir_refine_pass(iir_refine *rf, iir_renderer *r, iir_refine_vpls_fn vpls, void *ctx,
                           iir_image *out, iir_refine_stats *stats, iir_error *err)
{
    iir_refine_stats st;
    memset(&st, 0, sizeof st);
    double t0 = iir_now_ms();
    const iir_refine_params *p = &rf->params;
    iir_status s = check_call(rf, out, err);
    if (s == IIR_OK) s = buffers(rf, err);
    bool work = s == IIR_OK && rf->passes < (uint32_t)p->max_passes;
    uint32_t n2 = (uint32_t)(p->interleave * p->interleave), i = rf->passes;
    if (work) {
        if (i == 0) memset(rf->sum, 0, sizeof(double) * 3 * (size_t)rf->width * rf->height);
        s = sweep_set(rf, i / n2, vpls, ctx, &st, err);
    }
    if (work && s == IIR_OK) {
        iir_pass_params pp = {.interleave = p->interleave,
                              .shift = i % n2,
                              .jitter = p->jitter ? iir_refine_jitter(i) : iir_v2(0.5f, 0.5f),
                              .clamp = p->clamp,
                              .clamp_comp = p->clamp_comp,
                              .bounces = p->bounces,
                              .area_samples = p->area_samples};
        iir_render_input in = {.camera = &rf->camera,
                               .lights = rf->lights,
                               .num_lights = rf->num_lights,
                               .vpls = rf->vpls,
                               .num_vpls = rf->num_vpls,
                               .seed = iir_hash3(p->seed, i, 0x5eed)};
        s = iir_renderer_pass(r, &in, &pp, rf->pass, &st.timing, &st.rays, err);
    }
    if (work && s == IIR_OK) rf->passes++;
    if (s == IIR_OK && rf->passes > 0) average(rf, work, out);
    st.passes = rf->passes;
    st.converged = rf->active && rf->passes >= (uint32_t)p->max_passes;
    st.worked = work && s == IIR_OK;
    st.sweep = i / (n2 ? n2 : 1);
    st.whole_sweeps = n2 <= 1 || rf->passes % n2 == 0;
    st.num_vpls = rf->set_sweep == UINT32_MAX ? 0 : rf->num_vpls;
    st.total_ms = iir_now_ms() - t0;
    if (stats) *stats = st;
    return s;
}

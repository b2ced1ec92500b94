/* radiosity.c -- patch radiosity (Cohen & Greenberg 1985; Cohen & Wallace 1993), method
 * "radiosity": the scene meshed into patches (radiosity/mesh.c), hemicube form factors computed
 * once per scene and cached on disk (radiosity/hemicube.c, ffcache.c), and per frame the lights'
 * direct light shot onto the patches and the system re-solved (radiosity/solve.c). The solution
 * is displayed by Gouraud interpolation through the G-buffer. Not the solvers themselves.
 *
 * The equation, per patch i (B radiosity, W/m^2): B_i = E_i + rho_i sum_j F_ij B_j, with
 *     E_i = pi Le_i + rho_i Ed_i,
 * Le_i the patch material's emitted radiance and Ed_i the irradiance from the view's lights (the
 * mean over light_samples points of the patch, one shadow ray each). A moving light changes only
 * Ed, so a frame re-shoots direct light and re-solves with the cached F.
 *
 * Display. Per patch an irradiance H_i is averaged to the vertices (area-weighted over the patches
 * around a vertex) and interpolated over each patch (barycentrics of the pixel's point in its
 * sub-triangle); a pixel shows L = rho_x H(x) / pi plus:
 *  - direct = pixels (default): the renderer's exact direct light and emission per pixel (shadow
 *    rays, crisp shadows), and H_i = sum_j F_ij (B_j - pi Le_j), the light of one bounce or more;
 *  - direct = patches: the G-buffer's emission only, and H_i = Ed_i + sum_j F_ij B_j, all light at
 *    patch resolution (area lights seen directly by the camera are then not drawn).
 *
 * Solvers: gauss (dense, refused above RAD_GAUSS_MAX patches), gauss_seidel (iterations sweeps
 * or relative change below tolerance; from the last frame's B, so a moving light costs few sweeps),
 * progressive (a frame shoots shoot_batch patches, each refine call another batch, converged when
 * the unshot power is below tolerance times the emitted; the ambient term is displayed with the
 * partial solution). */
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../radiosity/radiosity.h"
#include "iir/method.h"
#include "iir/rng.h"
#include "iir/timer.h"
#include "method_internal.h"

enum { RAD_GAUSS_MAX = 3000, RAD_MAX_PATCHES = 200000, RAD_MAX_LIGHTS = 64 };

/* ---- parameters ---- */

typedef enum rad_direct { RAD_DIRECT_PATCHES, RAD_DIRECT_PIXELS } rad_direct;

typedef struct rad_options {
    iir_method_common common;
    float patch_area; /* target patch area as a fraction of the bounding box's surface */
    int hemicube_res;
    rad_solver solver;
    int iterations;
    float tolerance;
    int shoot_batch;
    int light_samples;
    rad_direct direct;
} rad_options;

static const char *const SOLVER_CHOICES[] = {"gauss", "gauss_seidel", "progressive", NULL};
static const char *const DIRECT_CHOICES[] = {"patches", "pixels", NULL};

static const iir_param ROWS[] = {
    {"patch_area", IIR_PARAM_FLOAT, offsetof(rad_options, patch_area), 0.002, 1e-6, 1, 0, NULL, "",
     "largest patch area, as a fraction of the scene bounding box's surface area",
     IIR_PARAM_RESTART},
    {"hemicube_res", IIR_PARAM_INT, offsetof(rad_options, hemicube_res), 32, 4, 512, 0, NULL,
     "cells", "hemicube top face resolution (sides res x res/2; even)", IIR_PARAM_RESTART},
    {"solver", IIR_PARAM_ENUM, offsetof(rad_options, solver), RAD_GAUSS_SEIDEL, 0, 2, 0,
     SOLVER_CHOICES, "",
     "gauss (dense, at most 3000 patches), gauss_seidel or progressive (shooting, refines)",
     IIR_PARAM_LIVE},
    {"iterations", IIR_PARAM_INT, offsetof(rad_options, iterations), 100, 1, 100000, 0, NULL,
     "sweeps", "gauss_seidel: most sweeps per solve", IIR_PARAM_LIVE},
    {"tolerance", IIR_PARAM_FLOAT, offsetof(rad_options, tolerance), 1e-4, 1e-9, 1, 0, NULL, "",
     "gauss_seidel: stop when a sweep changes B by less than this times max B; progressive: "
     "converged when unshot power is below this times the emitted",
     IIR_PARAM_LIVE},
    {"shoot_batch", IIR_PARAM_INT, offsetof(rad_options, shoot_batch), 128, 1, 1000000, 0, NULL,
     "shots", "progressive: patches shot per frame and per refinement pass", IIR_PARAM_LIVE},
    {"light_samples", IIR_PARAM_INT, offsetof(rad_options, light_samples), 4, 1, 256, 0, NULL,
     "rays", "direct light shot onto each patch: points (shadow rays) per patch and light",
     IIR_PARAM_LIVE},
    {"direct", IIR_PARAM_ENUM, offsetof(rad_options, direct), RAD_DIRECT_PIXELS, 0, 1, 0,
     DIRECT_CHOICES, "",
     "direct light per pixel with shadow rays (pixels, crisp) or from the patches (patches)",
     IIR_PARAM_LIVE},
};

static iir_status check_opts(const void *opts, const iir_params *given, const iir_param **bad,
                             iir_error *err)
{
    (void)given;
    const rad_options *o = opts;
    if (o->hemicube_res % 2 == 0) return IIR_OK;
    if (bad) *bad = &ROWS[1];
    return iir_fail(err, IIR_ERR_INVALID, "hemicube_res must be even (got %d)", o->hemicube_res);
}

static const iir_param_table RAD_TABLE = {"radiosity: patches, form factors, solver", ROWS,
                                          sizeof ROWS / sizeof ROWS[0], check_opts};

/* ---- state ---- */

typedef struct rad_state {
    const iir_scene *scene;
    const iir_rt *rt;
    rad_options o;
    iir_renderer *renderer;
    rad_mesh mesh;
    rad_ff ff;
    iir_vec3 *Ed, *E, *B, *Bd, *H, *vH; /* per patch (Bd: B as displayed); vH per vertex */
    float *vw;                          /* per vertex: the area around it */
    rad_progressive prog;
    bool prog_done;
    uint64_t passes;
    iir_light *lights; /* the lights of the last solve */
    uint32_t num_lights;
    bool solved;
    bool warm;        /* B holds a Gauss-Seidel solution to start the next solve from */
    iir_vec3 *direct; /* the last frame's renderer output (direct light), for refinement */
    size_t direct_cap;
    bool have_frame;
    iir_stop_fn stop;
    void *stop_ctx;
} rad_state;

/* ---- direct light onto the patches ---- */

static float u01(uint64_t h)
{
    return (float)(h >> 40) * 0x1p-24f;
}

/* Point k of S on patch p: stratified along the first barycentric axis, rotated per patch. */
static iir_vec3 patch_point(const rad_mesh *m, uint32_t p, int k, int S, uint64_t h)
{
    if (S == 1) return m->centre[p];
    float a = fmodf(((float)k + .5f) / (float)S + u01(h), 1.f);
    float b = fmodf(u01(iir_mix64(h)) + (float)k * 0.618034f, 1.f);
    float su = sqrtf(a), w1 = 1.f - su, w2 = b * su; /* uniform on the triangle */
    const iir_vec3 *v = m->vpos;
    const uint32_t *c = m->vert[p];
    return iir_add(iir_scale(v[c[0]], w1),
                   iir_add(iir_scale(v[c[1]], w2), iir_scale(v[c[2]], 1.f - w1 - w2)));
}

/* Irradiance at x (normal n) from light l, with a shadow ray; u for an area light's point. */
static iir_vec3 light_irradiance(const iir_rt *rt, const iir_light *l, const iir_light_eval *ev,
                                 iir_vec3 x, iir_vec3 n, iir_vec2 u, iir_raystats *st)
{
    iir_vec3 wi, E;
    float dist;
    if (l->type == IIR_LIGHT_SUN) {
        wi = iir_normalize(iir_neg(l->direction)), dist = INFINITY;
        E = iir_scale(l->intensity, fmaxf(0.f, iir_dot(n, wi)));
    } else if (l->type == IIR_LIGHT_AREA) {
        iir_light_sample ls = iir_area_light_sample(l, x, u);
        if (ls.pdf <= 0.f) return iir_v3s(0.f);
        wi = ls.wi, dist = ls.dist;
        E = iir_scale(ls.Li, fmaxf(0.f, iir_dot(n, wi)) / ls.pdf);
    } else {
        iir_vec3 d = iir_sub(l->position, x);
        dist = iir_length(d), wi = iir_scale(d, 1.f / fmaxf(dist, 1e-30f));
        E = iir_scale(iir_light_eval_intensity(ev, iir_neg(wi)),
                      fmaxf(0.f, iir_dot(n, wi)) / fmaxf(dist * dist, 1e-30f));
    }
    if (iir_is_black(E)) return E;
    float eps = iir_rt_epsilon(rt);
    iir_ray r = iir_make_ray(iir_madd(x, n, eps), wi, 0.f, dist * (1.f - 1e-4f) - eps);
    return iir_rt_occluded(rt, &r, st, IIR_RAYS_SHADOW) ? iir_v3s(0.f) : E;
}

/* Ed_i for every patch and E_i = pi Le_i + rho_i Ed_i. */
static void shoot_direct(rad_state *s, const iir_light *lights, uint32_t num_lights,
                         iir_raystats *rays)
{
    const rad_mesh *m = &s->mesh;
    const int S = s->o.light_samples;
    iir_light_eval ev[RAD_MAX_LIGHTS];
    const uint32_t nl = num_lights; /* <= RAD_MAX_LIGHTS (rad_render) */
    for (uint32_t l = 0; l < nl; l++) ev[l] = iir_light_prepare(&lights[l]);
#pragma omp parallel
    {
        iir_raystats st = {0};
#pragma omp for schedule(dynamic, 64)
        for (uint32_t p = 0; p < m->num_patches; p++) {
            iir_vec3 Ed = iir_v3s(0.f);
            for (uint32_t l = 0; l < nl; l++)
                for (int k = 0; k < S; k++) {
                    uint64_t h = iir_hash3(s->o.common.seed, p, l);
                    iir_vec3 x = patch_point(m, p, k, S, h);
                    iir_vec2 u = iir_v2(((float)k + u01(iir_mix64(h + 1))) / (float)S,
                                        u01(iir_hash3(h, (uint64_t)k, 7)));
                    Ed = iir_add(
                        Ed, light_irradiance(s->rt, &lights[l], &ev[l], x, m->normal[p], u, &st));
                }
            s->Ed[p] = iir_scale(Ed, 1.f / (float)S);
            s->E[p] = iir_add(m->emit[p], iir_mul(m->rho[p], s->Ed[p]));
        }
#pragma omp critical
        iir_raystats_add(rays, &st);
    }
}

/* ---- solving ---- */

/* Solves for B with the current E (progressive: restarts and shoots one batch). */
static iir_status solve(rad_state *s, iir_error *err)
{
    const rad_mesh *m = &s->mesh;
    s->passes = 0;
    s->prog_done = true;
    switch (s->o.solver) {
    case RAD_GAUSS:
        s->warm = false;
        return rad_solve_gauss(&s->ff, m->rho, s->E, s->B, err);
    case RAD_GAUSS_SEIDEL:
        rad_solve_gauss_seidel(&s->ff, m->rho, s->E, s->B, s->o.iterations, s->o.tolerance,
                               s->warm);
        s->warm = true;
        return IIR_OK;
    case RAD_PROGRESSIVE:
        s->warm = false;
        if (!rad_progressive_init(&s->prog, m, &s->ff, s->E, s->B))
            return iir_fail(err, IIR_ERR_NOMEM, "radiosity: out of memory");
        s->prog_done = rad_progressive_shoot(&s->prog, m, s->B, s->o.shoot_batch, s->o.tolerance);
        return IIR_OK;
    }
    return iir_fail(err, IIR_ERR_INVALID, "radiosity: unknown solver");
}

/* ---- display ---- */

/* The radiosity shown for patch j: B_j, plus rho_j times the ambient term while progressive
 * refinement has unshot power. */
static void display_B(const rad_state *s, iir_vec3 *Bd)
{
    const rad_mesh *m = &s->mesh;
    iir_vec3 amb =
        s->o.solver == RAD_PROGRESSIVE ? rad_progressive_ambient(&s->prog, m) : iir_v3s(0.f);
    for (uint32_t j = 0; j < m->num_patches; j++) Bd[j] = iir_add(s->B[j], iir_mul(m->rho[j], amb));
}

/* H per patch (see the top of the file), then per vertex (area-weighted). */
static void vertex_irradiance(rad_state *s)
{
    const rad_mesh *m = &s->mesh;
    const bool pixels = s->o.direct == RAD_DIRECT_PIXELS;
    display_B(s, s->Bd);
    for (uint32_t j = 0; pixels && j < m->num_patches; j++)
        s->Bd[j] = iir_sub(s->Bd[j], m->emit[j]);
#pragma omp parallel for schedule(dynamic, 64)
    for (uint32_t i = 0; i < m->num_patches; i++) {
        iir_vec3 h = pixels ? iir_v3s(0.f) : s->Ed[i];
        for (uint64_t k = s->ff.row[i]; k < s->ff.row[i + 1]; k++)
            h = iir_madd(h, s->Bd[s->ff.col[k]], s->ff.val[k]);
        s->H[i] = h;
    }
    memset(s->vH, 0, m->num_vertices * sizeof *s->vH);
    memset(s->vw, 0, m->num_vertices * sizeof *s->vw);
    for (uint32_t i = 0; i < m->num_patches; i++)
        for (int a = 0; a < 3; a++) {
            uint32_t v = m->vert[i][a];
            s->vH[v] = iir_madd(s->vH[v], s->H[i], m->area[i]);
            s->vw[v] += m->area[i];
        }
    for (uint32_t v = 0; v < m->num_vertices; v++)
        if (s->vw[v] > 0.f) s->vH[v] = iir_scale(s->vH[v], 1.f / s->vw[v]);
}

/* Barycentrics (u, v) of x in scene triangle t (p = (1-u-v) p0 + u p1 + v p2). */
static void tri_barycentrics(const iir_scene *sc, uint32_t t, iir_vec3 x, float *u, float *v)
{
    iir_vec3 p0 = sc->positions[sc->indices[3 * t]];
    iir_vec3 e1 = iir_sub(sc->positions[sc->indices[3 * t + 1]], p0);
    iir_vec3 e2 = iir_sub(sc->positions[sc->indices[3 * t + 2]], p0), d = iir_sub(x, p0);
    float d00 = iir_dot(e1, e1), d01 = iir_dot(e1, e2), d11 = iir_dot(e2, e2);
    float d20 = iir_dot(d, e1), d21 = iir_dot(d, e2), den = d00 * d11 - d01 * d01;
    *u = den != 0.f ? (d11 * d20 - d01 * d21) / den : 0.f;
    *v = den != 0.f ? (d00 * d21 - d01 * d20) / den : 0.f;
}

/* H at barycentrics (u, v) of triangle t: Gouraud over the patch's three vertices. */
static iir_vec3 gouraud(const rad_state *s, uint32_t t, float u, float v)
{
    const rad_mesh *m = &s->mesh;
    uint32_t p = rad_patch_of(m, t, u, v), n = m->tri_n[t];
    int gi[3], gj[3];
    rad_subtri_grid(n, p - m->tri_first[t], gi, gj);
    /* the point in grid coordinates, then its barycentrics in the sub-triangle */
    float a = u * (float)n - (float)gi[0], b = v * (float)n - (float)gj[0];
    float ax = (float)(gi[1] - gi[0]), ay = (float)(gj[1] - gj[0]);
    float bx = (float)(gi[2] - gi[0]), by = (float)(gj[2] - gj[0]), det = ax * by - ay * bx;
    float w1 = iir_clampf((a * by - b * bx) / det, 0.f, 1.f);
    float w2 = iir_clampf((ax * b - ay * a) / det, 0.f, 1.f - w1);
    const uint32_t *c = m->vert[p];
    return iir_add(iir_scale(s->vH[c[0]], 1.f - w1 - w2),
                   iir_add(iir_scale(s->vH[c[1]], w1), iir_scale(s->vH[c[2]], w2)));
}

/* out = base + rho_x H(x) / pi per pixel; base is the renderer's frame (pixels) or the G-buffer's
 * emission (patches). */
static void shade(rad_state *s, iir_image *out)
{
    const iir_gbuffer *gb = iir_renderer_gbuffer(s->renderer);
    const bool pixels = s->o.direct == RAD_DIRECT_PIXELS;
    const int n = gb->width * gb->height;
#pragma omp parallel for schedule(dynamic, 256)
    for (int q = 0; q < n; q++) {
        iir_vec3 L = pixels ? s->direct[q] : gb->emission[q];
        if (isfinite(gb->depth[q]) && gb->prim[q] != IIR_NO_HIT) {
            float u, v;
            tri_barycentrics(s->scene, gb->prim[q], gb->position[q], &u, &v);
            L = iir_madd(L, iir_mul(gb->albedo[q], gouraud(s, gb->prim[q], u, v)), IIR_INV_PI);
        }
        out->pixels[q] = L;
    }
}

/* ---- the frame ---- */

static bool lights_changed(const rad_state *s, const iir_view *view)
{
    return !s->solved || view->num_lights != s->num_lights ||
           (view->num_lights &&
            memcmp(view->lights, s->lights, view->num_lights * sizeof *view->lights) != 0);
}

/* Re-shoots direct light and re-solves when the lights moved. */
static iir_status update_solution(rad_state *s, const iir_view *view, iir_frame_stats *stats,
                                  iir_error *err)
{
    if (!lights_changed(s, view)) return IIR_OK;
    if (view->num_lights > RAD_MAX_LIGHTS)
        return iir_fail(err, IIR_ERR_INVALID, "radiosity: at most %d lights", RAD_MAX_LIGHTS);
    s->solved = false;
    double t0 = iir_now_ms();
    shoot_direct(s, view->lights, view->num_lights, &stats->rays);
    iir_status st = solve(s, err);
    if (st != IIR_OK) return st;
    if (view->num_lights) memcpy(s->lights, view->lights, view->num_lights * sizeof *s->lights);
    s->num_lights = view->num_lights;
    s->solved = true;
    stats->phase_ms[IIR_PHASE_VPLS] = iir_now_ms() - t0;
    return IIR_OK;
}

static iir_status rad_render(void *state, const iir_view *view, iir_image *out,
                             iir_frame_stats *stats, iir_error *err)
{
    rad_state *s = state;
    s->have_frame = false;
    iir_status st = iir_view_validate(view, err);
    if (st != IIR_OK) return st;
    double t0 = iir_now_ms();
    st = update_solution(s, view, stats, err);
    if (st != IIR_OK) return st;
    double solve_ms = stats->phase_ms[IIR_PHASE_VPLS];
    iir_indirect_params ind = iir_indirect_params_default();
    ind.visibility = IIR_VIS_RAYS, ind.interleave = 1; /* no VPLs: direct light only */
    iir_render_timing rt;
    iir_render_input in = {.camera = &view->camera,
                           .lights = view->lights,
                           .num_lights = view->num_lights,
                           .seed = iir_frame_direct_seed(s->o.common.seed)};
    st = iir_renderer_frame(s->renderer, &in, &ind, out, &rt, &stats->rays, err);
    if (st != IIR_OK) return st;
    size_t n = (size_t)out->width * (size_t)out->height;
    if (n > s->direct_cap) {
        iir_vec3 *d = realloc(s->direct, n * sizeof *d);
        if (!d) return iir_fail(err, IIR_ERR_NOMEM, "radiosity: out of memory for the frame");
        s->direct = d, s->direct_cap = n;
    }
    memcpy(s->direct, out->pixels, n * sizeof *s->direct);
    double t1 = iir_now_ms();
    vertex_irradiance(s);
    shade(s, out);
    iir_raystats rays = stats->rays;
    iir_render_timing_to_stats(&rt, stats);
    stats->rays = rays;
    stats->phase_ms[IIR_PHASE_VPLS] = solve_ms;
    stats->phase_ms[IIR_PHASE_INDIRECT] = iir_now_ms() - t1;
    stats->total_ms = iir_now_ms() - t0;
    stats->converged = s->prog_done;
    stats->whole_sweeps = true;
    s->have_frame = true;
    return IIR_OK;
}

/* Progressive: shoots another batch and redisplays; other solvers are converged at once. */
static iir_status rad_refine(void *state, iir_image *out, iir_frame_stats *stats, iir_error *err)
{
    rad_state *s = state;
    if (!s->have_frame) return iir_fail(err, IIR_ERR_INVALID, "radiosity: no frame to refine");
    memset(stats, 0, sizeof *stats);
    double t0 = iir_now_ms();
    if (!s->prog_done) {
        s->prog_done =
            rad_progressive_shoot(&s->prog, &s->mesh, s->B, s->o.shoot_batch, s->o.tolerance);
        s->passes++;
    }
    /* converged: counts as the still's refine_passes, so iird render stops here */
    if (s->prog_done && s->passes < (uint64_t)s->o.common.refine_passes)
        s->passes = (uint64_t)s->o.common.refine_passes;
    double t1 = iir_now_ms();
    vertex_irradiance(s);
    shade(s, out);
    stats->phase_ms[IIR_PHASE_VPLS] = t1 - t0;
    stats->phase_ms[IIR_PHASE_INDIRECT] = iir_now_ms() - t1;
    stats->total_ms = iir_now_ms() - t0;
    stats->samples_per_pixel = s->passes;
    stats->converged = s->prog_done;
    stats->whole_sweeps = true;
    return IIR_OK;
}

/* ---- form factors: the cache or the hemicube ---- */

static void log_progress(void *ctx, uint32_t done, uint32_t total)
{
    (void)ctx;
    fprintf(stderr, "radiosity: form factors %u/%u patches (%.0f%%)\n", done, total,
            100.0 * done / total);
}

/* Says once per process that the cache cannot be written. */
static void warn_uncached(const iir_error *e)
{
    static int said;
    int first;
#pragma omp atomic capture
    first = said++;
    if (first == 0) fprintf(stderr, "radiosity: form factors not cached: %s\n", e->msg);
}

static iir_status form_factors(rad_state *s, iir_error *err)
{
    char dir[1024];
    rad_cache_dir(dir, sizeof dir);
    float area = s->mesh.num_patches ? s->o.patch_area : 0.f;
    uint64_t key = rad_ff_key(s->scene, area, s->o.hemicube_res);
    const char *why = NULL;
    double t0 = iir_now_ms();
    if (*dir && rad_ff_load(&s->ff, dir, key, s->mesh.num_patches, &why)) {
        fprintf(stderr,
                "radiosity: form factors of %u patches (%llu non-zeros) loaded in %.1f ms\n",
                s->mesh.num_patches, (unsigned long long)s->ff.nnz, iir_now_ms() - t0);
        return IIR_OK;
    }
    if (*dir && why && strcmp(why, "no file") != 0)
        fprintf(stderr, "radiosity: cached form factors unusable (%s); recomputing\n", why);
    iir_status st = rad_ff_compute(&s->ff, &s->mesh, s->scene, s->rt, s->o.hemicube_res,
                                   s->mesh.num_patches >= 1000 ? log_progress : NULL, NULL, err);
    if (st != IIR_OK) return st;
    fprintf(stderr, "radiosity: form factors of %u patches (%llu non-zeros) computed in %.1f ms\n",
            s->mesh.num_patches, (unsigned long long)s->ff.nnz, iir_now_ms() - t0);
    iir_error e;
    if (!*dir)
        warn_uncached(&(iir_error){.msg = "no cache directory (IIR_CACHE_DIR is empty)"});
    else if (!rad_ff_save(&s->ff, dir, key, &e))
        warn_uncached(&e);
    return IIR_OK;
}

/* ---- the method interface ---- */

static void rad_destroy(void *state)
{
    rad_state *s = state;
    if (!s) return;
    iir_renderer_destroy(s->renderer);
    rad_mesh_free(&s->mesh);
    rad_ff_free(&s->ff);
    rad_progressive_free(&s->prog);
    free(s->Ed), free(s->E), free(s->B), free(s->Bd), free(s->H), free(s->vH), free(s->vw);
    free(s->lights), free(s->direct);
    free(s);
}

static bool alloc_state(rad_state *s)
{
    size_t n = s->mesh.num_patches ? s->mesh.num_patches : 1;
    size_t v = s->mesh.num_vertices ? s->mesh.num_vertices : 1;
    s->Ed = malloc(n * sizeof *s->Ed), s->E = malloc(n * sizeof *s->E);
    s->B = calloc(n, sizeof *s->B), s->Bd = malloc(n * sizeof *s->Bd);
    s->H = malloc(n * sizeof *s->H), s->vH = malloc(v * sizeof *s->vH);
    s->vw = malloc(v * sizeof *s->vw), s->lights = malloc(RAD_MAX_LIGHTS * sizeof *s->lights);
    return s->Ed && s->E && s->B && s->Bd && s->H && s->vH && s->vw && s->lights;
}

/* The target patch area: patch_area times the bounding box's surface. */
static float target_area(const iir_scene *sc, float frac)
{
    iir_vec3 e = iir_sub(sc->bounds_max, sc->bounds_min);
    return frac * 2.f * (e.x * e.y + e.y * e.z + e.z * e.x);
}

static iir_status rad_create(const iir_scene *scene, const iir_rt *rt, const void *opts,
                             void **state, iir_error *err)
{
    rad_state *s = calloc(1, sizeof *s);
    if (!s) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating radiosity");
    s->scene = scene, s->rt = rt, s->o = *(const rad_options *)opts;
    s->renderer = iir_renderer_create(scene, rt);
    iir_status st = s->renderer ? IIR_OK : iir_fail(err, IIR_ERR_NOMEM, "out of memory");
    if (st == IIR_OK)
        st = rad_mesh_build(&s->mesh, scene, target_area(scene, s->o.patch_area), RAD_MAX_PATCHES,
                            err);
    if (st == IIR_OK && s->o.solver == RAD_GAUSS && s->mesh.num_patches > RAD_GAUSS_MAX)
        st = iir_fail(err, IIR_ERR_UNSUPPORTED,
                      "radiosity: solver gauss takes at most %d patches, patch_area gives %u; "
                      "use gauss_seidel or progressive, or raise patch_area",
                      RAD_GAUSS_MAX, s->mesh.num_patches);
    if (st == IIR_OK && !alloc_state(s))
        st = iir_fail(err, IIR_ERR_NOMEM, "out of memory creating radiosity");
    if (st == IIR_OK) st = form_factors(s, err);
    if (st != IIR_OK) {
        rad_destroy(s);
        return st;
    }
    *state = s;
    return IIR_OK;
}

/* Live parameters: a new solver, tolerance or light sampling re-solves at the next frame. */
static void rad_update(void *state, const void *opts)
{
    rad_state *s = state;
    const rad_options *o = opts;
    if (o->solver == RAD_GAUSS && s->mesh.num_patches > RAD_GAUSS_MAX) return; /* keeps the old */
    s->o = *o;
    s->solved = false;
}

static void rad_set_stop(void *state, iir_stop_fn fn, void *ctx)
{
    rad_state *s = state;
    s->stop = fn, s->stop_ctx = ctx;
    iir_renderer_set_stop(s->renderer, fn, ctx);
}

/* F's non-zeros (at most min(n, 3 res^2) per row, 8 bytes each: column and value), the patches
 * (about 150 bytes each with vertices), gauss's dense n^2 doubles or progressive's transpose of F,
 * and the frame: G-buffer and
 * scratch as the VPL renderer's, plus the direct-light copy. n ~ 1.2 / patch_area (a closed room's
 * surface is about the bounding box's). */
static uint64_t rad_memory(const void *opts, int width, int height)
{
    const rad_options *o = opts;
    uint64_t n = (uint64_t)(1.2 / o->patch_area) + 1;
    uint64_t cells = 3ull * (uint64_t)o->hemicube_res * (uint64_t)o->hemicube_res;
    uint64_t nnz = n * (cells < n ? cells : n);
    uint64_t px = (uint64_t)width * (uint64_t)height;
    uint64_t solver = o->solver == RAD_GAUSS         ? n * n * 8
                      : o->solver == RAD_PROGRESSIVE ? nnz * 8
                                                     : 0;
    return nnz * 8 + n * 150 + solver + px * (56 + 12 + 16 + 12);
}

/* Radiosity renders every light and the emitters' light; mirrors and glass have no diffuse part,
 * so their patches are black. */
static uint32_t rad_dropped(const iir_scene *scene, const iir_light *lights, uint32_t num_lights,
                            iir_dropped *out, uint32_t max)
{
    (void)lights, (void)num_lights;
    uint32_t n = 0;
    for (uint32_t i = 0; i < scene->num_materials; i++) {
        const iir_material *m = &scene->material_list[i];
        if (m->kind != IIR_MATERIAL_DIFFUSE)
            iir_dropped_add(out, max, &n, "radiosity", "material", m->name,
                            "is a %s: radiosity's patches are diffuse only, so it is black; use "
                            "pt or whitted",
                            m->kind == IIR_MATERIAL_GLASS ? "dielectric (glass)" : "mirror");
    }
    return n;
}

/* Progressive: refine_passes batches; the other solvers' first frame is converged (0). */
static uint64_t rad_converged_at(const void *opts)
{
    const rad_options *o = opts;
    return o->solver == RAD_PROGRESSIVE ? (uint64_t)o->common.refine_passes : 0;
}

const iir_method_ops iir_method_radiosity = {
    .name = "radiosity",
    .summary = "patch radiosity: hemicube form factors (cached on disk), Gauss-Seidel or "
               "progressive solve, Gouraud display",
    .tables = {{&RAD_TABLE, 0}, {&iir_common_table, offsetof(rad_options, common)}},
    .opts_size = sizeof(rad_options),
    .create = rad_create,
    .destroy = rad_destroy,
    .render = rad_render,
    .refine = rad_refine,
    .set_stop = rad_set_stop,
    .update = rad_update,
    .memory = rad_memory,
    .converged_at = rad_converged_at,
    .dropped = rad_dropped,
    /* measured against a multi-bounce pt: 8 bounces (the Cornell box's walls keep ~5% past) */
    .reference_bounces = 8,
};

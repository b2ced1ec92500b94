/* solution.c -- the radiosity solution a method keeps (radiosity.h, "the solution"): the mesh and
 * its form factors (cached on disk), the lights' direct light shot onto the patches, the solve,
 * and the Gouraud lookup of the irradiance at any surface point. Not the pixels (the methods
 * radiosity.c and hybrid.c shade) and not the solvers (solve.c). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "iir/rng.h"
#include "iir/timer.h"
#include "radiosity.h"

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

/* Irradiance at x (normal n) from prepared light e, with a shadow ray; u for an area light's
 * point. */
static iir_vec3 light_irradiance(const iir_rt *rt, const iir_light_eval *e, iir_vec3 x, iir_vec3 n,
                                 iir_vec2 u, iir_raystats *st)
{
    iir_light_ctx ctx = {x, n, iir_rt_epsilon(rt)};
    iir_light_sample ls = iir_light_sample_li(e, &ctx, u);
    if (ls.pdf <= 0.f) return iir_v3s(0.f);
    iir_vec3 E = iir_scale(ls.Li, fmaxf(0.f, iir_dot(n, ls.wi)) / ls.pdf);
    if (iir_is_black(E)) return E;
    if (!(ls.shadow.tmax > 0.f)) return E;
    iir_ray r = iir_make_ray(ls.shadow.org, ls.shadow.dir, 0.f, ls.shadow.tmax);
    return iir_rt_occluded(rt, &r, st, IIR_RAYS_SHADOW) ? iir_v3s(0.f) : E;
}

/* Patches between two looks at the stop hook (a few hundred shadow rays and more). */
enum { STOP_PATCHES = 64 };

/* Ed_i for every patch and E_i = pi Le_i + rho_i Ed_i; false (E partial) once the stop hook says
 * stop. */
static bool shoot_direct(rad_solution *s, const iir_light *lights, uint32_t num_lights,
                         iir_raystats *rays)
{
    bool stopped = false;
    const rad_mesh *m = &s->mesh;
    const int S = s->o.light_samples;
    iir_light_eval ev[RAD_MAX_LIGHTS];
    const uint32_t nl = num_lights; /* <= RAD_MAX_LIGHTS (rad_solution_update) */
    for (uint32_t l = 0; l < nl; l++) ev[l] = iir_light_prepare(&lights[l]);
#pragma omp parallel
    {
        iir_raystats st = {0};
#pragma omp for schedule(dynamic, 64)
        for (uint32_t p = 0; p < m->num_patches; p++) {
            bool quit;
#pragma omp atomic read
            quit = stopped;
            if (quit) continue;
            if (p % STOP_PATCHES == 0 && iir_stop_now(&s->stop)) {
#pragma omp atomic write
                stopped = true;
            }
            iir_vec3 Ed = iir_v3s(0.f);
            for (uint32_t l = 0; l < nl; l++)
                for (int k = 0; k < S; k++) {
                    uint64_t h = iir_hash3(s->seed, p, l);
                    iir_vec3 x = patch_point(m, p, k, S, h);
                    iir_vec2 u = iir_v2(((float)k + u01(iir_mix64(h + 1))) / (float)S,
                                        u01(iir_hash3(h, (uint64_t)k, 7)));
                    Ed = iir_add(Ed, light_irradiance(s->rt, &ev[l], x, m->normal[p], u, &st));
                }
            s->Ed[p] = iir_scale(Ed, 1.f / (float)S);
            s->E[p] = iir_add(m->emit[p], iir_mul(m->rho[p], s->Ed[p]));
        }
#pragma omp critical
        iir_raystats_add(rays, &st);
    }
    return !stopped;
}

/* ---- solving ---- */

static iir_status stop_error(iir_error *err)
{
    return iir_fail(err, IIR_ERR_INTERRUPTED, "radiosity: stopped");
}

/* Solves for B with the current E (progressive: restarts and shoots one batch). */
static iir_status solve(rad_solution *s, iir_error *err)
{
    const rad_mesh *m = &s->mesh;
    s->converged = true;
    switch (s->o.solver) {
    case RAD_GAUSS:
        s->warm = false;
        return rad_solve_gauss(&s->ff, m->rho, s->E, s->B, &s->stop, err);
    case RAD_GAUSS_SEIDEL: {
        int sweeps = rad_solve_gauss_seidel(&s->ff, m->rho, s->E, s->B, s->o.iterations,
                                            s->o.tolerance, s->warm, &s->stop);
        s->warm = true;
        return sweeps < 0 ? stop_error(err) : IIR_OK;
    }
    case RAD_PROGRESSIVE: {
        s->warm = false;
        iir_status st = rad_progressive_init(&s->prog, m, &s->ff, s->E, s->B, &s->stop);
        if (st != IIR_OK)
            return st == IIR_ERR_INTERRUPTED ? stop_error(err)
                                             : iir_fail(err, st, "radiosity: out of memory");
        bool cut;
        s->converged = rad_progressive_shoot(&s->prog, m, s->B, s->o.shoot_batch, s->o.tolerance,
                                             &s->stop, &cut);
        return cut ? stop_error(err) : IIR_OK;
    }
    }
    return iir_fail(err, IIR_ERR_INVALID, "radiosity: unknown solver");
}

static bool lights_changed(const rad_solution *s, const iir_light *lights, uint32_t n)
{
    return !s->solved || n != s->num_lights ||
           (n && memcmp(lights, s->lights, n * sizeof *lights) != 0);
}

iir_status rad_solution_update(rad_solution *s, const iir_light *lights, uint32_t num_lights,
                               iir_raystats *rays, double *ms, iir_error *err)
{
    *ms = 0.0;
    if (!lights_changed(s, lights, num_lights)) return IIR_OK;
    if (num_lights > RAD_MAX_LIGHTS)
        return iir_fail(err, IIR_ERR_INVALID, "radiosity: at most %d lights", RAD_MAX_LIGHTS);
    s->solved = false;
    double t0 = iir_now_ms();
    iir_status st = shoot_direct(s, lights, num_lights, rays) ? solve(s, err) : stop_error(err);
    if (st != IIR_OK) return st;
    if (num_lights) memcpy(s->lights, lights, num_lights * sizeof *s->lights);
    s->num_lights = num_lights;
    s->solved = true;
    *ms = iir_now_ms() - t0;
    return IIR_OK;
}

iir_status rad_solution_refine(rad_solution *s, bool *shot, iir_error *err)
{
    *shot = false;
    if (s->converged || s->o.solver != RAD_PROGRESSIVE) return IIR_OK;
    bool cut;
    s->converged = rad_progressive_shoot(&s->prog, &s->mesh, s->B, s->o.shoot_batch, s->o.tolerance,
                                         &s->stop, &cut);
    *shot = true; /* whole shots before a stop stand: the next pass goes on from them */
    return cut ? stop_error(err) : IIR_OK;
}

/* ---- lookup ---- */

/* The radiosity shown for patch j: B_j, plus rho_j times the ambient term while progressive
 * refinement has unshot power. */
static void display_B(const rad_solution *s, iir_vec3 *Bd)
{
    const rad_mesh *m = &s->mesh;
    iir_vec3 amb =
        s->o.solver == RAD_PROGRESSIVE ? rad_progressive_ambient(&s->prog, m) : iir_v3s(0.f);
    for (uint32_t j = 0; j < m->num_patches; j++) Bd[j] = iir_add(s->B[j], iir_mul(m->rho[j], amb));
}

iir_status rad_solution_gather(rad_solution *s, bool with_direct, iir_error *err)
{
    const rad_mesh *m = &s->mesh;
    bool cut = false;
    display_B(s, s->Bd);
    for (uint32_t j = 0; !with_direct && j < m->num_patches; j++)
        s->Bd[j] = iir_sub(s->Bd[j], m->emit[j]);
#pragma omp parallel for schedule(dynamic, 64)
    for (uint32_t i = 0; i < m->num_patches; i++) {
        bool quit;
#pragma omp atomic read
        quit = cut;
        if (quit) continue;
        if (i % (4 * STOP_PATCHES) == 0 && iir_stop_now(&s->stop)) {
#pragma omp atomic write
            cut = true;
        }
        iir_vec3 h = with_direct ? s->Ed[i] : iir_v3s(0.f);
        for (uint64_t k = s->ff.row[i]; k < s->ff.row[i + 1]; k++)
            h = iir_madd(h, s->Bd[s->ff.col[k]], s->ff.val[k]);
        s->H[i] = h;
    }
    if (cut) return stop_error(err);
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
    return IIR_OK;
}

iir_vec3 rad_solution_H(const rad_solution *s, uint32_t t, float u, float v)
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

static iir_status form_factors(rad_solution *s, iir_error *err)
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
    iir_status st = rad_ff_compute(&s->ff, &s->mesh, s->scene, s->rt, s->o.hemicube_res, &s->stop,
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

/* ---- life ---- */

void rad_solution_free(rad_solution *s)
{
    rad_mesh_free(&s->mesh);
    rad_ff_free(&s->ff);
    rad_progressive_free(&s->prog);
    free(s->Ed), free(s->E), free(s->B), free(s->Bd), free(s->H), free(s->vH), free(s->vw);
    free(s->lights);
    memset(s, 0, sizeof *s);
}

static bool alloc_arrays(rad_solution *s)
{
    size_t n = s->mesh.num_patches ? s->mesh.num_patches : 1;
    size_t v = s->mesh.num_vertices ? s->mesh.num_vertices : 1;
    s->Ed = malloc(n * sizeof *s->Ed), s->E = malloc(n * sizeof *s->E);
    s->B = calloc(n, sizeof *s->B), s->Bd = malloc(n * sizeof *s->Bd);
    s->H = malloc(n * sizeof *s->H), s->vH = calloc(v, sizeof *s->vH);
    s->vw = malloc(v * sizeof *s->vw), s->lights = malloc(RAD_MAX_LIGHTS * sizeof *s->lights);
    return s->Ed && s->E && s->B && s->Bd && s->H && s->vH && s->vw && s->lights;
}

float rad_target_area(const iir_scene *sc, float frac)
{
    iir_vec3 e = iir_sub(sc->bounds_max, sc->bounds_min);
    return frac * 2.f * (e.x * e.y + e.y * e.z + e.z * e.x);
}

iir_status rad_solution_init(rad_solution *s, const iir_scene *scene, const iir_rt *rt,
                             const rad_params *o, uint64_t seed, const iir_stop *stop,
                             iir_error *err)
{
    memset(s, 0, sizeof *s);
    s->scene = scene, s->rt = rt, s->o = *o, s->seed = seed;
    if (stop) s->stop = *stop;
    iir_status st = rad_mesh_build(&s->mesh, scene, rad_target_area(scene, o->patch_area),
                                   RAD_MAX_PATCHES, err);
    if (st == IIR_OK && o->solver == RAD_GAUSS && s->mesh.num_patches > RAD_GAUSS_MAX)
        st = iir_fail(err, IIR_ERR_UNSUPPORTED,
                      "radiosity: solver gauss takes at most %d patches, patch_area gives %u; "
                      "use gauss_seidel or progressive, or raise patch_area",
                      RAD_GAUSS_MAX, s->mesh.num_patches);
    if (st == IIR_OK && !alloc_arrays(s))
        st = iir_fail(err, IIR_ERR_NOMEM, "out of memory creating radiosity");
    if (st == IIR_OK) st = form_factors(s, err);
    if (st != IIR_OK) rad_solution_free(s);
    return st;
}

void rad_solution_set_stop(rad_solution *s, iir_stop_fn fn, void *ctx)
{
    s->stop = (iir_stop){fn, ctx};
}

bool rad_solution_set_params(rad_solution *s, const rad_params *o, uint64_t seed)
{
    if (o->solver == RAD_GAUSS && s->mesh.num_patches > RAD_GAUSS_MAX) return false;
    s->o = *o, s->seed = seed;
    s->solved = false;
    return true;
}

/* F's non-zeros (at most min(n, 3 res^2) per row, 8 bytes each: column and value), the patches
 * (about 150 bytes each with vertices), gauss's dense n^2 doubles or progressive's transpose of
 * F. n ~ 1.2 / patch_area (a closed room's surface is about the bounding box's). */
uint64_t rad_solution_memory(const rad_params *o)
{
    uint64_t n = (uint64_t)(1.2 / o->patch_area) + 1;
    uint64_t cells = 3ull * (uint64_t)o->hemicube_res * (uint64_t)o->hemicube_res;
    uint64_t nnz = n * (cells < n ? cells : n);
    uint64_t solver = o->solver == RAD_GAUSS         ? n * n * 8
                      : o->solver == RAD_PROGRESSIVE ? nnz * 8
                                                     : 0;
    return nnz * 8 + n * 150 + solver;
}

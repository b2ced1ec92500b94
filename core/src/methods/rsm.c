/* rsm.c -- reflective shadow maps (Dachsbacher & Stamminger 2005), method "rsm": every frame each
 * light's view is rendered into a map of surface points, normals and reflected flux over its VPL
 * domain (rsm_map.h: a texel is comparable with an iir VPL), and every pixel gathers one-bounce
 * light from texels around its own projection into the map -- **without visibility**: RSM's
 * defining approximation, so light leaks through walls and under objects.
 *
 * Gathering. Pixel x (normal n_x, albedo rho_x) projects to map point t_x. M samples t_x + d_k,
 * d_k = r_max xi1 (sin 2 pi xi2, cos 2 pi xi2) for a fixed Hammersley pattern (xi1 = (k + 1/2) / M,
 * xi2 the radical inverse of k), read the nearest texel each. The pattern is dense near the
 * centre (its density per unit map area is 1 / (2 pi r_max |d|)), so nearby texels dominate, and
 * each sample is weighted by the inverse density -- the paper's density compensation, here with
 * the exact weight (it grows linearly with |d|; the paper's text says xi1^2):
 *     L(x) = (rho_x / pi) sum_k w_k (Phi_k / pi) min(G_k, clamp / D^2),
 *     w_k = 2 pi r_max |d_k| / (M A_t),   A_t = (2 / res)^2 (a texel's area in map units),
 *     G_k = max(0, n_k . w) max(0, -n_x . w) / d^2,  w = (x - x_k) / d,
 * an unbiased estimate of the one-bounce light from the texels within r_max of t_x (r_max =
 * rsm_radius, in map half-widths; 2 reaches every texel from anywhere).
 *
 * Screen-space interpolation (rsm_lowres = L > 1, the paper's cheap mode): the gather runs on every
 * L-th pixel of every L-th row (and the last column and row); a pixel takes the bilinear mean of
 * its four surrounding nodes when all four see its surface (not background, normals within the
 * geometry-aware filter's cosine, the node's point within its relative depth of the pixel's
 * plane), and gathers itself otherwise. The share of pixels gathered again is reported
 * (its counter `recomputed`).
 *
 * With shading = multires the gather runs on the G-buffer's multiresolution hierarchy instead
 * (multires.h: coarse texels where the surface is smooth, pixels at discontinuities; rsm_lowres is
 * then unused), and `recomputed` is the share of pixels gathered at full resolution.
 *
 * Direct light and the G-buffer are the VPL renderer's (render.h). There is no refinement: a
 * frame is what RSM gives. */
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "iir/method.h"
#include "iir/multires.h"
#include "iir/rng.h"
#include "iir/timer.h"
#include "iir/vplsets.h"
#include "method_internal.h"
#include "../render/render_internal.h"
#include "rsm_map.h"

/* rsm's counters: frame stats' counter[RSM_RECOMPUTED]. */
enum { RSM_RECOMPUTED };
#define RSM_COUNTERS                                                                               \
    {                                                                                              \
        {                                                                                          \
            "recomputed", IIR_COUNTER_SHARE,                                                       \
                "the share of the frame's pixels that gathered their own light (lowres: their "    \
                "four nodes "                                                                      \
                "disagreed; multires: pixels at full resolution)"                                  \
        }                                                                                          \
    }

/* ---- parameters ---- */

typedef struct rsm_options {
    iir_method_common common;
    float clamp;
    iir_rsm_options map; /* the maps and the gather: iir_rsm_table (rsm_map.c) */
    int lowres; /* L: gather every L-th pixel, interpolate between; 1 = every pixel gathers */
    iir_shading shading; /* multires: on the G-buffer's hierarchy instead (lowres unused) */
    iir_mr_params mr;    /* its hierarchy */
} rsm_options;

static const iir_param LOWRES_ROWS[] = {
    {"rsm_lowres", IIR_PARAM_INT, offsetof(rsm_options, lowres), 4, 1, 16, 0, NULL, "pixels",
     "gather every n-th pixel and interpolate where the surface agrees; 1 = every pixel",
     IIR_PARAM_LIVE},
};
static const iir_param_table LOWRES_TABLE = {"rsm: screen-space interpolation", LOWRES_ROWS,
                                             sizeof LOWRES_ROWS / sizeof LOWRES_ROWS[0], NULL};

/* ---- state ---- */

typedef struct rsm_state {
    const iir_scene *scene;
    const iir_rt *rt;
    rsm_options o;
    iir_renderer *renderer;
    rsm_map maps[IIR_VPLSETS_MAX_LIGHTS];
    uint32_t num_maps;
    rsm_pattern pattern;
    iir_multires *mr;
    uint64_t gb_serial; /* G-buffers rendered: the hierarchy's key */
    iir_vec3 *E;        /* multires: per pixel, the demodulated light */
    size_t E_cap;
    iir_vec3 *node; /* the gather at the interpolation nodes (demodulated: without rho / pi) */
    size_t node_cap;
    iir_vpl *lit; /* the lit texels of every map, for iir_method_vpls */
    uint32_t num_lit;
    size_t lit_cap;
    iir_stop_fn stop;
    void *stop_ctx;
    bool stopped; /* the frame's gathers were told to stop (row_stop) */
} rsm_state;

static bool grow(void **p, size_t *cap, size_t need, size_t size)
{
    if (need <= *cap) return true;
    void *q = realloc(*p, need * size);
    if (!q) return false;
    *p = q;
    *cap = need;
    return true;
}

float iir_clamp_g_max(const iir_scene *scene, float clamp)
{
    iir_vec3 e = iir_sub(scene->bounds_max, scene->bounds_min);
    return clamp > 0.f ? clamp / iir_dot(e, e) : INFINITY;
}

/* ---- gathering ---- */

/* The demodulated one-bounce light at a G-buffer pixel (0 for background): by its full BSDF
 * where it is glossy (rsm_receiver_pixel). */
static iir_vec3 gather(const rsm_state *s, const iir_gbuffer *gb, size_t i)
{
    iir_vec3 e = iir_v3s(0.f);
    if (!isfinite(gb->depth[i])) return e;
    rsm_receiver q = rsm_receiver_pixel(gb, i);
    for (uint32_t l = 0; l < s->num_maps; l++)
        e = iir_add(e, rsm_gather_map(&s->pattern, &s->maps[l], &q));
    return e;
}

/* Adds pixel i's radiance, demodulated light e, to out: times demod / pi and what its specular
 * chain passes on. */
static void put(iir_image *out, const iir_gbuffer *gb, size_t i, iir_vec3 e)
{
    iir_vec3 d = gb->any_pbr ? iir_gb_demod(gb, i, IIR_RECEIVER_GLOSSY) : gb->albedo[i];
    iir_vec3 L = iir_mul(d, e);
    if (gb->any_chain) L = iir_mul(L, gb->through[i]);
    out->pixels[i] = iir_madd(out->pixels[i], L, 1.f / (float)M_PI);
}

/* Whether pixel i's light is view-dependent (a glossy receiver): never interpolated. */
static bool glossy(const iir_gbuffer *gb, size_t i)
{
    return gb->any_pbr && iir_gb_glossy(gb, i, IIR_RECEIVER_GLOSSY);
}

/* Interpolation nodes: columns 0, L, 2L, ... and the last column; rows likewise. */
static int nodes_along(int size, int L)
{
    return (size - 1) / L + 1 + ((size - 1) % L != 0);
}
static int node_pixel(int i, int size, int L)
{
    int p = i * L;
    return p < size ? p : size - 1;
}

/* Whether node pixel j may stand for pixel i's surface: the filter's test (render.h), and
 * neither glossy. */
static bool node_agrees(const iir_gbuffer *gb, size_t i, size_t j)
{
    if (!isfinite(gb->depth[j]) || glossy(gb, i) || glossy(gb, j)) return false;
    if (iir_dot(gb->normal[i], gb->normal[j]) < IIR_FILTER_MIN_COS) return false;
    float plane = fabsf(iir_dot(gb->normal[i], iir_sub(gb->position[j], gb->position[i])));
    return plane <= IIR_FILTER_MAX_REL_DEPTH * gb->depth[i];
}

/* Whether the frame should end now: polled per row of the gathers (a row at the live limits is
 * ~2k pixels x 1024 samples, a few milliseconds). Once true it stays true for the frame. */
static bool row_stop(rsm_state *s)
{
    bool quit;
#pragma omp atomic read
    quit = s->stopped;
    if (quit || !s->stop || !s->stop(s->stop_ctx)) return quit;
#pragma omp atomic write
    s->stopped = true;
    return true;
}

static void gather_nodes(rsm_state *s, const iir_gbuffer *gb, int nx, int ny)
{
    const int L = s->o.lowres;
#pragma omp parallel for schedule(dynamic, 1)
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx && !row_stop(s); i++) {
            int x = node_pixel(i, gb->width, L), y = node_pixel(j, gb->height, L);
            s->node[(size_t)j * nx + i] = gather(s, gb, (size_t)y * gb->width + x);
        }
}

/* Pixel (x, y)'s light from the four nodes around it, or NULL-free recompute; true if gathered. */
static bool interpolate(const rsm_state *s, const iir_gbuffer *gb, int nx, int x, int y,
                        iir_vec3 *e)
{
    const int L = s->o.lowres, W = gb->width, H = gb->height;
    int i0 = x / L, j0 = y / L;
    int i1 = node_pixel(i0 + 1, W, L) > node_pixel(i0, W, L) ? i0 + 1 : i0;
    int j1 = node_pixel(j0 + 1, H, L) > node_pixel(j0, H, L) ? j0 + 1 : j0;
    int x0 = node_pixel(i0, W, L), x1 = node_pixel(i1, W, L);
    int y0 = node_pixel(j0, H, L), y1 = node_pixel(j1, H, L);
    size_t p = (size_t)y * W + x;
    const int ci[4] = {i0, i1, i0, i1}, cj[4] = {j0, j0, j1, j1};
    const int px[4] = {x0, x1, x0, x1}, py[4] = {y0, y0, y1, y1};
    for (int c = 0; c < 4; c++)
        if (!node_agrees(gb, p, (size_t)py[c] * W + px[c])) {
            *e = gather(s, gb, p);
            return true;
        }
    float ax = x1 > x0 ? (float)(x - x0) / (float)(x1 - x0) : 0.f;
    float ay = y1 > y0 ? (float)(y - y0) / (float)(y1 - y0) : 0.f;
    const float w[4] = {(1 - ax) * (1 - ay), ax * (1 - ay), (1 - ax) * ay, ax * ay};
    *e = iir_v3s(0.f);
    for (int c = 0; c < 4; c++) *e = iir_madd(*e, s->node[(size_t)cj[c] * nx + ci[c]], w[c]);
    return false;
}

/* Adds rho_x / pi times the gathered light to every pixel of out; the share of pixels that
 * gathered their own light. */
static iir_status shade_lowres(rsm_state *s, const iir_gbuffer *gb, iir_image *out,
                               iir_frame_stats *stats, iir_error *err)
{
    const int W = gb->width, H = gb->height, L = s->o.lowres;
    const int nx = nodes_along(W, L), ny = nodes_along(H, L);
    if (!grow((void **)&s->node, &s->node_cap, (size_t)nx * (size_t)ny, sizeof *s->node))
        return iir_fail(err, IIR_ERR_NOMEM, "rsm: out of memory for the interpolation nodes");
    s->stopped = false;
    if (L > 1) gather_nodes(s, gb, nx, ny);
    long gathered = 0;
#pragma omp parallel for schedule(dynamic, 4) reduction(+ : gathered)
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W && !(x % 256 == 0 && row_stop(s)); x++) {
            size_t p = (size_t)y * W + x;
            if (!isfinite(gb->depth[p])) continue;
            iir_vec3 e;
            if (L == 1) {
                e = gather(s, gb, p);
                gathered++;
            } else if (x % L == 0 && y % L == 0) {
                e = s->node[(size_t)(y / L) * nx + x / L];
            } else {
                gathered += interpolate(s, gb, nx, x, y, &e);
            }
            put(out, gb, p, e);
        }
    if (s->stopped) return iir_fail(err, IIR_ERR_INTERRUPTED, "frame stopped early");
    uint64_t per_gather = (uint64_t)s->num_maps * (uint64_t)s->pattern.m;
    uint64_t nodes = L > 1 ? (uint64_t)nx * (uint64_t)ny : 0;
    stats->vpl_evals = ((uint64_t)gathered + nodes) * per_gather;
    stats->counter[RSM_RECOMPUTED] = (double)gathered / ((double)W * H);
    return IIR_OK;
}

/* ---- shading on the hierarchy (shading = multires) ---- */

/* multires.h's callback: every sample gathers from every map (no interleaving). */
static uint64_t gather_samples(void *ctx, int item, int m, uint32_t cls, iir_mr_samples *src,
                               int count, iir_vec3 *E, iir_raystats *st)
{
    (void)item, (void)m, (void)cls, (void)st;
    const rsm_state *s = ctx;
    const iir_mr_sample *smp = iir_mr_samples_read(src);
    for (int i = 0; i < count; i++) {
        E[i] = iir_v3s(0.f);
        rsm_receiver q = rsm_receiver_at(smp[i].position, smp[i].normal);
        for (uint32_t l = 0; l < s->num_maps; l++)
            E[i] = iir_add(E[i], rsm_gather_map(&s->pattern, &s->maps[l], &q));
    }
    return (uint64_t)count * s->num_maps * (uint64_t)s->pattern.m;
}

/* Adds rho_x / pi times the light gathered on the hierarchy to every pixel of out; the share of
 * pixels gathered at full resolution (at discontinuities). */
static iir_status shade_multires(rsm_state *s, const iir_gbuffer *gb, iir_image *out,
                                 iir_frame_stats *stats, iir_error *err)
{
    const int n = gb->width * gb->height;
    if (!grow((void **)&s->E, &s->E_cap, (size_t)n, sizeof *s->E))
        return iir_fail(err, IIR_ERR_NOMEM, "rsm: out of memory for the frame");
    iir_status st = iir_multires_build(s->mr, gb, s->gb_serial, &s->o.mr, 1, err);
    if (st != IIR_OK) return st;
    uint64_t evals = 0;
    if (iir_multires_shade(s->mr, gather_samples, s, 1u, s->E, s->stop, s->stop_ctx, &stats->rays,
                           &evals))
        return iir_fail(err, IIR_ERR_INTERRUPTED, "frame stopped early");
    const uint8_t *levels = iir_multires_levels(s->mr);
    long gathered = 0;
#pragma omp parallel for schedule(dynamic, 256) reduction(+ : gathered)
    for (int q = 0; q < n; q++) {
        if (!isfinite(gb->depth[q])) continue;
        if (levels[q] == 0) s->E[q] = gather(s, gb, (size_t)q), gathered++; /* glossy ones too */
        put(out, gb, (size_t)q, s->E[q]);
    }
    stats->vpl_evals = evals + (uint64_t)gathered * s->num_maps * (uint64_t)s->pattern.m;
    stats->counter[RSM_RECOMPUTED] = (double)gathered / n;
    return IIR_OK;
}

/* ---- the frame ---- */

/* The lit texels of every map, in map order, for overlays (iir_method_vpls). */
static bool collect_lit(rsm_state *s)
{
    size_t n = 0;
    for (uint32_t l = 0; l < s->num_maps; l++) n += s->maps[l].lit;
    if (!grow((void **)&s->lit, &s->lit_cap, n, sizeof *s->lit)) return false;
    s->num_lit = 0;
    for (uint32_t l = 0; l < s->num_maps; l++) {
        const rsm_map *m = &s->maps[l];
        for (int k = 0; k < m->res * m->res; k++)
            if (!m->texel[k].null_sample) {
                s->lit[s->num_lit] = m->texel[k];
                s->lit[s->num_lit++].id = (uint32_t)k * s->num_maps + l;
            }
    }
    return true;
}

static iir_status render_maps(rsm_state *s, const iir_view *view, iir_frame_stats *stats,
                              iir_error *err)
{
    const iir_stop stop = {s->stop, s->stop_ctx};
    iir_status st = rsm_maps_render(s->maps, &s->num_maps, s->o.map.res, view->lights,
                                    view->num_lights, s->scene, s->rt, "rsm", &stop, stats, err);
    if (st == IIR_OK && !collect_lit(s))
        st = iir_fail(err, IIR_ERR_NOMEM, "rsm: out of memory for the texels");
    return st;
}

static iir_status rsm_render(void *state, const iir_view *view, iir_image *out,
                             iir_frame_stats *stats, iir_error *err)
{
    rsm_state *s = state;
    iir_status st = iir_view_validate(view, err);
    if (st != IIR_OK) return st;
    double t0 = iir_now_ms();
    st = render_maps(s, view, stats, err);
    if (st != IIR_OK) return st;
    double t1 = iir_now_ms();
    iir_indirect_params ind = iir_indirect_params_default();
    ind.visibility = IIR_VIS_RAYS, ind.interleave = 1; /* no VPLs: direct light only, no filter */
    iir_render_timing rt;
    iir_render_input in = {.camera = &view->camera,
                           .lights = view->lights,
                           .num_lights = view->num_lights,
                           .seed = iir_frame_direct_seed(s->o.common.seed)};
    st = iir_renderer_frame(s->renderer, &in, &ind, out, &rt, &stats->rays, err);
    if (st != IIR_OK) return st;
    s->gb_serial += !rt.gbuffer_cached;
    double t2 = iir_now_ms();
    const iir_gbuffer *gb = iir_renderer_gbuffer(s->renderer);
    st = s->o.shading == IIR_SHADING_MULTIRES ? shade_multires(s, gb, out, stats, err)
                                              : shade_lowres(s, gb, out, stats, err);
    if (st != IIR_OK) return st;
    uint64_t evals = stats->vpl_evals;
    iir_render_timing_to_stats(&rt, stats);
    stats->vpl_evals = evals;
    stats->phase_ms[IIR_PHASE_MAPS] = t1 - t0;
    stats->phase_ms[IIR_PHASE_INDIRECT] = iir_now_ms() - t2;
    stats->total_ms = iir_now_ms() - t0;
    return IIR_OK;
}

/* ---- the method interface ---- */

static void rsm_destroy(void *state)
{
    rsm_state *s = state;
    if (!s) return;
    for (uint32_t l = 0; l < IIR_VPLSETS_MAX_LIGHTS; l++) rsm_map_free(&s->maps[l]);
    iir_renderer_destroy(s->renderer);
    rsm_pattern_free(&s->pattern);
    iir_multires_destroy(s->mr);
    free(s->E);
    free(s->node);
    free(s->lit);
    free(s);
}

static iir_status rsm_create(const iir_scene *scene, const iir_rt *rt, const void *opts,
                             const iir_stop *stop, void **state, iir_error *err)
{
    (void)stop; /* allocations only: nothing here takes long enough to poll */
    rsm_state *s = calloc(1, sizeof *s);
    if (!s) return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating rsm");
    s->scene = scene;
    s->rt = rt;
    s->o = *(const rsm_options *)opts;
    s->renderer = iir_renderer_create(scene, rt);
    if (s->renderer) iir_renderer_follow_specular(s->renderer, IIR_VPL_SPECULAR_DEPTH);
    s->mr = iir_multires_create();
    if (!s->renderer || !s->mr ||
        !rsm_pattern_build(&s->pattern, &s->o.map, iir_clamp_g_max(scene, s->o.clamp))) {
        rsm_destroy(s);
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory creating rsm");
    }
    *state = s;
    return IIR_OK;
}

static void rsm_update(void *state, const void *opts)
{
    rsm_state *s = state;
    const rsm_options *o = opts;
    if (rsm_pattern_build(&s->pattern, &o->map, iir_clamp_g_max(s->scene, o->clamp)))
        s->o = *o; /* out of memory: the old parameters stay, with their pattern */
}

static const iir_vpl *rsm_vpls(const void *state, uint32_t *n)
{
    const rsm_state *s = state;
    *n = s->num_lit;
    return s->lit;
}

static void rsm_set_stop(void *state, iir_stop_fn fn, void *ctx)
{
    rsm_state *s = state;
    s->stop = fn;
    s->stop_ctx = ctx;
    iir_renderer_set_stop(s->renderer, fn, ctx);
}

/* The renderer's G-buffer and scratch, the nodes, one light's map and its copy for overlays. */
static uint64_t rsm_memory(const void *opts, int width, int height)
{
    const rsm_options *o = opts;
    uint64_t px = (uint64_t)width * (uint64_t)height;
    uint64_t texels = (uint64_t)o->map.res * (uint64_t)o->map.res;
    return iir_renderer_memory(width, height) + px / ((uint64_t)o->lowres * o->lowres) * 12 +
           2 * texels * sizeof(iir_vpl) + (uint64_t)o->map.samples * 12;
}

/* RSM's texels come from the lights only: emitters' indirect light is left out. */
static uint32_t rsm_dropped(const iir_scene *scene, const iir_light *lights, uint32_t num_lights,
                            iir_dropped *out, uint32_t max)
{
    return rsm_maps_dropped("rsm", scene, lights, num_lights, out, max);
}

const iir_method_ops iir_method_rsm = {
    .name = "rsm",
    .summary = "reflective shadow maps: one-bounce light gathered from each light's view, no "
               "indirect visibility",
    .tables = {{&iir_rsm_table, offsetof(rsm_options, map)},
               {&LOWRES_TABLE, 0},
               {&iir_shading_table, offsetof(rsm_options, shading)},
               {&iir_multires_table, offsetof(rsm_options, mr)},
               {&iir_clamp_table, offsetof(rsm_options, clamp)},
               {&iir_common_table, offsetof(rsm_options, common)}},
    .opts_size = sizeof(rsm_options),
    .create = rsm_create,
    .destroy = rsm_destroy,
    .render = rsm_render,
    .vpls = rsm_vpls,
    .set_stop = rsm_set_stop,
    .update = rsm_update,
    .memory = rsm_memory,
    .dropped = rsm_dropped,
    .full_surfaces = true,
    .phases = {IIR_PHASE_MAPS, IIR_PHASE_GBUFFER, IIR_PHASE_DIRECT, IIR_PHASE_INDIRECT,
               IIR_PHASE_COUNT},
    .counters = RSM_COUNTERS,
};

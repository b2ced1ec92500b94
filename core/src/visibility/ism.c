/* ism.c -- imperfect shadow maps (ism.h): the scene's area-uniform point set, splatting a VPL's
 * subset of it into a paraboloid depth map, pull-push hole filling (pullpush.c) and building the
 * maps of a VPL set. Not the maps' lookups (shadowmap.h) nor which VPLs get maps (the methods).
 *
 * Threads: iir_ism_build_until runs an OpenMP loop over VPLs; each thread allocates its pull-push
 * scratch once per call, and each iteration writes only its own VPL's map. The point set is
 * read-only while maps are built. */
#include "iir/ism.h"
#include "surface.h"

#include <assert.h>
#include <stdlib.h>

#include "iir/pullpush.h"
#include "iir/rng.h"
#include "iir/scene.h"
#include "iir/shadowmap.h"
#include "sampling.h"

/* ======================== the point set ======================== */

static iir_vec3 sample_position(const iir_scene *scene, iir_ism_sample s)
{
    const uint32_t *tri = &scene->indices[3 * (size_t)s.tri];
    iir_vec3 v0 = scene->positions[tri[0]], v1 = scene->positions[tri[1]];
    iir_vec3 v2 = scene->positions[tri[2]];
    float b0 = 1.f - s.b1 - s.b2;
    return iir_add(iir_add(iir_scale(v0, b0), iir_scale(v1, s.b1)), iir_scale(v2, s.b2));
}

void iir_ism_points_update(iir_ism_points *pts, const iir_scene *scene)
{
    for (uint32_t k = 0; k < pts->n; k++) pts->p[k] = sample_position(scene, pts->sample[k]);
}

void iir_ism_points_destroy(iir_ism_points *pts)
{
    if (!pts) return;
    free(pts->sample);
    free(pts->p);
    free(pts);
}

/* Sample k of n: the triangle *t whose CDF interval [cdf[t], cdf[t + 1]) holds the stratified
 * u = (k + xi) / n of the total area (cdf[t] = area of the triangles before t; u, hence *t, only
 * grows with k), then a uniform point on it. */
static iir_ism_sample stratified_sample(const double *cdf, uint32_t num_tris, uint32_t *t,
                                        uint32_t k, uint32_t n, iir_rng *rng)
{
    double u = ((double)k + (double)iir_rng_uniform(rng)) / (double)n * cdf[num_tris];
    while (*t + 1 < num_tris && cdf[*t + 1] <= u) (*t)++; /* passes zero-area triangles */
    iir_vec2 b = iir_sample_uniform_triangle(iir_rng_uniform2(rng));
    return (iir_ism_sample){*t, b.y, 1.f - b.x - b.y};
}

/* Fisher-Yates with rng: every order equally likely. */
static void shuffle(iir_ism_sample *s, uint32_t n, iir_rng *rng)
{
    for (uint32_t i = n; i > 1; i--) {
        uint32_t j = (uint32_t)(((uint64_t)iir_rng_u32(rng) * i) >> 32);
        iir_ism_sample tmp = s[i - 1];
        s[i - 1] = s[j];
        s[j] = tmp;
    }
}

iir_status iir_ism_points_create(const iir_scene *scene, uint32_t n, uint64_t seed,
                                 iir_ism_points **out, iir_error *err)
{
    *out = NULL;
    uint32_t nt = scene->num_triangles;
    double *cdf = malloc(sizeof(double) * ((size_t)nt + 1));
    iir_ism_points *pts = calloc(1, sizeof *pts);
    if (pts) pts->sample = malloc(sizeof(iir_ism_sample) * (size_t)n);
    if (pts) pts->p = malloc(sizeof(iir_vec3) * (size_t)n);
    if (!cdf || !pts || !pts->sample || !pts->p) {
        free(cdf), iir_ism_points_destroy(pts);
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for %u ISM points", n);
    }
    cdf[0] = 0.0;
    for (uint32_t t = 0; t < nt; t++) cdf[t + 1] = cdf[t] + (double)scene->areas[t];
    if (!(cdf[nt] > 0.0)) {
        free(cdf), iir_ism_points_destroy(pts);
        return iir_fail(err, IIR_ERR_INVALID, "ISM points: the scene has no surface area");
    }
    iir_rng rng = iir_rng_make(seed, 0x15a9);
    uint32_t t = 0;
    uint32_t kept = 0;
    bool cutouts = scene->materials && iir_scene_has_cutouts(scene);
    for (uint32_t k = 0; k < n; k++) {
        iir_ism_sample smp = stratified_sample(cdf, nt, &t, k, n, &rng);
        /* no points on a cut-out's holes (the last one stays, so a set is never empty) */
        if (!cutouts || iir_surface_covers(scene, smp.tri, smp.b1, smp.b2) ||
            (kept == 0 && k + 1 == n))
            pts->sample[kept++] = smp;
    }
    free(cdf);
    shuffle(pts->sample, kept, &rng);
    pts->n = kept;
    iir_ism_points_update(pts, scene);
    *out = pts;
    return IIR_OK;
}

/* ======================== one map ======================== */

size_t iir_ism_scratch_floats(int res)
{
    return (size_t)res * (size_t)res + iir_pullpush_scratch_floats(res, res);
}

/* The texel holding local direction w (w.z > 0, |w| = len) at resolution res: iir_paraboloid_uv
 * of w / len, u = (x / (1 + z) + 1) / 2 = (w.x / (len + w.z) + 1) / 2, scaled to texels. */
static size_t texel_of(iir_vec3 w, float len, int res)
{
    float k = 0.5f * (float)res / (len + w.z), c = 0.5f * (float)res;
    int i = (int)(w.x * k + c), j = (int)(w.y * k + c);
    i = i < 0 ? 0 : (i < res ? i : res - 1);
    j = j < 0 ? 0 : (j < res ? j : res - 1);
    return (size_t)j * (size_t)res + (size_t)i;
}

uint32_t iir_ism_splat(float *depth, const iir_ism_points *pts, const iir_vpl *v,
                       const iir_ism_params *p, float eps)
{
    iir_vec3 o = iir_madd(v->position, v->frame.f, eps);
    uint32_t m = p->points_per_vpl < pts->n ? p->points_per_vpl : pts->n;
    uint32_t start = (uint32_t)(iir_hash3(p->key, v->id, 0x5b1a7) % pts->n);
    uint32_t splatted = 0;
    for (uint32_t k = 0, idx = start; k < m; k++, idx = idx + 1 < pts->n ? idx + 1 : 0) {
        iir_vec3 d = iir_sub(pts->p[idx], o);
        iir_vec3 w = iir_v3(iir_dot(d, v->frame.r), iir_dot(d, v->frame.u), iir_dot(d, v->frame.f));
        if (!(w.z > 0.f)) continue;
        float len = iir_length(w);
        float *z = &depth[texel_of(w, len, p->res)];
        if (len < *z) *z = len;
        splatted++;
    }
    return splatted;
}

bool iir_ism_render(iir_smap *m, const iir_ism_points *pts, const iir_vpl *v,
                    const iir_ism_params *p, float eps, float *scratch)
{
    assert(p->res >= 1 && p->res <= IIR_SMAP_MAX_RES && "iir_ism_render: resolution out of range");
    size_t texels = (size_t)p->res * (size_t)p->res;
    if (!m->depth || m->res != p->res) {
        iir_smap_release(m);
        m->depth = malloc(sizeof *m->depth * texels);
        if (!m->depth) return false;
    }
    float *depth = scratch; /* the map in floats, then pull-push's levels */
    for (size_t k = 0; k < texels; k++) depth[k] = INFINITY;
    iir_ism_splat(depth, pts, v, p, eps);
    iir_pullpush(depth, p->res, p->res, scratch + texels);
    m->scale = iir_smap_scale(eps);
    for (size_t k = 0; k < texels; k++) m->depth[k] = iir_half_from_float(depth[k] / m->scale);
    m->res = p->res;
    m->stamp = iir_smap_next_stamp();
    return true;
}

/* ======================== a VPL set ======================== */

uint32_t iir_ism_build_until(iir_vpl *vpls, uint32_t n, const iir_ism_points *pts,
                             const iir_ism_params *p, float eps, iir_stop_fn stop, void *ctx)
{
    uint32_t built = 0;
    size_t scratch_floats = iir_ism_scratch_floats(p->res);
#pragma omp parallel reduction(+ : built)
    {
        float *scratch = malloc(sizeof(float) * (scratch_floats ? scratch_floats : 1));
#pragma omp for schedule(dynamic, 8)
        for (int64_t i = 0; i < (int64_t)n; i++) {
            iir_vpl *v = &vpls[i];
            if (!scratch || v->null_sample || v->smap.res == p->res || (stop && stop(ctx)))
                continue;
            built += iir_ism_render(&v->smap, pts, v, p, eps, scratch);
        }
        free(scratch);
    }
    return built;
}

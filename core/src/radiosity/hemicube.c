/* hemicube.c -- form factors by the hemicube (Cohen & Greenberg 1985): per patch, rays from its
 * centre through the centres of a hemicube's cells (the depth test is Embree's nearest hit), each
 * cell's delta form factor added to the patch it sees. Sparse rows (CSR). Not the cache, not the
 * solvers.
 *
 * Threads: OpenMP over patches; each thread owns a dense accumulator of n floats and a list of
 * the patches it touched, allocated once per thread, so the per-cell loop allocates nothing. Rows
 * are gathered into the CSR arrays after the parallel loop, in patch order (deterministic). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "iir/rng.h"
#include "radiosity.h"

/* ---- the hemicube's cells ----
 * Top face z = 1, (x, y) in [-1, 1]^2, res x res cells of area dA = (2 / res)^2:
 *     dF = dA / (pi (x^2 + y^2 + 1)^2).
 * Side faces (x = +-1 or y = +-1), res x res / 2 cells with z in [0, 1]; on x = 1:
 *     dF = z dA / (pi (y^2 + z^2 + 1)^2).
 * The sum is 1 up to the discretisation; it is normalised to exactly 1. */

uint32_t rad_hemicube_cells(int res, float *dF, iir_vec3 *dir)
{
    const float h = 2.f / (float)res, dA = h * h;
    uint32_t c = 0;
    double sum = 0;
    for (int b = 0; b < res; b++)
        for (int a = 0; a < res; a++, c++) {
            float x = -1.f + h * ((float)a + .5f), y = -1.f + h * ((float)b + .5f);
            if (dF) dF[c] = dA / ((float)M_PI * iir_sqr(x * x + y * y + 1.f)), sum += dF[c];
            if (dir) dir[c] = iir_v3(x, y, 1.f);
        }
    for (int face = 0; face < 4; face++)
        for (int b = 0; b < res / 2; b++)
            for (int a = 0; a < res; a++, c++) {
                float s = -1.f + h * ((float)a + .5f), z = h * ((float)b + .5f);
                if (dF) dF[c] = z * dA / ((float)M_PI * iir_sqr(s * s + z * z + 1.f)), sum += dF[c];
                if (!dir) continue;
                const iir_vec3 d[4] = {iir_v3(1.f, s, z), iir_v3(-1.f, -s, z), iir_v3(-s, 1.f, z),
                                       iir_v3(s, -1.f, z)};
                dir[c] = d[face];
            }
    if (dF)
        for (uint32_t k = 0; k < c; k++) dF[k] = (float)(dF[k] / sum);
    return c;
}

/* ---- one patch's row ---- */

typedef struct row_scratch {
    float *acc;        /* n, zero between rows */
    uint32_t *touched; /* patches with acc != 0 */
    uint32_t count;
} row_scratch;

typedef struct hemicube {
    uint32_t cells;
    float *dF;
    iir_vec3 *dir;
} hemicube;

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* Cells between two looks at the stop hook: 4096 rays, well under a millisecond. */
enum { STOP_CELLS = 4096 };

/* Casts patch i's hemicube rays and accumulates their delta form factors in sc; false (sc partly
 * filled) once stop says stop. */
static bool trace_row(const rad_mesh *m, const iir_scene *scene, const iir_rt *rt,
                      const hemicube *hc, uint32_t i, row_scratch *sc, iir_raystats *st,
                      const iir_stop *stop)
{
    const iir_frame fr = iir_frame_from_normal(m->normal[i]);
    const iir_vec3 o = iir_madd(m->centre[i], m->normal[i], iir_rt_epsilon(rt));
    for (uint32_t c0 = 0; c0 < hc->cells; c0 += 8) {
        if (c0 % STOP_CELLS == 0 && iir_stop_now(stop)) return false;
        iir_ray8 r;
        iir_vec3 d[8];
        for (int l = 0; l < 8; l++) {
            uint32_t c = c0 + (uint32_t)l;
            r.valid[l] = c < hc->cells ? -1 : 0;
            d[l] = iir_frame_to_world(&fr, hc->dir[c < hc->cells ? c : 0]);
            r.ox[l] = o.x, r.oy[l] = o.y, r.oz[l] = o.z;
            r.dx[l] = d[l].x, r.dy[l] = d[l].y, r.dz[l] = d[l].z;
            r.tnear[l] = 0.f, r.tfar[l] = INFINITY;
        }
        iir_hit hit[8];
        iir_rt_intersect8(rt, &r, hit, st, IIR_RAYS_BENCH);
        for (int l = 0; l < 8; l++) {
            if (!r.valid[l] || hit[l].prim == IIR_NO_HIT) continue;
            if (iir_dot(d[l], scene->normals[hit[l].prim]) >= 0.f) continue; /* its back */
            uint32_t j = rad_patch_of(m, hit[l].prim, hit[l].u, hit[l].v);
            if (sc->acc[j] == 0.f) sc->touched[sc->count++] = j;
            sc->acc[j] += hc->dF[c0 + (uint32_t)l];
        }
    }
    return true;
}

/* Moves sc's row into freshly allocated col / val (sorted by column), clearing sc. */
static bool take_row(row_scratch *sc, uint32_t **col, float **val, uint32_t *len)
{
    qsort(sc->touched, sc->count, sizeof *sc->touched, cmp_u32);
    *len = sc->count;
    *col = malloc((sc->count ? sc->count : 1) * sizeof **col);
    *val = malloc((sc->count ? sc->count : 1) * sizeof **val);
    bool ok = *col && *val;
    for (uint32_t k = 0; k < sc->count; k++) {
        if (ok) (*col)[k] = sc->touched[k], (*val)[k] = sc->acc[sc->touched[k]];
        sc->acc[sc->touched[k]] = 0.f;
    }
    sc->count = 0;
    return ok;
}

/* ---- a sampled row, for estimates ---- */

uint32_t rad_ff_sample_row(const rad_mesh *m, const iir_scene *scene, const iir_rt *rt,
                           const iir_vec3 *dir, uint32_t cells, uint32_t max_cells, iir_vec3 centre,
                           iir_vec3 normal, uint64_t seed, uint32_t *hits, uint32_t *touched)
{
    const iir_frame fr = iir_frame_from_normal(normal);
    const iir_vec3 o = iir_madd(centre, normal, iir_rt_epsilon(rt));
    const uint32_t traced = cells < max_cells ? cells : max_cells;
    uint32_t count = 0;
    iir_raystats st = {0};
    for (uint32_t k = 0; k < traced; k++) {
        /* every cell, or a uniform choice of them (with repetition: Chao's estimator's model) */
        uint32_t c = traced == cells ? k : (uint32_t)(iir_hash3(seed, k, 1) % cells);
        iir_vec3 d = iir_frame_to_world(&fr, dir[c]);
        iir_ray r = iir_make_ray(o, d, 0.f, INFINITY);
        iir_hit hit;
        if (!iir_rt_intersect(rt, &r, &hit, &st, IIR_RAYS_BENCH) || hit.prim == IIR_NO_HIT)
            continue;
        if (iir_dot(d, scene->normals[hit.prim]) >= 0.f) continue; /* its back */
        uint32_t j = rad_patch_of(m, hit.prim, hit.u, hit.v);
        if (hits[j]++ == 0) touched[count++] = j;
    }
    return count;
}

/* ---- all rows ---- */

static bool gather_csr(rad_ff *ff, uint32_t n, uint32_t **cols, float **vals, const uint32_t *len)
{
    ff->n = n;
    ff->row = malloc(((size_t)n + 1) * sizeof *ff->row);
    if (!ff->row) return false;
    ff->row[0] = 0;
    for (uint32_t i = 0; i < n; i++) ff->row[i + 1] = ff->row[i] + len[i];
    ff->nnz = ff->row[n];
    ff->col = malloc((ff->nnz ? ff->nnz : 1) * sizeof *ff->col);
    ff->val = malloc((ff->nnz ? ff->nnz : 1) * sizeof *ff->val);
    if (!ff->col || !ff->val) return false;
    for (uint32_t i = 0; i < n; i++) {
        memcpy(ff->col + ff->row[i], cols[i], len[i] * sizeof *ff->col);
        memcpy(ff->val + ff->row[i], vals[i], len[i] * sizeof *ff->val);
    }
    return true;
}

iir_status rad_ff_compute(rad_ff *ff, const rad_mesh *m, const iir_scene *scene, const iir_rt *rt,
                          int res, const iir_stop *stop, rad_progress_fn progress, void *ctx,
                          iir_error *err)
{
    memset(ff, 0, sizeof *ff);
    const uint32_t n = m->num_patches;
    hemicube hc = {rad_hemicube_cells(res, NULL, NULL), NULL, NULL};
    hc.dF = malloc(hc.cells * sizeof *hc.dF), hc.dir = malloc(hc.cells * sizeof *hc.dir);
    uint32_t **cols = calloc(n ? n : 1, sizeof *cols), *len = calloc(n ? n : 1, sizeof *len);
    float **vals = calloc(n ? n : 1, sizeof *vals);
    bool ok = hc.dF && hc.dir && cols && vals && len;
    if (ok) rad_hemicube_cells(res, hc.dF, hc.dir);
    const bool ready = ok;
    uint32_t done = 0;
    bool stopped = false;
#pragma omp parallel
    {
        row_scratch sc = {calloc(n ? n : 1, sizeof(float)), malloc((n ? n : 1) * sizeof(uint32_t)),
                          0};
        iir_raystats st = {0};
        bool mine = ready && sc.acc && sc.touched;
        if (!mine) {
#pragma omp atomic write
            ok = false;
        }
#pragma omp for schedule(dynamic, 4)
        for (uint32_t i = 0; i < n; i++) {
            bool quit;
#pragma omp atomic read
            quit = stopped;
            if (!mine || quit) continue;
            if (!trace_row(m, scene, rt, &hc, i, &sc, &st, stop)) {
#pragma omp atomic write
                stopped = true;
            }
            if (!take_row(&sc, &cols[i], &vals[i], &len[i])) {
#pragma omp atomic write
                ok = false;
            }
            uint32_t now;
#pragma omp atomic capture
            now = ++done;
            if (progress && (uint64_t)now * 10 / n != (uint64_t)(now - 1) * 10 / n)
                progress(ctx, now, n);
        }
        free(sc.acc), free(sc.touched);
    }
    ok = ok && !stopped && gather_csr(ff, n, cols, vals, len);
    for (uint32_t i = 0; cols && vals && i < n; i++) free(cols[i]), free(vals[i]);
    free(cols), free(vals), free(len), free(hc.dF), free(hc.dir);
    if (stopped) {
        rad_ff_free(ff);
        return iir_fail(err, IIR_ERR_INTERRUPTED, "radiosity: form factors stopped");
    }
    if (!ok) {
        rad_ff_free(ff);
        return iir_fail(err, IIR_ERR_NOMEM, "radiosity: out of memory for the form factors");
    }
    return IIR_OK;
}

void rad_ff_free(rad_ff *ff)
{
    free(ff->row), free(ff->col), free(ff->val);
    memset(ff, 0, sizeof *ff);
}

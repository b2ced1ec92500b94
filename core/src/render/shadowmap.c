/* shadowmap.c -- rendering VPL paraboloid shadow maps with Embree packets, one map or a whole VPL
 * set in parallel; not lookups (inline in shadowmap.h) and not the maps' lifetime (vpl.h).
 *
 * Threads: iir_smaps_build runs an OpenMP loop over VPLs; each iteration writes only its own
 * VPL's map, and ray counters are per thread, summed once after the loop. */
#include "iir/shadowmap.h"

#include <assert.h>
#include <stdlib.h>

#include "iir/isa.h"

/* Local direction of the centre of texel (i, j); corners outside the parametrisation's unit disk
 * go to the horizon direction of their angle. */
static iir_vec3 texel_dir(int i, int j, int res)
{
    float x = 2.f * ((float)i + 0.5f) / (float)res - 1.f;
    float y = 2.f * ((float)j + 0.5f) / (float)res - 1.f;
    float r2 = x * x + y * y;
    if (r2 > 1.f) {
        float k = 1.f / sqrtf(r2);
        return iir_v3(x * k, y * k, 0.f);
    }
    return iir_paraboloid_dir(iir_v2(0.5f * (x + 1.f), 0.5f * (y + 1.f)));
}

/* Texels i0 .. i0+7 of row j (those < res) seen from org in frame fr as packet rays (the scalar
 * iir_smap_texel_rays_avx2). */
static void texel_rays(const iir_frame *fr, iir_vec3 org, int i0, int j, int res, iir_ray8 *rays)
{
    for (int k = 0; k < 8; k++) {
        int i = i0 + k < res ? i0 + k : res - 1;
        iir_vec3 d = iir_frame_to_world(fr, texel_dir(i, j, res));
        rays->ox[k] = org.x, rays->oy[k] = org.y, rays->oz[k] = org.z;
        rays->dx[k] = d.x, rays->dy[k] = d.y, rays->dz[k] = d.z;
        rays->tnear[k] = 0.f;
        rays->tfar[k] = INFINITY;
        rays->valid[k] = i0 + k < res;
    }
}

/* Traces texels i0 .. i0+15 of row j (those < res) as one packet of 16 (Embree's 16-wide
 * traversal where the CPU has it), storing each distance times inv_scale as a half float; avx2:
 * the rays 8 at a time (iir_smap_texel_rays_avx2). */
static void trace_run(const iir_rt *rt, const iir_vpl *v, iir_vec3 org, int i0, int j, int res,
                      float inv_scale, uint16_t *row, bool avx2, iir_raystats *st)
{
    iir_ray8 rays[2];
    for (int h = 0; h < 2; h++) {
#if defined(__x86_64__)
        if (avx2) {
            iir_smap_texel_rays_avx2(&v->frame, org, i0 + 8 * h, j, res, &rays[h]);
            continue;
        }
#endif
        texel_rays(&v->frame, org, i0 + 8 * h, j, res, &rays[h]);
    }
    iir_hit hits[16];
    iir_rt_intersect16(rt, rays, hits, st, IIR_RAYS_SHADOWMAP);
    for (int k = 0; k < 16 && i0 + k < res; k++)
        row[i0 + k] = iir_half_from_float(hits[k].t * inv_scale);
}

uint64_t iir_smap_next_stamp(void)
{
    static _Atomic uint64_t next = 1;
    return next++;
}

bool iir_smap_render(iir_smap *m, const iir_rt *rt, const iir_vpl *v, int res, iir_raystats *st)
{
    assert(res >= 1 && res <= IIR_SMAP_MAX_RES && "iir_smap_render: resolution out of range");
    if (!m->depth || m->res != res) {
        iir_smap_release(m);
        m->depth = malloc(sizeof *m->depth * (size_t)res * (size_t)res);
        if (!m->depth) return false;
    }
    m->scale = iir_smap_scale(iir_rt_epsilon(rt));
    iir_vec3 org = iir_madd(v->position, v->frame.f, iir_rt_epsilon(rt));
    bool avx2 = iir_isa_default() >= IIR_ISA_AVX2;
    for (int j = 0; j < res; j++)
        for (int i0 = 0; i0 < res; i0 += 16)
            trace_run(rt, v, org, i0, j, res, 1.f / m->scale, m->depth + (size_t)j * (size_t)res,
                      avx2, st);
    m->res = res;
    m->coarse = false;
    m->stamp = iir_smap_next_stamp();
    return true;
}

uint32_t iir_smaps_build(iir_vpl *vpls, uint32_t n, const iir_rt *rt, int res, iir_raystats *st)
{
    return iir_smaps_build_until(vpls, n, rt, res, st, NULL, NULL);
}

/* The maps of the non-null VPLs that need one: any map of another resolution than res, or (keep)
 * only those with none. */
static uint32_t build(iir_vpl *vpls, uint32_t n, const iir_rt *rt, int res, bool keep,
                      iir_raystats *st, iir_stop_fn stop, void *ctx)
{
    uint32_t built = 0;
    iir_raystats total = {0};
#pragma omp parallel reduction(+ : built)
    {
        iir_raystats local = {0};
#pragma omp for schedule(dynamic, 1)
        for (int64_t i = 0; i < (int64_t)n; i++) {
            iir_vpl *v = &vpls[i];
            bool has = keep ? v->smap.res != 0 : v->smap.res == res;
            if (v->null_sample || has || (stop && stop(ctx))) continue;
            built += iir_smap_render(&v->smap, rt, v, res, &local);
        }
#pragma omp critical(iir_smap_rays)
        iir_raystats_add(&total, &local);
    }
    if (st) iir_raystats_add(st, &total);
    return built;
}

uint32_t iir_smaps_build_until(iir_vpl *vpls, uint32_t n, const iir_rt *rt, int res,
                               iir_raystats *st, iir_stop_fn stop, void *ctx)
{
    return build(vpls, n, rt, res, false, st, stop, ctx);
}

/* Whether v lacks a map (pass 0) or holds a coarse one below res (pass 1). */
static bool wants(const iir_vpl *v, int res, int pass)
{
    if (v->null_sample) return false;
    return pass == 0 ? v->smap.res == 0 : v->smap.coarse && v->smap.res < res;
}

/* The index before which the first `budget` VPLs that pass wants lie (n when fewer do); *used
 * gets how many that is. */
static uint32_t cut(const iir_vpl *vpls, uint32_t n, int res, int pass, uint32_t budget,
                    uint32_t *used)
{
    *used = 0;
    for (uint32_t i = 0; i < n; i++)
        if (wants(&vpls[i], res, pass) && (*used)++ == budget) {
            *used = budget;
            return i;
        }
    return n;
}

uint32_t iir_smaps_build_budget(iir_vpl *vpls, uint32_t n, const iir_rt *rt, int res, uint32_t full,
                                iir_raystats *st, iir_stop_fn stop, void *ctx)
{
    /* in array order (deterministic): the first `full` missing maps at res, the other missing ones
       coarse, and as many of the coarse ones already there as the budget has left at res */
    uint32_t used[2];
    uint32_t cuts[2] = {cut(vpls, n, res, 0, full, &used[0]), 0};
    cuts[1] = cut(vpls, n, res, 1, full - used[0], &used[1]);
    int coarse_res = res / 4 > 8 ? res / 4 : res < 8 ? res : 8;
    uint32_t built = 0;
    iir_raystats total = {0};
    for (int pass = 1; pass >= 0; pass--) { /* upgrades first: pass 0 makes new coarse maps */
#pragma omp parallel reduction(+ : built)
        {
            iir_raystats local = {0};
#pragma omp for schedule(dynamic, 1)
            for (int64_t i = 0; i < (int64_t)n; i++) {
                iir_vpl *v = &vpls[i];
                bool at_res = (uint32_t)i < cuts[pass];
                if (!wants(v, res, pass) || (pass == 1 && !at_res) || (stop && stop(ctx))) continue;
                if (!iir_smap_render(&v->smap, rt, v, at_res ? res : coarse_res, &local)) continue;
                v->smap.coarse = !at_res;
                built++;
            }
#pragma omp critical(iir_smap_rays)
            iir_raystats_add(&total, &local);
        }
    }
    if (st) iir_raystats_add(st, &total);
    return built;
}

uint32_t iir_smaps_build_missing(iir_vpl *vpls, uint32_t n, const iir_rt *rt, int res,
                                 iir_raystats *st, iir_stop_fn stop, void *ctx)
{
    return build(vpls, n, rt, res, true, st, stop, ctx);
}

/* raybench.c -- the raw ray-rate micro-benchmark: generating random incoherent rays and timing
 * Embree on them with no shading. Not the renderer's own throughput (that is in the stats). */
#include "iir/raybench.h"

#include <omp.h>
#include <stdlib.h>

#include "iir/rng.h"
#include "sampling.h"
#include "iir/timer.h"

static float *area_cdf(const iir_scene *s)
{
    float *cdf = malloc(sizeof(float) * (s->num_triangles + 1));
    if (!cdf) return NULL;
    double total = 0.0;
    cdf[0] = 0.f;
    for (uint32_t t = 0; t < s->num_triangles; t++) {
        total += s->areas[t];
        cdf[t + 1] = (float)total;
    }
    for (uint32_t t = 1; t <= s->num_triangles; t++) cdf[t] = (float)(cdf[t] / total);
    return cdf;
}

static uint32_t pick(const float *cdf, uint32_t n, float u)
{
    uint32_t lo = 0, hi = n;
    while (hi - lo > 1) {
        uint32_t mid = (lo + hi) / 2;
        if (cdf[mid] <= u)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

static iir_ray random_ray(const iir_scene *s, const float *cdf, float eps, iir_rng *rng)
{
    uint32_t t = pick(cdf, s->num_triangles, iir_rng_uniform(rng));
    const uint32_t *ix = &s->indices[3 * t];
    iir_vec2 b = iir_sample_uniform_triangle(iir_rng_uniform2(rng));
    iir_vec3 p =
        iir_add(iir_add(iir_scale(s->positions[ix[0]], b.x), iir_scale(s->positions[ix[1]], b.y)),
                iir_scale(s->positions[ix[2]], 1.f - b.x - b.y));
    iir_vec3 d = iir_sample_uniform_sphere(iir_rng_uniform2(rng));
    iir_vec3 n = s->normals[t];
    p = iir_madd(p, n, iir_dot(n, d) >= 0.f ? eps : -eps);
    return iir_make_ray(p, d, 0.f, INFINITY);
}

static double trace_all(const iir_rt *rt, const iir_ray *rays, uint64_t n, bool occlusion,
                        uint64_t *hits)
{
    uint64_t h = 0;
    double t0 = iir_now_ms();
#pragma omp parallel for schedule(static, 4096) reduction(+ : h)
    for (uint64_t i = 0; i < n; i++) {
        iir_hit hit;
        h += occlusion ? iir_rt_occluded(rt, &rays[i], NULL, IIR_RAYS_BENCH)
                       : iir_rt_intersect(rt, &rays[i], &hit, NULL, IIR_RAYS_BENCH);
    }
    *hits = h;
    return iir_now_ms() - t0;
}

iir_status iir_raybench_run(const iir_scene *s, const iir_rt *rt, uint64_t n, uint64_t seed,
                            iir_raybench_result *out, iir_error *err)
{
    if (n == 0 || n > (1ull << 28))
        return iir_fail(err, IIR_ERR_INVALID, "raybench: ray count %llu is outside [1, 2^28]",
                        (unsigned long long)n);
    float *cdf = area_cdf(s);
    iir_ray *rays = malloc(sizeof(iir_ray) * n);
    if (!cdf || !rays) {
        free(cdf);
        free(rays);
        return iir_fail(err, IIR_ERR_NOMEM, "raybench: out of memory for %llu rays",
                        (unsigned long long)n);
    }
#pragma omp parallel for schedule(static)
    for (uint64_t i = 0; i < n; i++) {
        iir_rng rng = iir_rng_make(seed, i);
        rays[i] = random_ray(s, cdf, iir_rt_epsilon(rt), &rng);
    }
    uint64_t hits, occl;
    out->rays = n;
    out->closest_ms = trace_all(rt, rays, n, false, &hits);
    out->occluded_ms = trace_all(rt, rays, n, true, &occl);
    out->closest_per_s = (double)n / (out->closest_ms * 1e-3);
    out->occluded_per_s = (double)n / (out->occluded_ms * 1e-3);
    out->hit_fraction = (double)hits / (double)n;
    out->threads = omp_get_max_threads();
    free(cdf);
    free(rays);
    return IIR_OK;
}

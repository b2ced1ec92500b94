/* render_direct_avx2.c -- direct light's lean block with AVX2 (render_internal.h:
 * iir_direct_lean_block_avx2): the common frame's two 4x4 blocks side by side -- points, spots and
 * suns alone, no specular chain -- as four halves of 8 lanes held in registers from the G-buffer's
 * rows to the frame's, each light's 32 samples in one call (iir_light_sample_delta32_avx2) and
 * each block's 16 shadow rays in one packet. Its sums are render_direct.c's shade_block's,
 * product for product and in the same order (this file is built with -mavx2 alone: no FMA), so the
 * frame is the same bit for bit. Called only where the CPU has AVX2. */
#include "render_internal.h"

#if defined(__x86_64__)
#include <immintrin.h>
#include <string.h>

#include "iir/bsdf.h"
#include "render_lanes_avx2.h"

enum { HALF_W = 4, HALF_H = 2 }; /* a half's pixels: lane r * HALF_W + j is (x0 + j, y0 + r) */
enum { NH = 4 };                 /* halves a call shades: two 4x4 blocks side by side */

/* The 8 lanes of a half of a lean block. */
typedef struct lean_half {
    int x0, y0;
    bool whole; /* every pixel inside the image */
    size_t row[HALF_H];
    v3 p, n, L;          /* receivers; radiance so far (from the emission) */
    __m256 hit;          /* lane masks: geometry */
    bool loaded;         /* the materials below are read */
    __m256 shaded;       /* geometry that reflects: non-zero albedo, or glossy */
    v3 f;                /* a Lambertian lane's BRDF rho / pi (0 where not shaded) */
    bool any_glossy;     /* a metallic-roughness lane: its f is its BSDF's, per light */
    __m256 glossy;       /* which */
    iir_bsdf_lanes bsdf; /* the glossy lanes' BSDFs */
    v3 pending;          /* a light's contribution, kept where its ray is unoccluded */
} lean_half;

/* half_vec3 at a half reaching past the image's edge. */
static __attribute__((noinline)) v3 edge_vec3(const lean_half *q, const iir_gbuffer *gb,
                                              const iir_vec3 *a)
{
    _Alignas(32) float x[8], y[8], z[8];
    for (int k = 0; k < 8; k++) {
        int px = q->x0 + k % HALF_W, py = q->y0 + k / HALF_W;
        bool in = px < gb->width && py < gb->height;
        iir_vec3 v = in ? a[(size_t)py * (size_t)gb->width + (size_t)px] : iir_v3s(0.f);
        x[k] = v.x, y[k] = v.y, z[k] = v.z;
    }
    return load_planes(x, y, z);
}

/* Array a's values at the half's pixels (0 outside the image). */
static inline v3 half_vec3(const lean_half *q, const iir_gbuffer *gb, const iir_vec3 *a)
{
    return q->whole ? load_aos(a + q->row[0], a + q->row[1]) : edge_vec3(q, gb, a);
}

/* Lanes whose pixel is geometry. */
static __m256 half_hit(const lean_half *q, const iir_gbuffer *gb)
{
    if (q->whole) { /* two rows of 4 as one vector (no store to forward from) */
        __m128i a = _mm_loadu_si128((const __m128i *)(gb->prim + q->row[0]));
        __m128i b = _mm_loadu_si128((const __m128i *)(gb->prim + q->row[1]));
        return hit_mask(_mm256_set_m128i(b, a));
    }
    uint32_t prim[8];
    for (int k = 0; k < 8; k++) {
        int px = q->x0 + k % HALF_W, py = q->y0 + k / HALF_W;
        bool in = px < gb->width && py < gb->height;
        prim[k] = in ? gb->prim[(size_t)py * (size_t)gb->width + (size_t)px] : IIR_NO_HIT;
    }
    return hit_lanes(prim);
}

/* The half's place and which of its pixels are geometry. */
static void half_at(lean_half *q, const iir_gbuffer *gb, int x0, int y0)
{
    q->x0 = x0, q->y0 = y0, q->loaded = false;
    q->whole = x0 + HALF_W <= gb->width && y0 + HALF_H <= gb->height;
    for (int r = 0; r < HALF_H; r++) q->row[r] = (size_t)(y0 + r) * (size_t)gb->width + (size_t)x0;
    q->hit = half_hit(q, gb);
}

/* The half's surfaces: receivers, emission. */
static void half_surface(lean_half *q, const iir_gbuffer *gb)
{
    q->p = half_vec3(q, gb, gb->position);
    q->n = half_vec3(q, gb, gb->normal);
    q->L = gb->any_emission ? half_vec3(q, gb, gb->emission) : (v3){zero(), zero(), zero()};
}

/* The glossy lanes' BSDFs (metallic-roughness pixels), lane by lane. */
static void half_glossy(lean_half *q, const iir_gbuffer *gb)
{
    _Alignas(32) int32_t glossy[8] = {0};
    int hit = _mm256_movemask_ps(q->hit);
    memset(&q->bsdf, 0, sizeof q->bsdf);
    for (int k = 0; k < 8; k++) {
        if (!(hit >> k & 1)) continue;
        size_t i = q->row[k / HALF_W] + (size_t)(k % HALF_W);
        iir_vec3 m = gb->mr[i];
        if (!(m.y >= 0.f)) continue;
        iir_bsdf_lanes_set(&q->bsdf, k, gb->normal[i], gb->wo[i], gb->base[i], m.x, m.y, m.z);
        glossy[k] = -1;
    }
    q->glossy = _mm256_castsi256_ps(_mm256_load_si256((const __m256i *)glossy));
    q->any_glossy = _mm256_movemask_ps(q->glossy) != 0;
}

/* The half's materials, once: shade_block's f and which lanes are shaded. */
static void half_materials(lean_half *q, const iir_gbuffer *gb)
{
    if (q->loaded) return;
    q->loaded = true;
    q->any_glossy = false;
    q->glossy = zero();
    if (gb->any_pbr) half_glossy(q, gb);
    v3 albedo = half_vec3(q, gb, gb->albedo);
    q->shaded = _mm256_and_ps(q->hit, _mm256_or_ps(q->glossy, not_black(albedo)));
    q->f = and3(scale3(albedo, _mm256_set1_ps(IIR_INV_PI)), q->shaded);
}

/* The packet's lanes: o's shadow segments where traced. */
static void set_rays(iir_ray8 *rays, const iir_light_delta_lanes *o, __m256 traced, __m256 tmax)
{
    __m256i one = _mm256_set1_epi32(1);
    _mm256_storeu_si256((__m256i *)rays->valid, _mm256_and_si256(_mm256_castps_si256(traced), one));
    const float *from[6] = {o->ox, o->oy, o->oz, o->dx, o->dy, o->dz};
    float *to[6] = {rays->ox, rays->oy, rays->oz, rays->dx, rays->dy, rays->dz};
    for (int k = 0; k < 6; k++) _mm256_storeu_ps(to[k], _mm256_loadu_ps(from[k]));
    _mm256_storeu_ps(rays->tnear, zero());
    _mm256_storeu_ps(rays->tfar, tmax);
}

/* Light sample o at half q into rays (lanes_into_rays's rule: a shaded lane that receives light
 * gets its pending f E, added at once when its segment is too short to test). True when a lane
 * has a ray. A half the light does not reach reads no material. */
static bool half_rays(const iir_direct_lean *c, const iir_light_delta_lanes *o, lean_half *q,
                      iir_ray8 *rays)
{
    v3 E = load_planes(o->Ex, o->Ey, o->Ez);
    __m256 lit = not_black(E);
    if (!_mm256_movemask_ps(lit)) {
        memset(rays->valid, 0, sizeof rays->valid);
        return false;
    }
    half_materials(q, c->gb);
    v3 f = q->f;
    if (q->any_glossy) {
        _Alignas(32) float fx[8], fy[8], fz[8];
        iir_bsdf_f8_avx2(&q->bsdf, o->wx, o->wy, o->wz, fx, fy, fz);
        f = blend3(f, load_planes(fx, fy, fz), q->glossy);
    }
    lit = _mm256_and_ps(lit, q->shaded);
    q->pending = mul3(f, E);
    __m256 tmax = _mm256_loadu_ps(o->tmax);
    __m256 traced = _mm256_and_ps(lit, _mm256_cmp_ps(tmax, zero(), _CMP_GT_OQ));
    q->L = blend3(q->L, add3(q->L, q->pending), _mm256_andnot_ps(traced, lit));
    set_rays(rays, o, traced, tmax);
    return _mm256_movemask_ps(traced) != 0;
}

/* Light e's samples at the NH halves in one call (their latencies overlap), into the halves'
 * rays. rays_any[b]: block b (halves 2b, 2b + 1) has a lane with a ray. */
static void block_samples(const iir_direct_lean *c, const iir_light_eval *e, lean_half *q,
                          iir_ray8 *rays, bool *rays_any)
{
    iir_light_lanes in[NH];
    for (int h = 0; h < NH; h++) {
        _mm256_store_ps(in[h].px, q[h].p.x), _mm256_store_ps(in[h].py, q[h].p.y);
        _mm256_store_ps(in[h].pz, q[h].p.z), _mm256_store_ps(in[h].nx, q[h].n.x);
        _mm256_store_ps(in[h].ny, q[h].n.y), _mm256_store_ps(in[h].nz, q[h].n.z);
    }
    iir_light_delta_lanes o[NH];
    iir_light_sample_delta32_avx2(e, c->eps, in, o);
    for (int b = 0; b < NH / 2; b++) {
        bool any = half_rays(c, &o[2 * b], &q[2 * b], &rays[2 * b]);
        rays_any[b] = half_rays(c, &o[2 * b + 1], &q[2 * b + 1], &rays[2 * b + 1]) | any;
    }
}

/* Lanes of 8 bools. */
static inline __m256 bool_lanes(const bool *b)
{
    uint64_t bytes;
    memcpy(&bytes, b, sizeof bytes);
    __m256i v = _mm256_cvtepu8_epi32(_mm_cvtsi64_si128((long long)bytes));
    return _mm256_castsi256_ps(
        _mm256_xor_si256(_mm256_cmpeq_epi32(v, _mm256_setzero_si256()), _mm256_set1_epi32(-1)));
}

/* A block's 16 shadow rays as one packet: each half's pending light kept where its ray is
 * unoccluded. */
static void block_rays(const iir_direct_lean *c, const iir_ray8 rays[2], lean_half q[2],
                       iir_raystats *st)
{
    bool occluded[16];
    iir_rt_occluded16(c->rt, rays, occluded, st, IIR_RAYS_SHADOW);
    for (int h = 0; h < 2; h++) {
        __m256 valid = _mm256_castsi256_ps(_mm256_cmpgt_epi32(
            _mm256_loadu_si256((const __m256i *)rays[h].valid), _mm256_setzero_si256()));
        __m256 keep = _mm256_andnot_ps(bool_lanes(occluded + 8 * h), valid);
        q[h].L = blend3(q[h].L, add3(q[h].L, q[h].pending), keep);
    }
}

/* The half's radiance into the frame (its pixels inside it). */
static void half_store(const lean_half *q, iir_image *out)
{
    if (q->whole) {
        store_aos(q->L, iir_image_at(out, q->x0, q->y0), iir_image_at(out, q->x0, q->y0 + 1));
        return;
    }
    _Alignas(32) float x[8], y[8], z[8];
    _mm256_store_ps(x, q->L.x), _mm256_store_ps(y, q->L.y), _mm256_store_ps(z, q->L.z);
    for (int k = 0; k < 8; k++) {
        int px = q->x0 + k % HALF_W, py = q->y0 + k / HALF_W;
        if (px < out->width && py < out->height)
            *iir_image_at(out, px, py) = iir_v3(x[k], y[k], z[k]);
    }
}

/* Pixels ahead along the band that a block asks for: a band's four rows of each G-buffer array
 * and of the frame are ~20 streams at once, more than the prefetchers follow (at 1024x768 the
 * loads waited on memory: direct light ~15% faster with this). */
enum { AHEAD = 32 };

/* The lines the block AHEAD pixels to the right reads and writes, asked for now. */
IIR_PREFETCH_FN prefetch_ahead(const iir_direct_lean *c, int x0, int y0, iir_image *out)
{
    const iir_gbuffer *gb = c->gb;
    if (x0 + AHEAD >= gb->width || y0 + 2 * HALF_H > gb->height) return;
    for (int r = 0; r < 2 * HALF_H; r++) {
        size_t i = (size_t)(y0 + r) * (size_t)gb->width + (size_t)(x0 + AHEAD);
        _mm_prefetch((const char *)(gb->position + i), _MM_HINT_T0);
        _mm_prefetch((const char *)(gb->normal + i), _MM_HINT_T0);
        _mm_prefetch((const char *)(gb->albedo + i), _MM_HINT_T0);
        _mm_prefetch((const char *)(gb->prim + i), _MM_HINT_T0);
        if (gb->any_emission) _mm_prefetch((const char *)(gb->emission + i), _MM_HINT_T0);
        _mm_prefetch((const char *)iir_image_at(out, x0 + AHEAD, y0 + r), _MM_HINT_T0);
    }
}

void iir_direct_lean_block_avx2(const iir_direct_lean *c, int x0, int y0, iir_image *out,
                                iir_raystats *st)
{
    lean_half q[NH];
    prefetch_ahead(c, x0, y0, out);
    prefetch_ahead(c, x0 + HALF_W, y0, out);
    __m256 hit = zero();
    for (int h = 0; h < NH; h++) {
        half_at(&q[h], c->gb, x0 + HALF_W * (h / 2), y0 + HALF_H * (h % 2));
        hit = _mm256_or_ps(hit, q[h].hit);
    }
    if (!_mm256_movemask_ps(hit)) { /* background: black */
        for (int h = 0; h < NH; h++) q[h].L = (v3){zero(), zero(), zero()}, half_store(&q[h], out);
        return;
    }
    for (int h = 0; h < NH; h++) half_surface(&q[h], c->gb);
    for (uint32_t l = 0; l < c->num_lights; l++) {
        iir_ray8 rays[NH];
        bool any[NH / 2];
        block_samples(c, &c->evals[l], q, rays, any);
        for (int b = 0; b < NH / 2; b++)
            if (any[b]) block_rays(c, &rays[2 * b], &q[2 * b], st);
    }
    for (int h = 0; h < NH; h++) half_store(&q[h], out);
}

#endif

/* render_direct.c -- emission and direct light at the G-buffer's pixels: every delta light (point,
 * spots, sun) by one shadow ray per pixel (a sun's goes to infinity), every rectangular area light
 * and the emissive triangles by one seeded sample per pixel each; and the area lights that the
 * pixels' camera rays meet from the front before their surface (they are not in the BVH, so not in
 * the G-buffer: their radiance is added here, each frame, as they move). Not indirect light.
 *
 * Agrees in expectation with `pt --bounces 1`: pt picks one light by flux per sample, this sums
 * every light; pt weights area-light samples by MIS against BSDF sampling, this uses the
 * light sample alone (weight 1), which is unbiased by itself. Shadow rays go out as 8-wide packets
 * over 4x2 pixel blocks (neighbouring pixels, one light: coherent rays). Threads: OpenMP over
 * tiles, each writing only its own pixels of the frame; ray counters per thread, summed once. */
#include <omp.h>

#include "iir/rng.h"
#include "render_internal.h"

enum { BLOCK_W = 4, BLOCK_H = 2 }; /* one packet; divides IIR_RENDER_TILE */

typedef struct direct_ctx {
    const iir_renderer *r;
    const iir_light *lights;
    uint32_t num_lights;
    uint64_t seed;
    iir_camera_frame cam; /* the G-buffer's camera: its rays through r->gb_shift */
} direct_ctx;

/* The pixels of one 4x2 block and their shadow rays. */
typedef struct block {
    int x0, y0;
    size_t index[8];
    bool shaded[8];      /* geometry with non-zero albedo */
    iir_vec3 f[8];       /* BRDF rho / pi */
    iir_vec3 L[8];       /* radiance so far */
    iir_vec3 pending[8]; /* a light's contribution, kept if its shadow ray is unoccluded */
    iir_ray8 rays;
} block;

static void clear_rays(block *b)
{
    for (int k = 0; k < 8; k++) b->rays.valid[k] = 0;
}

static void set_lane(iir_ray8 *rays, int k, iir_vec3 org, iir_vec3 dir, float tfar)
{
    rays->ox[k] = org.x, rays->oy[k] = org.y, rays->oz[k] = org.z;
    rays->dx[k] = dir.x, rays->dy[k] = dir.y, rays->dz[k] = dir.z;
    rays->tnear[k] = 0.f;
    rays->tfar[k] = tfar;
    rays->valid[k] = 1;
}

/* Traces the block's pending shadow rays and adds the contributions of the unoccluded ones. */
static void resolve(const iir_renderer *r, block *b, iir_raystats *st)
{
    bool any = false;
    for (int k = 0; k < 8; k++) any |= b->rays.valid[k] != 0;
    if (!any) return;
    bool occluded[8];
    iir_rt_occluded8(r->rt, &b->rays, occluded, st, IIR_RAYS_SHADOW);
    for (int k = 0; k < 8; k++)
        if (b->rays.valid[k] && !occluded[k]) b->L[k] = iir_add(b->L[k], b->pending[k]);
}

/* Lane k's unshadowed f E cos for a sun (irradiance E from -direction), and its shadow ray to
 * infinity. */
static void sun_lane(const iir_renderer *r, const iir_light *l, block *b, int k)
{
    const iir_gbuffer *gb = &r->gb;
    iir_vec3 p = gb->position[b->index[k]], n = gb->normal[b->index[k]];
    iir_vec3 wi = iir_neg(iir_normalize(l->direction));
    float cos_theta = iir_dot(n, wi);
    if (cos_theta <= 0.f || iir_is_black(l->intensity)) return;
    b->pending[k] = iir_scale(iir_mul(b->f[k], l->intensity), cos_theta);
    set_lane(&b->rays, k, iir_madd(p, n, r->eps), wi, INFINITY);
}

/* Lane k's unshadowed f I(-wi) cos / d^2 for the prepared light e (point, cosine or glTF spot;
 * a sun goes to sun_lane), and its shadow ray. */
static void punctual_lane(const iir_renderer *r, const iir_light_eval *e, block *b, int k)
{
    const iir_light *l = e->light;
    if (l->type == IIR_LIGHT_SUN) {
        sun_lane(r, l, b, k);
        return;
    }
    const iir_gbuffer *gb = &r->gb;
    iir_vec3 p = gb->position[b->index[k]], n = gb->normal[b->index[k]];
    iir_vec3 d = iir_sub(l->position, p);
    float dist2 = iir_length_sq(d);
    if (!(dist2 > 0.f)) return;
    float dist = sqrtf(dist2);
    iir_vec3 wi = iir_scale(d, 1.f / dist);
    float cos_theta = iir_dot(n, wi);
    if (cos_theta <= 0.f) return;
    iir_vec3 I = iir_light_eval_intensity(e, iir_neg(wi));
    if (iir_is_black(I)) return;
    b->pending[k] = iir_scale(iir_mul(b->f[k], I), cos_theta / dist2);
    set_lane(&b->rays, k, iir_madd(p, n, r->eps), wi, dist - 2.f * r->eps);
}

/* Lane k's shadow ray from p (normal n) to the point sampled by ls: from the lifted point aimed at
 * the sampled point itself, stopping 2 eps short (surface.h's iir_light_sample_ray: along wi from
 * the lifted point, a grazing ray met an emissive triangle just before the point). */
static void aim_lane(const iir_renderer *r, block *b, int k, iir_vec3 p, iir_vec3 n,
                     const iir_light_sample *ls)
{
    iir_vec3 o = iir_madd(p, n, r->eps);
    iir_vec3 d = iir_sub(iir_madd(p, ls->wi, ls->dist), o);
    float len = iir_length(d);
    if (!(len > 2.f * r->eps)) return;
    set_lane(&b->rays, k, o, iir_scale(d, 1.f / len), len - 2.f * r->eps);
}

/* Lane k's unshadowed f Li cos / pdf for one sample (point uniform on it) of area light l, the
 * light's index li in the frame's list (its random numbers), and the shadow ray to the point. */
static void area_light_lane(const direct_ctx *c, const iir_light *l, uint32_t li, block *b, int k)
{
    const iir_renderer *r = c->r;
    const iir_gbuffer *gb = &r->gb;
    int x = b->x0 + k % BLOCK_W, y = b->y0 + k / BLOCK_W;
    iir_vec3 p = gb->position[b->index[k]], n = gb->normal[b->index[k]];
    iir_rng rng = iir_rng_make(c->seed, iir_hash3((uint64_t)x, (uint64_t)y, 1u + (uint64_t)li));
    iir_light_sample ls = iir_area_light_sample(l, p, iir_rng_uniform2(&rng));
    if (ls.pdf <= 0.f || iir_is_black(ls.Li)) return;
    float cos_theta = iir_dot(n, ls.wi);
    if (cos_theta <= 0.f) return;
    b->pending[k] = iir_scale(iir_mul(b->f[k], ls.Li), cos_theta / ls.pdf);
    aim_lane(r, b, k, p, n, &ls);
}

/* Adds area light l's radiance to the pixels whose camera rays meet it from the front before their
 * surface (or with no surface behind). */
static void area_light_seen(const direct_ctx *c, const iir_light *l, block *b)
{
    const iir_gbuffer *gb = &c->r->gb;
    iir_vec2 shift = c->r->gb_shift;
    iir_frame fr = iir_spot_frame(l);
    for (int k = 0; k < 8; k++) {
        int x = b->x0 + k % BLOCK_W, y = b->y0 + k / BLOCK_W;
        if (x >= gb->width || y >= gb->height) continue;
        iir_vec3 d = iir_camera_dir(&c->cam, x + 0.5f + shift.x, y + 0.5f + shift.y);
        float t = iir_area_light_hit(l, c->cam.origin, d, gb->depth[b->index[k]]);
        if (!isinf(t))
            b->L[k] =
                iir_add(b->L[k], iir_area_light_radiance_at(l, &fr, iir_madd(c->cam.origin, d, t)));
    }
}

/* One light's direct light at the block: a delta light's or an area light's sample per pixel, and
 * an area light seen by the camera. */
static void shade_light(const direct_ctx *c, uint32_t li, block *b, iir_raystats *st)
{
    const iir_light *l = &c->lights[li];
    iir_light_eval e = iir_light_prepare(l);
    clear_rays(b);
    for (int k = 0; k < 8; k++) {
        if (!b->shaded[k]) continue;
        if (l->type == IIR_LIGHT_AREA)
            area_light_lane(c, l, li, b, k);
        else
            punctual_lane(c->r, &e, b, k);
    }
    resolve(c->r, b, st);
    if (l->type == IIR_LIGHT_AREA) area_light_seen(c, l, b);
}

/* Lane k's unshadowed f Li cos / pdf for one sample of the emissive triangles, and its ray. */
static void area_lane(const direct_ctx *c, block *b, int k)
{
    const iir_renderer *r = c->r;
    const iir_gbuffer *gb = &r->gb;
    int x = b->x0 + k % BLOCK_W, y = b->y0 + k / BLOCK_W;
    iir_vec3 p = gb->position[b->index[k]], n = gb->normal[b->index[k]];
    iir_rng rng = iir_rng_make(c->seed, iir_hash3((uint64_t)x, (uint64_t)y, 0));
    float u_pick = iir_rng_uniform(&rng);
    iir_light_sample ls = iir_lightset_sample(r->area_lights, p, u_pick, iir_rng_uniform2(&rng));
    if (ls.pdf <= 0.f || iir_is_black(ls.Li)) return;
    float cos_theta = iir_dot(n, ls.wi);
    if (cos_theta <= 0.f) return;
    b->pending[k] = iir_scale(iir_mul(b->f[k], ls.Li), cos_theta / ls.pdf);
    aim_lane(r, b, k, p, n, &ls);
}

/* Reads the block's pixels: emission, and which of them direct light can reach. */
static void load_block(const iir_gbuffer *gb, int x0, int y0, block *b)
{
    b->x0 = x0, b->y0 = y0;
    for (int k = 0; k < 8; k++) {
        int x = x0 + k % BLOCK_W, y = y0 + k / BLOCK_W;
        bool inside = x < gb->width && y < gb->height;
        size_t i = inside ? (size_t)y * (size_t)gb->width + (size_t)x : 0;
        b->index[k] = i;
        b->shaded[k] = inside && gb->prim[i] != IIR_NO_HIT && !iir_is_black(gb->albedo[i]);
        b->L[k] = inside ? gb->emission[i] : iir_v3s(0.f);
        b->f[k] = b->shaded[k] ? iir_scale(gb->albedo[i], IIR_INV_PI) : iir_v3s(0.f);
    }
}

static void shade_block(const direct_ctx *c, int x0, int y0, iir_image *out, iir_raystats *st)
{
    block b;
    load_block(&c->r->gb, x0, y0, &b);
    for (uint32_t l = 0; l < c->num_lights; l++) shade_light(c, l, &b, st);
    if (c->r->area_lights) {
        clear_rays(&b);
        for (int k = 0; k < 8; k++)
            if (b.shaded[k]) area_lane(c, &b, k);
        resolve(c->r, &b, st);
    }
    for (int k = 0; k < 8; k++) {
        int x = x0 + k % BLOCK_W, y = y0 + k / BLOCK_W;
        if (x < out->width && y < out->height) *iir_image_at(out, x, y) = b.L[k];
    }
}

bool iir_render_direct(const iir_renderer *r, const iir_light *lights, uint32_t num_lights,
                       uint64_t seed, iir_image *out, iir_raystats *st)
{
    bool stopped = false;
    direct_ctx c = {r, lights, num_lights, seed,
                    iir_camera_setup(&r->gb_camera, r->gb.width, r->gb.height)};
    int w = out->width, h = out->height, tiles = iir_tile_count(w, h, IIR_RENDER_TILE);
    iir_raystats total = {0};
#pragma omp parallel
    {
        iir_raystats local = {0};
#pragma omp for schedule(dynamic, 1)
        for (int t = 0; t < tiles; t++) {
            if (r->stop && r->stop(r->stop_ctx)) {
#pragma omp atomic write
                stopped = true;
                continue;
            }
            iir_tile tl = iir_tile_at(w, h, IIR_RENDER_TILE, t);
            for (int y = tl.y0; y < tl.y1; y += BLOCK_H)
                for (int x = tl.x0; x < tl.x1; x += BLOCK_W) shade_block(&c, x, y, out, &local);
        }
#pragma omp critical(iir_direct_rays)
        iir_raystats_add(&total, &local);
    }
    iir_raystats_add(st, &total);
    return stopped;
}

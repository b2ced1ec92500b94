/* render_direct.c -- emission and direct light at the G-buffer's pixels: every delta light (point,
 * spots, sun) by one shadow ray per pixel (a sun's goes to infinity), every area light and the
 * emissive triangles by area_samples stratified samples per pixel each (a 2D Sobol net, shuffled
 * and Owen-scrambled per pixel and light: any prefix is well spread, a power of two of them is
 * stratified over the emitter; Burley 2020, "Practical hash-based Owen scrambling"); and the area
 * lights that the
 * pixels' camera rays meet from the front before their surface (they are not in the BVH, so not in
 * the G-buffer: their radiance is added here, each frame, as they move). Not indirect light.
 *
 * Agrees in expectation with `pt --bounces 1`: pt picks one light by flux per sample, this sums
 * every light; pt weights area-light samples by MIS against BSDF sampling, this uses the
 * light sample alone (weight 1), which is unbiased by itself. Shadow rays go out as 8-wide packets
 * over 4x2 pixel blocks (neighbouring pixels, one light: coherent rays); with AVX2 a point, spot
 * or sun is evaluated at the block's 8 pixels at once (iir_light_sample_delta8_avx2), and a frame
 * of such lights alone (lean) goes in pairs of 4x4 blocks held in registers, one 16-wide packet a
 * block, a metallic-roughness pixel's BSDF evaluated 8 lanes at once (iir_bsdf_f8_avx2;
 * render_direct_avx2.c), emission read only when some pixel has it.
 * Threads: OpenMP over bands of two (lean: four) whole rows, each writing only its own pixels of
 * the frame; ray counters per thread, summed once.
 *
 * Shading multires with mr_direct tree: a frame of points, spots and suns alone on diffuse surfaces
 * seen directly interpolates their irradiance over the light tree (light_tree.h: blocks split at
 * the multires hierarchy's discontinuities and where the light changes), its points evaluated 8 at
 * a time as above; then every pixel takes its emission plus its albedo / pi times the irradiance. A
 * pixel the tree evaluates gets full shading's value (the same sums). */
#include <omp.h>

#include <string.h>

#include "iir/rng.h"
#include "iir/bsdf.h"
#include "render_internal.h"

enum { BLOCK_W = 4, BLOCK_H = 2 }; /* one packet; divides IIR_RENDER_TILE */
enum { MAX_PREPARED = 64 }; /* lights prepared once a frame (more: once a block, as they come) */

typedef struct direct_ctx {
    const iir_renderer *r;
    const iir_light *lights;
    uint32_t num_lights;
    const iir_light_eval *evals; /* lights[i] prepared, when the frame has few (else NULL) */
    bool lean; /* AVX2, delta lights only (prepared), no specular chain: iir_direct_lean_block_avx2
                  (glossy pixels by iir_bsdf_f8_avx2) */
    uint64_t seed;
    int samples; /* per pixel per area light (and for the emissive triangles) */
    float inv_samples;
    iir_camera_frame cam; /* the G-buffer's camera: its rays through r->gb_shift */
    iir_mr_direct mr_direct;
} direct_ctx;

/* ---- stratified samples: a shuffled, Owen-scrambled 2D Sobol sequence per pixel and light ---- */

static uint32_t reverse_bits(uint32_t x)
{
    x = (x << 16) | (x >> 16);
    x = ((x & 0x00ff00ffu) << 8) | ((x & 0xff00ff00u) >> 8);
    x = ((x & 0x0f0f0f0fu) << 4) | ((x & 0xf0f0f0f0u) >> 4);
    x = ((x & 0x33333333u) << 2) | ((x & 0xccccccccu) >> 2);
    return ((x & 0x55555555u) << 1) | ((x & 0xaaaaaaaau) >> 1);
}

/* Nested uniform (Owen) scramble of x's bits from the top, by a hash (Laine-Karras in reverse):
 * each bit is flipped by a function of the bits above it, so nets stay nets. */
static uint32_t owen_scramble(uint32_t x, uint32_t seed)
{
    x = reverse_bits(x) + seed;
    x ^= x * 0x6c50b47cu;
    x ^= x * 0xb82f1e52u;
    x ^= x * 0xc7afe638u;
    x ^= x * 0x8d22f6e6u;
    return reverse_bits(x);
}

/* The second dimension of the Sobol sequence (the first is reverse_bits): together a (0,2)-net
 * in every aligned block of 2^m indices. */
static uint32_t sobol_dim1(uint32_t i)
{
    uint32_t x = 0;
    for (uint32_t v = 1u << 31; i; i >>= 1, v ^= v >> 1)
        if (i & 1u) x ^= v;
    return x;
}

static float unit_float(uint32_t x)
{
    return (float)(x >> 8) * 0x1p-24f;
}

/* One pixel's and one light's sample stream: hashes of (seed, x, y, stream). */
typedef struct strat {
    uint32_t shuffle, sx, sy, shuffle_pick, spick;
} strat;

static strat strat_make(uint64_t seed, int x, int y, uint64_t stream)
{
    uint64_t a = iir_hash3(seed, iir_hash3((uint64_t)x, (uint64_t)y, stream), 0x57a7);
    uint64_t b = iir_mix64(a ^ 0x9e3779b97f4a7c15ull), c = iir_mix64(b + 1);
    strat s = {(uint32_t)a, (uint32_t)(a >> 32), (uint32_t)b, (uint32_t)(b >> 32), (uint32_t)c};
    return s;
}

/* Sample i (of the first n) of the stream: a point in [0, 1)^2. */
static iir_vec2 strat_point(const strat *s, uint32_t i)
{
    uint32_t j = owen_scramble(i, s->shuffle);
    return iir_v2(unit_float(owen_scramble(reverse_bits(j), s->sx)),
                  unit_float(owen_scramble(sobol_dim1(j), s->sy)));
}

/* A third, independently shuffled dimension (stratified in 1D): the emissive triangles' pick. */
static float strat_pick(const strat *s, uint32_t i)
{
    return unit_float(owen_scramble(reverse_bits(owen_scramble(i, s->shuffle_pick)), s->spick));
}

/* The pixels of one 4x2 block and their shadow rays. */
typedef struct block {
    int x0, y0;
    size_t index[8];
    bool shaded[8]; /* geometry that reflects: non-zero albedo, or glossy */
    bool glossy[8]; /* a metal_rough pixel: f is the full BSDF (bsdf, wo) */
    iir_vec3 f[8];  /* a Lambertian pixel's BRDF rho / pi */
    iir_bsdf bsdf[8];
    iir_vec3 wo[8];
    iir_vec3 through[8]; /* what the pixel's specular chain passes on (iir_gbuffer.through) */
    iir_vec3 L[8];       /* radiance so far */
    iir_vec3 pending[8]; /* a light's contribution, kept if its shadow ray is unoccluded */
    iir_ray8 rays;
} block;

static void clear_rays(block *b)
{
    for (int k = 0; k < 8; k++) b->rays.valid[k] = 0;
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

/* Where light arrives at lane k's pixel. */
static iir_light_ctx lane_ctx(const iir_renderer *r, const block *b, int k)
{
    iir_light_ctx ctx = {r->gb.position[b->index[k]], r->gb.normal[b->index[k]], r->eps};
    return ctx;
}

/* Lane k's unshadowed f Li cos w / pdf for sample ls (w: 1 / N for one of N samples), and its
 * shadow ray; added at once when the segment is too short to test. */
static void sample_lane(const iir_renderer *r, block *b, int k, const iir_light_sample *ls, float w)
{
    iir_vec3 n = r->gb.normal[b->index[k]];
    if (ls->pdf <= 0.f || iir_is_black(ls->Li)) return;
    float cos_theta = iir_dot(n, ls->wi);
    if (cos_theta <= 0.f) return;
    iir_vec3 f = b->glossy[k] ? iir_bsdf_f(&b->bsdf[k], b->wo[k], ls->wi) : b->f[k];
    b->pending[k] = iir_scale(iir_mul(iir_mul(f, b->through[k]), ls->Li), cos_theta * w / ls->pdf);
    const iir_light_segment *seg = &ls->shadow;
    if (seg->tmax > 0.f)
        iir_ray8_set(&b->rays, k, seg->org, seg->dir, seg->tmax);
    else
        b->L[k] = iir_add(b->L[k], b->pending[k]);
}

/* The block's sample streams of stream number `stream` (area light li: 1 + li; emissive
 * triangles: 0). */
static void block_strats(const direct_ctx *c, const block *b, uint64_t stream, strat s[8])
{
    for (int k = 0; k < 8; k++)
        s[k] = strat_make(c->seed, b->x0 + k % BLOCK_W, b->y0 + k / BLOCK_W, stream);
}

/* Sample i of light e (NULL: the emissive triangles) for ctx, drawn from stream s: a point by the
 * 2D net, and for the emissive triangles a triangle picked by a stratified 1D number. */
static iir_light_sample draw(const direct_ctx *c, const iir_light_eval *e, const iir_light_ctx *ctx,
                             const strat *s, uint32_t i)
{
    iir_vec2 u = strat_point(s, i);
    if (e) return iir_light_sample_li(e, ctx, u);
    return iir_lightset_sample_li(c->r->area_lights, ctx, strat_pick(s, i), u);
}

/* The direct light of area light e (stream 1 + its index), or of the emissive triangles (e NULL,
 * stream 0), at the block: sample i of each shaded pixel's stratified stream, one packet of
 * shadow rays per sample. */
static void light_samples(const direct_ctx *c, const iir_light_eval *e, uint64_t stream, block *b,
                          iir_raystats *st)
{
    strat s[8];
    block_strats(c, b, stream, s);
    for (int i = 0; i < c->samples; i++) {
        clear_rays(b);
        for (int k = 0; k < 8; k++) {
            if (!b->shaded[k]) continue;
            iir_light_ctx ctx = lane_ctx(c->r, b, k);
            iir_light_sample ls = draw(c, e, &ctx, &s[k], (uint32_t)i);
            sample_lane(c->r, b, k, &ls, c->inv_samples);
        }
        resolve(c->r, b, st);
    }
}

/* Adds area light l's radiance to the pixels whose camera rays meet it from the front before their
 * surface (or with no surface behind). */
static void area_light_seen(const direct_ctx *c, const iir_light_eval *e, block *b)
{
    const iir_light *l = e->light;
    const iir_gbuffer *gb = &c->r->gb;
    iir_vec2 shift = c->r->gb_shift;
    for (int k = 0; k < 8; k++) {
        int x = b->x0 + k % BLOCK_W, y = b->y0 + k / BLOCK_W;
        if (x >= gb->width || y >= gb->height) continue;
        iir_vec3 d = iir_camera_dir(&c->cam, x + 0.5f + shift.x, y + 0.5f + shift.y);
        float t = iir_area_light_hit(l, c->cam.origin, d, gb->camera_t[b->index[k]]);
        if (!isinf(t))
            b->L[k] = iir_add(
                b->L[k], iir_area_light_radiance_at(l, &e->frame, iir_madd(c->cam.origin, d, t)));
    }
}

#if defined(__x86_64__)
/* Lane k of a delta light's 8 receivers: point p, normal n. */
static void set_receiver(iir_light_lanes *in, int k, iir_vec3 p, iir_vec3 n)
{
    in->px[k] = p.x, in->py[k] = p.y, in->pz[k] = p.z;
    in->nx[k] = n.x, in->ny[k] = n.y, in->nz[k] = n.z;
}

/* A delta light's 8 lane samples o into pending light (f times each lane's E, f[k] the pixel's
 * reflectance towards the light) and rays; a lane whose segment is too short to test adds its
 * light to L at once. True when a lane has a ray. sample_lane's rule, 8 lanes at a time. */
static bool lanes_into_rays(const iir_light_delta_lanes *o, const bool shaded[8],
                            const iir_vec3 f[8], iir_vec3 pending[8], iir_vec3 L[8], iir_ray8 *rays)
{
    bool any = false;
    for (int k = 0; k < 8; k++) {
        rays->valid[k] = 0;
        iir_vec3 E = iir_v3(o->Ex[k], o->Ey[k], o->Ez[k]);
        if (!shaded[k] || iir_is_black(E)) continue;
        pending[k] = iir_mul(f[k], E);
        if (!(o->tmax[k] > 0.f)) {
            L[k] = iir_add(L[k], pending[k]);
            continue;
        }
        iir_ray8_set(rays, k, iir_v3(o->ox[k], o->oy[k], o->oz[k]),
                     iir_v3(o->dx[k], o->dy[k], o->dz[k]), o->tmax[k]);
        any = true;
    }
    return any;
}

/* A delta light at the block by iir_light_sample_delta8_avx2: one packet of shadow rays. */
static void delta_lanes(const direct_ctx *c, const iir_light_eval *e, block *b, iir_raystats *st)
{
    const iir_gbuffer *gb = &c->r->gb;
    iir_light_lanes in;
    for (int k = 0; k < 8; k++)
        set_receiver(&in, k, gb->position[b->index[k]], gb->normal[b->index[k]]);
    iir_light_delta_lanes o;
    iir_light_sample_delta8_avx2(e, c->r->eps, &in, &o);
    iir_vec3 f[8]; /* the reflectance towards the light, through the pixel's chain */
    for (int k = 0; k < 8; k++) {
        iir_vec3 wi = iir_v3(o.wx[k], o.wy[k], o.wz[k]); /* 0 where no light arrives */
        bool lit = b->shaded[k] && !iir_is_black(iir_v3(o.Ex[k], o.Ey[k], o.Ez[k]));
        f[k] = !lit ? iir_v3s(0.f)
                    : iir_mul(b->glossy[k] ? iir_bsdf_f(&b->bsdf[k], b->wo[k], wi) : b->f[k],
                              b->through[k]);
    }
    lanes_into_rays(&o, b->shaded, f, b->pending, b->L, &b->rays);
    resolve(c->r, b, st);
}
#endif

/* One light's direct light at the block: a delta light's sample per pixel (one packet), an area
 * light's samples and where the camera sees it. */
static void shade_light(const direct_ctx *c, uint32_t li, block *b, iir_raystats *st)
{
    iir_light_eval e = c->evals ? c->evals[li] : iir_light_prepare(&c->lights[li]);
    if (!iir_light_is_delta(e.light)) {
        light_samples(c, &e, 1u + (uint64_t)li, b, st);
        area_light_seen(c, &e, b);
        return;
    }
#if defined(__x86_64__)
    if (c->r->isa >= IIR_ISA_AVX2) {
        delta_lanes(c, &e, b, st);
        return;
    }
#endif
    clear_rays(b);
    for (int k = 0; k < 8; k++) {
        if (!b->shaded[k]) continue;
        iir_light_ctx ctx = lane_ctx(c->r, b, k);
        iir_light_sample ls = iir_light_sample_li(&e, &ctx, iir_v2(0.f, 0.f));
        sample_lane(c->r, b, k, &ls, 1.f);
    }
    resolve(c->r, b, st);
}

/* Reads the block's pixels: emission, and which of them direct light can reach. */
static void load_block(const iir_gbuffer *gb, int x0, int y0, block *b)
{
    b->x0 = x0, b->y0 = y0;
    for (int k = 0; k < 8; k++) {
        int x = x0 + k % BLOCK_W, y = y0 + k / BLOCK_W;
        bool inside = x < gb->width && y < gb->height;
        size_t i = inside ? (size_t)y * (size_t)gb->width + (size_t)x : 0;
        bool hit = inside && gb->prim[i] != IIR_NO_HIT;
        b->index[k] = i;
        b->glossy[k] = hit && gb->mr[i].y >= 0.f;
        b->shaded[k] = hit && (b->glossy[k] || !iir_is_black(gb->albedo[i]));
        b->L[k] = inside ? gb->emission[i] : iir_v3s(0.f);
        b->through[k] = !hit ? iir_v3s(0.f) : gb->any_chain ? gb->through[i] : iir_v3s(1.f);
        b->f[k] = b->shaded[k] ? iir_scale(gb->albedo[i], IIR_INV_PI) : iir_v3s(0.f);
        if (!b->glossy[k]) continue;
        /* glossy direct light by the full BSDF, seen from the camera (wo) */
        b->wo[k] = gb->wo[i];
        b->bsdf[k] = iir_gb_bsdf(gb, i);
    }
}

static void shade_block(const direct_ctx *c, int x0, int y0, iir_image *out, iir_raystats *st)
{
#if defined(__x86_64__)
    if (c->lean) {
        iir_direct_lean lean = {&c->r->gb, c->r->rt, c->evals, c->num_lights, c->r->eps};
        iir_direct_lean_block_avx2(&lean, x0, y0, out, st);
        return;
    }
#endif
    block b;
    load_block(&c->r->gb, x0, y0, &b);
    for (uint32_t l = 0; l < c->num_lights; l++) shade_light(c, l, &b, st);
    if (c->r->area_lights) light_samples(c, NULL, 0, &b, st);
    for (int k = 0; k < 8; k++) {
        int x = x0 + k % BLOCK_W, y = y0 + k / BLOCK_W;
        if (x < out->width && y < out->height) *iir_image_at(out, x, y) = b.L[k];
    }
}

/* ---- shading multires: the delta lights' irradiance on the light tree ---- */

/* Whether the frame's direct light goes on the light tree: multires asking for it, and the lean
 * frame's lights and surfaces (any instruction set). */
static bool tree_frame(const direct_ctx *c)
{
    const iir_renderer *r = c->r;
    if (!r->level || !c->evals || r->area_lights || r->gb.any_pbr || r->gb.any_chain) return false;
    if (c->mr_direct != IIR_MR_DIRECT_TREE) return false;
    for (uint32_t l = 0; l < c->num_lights; l++)
        if (!iir_light_is_delta(&c->lights[l])) return false;
    return true;
}

/* Delta light e's sample at the m <= 8 pixels px into rays, E where no ray is needed and pending
 * (Li cos / pdf) where one is: lanes_into_rays's rule with f = 1. True when a lane has a ray. */
static bool tree_samples(const direct_ctx *c, const iir_light_eval *e, const uint32_t *px, int m,
                         iir_vec3 pending[8], iir_vec3 E[8], iir_ray8 *rays)
{
    const iir_gbuffer *gb = &c->r->gb;
    bool lane[8], any = false;
    iir_vec3 one[8];
    for (int k = 0; k < 8; k++) lane[k] = k < m, one[k] = iir_v3s(1.f), rays->valid[k] = 0;
#if defined(__x86_64__)
    if (c->r->isa >= IIR_ISA_AVX2) {
        iir_light_lanes in;
        for (int k = 0; k < 8; k++) {
            uint32_t i = px[k < m ? k : m - 1];
            set_receiver(&in, k, gb->position[i], gb->normal[i]);
        }
        iir_light_delta_lanes o;
        iir_light_sample_delta8_avx2(e, c->r->eps, &in, &o);
        return lanes_into_rays(&o, lane, one, pending, E, rays);
    }
#endif
    for (int k = 0; k < m; k++) {
        iir_light_ctx ctx = {gb->position[px[k]], gb->normal[px[k]], c->r->eps};
        iir_light_sample ls = iir_light_sample_li(e, &ctx, iir_v2(0.f, 0.f));
        float cos_theta = iir_dot(ctx.n, ls.wi);
        if (ls.pdf <= 0.f || iir_is_black(ls.Li) || cos_theta <= 0.f) continue;
        pending[k] = iir_scale(ls.Li, cos_theta / ls.pdf);
        if (ls.shadow.tmax > 0.f) {
            iir_ray8_set(rays, k, ls.shadow.org, ls.shadow.dir, ls.shadow.tmax);
            any = true;
        } else {
            E[k] = iir_add(E[k], pending[k]);
        }
    }
    return any;
}

/* The light tree's points (light_tree_eval_fn): every delta light's unoccluded Li cos / pdf,
 * summed over the lights, 8 pixels a packet. */
static uint64_t tree_points(void *ctx, const uint32_t *px, int n, iir_vec3 *D, iir_raystats *st)
{
    const direct_ctx *c = ctx;
    for (int i = 0; i < n; i += 8) {
        int m = n - i < 8 ? n - i : 8;
        iir_vec3 E[8], pending[8];
        for (int k = 0; k < 8; k++) E[k] = iir_v3s(0.f);
        for (uint32_t l = 0; l < c->num_lights; l++) {
            iir_ray8 rays;
            if (!tree_samples(c, &c->evals[l], px + i, m, pending, E, &rays)) continue;
            bool occluded[8];
            iir_rt_occluded8(c->r->rt, &rays, occluded, st, IIR_RAYS_SHADOW);
            for (int k = 0; k < m; k++)
                if (rays.valid[k] && !occluded[k]) E[k] = iir_add(E[k], pending[k]);
        }
        for (int k = 0; k < m; k++) D[px[i + k]] = E[k];
    }
    return (uint64_t)n * c->num_lights;
}

/* Every pixel: its emission plus, on a surface, its albedo / pi times the tree's irradiance. */
static void tree_compose(const iir_renderer *r, iir_image *out)
{
    const iir_gbuffer *gb = &r->gb;
    const size_t n = (size_t)gb->width * (size_t)gb->height;
#pragma omp parallel for schedule(static)
    for (size_t p = 0; p < n; p++) {
        iir_vec3 L = gb->emission[p];
        if (gb->prim[p] != IIR_NO_HIT && !iir_is_black(gb->albedo[p]))
            L = iir_add(L, iir_mul(iir_scale(gb->albedo[p], IIR_INV_PI), r->dtree.D[p]));
        out->pixels[p] = L;
    }
}

/* The frame's direct light on the light tree; IIR_ERR_NOMEM when its arrays cannot grow (the
 * caller then shades every pixel), IIR_ERR_INTERRUPTED when r->stop said so. */
static iir_status tree_direct(iir_renderer *r, direct_ctx *c, const iir_shade_job *job,
                              iir_raystats *st)
{
    const iir_mr_params *mp = &job->p->mr;
    light_tree_input in = {&r->gb, r->mr, tree_points, c, mp->mr_levels, mp->light_split};
    const iir_stop stop = {r->stop, r->stop_ctx};
    uint64_t evals = 0;
    iir_error err;
    iir_status s = light_tree_shade(&r->dtree, &in, &stop, &evals, st, &err);
    if (s == IIR_OK) tree_compose(r, job->out);
    return s;
}

bool iir_render_direct(iir_renderer *r, const iir_shade_job *job, iir_side_run *side,
                       iir_raystats *st)
{
    bool stopped = false;
    int n = job->p->area_samples;
    direct_ctx c = {r,
                    job->lights,
                    job->num_lights,
                    NULL,
                    false,
                    job->seed,
                    n,
                    1.f / (float)n,
                    iir_camera_setup(&r->gb_camera, r->gb.width, r->gb.height),
                    job->p->mr.mr_direct};
    iir_light_eval evals[MAX_PREPARED];
    if (c.num_lights <= MAX_PREPARED) {
        for (uint32_t l = 0; l < c.num_lights; l++) evals[l] = iir_light_prepare(&c.lights[l]);
        c.evals = evals;
    }
    c.lean = c.evals && r->isa >= IIR_ISA_AVX2 && !r->area_lights && !r->gb.any_chain;
    for (uint32_t l = 0; l < c.num_lights && c.lean; l++) c.lean = iir_light_is_delta(&c.lights[l]);
    if (tree_frame(&c)) {
        if (side) iir_side_go(side); /* first: the tree's loops are OpenMP loops of their own */
        side = NULL;
        iir_status s = tree_direct(r, &c, job, st);
        if (s != IIR_ERR_NOMEM) return s == IIR_ERR_INTERRUPTED;
    }
    iir_image *out = job->out;
    /* bands of whole rows, a block high: each per-pixel array streams through memory in long runs
       (16-pixel tile rows are a few cache lines each, too short for the prefetchers) */
    int w = out->width, h = out->height, band_h = c.lean ? 2 * BLOCK_H : BLOCK_H;
    int bands = (h + band_h - 1) / band_h; /* lean blocks are 4x4, two a call */
    iir_raystats total = {0};
#pragma omp parallel
    {
        iir_raystats local = {0};
        if (side) {
#pragma omp single nowait
            iir_side_go(side); /* the other threads take the bands meanwhile */
        }
#pragma omp for schedule(dynamic, 1)
        for (int t = 0; t < bands; t++) {
            if (side && iir_side_failed(side)) continue;
            if (r->stop && r->stop(r->stop_ctx)) {
#pragma omp atomic write
                stopped = true;
                continue;
            }
            for (int x = 0; x < w; x += c.lean ? 2 * BLOCK_W : BLOCK_W)
                shade_block(&c, x, t * band_h, out, &local);
        }
#pragma omp critical(iir_direct_rays)
        iir_raystats_add(&total, &local);
    }
    iir_raystats_add(st, &total);
    return stopped;
}

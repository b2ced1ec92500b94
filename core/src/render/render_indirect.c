/* render_indirect.c -- indirect light from VPLs at the G-buffer's pixels: checking the VPL set,
 * sorting the VPLs in use into interleaved subsets by id, and the per-pixel sum of vpl.h's formula
 * with the clamped geometry term and shadow-map or exact-ray visibility; at a glossy
 * (metal_rough) pixel each VPL's light goes through the pixel's BSDF toward the camera, demodulated
 * by iir_gb_demod (multires shades such pixels at full resolution, its coarse texels as diffuse
 * surfaces); not the filter that gathers the
 * subsets back (render_filter.c).
 *
 * The per-frame lists are built once, single-threaded (a counting sort over a few hundred VPLs),
 * into scratch the renderer keeps; the pixel loop then only reads them. Threads: OpenMP over 64x64
 * tiles, each writing only its own pixels of r->raw, with its pixel batch on its own stack and its
 * own ray counters (summed once at the end). */
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "iir/bsdf.h"
#include "iir/rng.h"
#include "iir/shadowmap.h"
#include "gv_columns.h"
#include "render_batch.h"
#include "../vpls/vpl_lobe.h"

/* ---- the VPL set of this frame ---- */

static bool in_use(const iir_vpl *v)
{
    return !v->null_sample && !iir_is_black(v->flux);
}

static iir_status check_vpl(const iir_vpl *v, iir_visibility vis, iir_error *err)
{
    if (v->null_sample) return IIR_OK;
    if (!iir_is_finite3(v->position) || !iir_is_finite3(v->normal) || !iir_is_finite3(v->frame.r) ||
        !iir_is_finite3(v->frame.u))
        return iir_fail(err, IIR_ERR_INVALID, "VPL %u: position or normal is not finite", v->id);
    if (fabsf(iir_length(v->normal) - 1.f) > 1e-3f ||
        iir_length_sq(iir_sub(v->frame.f, v->normal)) > 1e-6f)
        return iir_fail(err, IIR_ERR_INVALID,
                        "VPL %u: normal is not unit length or its frame does not match it (set "
                        "both with iir_vpl_set_normal)",
                        v->id);
    if (!iir_is_finite3(v->flux) || v->flux.x < 0.f || v->flux.y < 0.f || v->flux.z < 0.f)
        return iir_fail(err, IIR_ERR_INVALID, "VPL %u: flux must be finite and non-negative",
                        v->id);
    if (v->lobe.glossy &&
        (fabsf(iir_length(v->wi) - 1.f) > 1e-3f || !(v->albedo.x > 0.f) || !(v->albedo.y > 0.f) ||
         !(v->albedo.z > 0.f) || !iir_is_finite3(v->lobe.base) ||
         !isfinite(v->lobe.metallic + v->lobe.roughness + v->lobe.f0)))
        return iir_fail(err, IIR_ERR_INVALID,
                        "VPL %u: a glossy lobe needs a unit wi, a positive albedo and finite "
                        "parameters",
                        v->id);
    if (vis != IIR_VIS_RAYS && (v->smap.res < 1 || !v->smap.depth))
        return iir_fail(err, IIR_ERR_INVALID,
                        "VPL %u has no shadow map (build the maps with iir_smaps_build before "
                        "rendering with shadow-map visibility)",
                        v->id);
    return IIR_OK;
}

static iir_status reserve(iir_renderer *r, uint32_t n, iir_error *err)
{
    if (n <= r->vpl_cap) return IIR_OK;
    iir_shade_vpl *grown = realloc(r->vpl, sizeof(iir_shade_vpl) * n);
    if (!grown) return iir_fail(err, IIR_ERR_NOMEM, "out of memory for %u VPLs", n);
    r->vpl = grown;
    r->vpl_cap = n;
    return IIR_OK;
}

static iir_shade_vpl shade_vpl(const iir_vpl *v, float scale, float eps)
{
    iir_shade_vpl s;
    s.p = v->position;
    s.r = v->frame.r;
    s.u = v->frame.u;
    s.n = v->frame.f;
    s.org = iir_madd(v->position, v->frame.f, eps);
    s.power = iir_scale(v->flux, IIR_INV_PI * scale);
    s.smap = &v->smap;
    s.generation = v->generation;
    s.glossy = v->lobe.glossy;
    s.radius = 0.f;
    if (!s.glossy) return s;
    s.wi = v->wi;
    s.inv_albedo_pi = iir_pi_over(v->albedo);
    s.bsdf = iir_vpl_lobe_bsdf(v);
    return s;
}

/* Virtual spherical lights: each VPL's radius, the distance to its IIR_VSL_NEIGHBOURS-th nearest
 * VPL in use (the local density of the set; 0 with fewer VPLs). O(n^2) over a few hundred. */
static void sphere_radii(iir_shade_vpl *v, uint32_t n)
{
    enum { K = IIR_VSL_NEIGHBOURS };
    for (uint32_t i = 0; i < n; i++) {
        float near[K]; /* the K smallest squared distances, ascending */
        for (int q = 0; q < K; q++) near[q] = INFINITY;
        for (uint32_t j = 0; j < n; j++) {
            float d2 = iir_length_sq(iir_sub(v[i].p, v[j].p));
            if (j == i || !(d2 < near[K - 1])) continue;
            int q = K - 1;
            for (; q > 0 && near[q - 1] > d2; q--) near[q] = near[q - 1];
            near[q] = d2;
        }
        v[i].radius = isfinite(near[K - 1]) ? sqrtf(near[K - 1]) : 0.f;
    }
}

iir_status iir_render_subsets(iir_renderer *r, const iir_vpl *vpls, uint32_t num_vpls,
                              const iir_indirect_params *p, bool exact_mean, iir_error *err)
{
    uint32_t n2 = (uint32_t)(p->interleave * p->interleave), count[IIR_MAX_SUBSETS] = {0}, used = 0;
    for (uint32_t i = 0; i < num_vpls; i++) {
        iir_status s = check_vpl(&vpls[i], p->visibility, err);
        if (s != IIR_OK) return s;
        if (in_use(&vpls[i])) count[iir_vpl_subset_of(&vpls[i], n2)]++, used++;
    }
    iir_status s = reserve(r, used, err);
    if (s != IIR_OK) return s;
    r->num_subsets = n2;
    r->start[0] = 0;
    for (uint32_t k = 0; k < n2; k++) r->start[k + 1] = r->start[k] + count[k];
    uint32_t next[IIR_MAX_SUBSETS];
    for (uint32_t k = 0; k < n2; k++) next[k] = r->start[k];
    for (uint32_t i = 0; i < num_vpls; i++) {
        if (!in_use(&vpls[i])) continue;
        uint32_t k = iir_vpl_subset_of(&vpls[i], n2);
        float scale = exact_mean ? (float)n2 : (float)used / (float)count[k];
        r->vpl[next[k]++] = shade_vpl(&vpls[i], scale, r->eps);
    }
    if (p->vpl_kind == IIR_VPL_SPHERE) sphere_radii(r->vpl, used);
    return IIR_OK;
}

/* ---- the pixel loop ----
 *
 * Order: per tile, per subset, the tile's pixels of that subset are collected into a batch; then
 * each of the subset's VPLs is applied to the whole batch. Consecutive lookups thus hit one map at
 * neighbouring texels (the batch spans a few degrees seen from the VPL), and everything about the
 * VPL stays in registers. The batch is structure-of-arrays, padded to whole vector lanes with
 * pixels of zero normal (which no VPL lights), so the shadow-map kernel of the renderer's
 * instruction set (render_batch.h) runs 4 or 8 pixels per step.
 */

typedef struct indirect_ctx {
    const iir_renderer *r;
    iir_stop_fn stop; /* NULL when the work must not stop early */
    uint32_t shift;   /* added to every pixel's subset (mod n^2) */
    bool use_smap;
    iir_kernel_args args;   /* g_max: clamp / D^2, or INFINITY; rel_bias: sm_bias */
    iir_smap_kernel kernel; /* the renderer's instruction set's (r->isa) */
    int n;                  /* multires: the interleave n (subset k sits at (k mod n, k / n)) */
    iir_receiver_bsdf receivers;      /* which pixels reflect by their full BSDF (iir_gb_glossy) */
    iir_gv_frame gv;                  /* the kept VPLs' columns (none: gv.ref NULL) */
    uint32_t prefix[IIR_MAX_SUBSETS]; /* subset k's leading VPLs that read their columns and are
                                         not glossy (all of them: the columns alone shade it) */
    uint32_t reads[IIR_MAX_SUBSETS];  /* subset k's VPLs that read their columns */
    bool fresh; /* the first frame on this G-buffer: its background pixels of r->raw are zeroed */
} indirect_ctx;

typedef iir_pixel_batch pixel_batch;

/* The pixel's position and normal. */
static inline iir_vec3 batch_x(const pixel_batch *b, int j)
{
    return iir_v3(b->px[j], b->py[j], b->pz[j]);
}
static inline iir_vec3 batch_n(const pixel_batch *b, int j)
{
    return iir_v3(b->nx[j], b->ny[j], b->nz[j]);
}
static inline void batch_add(pixel_batch *b, int j, iir_vec3 L)
{
    b->Ex[j] += L.x, b->Ey[j] += L.y, b->Ez[j] += L.z;
}

/* What glossy VPL v sends toward x relative to a diffuse VPL of its albedo: f(wi, w) pi / albedo,
 * w the unit direction from v to x (its cosine is in G). */
static inline iir_vec3 sender(const iir_shade_vpl *v, iir_vec3 x)
{
    iir_vec3 w = iir_normalize(iir_sub(x, v->p));
    return iir_mul(iir_bsdf_f(&v->bsdf, w, v->wi), v->inv_albedo_pi);
}

/* What glossy pixel j of the batch reflects toward the camera of light arriving from the VPL at p,
 * relative to a diffuse receiver of the demodulating albedo: f(wo, wi) pi / demod (1 for a
 * Lambertian pixel of that albedo). */
static inline iir_vec3 receiver(const pixel_batch *b, int j, iir_vec3 p)
{
    iir_vec3 wi = iir_normalize(iir_sub(p, batch_x(b, j)));
    return iir_mul(iir_bsdf_f(&b->bsdf[j], b->wo[j], wi), b->demod_pi[j]);
}

/* ---- virtual spherical lights: a glossy receiver's BSDF averaged over the sphere's cone ---- */

/* The directions of a cone that a sphere subtends: its frame (axis frame.f), cos of its half-angle,
 * 1 minus that (h_max) and its solid angle omega = 2 pi h_max. */
typedef struct vsl_cone {
    iir_frame frame;
    float cos_max, h_max, omega;
} vsl_cone;

/* The direction of the cone at height u in [0, 1) (1 - cos theta = u h_max: uniform in solid
 * angle) and azimuth phi. */
static iir_vec3 cone_sample(const vsl_cone *c, float u, float phi)
{
    float ct = 1.f - u * c->h_max, st = sqrtf(fmaxf(0.f, 1.f - ct * ct));
    return iir_frame_to_world(&c->frame, iir_v3(st * cosf(phi), st * sinf(phi), ct));
}

/* A random stream of its own for the pair of pixel i and the VPL at p: the same every frame. */
static iir_rng pair_rng(uint32_t i, iir_vec3 p)
{
    uint32_t px, pz;
    memcpy(&px, &p.x, sizeof px), memcpy(&pz, &p.z, sizeof pz);
    return iir_rng_make(iir_hash3(i, px, pz), 0);
}

/* The direction of the cone nearest to w: w itself inside it, else on its rim. */
static iir_vec3 cone_nearest(const vsl_cone *c, iir_vec3 w)
{
    float cw = iir_dot(w, c->frame.f);
    if (cw >= c->cos_max) return w;
    iir_vec3 t = iir_sub(w, iir_scale(c->frame.f, cw));
    float len = iir_length(t);
    if (!(len > 1e-6f)) return c->frame.f;
    float sin_max = sqrtf(c->h_max * (1.f + c->cos_max));
    return iir_add(iir_scale(c->frame.f, c->cos_max), iir_scale(t, sin_max / len));
}

/* How many of the IIR_VSL_SAMPLES directions the BSDF draws for a receiver seen from wo, by k =
 * omega p_b at the cone's direction nearest the lobe's peak (the mirror direction of wo): about
 * how many times narrower than the cone the lobe is. A lobe as wide as the cone or wider (k < 4:
 * roughness 0.5 and 0.3 in test_render's scene) is estimated best by uniform directions alone; a
 * narrower one (0.15) mostly falls between them, and the BSDF draws half, or 3/4 when k >= 16.
 * The count depends on the pair only, not on random numbers, so the estimate stays unbiased. */
static int vsl_bsdf_count(const vsl_cone *c, const iir_bsdf *bsdf, iir_vec3 wo)
{
    iir_vec3 n = bsdf->frame.f, mirror = iir_sub(iir_scale(n, 2.f * iir_dot(n, wo)), wo);
    float k = c->omega * iir_bsdf_pdf(bsdf, wo, cone_nearest(c, mirror));
    return k < 4.f ? 0 : k < 16.f ? IIR_VSL_SAMPLES / 2 : IIR_VSL_SAMPLES * 3 / 4;
}

/* The same as receiver() for a virtual spherical light of radius r at p: the BSDF times the
 * receiver's cosine averaged over the cone the sphere subtends, over the cosine toward its centre
 * ca (which G holds); a point's receiver() as r goes to 0. The average (1 / omega) int_cone f cos
 * dw is estimated from IIR_VSL_SAMPLES directions by multiple importance sampling (Veach's
 * balance heuristic): N_u uniform in the cone (pdf 1 / omega; rings stratified in cos theta,
 * jittered, turned by the golden angle) and N_b = vsl_bsdf_count drawn by iir_bsdf_sample_f (pdf
 * p_b, u stratified 2 x N_b / 2; one outside the cone adds 0 but counts), all from the pair's own
 * stream (pair_rng):
 *     (1 / omega) sum over the directions w in the cone of f cos / (N_u / omega + N_b p_b(w))
 *   = sum over the directions w in the cone of f(wo, w) cos_x(w) / (N_u + N_b omega p_b(w)).
 * Unbiased, as the uniform directions cover the cone; but one estimate per pixel stays noisy where
 * the cone cuts a lobe about its own size (test_render's figures). */
static iir_vec3 receiver_sphere(const pixel_batch *b, int j, const iir_shade_vpl *v)
{
    iir_vec3 x = batch_x(b, j), n = batch_n(b, j), a = iir_sub(v->p, x);
    float d = iir_length(a);
    a = iir_scale(a, 1.f / d);
    float sin2 = iir_sqr(fminf(v->radius / d, 1.f)), cos_max = sqrtf(1.f - sin2);
    float h_max = sin2 / (1.f + cos_max); /* 1 - cos_max without the cancellation */
    float ca = iir_dot(n, a);
    if (!(h_max > 1e-7f) || !(ca > 0.f)) return receiver(b, j, v->p);
    vsl_cone c = {iir_frame_from_normal(a), cos_max, h_max, 2.f * IIR_PI * h_max};
    const iir_bsdf *bsdf = &b->bsdf[j];
    iir_vec3 wo = b->wo[j], sum = iir_v3s(0.f);
    int n_b = vsl_bsdf_count(&c, bsdf, wo), n_u = IIR_VSL_SAMPLES - n_b;
    float nb_omega = (float)n_b * c.omega;
    iir_rng rng = pair_rng(b->index[j], v->p);
    /* uniform in the cone */
    float turn = 2.f * IIR_PI * iir_rng_uniform(&rng), jit = iir_rng_uniform(&rng);
    for (int s = 0; s < n_u; s++) {
        iir_vec3 w = cone_sample(&c, ((float)s + jit) / (float)n_u, turn + (float)s * 2.3999632f);
        float cos_x = iir_dot(n, w);
        if (cos_x <= 0.f) continue;
        float pdf_b = n_b ? iir_bsdf_pdf(bsdf, wo, w) : 0.f;
        sum = iir_madd(sum, iir_bsdf_f(bsdf, wo, w), cos_x / ((float)n_u + nb_omega * pdf_b));
    }
    /* by the BSDF; its delta lobe is no part of iir_bsdf_f, nor of the average */
    for (int s = 0; s < n_b; s++) {
        float u0 = iir_rng_uniform(&rng), u1 = iir_rng_uniform(&rng), uc = iir_rng_uniform(&rng);
        iir_vec2 u = iir_v2(fminf(((float)(s % 2) + u0) * 0.5f, 0x1.fffffep-1f),
                            fminf(((float)(s / 2) + u1) / (float)(n_b / 2), 0x1.fffffep-1f));
        iir_bsdf_sample bs;
        if (!iir_bsdf_sample_f(bsdf, wo, uc, u, &bs) || (bs.flags & IIR_BSDF_SPECULAR) ||
            iir_dot(bs.wi, a) < cos_max)
            continue;
        float cos_x = iir_dot(n, bs.wi);
        if (cos_x <= 0.f) continue;
        sum = iir_madd(sum, bs.f, cos_x / ((float)n_u + nb_omega * bs.pdf));
    }
    return iir_mul(iir_scale(sum, 1.f / ca), b->demod_pi[j]);
}

/* Adds power G (G: the clamped geometry term times visibility) of VPL v to batch pixel j, through
 * its BSDF when it is glossy. The clamp bounds a glossy pixel's G times its receiver factor as it
 * bounds a diffuse pixel's G (g_max): a VPL in a sharp lobe adds no more than one beside a
 * diffuse pixel does, keeping the lobe's colour (the spikes of point VPLs on glossy surfaces are
 * what virtual spherical lights remove instead). */
void iir_batch_add_lit(pixel_batch *b, int j, const iir_shade_vpl *v, float G, float g_max)
{
    if (G <= 0.f) return;
    bool glossy = iir_batch_is_glossy(b, j);
    if (!glossy && !v->glossy) {
        batch_add(b, j, iir_scale(v->power, G));
        return;
    }
    iir_vec3 f = iir_v3s(G);
    if (glossy) f = iir_mul(f, v->radius > 0.f ? receiver_sphere(b, j, v) : receiver(b, j, v->p));
    if (v->glossy) f = iir_mul(f, sender(v, batch_x(b, j)));
    float peak = fmaxf(f.x, fmaxf(f.y, f.z));
    if (peak > g_max) f = iir_scale(f, g_max / peak);
    batch_add(b, j, iir_mul(v->power, f));
}

/* The occlusion ray from x lifted along n to the VPL's lifted position. False when the two are
 * closer than the lifts: nothing can lie between them. */
static bool lifted_ray(float eps, const iir_shade_vpl *v, iir_vec3 x, iir_vec3 n, iir_ray *ray)
{
    iir_vec3 org = iir_madd(x, n, eps), d = iir_sub(v->org, org);
    float len = iir_length(d);
    if (len <= 2.f * eps) return false;
    *ray = iir_make_ray(org, iir_scale(d, 1.f / len), 0.f, len - 2.f * eps);
    return true;
}

/* Lane k of a packet: lifted_ray's ray (lane left invalid when there is none). */
static bool visibility_ray(const indirect_ctx *c, const iir_shade_vpl *v, iir_vec3 x, iir_vec3 n,
                           iir_ray8 *rays, int k)
{
    iir_ray ray;
    rays->valid[k] = 0;
    if (!lifted_ray(c->r->eps, v, x, n, &ray)) return false;
    rays->ox[k] = ray.org.x, rays->oy[k] = ray.org.y, rays->oz[k] = ray.org.z;
    rays->dx[k] = ray.dir.x, rays->dy[k] = ray.dir.y, rays->dz[k] = ray.dir.z;
    rays->tnear[k] = ray.tnear;
    rays->tfar[k] = ray.tfar;
    rays->valid[k] = 1;
    return true;
}

/* Adds power G V of VPL v to every pixel of the batch, V by exact occlusion rays: 8 pixels per
 * packet, all rays ending at the VPL (coherent). */
static void apply_vpl_rays(const indirect_ctx *c, const iir_shade_vpl *v, pixel_batch *b,
                           iir_raystats *st)
{
    for (int j0 = 0; j0 < b->m; j0 += 8) {
        iir_ray8 rays;
        float G[8];
        bool any = false, occluded[8];
        for (int k = 0; k < 8; k++) {
            int j = j0 + k;
            G[k] = 0.f;
            rays.valid[k] = 0;
            if (j >= b->m) continue;
            iir_vpl_geometry g =
                iir_vpl_geometry_at(v, batch_x(b, j), batch_n(b, j), c->args.g_max);
            if (!g.lit) continue;
            G[k] = g.G;
            any |= visibility_ray(c, v, batch_x(b, j), batch_n(b, j), &rays, k);
        }
        if (any) iir_rt_occluded8(c->r->rt, &rays, occluded, st, IIR_RAYS_VISIBILITY);
        for (int k = 0; k < 8 && j0 + k < b->m; k++)
            if (!rays.valid[k] || !occluded[k])
                iir_batch_add_lit(b, j0 + k, v, G[k], c->args.g_max);
    }
}

static void batch_push(pixel_batch *b, uint32_t i, iir_vec3 x, iir_vec3 n)
{
    int j = b->m++;
    if (!(j & 7)) b->glossy[j >> 3] = 0;
    b->index[j] = i;
    b->px[j] = x.x, b->py[j] = x.y, b->pz[j] = x.z;
    b->nx[j] = n.x, b->ny[j] = n.y, b->nz[j] = n.z;
    b->Ex[j] = b->Ey[j] = b->Ez[j] = 0.f;
}

/* Marks the pixel just pushed (G-buffer pixel i) glossy when its material is: its BSDF, seen
 * from the viewer (the eye, or the specular chain's last link). */
static void batch_mark_glossy(pixel_batch *b, const iir_gbuffer *gb, size_t i,
                              iir_receiver_bsdf mode)
{
    if (!iir_gb_glossy(gb, i, mode)) return;
    int j = b->m - 1;
    b->glossy[j >> 3] |= (uint8_t)(1u << (j & 7));
    b->bsdf[j] = iir_gb_bsdf(gb, i);
    b->wo[j] = gb->wo[i];
    b->demod_pi[j] = iir_pi_over(iir_gb_demod(gb, i, mode));
}

/* Fills b with the next (up to IIR_BATCH) pixels that see geometry of the lattice (x_first + a n,
 * y + b n) inside the tile, from (*x, *y) on, advancing them, and pads it to whole lanes.
 * False when none are left. */
static bool collect(const indirect_ctx *c, const iir_tile *tl, int x_first, int n, int *x, int *y,
                    pixel_batch *b)
{
    const iir_gbuffer *gb = &c->r->gb;
    b->m = 0;
    while (*y < tl->y1 && b->m < IIR_BATCH) {
        size_t i = (size_t)*y * (size_t)gb->width + (size_t)*x;
        if (gb->prim[i] != IIR_NO_HIT) {
            batch_push(b, (uint32_t)i, gb->position[i], gb->normal[i]);
            if (gb->any_pbr) batch_mark_glossy(b, gb, i, c->receivers);
        }
        *x += n;
        if (*x >= tl->x1) *x = x_first, *y += n;
    }
    int m = b->m;
    while (b->m % IIR_BATCH_LANES) batch_push(b, 0, iir_v3s(0.f), iir_v3s(0.f)); /* never lit */
    b->m = m;
    return m > 0;
}

/* Adds power G V of VPLs v[0 .. count) to every pixel of the batch: V from their maps by the
 * kernel (gv: their columns, or NULL), or by rays. */
static void apply_vpls(const indirect_ctx *c, const iir_shade_vpl *v, const iir_gv_ref *gv,
                       uint32_t count, pixel_batch *b, iir_raystats *st)
{
    if (c->use_smap)
        c->kernel(&c->args, v, gv, count, b);
    else
        for (uint32_t i = 0; i < count; i++) apply_vpl_rays(c, &v[i], b, st);
}

/* Subset k's sums at the tile's pixels of class cls from the columns alone (every VPL of it in
 * c->prefix[k], no glossy pixel): the kernel's sums without collecting the pixels
 * (gv_columns.h). */
static void columns_only(const indirect_ctx *c, int t, uint32_t k, uint32_t cls, int count)
{
    const iir_renderer *r = c->r;
    uint32_t n2 = r->num_subsets, ord = c->gv.ord[(size_t)t * n2 + cls];
    const uint32_t *pixel = c->gv.pixel + c->gv.base[cls];
    _Alignas(32) float E[3][IIR_BATCH];
    for (int q0 = 0; q0 < count; q0 += IIR_BATCH) {
        int m = count - q0 < IIR_BATCH ? count - q0 : IIR_BATCH;
        iir_columns_sum_avx2(&r->vpl[r->start[k]], &c->gv.ref[r->start[k]],
                             r->start[k + 1] - r->start[k], ord + (uint32_t)q0, m, E[0], E[1],
                             E[2]);
        for (int q = 0; q < m; q++)
            r->raw[pixel[ord + (uint32_t)q0 + (uint32_t)q]] = iir_v3(E[0][q], E[1][q], E[2][q]);
    }
}

/* The batch of class cls's pixels [ord, ord + m) from the columns' copy of their positions and
 * normals (none of them glossy): collect's batch without reading the G-buffer. */
static void fill_batch(const indirect_ctx *c, uint32_t cls, uint32_t ord, int m, pixel_batch *b)
{
    size_t at = c->gv.base[cls] + ord, bytes = sizeof(float) * (size_t)m;
    float *plane[6] = {b->px, b->py, b->pz, b->nx, b->ny, b->nz};
    for (int q = 0; q < 6; q++) memcpy(plane[q], c->gv.soa + (size_t)q * c->gv.plane + at, bytes);
    memcpy(b->index, c->gv.pixel + at, sizeof(uint32_t) * (size_t)m);
    memset(b->Ex, 0, bytes), memset(b->Ey, 0, bytes), memset(b->Ez, 0, bytes);
    memset(b->glossy, 0, sizeof b->glossy);
    b->m = m;
    while (b->m % IIR_BATCH_LANES) batch_push(b, 0, iir_v3s(0.f), iir_v3s(0.f)); /* never lit */
    b->m = m;
}

/* Hit pixels of class cls in tile t (columns: their ord's difference). */
static int class_count(const indirect_ctx *c, int t, uint32_t cls, int tiles)
{
    uint32_t n2 = c->r->num_subsets;
    uint32_t end = t + 1 < tiles ? c->gv.ord[(size_t)(t + 1) * n2 + cls]
                                 : c->gv.base[cls + 1] - c->gv.base[cls];
    return (int)(end - c->gv.ord[(size_t)t * n2 + cls]);
}

/* Subset k's light at batch b's pixels into r->raw, its first `lead` VPLs from their columns
 * alone; returns the pairs shaded and adds those read from columns to *reused. */
static uint64_t shade_batch(const indirect_ctx *c, uint32_t k, uint32_t lead, pixel_batch *b,
                            iir_raystats *st, uint64_t *reused)
{
    const iir_renderer *r = c->r;
    uint32_t count = r->start[k + 1] - r->start[k];
    const iir_gv_ref *gv = c->gv.ref ? &c->gv.ref[r->start[k]] : NULL;
    int m = b->m;
    *reused += (uint64_t)m * c->reads[k];
    if (lead) iir_columns_sum_avx2(&r->vpl[r->start[k]], gv, lead, b->ord, m, b->Ex, b->Ey, b->Ez);
    apply_vpls(c, &r->vpl[r->start[k] + lead], gv ? gv + lead : NULL, count - lead, b, st);
    for (int q = 0; q < m; q++) r->raw[b->index[q]] = iir_v3(b->Ex[q], b->Ey[q], b->Ez[q]);
    return (uint64_t)m * count;
}

/* The background pixels of tile tl in r->raw: 0 (every other pixel is written each frame). Once
 * per G-buffer: nothing writes them but with 0 (the empty lattices here, multires's fine pass),
 * and a frame that read the G-buffer's primitives again just to find them spent ~15% of the
 * indirect phase at 1024x768 waiting on those lines. */
static void zero_background(const iir_renderer *r, const iir_tile *tl)
{
    const iir_gbuffer *gb = &r->gb;
    for (int y = tl->y0; y < tl->y1; y++)
        for (int x = tl->x0; x < tl->x1; x++) {
            size_t i = (size_t)y * (size_t)gb->width + (size_t)x;
            if (gb->prim[i] == IIR_NO_HIT) r->raw[i] = iir_v3s(0.f);
        }
}

/* Whether the frame's stop hook asks to stop (never when not stoppable). */
static bool stop_asked(const indirect_ctx *c)
{
    return c->stop && c->stop(c->r->stop_ctx);
}

/* Shades one tile (a band: its subsets one by one, asking the stop hook before each and leaving
 * the rest when it says stop, *stopped then set); returns the pixel-VPL pairs shaded, and adds
 * those read from columns to *reused. */
static uint64_t indirect_tile(const indirect_ctx *c, int n, int t, int tiles, pixel_batch *b,
                              iir_raystats *st, uint64_t *reused, int *stopped)
{
    uint64_t evals = 0;
    const iir_renderer *r = c->r;
    const iir_gbuffer *gb = &r->gb;
    iir_tile tl = iir_indirect_tile_at(gb->width, gb->height, t);
    if (c->fresh) zero_background(r, &tl);
    /* The lattice through (x0 + i, y0 + j) is one subset. */
    for (int j = 0; j < n && tl.y0 + j < tl.y1; j++)
        for (int i = 0; i < n && tl.x0 + i < tl.x1; i++) {
            if (stop_asked(c)) {
                *stopped = 1;
                return evals;
            }
            uint32_t k = ((uint32_t)(((tl.y0 + j) % n) * n + (tl.x0 + i) % n) + c->shift) %
                         (uint32_t)(n * n);
            int x = tl.x0 + i, y = tl.y0 + j;
            if (r->start[k] == r->start[k + 1]) { /* no light on its lattice */
                for (int yy = y; yy < tl.y1; yy += n)
                    for (int xx = x; xx < tl.x1; xx += n)
                        r->raw[(size_t)yy * (size_t)gb->width + (size_t)xx] = iir_v3s(0.f);
                continue;
            }
            uint32_t cls = (uint32_t)(((tl.y0 + j) % n) * n + (tl.x0 + i) % n);
            uint32_t count = r->start[k + 1] - r->start[k];
            bool plain = c->gv.ref && !c->gv.glossy[(size_t)t * r->num_subsets + cls];
            uint32_t lead = plain ? c->prefix[k] : 0; /* VPLs summed from columns alone */
            if (lead == count) {
                int pixels = class_count(c, t, cls, tiles);
                evals += (uint64_t)pixels * count;
                *reused += (uint64_t)pixels * c->reads[k];
                columns_only(c, t, k, cls, pixels);
                continue;
            }
            uint32_t ord = c->gv.ref ? c->gv.ord[(size_t)t * (size_t)(n * n) + cls] : 0;
            if (plain) { /* the pixels from the columns' copy */
                int pixels = class_count(c, t, cls, tiles);
                for (int q0 = 0; q0 < pixels; q0 += IIR_BATCH) {
                    int m = pixels - q0 < IIR_BATCH ? pixels - q0 : IIR_BATCH;
                    fill_batch(c, cls, ord + (uint32_t)q0, m, b);
                    b->ord = ord + (uint32_t)q0;
                    evals += shade_batch(c, k, lead, b, st, reused);
                }
                continue;
            }
            while (collect(c, &tl, tl.x0 + i, n, &x, &y, b)) {
                b->ord = ord, ord += (uint32_t)b->m;
                evals += shade_batch(c, k, lead, b, st, reused);
            }
        }
    return evals;
}

/* The context of one frame's gather: subset shift, stop hook when stoppable, the kernel. */
static indirect_ctx make_ctx(const iir_renderer *r, const iir_indirect_params *p, uint32_t shift,
                             bool stoppable)
{
    indirect_ctx c = {.r = r,
                      .stop = stoppable ? r->stop : NULL,
                      .shift = shift,
                      .use_smap = p->visibility != IIR_VIS_RAYS,
                      .args = {p->clamp > 0.f ? p->clamp / r->diag2 : INFINITY, p->sm_bias, r->eps},
                      .kernel = iir_smap_kernel_for(r->isa),
                      .n = p->interleave,
                      .receivers = iir_render_receivers(r, p)};
    return c;
}

/* Each subset's VPLs that read their columns (c->reads), and the leading ones of them that are
 * not glossy (c->prefix: summed from the columns alone at non-glossy samples). */
static void count_readers(indirect_ctx *c)
{
    const iir_renderer *r = c->r;
    for (uint32_t k = 0; k < r->num_subsets && c->gv.ref; k++) {
        bool leading = true;
        for (uint32_t i = r->start[k]; i < r->start[k + 1]; i++) {
            leading &= c->gv.ref[i].mode == IIR_GV_READ && !r->vpl[i].glossy;
            c->prefix[k] += leading;
            c->reads[k] += c->gv.ref[i].mode == IIR_GV_READ;
        }
    }
}

bool iir_render_indirect(iir_renderer *r, const iir_indirect_params *p, uint32_t shift,
                         bool stoppable, iir_raystats *st, uint64_t *evals, uint64_t *reused)
{
    indirect_ctx c = make_ctx(r, p, shift, stoppable);
    int tiles = iir_indirect_tile_count(r->gb.width, r->gb.height), n = p->interleave;
    bool columns = c.use_smap && r->isa >= IIR_ISA_AVX2; /* the AVX2 kernel's (render_batch.h) */
    if (columns) {
        iir_gv_free(r->gv_mr), r->gv_mr = NULL; /* one set of columns at a time */
        c.gv = iir_gv_begin(r, &r->gv, &c.args, n, shift, c.receivers, NULL);
    }
    count_readers(&c);
    c.fresh = r->bg_serial != r->gb_serial;
    iir_raystats total = {0};
    int skipped = 0;
    uint64_t sum = 0, read = 0;
#pragma omp parallel reduction(+ : skipped, sum, read)
    {
        iir_raystats local = {0};
        pixel_batch b; /* on the stack: no allocation */
#pragma omp for schedule(dynamic, 1)
        for (int t = 0; t < tiles; t++) {
            if (skipped) continue; /* this thread's remaining tiles, without asking again */
            sum += indirect_tile(&c, n, t, tiles, &b, &local, &read, &skipped);
        }
#pragma omp critical(iir_indirect_rays)
        iir_raystats_add(&total, &local);
    }
    iir_raystats_add(st, &total);
    if (columns) iir_gv_end(r->gv, !skipped);
    if (!skipped) r->bg_serial = r->gb_serial;
    *evals += sum;
    *reused += read;
    return skipped > 0;
}

/* ---- one point: the clamp compensation's hits (render_compensate.c) ---- */

iir_vec3 iir_render_vpl_light_at(const iir_renderer *r, const iir_indirect_params *p, uint32_t k,
                                 iir_vec3 x, iir_vec3 n, int max_generation, iir_raystats *st)
{
    float g_max = p->clamp > 0.f ? p->clamp / r->diag2 : INFINITY;
    iir_vec3 E = iir_v3s(0.f);
    for (uint32_t i = r->start[k]; i < r->start[k + 1]; i++) {
        const iir_shade_vpl *v = &r->vpl[i];
        if (v->generation > max_generation) continue;
        iir_vpl_geometry g = iir_vpl_geometry_at(v, x, n, g_max);
        if (!g.lit) continue;
        float V = 1.f;
        iir_ray ray;
        if (p->visibility != IIR_VIS_RAYS) {
            iir_smap_probe probe = iir_smap_probe_make(v->smap, p->sm_bias, r->eps);
            V = iir_smap_probe_visibility(&probe, iir_dot(g.w, v->r), iir_dot(g.w, v->u), g.ci,
                                          sqrtf(g.d2), g.cx);
        } else if (lifted_ray(r->eps, v, x, n, &ray)) {
            V = iir_rt_occluded(r->rt, &ray, st, IIR_RAYS_VISIBILITY) ? 0.f : 1.f;
        }
        iir_vec3 power = v->glossy ? iir_mul(v->power, sender(v, x)) : v->power;
        E = iir_madd(E, power, g.G * V);
    }
    return E;
}

/* ---- multires: the VPL sum at the hierarchy's texels and level-0 pixels (multires.h's client)
 * ---- */

_Static_assert((int)IIR_MR_BATCH <= (int)IIR_BATCH, "a multires batch must fit a pixel batch");

/* Adds subset k's power G V to every sample of the batch (its E zeroed first), the batch being
 * work item `item`, which lattice class j unites (its columns' place: gv_columns.h); `plain`: no
 * sample is glossy, so the subset's leading readers are summed from their columns alone (the
 * kernel's sums: shade_batch's rule). */
static void apply_subset(const indirect_ctx *c, uint32_t k, uint32_t j, int item, bool plain,
                         int count, pixel_batch *b, iir_raystats *st)
{
    const iir_renderer *r = c->r;
    for (int q = 0; q < iir_batch_padded(count); q++) b->Ex[q] = b->Ey[q] = b->Ez[q] = 0.f;
    const iir_gv_ref *gv = c->gv.ref ? &c->gv.ref[r->start[k]] : NULL;
    uint32_t size = r->start[k + 1] - r->start[k], lead = gv && plain ? c->prefix[k] : 0;
    if (gv) b->ord = c->gv.ord[(size_t)item * r->num_subsets + j];
    if (lead)
        iir_columns_sum_avx2(&r->vpl[r->start[k]], gv, lead, b->ord, count, b->Ex, b->Ey, b->Ez);
    if (lead < size)
        apply_vpls(c, &r->vpl[r->start[k] + lead], gv ? gv + lead : NULL, size - lead, b, st);
}

/* Whether subset k is in the union of class (cx, cy) of an m x m lattice (coarse_samples). */
static inline bool in_union(uint32_t k, uint32_t n, uint32_t m, uint32_t cx, uint32_t cy)
{
    return k % n % m == cx && k / n % m == cy;
}

/* The samples as a batch (glossy pixels marked); false when none of them is glossy. */
static bool coarse_batch(const indirect_ctx *c, const iir_mr_sample *s, int count, pixel_batch *b)
{
    const iir_renderer *r = c->r;
    bool glossy = false;
    b->m = 0;
    for (int q = 0; q < count; q++) {
        bool pixel = s[q].pixel != IIR_MR_TEXEL; /* its index seeds a sphere's directions */
        batch_push(b, pixel ? s[q].pixel : (uint32_t)q, s[q].position, s[q].normal);
        if (pixel && r->gb.any_pbr) batch_mark_glossy(b, &r->gb, s[q].pixel, c->receivers);
        glossy |= iir_batch_is_glossy(b, b->m - 1);
    }
    while (b->m % IIR_BATCH_LANES) batch_push(b, 0, iir_v3s(0.f), iir_v3s(0.f)); /* never lit */
    b->m = count;
    return glossy;
}

/* Shades samples of class cls of an m x m lattice: the union U of the subsets k whose lattice
 * position is cls's mod m, subset k's estimate weighted |k| / |U| (so U's VPLs carry
 * Phi_i N / |U|: m = n is subset cls alone, m = 1 every VPL with its own flux). A union whose every
 * VPL is summed from its columns (no pixel of it can be glossy) skips the batch. */
static uint64_t coarse_samples(void *ctx, int item, int m, uint32_t cls, iir_mr_samples *src,
                               int count, iir_vec3 *E, iir_raystats *st)
{
    const indirect_ctx *c = ctx;
    const iir_renderer *r = c->r;
    uint32_t n = (uint32_t)c->n, cx = cls % (uint32_t)m, cy = cls / (uint32_t)m, union_size = 0;
    bool columns = c->gv.ref && !r->gb.any_pbr;
    for (uint32_t k = 0; k < r->num_subsets; k++) {
        if (!in_union(k, n, (uint32_t)m, cx, cy)) continue;
        uint32_t j = (k + c->shift) % r->num_subsets; /* apply_subset's */
        union_size += r->start[k + 1] - r->start[k];
        columns &= c->prefix[j] == r->start[j + 1] - r->start[j];
    }
    pixel_batch b;
    bool plain = true;
    if (!columns) plain = !coarse_batch(c, iir_mr_samples_read(src), count, &b);
    b.m = count;
    for (int q = 0; q < count; q++) E[q] = iir_v3s(0.f);
    for (uint32_t k = 0; k < r->num_subsets && union_size; k++) {
        uint32_t size = r->start[k + 1] - r->start[k];
        if (!size || !in_union(k, n, (uint32_t)m, cx, cy)) continue;
        apply_subset(c, (k + c->shift) % r->num_subsets, k, item, plain, count, &b, st);
        float w = (float)size / (float)union_size;
        for (int q = 0; q < count; q++) E[q] = iir_madd(E[q], iir_v3(b.Ex[q], b.Ey[q], b.Ez[q]), w);
    }
    return (uint64_t)count * union_size;
}

/* The pairs of a multires frame whose G V came from columns: each subset's reading VPLs times
 * the samples of its columns. */
static uint64_t reused_pairs(const indirect_ctx *c)
{
    const iir_renderer *r = c->r;
    uint64_t pairs = 0;
    for (uint32_t k = 0; k < r->num_subsets && c->gv.ref; k++)
        for (uint32_t i = r->start[k]; i < r->start[k + 1]; i++)
            pairs += c->gv.ref[i].mode == IIR_GV_READ ? c->gv.total[k] : 0;
    return pairs;
}

bool iir_render_indirect_coarse(iir_renderer *r, const iir_indirect_params *p, bool stoppable,
                                iir_raystats *st, uint64_t *evals, uint64_t *reused)
{
    indirect_ctx c = make_ctx(r, p, 0, stoppable); /* coarse texels: diffuse (coarse_samples) */
    uint64_t live = 0;
    for (uint32_t k = 0; k < r->num_subsets; k++)
        if (r->start[k] < r->start[k + 1]) live |= 1ull << k;
    bool columns = c.use_smap && r->isa >= IIR_ISA_AVX2; /* the AVX2 kernel's (render_batch.h) */
    if (columns) {
        iir_gv_free(r->gv), r->gv = NULL; /* one set of columns at a time */
        c.gv = iir_gv_begin(r, &r->gv_mr, &c.args, c.n, 0, c.receivers, r->mr);
    }
    count_readers(&c);
    bool stopped = iir_multires_shade_fine(r->mr, &r->gb, coarse_samples, &c, live, r->raw, c.stop,
                                           r->stop_ctx, st, evals) ||
                   iir_multires_shade(r->mr, coarse_samples, &c, live, NULL, c.stop, r->stop_ctx,
                                      st, evals); /* the filter phase upsamples (render_filter.c) */
    if (columns) iir_gv_end(r->gv_mr, !stopped);
    *reused += stopped ? 0 : reused_pairs(&c);
    return stopped;
}

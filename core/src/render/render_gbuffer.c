/* render_gbuffer.c -- the camera G-buffer: its storage and rendering it with 8-wide packets over
 * 4x2 pixel blocks (camera rays; a specular chain's rays one at a time), OpenMP over tiles; not
 * deciding when to re-render (render.c). Threads: each
 * tile writes only its own pixels; ray counters are per thread, summed once. */
#include <omp.h>
#include <stdlib.h>

#include "render_internal.h"
#include "specular.h"
#include "surface.h"

enum { BLOCK_W = 4, BLOCK_H = 2 }; /* one packet; divides IIR_RENDER_TILE */

void iir_gbuffer_free(iir_gbuffer *gb)
{
    free(gb->position);
    free(gb->normal);
    free(gb->albedo);
    free(gb->base);
    free(gb->mr);
    free(gb->emission);
    free(gb->depth);
    free(gb->prim);
    free(gb->through);
    free(gb->wo);
    free(gb->camera_t);
    iir_gbuffer empty = {0};
    *gb = empty;
}

iir_status iir_gbuffer_resize(iir_gbuffer *gb, int width, int height, iir_error *err)
{
    if (gb->width == width && gb->height == height && gb->position) return IIR_OK;
    iir_gbuffer_free(gb);
    size_t n = (size_t)width * (size_t)height;
    gb->position = malloc(sizeof(iir_vec3) * n);
    gb->normal = malloc(sizeof(iir_vec3) * n);
    gb->albedo = malloc(sizeof(iir_vec3) * n);
    gb->base = malloc(sizeof(iir_vec3) * n);
    gb->mr = malloc(sizeof(iir_vec3) * n);
    gb->emission = malloc(sizeof(iir_vec3) * n);
    gb->depth = malloc(sizeof(float) * n);
    gb->prim = malloc(sizeof(uint32_t) * n);
    gb->through = malloc(sizeof(iir_vec3) * n);
    gb->wo = malloc(sizeof(iir_vec3) * n);
    gb->camera_t = malloc(sizeof(float) * n);
    if (!gb->position || !gb->normal || !gb->albedo || !gb->base || !gb->mr || !gb->emission ||
        !gb->depth || !gb->prim || !gb->through || !gb->wo || !gb->camera_t) {
        iir_gbuffer_free(gb);
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for a %dx%d G-buffer", width, height);
    }
    gb->width = width;
    gb->height = height;
    return IIR_OK;
}

/* Pixel i sees nothing (background, or a chain that left the scene or ended on a specular
 * surface): black, no surface; camera_t: the camera ray's first hit. */
static void store_none(iir_gbuffer *gb, size_t i, float camera_t)
{
    iir_vec3 zero = iir_v3s(0.f);
    gb->prim[i] = IIR_NO_HIT;
    gb->position[i] = zero;
    gb->normal[i] = zero;
    gb->albedo[i] = zero;
    gb->base[i] = zero;
    gb->mr[i] = iir_v3(0.f, -1.f, 0.f);
    gb->emission[i] = zero;
    gb->depth[i] = INFINITY;
    gb->camera_t[i] = camera_t;
    gb->through[i] = zero;
    gb->wo[i] = zero;
}

/* Whether a chain goes on at sf: a mirror, glass, or a metal smoother than IIR_MIRROR_ROUGHNESS
 * (metallic above one half: its reflection carries most of its light; a smooth dielectric is
 * gathered where it is, its diffuse base showing, its few percent of reflection left out). */
static bool is_specular(const iir_surface *sf)
{
    return sf->kind == IIR_MATERIAL_MIRROR || sf->kind == IIR_MATERIAL_GLASS ||
           (sf->kind == IIR_MATERIAL_METAL_ROUGH && sf->roughness < IIR_MIRROR_ROUGHNESS &&
            sf->metallic > 0.5f);
}

/* One link of a chain at specular surface sf, met along unit V: the ray on (lifted off the side it
 * leaves from) and the weight it passes back: a mirror's reflection (its `specular`), glass's
 * stronger branch (F, or 1 - F tinted; the other is left out), a near-mirror metal's reflection
 * about its shading normal (Schlick's F). False when nothing goes on. */
static bool chain_link(const iir_surface *sf, iir_vec3 V, float eps, iir_ray *ray, iir_vec3 *w)
{
    iir_vec3 d;
    if (sf->kind == IIR_MATERIAL_MIRROR) {
        d = iir_reflect(V, sf->n), *w = sf->specular;
    } else if (sf->kind == IIR_MATERIAL_GLASS) {
        iir_glass_split g = iir_glass_at(V, sf->n, sf->ior);
        bool refract = g.has_t && 1.f - g.F >= g.F;
        d = refract ? g.wt : g.wr;
        *w = refract ? iir_scale(sf->specular, 1.f - g.F) : iir_v3s(g.F);
    } else if (!iir_surface_mirror_reflection(sf, V, &d, w)) {
        return false;
    }
    iir_vec3 side = iir_dot(d, sf->n) < 0.f ? iir_neg(sf->n) : sf->n;
    *ray = iir_make_ray(iir_madd(sf->p, side, eps), d, 0.f, INFINITY);
    return !iir_is_black(*w);
}

/* Writes pixel i from its camera ray's hit (or background): with depth > 0, a specular surface's
 * chain followed to the first rough surface (at most depth links). */
static void store(iir_gbuffer *gb, size_t i, const iir_scene *scene, const iir_rt *rt,
                  const iir_hit *first, iir_vec3 dir, float spread, int depth, iir_raystats *st)
{
    if (first->prim == IIR_NO_HIT) {
        store_none(gb, i, INFINITY);
        return;
    }
    iir_hit hit = *first;
    iir_vec3 wo = iir_neg(dir), through = iir_v3s(1.f);
    /* textures filtered over the pixel's footprint: a ray cone of the pixel's spread angle */
    iir_surface sf = iir_surface_at_cone(scene, &hit, wo, spread * hit.t * iir_length(dir));
    float eps = iir_rt_epsilon(rt), length = first->t; /* dir is unit (iir_camera_dir) */
    for (int link = 0; link < depth && is_specular(&sf); link++) {
        iir_ray ray;
        iir_vec3 w;
        if (!chain_link(&sf, iir_neg(wo), eps, &ray, &w) ||
            !iir_rt_intersect(rt, &ray, &hit, st, IIR_RAYS_BOUNCE)) {
            store_none(gb, i, first->t);
            return;
        }
        through = iir_mul(through, w);
        length += hit.t;
        wo = iir_neg(ray.dir);
        sf = iir_surface_at(scene, &hit, wo);
    }
    if (depth > 0 && is_specular(&sf)) {
        store_none(gb, i, first->t); /* the chain is longer than depth */
        return;
    }
    gb->prim[i] = hit.prim;
    gb->position[i] = sf.p;
    gb->normal[i] = sf.sn;
    gb->albedo[i] = sf.albedo;
    bool pbr = sf.kind == IIR_MATERIAL_METAL_ROUGH;
    gb->base[i] = pbr ? sf.base : sf.albedo;
    gb->mr[i] = pbr ? iir_v3(sf.metallic, sf.roughness, sf.specular_f0) : iir_v3(0.f, -1.f, 0.f);
    gb->emission[i] = iir_mul(through, iir_surface_Le(&sf, wo));
    gb->depth[i] = length;
    gb->camera_t[i] = first->t;
    gb->through[i] = through;
    gb->wo[i] = wo;
}

/* One packet: the BLOCK_W x BLOCK_H pixels at (x0, y0) that lie inside the image. */
static void render_block(iir_gbuffer *gb, const iir_scene *scene, const iir_rt *rt,
                         const iir_camera_frame *cf, iir_vec2 jitter, int depth, int x0, int y0,
                         iir_raystats *st)
{
    iir_ray8 rays;
    iir_vec3 dirs[8];
    for (int k = 0; k < 8; k++) {
        int x = x0 + k % BLOCK_W, y = y0 + k / BLOCK_W;
        dirs[k] = iir_camera_dir(cf, (float)x + jitter.x, (float)y + jitter.y);
        rays.ox[k] = cf->origin.x, rays.oy[k] = cf->origin.y, rays.oz[k] = cf->origin.z;
        rays.dx[k] = dirs[k].x, rays.dy[k] = dirs[k].y, rays.dz[k] = dirs[k].z;
        rays.tnear[k] = 0.f;
        rays.tfar[k] = INFINITY;
        rays.valid[k] = x < gb->width && y < gb->height;
    }
    iir_hit hits[8];
    iir_rt_intersect8(rt, &rays, hits, st, IIR_RAYS_CAMERA);
    for (int k = 0; k < 8; k++) {
        if (!rays.valid[k]) continue;
        int x = x0 + k % BLOCK_W, y = y0 + k / BLOCK_W;
        store(gb, (size_t)y * (size_t)gb->width + (size_t)x, scene, rt, &hits[k], dirs[k],
              2.f * cf->tan_half_y / (float)cf->height, depth, st);
    }
}

/* The flags that let shading skip reading what every pixel has the same of. */
static void summarize(iir_gbuffer *gb)
{
    gb->any_chain = gb->any_pbr = gb->any_emission = false;
    for (size_t i = 0, n = (size_t)gb->width * (size_t)gb->height; i < n; i++) {
        iir_vec3 t = gb->through[i];
        gb->any_chain |= gb->prim[i] != IIR_NO_HIT && (t.x != 1.f || t.y != 1.f || t.z != 1.f);
        gb->any_pbr |= gb->mr[i].y >= 0.f;
        gb->any_emission |= !iir_is_black(gb->emission[i]);
    }
}

bool iir_gbuffer_render(iir_gbuffer *gb, const iir_scene *scene, const iir_rt *rt,
                        const iir_camera_frame *cf, iir_vec2 jitter, int specular_depth,
                        const iir_stop *stop, iir_raystats *st)
{
    int tiles = iir_tile_count(gb->width, gb->height, IIR_RENDER_TILE);
    iir_raystats total = {0};
    bool stopped = false;
#pragma omp parallel
    {
        iir_raystats local = {0};
#pragma omp for schedule(dynamic, 1)
        for (int t = 0; t < tiles; t++) {
            bool quit;
#pragma omp atomic read
            quit = stopped;
            if (quit) continue;
            if (iir_stop_now(stop)) {
#pragma omp atomic write
                stopped = true;
                continue;
            }
            iir_tile tl = iir_tile_at(gb->width, gb->height, IIR_RENDER_TILE, t);
            for (int y = tl.y0; y < tl.y1; y += BLOCK_H)
                for (int x = tl.x0; x < tl.x1; x += BLOCK_W)
                    render_block(gb, scene, rt, cf, jitter, specular_depth, x, y, &local);
        }
#pragma omp critical(iir_gbuffer_rays)
        iir_raystats_add(&total, &local);
    }
    iir_raystats_add(st, &total);
    if (!stopped) summarize(gb);
    return !stopped;
}

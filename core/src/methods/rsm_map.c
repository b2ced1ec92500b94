/* rsm_map.c -- rendering one light's reflective shadow map over its VPL domain, projecting a
 * receiver into it and gathering from it (rsm_map.h), and the gather's parameter table. One
 * closest-hit ray per texel; a map is rebuilt every frame. */
#include "rsm_map.h"

#include <math.h>
#include <stddef.h>
#include <stdlib.h>

#include "iir/rng.h"
#include "iir/vplsets.h"
#include "method_internal.h"

#include "../render/render_internal.h"
#include "../vpls/vpl_lobe.h"
#include "surface.h"

bool rsm_map_alloc(rsm_map *m, int res)
{
    m->texel = calloc((size_t)res * (size_t)res, sizeof *m->texel);
    m->res = m->texel ? res : 0;
    return m->texel != NULL;
}

void rsm_map_free(rsm_map *m)
{
    free(m->texel);
    m->texel = NULL;
    m->res = 0;
}

/* Straight down: a point light's map is centred on what lies below it. */
static iir_frame down_frame(void)
{
    return (iir_frame){
        .r = iir_v3(1.f, 0.f, 0.f), .u = iir_v3(0.f, 0.f, 1.f), .f = iir_v3(0.f, -1.f, 0.f)};
}

/* The domain point of map coordinates t (|t| < 1). */
static void domain_point(const rsm_map *m, iir_vec2 t, double s[3])
{
    if (m->dom.shape == IIR_DOMAIN_SPHERE) {
        iir_vec3 w =
            iir_normalize(iir_cap_disk_to_dir(&m->sphere, iir_v2(t.x * m->half, t.y * m->half)));
        s[0] = w.x, s[1] = w.y, s[2] = w.z;
        return;
    }
    s[0] = (double)(t.x * m->half), s[1] = (double)(t.y * m->half), s[2] = 0.0;
}

/* What the light emits per unit of its domain's profile: an area light's radiance at texel k's
 * point of it (its emitter stratum), any other light's intensity. */
static iir_vec3 emitter_radiance(const rsm_map *m, uint32_t k)
{
    const iir_light *l = &m->light;
    if (iir_light_is_delta(l)) return l->intensity;
    return iir_light_emission_at(l, iir_domain_emitter_stratum(&m->dom, k));
}

/* Texel k at map coordinates t: the surface the light's ray meets there, with its reflected flux.
 */
static iir_vpl texel_at(const rsm_map *m, uint32_t k, iir_vec2 t, const iir_scene *scene,
                        const iir_rt *rt, iir_raystats *st)
{
    iir_vpl v = {.id = k, .null_sample = true};
    if (t.x * t.x + t.y * t.y >= 1.f) return v;
    double s[3];
    domain_point(m, t, s);
    iir_light_domain at = iir_domain_at_emitter(&m->dom, iir_domain_emitter_stratum(&m->dom, k));
    iir_vec3 o, w;
    iir_domain_ray(&at, s, &o, &w);
    iir_ray ray = iir_make_ray(o, w, 0.f, INFINITY);
    iir_hit hit;
    if (!iir_rt_intersect(rt, &ray, &hit, st, IIR_RAYS_VPL)) return v;
    iir_surface sf = iir_surface_at(scene, &hit, iir_neg(w));
    if (!iir_is_black(sf.Le)) return v;
    float A = iir_sqr(2.f * m->half / (float)m->res);
    float emitted = iir_domain_profile(&m->dom, s) * A;
    v.null_sample = false;
    v.position = sf.p;
    v.lobe = iir_vpl_lobe_at(&sf, &v.albedo);
    v.wi = iir_neg(w);
    v.flux = iir_scale(iir_mul(emitter_radiance(m, k), v.albedo), emitted);
    iir_vpl_set_normal(&v, sf.ns);
    return v;
}

iir_status rsm_map_render(rsm_map *m, const iir_light *l, const iir_scene *scene, const iir_rt *rt,
                          const iir_stop *stop, iir_raystats *st, iir_error *err)
{
    m->light = *l;
    iir_status s = iir_light_domain_make(&m->light, &m->dom, err);
    if (s != IIR_OK) return s;
    bool sphere = m->dom.shape == IIR_DOMAIN_SPHERE;
    m->sphere = down_frame();
    m->half = sphere ? 2.f : (float)m->dom.R;
    const int res = m->res;
    uint32_t lit = 0, in_disk = 0, glossy = 0;
    iir_raystats rays = {0};
    bool stopped = false;
#pragma omp parallel for schedule(dynamic, 4) reduction(+ : lit, in_disk, glossy)
    for (int y = 0; y < res; y++) {
        bool quit;
#pragma omp atomic read
        quit = stopped;
        if (quit) continue;
        if (iir_stop_now(stop)) {
#pragma omp atomic write
            stopped = true;
        }
        iir_raystats local = {0};
        for (int x = 0; x < res; x++) {
            uint32_t k = (uint32_t)(y * res + x);
            iir_vec2 t = iir_v2(2.f * ((float)x + 0.5f) / (float)res - 1.f,
                                2.f * ((float)y + 0.5f) / (float)res - 1.f);
            m->texel[k] = texel_at(m, k, t, scene, rt, &local);
            lit += !m->texel[k].null_sample;
            glossy += m->texel[k].lobe.glossy;
            in_disk += t.x * t.x + t.y * t.y < 1.f;
        }
#pragma omp critical(rsm_rays)
        iir_raystats_add(&rays, &local);
    }
    m->lit = lit;
    m->glossy = glossy > 0;
    m->in_disk = in_disk;
    if (st) iir_raystats_add(st, &rays);
    return stopped ? iir_fail(err, IIR_ERR_INTERRUPTED, "frame stopped early") : IIR_OK;
}

iir_vec2 rsm_map_project(const rsm_map *m, iir_vec3 x)
{
    if (m->dom.shape == IIR_DOMAIN_SPHERE) {
        iir_vec3 w = iir_normalize(iir_sub(x, m->dom.p));
        iir_vec2 s = iir_cap_dir_to_disk(&m->sphere, w);
        return iir_v2(s.x / m->half, s.y / m->half);
    }
    double s[3];
    iir_domain_locate(&m->dom, x, s); /* s is its point even where it is not inside */
    return iir_v2((float)s[0] / m->half, (float)s[1] / m->half);
}

/* ---- the maps of a frame ---- */

iir_status rsm_maps_render(rsm_map *maps, uint32_t *num_maps, int res, const iir_light *lights,
                           uint32_t num_lights, const iir_scene *scene, const iir_rt *rt,
                           const char *method, const iir_stop *stop, iir_frame_stats *stats,
                           iir_error *err)
{
    uint32_t n = num_lights < IIR_VPLSETS_MAX_LIGHTS ? num_lights : IIR_VPLSETS_MAX_LIGHTS;
    for (uint32_t l = *num_maps; l < n; l++) {
        if (!maps[l].texel && !rsm_map_alloc(&maps[l], res))
            return iir_fail(err, IIR_ERR_NOMEM, "%s: out of memory for the light's map", method);
        *num_maps = l + 1;
    }
    *num_maps = n;
    stats->vpl = (iir_vpl_counts){.regenerated = 1};
    for (uint32_t l = 0; l < n; l++) {
        iir_status st = rsm_map_render(&maps[l], &lights[l], scene, rt, stop, &stats->rays, err);
        if (st != IIR_OK) return st;
        stats->vpl.count += maps[l].in_disk;
        stats->vpl.inserted += maps[l].in_disk;
        stats->vpl.null_samples += maps[l].in_disk - maps[l].lit;
    }
    return IIR_OK;
}

uint32_t rsm_maps_dropped(const char *method, const iir_scene *scene, const iir_light *lights,
                          uint32_t num_lights, iir_dropped *out, uint32_t max)
{
    uint32_t n = 0;
    for (uint32_t i = IIR_VPLSETS_MAX_LIGHTS; i < num_lights; i++)
        iir_dropped_add(out, max, &n, method, "light", lights[i].name,
                        "light %u: its indirect light is left out, as %s renders maps for %u "
                        "lights at most (its direct light is rendered)",
                        i + 1, method, IIR_VPLSETS_MAX_LIGHTS);
    return n + iir_dropped_emitters(scene, method, n < max ? out + n : NULL, n < max ? max - n : 0);
}

/* ---- gathering ---- */

static const iir_param RSM_ROWS[] = {
    {"rsm_res", IIR_PARAM_INT, offsetof(iir_rsm_options, res), 64, 4, 1024, 256, NULL, "texels",
     "reflective shadow map resolution per light (res^2 rays per light per frame)",
     IIR_PARAM_RESTART},
    {"rsm_samples", IIR_PARAM_INT, offsetof(iir_rsm_options, samples), 100, 1, 4096, 1024, NULL,
     "texels", "texels gathered per pixel and light", IIR_PARAM_LIVE},
    /* of 0.3, 0.6, 1 and 2 the Cornell box orbit's error against pt was lowest at 2 (relMSE
       0.0195, 0.0131, 0.0052, 0.0019 at 100 samples), and so was the conference room's: light
       lands far from where it came, and the pattern still favours the texels near the centre */
    {"rsm_radius", IIR_PARAM_FLOAT, offsetof(iir_rsm_options, radius), 2, 0.001, 2, 0, NULL, "",
     "gather radius around a pixel's projection, in map half-widths (2 = the whole map)",
     IIR_PARAM_LIVE},
};
const iir_param_table iir_rsm_table = {"reflective shadow maps (rsm, hier)", RSM_ROWS,
                                       sizeof RSM_ROWS / sizeof RSM_ROWS[0], NULL};

bool rsm_pattern_build(rsm_pattern *p, const iir_rsm_options *o, float g_max)
{
    int m = o->samples;
    float *s = realloc(p->s, sizeof(float) * 3 * (size_t)m);
    if (!s) return false;
    p->s = s;
    p->m = m;
    p->g_max = g_max;
    float r_max = o->radius, A_t = iir_sqr(2.f / (float)o->res);
    for (int k = 0; k < m; k++) {
        float r = r_max * ((float)k + 0.5f) / (float)m;
        float phi = 2.f * (float)M_PI * iir_radical_inverse(2, (uint32_t)k);
        s[3 * k] = r * sinf(phi);
        s[3 * k + 1] = r * cosf(phi);
        s[3 * k + 2] = 2.f * (float)M_PI * r_max * r / ((float)m * A_t);
    }
    return true;
}

void rsm_pattern_free(rsm_pattern *p)
{
    free(p->s);
    p->s = NULL;
    p->m = 0;
}

rsm_receiver rsm_receiver_pixel(const iir_gbuffer *gb, size_t i)
{
    rsm_receiver q = rsm_receiver_at(gb->position[i], gb->normal[i]);
    if (!gb->any_pbr || !iir_gb_glossy(gb, i, IIR_RECEIVER_GLOSSY)) return q;
    q.glossy = true;
    q.bsdf = iir_gb_bsdf(gb, i);
    q.wo = gb->wo[i];
    q.demod_pi = iir_pi_over(iir_gb_demod(gb, i, IIR_RECEIVER_GLOSSY));
    return q;
}

/* G_k s_k r_k of texel v toward receiver q (w: unit, from v to q), its peak clamped to g_max. */
static iir_vec3 lobes(const iir_vpl *v, const rsm_receiver *q, iir_vec3 w, float G, float g_max)
{
    iir_vec3 f = iir_v3s(G);
    if (q->glossy) f = iir_mul(f, iir_mul(iir_bsdf_f(&q->bsdf, q->wo, iir_neg(w)), q->demod_pi));
    if (v->lobe.glossy) {
        iir_bsdf b = iir_vpl_lobe_bsdf(v);
        f = iir_mul(f, iir_mul(iir_bsdf_f(&b, w, v->wi), iir_pi_over(v->albedo)));
    }
    float peak = fmaxf(f.x, fmaxf(f.y, f.z));
    return peak > g_max ? iir_scale(f, g_max / peak) : f;
}

/* The gather's sum over the pattern; `diffuse` (a constant where it is inlined) when neither the
 * receiver nor any texel is glossy. */
static inline iir_vec3 gather_sum(const rsm_pattern *p, const rsm_map *m, const rsm_receiver *q,
                                  const bool diffuse)
{
    iir_vec2 c = rsm_map_project(m, q->x);
    const int res = m->res;
    const float half_res = 0.5f * (float)res;
    iir_vec3 sum = iir_v3s(0.f);
    for (int k = 0; k < p->m; k++) {
        const float *d = &p->s[3 * k];
        float fx = (c.x + d[0] + 1.f) * half_res, fy = (c.y + d[1] + 1.f) * half_res;
        if (!(fx >= 0.f && fy >= 0.f && fx < (float)res && fy < (float)res)) continue;
        const iir_vpl *v = &m->texel[(int)fy * res + (int)fx];
        if (v->null_sample) continue;
        iir_vec3 to = iir_sub(q->x, v->position);
        float d2 = iir_dot(to, to);
        if (!(d2 > 0.f)) continue;
        float cos_v = iir_dot(v->normal, to), cos_x = -iir_dot(q->n, to);
        if (cos_v <= 0.f || cos_x <= 0.f) continue;
        float G = cos_v * cos_x / (d2 * d2);
        if (diffuse || (!q->glossy && !v->lobe.glossy)) {
            sum = iir_madd(sum, v->flux, d[2] * fminf(G, p->g_max));
            continue;
        }
        iir_vec3 f = lobes(v, q, iir_scale(to, 1.f / sqrtf(d2)), G, p->g_max);
        sum = iir_add(sum, iir_scale(iir_mul(v->flux, f), d[2]));
    }
    return iir_scale(sum, 1.f / (float)M_PI);
}

iir_vec3 rsm_gather_map(const rsm_pattern *p, const rsm_map *m, const rsm_receiver *q)
{
    return !q->glossy && !m->glossy ? gather_sum(p, m, q, true) : gather_sum(p, m, q, false);
}

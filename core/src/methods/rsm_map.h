/* rsm_map.h -- the reflective shadow map of one light (Dachsbacher & Stamminger 2005), internal to
 * the rsm method: what the light sees, texel by texel, as the surface point, its normal and the
 * flux it reflects. Not the gathering (rsm.c).
 *
 * The map is a res x res grid over map coordinates t in [-1, 1]^2, laid over the light's VPL
 * domain (light_domain.h) so that a texel is comparable with an iir VPL: a disk domain (spots,
 * sun, area light) is the disk of radius `half` = R, s = half t; a point light's sphere is
 * Lambert's azimuthal equal-area map about straight down, whose disk of radius 2 holds the whole
 * sphere (half = 2, and disk area equals solid angle). Texel k (centre t_k) is lit by the light's
 * ray at s_k = half t_k (an area light's from its emitter stratum k, as iir's VPL k) and reflects
 *     Phi_k = rho(x_k) I profile(s_k) A,    A = (2 half / res)^2,
 * the flux a domain cell of area A carries (I the light's `intensity`); the texels tile the domain,
 * so they carry the light's whole flux less what escapes. A texel whose centre lies outside the
 * disk, whose ray escapes, or hits an emitter is a null sample (no flux). */
#ifndef IIR_RSM_MAP_H
#define IIR_RSM_MAP_H

#include "iir/light.h"
#include "iir/method.h"
#include "iir/light_domain.h"
#include "iir/render.h"
#include "iir/bsdf.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "iir/vpl.h"

typedef struct rsm_map {
    iir_light light;      /* the light the map was rendered for (a copy: dom refers to it) */
    iir_light_domain dom; /* its domain; an area light's at the emitter's centre */
    iir_frame sphere;     /* point light: the equal-area map is about sphere.f (straight down) */
    float half;           /* the map's half-width in domain units */
    int res;
    iir_vpl *texel;   /* res * res, row-major from t = (-1, -1); id = texel index */
    uint32_t in_disk; /* texels whose centre lies on the domain's disk (all for a sphere) */
    uint32_t lit;     /* texels that are not null samples */
    bool glossy;      /* some texel's lobe is glossy */
} rsm_map;

/* Allocates the texels of a res x res map; false when out of memory. */
bool rsm_map_alloc(rsm_map *m, int res);
void rsm_map_free(rsm_map *m);

/* Renders map m (allocated) for light l with one Embree ray per texel (OpenMP over rows, stop
 * polled per row: IIR_ERR_INTERRUPTED with m unusable). IIR_ERR_INVALID for a light that fails
 * iir_light_validate. */
iir_status rsm_map_render(rsm_map *m, const iir_light *l, const iir_scene *scene, const iir_rt *rt,
                          const iir_stop *stop, iir_raystats *st, iir_error *err);

/* The maps of a frame's lights (up to IIR_VPLSETS_MAX_LIGHTS; maps[] holds that many): allocates
 * res^2 texels for lights not seen before, renders every map, and counts the texels on the
 * domains as the frame's VPLs (*num_maps: the maps in use). `method` names the caller in errors. */
iir_status rsm_maps_render(rsm_map *maps, uint32_t *num_maps, int res, const iir_light *lights,
                           uint32_t num_lights, const iir_scene *scene, const iir_rt *rt,
                           const char *method, const iir_stop *stop, iir_frame_stats *stats,
                           iir_error *err);

/* iir_method_dropped's entries of a method that renders maps for the first lights only (rsm,
 * hier): the lights beyond them, then the emissive materials. */
uint32_t rsm_maps_dropped(const char *method, const iir_scene *scene, const iir_light *lights,
                          uint32_t num_lights, iir_dropped *out, uint32_t max);

/* Map coordinates of world point x: where the light's ray towards x crosses the map (outside
 * [-1, 1]^2 for points the light cannot see along its domain). */
iir_vec2 rsm_map_project(const rsm_map *m, iir_vec3 x);

/* ---- gathering (the pattern of rsm.c's top comment) ---- */

/* The parameters a gather takes, in every method that gathers from maps (table iir_rsm_table). */
typedef struct iir_rsm_options {
    int res;      /* map resolution */
    int samples;  /* M, per pixel and light */
    float radius; /* r_max, in map half-widths */
} iir_rsm_options;

/* M samples around a projection and their inverse-density weights, with the geometry term's
 * bound. */
typedef struct rsm_pattern {
    float *s; /* M x (dx, dy, w) */
    int m;
    float g_max; /* clamp / D^2, or INFINITY */
} rsm_pattern;

/* (Re)builds the pattern for o (false when out of memory: the pattern is then unchanged). */
bool rsm_pattern_build(rsm_pattern *p, const iir_rsm_options *o, float g_max);
void rsm_pattern_free(rsm_pattern *p);

/* Who gathers: a point and its unit normal, and for a glossy receiver (a G-buffer pixel that
 * iir_gb_glossy says reflects by its full BSDF) that BSDF, the direction toward the viewer and
 * pi / demod (demod: iir_gb_demod, what the gather's result is multiplied by over pi). */
typedef struct rsm_receiver {
    iir_vec3 x, n;
    bool glossy;
    iir_bsdf bsdf;
    iir_vec3 wo, demod_pi;
} rsm_receiver;

/* A diffuse receiver at x (normal n); its glossy fields are left unset. */
static inline rsm_receiver rsm_receiver_at(iir_vec3 x, iir_vec3 n)
{
    rsm_receiver q;
    q.x = x, q.n = n, q.glossy = false;
    return q;
}

/* G-buffer pixel i as a receiver (glossy when iir_gb_glossy says so at receiver_bsdf = glossy;
 * the gather's result is then multiplied by iir_gb_demod over pi). */
rsm_receiver rsm_receiver_pixel(const iir_gbuffer *gb, size_t i);

/* sum_k w_k (Phi_k / pi) min(G_k s_k r_k, g_max) over map m's texels around receiver q: the
 * demodulated one-bounce light (times demod / pi it is radiance). s_k is a glossy texel's lobe
 * toward q relative to a diffuse texel (f(wi_k, w) pi / albedo_k), r_k a glossy receiver's
 * (f(wo, w) pi / demod), 1 for diffuse ones; the clamp bounds the product as rendering does. */
iir_vec3 rsm_gather_map(const rsm_pattern *p, const rsm_map *m, const rsm_receiver *q);

#endif

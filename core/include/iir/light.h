/* light.h -- punctual lights (spot with a cosine lobe inside a cone, isotropic point), the spot's
 * disk domain (DESIGN section 5), and the light set that samples punctual lights and emissive
 * triangles (quad area lights) for next-event estimation. Not VPLs.
 *
 * Spot: frame (p; r, u, f), half-angle alpha in (0, 90] degrees, I(w) = I0 cos(theta) inside the
 * cone, optionally faded to zero over an edge of `smooth` radians just inside the cone. The disk
 * domain has radius R = sin(alpha); direction w maps to s = (w.r, w.u) and back with
 * w = s.x r + s.y u + sqrt(1 - |s|^2) f. Uniform density on the disk is exactly the cosine lobe,
 * so disk area is proportional to emitted flux: Phi = pi I0 R^2 (hard edge). */
#ifndef IIR_LIGHT_H
#define IIR_LIGHT_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/status.h"
#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

struct iir_scene;

typedef enum iir_light_type { IIR_LIGHT_POINT, IIR_LIGHT_SPOT } iir_light_type;

typedef struct iir_light {
    iir_light_type type;
    char name[64];
    iir_vec3 position;
    iir_vec3 direction; /* spot: unit axis f */
    iir_vec3 up;        /* spot: hint for the disk's u axis (default +y) */
    float cone_angle;   /* spot: half-angle alpha, radians, (0, pi/2] */
    float smooth;       /* spot: width of the fading edge, radians, [0, alpha] */
    iir_vec3 intensity; /* W/sr, RGB: point: isotropic; spot: I0 on the axis */
} iir_light;

/* ---- description and validity ---- */

/* IIR_ERR_INVALID naming the light and the field for NaN/Inf, negative intensity, a zero
 * direction, a cone angle outside (0, 90] degrees or a smooth edge wider than the cone. */
iir_status iir_light_validate(const iir_light *light, iir_error *err);

/* The light a user moves in scene (the daemon's session light, an animation script's light track):
 * the first spot, else the first light; for a scene without lights a white spot made up just under
 * the middle of the scene's top, aimed down (60 degree half-angle, intensity the bounds' diagonal
 * squared, name "spot"). Writes it to *out; returns its index in scene->lights, or
 * scene->num_lights for the made-up spot. */
uint32_t iir_scene_moved_light(const struct iir_scene *scene, iir_light *out);

/* Total emitted flux (W, RGB). */
iir_vec3 iir_light_flux(const iir_light *light);

/* Radiant intensity (W/sr) emitted towards the unit world direction w (pointing away from the
 * light). */
iir_vec3 iir_light_intensity(const iir_light *light, iir_vec3 w);

/* A light prepared for evaluating many directions: the spot's frame and disk radii are computed
 * once (iir_light_intensity recomputes them per call). Valid while *light is unchanged. */
typedef struct iir_light_eval {
    const iir_light *light;
    iir_frame frame;
    float R, R_in; /* disk radius sin(alpha) and where the smooth edge starts */
} iir_light_eval;

iir_light_eval iir_light_prepare(const iir_light *light);
iir_vec3 iir_light_eval_intensity(const iir_light_eval *e, iir_vec3 w);

/* ---- the spot's disk domain ---- */

iir_frame iir_spot_frame(const iir_light *spot);
static inline float iir_spot_radius(const iir_light *spot)
{
    return sinf(spot->cone_angle);
}

/* Disk coordinates of unit direction w; |s| <= 1 for any w in the front hemisphere. */
static inline iir_vec2 iir_spot_dir_to_disk(const iir_frame *fr, iir_vec3 w)
{
    return iir_v2(iir_dot(w, fr->r), iir_dot(w, fr->u));
}

/* Unit direction for disk point s (|s| <= 1). */
static inline iir_vec3 iir_spot_disk_to_dir(const iir_frame *fr, iir_vec2 s)
{
    float z = iir_safe_sqrt(1.f - s.x * s.x - s.y * s.y);
    return iir_add(iir_add(iir_scale(fr->r, s.x), iir_scale(fr->u, s.y)), iir_scale(fr->f, z));
}

/* Fraction of I0 cos(theta) emitted at disk radius rho (1 inside, smoothstep across the edge, 0
 * outside). */
float iir_spot_falloff(const iir_light *spot, float rho);

/* ---- emission sampling (light paths: IR, VPLs) ---- */

typedef struct iir_light_ray {
    iir_vec3 origin, dir;
    iir_vec3 beta; /* flux carried by this sample: Le cos / pdf, so E[beta] = Phi */
} iir_light_ray;

/* Spot: uniform on the disk (the cosine lobe); point: uniform on the sphere. u in [0,1)^2. */
iir_light_ray iir_light_sample_emission(const iir_light *light, iir_vec2 u);

/* ---- the light set: punctual lights + emissive triangles, for next-event estimation ---- */

typedef struct iir_lightset iir_lightset;

/* Builds the set from the given punctual lights and the scene's emissive triangles, choosing lights
 * in proportion to flux (luminance). The lights array is copied. Returns NULL on allocation
 * failure. */
iir_lightset *iir_lightset_create(const struct iir_scene *scene, const iir_light *lights,
                                  uint32_t num_lights);
void iir_lightset_destroy(iir_lightset *set);
bool iir_lightset_empty(const iir_lightset *set);
/* True when the scene has emissive triangles (BSDF-sampled rays can then find light). */
bool iir_lightset_has_area_lights(const iir_lightset *set);

typedef struct iir_light_sample {
    iir_vec3 wi;   /* unit direction from the shading point to the light */
    float dist;    /* distance to the sampled point */
    iir_vec3 Li;   /* incident radiance (area) or I/d^2 (punctual), not divided by pdf */
    float pdf;     /* solid-angle pdf (area) or the pmf of choosing a punctual light */
    bool is_delta; /* punctual: no MIS */
} iir_light_sample;

/* Samples one light for shading point x. u_pick chooses the light, u a point on it. pdf == 0 means
 * nothing was sampled (no lights, or the point faces away). */
iir_light_sample iir_lightset_sample(const iir_lightset *set, iir_vec3 x, float u_pick, iir_vec2 u);

/* Solid-angle pdf with which iir_lightset_sample would have chosen the point on emissive triangle
 * `prim` seen from x along unit direction wi at distance dist (for MIS when a BSDF ray hits it). */
float iir_lightset_pdf_area(const iir_lightset *set, uint32_t prim, iir_vec3 wi, float dist);

#ifdef __cplusplus
}
#endif
#endif

/* light_domain.h -- a light's VPL domain (DESIGN section 5): the set on which the incremental step
 * spreads one light's VPLs, the map between a domain point and the ray the light emits there, the
 * flux a unit of domain area carries, and the domain's boundary. Not the triangulation of the
 * points (tri.h, stri.h) and not how VPLs are kept (incremental.h).
 *
 * A domain point s is three doubles: (x, y, 0) on a disk of radius R centred at the origin, a unit
 * vector on the sphere. Each light has the domain its emission makes uniform or nearly so:
 *
 *   light        shape   s of a world point x                 R               flux per area
 *   cosine spot  disk    (w.r, w.u), w = (x - p) / |x - p|      sin(alpha)      I0 falloff(|s|)
 *   glTF spot    disk    equal-area (Lambert) map of w          2 sin(alpha/2)  I0 t^2(theta)
 *   point        sphere  w                                      1               I0
 *   sun          disk    ((x - c).r, (x - c).u)                 radius          E
 *   area         disk    (w.r, w.u), w = (x - o) / |x - o|      1               L A
 *
 * (light.h has each map.) The flux per unit domain area is the light's emission divided by the
 * map's Jacobian: for the cosine disk dA = cos(theta) dw, so I(w) / cos = I0 falloff; the
 * equal-area disk and the sphere have dA = dw; the sun's disk is in metres, dA = the area its rays
 * cross. So a VPL whose cell has area A_i carries Phi_i = rho_i A_i flux_per_area(s_i), and the
 * cells tile the domain: the VPLs carry the light's whole flux, the null samples' share escapes.
 *
 * Rays. A domain point's ray starts at the light (spot, point) or on the sun's plane `radius`
 * behind its disk's centre, and goes along the light's direction for s. A world point x is reached
 * from origin(x) (the light, or the point of the sun's plane behind x): a VPL faces the light when
 * its normal points towards origin(x), and is lit when the segment origin(x) -> x is free.
 * A null sample (the ray escaped, hit an emitter or grazed) keeps its place as the unit direction
 * of its ray (spot, point: a point at infinity) or as the point where its ray leaves the sun's
 * sphere (sun): iir_domain_null_pose and iir_domain_locate_null.
 *
 * Area lights. An emitter (its rectangle, or the shape in it; A its area) emits from every point
 * of it, so its emission is four-dimensional (point, direction). The domain keeps the two
 * dimensions that decide where light lands and that light moves most: directions, on the cosine
 * disk of the hemisphere about the normal (uniform density there is the cosine emitter). Each VPL
 * keeps its own origin o on the emitter (its light-local point q, moved with the light as a rigid
 * body), chosen stratified over the emitter by the VPL's id (iir_domain_emitter_stratum: through
 * the shape's area CDF, so only points of the real emitter); all of the domain's calls for that
 * VPL are made at o: the domain is that of a 90-degree cosine spot at o (iir_domain_at_emitter).
 * A cell of domain area a then stands for the flux L A a the whole emitter sends into its
 * directions, carried from one point of it: the VPLs spread evenly over what the light emits in
 * direction, and over the emitter in expectation. */
#ifndef IIR_LIGHT_DOMAIN_H
#define IIR_LIGHT_DOMAIN_H

#include <stdbool.h>

#include "iir/light.h"
#include "iir/status.h"
#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum iir_domain_shape { IIR_DOMAIN_DISK, IIR_DOMAIN_SPHERE } iir_domain_shape;

typedef enum iir_domain_map {
    IIR_MAP_COSINE_DISK, /* cosine spot */
    IIR_MAP_CAP_DISK,    /* glTF spot */
    IIR_MAP_SPHERE,      /* point */
    IIR_MAP_SUN_DISK,    /* sun */
    IIR_MAP_AREA_DISK    /* area light: the cosine disk of directions from a point on it */
} iir_domain_map;

typedef struct iir_light_domain {
    const iir_light *light;
    iir_domain_map map;
    iir_domain_shape shape;
    iir_light_eval eval; /* the light prepared: frame (r, u, f), profile constants */
    iir_vec3 p;          /* the light's position; the sun: its disk's centre */
    double R;            /* disk radius (domain units); the sphere: 1 */
    double area;         /* pi R^2, or 4 pi */
} iir_light_domain;

/* The domain of the light's current pose. IIR_ERR_INVALID for a light that fails
 * iir_light_validate. *d refers to *light, which must outlive it unchanged. */
iir_status iir_light_domain_make(const iir_light *light, iir_light_domain *d, iir_error *err);

/* An area light's domain as seen from its emitter's light-local point q in [-1/2, 1/2]^2: *d with
 * p moved to that point (every other map: *d itself). */
iir_light_domain iir_domain_at_emitter(const iir_light_domain *d, iir_vec2 q);

/* The i-th point of the emitter strata of d's area light, in light-local coordinates: the Halton
 * point u in bases 3 and 5 (independent of the Hammersley points that place directions) mapped
 * onto the emitter by iir_area_light_sample_q (u - 1/2 on a rectangle; through the shape's area
 * CDF on a shape). Other maps: u - 1/2. */
iir_vec2 iir_domain_emitter_stratum(const iir_light_domain *d, uint32_t i);

/* The domain seen from emitter stratum i: iir_domain_at_emitter(d, iir_domain_emitter_stratum(d,
 * i)), the stratum drawn only for an area light (every other map: *d itself). */
iir_light_domain iir_domain_at_stratum(const iir_light_domain *d, uint32_t i);

/* Short name: "disk", "cap disk" (glTF spot), "sphere", "sun disk", "area disk". */
const char *iir_domain_map_name(iir_domain_map map);

/* The domain point of world point x (in double precision); true when strictly inside the domain
 * (disk: in front of the light and |s| < R; sphere: x is not the light's position). */
bool iir_domain_locate(const iir_light_domain *d, iir_vec3 x, double s[3]);

/* A null sample born from the ray (o, w): the position and direction it keeps (the VPL's
 * `position` and `normal`): the light's position and w (spot, point: only w places it), or the
 * point where the ray leaves the sun's sphere and w. */
void iir_domain_null_pose(const iir_light_domain *d, iir_vec3 o, iir_vec3 w, iir_vec3 *position,
                          iir_vec3 *dir);

/* The domain point of a null sample kept as (position, dir); true when strictly inside. */
bool iir_domain_locate_null(const iir_light_domain *d, iir_vec3 position, iir_vec3 dir,
                            double s[3]);

/* The ray the light emits at domain point s (unit direction *w, origin *o). s is rounded to float
 * first. */
void iir_domain_ray(const iir_light_domain *d, const double s[3], iir_vec3 *o, iir_vec3 *w);

/* The ray that re-finds a null sample kept as (position, dir): from the light along dir (spot,
 * point), or the sun's ray through the domain point of position. */
void iir_domain_null_ray(const iir_light_domain *d, iir_vec3 position, iir_vec3 dir, iir_vec3 *o,
                         iir_vec3 *w);

/* Where light reaching world point x starts: the light's position, or the point of the sun's plane
 * behind x. */
iir_vec3 iir_domain_origin(const iir_light_domain *d, iir_vec3 x);

/* Whether a surface at x with normal n faces the light (n points towards iir_domain_origin). */
bool iir_domain_faces(const iir_light_domain *d, iir_vec3 x, iir_vec3 n);

/* The light's flux per unit domain area at s, as a factor of the light's `intensity` (the table
 * above without I0 or E): falloff, t^2 or 1. */
float iir_domain_profile(const iir_light_domain *d, const double s[3]);

/* A point of the domain for u in [0, 1)^2, uniform in area: the concentric map onto the disk
 * shrunk by (1 - margin), or the uniform map onto the sphere. */
void iir_domain_sample(const iir_light_domain *d, iir_vec2 u, double margin, double s[3]);

/* s pulled inside the domain for a new sample: a disk point to at most R (1 - margin) from the
 * centre; a sphere point normalised. */
void iir_domain_pull_inside(const iir_light_domain *d, const double c[3], double margin,
                            double s[3]);

#ifdef __cplusplus
}
#endif
#endif

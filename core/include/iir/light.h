/* light.h -- the lights a scene moves (delta lights: spot with a cosine lobe or glTF's profile
 * inside a cone, isotropic point, the sun; and the planar area light), the maps from their
 * directions to the disks of their VPL domains (light_domain.h), the area light's rectangle and
 * shape (sampling them, hitting them), the light arriving at a point (every method's one way to
 * sample a light: direction, distance, radiance, pdf and the shadow segment), and the light set
 * that samples all of them and the emissive triangles for next-event estimation. Not VPLs.
 *
 * Cosine spot (profile IIR_SPOT_COSINE, iir's own): frame (p; r, u, f), half-angle alpha in
 * (0, 90] degrees, I(w) = I0 cos(theta) inside the cone, optionally faded to zero over an edge of
 * `smooth` radians just inside the cone. Its disk has radius R = sin(alpha); direction w maps to
 * s = (w.r, w.u) and back with w = s.x r + s.y u + sqrt(1 - |s|^2) f. Uniform density on the disk
 * is exactly the cosine lobe, so disk area is proportional to emitted flux: Phi = pi I0 R^2.
 *
 * glTF spot (profile IIR_SPOT_GLTF, KHR_lights_punctual): cone_angle is glTF's outerConeAngle,
 * inner_angle its innerConeAngle, and I(w) = I0 t^2 with
 * t = clamp((cos(theta) - cos(outer)) / max(1e-3, cos(inner) - cos(outer)), 0, 1) -- the
 * specification's own formula: I0 inside the inner cone, no cosine lobe. Its disk is the cone's cap
 * under Lambert's azimuthal equal-area map, radius R = 2 sin(alpha / 2): s = w_perp
 * sqrt(2 / (1 + w.f)), back w_perp = s sqrt(1 - |s|^2 / 4), w.f = 1 - |s|^2 / 2. Disk area equals
 * solid angle, so a cell's flux is I(w) times its area.
 *
 * Sun (IIR_LIGHT_SUN): parallel rays along `direction`, `intensity` the irradiance E (W/m^2, RGB)
 * on a surface facing it. It lights the scene through the disk of radius `radius` centred at
 * `position`, perpendicular to the direction -- the scene's bounding sphere
 * (iir_light_fit_sun); rays start on that disk's plane `radius` behind the centre. Its flux into
 * the scene is Phi = E pi radius^2.
 *
 * Area light (IIR_LIGHT_AREA): a one-sided planar emitter, a cosine emitter of radiance
 * `intensity` (W/(sr m^2), RGB) that moves as a rigid body: centre `position`, emitting towards
 * `direction` (its normal f), inside its bounding rectangle of sides `size.x` along r and `size.y`
 * along u of the frame (f, up). A point of the rectangle has light-local coordinates
 * q in [-1/2, 1/2]^2: x = position + q.x size.x r + q.y size.y u. The emitter is the whole
 * rectangle (shape.num_triangles == 0), or the union of `shape`'s triangles (a disc lamp, an
 * L-shaped panel: up to IIR_AREA_MAX_TRIANGLES, non-overlapping, in q coordinates, so they stretch
 * with size). Its area is A = w h a with a the shape's fraction of the rectangle (1 without a
 * shape; iir_area_light_area). From afar it is a cosine lobe of I0 = L A; its flux is
 * Phi = pi L A. Points on it are sampled uniformly by area (a triangle by its area, then the
 * square-to-triangle warp). It is not part of the scene's geometry (the BVH is static and shared):
 * pt and the direct-light pass of the VPL renderer (for the G-buffer's camera rays) see it by an
 * analytic test (iir_area_light_hit: the rectangle's plane, then the point in the shape), and it
 * casts no shadow. Rays pass through it (from the front they collect its radiance on the way):
 * what lies behind it is seen and lit as if it were not there. The shape is part of the plain
 * struct (copied with it); a client moving or resizing a light keeps it.
 *
 * An area light's radiance may be an image (a "screen", `map`): L(q) = intensity x map(u, v),
 * u = q.x + 1/2 to the right and v = 1/2 - q.y down the image, as its front is seen (r points to
 * the right of a viewer facing it when up is up); bilinear, linear RGB (a PNG is decoded from
 * sRGB). Points and directions are still sampled uniformly (not by the image), so every estimator
 * stays unbiased: a sample carries the radiance at its own point. Flux and the far-field lobe use
 * the image's mean over the rectangle. The maps belong to the scene (iir_scene.maps); a light
 * copied from it points at its map for as long as the scene lives. */
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

typedef enum iir_light_type {
    IIR_LIGHT_POINT,
    IIR_LIGHT_SPOT,
    IIR_LIGHT_SUN,
    IIR_LIGHT_AREA
} iir_light_type;

/* A spot's angular profile. */
typedef enum iir_spot_profile { IIR_SPOT_COSINE, IIR_SPOT_GLTF } iir_spot_profile;

/* Most triangles an area light's shape has. */
#define IIR_AREA_MAX_TRIANGLES 64

/* An area light's emitter inside its bounding rectangle: num_triangles triangles (either winding)
 * in light-local q coordinates, each corner in [-1/2, 1/2]^2, not overlapping; 0 triangles = the
 * whole rectangle. Unused entries stay zero (lights are compared with memcmp). */
typedef struct iir_area_shape {
    uint32_t num_triangles;
    iir_vec2 tri[IIR_AREA_MAX_TRIANGLES][3];
} iir_area_shape;

/* An area light's radiance image (a scene's: iir_scene.maps). */
typedef struct iir_emission_map {
    int width, height;
    iir_vec3 *texels; /* linear RGB, row-major from the top row */
    iir_vec3 mean;    /* over every texel */
    char path[1024];  /* the file it was read from (absolute) */
} iir_emission_map;

typedef struct iir_light {
    iir_light_type type;
    char name[64];
    iir_vec3 position;        /* sun: the centre of its disk (the scene's bounding sphere) */
    iir_vec3 direction;       /* spot: unit axis f; sun: the direction its light travels */
    iir_vec3 up;              /* spot, sun: hint for the disk's u axis (default +y) */
    float cone_angle;         /* spot: half-angle alpha (glTF: outer), radians, (0, pi/2] */
    float smooth;             /* cosine spot: width of the fading edge, radians, [0, alpha] */
    iir_spot_profile profile; /* spot: IIR_SPOT_COSINE (the default) or IIR_SPOT_GLTF */
    float inner_angle;        /* glTF spot: innerConeAngle, radians, [0, cone_angle] */
    float radius;             /* sun: radius of its disk (> 0) */
    iir_vec2 size;            /* area: bounding rectangle, width along r, height along u (> 0) */
    iir_area_shape shape;     /* area: the emitter inside the rectangle (0 triangles: all of it) */
    const iir_emission_map *map; /* area: radiance image times intensity, NULL = uniform */
    iir_vec3 intensity; /* RGB: point: W/sr, isotropic; spot: I0 (W/sr) on the axis; sun: W/m^2;
                           area: radiance W/(sr m^2) */
} iir_light;

/* ---- description and validity ---- */

/* IIR_ERR_INVALID naming the light and the field for NaN/Inf, negative intensity, a zero
 * direction, a cone angle outside (0, 90] degrees, a smooth edge wider than the cone, a glTF inner
 * angle outside [0, cone angle], a sun without a disk (radius not finite and > 0), an area light
 * without a size (a side not finite and > 0) or with a bad shape (iir_area_shape_check). */
iir_status iir_light_validate(const iir_light *light, iir_error *err);

/* h extended by every field of the light that changes an image: its kind, placement, cone, disk,
 * size, shape, radiance image (size and texels) and intensity; not its name. Two lights with
 * the same hash light a scene the same (iird bench's reference cache keys on it). */
uint64_t iir_light_hash(uint64_t h, const iir_light *light);

/* The light a user moves in scene (the daemon's session light, an animation script's light track):
 * the first spot, else the first light; for a scene without lights a white spot made up just under
 * the middle of the scene's top, aimed down (60 degree half-angle, intensity the bounds' diagonal
 * squared, name "spot"). Writes it to *out; returns its index in scene->lights, or
 * scene->num_lights for the made-up spot. */
uint32_t iir_scene_moved_light(const struct iir_scene *scene, iir_light *out);
/* The same rule over n lights (n > 0): the index of the first spot, else 0. */
uint32_t iir_lights_moved(const iir_light *lights, uint32_t n);

/* Gives a sun the disk that covers the scene: position = the centre of the scene's bounds,
 * radius = half their diagonal (times 1.001, at least 1e-3). Other lights are left as they are.
 * Every code path that makes or moves a sun calls it (scene loading, the daemon's light moves,
 * animation tracks). */
void iir_light_fit_sun(iir_light *light, const struct iir_scene *scene);

/* Short name of the light's kind: "point", "spot", "gltf_spot", "sun" or "area" (the sidecar's
 * type). */
const char *iir_light_kind(const iir_light *light);

/* Total emitted flux (W, RGB); a sun's is what crosses its disk, E pi radius^2; an area light's
 * pi L A (A = iir_area_light_area). */
iir_vec3 iir_light_flux(const iir_light *light);

/* True for a light with no extent (point, spot, sun): one direction and distance reach a point,
 * no MIS; false for an area light, which methods sample over its emitter. */
bool iir_light_is_delta(const iir_light *light);
/* True when `position` is where the light is (not a sun, whose position is only its disk's
 * centre). */
bool iir_light_has_position(const iir_light *light);
/* What a VPL born at the light's emission point q scales its flux by (its domain's flux per unit
 * area is this times the profile): an area light's radiance at light-local q (its emission map),
 * any other light's intensity. */
iir_vec3 iir_light_emission_at(const iir_light *light, iir_vec2 q);
/* The same averaged over the light's emitter: an area light's mean radiance, else intensity. */
iir_vec3 iir_light_mean_emission(const iir_light *light);

/* Radiant intensity (W/sr) emitted towards the unit world direction w (pointing away from the
 * light). A sun has none (0): use its irradiance, `intensity`, along `direction`. An area light's
 * is its far field, the cosine lobe L A max(0, w.f) as if all of it sat at its centre: right for
 * whoever sees it from many times its size away (iir_light_sample_li is exact near it). */
iir_vec3 iir_light_intensity(const iir_light *light, iir_vec3 w);

/* A light prepared for evaluating many directions: the spot's (and the area light's) frame and disk
 * radii are computed once (iir_light_intensity recomputes them per call). Valid while *light is
 * unchanged. */
typedef struct iir_light_eval {
    const iir_light *light;
    iir_frame frame;
    float R, R_in; /* cosine spot: disk radius sin(alpha), where the smooth edge starts */
    float cos_outer, t_scale; /* glTF spot: cos(outer), 1 / max(1e-3, cos(inner) - cos(outer)) */
    float area;               /* area light: its emitter's area (iir_area_light_area) */
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

/* ---- the glTF spot's equal-area disk (Lambert azimuthal) ---- */

static inline float iir_gltf_spot_radius(const iir_light *spot)
{
    return 2.f * sinf(0.5f * spot->cone_angle);
}

/* Equal-area disk coordinates of unit direction w (|s| <= 2; <= R inside the cone). */
static inline iir_vec2 iir_cap_dir_to_disk(const iir_frame *fr, iir_vec3 w)
{
    float k = iir_safe_sqrt(2.f / fmaxf(1.f + iir_dot(w, fr->f), 1e-30f));
    return iir_v2(k * iir_dot(w, fr->r), k * iir_dot(w, fr->u));
}

/* Unit direction for equal-area disk point s (|s| <= 2). */
static inline iir_vec3 iir_cap_disk_to_dir(const iir_frame *fr, iir_vec2 s)
{
    float rho2 = s.x * s.x + s.y * s.y, k = iir_safe_sqrt(1.f - 0.25f * rho2);
    return iir_add(iir_add(iir_scale(fr->r, k * s.x), iir_scale(fr->u, k * s.y)),
                   iir_scale(fr->f, 1.f - 0.5f * rho2));
}

/* glTF's angular attenuation t^2 at cos(theta) (see the top of this file), for a prepared light. */
float iir_gltf_spot_attenuation(const iir_light_eval *e, float cos_theta);

/* Fraction of I0 cos(theta) emitted at disk radius rho (1 inside, smoothstep across the edge, 0
 * outside). */
float iir_spot_falloff(const iir_light *spot, float rho);

/* ---- emission sampling (light paths: IR, VPLs) ---- */

typedef struct iir_light_ray {
    iir_vec3 origin, dir;
    iir_vec3 beta; /* flux carried by this sample: Le cos / pdf, so E[beta] = Phi */
} iir_light_ray;

/* Cosine spot: uniform on its disk (the cosine lobe); glTF spot: uniform on its equal-area disk
 * (uniform in solid angle over the cone); point: uniform on the sphere; sun: origin uniform on its
 * disk (on the plane `radius` behind the centre), direction `direction`; area light: as
 * iir_light_sample_emission_from with u_origin a hash of u's bits (deterministic, and independent
 * of u for any practical purpose). u in [0,1)^2. */
iir_light_ray iir_light_sample_emission(const iir_light *light, iir_vec2 u);

/* The same with the area light's origin chosen by u_origin: uniform on the emitter
 * (q = iir_area_light_sample_q(l, u_origin)), direction from u uniform on the unit disk of the
 * frame (r, u, f) as the cosine spot's (the cosine lobe), beta = pi L A. Other lights ignore
 * u_origin. */
iir_light_ray iir_light_sample_emission_from(const iir_light *light, iir_vec2 u, iir_vec2 u_origin);

/* ---- the area light's rectangle and shape (area_shape.c, area_hit.c) ---- */

/* Why shape is not usable (a phrase: "has a degenerate triangle"), or NULL when it is: more
 * than IIR_AREA_MAX_TRIANGLES triangles, a corner not finite or outside [-1/2, 1/2]^2, a
 * degenerate triangle (area below 1e-7 of the rectangle), overlapping triangles (their areas sum
 * to more than the rectangle's, or two of them share interior points). */
const char *iir_area_shape_check(const iir_area_shape *shape);

/* The fraction a of the bounding rectangle the emitter covers: 1 without a shape, else the sum of
 * its triangles' areas. */
float iir_area_shape_fraction(const iir_area_shape *shape);

/* The emitter's area A = size.x size.y a (world units^2). */
float iir_area_light_area(const iir_light *l);

/* A light-local point q uniform by area on the emitter, for u in [0, 1)^2: u - 1/2 on the
 * rectangle; on a shape, a triangle chosen by u.x over the triangles' area CDF (u.x rescaled to
 * [0, 1) inside it), then the square-to-triangle warp. Stratified u gives points stratified over
 * the emitter. */
iir_vec2 iir_area_light_sample_q(const iir_light *l, iir_vec2 u);

/* Whether light-local q lies on the emitter (inside the rectangle and, with a shape, in one of its
 * triangles; boundaries included). */
bool iir_area_light_contains(const iir_light *l, iir_vec2 q);

/* The world point of light-local q in [-1/2, 1/2]^2 on area light l, whose frame is
 * fr = iir_spot_frame(l). */
static inline iir_vec3 iir_area_light_point(const iir_light *l, const iir_frame *fr, iir_vec2 q)
{
    return iir_add(iir_add(l->position, iir_scale(fr->r, q.x * l->size.x)),
                   iir_scale(fr->u, q.y * l->size.y));
}

/* ---- an area light's radiance image (emission_map.c) ---- */

/* Reads a .png (sRGB, decoded to linear), .exr or .pfm as an emission map (its path made absolute).
 * IIR_ERR_IO / IIR_ERR_FORMAT naming the file, IIR_ERR_NOMEM. */
iir_status iir_emission_map_load(const char *path, iir_emission_map **out, iir_error *err);
void iir_emission_map_free(iir_emission_map *m);

/* The radiance area light l emits at light-local q: intensity, times its map at q (bilinear, q
 * clamped to the rectangle) when it has one. */
iir_vec3 iir_area_light_radiance(const iir_light *l, iir_vec2 q);
/* The same at world point x on the light's plane. */
iir_vec3 iir_area_light_radiance_at(const iir_light *l, const iir_frame *fr, iir_vec3 x);
/* The mean radiance over the rectangle: intensity times the map's mean (intensity without one). */
iir_vec3 iir_area_light_mean_radiance(const iir_light *l);

/* The t in (0, tmax) where the ray o + t d (d need not be unit) meets area light l's emitter
 * (its rectangle, and its shape when it has one) from its emitting side (d.f < 0), or INFINITY
 * when it misses it, meets it from behind or runs parallel to it. */
float iir_area_light_hit(const iir_light *l, iir_vec3 o, iir_vec3 d, float tmax);

/* ---- light arriving at a point (lightset.c): how every method asks a light ---- */

/* Where light is wanted (pbrt's LightSampleContext). */
typedef struct iir_light_ctx {
    iir_vec3 p; /* the receiving point, on its surface (not lifted off it) */
    iir_vec3 n; /* its surface's unit normal, either orientation; 0 for a point in space */
    float eps;  /* the scene's ray epsilon (iir_rt_epsilon; hier: a voxel cell's diagonal) */
} iir_light_ctx;

/* The segment a shadow ray tests: org + t dir (unit dir) for t in (0, tmax); tmax is INFINITY
 * for a sun, 0 when the ends are too close to test (count the light as unblocked). */
typedef struct iir_light_segment {
    iir_vec3 org, dir;
    float tmax;
} iir_light_segment;

/* The light arriving at a receiving point from one sampled point of a light (pbrt's
 * LightLiSample); Li cos / pdf is the estimate, cos the receiver's n . wi. */
typedef struct iir_light_sample {
    iir_vec3 wi;      /* unit direction from ctx->p to the light */
    float dist;       /* distance from ctx->p to p_light; INFINITY for a sun */
    iir_vec3 Li;      /* radiance (areas), I/d^2 (point, spot) or E (sun), not divided by pdf */
    float pdf;        /* solid angle (areas); 1 for a delta light (times the pick's pmf in a set) */
    bool is_delta;    /* point, spot or sun: no MIS */
    iir_vec3 p_light; /* the sampled point (the position of a point or spot; none for a sun) */
    iir_vec3 n_light; /* the emitter's unit normal there, towards ctx->p; 0 for delta lights */
    iir_light_segment shadow; /* what to test: the one rule (iir_light_shadow) */
} iir_light_sample;

/* The light arriving at ctx->p from the prepared light e (iir_light_prepare, any kind), for u in
 * [0, 1)^2 (delta lights ignore it): point, spot: from its position, Li = I(-wi) / d^2; sun:
 * along -direction, Li = E; area light: a point uniform by area on its emitter
 * (iir_area_light_sample_q(l, u)), Li its radiance there, pdf d^2 / (A cos theta_l). Fills the
 * shadow segment. pdf == 0 means no light arrives: ctx->p is at the light, or behind an area
 * light's plane. Whether ctx's surface faces wi is the caller's to test. */
iir_light_sample iir_light_sample_li(const iir_light_eval *e, const iir_light_ctx *ctx, iir_vec2 u);

/* ---- a delta light at 8 or 32 receivers at once (light_lanes_avx2.c): the direct-light kernel */

/* 8 receiving points, structure of arrays: the points on their surfaces and their unit normals. */
typedef struct iir_light_lanes {
    _Alignas(32) float px[8], py[8], pz[8], nx[8], ny[8], nz[8];
} iir_light_lanes;

/* What iir_light_sample_li and the renderer's sample test make of delta light e at each lane: wi,
 * the unit direction to the light; E = Li (n . wi), 0 where no light arrives or the surface faces
 * away from wi; and the shadow segment org + t dir, t in (0, tmax), org the receiver's end
 * (iir_light_ctx_origin), tmax 0 when the ends are too close to test and INFINITY for a sun. */
typedef struct iir_light_delta_lanes {
    _Alignas(32) float wx[8], wy[8], wz[8], Ex[8], Ey[8], Ez[8];
    float ox[8], oy[8], oz[8], dx[8], dy[8], dz[8], tmax[8];
} iir_light_delta_lanes;

/* iir_light_sample_li of delta light e (point, spot or sun) at the 8 lanes (ctx.eps = eps), with
 * AVX2 and FMA: only where iir_isa_supported(IIR_ISA_AVX2). The same light as the scalar
 * function up to float rounding (test_light: every kind, lane by lane). */
void iir_light_sample_delta8_avx2(const iir_light_eval *e, float eps, const iir_light_lanes *in,
                                  iir_light_delta_lanes *out);

/* iir_light_sample_delta8_avx2 at four sets of 8 lanes, the same bit for bit as four calls and
 * not much slower than one (their chains of square roots and divisions overlap). */
void iir_light_sample_delta32_avx2(const iir_light_eval *e, float eps, const iir_light_lanes in[4],
                                   iir_light_delta_lanes out[4]);

/* The solid-angle pdf iir_light_sample_li gives area light l's point at distance dist along unit
 * wi from the receiving point (0 when wi meets it from behind), the pick probability not included.
 */
float iir_area_light_pdf(const iir_light *l, iir_vec3 wi, float dist);

/* The receiver's end of a shadow segment towards w: ctx->p moved ctx->eps along its normal, on
 * w's side (along w itself when ctx->n is 0). */
iir_vec3 iir_light_ctx_origin(const iir_light_ctx *ctx, iir_vec3 w);

/* The one shadow-ray rule, from o, the receiver's end (iir_light_ctx_origin), to ls's light: the
 * segment keeps eps off both its ends. Off the receiver's surface by o; off an emitter along its
 * normal (the segment ends at p_light + eps n_light, so a grazing ray does not cross the emitter's
 * own surface before the point); off a point or spot, which lies on no surface, by stopping eps
 * short of its position. A sun's runs from o along wi to infinity. */
iir_light_segment iir_light_shadow(iir_vec3 o, const iir_light_sample *ls, float eps);

/* ---- the light set: the scene's lights + emissive triangles, for next-event estimation ---- */

typedef struct iir_lightset iir_lightset;

/* Builds the set from the given lights (delta and area lights) and the scene's emissive triangles,
 * choosing lights in proportion to flux (luminance). The lights array is copied. Returns NULL on
 * allocation failure. */
iir_lightset *iir_lightset_create(const struct iir_scene *scene, const iir_light *lights,
                                  uint32_t num_lights);
void iir_lightset_destroy(iir_lightset *set);
bool iir_lightset_empty(const iir_lightset *set);
/* True when the scene has emissive triangles or the set an area light (BSDF-sampled rays can then
 * find light). */
bool iir_lightset_has_area_lights(const iir_lightset *set);

/* Samples one of the set's lights (or emissive triangles) for ctx: u_pick chooses it by flux, then
 * as iir_light_sample_li (an emissive triangle: a point uniform by area on it, n_light its
 * normal), pdf times the pick's probability. pdf == 0 means nothing was sampled (no lights, or the
 * point is behind the sampled emitter). */
iir_light_sample iir_lightset_sample_li(const iir_lightset *set, const iir_light_ctx *ctx,
                                        float u_pick, iir_vec2 u);

/* Solid-angle pdf with which iir_lightset_sample_li would have chosen the point on emissive
 * triangle `prim` seen from x along unit direction wi at distance dist (for MIS when a BSDF ray
 * hits it). */
float iir_lightset_pdf_area(const iir_lightset *set, uint32_t prim, iir_vec3 wi, float dist);

/* The number of lights the set was created with (emissive triangles not counted). */
uint32_t iir_lightset_num_lights(const iir_lightset *set);

/* What a ray meets of one of the set's lights. */
typedef struct iir_emitter_hit {
    float t;     /* along the ray; INFINITY when it meets nothing (and then Le = 0, pdf = 0) */
    iir_vec3 Le; /* radiance towards the ray's origin */
    float pdf; /* solid-angle pdf with which iir_lightset_sample_li would have chosen that point */
} iir_emitter_hit;

/* Light i (< iir_lightset_num_lights) on the ray o + t d (unit d), t in (0, tmax): an area light
 * met from its emitting side, with the pdf for MIS when a BSDF ray finds it; delta lights are
 * never met. Area lights do not block rays: a caller adds every light met before its surface. */
iir_emitter_hit iir_lightset_hit_light(const iir_lightset *set, uint32_t i, iir_vec3 o, iir_vec3 d,
                                       float tmax);

#ifdef __cplusplus
}
#endif
#endif

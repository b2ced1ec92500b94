/* light.c -- the lights a scene moves (cosine spot, glTF spot, point, sun, planar area
 * light): validity, kind, intensity, flux, the spots' disk maps' radii and falloff, emission
 * sampling, and fitting a sun to the scene. Not the light set (lightset.c), not an area light's
 * shape (area_shape.c) or hitting it (area_hit.c), and not VPLs. */
#include "iir/light.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "iir/hash.h"
#include "iir/rng.h"
#include "iir/scene.h"

#include "sampling.h"

static bool finite_nonneg(iir_vec3 c)
{
    return iir_is_finite3(c) && c.x >= 0.f && c.y >= 0.f && c.z >= 0.f;
}

/* ======================== validity and kind ======================== */

static iir_status validate_spot(const iir_light *l, const char *name, iir_error *err)
{
    if (!(l->cone_angle > 0.f && l->cone_angle <= IIR_PI * 0.5f + 1e-6f))
        return iir_fail(err, IIR_ERR_INVALID,
                        "light '%s': cone angle %g degrees is outside (0, 90]", name,
                        (double)iir_degrees(l->cone_angle));
    if (!(l->smooth >= 0.f && l->smooth <= l->cone_angle))
        return iir_fail(err, IIR_ERR_INVALID,
                        "light '%s': smooth edge %g degrees must be in [0, cone angle]", name,
                        (double)iir_degrees(l->smooth));
    if (l->profile != IIR_SPOT_COSINE && l->profile != IIR_SPOT_GLTF)
        return iir_fail(err, IIR_ERR_INVALID, "light '%s': unknown spot profile %d", name,
                        (int)l->profile);
    if (l->profile == IIR_SPOT_GLTF && !(l->inner_angle >= 0.f && l->inner_angle <= l->cone_angle))
        return iir_fail(err, IIR_ERR_INVALID,
                        "light '%s': inner angle %g degrees must be in [0, cone angle %g]", name,
                        (double)iir_degrees(l->inner_angle), (double)iir_degrees(l->cone_angle));
    return IIR_OK;
}

static iir_status validate_area(const iir_light *l, const char *name, iir_error *err)
{
    if (!(isfinite(l->size.x) && isfinite(l->size.y) && l->size.x > 0.f && l->size.y > 0.f))
        return iir_fail(err, IIR_ERR_INVALID,
                        "light '%s': an area light's size must be finite and > 0, got %g x %g",
                        name, (double)l->size.x, (double)l->size.y);
    const char *why = iir_area_shape_check(&l->shape);
    if (why) return iir_fail(err, IIR_ERR_INVALID, "light '%s': its shape %s", name, why);
    return IIR_OK;
}

iir_status iir_light_validate(const iir_light *l, iir_error *err)
{
    const char *name = l->name[0] ? l->name : "(unnamed)";
    if (l->type != IIR_LIGHT_POINT && l->type != IIR_LIGHT_SPOT && l->type != IIR_LIGHT_SUN &&
        l->type != IIR_LIGHT_AREA)
        return iir_fail(err, IIR_ERR_INVALID, "light '%s': unknown type %d", name, (int)l->type);
    if (!iir_is_finite3(l->position))
        return iir_fail(err, IIR_ERR_INVALID, "light '%s': position is not finite", name);
    if (!finite_nonneg(l->intensity))
        return iir_fail(err, IIR_ERR_INVALID,
                        "light '%s': intensity must be finite and non-negative", name);
    if (l->type == IIR_LIGHT_POINT) return IIR_OK;
    if (!iir_is_finite3(l->direction) || iir_length(l->direction) < 1e-6f)
        return iir_fail(err, IIR_ERR_INVALID, "light '%s': direction is zero or not finite", name);
    if (l->type == IIR_LIGHT_SPOT) return validate_spot(l, name, err);
    if (l->type == IIR_LIGHT_AREA) return validate_area(l, name, err);
    if (!(isfinite(l->radius) && l->radius > 0.f))
        return iir_fail(err, IIR_ERR_INVALID,
                        "light '%s': a sun needs a disk radius > 0 (iir_light_fit_sun), got %g",
                        name, (double)l->radius);
    return IIR_OK;
}

const char *iir_light_kind(const iir_light *l)
{
    switch (l->type) {
    case IIR_LIGHT_POINT:
        return "point";
    case IIR_LIGHT_SPOT:
        return l->profile == IIR_SPOT_GLTF ? "gltf_spot" : "spot";
    case IIR_LIGHT_SUN:
        return "sun";
    case IIR_LIGHT_AREA:
        return "area";
    }
    return "unknown";
}

void iir_light_fit_sun(iir_light *l, const iir_scene *scene)
{
    if (l->type != IIR_LIGHT_SUN) return;
    iir_vec3 lo = scene->bounds_min, hi = scene->bounds_max;
    l->position = iir_scale(iir_add(lo, hi), 0.5f);
    l->radius = fmaxf(1e-3f, 0.5f * 1.001f * iir_length(iir_sub(hi, lo)));
}

/* ======================== the spots' disks ======================== */

/* The spot's frame, and the sun's and the area light's (their disk and rectangle are spanned by r
 * and u as a spot's disk is). */
iir_frame iir_spot_frame(const iir_light *spot)
{
    iir_vec3 up = iir_length_sq(spot->up) > 0.f ? spot->up : iir_v3(0, 1, 0);
    return iir_frame_from_forward(spot->direction, up);
}

/* 1 inside R_in, smoothstep down to 0 at R, 0 outside. */
static float falloff(float R, float R_in, float rho)
{
    if (rho >= R) return 0.f;
    if (rho <= R_in) return 1.f;
    float t = (R - rho) / (R - R_in);
    return t * t * (3.f - 2.f * t);
}

static float smooth_edge_start(const iir_light *spot)
{
    return spot->smooth > 0.f ? sinf(spot->cone_angle - spot->smooth) : iir_spot_radius(spot);
}

float iir_spot_falloff(const iir_light *spot, float rho)
{
    return falloff(iir_spot_radius(spot), smooth_edge_start(spot), rho);
}

float iir_gltf_spot_attenuation(const iir_light_eval *e, float cos_theta)
{
    float t = iir_clampf((cos_theta - e->cos_outer) * e->t_scale, 0.f, 1.f);
    return t * t;
}

/* ======================== flux and intensity ======================== */

/* Phi = I0 * integral over the disk of falloff(rho) dA (the cosine lobe is uniform on the disk). */
static float spot_flux_factor(const iir_light *spot)
{
    float R = iir_spot_radius(spot);
    if (spot->smooth <= 0.f) return IIR_PI * R * R;
    enum { STEPS = 512 };
    double sum = 0.0, dr = R / STEPS;
    for (int i = 0; i < STEPS; i++) {
        double rho = (i + 0.5) * dr;
        sum += iir_spot_falloff(spot, (float)rho) * rho * dr;
    }
    return (float)(2.0 * IIR_PI * sum);
}

/* Phi = I0 2 pi integral_{cos outer}^{1} t(c)^2 dc in closed form, for the prepared light's own
 * (float) cos_outer a and width w = 1 / t_scale: t rises linearly over [a, a + w], then is 1. */
static float gltf_flux_factor(const iir_light *spot)
{
    iir_light_eval e = iir_light_prepare(spot);
    double a = e.cos_outer, w = 1.0 / (double)e.t_scale, top = fmin(1.0, a + w);
    double ramp = (top - a) * (top - a) * (top - a) / (3.0 * w * w);
    return (float)(2.0 * IIR_PI * (ramp + (1.0 - top)));
}

iir_vec3 iir_light_flux(const iir_light *l)
{
    switch (l->type) {
    case IIR_LIGHT_POINT:
        return iir_scale(l->intensity, 4.f * IIR_PI);
    case IIR_LIGHT_SUN:
        return iir_scale(l->intensity, IIR_PI * l->radius * l->radius);
    case IIR_LIGHT_AREA:
        return iir_scale(iir_area_light_mean_radiance(l), IIR_PI * iir_area_light_area(l));
    default:
        return iir_scale(l->intensity,
                         l->profile == IIR_SPOT_GLTF ? gltf_flux_factor(l) : spot_flux_factor(l));
    }
}

bool iir_light_is_delta(const iir_light *l)
{
    return l->type != IIR_LIGHT_AREA;
}

bool iir_light_has_position(const iir_light *l)
{
    return l->type != IIR_LIGHT_SUN;
}

iir_vec3 iir_light_emission_at(const iir_light *l, iir_vec2 q)
{
    return l->type == IIR_LIGHT_AREA ? iir_area_light_radiance(l, q) : l->intensity;
}

iir_vec3 iir_light_mean_emission(const iir_light *l)
{
    return l->type == IIR_LIGHT_AREA ? iir_area_light_mean_radiance(l) : l->intensity;
}

iir_light_eval iir_light_prepare(const iir_light *l)
{
    iir_light_eval e = {.light = l};
    if (l->type == IIR_LIGHT_AREA) e.frame = iir_spot_frame(l), e.area = iir_area_light_area(l);
    if (l->type != IIR_LIGHT_SPOT) return e;
    e.frame = iir_spot_frame(l);
    if (l->profile == IIR_SPOT_GLTF) {
        e.cos_outer = cosf(l->cone_angle);
        e.t_scale = 1.f / fmaxf(1e-3f, cosf(l->inner_angle) - e.cos_outer);
    } else {
        e.R = iir_spot_radius(l);
        e.R_in = smooth_edge_start(l);
    }
    return e;
}

iir_vec3 iir_light_eval_intensity(const iir_light_eval *e, iir_vec3 w)
{
    const iir_light *l = e->light;
    if (l->type == IIR_LIGHT_POINT) return l->intensity;
    if (l->type == IIR_LIGHT_SUN) return iir_v3s(0.f);
    float cos_theta = iir_dot(w, e->frame.f);
    if (cos_theta <= 0.f) return iir_v3s(0.f);
    if (l->type == IIR_LIGHT_AREA) /* the far field: I0 = L A (L the mean over the image) */
        return iir_scale(iir_area_light_mean_radiance(l), cos_theta * iir_area_light_area(l));
    if (l->profile == IIR_SPOT_GLTF)
        return iir_scale(l->intensity, iir_gltf_spot_attenuation(e, cos_theta));
    iir_vec2 s = iir_spot_dir_to_disk(&e->frame, w);
    float rho = sqrtf(s.x * s.x + s.y * s.y);
    return iir_scale(l->intensity, cos_theta * falloff(e->R, e->R_in, rho));
}

iir_vec3 iir_light_intensity(const iir_light *l, iir_vec3 w)
{
    iir_light_eval e = iir_light_prepare(l);
    return iir_light_eval_intensity(&e, w);
}

/* ======================== emission sampling ======================== */

/* Uniform on the disk of radius R is the cosine lobe: pdf(w) = cos / (pi R^2), so
 * beta = I0 cos falloff / pdf = pi R^2 I0 falloff. */
static iir_light_ray sample_cosine_spot(const iir_light *l, iir_vec2 u)
{
    iir_frame fr = iir_spot_frame(l);
    float R = iir_spot_radius(l);
    iir_vec2 d = iir_sample_uniform_disk_concentric(u);
    iir_vec2 s = iir_v2(d.x * R, d.y * R);
    float rho = sqrtf(s.x * s.x + s.y * s.y);
    iir_light_ray r = {l->position, iir_spot_disk_to_dir(&fr, s),
                       iir_scale(l->intensity, IIR_PI * R * R * iir_spot_falloff(l, rho))};
    return r;
}

/* Uniform on the equal-area disk of radius R is uniform in solid angle over the cone:
 * pdf(w) = 1 / (pi R^2) = 1 / (2 pi (1 - cos outer)), so beta = I0 t^2 pi R^2. */
static iir_light_ray sample_gltf_spot(const iir_light *l, iir_vec2 u)
{
    iir_light_eval e = iir_light_prepare(l);
    float R = iir_gltf_spot_radius(l);
    iir_vec2 d = iir_sample_uniform_disk_concentric(u);
    iir_vec2 s = iir_v2(d.x * R, d.y * R);
    float cos_theta = 1.f - 0.5f * (s.x * s.x + s.y * s.y);
    float k = IIR_PI * R * R * iir_gltf_spot_attenuation(&e, cos_theta);
    iir_light_ray r = {l->position, iir_cap_disk_to_dir(&e.frame, s), iir_scale(l->intensity, k)};
    return r;
}

/* Origin uniform on the sun's disk, moved `radius` back along its direction: pdf = 1 / (pi r^2)
 * per unit area, so beta = E pi r^2. */
static iir_light_ray sample_sun(const iir_light *l, iir_vec2 u)
{
    iir_frame fr = iir_spot_frame(l);
    iir_vec2 d = iir_sample_uniform_disk_concentric(u);
    iir_vec3 o = iir_madd(l->position, fr.r, d.x * l->radius);
    o = iir_madd(o, fr.u, d.y * l->radius);
    iir_light_ray r = {iir_madd(o, fr.f, -l->radius), fr.f,
                       iir_scale(l->intensity, IIR_PI * l->radius * l->radius)};
    return r;
}

/* Origin uniform on the emitter (pdf 1 / A per unit area), direction uniform on the unit disk of
 * its frame (pdf cos / pi): beta = L(q) cos / (cos / (pi A)) = pi L(q) A. */
static iir_light_ray sample_area(const iir_light *l, iir_vec2 u, iir_vec2 u_origin)
{
    iir_frame fr = iir_spot_frame(l);
    iir_vec2 q = iir_area_light_sample_q(l, u_origin);
    iir_light_ray r = {iir_area_light_point(l, &fr, q),
                       iir_spot_disk_to_dir(&fr, iir_sample_uniform_disk_concentric(u)),
                       iir_scale(iir_area_light_radiance(l, q), IIR_PI * iir_area_light_area(l))};
    return r;
}

/* Two numbers in [0, 1) from the bits of u. */
static iir_vec2 hash_uniform2(iir_vec2 u)
{
    uint32_t a, b;
    memcpy(&a, &u.x, sizeof a);
    memcpy(&b, &u.y, sizeof b);
    uint64_t h = iir_hash3(a, b, 0xa7ea);
    return iir_v2((float)(h >> 40) * 0x1p-24f, (float)((h >> 8) & 0xffffff) * 0x1p-24f);
}

iir_light_ray iir_light_sample_emission(const iir_light *l, iir_vec2 u)
{
    if (l->type == IIR_LIGHT_AREA) return sample_area(l, u, hash_uniform2(u));
    return iir_light_sample_emission_from(l, u, iir_v2(0.5f, 0.5f));
}

iir_light_ray iir_light_sample_emission_from(const iir_light *l, iir_vec2 u, iir_vec2 u_origin)
{
    if (l->type == IIR_LIGHT_AREA) return sample_area(l, u, u_origin);
    if (l->type == IIR_LIGHT_SUN) return sample_sun(l, u);
    if (l->type == IIR_LIGHT_SPOT)
        return l->profile == IIR_SPOT_GLTF ? sample_gltf_spot(l, u) : sample_cosine_spot(l, u);
    iir_light_ray r = {l->position, iir_sample_uniform_sphere(u),
                       iir_scale(l->intensity, 4.f * IIR_PI)};
    return r;
}

/* ======================== the light a user moves ======================== */

uint32_t iir_lights_moved(const iir_light *lights, uint32_t n)
{
    for (uint32_t i = 0; i < n; i++)
        if (lights[i].type == IIR_LIGHT_SPOT) return i;
    return 0;
}

uint32_t iir_scene_moved_light(const iir_scene *scene, iir_light *out)
{
    if (scene->num_lights > 0) {
        uint32_t i = iir_lights_moved(scene->lights, scene->num_lights);
        return *out = scene->lights[i], i;
    }
    iir_vec3 lo = scene->bounds_min, ext = iir_sub(scene->bounds_max, lo);
    float diag = iir_length(ext);
    *out = (iir_light){.type = IIR_LIGHT_SPOT,
                       .position = iir_v3(lo.x + 0.5f * ext.x, scene->bounds_max.y - 0.02f * diag,
                                          lo.z + 0.5f * ext.z),
                       .direction = iir_v3(0, -1, 0),
                       .up = iir_v3(0, 0, 1),
                       .cone_angle = (float)(60.0 * M_PI / 180.0),
                       .intensity = iir_scale(iir_v3(1, 1, 1), diag * diag)};
    snprintf(out->name, sizeof out->name, "spot");
    return scene->num_lights;
}

/* ---- the light's content key ---- */

static uint64_t hash_map(uint64_t h, const iir_emission_map *m)
{
    uint8_t has = m != NULL;
    h = IIR_HASH(h, has);
    if (!m) return h;
    h = IIR_HASH(h, m->width);
    h = IIR_HASH(h, m->height);
    return iir_hash_bytes(h, m->texels, (size_t)m->width * (size_t)m->height * sizeof *m->texels);
}

uint64_t iir_light_hash(uint64_t h, const iir_light *l)
{
    int32_t type = (int32_t)l->type, profile = (int32_t)l->profile;
    h = IIR_HASH(h, type);
    h = IIR_HASH(h, l->position);
    h = IIR_HASH(h, l->direction);
    h = IIR_HASH(h, l->up);
    h = IIR_HASH(h, l->cone_angle);
    h = IIR_HASH(h, l->smooth);
    h = IIR_HASH(h, profile);
    h = IIR_HASH(h, l->inner_angle);
    h = IIR_HASH(h, l->radius);
    h = IIR_HASH(h, l->size);
    h = IIR_HASH(h, l->shape.num_triangles);
    for (uint32_t t = 0; t < l->shape.num_triangles && t < IIR_AREA_MAX_TRIANGLES; t++)
        h = IIR_HASH(h, l->shape.tri[t]);
    h = hash_map(h, l->map);
    return IIR_HASH(h, l->intensity);
}

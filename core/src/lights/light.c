/* light.c -- punctual lights: validity, intensity, flux, the spot's disk domain and emission
 * sampling. Not the light set (lightset.c) and not VPLs. */
#include "iir/light.h"

#include <math.h>
#include <stdio.h>

#include "iir/scene.h"

#include "sampling.h"

static bool finite_nonneg(iir_vec3 c)
{
    return iir_is_finite3(c) && c.x >= 0.f && c.y >= 0.f && c.z >= 0.f;
}

iir_status iir_light_validate(const iir_light *l, iir_error *err)
{
    const char *name = l->name[0] ? l->name : "(unnamed)";
    if (!iir_is_finite3(l->position))
        return iir_fail(err, IIR_ERR_INVALID, "light '%s': position is not finite", name);
    if (!finite_nonneg(l->intensity))
        return iir_fail(err, IIR_ERR_INVALID,
                        "light '%s': intensity must be finite and non-negative", name);
    if (l->type == IIR_LIGHT_POINT) return IIR_OK;
    if (!iir_is_finite3(l->direction) || iir_length(l->direction) < 1e-6f)
        return iir_fail(err, IIR_ERR_INVALID, "light '%s': direction is zero or not finite", name);
    if (!(l->cone_angle > 0.f && l->cone_angle <= IIR_PI * 0.5f + 1e-6f))
        return iir_fail(err, IIR_ERR_INVALID,
                        "light '%s': cone angle %g degrees is outside (0, 90]", name,
                        (double)iir_degrees(l->cone_angle));
    if (!(l->smooth >= 0.f && l->smooth <= l->cone_angle))
        return iir_fail(err, IIR_ERR_INVALID,
                        "light '%s': smooth edge %g degrees must be in [0, cone angle]", name,
                        (double)iir_degrees(l->smooth));
    return IIR_OK;
}

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

iir_vec3 iir_light_flux(const iir_light *l)
{
    if (l->type == IIR_LIGHT_POINT) return iir_scale(l->intensity, 4.f * IIR_PI);
    return iir_scale(l->intensity, spot_flux_factor(l));
}

iir_light_eval iir_light_prepare(const iir_light *l)
{
    iir_light_eval e = {.light = l};
    if (l->type == IIR_LIGHT_SPOT) {
        e.frame = iir_spot_frame(l);
        e.R = iir_spot_radius(l);
        e.R_in = smooth_edge_start(l);
    }
    return e;
}

iir_vec3 iir_light_eval_intensity(const iir_light_eval *e, iir_vec3 w)
{
    const iir_light *l = e->light;
    if (l->type == IIR_LIGHT_POINT) return l->intensity;
    float cos_theta = iir_dot(w, e->frame.f);
    if (cos_theta <= 0.f) return iir_v3s(0.f);
    iir_vec2 s = iir_spot_dir_to_disk(&e->frame, w);
    float rho = sqrtf(s.x * s.x + s.y * s.y);
    return iir_scale(l->intensity, cos_theta * falloff(e->R, e->R_in, rho));
}

iir_vec3 iir_light_intensity(const iir_light *l, iir_vec3 w)
{
    iir_light_eval e = iir_light_prepare(l);
    return iir_light_eval_intensity(&e, w);
}

iir_light_ray iir_light_sample_emission(const iir_light *l, iir_vec2 u)
{
    iir_light_ray r;
    r.origin = l->position;
    if (l->type == IIR_LIGHT_POINT) {
        r.dir = iir_sample_uniform_sphere(u);
        r.beta = iir_scale(l->intensity, 4.f * IIR_PI);
        return r;
    }
    /* Uniform on the disk of radius R is the cosine lobe: pdf(w) = cos / (pi R^2), so
     * beta = I0 cos falloff / pdf = pi R^2 I0 falloff. */
    iir_frame fr = iir_spot_frame(l);
    float R = iir_spot_radius(l);
    iir_vec2 d = iir_sample_uniform_disk_concentric(u);
    iir_vec2 s = iir_v2(d.x * R, d.y * R);
    r.dir = iir_spot_disk_to_dir(&fr, s);
    float rho = sqrtf(s.x * s.x + s.y * s.y);
    r.beta = iir_scale(l->intensity, IIR_PI * R * R * iir_spot_falloff(l, rho));
    return r;
}

uint32_t iir_scene_moved_light(const iir_scene *scene, iir_light *out)
{
    for (uint32_t i = 0; i < scene->num_lights; i++)
        if (scene->lights[i].type == IIR_LIGHT_SPOT) return *out = scene->lights[i], i;
    if (scene->num_lights > 0) return *out = scene->lights[0], 0;
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

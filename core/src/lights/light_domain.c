/* light_domain.c -- the four VPL domains of light_domain.h: each light's map between domain points
 * and emitted rays, its boundary, and its flux per unit domain area. Placing points is done in
 * double precision from float world coordinates, so a VPL's point follows from its stored position
 * alone; rays are made in float from the point rounded to float. */
#include "iir/light_domain.h"

#include <math.h>

#include "iir/rng.h"
#include "sampling.h"

const char *iir_domain_map_name(iir_domain_map map)
{
    static const char *const names[] = {"disk", "cap disk", "sphere", "sun disk", "area disk"};
    return (unsigned)map < sizeof names / sizeof names[0] ? names[map] : "?";
}

iir_status iir_light_domain_make(const iir_light *l, iir_light_domain *d, iir_error *err)
{
    iir_status st = iir_light_validate(l, err);
    if (st != IIR_OK) return st;
    *d = (iir_light_domain){.light = l, .eval = iir_light_prepare(l), .p = l->position};
    if (l->type == IIR_LIGHT_POINT) {
        d->map = IIR_MAP_SPHERE, d->shape = IIR_DOMAIN_SPHERE, d->R = 1.0;
        d->area = 4.0 * M_PI;
        return IIR_OK;
    }
    d->shape = IIR_DOMAIN_DISK;
    if (l->type == IIR_LIGHT_AREA) {
        d->eval.frame = iir_spot_frame(l);
        d->map = IIR_MAP_AREA_DISK, d->R = 1.0;
    } else if (l->type == IIR_LIGHT_SUN) {
        d->eval.frame = iir_spot_frame(l);
        d->map = IIR_MAP_SUN_DISK, d->R = (double)l->radius;
    } else if (l->profile == IIR_SPOT_GLTF) {
        d->map = IIR_MAP_CAP_DISK, d->R = (double)iir_gltf_spot_radius(l);
    } else {
        d->map = IIR_MAP_COSINE_DISK, d->R = (double)iir_spot_radius(l);
    }
    d->area = M_PI * d->R * d->R;
    return IIR_OK;
}

/* ---- placing points ---- */

static double dot3(const double a[3], iir_vec3 b)
{
    return a[0] * b.x + a[1] * b.y + a[2] * b.z;
}

static bool inside_disk(const iir_light_domain *d, const double s[3])
{
    return s[0] * s[0] + s[1] * s[1] < d->R * d->R;
}

/* Direction v (any length > 0) from the light onto its disk or sphere; see the table. */
static bool place_dir(const iir_light_domain *d, iir_vec3 v, double s[3])
{
    double a[3] = {v.x, v.y, v.z};
    double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    s[0] = s[1] = s[2] = 0.0;
    if (!(len > 0.0)) return false;
    const iir_frame *fr = &d->eval.frame;
    if (d->map == IIR_MAP_SPHERE) {
        for (int k = 0; k < 3; k++) s[k] = a[k] / len;
        return true;
    }
    s[0] = dot3(a, fr->r) / len;
    s[1] = dot3(a, fr->u) / len;
    double wf = dot3(a, fr->f) / len;
    if (d->map == IIR_MAP_CAP_DISK) { /* Lambert: scale the perpendicular part by sqrt(2/(1+wf)) */
        double k = sqrt(2.0 / fmax(1.0 + wf, 1e-300));
        s[0] *= k, s[1] *= k;
    } else {
        wf = dot3(a, fr->f); /* the cosine disk's test, as it always was: unnormalised */
    }
    return wf > 0.0 && inside_disk(d, s);
}

/* World point x onto the sun's disk: its offset from the centre along r and u. */
static bool place_sun(const iir_light_domain *d, iir_vec3 x, double s[3])
{
    const iir_frame *fr = &d->eval.frame;
    double a[3] = {(double)x.x - d->p.x, (double)x.y - d->p.y, (double)x.z - d->p.z};
    s[0] = dot3(a, fr->r), s[1] = dot3(a, fr->u), s[2] = 0.0;
    return inside_disk(d, s);
}

bool iir_domain_locate(const iir_light_domain *d, iir_vec3 x, double s[3])
{
    if (d->map == IIR_MAP_SUN_DISK) return place_sun(d, x, s);
    return place_dir(d, iir_sub(x, d->p), s);
}

void iir_domain_null_pose(const iir_light_domain *d, iir_vec3 o, iir_vec3 w, iir_vec3 *position,
                          iir_vec3 *dir)
{
    *dir = w;
    *position = d->p;
    if (d->map != IIR_MAP_SUN_DISK) return;
    /* o lies on the plane R behind the centre: the far root of |o + t w - c| = R */
    iir_vec3 oc = iir_sub(o, d->p);
    float b = iir_dot(oc, w), c = iir_dot(oc, oc) - (float)(d->R * d->R);
    *position = iir_madd(o, w, -b + iir_safe_sqrt(b * b - c));
}

bool iir_domain_locate_null(const iir_light_domain *d, iir_vec3 position, iir_vec3 dir, double s[3])
{
    return d->map == IIR_MAP_SUN_DISK ? place_sun(d, position, s) : place_dir(d, dir, s);
}

/* ---- rays ---- */

void iir_domain_ray(const iir_light_domain *d, const double s[3], iir_vec3 *o, iir_vec3 *w)
{
    const iir_frame *fr = &d->eval.frame;
    iir_vec2 t = iir_v2((float)s[0], (float)s[1]);
    *o = d->p;
    switch (d->map) {
    case IIR_MAP_COSINE_DISK:
    case IIR_MAP_AREA_DISK:
        *w = iir_normalize(iir_spot_disk_to_dir(fr, t));
        break;
    case IIR_MAP_CAP_DISK:
        *w = iir_normalize(iir_cap_disk_to_dir(fr, t));
        break;
    case IIR_MAP_SPHERE:
        *w = iir_normalize(iir_v3((float)s[0], (float)s[1], (float)s[2]));
        break;
    case IIR_MAP_SUN_DISK:
        *w = fr->f;
        *o = iir_add(iir_add(d->p, iir_scale(fr->r, t.x)), iir_scale(fr->u, t.y));
        *o = iir_madd(*o, fr->f, -(float)d->R);
        break;
    }
}

void iir_domain_null_ray(const iir_light_domain *d, iir_vec3 position, iir_vec3 dir, iir_vec3 *o,
                         iir_vec3 *w)
{
    if (d->map != IIR_MAP_SUN_DISK) {
        *o = d->p, *w = dir;
        return;
    }
    double s[3];
    place_sun(d, position, s);
    iir_domain_ray(d, s, o, w);
}

iir_vec3 iir_domain_origin(const iir_light_domain *d, iir_vec3 x)
{
    if (d->map != IIR_MAP_SUN_DISK) return d->p;
    const iir_vec3 f = d->eval.frame.f;
    return iir_madd(x, f, -(iir_dot(iir_sub(x, d->p), f) + (float)d->R));
}

bool iir_domain_faces(const iir_light_domain *d, iir_vec3 x, iir_vec3 n)
{
    if (d->map == IIR_MAP_SUN_DISK) return iir_dot(n, d->eval.frame.f) < 0.f;
    return iir_dot(n, iir_sub(d->p, x)) > 0.f;
}

/* ---- flux and sampling ---- */

float iir_domain_profile(const iir_light_domain *d, const double s[3])
{
    float rho = (float)sqrt(s[0] * s[0] + s[1] * s[1]);
    switch (d->map) {
    case IIR_MAP_COSINE_DISK:
        return iir_spot_falloff(d->light, rho);
    case IIR_MAP_CAP_DISK:
        return iir_gltf_spot_attenuation(&d->eval,
                                         (float)(1.0 - 0.5 * (s[0] * s[0] + s[1] * s[1])));
    case IIR_MAP_SPHERE:
    case IIR_MAP_SUN_DISK:
        return 1.f;
    case IIR_MAP_AREA_DISK:
        return iir_area_light_area(d->light);
    }
    return 0.f;
}

void iir_domain_sample(const iir_light_domain *d, iir_vec2 u, double margin, double s[3])
{
    if (d->shape == IIR_DOMAIN_SPHERE) {
        iir_vec3 w = iir_sample_uniform_sphere(u);
        s[0] = w.x, s[1] = w.y, s[2] = w.z;
        return;
    }
    float scale = (float)(d->R * (1.0 - margin));
    iir_vec2 q = iir_sample_uniform_disk_concentric(u);
    s[0] = (double)q.x * scale, s[1] = (double)q.y * scale, s[2] = 0.0;
}

void iir_domain_pull_inside(const iir_light_domain *d, const double c[3], double margin,
                            double s[3])
{
    if (d->shape == IIR_DOMAIN_SPHERE) {
        double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        for (int k = 0; k < 3; k++) s[k] = len > 0.0 ? c[k] / len : (k == 2);
        return;
    }
    double r = sqrt(c[0] * c[0] + c[1] * c[1]), rmax = d->R * (1.0 - margin);
    double k = r > rmax ? rmax / r : 1.0;
    s[0] = c[0] * k, s[1] = c[1] * k, s[2] = 0.0;
}

/* ---- area lights ---- */

iir_light_domain iir_domain_at_emitter(const iir_light_domain *d, iir_vec2 q)
{
    iir_light_domain at = *d;
    if (d->map != IIR_MAP_AREA_DISK) return at;
    const iir_frame *fr = &d->eval.frame;
    const iir_vec2 size = d->light->size;
    at.p = iir_add(iir_add(d->p, iir_scale(fr->r, q.x * size.x)), iir_scale(fr->u, q.y * size.y));
    return at;
}

iir_vec2 iir_domain_emitter_stratum(const iir_light_domain *d, uint32_t i)
{
    iir_vec2 u = iir_v2(iir_radical_inverse(3, i), iir_radical_inverse(5, i));
    if (d->map != IIR_MAP_AREA_DISK) return iir_v2(u.x - 0.5f, u.y - 0.5f);
    return iir_area_light_sample_q(d->light, u);
}

iir_light_domain iir_domain_at_stratum(const iir_light_domain *d, uint32_t i)
{
    return d->map == IIR_MAP_AREA_DISK ? iir_domain_at_emitter(d, iir_domain_emitter_stratum(d, i))
                                       : *d;
}

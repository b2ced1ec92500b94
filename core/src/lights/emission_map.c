/* emission_map.c -- an area light's radiance image (light.h): reading it, and the radiance the
 * light emits at a point of its rectangle. */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "iir/image.h"
#include "iir/light.h"

iir_status iir_emission_map_load(const char *path, iir_emission_map **out, iir_error *err)
{
    *out = NULL;
    iir_image *img = NULL;
    iir_status st = iir_image_read(path, &img, err);
    if (st != IIR_OK) return st;
    iir_emission_map *m = calloc(1, sizeof *m);
    if (!m) {
        iir_image_destroy(img);
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for the emission map %s", path);
    }
    m->width = img->width, m->height = img->height;
    m->texels = img->pixels; /* taken over */
    img->pixels = NULL;
    iir_image_destroy(img);
    double sum[3] = {0, 0, 0};
    for (size_t i = 0; i < (size_t)m->width * (size_t)m->height; i++)
        sum[0] += m->texels[i].x, sum[1] += m->texels[i].y, sum[2] += m->texels[i].z;
    double n = (double)m->width * (double)m->height;
    m->mean = iir_v3((float)(sum[0] / n), (float)(sum[1] / n), (float)(sum[2] / n));
    char abs[PATH_MAX];
    const char *full = realpath(path, abs) ? abs : path;
    if (strlen(full) >= sizeof m->path) {
        iir_emission_map_free(m);
        return iir_fail(err, IIR_ERR_INVALID, "emission map %s: its path is too long", path);
    }
    memcpy(m->path, full, strlen(full) + 1);
    *out = m;
    return IIR_OK;
}

void iir_emission_map_free(iir_emission_map *m)
{
    if (!m) return;
    free(m->texels);
    free(m);
}

/* Bilinear between texel centres at image coordinates (u, v) in [0, 1]^2, clamped at the edges. */
static iir_vec3 lookup(const iir_emission_map *m, float u, float v)
{
    float x = fminf(fmaxf(u, 0.f), 1.f) * (float)m->width - 0.5f;
    float y = fminf(fmaxf(v, 0.f), 1.f) * (float)m->height - 0.5f;
    int x0 = (int)floorf(x), y0 = (int)floorf(y);
    float ax = x - (float)x0, ay = y - (float)y0;
    int xa = x0 < 0 ? 0 : x0, xb = x0 + 1 >= m->width ? m->width - 1 : x0 + 1;
    int ya = y0 < 0 ? 0 : y0, yb = y0 + 1 >= m->height ? m->height - 1 : y0 + 1;
    const iir_vec3 *t = m->texels;
    iir_vec3 top =
        iir_add(iir_scale(t[ya * m->width + xa], 1.f - ax), iir_scale(t[ya * m->width + xb], ax));
    iir_vec3 bottom =
        iir_add(iir_scale(t[yb * m->width + xa], 1.f - ax), iir_scale(t[yb * m->width + xb], ax));
    return iir_add(iir_scale(top, 1.f - ay), iir_scale(bottom, ay));
}

iir_vec3 iir_area_light_radiance(const iir_light *l, iir_vec2 q)
{
    if (!l->map) return l->intensity;
    return iir_mul(l->intensity, lookup(l->map, q.x + 0.5f, 0.5f - q.y));
}

iir_vec3 iir_area_light_radiance_at(const iir_light *l, const iir_frame *fr, iir_vec3 x)
{
    if (!l->map) return l->intensity;
    iir_vec3 d = iir_sub(x, l->position);
    return iir_area_light_radiance(
        l, iir_v2(iir_dot(d, fr->r) / l->size.x, iir_dot(d, fr->u) / l->size.y));
}

iir_vec3 iir_area_light_mean_radiance(const iir_light *l)
{
    return l->map ? iir_mul(l->intensity, l->map->mean) : l->intensity;
}

/* area_hit.c -- the analytic ray test of an area light (IIR_LIGHT_AREA): its rectangle's plane,
 * then the point in its shape (area_shape.c); pt and the direct-light pass use it to see the
 * light, which is not in the scene's BVH. Not its sampling (light.c, lightset.c). */
#include "iir/light.h"

#include <math.h>

float iir_area_light_hit(const iir_light *l, iir_vec3 o, iir_vec3 d, float tmax)
{
    iir_frame fr = iir_spot_frame(l);
    float d_f = iir_dot(d, fr.f);
    if (!(d_f < 0.f)) return INFINITY; /* from behind, parallel or NaN */
    iir_vec3 to_c = iir_sub(l->position, o);
    float t = iir_dot(to_c, fr.f) / d_f;
    if (!(t > 0.f && t < tmax)) return INFINITY;
    iir_vec3 x = iir_sub(iir_madd(o, d, t), l->position);
    float a = iir_dot(x, fr.r), b = iir_dot(x, fr.u);
    if (fabsf(a) > 0.5f * l->size.x || fabsf(b) > 0.5f * l->size.y) return INFINITY;
    if (l->shape.num_triangles && !iir_area_light_contains(l, iir_v2(a / l->size.x, b / l->size.y)))
        return INFINITY;
    return t;
}

/* anim_eval.c -- evaluating a parsed animation script: the lights and the camera at time t (key
 * lookup, linear / Catmull-Rom / step interpolation, orbit and sweep paths, on/off); not parsing
 * or checking a script against a scene (anim_check.c). A sun keeps its disk: a track turns it,
 * never moves it.
 *
 * Every field is its own curve through the keys that give it; a key without the field does not
 * pin it. Catmull-Rom is the time-parameterised (non-uniform) one: a cubic Hermite segment whose
 * tangent at a key is (v[i+1] - v[i-1]) / (t[i+1] - t[i-1]), and the secant at the ends and next
 * to jumps, so the curve passes through the keys and its velocity in time is continuous. */
#include "anim_internal.h"

#include <math.h>
#include <string.h>

/* A segment of one field's curve: keys c, a, b, d (indices, -1 when absent) around t, with
 * t in [t_a, t_b) at fraction u. b < 0 means "hold a". */
typedef struct iir_anim_seg {
    int c, a, b, d;
    double u;
} iir_anim_seg;

static int next_with(const iir_anim_track *tr, unsigned mask, int from, int step)
{
    for (int i = from; i >= 0 && i < tr->num_keys; i += step)
        if (tr->keys[i].fields & mask) return i;
    return -1;
}

/* Finds the segment of the curve of the keys giving `mask` at time t; false when no key does. */
static bool seg_find(const iir_anim_track *tr, unsigned mask, double t, iir_anim_seg *s)
{
    s->c = s->b = s->d = -1;
    s->u = 0.0;
    /* Keys are in increasing time: binary search for the first key after t, then step back to
     * the last one that gives this field (recorded paths have 1e5 keys, all with every field). */
    int lo = 0, hi = tr->num_keys;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (tr->keys[mid].t <= t)
            lo = mid + 1;
        else
            hi = mid;
    }
    s->a = next_with(tr, mask, lo - 1, -1);
    if (s->a < 0) {
        s->a = next_with(tr, mask, 0, 1); /* before the first key: hold it */
        return s->a >= 0;
    }
    int b = next_with(tr, mask, s->a + 1, 1);
    if (b < 0 || tr->interp == IIR_ANIM_STEP || tr->keys[b].step) return true;
    const iir_anim_key *ka = &tr->keys[s->a], *kb = &tr->keys[b];
    s->b = b;
    s->u = (t - ka->t) / (kb->t - ka->t);
    if (tr->interp != IIR_ANIM_CATMULL_ROM) return true;
    s->c = ka->step ? -1 : next_with(tr, mask, s->a - 1, -1);
    s->d = next_with(tr, mask, b + 1, 1);
    if (s->d >= 0 && tr->keys[s->d].step) s->d = -1;
    return true;
}

/* Combines the values v[0..3] of keys c, a, b, d of segment s. */
static iir_vec3 seg_combine(const iir_anim_track *tr, const iir_anim_seg *s, const iir_vec3 v[4])
{
    if (s->b < 0) return v[1];
    float u = (float)s->u;
    if (tr->interp == IIR_ANIM_LINEAR) return iir_add(iir_scale(v[1], 1.f - u), iir_scale(v[2], u));
    double ta = tr->keys[s->a].t, tb = tr->keys[s->b].t, h = tb - ta;
    iir_vec3 secant = iir_scale(iir_sub(v[2], v[1]), (float)(1.0 / h));
    iir_vec3 m_a =
        s->c < 0 ? secant : iir_scale(iir_sub(v[2], v[0]), (float)(1.0 / (tb - tr->keys[s->c].t)));
    iir_vec3 m_b =
        s->d < 0 ? secant : iir_scale(iir_sub(v[3], v[1]), (float)(1.0 / (tr->keys[s->d].t - ta)));
    /* cubic Hermite basis */
    float u2 = u * u, u3 = u2 * u;
    float h00 = 2.f * u3 - 3.f * u2 + 1.f, h10 = u3 - 2.f * u2 + u;
    float h01 = -2.f * u3 + 3.f * u2, h11 = u3 - u2;
    iir_vec3 p = iir_add(iir_scale(v[1], h00), iir_scale(v[2], h01));
    p = iir_madd(p, m_a, h10 * (float)h);
    return iir_madd(p, m_b, h11 * (float)h);
}

static iir_vec3 key_value(const iir_anim_key *k, unsigned mask)
{
    switch (mask) {
    case IIR_AF_POSITION:
        return k->position;
    case IIR_AF_TARGET:
        return k->target;
    case IIR_AF_INTENSITY:
        return k->intensity;
    case IIR_AF_CONE:
        return iir_v3s(k->cone);
    case IIR_AF_SMOOTH:
        return iir_v3s(k->smooth);
    case IIR_AF_FOV:
        return iir_v3s(k->fov);
    case IIR_AF_UP:
        return k->up;
    case IIR_AF_INNER:
        return iir_v3s(k->inner);
    case IIR_AF_SIZE:
        return k->size;
    case IIR_AF_EXPOSURE:
        return iir_v3s(k->stops);
    default:
        return k->direction;
    }
}

/* The curve of a plain field at t; false (and *out untouched) when no key gives it. */
static bool eval_field(const iir_anim_track *tr, unsigned mask, double t, iir_vec3 *out)
{
    iir_anim_seg s;
    if (!seg_find(tr, mask, t, &s)) return false;
    const int idx[4] = {s.c, s.a, s.b, s.d};
    iir_vec3 v[4];
    for (int i = 0; i < 4; i++) v[i] = key_value(&tr->keys[idx[i] >= 0 ? idx[i] : s.a], mask);
    *out = seg_combine(tr, &s, v);
    return true;
}

static double clamp_time(const iir_anim *a, double t)
{
    return t > 0.0 ? (t < a->duration ? t : a->duration) : 0.0; /* NaN -> 0 */
}

static iir_vec3 eval_position(const iir_anim *a, const iir_anim_track *tr, iir_vec3 base, double t)
{
    double s = t / a->duration;
    if (tr->path == IIR_ANIM_ORBIT) {
        double phi = tr->phase + 2.0 * 3.14159265358979323846 * tr->turns * s;
        iir_vec3 off = iir_v3((float)cos(phi), 0.f, (float)sin(phi));
        return iir_madd(tr->center, off, (float)tr->radius);
    }
    if (tr->path == IIR_ANIM_SWEEP)
        return iir_add(iir_scale(tr->from, (float)(1.0 - s)), iir_scale(tr->to, (float)s));
    eval_field(tr, IIR_AF_POSITION, t, &base);
    return base;
}

/* Unit direction from `from` to `to`, or fallback when they coincide. */
static iir_vec3 aim_at(iir_vec3 from, iir_vec3 to, iir_vec3 fallback)
{
    iir_vec3 d = iir_sub(to, from);
    return iir_length(d) > 1e-6f ? iir_scale(d, 1.f / iir_length(d)) : fallback;
}

/* The light's unit direction at t. When every key used gives a target, the target point is
 * interpolated and the light aims at it; otherwise each key's aim becomes a direction (a target
 * seen from the light's position at that key's time) and the directions are interpolated and
 * renormalised. */
static iir_vec3 eval_aim(const iir_anim *a, const iir_anim_track *tr, const iir_light *base,
                         iir_vec3 pos, double t)
{
    iir_anim_seg s;
    if (!seg_find(tr, IIR_AF_DIRECTION | IIR_AF_TARGET, t, &s)) return base->direction;
    const int idx[4] = {s.c, s.a, s.b, s.d};
    bool all_targets = true;
    for (int i = 0; i < 4; i++)
        if (idx[i] >= 0) all_targets &= (tr->keys[idx[i]].fields & IIR_AF_TARGET) != 0;
    iir_vec3 v[4];
    for (int i = 0; i < 4; i++) {
        const iir_anim_key *k = &tr->keys[idx[i] >= 0 ? idx[i] : s.a];
        if (all_targets || !(k->fields & IIR_AF_TARGET))
            v[i] = all_targets ? k->target : k->direction;
        else
            v[i] = aim_at(eval_position(a, tr, base->position, k->t), k->target, base->direction);
    }
    iir_vec3 r = seg_combine(tr, &s, v);
    if (all_targets) return aim_at(pos, r, base->direction);
    /* opposite directions can cancel half-way: keep the nearer key's */
    return aim_at(iir_v3s(0.f), r, s.u < 0.5 ? v[1] : v[2]);
}

/* A sun is not moved in space: the track's position only aims it (a target seen from there), and
 * its disk stays the one base was fitted with (iir_light_fit_sun: the scene's bounding sphere,
 * which no light move changes). */
static void keep_sun_disk(iir_light *L, const iir_light *base)
{
    if (L->type != IIR_LIGHT_SUN) return;
    L->position = base->position;
    L->radius = base->radius;
}

/* On or off at t: the value of the last key at or before t that gives it; on before the first
 * (the scene's light as it is). */
static bool eval_on(const iir_anim_track *tr, double t)
{
    int lo = 0, hi = tr->num_keys; /* the first key after t */
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (tr->keys[mid].t <= t)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo == 0 || tr->keys[lo - 1].on_held;
}

/* Cone, smooth edge, inner cone, size and intensity, kept valid (see anim.h). */
static void eval_optics(const iir_anim_track *tr, double t, iir_light *L)
{
    iir_vec3 v;
    if (eval_field(tr, IIR_AF_CONE, t, &v))
        L->cone_angle = iir_radians(iir_clampf(v.x, 1e-3f, 90.f));
    if (eval_field(tr, IIR_AF_SMOOTH, t, &v)) L->smooth = iir_radians(fmaxf(v.x, 0.f));
    if (eval_field(tr, IIR_AF_INNER, t, &v)) L->inner_angle = iir_radians(fmaxf(v.x, 0.f));
    L->smooth = fminf(L->smooth, L->cone_angle);
    L->inner_angle = fminf(L->inner_angle, L->cone_angle); /* a glTF spot's inner cone */
    if (eval_field(tr, IIR_AF_SIZE, t, &v)) L->size = iir_v2(fmaxf(v.x, 1e-6f), fmaxf(v.y, 1e-6f));
    if (eval_field(tr, IIR_AF_INTENSITY, t, &v))
        L->intensity = iir_v3(fmaxf(v.x, 0.f), fmaxf(v.y, 0.f), fmaxf(v.z, 0.f));
    if (!eval_on(tr, t)) L->intensity = iir_v3s(0.f);
}

/* The light of track tr at t (already clamped), from base. */
static iir_light eval_light(const iir_anim *a, const iir_anim_track *tr, const iir_light *base,
                            double t)
{
    iir_light L = *base;
    L.position = eval_position(a, tr, base->position, t);
    L.direction = eval_aim(a, tr, base, L.position, t);
    keep_sun_disk(&L, base);
    iir_vec3 v;
    if (eval_field(tr, IIR_AF_UP, t, &v) && iir_length(v) > 1e-6f) L.up = iir_normalize(v);
    eval_optics(tr, t, &L);
    return L;
}

iir_light iir_anim_light(const iir_anim *a, const iir_light *base, double t)
{
    if (!a->light.present) return *base;
    return eval_light(a, &a->light, base, clamp_time(a, t));
}

int iir_anim_find_light(const iir_light *lights, uint32_t n, const char *name)
{
    int found = -1;
    for (uint32_t i = 0; i < n; i++) {
        if (strcmp(lights[i].name, name) != 0) continue;
        if (found >= 0) return -2;
        found = (int)i;
    }
    return found;
}

void iir_anim_lights(const iir_anim *a, const iir_light *lights, uint32_t n, uint32_t moved,
                     double t, iir_light *out)
{
    if (out != lights)
        for (uint32_t i = 0; i < n; i++) out[i] = lights[i];
    t = clamp_time(a, t);
    bool moves = moved < n && a->light.present;
    if (moves) out[moved] = eval_light(a, &a->light, &out[moved], t);
    for (int k = 0; k < a->num_lights; k++) {
        int i = iir_anim_find_light(out, n, a->lights[k].name);
        if (i >= 0 && !(moves && (uint32_t)i == moved))
            out[i] = eval_light(a, &a->lights[k], &out[i], t);
    }
}

iir_camera iir_anim_camera(const iir_anim *a, const iir_camera *base, double t)
{
    iir_camera cam = *base;
    const iir_anim_track *tr = &a->camera;
    if (!tr->present) return cam;
    t = clamp_time(a, t);
    cam.position = eval_position(a, tr, base->position, t);
    eval_field(tr, IIR_AF_TARGET, t, &cam.target);
    iir_vec3 v;
    if (eval_field(tr, IIR_AF_FOV, t, &v)) cam.fov_y = iir_clampf(v.x, 1e-3f, 179.999f);
    if (eval_field(tr, IIR_AF_UP, t, &v) && iir_length(v) > 1e-6f) cam.up = v; /* any length */
    return cam;
}

float iir_anim_exposure(const iir_anim *a, float base, double t)
{
    iir_vec3 v;
    if (!a->exposure.present || !eval_field(&a->exposure, IIR_AF_EXPOSURE, clamp_time(a, t), &v))
        return base;
    return iir_clampf(v.x, -30.f, 30.f);
}

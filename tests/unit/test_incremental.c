/* test_incremental.c -- the incremental instant radiosity step (incremental.h) against independent
 * answers in the built-in Cornell box: flux conservation against a dense quadrature of the disk
 * with the test's own rays, every VPL re-validated with the test's own ray, cone and facing test
 * over a random light path, the still-light budget, the budget along a smooth path, regeneration,
 * determinism, bad input. Timing is not a test: `iird bench` reports the step's phases per frame.
 * Nothing here shares code with incremental.c. */
#include <malloc.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/incremental.h"
#include "iir/rng.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "iir/tri.h"
#include "testutil.h"

/* ---- fixtures and small helpers ------------------------------------------------------------- */

/* The built-in Cornell box and its rays: the shared group fixture (testutil.h). */
typedef iir_test_cornell env;

/* splitmix64 over a counter: iir_mix64 adds the increment itself. */
static uint64_t next_u64(uint64_t *s)
{
    uint64_t z = *s;
    *s += 0x9e3779b97f4a7c15ull;
    return iir_mix64(z);
}

static double urand(uint64_t *s)
{
    return (double)(next_u64(s) >> 11) * 0x1.0p-53;
}

static double urange(uint64_t *s, double lo, double hi)
{
    return lo + (hi - lo) * urand(s);
}

static iir_light spot_at(iir_vec3 p, iir_vec3 dir, float cone_deg, float smooth_deg)
{
    iir_light l = {
        .type = IIR_LIGHT_SPOT,
        .name = "test_spot",
        .position = p,
        .direction = iir_normalize(dir),
        .up = iir_v3(0.f, 0.f, -1.f),
        .cone_angle = iir_radians(cone_deg),
        .smooth = iir_radians(smooth_deg),
        .intensity = iir_v3(3.f, 2.f, 0.75f),
    };
    return l;
}

/* The Cornell box's own spot: under the ceiling, aimed down, 60 degrees. */
static iir_light cornell_spot(const env *e)
{
    return e->scene->lights[0];
}

static iir_incr *make_incr(const env *e, uint32_t n, iir_weights w, uint64_t seed)
{
    iir_incr_params p = iir_incr_params_default();
    p.target = n;
    p.weights = w;
    p.seed = seed;
    iir_incr *inc = NULL;
    iir_error err = {0};
    if (iir_incr_create(e->scene, e->rt, &p, &inc, &err) != IIR_OK) fail_msg("create: %s", err.msg);
    return inc;
}

static iir_incr_stats update(iir_incr *inc, const iir_light *l)
{
    iir_incr_stats st;
    iir_error err = {0};
    if (iir_incr_update(inc, l, &st, &err) != IIR_OK) fail_msg("update: %s", err.msg);
    return st;
}

/* The renderer's part, faked: a one-texel "map" for every new non-null VPL, so LeakSanitizer
 * reports any map the step forgets to release. */
static void give_maps(iir_incr *inc)
{
    uint32_t n;
    iir_vpl *v = iir_incr_vpls(inc, &n);
    for (uint32_t i = 0; i < n; i++)
        if (!v[i].null_sample && v[i].smap.res == 0) {
            v[i].smap.depth = malloc(sizeof(uint16_t));
            v[i].smap.res = 1;
        }
}

static const iir_vpl *find_vpl(const iir_vpl *v, uint32_t n, uint32_t id)
{
    for (uint32_t lo = 0, hi = n; lo < hi;) {
        uint32_t mid = (lo + hi) / 2;
        if (v[mid].id == id) return &v[mid];
        if (v[mid].id < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    return NULL;
}

/* ---- the test's own geometry: disk coordinates and rays ---------------------------------------
 */

typedef struct dvec {
    double x, y, z;
} dvec;

static dvec dv(iir_vec3 a)
{
    dvec d = {a.x, a.y, a.z};
    return d;
}

static double ddot(dvec a, dvec b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

/* Own disk coordinates of world direction d from the light; returns w.f (> 0: front). */
static double own_disk(const iir_light *l, iir_vec3 d, double s[2])
{
    iir_frame fr = iir_spot_frame(l);
    dvec w = dv(d);
    double len = sqrt(ddot(w, w));
    s[0] = ddot(w, dv(fr.r)) / len;
    s[1] = ddot(w, dv(fr.u)) / len;
    return ddot(w, dv(fr.f)) / len;
}

/* Own direction for disk point s. */
static iir_vec3 own_dir(const iir_light *l, double sx, double sy)
{
    iir_frame fr = iir_spot_frame(l);
    double z = sqrt(fmax(0.0, 1.0 - sx * sx - sy * sy));
    return iir_v3((float)(sx * fr.r.x + sy * fr.u.x + z * fr.f.x),
                  (float)(sx * fr.r.y + sy * fr.u.y + z * fr.f.y),
                  (float)(sx * fr.r.z + sy * fr.u.z + z * fr.f.z));
}

/* What the light sees along unit w: the albedo of a reflecting (non-emitting, non-grazed)
 * surface, black otherwise; *t the hit distance (INFINITY on a miss). */
static iir_vec3 own_rho(const env *e, iir_vec3 p, iir_vec3 w, double *t)
{
    iir_ray ray = {p, 0.f, w, INFINITY};
    iir_hit hit;
    *t = INFINITY;
    if (!iir_rt_intersect(e->rt, &ray, &hit, NULL, IIR_RAYS_BENCH)) return iir_v3s(0.f);
    *t = hit.t;
    const iir_material *m = &e->scene->material_list[e->scene->materials[hit.prim]];
    bool grazing = iir_dot(e->scene->normals[hit.prim], w) == 0.f;
    if (!iir_is_black(m->emission) || grazing) return iir_v3s(0.f);
    return m->albedo;
}

static bool finite2(iir_vec2 a)
{
    return isfinite(a.x) && isfinite(a.y);
}

/* Own validity of a non-null VPL for light l: inside the cone, facing the light, and the first
 * surface along the ray from the light towards it is where it sits. Fails with a reason. */
static void check_vpl_valid(const env *e, const iir_light *l, const iir_vpl *v, int frame)
{
    double s[2], R = sin((double)l->cone_angle);
    iir_vec3 d = iir_sub(v->position, l->position);
    double wf = own_disk(l, d, s), dist = iir_length(d);
    if (!(wf > 0 && s[0] * s[0] + s[1] * s[1] < R * R))
        fail_msg("frame %d: VPL %u outside the cone (w.f %g, |s| %g, R %g)", frame, v->id, wf,
                 sqrt(s[0] * s[0] + s[1] * s[1]), R);
    if (!(iir_dot(v->normal, iir_sub(l->position, v->position)) > 0.f))
        fail_msg("frame %d: VPL %u faces away from the light", frame, v->id);
    if (fabs(v->disk.x - s[0]) > 1e-5 || fabs(v->disk.y - s[1]) > 1e-5)
        fail_msg("frame %d: VPL %u disk (%g, %g), own reprojection (%g, %g)", frame, v->id,
                 v->disk.x, v->disk.y, s[0], s[1]);
    double t;
    own_rho(e, l->position, iir_normalize(d), &t);
    if (!(fabs(t - dist) <= 1e-3 * dist + 1e-4))
        fail_msg("frame %d: VPL %u at distance %g, but the light's ray stops at %g (occluded)",
                 frame, v->id, dist, t);
    if (fabsf(iir_length(v->normal) - 1.f) > 1e-4f)
        fail_msg("frame %d: VPL %u normal not unit", frame, v->id);
}

/* Structural checks of the set after any update: finite values, ids ascending, null samples in
 * the disk with no flux, fluxes non-negative. */
static void check_set_shape(const iir_light *l, const iir_vpl *v, uint32_t n, int frame)
{
    double R = sin((double)l->cone_angle);
    for (uint32_t i = 0; i < n; i++) {
        if (!iir_is_finite3(v[i].position) || !iir_is_finite3(v[i].normal) ||
            !iir_is_finite3(v[i].flux) || !iir_is_finite3(v[i].albedo) || !finite2(v[i].disk))
            fail_msg("frame %d: VPL %u has a NaN/Inf field", frame, v[i].id);
        if (v[i].flux.x < 0 || v[i].flux.y < 0 || v[i].flux.z < 0)
            fail_msg("frame %d: VPL %u has negative flux", frame, v[i].id);
        if (i > 0 && v[i].id <= v[i - 1].id)
            fail_msg("frame %d: ids not ascending at %u", frame, i);
        if (v[i].null_sample) {
            double r = hypot(v[i].disk.x, v[i].disk.y);
            if (!(r < R))
                fail_msg("frame %d: null sample %u at |s| %g >= R %g", frame, v[i].id, r, R);
            if (!iir_is_black(v[i].flux))
                fail_msg("frame %d: null sample %u carries flux", frame, v[i].id);
        }
    }
}

/* ---- flux conservation ---------------------------------------------------------------------- */

/* Dense quadrature of the disk by the test's own rays: G x G equal-area polar strata
 * (r = R sqrt((i + xi) / G), phi = 2 pi (j + xi') / G), one jittered ray each.
 *   g(s)   = rho(s) falloff(|s|): what the light's flux meets, per unit I0 and disk area;
 *   D      = a sum_k g(s_k) estimates the integral of g over the disk (a = pi R^2 / G^2);
 *   g_i    = the same quantity at VPL i's site (0 for a null sample), from the VPL's albedo;
 *   T      = a sum_k g_{site(s_k)}, with site() the nearest site (the Voronoi cell) -- an estimate
 *            of sum_i g_i A_i, the flux of the set with Voronoi weights, per unit I0;
 *   L1     = a sum_k |g_{site(s_k)} - g(s_k)|, so |T - D| <= L1 exactly (triangle inequality):
 *            the error of the piecewise-constant Voronoi quadrature, measured, not guessed.
 * Stratified sampling errs only in strata that straddle an edge of g (K_g of them) or of a cell
 * (K_c), each by at most a (values in [0, 1]); with independent jitter, the standard deviation is
 * at most a sqrt(K) / 2. K is counted as strata whose neighbour differs, doubled for safety.
 * So, per channel, the set conserves flux when
 *   |sum_i Phi_i / I0 - D| <= L1 + 5 a (sqrt(2 K_g) + sqrt(2 K_c)) / 2 (+ a float slack),
 * and with uniform weights sum_i g_i pi R^2 / n differs from T by at most
 *   sum_i g_i |pi R^2 / n - Ahat_i| (Ahat_i = a * strata in cell i), added to the bound. */
typedef struct quad {
    double D[3], L1[3], T[3], bound_extra;
    uint32_t Kg, Kc;
    double a;
} quad;

enum { G = 256 };

static double chan(iir_vec3 v, int c)
{
    return c == 0 ? v.x : (c == 1 ? v.y : v.z);
}

static quad dense_quadrature(const env *e, iir_incr *inc, const iir_light *l, double *Ahat,
                             uint32_t *Kcell)
{
    uint32_t n;
    const iir_vpl *v = iir_incr_vpls(inc, &n);
    const iir_tri *tri = iir_incr_tri(inc);
    double R = sin((double)l->cone_angle);
    quad q = {.a = IIR_PI * R * R / ((double)G * G)};
    uint32_t *site = malloc(sizeof(uint32_t) * G * G);
    iir_vec3 *g = malloc(sizeof(iir_vec3) * G * G);
    uint64_t rs = 12345;
    for (uint32_t i = 0; i < n; i++) Ahat[i] = 0, Kcell[i] = 0;
    for (int i = 0; i < G; i++)
        for (int j = 0; j < G; j++) {
            double r = R * sqrt((i + urand(&rs)) / G), phi = 2 * M_PI * (j + urand(&rs)) / G;
            double sx = r * cos(phi), sy = r * sin(phi), t;
            iir_vec3 rho = own_rho(e, l->position, own_dir(l, sx, sy), &t);
            g[i * G + j] = iir_scale(rho, iir_spot_falloff(l, (float)r));
            uint32_t id;
            assert_int_equal(iir_tri_nearest(tri, sx, sy, &id, NULL), IIR_TRI_OK);
            const iir_vpl *vi = find_vpl(v, n, id);
            assert_non_null(vi);
            site[i * G + j] = (uint32_t)(vi - v);
            Ahat[vi - v] += q.a;
            iir_vec3 gi =
                vi->null_sample
                    ? iir_v3s(0.f)
                    : iir_scale(vi->albedo, iir_spot_falloff(l, hypotf(vi->disk.x, vi->disk.y)));
            for (int c = 0; c < 3; c++) {
                q.D[c] += q.a * chan(g[i * G + j], c);
                q.T[c] += q.a * chan(gi, c);
                q.L1[c] += q.a * fabs(chan(gi, c) - chan(g[i * G + j], c));
            }
        }
    for (int i = 0; i < G; i++)
        for (int j = 0; j < G; j++) {
            int k = i * G + j, right = i * G + (j + 1) % G, up = i + 1 < G ? k + G : k;
            iir_vec3 d1 = iir_sub(g[k], g[right]), d2 = iir_sub(g[k], g[up]);
            q.Kg += !iir_is_black(d1) || !iir_is_black(d2);
            bool straddles = site[k] != site[right] || site[k] != site[up];
            q.Kc += straddles;
            Kcell[site[k]] += straddles;
        }
    free(site);
    free(g);
    return q;
}

static void check_conservation(const env *e, iir_incr *inc, const iir_light *l, const char *what)
{
    uint32_t n;
    const iir_vpl *v = iir_incr_vpls(inc, &n);
    double *Ahat = calloc(n, sizeof(double));
    uint32_t *Kcell = calloc(n, sizeof(uint32_t));
    quad q = dense_quadrature(e, inc, l, Ahat, Kcell);
    double R = sin((double)l->cone_angle), Aunif = IIR_PI * R * R / n;
    bool uniform = iir_incr_get_params(inc).weights == IIR_WEIGHTS_UNIFORM;
    double stat = 2.5 * q.a * (sqrt(2.0 * q.Kg) + sqrt(2.0 * q.Kc));
    for (int c = 0; c < 3; c++) {
        double I0 = chan(l->intensity, c), sum = 0, nonunif = 0;
        for (uint32_t i = 0; i < n; i++) {
            sum += chan(v[i].flux, c) / I0;
            double gi =
                v[i].null_sample
                    ? 0
                    : chan(v[i].albedo, c) * iir_spot_falloff(l, hypotf(v[i].disk.x, v[i].disk.y));
            nonunif += gi * fabs(Aunif - Ahat[i]);
        }
        /* the weights themselves: with Voronoi weights the set's flux is sum_i g_i A_i, which T
         * estimates from the dense cell areas within the straddling error alone */
        double cells = 2.5 * q.a * sqrt(2.0 * q.Kc) + 1e-5 * q.T[c];
        if (!uniform && !(fabs(sum - q.T[c]) <= cells))
            fail_msg("%s: channel %d: sum Phi_i / I0 = %.6f, but sum g_i Ahat_i = %.6f (tol %.3g)",
                     what, c, sum, q.T[c], cells);
        double bound = q.L1[c] + stat + (uniform ? nonunif : 0) + 1e-5 * q.D[c];
        print_message("%s ch%d: sum Phi/I0 %.5f, dense %.5f (rel %+.3f%%), bound %.5f (L1 %.5f, "
                      "stat %.5f%s); sum g_i Ahat_i %.5f\n",
                      what, c, sum, q.D[c], 100 * (sum - q.D[c]) / q.D[c], bound, q.L1[c], stat,
                      uniform ? ", + nonuniform cells" : "", q.T[c]);
        if (!(fabs(sum - q.D[c]) <= bound))
            fail_msg("%s: channel %d: sum Phi_i / I0 = %.6f, dense quadrature %.6f, |diff| %.3g > "
                     "bound %.3g",
                     what, c, sum, q.D[c], fabs(sum - q.D[c]), bound);
    }
    /* Per VPL: the flux is I0 rho_i A_i falloff with A_i its cell's area (Voronoi, against the
     * dense count, within that cell's straddling error) or pi R^2 / n (uniform, to 1e-4). */
    for (uint32_t i = 0; i < n; i++) {
        if (v[i].null_sample) {
            assert_true(iir_is_black(v[i].flux));
            continue;
        }
        /* A f: the flux per unit I0 rho; f from the float disk point, whose rounding moves the
         * smooth edge's falloff by far less than 1e-4 */
        double f = iir_spot_falloff(l, hypotf(v[i].disk.x, v[i].disk.y));
        if (v[i].albedo.x <= 0) continue;
        double Af = v[i].flux.x / (l->intensity.x * v[i].albedo.x);
        double tol = uniform ? 1e-4 * Aunif
                             : (2.5 * q.a * sqrt(4.0 * Kcell[i] + 4.0) + q.a) * f + 1e-4 * Aunif;
        double expect = (uniform ? Aunif : Ahat[i]) * f;
        if (!(fabs(Af - expect) <= tol))
            fail_msg("%s: VPL %u: area x falloff from flux %.6g, expected %.6g (tol %.3g)", what,
                     v[i].id, Af, expect, tol);
    }
    free(Ahat);
    free(Kcell);
}

static void run_conservation(const env *e, iir_light l, uint32_t n, iir_weights w, int moves,
                             const char *what)
{
    iir_incr *inc = make_incr(e, n, w, 7);
    update(inc, &l);
    check_conservation(e, inc, &l, what);
    /* after a drift of small moves the set is no longer the Hammersley set */
    for (int f = 0; f < moves; f++) {
        l.position.x += 0.004f;
        l.direction = iir_normalize(iir_add(l.direction, iir_v3(0.003f, 0.f, 0.002f)));
        update(inc, &l);
    }
    if (moves) check_conservation(e, inc, &l, what);
    iir_incr_destroy(inc);
}

static void test_flux_conservation_enclosed(void **state)
{
    const env *e = *state;
    iir_light l = cornell_spot(e);
    run_conservation(e, l, 256, IIR_WEIGHTS_VORONOI, 40, "enclosed voronoi N=256");
    run_conservation(e, l, 256, IIR_WEIGHTS_UNIFORM, 0, "enclosed uniform N=256");
    run_conservation(e, l, 2048, IIR_WEIGHTS_VORONOI, 0, "enclosed voronoi N=2048");
}

/* Aimed out of the open front of the box: the centre of the cone escapes, so null samples exist,
 * carry nothing, and the set still carries exactly the flux that meets the box. A smooth edge. */
static void test_flux_conservation_escaping(void **state)
{
    const env *e = *state;
    iir_light l = spot_at(iir_v3(0.1f, 1.0f, -0.6f), iir_v3(0.f, -0.1f, 1.f), 70.f, 10.f);
    for (int k = 0; k < 2; k++) {
        iir_weights w = k ? IIR_WEIGHTS_UNIFORM : IIR_WEIGHTS_VORONOI;
        iir_incr *inc = make_incr(e, 256, w, 3);
        iir_incr_stats st = update(inc, &l);
        assert_true(st.vpl.null_samples > 20);
        assert_true(st.vpl.null_samples < st.vpl.count);
        check_conservation(e, inc, &l, k ? "escaping uniform" : "escaping voronoi");
        iir_incr_destroy(inc);
    }
    run_conservation(e, l, 256, IIR_WEIGHTS_VORONOI, 40, "escaping voronoi after moves");
}

/* ---- the property test: a random light path ----------------------------------------------------
 */

typedef struct tracker {
    uint32_t *prev_ids, prev_n, max_id_seen;
    bool any;
} tracker;

/* No id is ever reused: an id at most the largest seen before must have been in the previous set;
 * ids above it are exactly this frame's new VPLs, born now. Returns how many are new. */
static uint32_t track_ids(tracker *tr, const iir_vpl *v, uint32_t n, uint32_t frame)
{
    uint32_t fresh = 0, j = 0;
    for (uint32_t i = 0; i < n; i++) {
        if (tr->any && v[i].id <= tr->max_id_seen) {
            while (j < tr->prev_n && tr->prev_ids[j] < v[i].id) j++;
            if (j == tr->prev_n || tr->prev_ids[j] != v[i].id)
                fail_msg("frame %u: id %u reappeared after it died", frame, v[i].id);
            if (v[i].birth >= frame)
                fail_msg("frame %u: old VPL %u has a new birth", frame, v[i].id);
        } else {
            fresh++;
            if (v[i].birth != frame)
                fail_msg("frame %u: new VPL %u born %u", frame, v[i].id, v[i].birth);
        }
    }
    tr->prev_ids = realloc(tr->prev_ids, sizeof(uint32_t) * (n + 1));
    for (uint32_t i = 0; i < n; i++) {
        tr->prev_ids[i] = v[i].id;
        if (!tr->any || v[i].id > tr->max_id_seen) tr->max_id_seen = v[i].id;
        tr->any = true;
    }
    tr->prev_n = n;
    return fresh;
}

/* The budgets of one frame (DELETE and INSERT), exactly as incremental.h defines them. */
static void check_budgets(const iir_incr_params *p, const iir_incr_stats *st, uint32_t count_prev,
                          int frame)
{
    if (count_prev - st->vpl.invalidated - st->vpl.deleted + st->vpl.inserted != st->vpl.count)
        fail_msg("frame %d: %u - %u - %u + %u != %u", frame, count_prev, st->vpl.invalidated,
                 st->vpl.deleted, st->vpl.inserted, st->vpl.count);
    if (st->vpl.count > p->target)
        fail_msg("frame %d: count %u > N %u", frame, st->vpl.count, p->target);
    if (st->vpl.regenerated || st->initial) {
        assert_true(st->vpl.count > 0);
        return;
    }
    int64_t v = st->vpl.valid, want = (int64_t)p->k_min - st->vpl.invalidated;
    if (v - (int64_t)p->target > want) want = v - (int64_t)p->target;
    if (want < 0) want = 0;
    if (want > (v > 0 ? v - 1 : 0)) want = v > 0 ? v - 1 : 0;
    if ((int64_t)st->vpl.deleted != want)
        fail_msg("frame %d: deleted %u, expected %lld (valid %u, invalidated %u)", frame,
                 st->vpl.deleted, (long long)want, st->vpl.valid, st->vpl.invalidated);
    /* "big enough": with at least k_min - invalidated + 1 sites left after validation, the frame
     * replaced at least k_min */
    if (v >= (int64_t)p->k_min - st->vpl.invalidated + 1 &&
        st->vpl.deleted + st->vpl.invalidated < p->k_min)
        fail_msg("frame %d: only %u replaced, k_min %u", frame,
                 st->vpl.deleted + st->vpl.invalidated, p->k_min);
    if (st->vpl.inserted > p->k_max)
        fail_msg("frame %d: inserted %u > k_max", frame, st->vpl.inserted);
    uint32_t after_delete = st->vpl.valid - st->vpl.deleted;
    uint32_t fill = p->target - after_delete < p->k_max ? p->target - after_delete : p->k_max;
    if (st->vpl.inserted != fill)
        fail_msg("frame %d: inserted %u, expected %u", frame, st->vpl.inserted, fill);
}

/* A random step of the light: kind 0 small (1 cm, ~2 degrees), 1 large (15 cm, ~25 degrees), 2 a
 * jump anywhere, any aim. The light roams inside the box and around it (through its walls and out
 * of its open front), so VPLs die by the cone, by occlusion and by facing away. */
static iir_light random_move(iir_light l, uint64_t *rs, int kind)
{
    float step = kind == 0 ? 0.01f : 0.15f, turn = kind == 0 ? 0.03f : 0.4f;
    if (kind == 2) {
        bool inside = urand(rs) < 0.6;
        l.position = inside ? iir_v3((float)urange(rs, -0.9, 0.9), (float)urange(rs, 0.1, 1.9),
                                     (float)urange(rs, -0.95, 0.9))
                            : iir_v3((float)urange(rs, -2.5, 2.5), (float)urange(rs, -0.8, 2.8),
                                     (float)urange(rs, -2.5, 3.5));
        step = 0.f;
        turn = 3.f;
    }
    l.position.x = iir_clampf(l.position.x + step * (float)urange(rs, -1, 1), -2.5f, 2.5f);
    l.position.y = iir_clampf(l.position.y + step * (float)urange(rs, -1, 1), -0.8f, 2.8f);
    l.position.z = iir_clampf(l.position.z + step * (float)urange(rs, -1, 1), -2.5f, 3.5f);
    iir_vec3 jitter =
        iir_v3((float)urange(rs, -1, 1), (float)urange(rs, -1, 1), (float)urange(rs, -1, 1));
    iir_vec3 d = iir_normalize(iir_madd(l.direction, jitter, turn));
    if (iir_length(d) > 0.5f) l.direction = d;
    return l;
}

static void test_property_random_path(void **state)
{
    const env *e = *state;
    iir_incr *inc = make_incr(e, 256, IIR_WEIGHTS_VORONOI, 11);
    iir_incr_params p = iir_incr_get_params(inc);
    iir_light l = cornell_spot(e);
    uint64_t rs = 99;
    tracker tr = {0};
    uint32_t count_prev = 0, still = 0, regens = 0, nulls_seen = 0;
    enum { FRAMES = 400 };
    for (int f = 0; f < FRAMES; f++) {
        bool hold = (f >= 120 && f < 180) || (f >= 300 && f < 350);
        if (!hold && f > 0) {
            double u = urand(&rs);
            int kind = u < 0.75 ? 0 : (u < 0.93 ? 1 : 2);
            l = random_move(l, &rs, kind);
            if (urand(&rs) < 0.08) { /* a cone angle change, sometimes with a smooth edge */
                l.cone_angle = iir_radians((float)urange(&rs, 15, 90));
                l.smooth = urand(&rs) < 0.5 ? 0.f : l.cone_angle * (float)urange(&rs, 0, 0.3);
            }
        }
        still = hold ? still + 1 : 0;
        iir_incr_stats st = update(inc, &l);
        give_maps(inc);
        uint32_t n;
        const iir_vpl *v = iir_incr_vpls(inc, &n);
        assert_int_equal(n, st.vpl.count);
        check_set_shape(&l, v, n, f);
        uint32_t nulls = 0;
        for (uint32_t i = 0; i < n; i++) {
            if (v[i].null_sample)
                nulls++;
            else
                check_vpl_valid(e, &l, &v[i], f);
        }
        assert_int_equal(nulls, st.vpl.null_samples);
        check_budgets(&p, &st, count_prev, f);
        assert_int_equal(track_ids(&tr, v, n, (uint32_t)f), st.vpl.inserted);
        /* after a jump the set refills by k_max - k_min per frame: at most N / 2 / 4 + 1 frames */
        if (still > p.target / 2 / (p.k_max - p.k_min) + 1 && st.vpl.count != p.target)
            fail_msg("frame %d: light still for %u frames, count %u != N", f, still, st.vpl.count);
        for (int ph = 0; ph < IIR_INCR_PHASE_COUNT; ph++) assert_true(st.phase_ms[ph] >= 0);
        assert_true(st.rays.n[IIR_RAYS_VPL] == iir_raystats_total(&st.rays));
        regens += st.vpl.regenerated;
        nulls_seen += st.vpl.null_samples > 0;
        count_prev = st.vpl.count;
    }
    print_message("random path: %d frames, %u regenerations, %u frames with null samples\n", FRAMES,
                  regens, nulls_seen);
    assert_true(regens > 0); /* the path has jumps: the fallback was exercised */
    free(tr.prev_ids);
    iir_incr_destroy(inc);
}

/* ---- a still light ----------------------------------------------------------------------------
 */

static void test_still_light(void **state)
{
    const env *e = *state;
    iir_incr *inc = make_incr(e, 256, IIR_WEIGHTS_VORONOI, 5);
    iir_incr_params p = iir_incr_get_params(inc);
    iir_light l = spot_at(iir_v3(0.2f, 1.5f, 0.1f), iir_v3(-0.3f, -1.f, -0.2f), 55.f, 0.f);
    tracker tr = {0};
    uint32_t count_prev = 0;
    for (int f = 0; f < 60; f++) {
        iir_incr_stats st = update(inc, &l);
        give_maps(inc);
        uint32_t n;
        const iir_vpl *v = iir_incr_vpls(inc, &n);
        uint32_t fresh = track_ids(&tr, v, n, (uint32_t)f);
        check_budgets(&p, &st, count_prev, f);
        if (f == 0) {
            assert_int_equal(st.initial, 1);
            assert_int_equal(st.vpl.regenerated, 0);
            assert_int_equal(st.vpl.inserted, p.target);
        } else {
            /* nothing dies on its own; exactly k_min are replaced, by k_min new ones */
            assert_int_equal(st.vpl.invalidated, 0);
            assert_int_equal(st.vpl.deleted, p.k_min);
            assert_int_equal(st.vpl.inserted, p.k_min);
            assert_int_equal(fresh, p.k_min);
            assert_int_equal(st.vpl.regenerated, 0);
        }
        assert_int_equal(st.vpl.count, p.target);
        assert_int_equal(st.vpl.valid, f == 0 ? 0 : p.target);
        count_prev = st.vpl.count;
    }
    free(tr.prev_ids);
    iir_incr_destroy(inc);
}

/* ---- regeneration -----------------------------------------------------------------------------
 */

static void test_regeneration_on_teleport(void **state)
{
    const env *e = *state;
    for (int k = 0; k < 2; k++) {
        iir_incr *inc = make_incr(e, 256, IIR_WEIGHTS_VORONOI, 21);
        iir_incr_params p = iir_incr_get_params(inc);
        if (k == 1) { /* threshold 1: nothing short of everything dying regenerates */
            p.regen_threshold = 1.f;
            assert_int_equal(iir_incr_set_params(inc, &p, NULL), IIR_OK);
        }
        iir_light l = spot_at(iir_v3(0.f, 1.f, 0.f), iir_v3(0.f, -1.f, 0.f), 60.f, 0.f);
        uint32_t first_new = 0;
        for (int f = 0; f < 5; f++) update(inc, &l);
        give_maps(inc);
        uint32_t n;
        const iir_vpl *v = iir_incr_vpls(inc, &n);
        first_new = v[n - 1].id + 1;
        l.direction = iir_v3(0.f, 1.f, 0.f); /* the other way: every VPL is behind the light */
        iir_incr_stats st = update(inc, &l);
        give_maps(inc);
        v = iir_incr_vpls(inc, &n);
        assert_int_equal(st.vpl.valid, 0);
        assert_int_equal(st.vpl.invalidated, p.target);
        assert_int_equal(st.vpl.regenerated, 1); /* an empty set is always regenerated */
        assert_int_equal(st.vpl.count, p.target);
        check_set_shape(&l, v, n, 5);
        for (uint32_t i = 0; i < n; i++) {
            assert_true(v[i].id >= first_new); /* fresh ids */
            if (!v[i].null_sample) check_vpl_valid(e, &l, &v[i], 5);
        }
        assert_true(st.vpl.null_samples <
                    n / 2); /* the open front lets only part of the cone out */
        /* half the cone turns away: 50% threshold regenerates, threshold 1 refills slowly */
        l.direction = iir_normalize(iir_v3(1.f, 0.6f, 0.f));
        st = update(inc, &l);
        give_maps(inc);
        v = iir_incr_vpls(inc, &n);
        print_message("threshold %.1f: turned 60 degrees: invalidated %u of %u, regenerated %u\n",
                      (double)p.regen_threshold, st.vpl.invalidated, p.target, st.vpl.regenerated);
        assert_true(st.vpl.invalidated > p.target / 2 && st.vpl.invalidated < p.target);
        assert_int_equal(st.vpl.regenerated, k == 0);
        assert_int_equal(st.vpl.count, k == 0 ? p.target : p.target - st.vpl.invalidated + p.k_max);
        check_set_shape(&l, v, n, 6);
        for (uint32_t i = 0; i < n; i++)
            if (!v[i].null_sample) check_vpl_valid(e, &l, &v[i], 6);
        iir_incr_destroy(inc);
    }
}

/* ---- facing: a light that steps through a wall ----------------------------------------------- */

/* From just inside the right wall to just behind it, turned round: the wall's VPLs stay inside the
 * cone and the segment to them crosses nothing, so only the facing test can (and must) remove
 * them. */
static void test_facing_light_through_wall(void **state)
{
    const env *e = *state;
    iir_incr *inc = make_incr(e, 256, IIR_WEIGHTS_VORONOI, 6);
    iir_incr_params p = iir_incr_get_params(inc);
    p.regen_threshold = 1.f; /* keep the survivors: no regeneration */
    assert_int_equal(iir_incr_set_params(inc, &p, NULL), IIR_OK);
    iir_light l = spot_at(iir_v3(0.9f, 1.f, 0.f), iir_v3(1.f, 0.f, 0.f), 60.f, 0.f);
    update(inc, &l);
    uint32_t n, on_wall = 0;
    const iir_vpl *v = iir_incr_vpls(inc, &n);
    for (uint32_t i = 0; i < n; i++) on_wall += !v[i].null_sample && v[i].position.x > 0.99f;
    assert_true(on_wall > n / 2);
    l.position.x = 1.1f;
    l.direction = iir_v3(-1.f, 0.f, 0.f);
    iir_incr_stats st = update(inc, &l);
    /* the wall's VPLs face away, every other one is behind the wall: nothing survives, and the
     * empty set is regenerated (whatever the threshold) on the wall's outer face */
    assert_int_equal(st.vpl.valid, 0);
    assert_int_equal(st.vpl.invalidated, n);
    assert_int_equal(st.vpl.regenerated, 1);
    v = iir_incr_vpls(inc, &n);
    check_set_shape(&l, v, n, 1);
    for (uint32_t i = 0; i < n; i++)
        if (!v[i].null_sample) check_vpl_valid(e, &l, &v[i], 1);
    iir_incr_destroy(inc);
}

/* ---- determinism ---------------------------------------------------------------------------- */

static bool same_vpl(const iir_vpl *a, const iir_vpl *b)
{
    return a->id == b->id && a->null_sample == b->null_sample && a->birth == b->birth &&
           !memcmp(&a->position, &b->position, sizeof a->position) &&
           !memcmp(&a->normal, &b->normal, sizeof a->normal) &&
           !memcmp(&a->albedo, &b->albedo, sizeof a->albedo) &&
           !memcmp(&a->flux, &b->flux, sizeof a->flux) &&
           !memcmp(&a->disk, &b->disk, sizeof a->disk);
}

static void test_determinism(void **state)
{
    const env *e = *state;
    iir_incr *a = make_incr(e, 200, IIR_WEIGHTS_VORONOI, 42);
    iir_incr *b = make_incr(e, 200, IIR_WEIGHTS_VORONOI, 42);
    iir_incr *c = make_incr(e, 200, IIR_WEIGHTS_VORONOI, 43);
    iir_light l = cornell_spot(e);
    uint64_t rs = 5;
    bool differs = false;
    for (int f = 0; f < 80; f++) {
        if (f > 0) l = random_move(l, &rs, f % 25 == 0 ? 2 : (f % 7 == 0 ? 1 : 0));
        update(a, &l);
        update(b, &l);
        update(c, &l);
        uint32_t na, nb, nc;
        const iir_vpl *va = iir_incr_vpls(a, &na), *vb = iir_incr_vpls(b, &nb),
                      *vc = iir_incr_vpls(c, &nc);
        assert_int_equal(na, nb);
        for (uint32_t i = 0; i < na; i++)
            if (!same_vpl(&va[i], &vb[i])) fail_msg("frame %d: VPL %u differs between runs", f, i);
        for (uint32_t i = 0; i < na && i < nc && !differs; i++)
            differs = memcmp(&va[i].position, &vc[i].position, sizeof va[i].position) != 0;
    }
    assert_true(differs);
    iir_incr_destroy(a);
    iir_incr_destroy(b);
    iir_incr_destroy(c);
}

/* ---- deaths spread over frames ------------------------------------------------------------------
 */

/* A cone that narrows a little every frame kills the VPLs near the disk's rim: each frame fewer
 * than regen_threshold of the set, but more than k_max insertions can refill. The set must not
 * dwindle below (1 - regen_threshold) N: it is regenerated instead (once a frame's deaths leave
 * fewer), and a narrowed cone that then holds still keeps a full set. */
static void test_gradual_deaths_regenerate(void **state)
{
    const env *e = *state;
    iir_incr *inc = make_incr(e, 256, IIR_WEIGHTS_VORONOI, 3);
    iir_incr_params p = iir_incr_get_params(inc);
    iir_light l = cornell_spot(e);
    update(inc, &l);
    uint32_t prev = 256, regens = 0, min_count = 256;
    for (int f = 1; f <= 30; f++) {
        l.cone_angle *= 0.96f; /* the disk's area shrinks ~8% a frame */
        if (l.smooth > l.cone_angle) l.smooth = l.cone_angle;
        iir_incr_stats st = update(inc, &l);
        assert_true((double)st.vpl.invalidated <= p.regen_threshold * prev || st.vpl.regenerated);
        regens += st.vpl.regenerated;
        min_count = st.vpl.count < min_count ? st.vpl.count : min_count;
        assert_true((double)st.vpl.count >= (1.0 - p.regen_threshold) * p.target);
        prev = st.vpl.count;
    }
    assert_true(regens >= 1);
    for (int f = 0; f < 5; f++) assert_int_equal(update(inc, &l).vpl.regenerated, 0);
    print_message("narrowing cone: %u regenerations in 30 frames, smallest set %u\n", regens,
                  min_count);
    iir_incr_destroy(inc);
}

/* ---- parameter changes ----------------------------------------------------------------------- */

static void test_param_changes(void **state)
{
    const env *e = *state;
    iir_incr *inc = make_incr(e, 256, IIR_WEIGHTS_VORONOI, 8);
    iir_light l = cornell_spot(e);
    update(inc, &l);
    iir_incr_params p = iir_incr_get_params(inc);
    p.target = 100;
    assert_int_equal(iir_incr_set_params(inc, &p, NULL), IIR_OK);
    iir_incr_stats st = update(inc, &l);
    assert_int_equal(st.vpl.count, 100);
    assert_int_equal(st.vpl.deleted, 156);
    assert_int_equal(st.vpl.inserted, 0);
    p.target = 300;
    p.weights = IIR_WEIGHTS_UNIFORM;
    assert_int_equal(iir_incr_set_params(inc, &p, NULL), IIR_OK);
    uint32_t frames = 0;
    do {
        st = update(inc, &l);
        assert_true(st.vpl.inserted <= p.k_max);
        frames++;
        if (frames == 10) { /* uniform weights while the set is below N: pi R^2 / count */
            assert_int_equal(st.vpl.count, 140);
            check_conservation(e, inc, &l, "filling from 100 to 300, uniform");
        }
    } while (st.vpl.count < 300 && frames < 200);
    assert_int_equal(st.vpl.count, 300);
    assert_int_equal(frames, (300 - 100 + 3) / 4); /* net k_max - k_min = 4 per frame */
    check_conservation(e, inc, &l, "after N 256 -> 100 -> 300, uniform");
    iir_incr_destroy(inc);
}

/* ---- bad input --------------------------------------------------------------------------------
 */

static void expect_invalid(iir_status st, const iir_error *err, const char *field)
{
    assert_int_equal(st, IIR_ERR_INVALID);
    if (!strstr(err->msg, field)) fail_msg("message '%s' does not name '%s'", err->msg, field);
}

static void test_bad_input(void **state)
{
    const env *e = *state;
    iir_error err = {0};
    iir_incr *inc = NULL;
    iir_incr_params p = iir_incr_params_default();
    p.target = 0;
    expect_invalid(iir_incr_create(e->scene, e->rt, &p, &inc, &err), &err, "target");
    assert_null(inc);
    p.target = IIR_INCR_MAX_TARGET + 1;
    expect_invalid(iir_incr_params_validate(&p, &err), &err, "target");
    p = iir_incr_params_default();
    p.k_min = 9;
    p.k_max = 8;
    expect_invalid(iir_incr_create(e->scene, e->rt, &p, &inc, &err), &err, "k_min");
    p = iir_incr_params_default();
    p.k_max = 0;
    p.k_min = 0;
    expect_invalid(iir_incr_params_validate(&p, &err), &err, "k_max");
    p = iir_incr_params_default();
    p.regen_threshold = 0.f;
    expect_invalid(iir_incr_params_validate(&p, &err), &err, "regen_threshold");
    p.regen_threshold = NAN;
    expect_invalid(iir_incr_params_validate(&p, &err), &err, "regen_threshold");
    p = iir_incr_params_default();
    p.weights = (iir_weights)7;
    expect_invalid(iir_incr_params_validate(&p, &err), &err, "weights");

    inc = make_incr(e, 64, IIR_WEIGHTS_VORONOI, 1);
    iir_light good = cornell_spot(e);
    update(inc, &good);
    uint32_t n0;
    uint32_t first_id = iir_incr_vpls(inc, &n0)[0].id;
    /* bad parameters are refused and the old ones stay */
    p = iir_incr_params_default();
    p.k_min = 20;
    expect_invalid(iir_incr_set_params(inc, &p, &err), &err, "k_min");
    assert_int_equal(iir_incr_get_params(inc).target, 64);
    /* bad lights are refused and the set does not change */
    iir_light nan_pos = good;
    nan_pos.position.y = NAN;
    expect_invalid(iir_incr_update(inc, &nan_pos, NULL, &err), &err, "position");
    iir_light wide = good;
    wide.cone_angle = iir_radians(100.f);
    expect_invalid(iir_incr_update(inc, &wide, NULL, &err), &err, "cone angle");
    uint32_t n1;
    assert_int_equal(iir_incr_vpls(inc, &n1)[0].id, first_id);
    assert_int_equal(n1, n0);
    iir_incr_destroy(inc);
    iir_incr_destroy(NULL);
}

/* ---- a smooth path: a full set and bounded churn ------------------------------------------- */

/* A smooth orbit under the ceiling with the aim swinging (the light moves about 1 cm a frame). */
static iir_light orbit(iir_light l, int f)
{
    float a = 0.02f * (float)f;
    l.position = iir_v3(0.5f * cosf(a), 1.7f, 0.5f * sinf(a) - 0.1f);
    l.direction = iir_normalize(iir_v3(-0.4f * cosf(a), -1.f, -0.4f * sinf(a)));
    return l;
}

/* With refill, a fast sweep (the orbit at 8 times its speed: about 8 VPLs die a frame, and the
 * cone leaves uncovered ground behind its survivors) keeps the set at N on every frame; a frame
 * inserts what it removed before the holes plus at most k_max for the holes, and after each
 * frame no empty circle is wider than IIR_INCR_HOLE cells unless those k_max were all spent;
 * without refill the same sweep leaves the set short (155 of 256). */
static void test_refill_keeps_n(void **state)
{
    const env *e = *state;
    enum { FRAMES = 40 };
    for (int k = 0; k < 2; k++) {
        iir_incr *inc = make_incr(e, 256, IIR_WEIGHTS_VORONOI, 1);
        iir_incr_params p = iir_incr_get_params(inc);
        p.refill = k == 0;
        iir_error err = {0};
        assert_int_equal(iir_incr_set_params(inc, &p, &err), IIR_OK);
        iir_light l = cornell_spot(e);
        uint32_t least = p.target, open = 0;
        double R = 0;
        for (int f = 0; f <= FRAMES; f++) {
            l = orbit(l, 8 * f);
            iir_incr_stats st = update(inc, &l);
            give_maps(inc);
            const iir_vpl_counts *c = &st.vpl;
            if (f == 0 || c->regenerated) continue;
            least = c->count < least ? c->count : least;
            double centre[2], r;
            assert_int_equal(iir_tri_largest_empty_circle(iir_incr_tri(inc), centre, &r),
                             IIR_TRI_OK);
            R = iir_tri_radius(iir_incr_tri(inc));
            double hole = IIR_INCR_HOLE * R / sqrt((double)p.target);
            bool spent = c->inserted >= p.k_max; /* the holes may have had all of k_max */
            open += r > hole && !spent;
            if (k == 0 && r > hole && !spent)
                fail_msg("frame %d: an empty circle of %g, a hole is %g", f, r, hole);
        }
        print_message("fast sweep, refill %s: the set at least %u of %u, %u frames with a hole "
                      "left open\n",
                      k == 0 ? "on" : "off", least, p.target, open);
        if (k == 0) assert_int_equal(least, p.target);
        if (k == 1) assert_true(least < p.target);
        iir_incr_destroy(inc); /* and the maps */
    }
}

/* Along the orbit nothing jumps, so after the first update no frame regenerates; each frame
 * replaces between k_min and k_max + invalidated VPLs (invalidated + deleted) and inserts at most
 * k_max; the set is back at N whenever the frame's budget allows (count = min(N, valid - deleted +
 * k_max)), which on this path is nearly every frame (a few frames lose more than k_max VPLs at
 * once); and its rays are one per VPL validated plus one per insertion: at least valid + inserted,
 * at most count_prev + inserted. Both weightings. (Speed is `iird bench`'s.) */
static void test_smooth_path_steady(void **state)
{
    const env *e = *state;
    enum { FRAMES = 80 };
    for (int k = 0; k < 2; k++) {
        iir_weights w = k ? IIR_WEIGHTS_UNIFORM : IIR_WEIGHTS_VORONOI;
        iir_incr *inc = make_incr(e, 256, w, 1);
        iir_incr_params p = iir_incr_get_params(inc);
        iir_light l = cornell_spot(e);
        uint32_t count_prev = 0, invalidated = 0, most = 0, full = 0;
        for (int f = 0; f <= FRAMES; f++) {
            l = orbit(l, f);
            iir_incr_stats st = update(inc, &l);
            const iir_vpl_counts *c = &st.vpl;
            uint64_t rays = st.rays.n[IIR_RAYS_VPL];
            if (f > 0) {
                uint32_t replaced = c->invalidated + c->deleted;
                uint32_t budget = c->valid - c->deleted + p.k_max;
                if (c->regenerated) fail_msg("frame %d: regenerated on a smooth path", f);
                if (replaced < p.k_min || replaced > p.k_max + c->invalidated)
                    fail_msg("frame %d: replaced %u (invalidated %u), not in [%u, %u + %u]", f,
                             replaced, c->invalidated, p.k_min, p.k_max, c->invalidated);
                if (c->inserted > p.k_max)
                    fail_msg("frame %d: inserted %u > k_max %u", f, c->inserted, p.k_max);
                if (c->count != (budget < p.target ? budget : p.target))
                    fail_msg("frame %d: %u VPLs, N %u, valid %u, deleted %u, k_max %u", f, c->count,
                             p.target, c->valid, c->deleted, p.k_max);
                if (rays < (uint64_t)c->valid + c->inserted ||
                    rays > (uint64_t)count_prev + c->inserted)
                    fail_msg("frame %d: %llu rays for %u VPLs validated (%u valid), %u inserted", f,
                             (unsigned long long)rays, count_prev, c->valid, c->inserted);
                invalidated += c->invalidated;
                most = replaced > most ? replaced : most;
                full += c->count == p.target;
            }
            count_prev = c->count;
        }
        print_message("smooth orbit, %s: %d frames, %u with N VPLs, %u invalidated, at most %u "
                      "replaced a frame\n",
                      k ? "uniform" : "voronoi", FRAMES, full, invalidated, most);
        assert_true(invalidated > 0); /* the path does move the cone over VPLs */
        if (full < FRAMES * 9 / 10) fail_msg("the set was full on %u of %d frames", full, FRAMES);
        iir_incr_destroy(inc);
    }
}

/* ---- memory: buffers are reused, nothing grows with the number of frames --------------------- */

#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
/* The sanitizer's allocator, which mallinfo2 does not see (sanitizer/allocator_interface.h, which
 * Debian's gcc does not ship). */
size_t __sanitizer_get_current_allocated_bytes(void);
#endif

/* Bytes allocated and not freed: the sanitizer's count in the test build, else glibc's. */
static size_t heap_in_use(void)
{
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
    return __sanitizer_get_current_allocated_bytes();
#else
    struct mallinfo2 mi = mallinfo2();
    return mi.uordblks + mi.hblkhd;
#endif
}

static void test_memory_steady(void **state)
{
    const env *e = *state;
    assert_true(heap_in_use() > 0); /* the count is real wherever the test runs */
    iir_incr *inc = make_incr(e, 256, IIR_WEIGHTS_VORONOI, 4);
    iir_light l = cornell_spot(e);
    size_t at[4] = {0};
    for (int f = 0; f < 400; f++) {
        update(inc, (l = orbit(l, f), &l));
        give_maps(inc); /* the maps are the test's, but their count is bounded by N */
        if (f % 100 == 99) at[f / 100] = heap_in_use();
    }
    print_message("heap in use after 100/200/300/400 frames: %zu %zu %zu %zu bytes\n", at[0], at[1],
                  at[2], at[3]);
    for (int k = 2; k < 4; k++)
        if (at[k] > at[1] + 64 * 1024)
            fail_msg("heap grew from %zu to %zu bytes between frames 200 and %d", at[1], at[k],
                     100 * (k + 1));
    iir_incr_destroy(inc);
}

/* ---- a glossy floor: kept VPLs' lobes follow the light ----------------------------------------
 */

/* A 4 x 4 metal floor (MTL PBR: base 0.8, metallic 1, roughness 0.3) under a spot: every VPL is
 * glossy with albedo c_diff + F0 = 0.8 and its light arriving from the spot (wi), and a VPL kept
 * when the spot moves has its wi turned toward the new position. */
static void test_glossy_lobes_follow_the_light(void **state)
{
    (void)state;
    const char *dir = iir_test_tmpdir("incr-glossy");
    FILE *f = iir_test_open_obj(dir, "floor", "newmtl metal\nKd 0.8 0.8 0.8\nPm 1\nPr 0.3\n");
    iir_test_write_quad(f, "metal", iir_v3(0, 0, 0), iir_v3(0, 0, 2), iir_v3(2, 0, 0));
    fclose(f);
    iir_test_write_file(dir, "floor.scene.json",
                        "{\"camera\": {\"position\": [0, 2, 3], \"target\": [0, 0, 0]},"
                        " \"lights\": []}");
    env e = {0};
    iir_error err = {0};
    if (iir_test_load_obj(dir, "floor", &e.scene, &e.rt, &err) != IIR_OK) fail_msg("%s", err.msg);
    iir_incr *inc = make_incr(&e, 64, IIR_WEIGHTS_VORONOI, 5);
    iir_light l = spot_at(iir_v3(0, 1.5f, 0), iir_v3(0, -1, 0), 40.f, 5.f);
    iir_vec3 wi0[64];
    uint32_t id0[64], n0 = 0;
    for (int frame = 0; frame < 2; frame++) {
        if (frame) l.position = iir_add(l.position, iir_v3(0.05f, 0, 0.03f));
        update(inc, &l);
        uint32_t n = 0, kept = 0, glossy = 0;
        const iir_vpl *v = iir_incr_vpls(inc, &n);
        for (uint32_t i = 0; i < n; i++) {
            if (v[i].null_sample) continue;
            glossy++;
            if (!v[i].lobe.glossy || fabsf(v[i].albedo.x - 0.8f) > 1e-5f)
                fail_msg("frame %d: VPL %u: glossy %d, albedo %g", frame, v[i].id, v[i].lobe.glossy,
                         v[i].albedo.x);
            iir_vec3 want = iir_normalize(iir_sub(l.position, v[i].position));
            if (iir_length(iir_sub(v[i].wi, want)) > 1e-4f)
                fail_msg("frame %d: VPL %u: wi %g %g %g, toward the spot %g %g %g", frame, v[i].id,
                         v[i].wi.x, v[i].wi.y, v[i].wi.z, want.x, want.y, want.z);
            for (uint32_t k = 0; frame && k < n0; k++)
                if (id0[k] == v[i].id && iir_length(iir_sub(wi0[k], v[i].wi)) > 1e-3f) kept++;
            if (!frame && n0 < 64) wi0[n0] = v[i].wi, id0[n0++] = v[i].id;
        }
        assert_true(glossy > 32);
        if (frame && kept < 16) fail_msg("only %u kept VPLs turned their lobes", kept);
        give_maps(inc);
    }
    iir_incr_destroy(inc);
    iir_rt_destroy(e.rt);
    iir_scene_destroy(e.scene);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_flux_conservation_enclosed),
        cmocka_unit_test(test_flux_conservation_escaping),
        cmocka_unit_test(test_property_random_path),
        cmocka_unit_test(test_still_light),
        cmocka_unit_test(test_regeneration_on_teleport),
        cmocka_unit_test(test_facing_light_through_wall),
        cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_gradual_deaths_regenerate),
        cmocka_unit_test(test_param_changes),
        cmocka_unit_test(test_bad_input),
        cmocka_unit_test(test_memory_steady),
        cmocka_unit_test(test_smooth_path_steady),
        cmocka_unit_test(test_refill_keeps_n),
        cmocka_unit_test(test_glossy_lobes_follow_the_light),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

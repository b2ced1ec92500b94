/* test_stri.c -- libiirtri's sphere (stri.h) through its C header: every answer checked against
 * brute force (closest pair and second-nearest neighbours, 100k random probes for the largest empty
 * cap and the cell areas), the areas tiling the sphere, edits against fresh builds (the handle's
 * per-site summaries, kept across edits), each degenerate dimension (1 and 2 sites, sites on one
 * circle, sites in a hemisphere or a small cap), duplicates, statuses and buffers. Not the VPL
 * step. Also prints the timings of a frame's calls for n = 256, 1024, 4096. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "iir/stri.h"

/* ---- helpers -------------------------------------------------------------------------------- */

#define PI 3.14159265358979323846

#define assert_near(a, b, tol)                                                                     \
    do {                                                                                           \
        double a_ = (a), b_ = (b), t_ = (tol);                                                     \
        if (!(fabs(a_ - b_) <= t_))                                                                \
            fail_msg("%s = %.17g vs %s = %.17g (diff %.3g > %.3g)", #a, a_, #b, b_, fabs(a_ - b_), \
                     t_);                                                                          \
    } while (0)

#define assert_ok(call) assert_int_equal((call), IIR_TRI_OK)

/* A small deterministic generator (splitmix64), local so the test depends only on stri.h. */
static uint64_t next_u64(uint64_t *s)
{
    uint64_t z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return z ^ (z >> 31);
}

static double urand(uint64_t *s)
{
    return (double)(next_u64(s) >> 11) * 0x1.0p-53;
}

static double gauss(uint64_t *s)
{
    double u = urand(s), v = urand(s);
    return sqrt(-2 * log(1 - u)) * cos(2 * PI * v);
}

static void normalize3(double *p)
{
    double l = sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
    p[0] /= l, p[1] /= l, p[2] /= l;
}

/* A uniform random unit vector. */
static void random_dir(uint64_t *s, double *p)
{
    do {
        p[0] = gauss(s), p[1] = gauss(s), p[2] = gauss(s);
    } while (p[0] * p[0] + p[1] * p[1] + p[2] * p[2] < 1e-12);
    normalize3(p);
}

static double dot3(const double *a, const double *b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross3(const double *a, const double *b, double *c)
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Geodesic distance, computed as the library does (atan2 of |a x b| and a.b). */
static double ang(const double *a, const double *b)
{
    double c[3];
    cross3(a, b, c);
    return atan2(sqrt(dot3(c, c)), dot3(a, b));
}

/* Signed area of the spherical triangle abc (Van Oosterom-Strackee). */
static double tri_area(const double *a, const double *b, const double *c)
{
    double bc[3];
    cross3(b, c, bc);
    return 2 * atan2(dot3(a, bc), 1 + dot3(a, b) + dot3(b, c) + dot3(c, a));
}

/* Ids that are distinct but neither sequential nor sorted like the points. */
static uint32_t id_of(size_t i)
{
    return (uint32_t)(i * 2654435761u + 17u);
}

/* A point set with its ids (owned: free with set_free). */
typedef struct set {
    double *xyz;
    uint32_t *ids;
    size_t n;
} set;

static set set_alloc(size_t n)
{
    set s = {calloc(3 * n + 3, sizeof(double)), calloc(n + 1, sizeof(uint32_t)), n};
    assert_non_null(s.xyz);
    assert_non_null(s.ids);
    for (size_t i = 0; i < n; i++) s.ids[i] = id_of(i);
    return s;
}

static void set_free(set *s)
{
    free(s->xyz);
    free(s->ids);
}

enum kind { UNIFORM, HEMISPHERE, GREAT_CIRCLE, HALF_CIRCLE, TILTED_CIRCLE, SMALL_CAP };

/* n unit vectors: uniform; uniform over z > 0.3; on the equator (z = 0 exactly: dimension 1);
 * on a third of the equator; on a tilted great circle (not exactly coplanar in double); uniform in
 * a cap of radius 0.02 around a random axis. */
static set make_set(enum kind kind, size_t n, uint64_t seed)
{
    set s = set_alloc(n);
    double axis[3], e1[3], e2[3], tmp[3] = {0.3, -0.5, 0.8};
    random_dir(&seed, axis);
    cross3(axis, tmp, e1);
    normalize3(e1);
    cross3(axis, e1, e2);
    for (size_t i = 0; i < n; i++) {
        double *p = &s.xyz[3 * i], t = 2 * PI * urand(&seed);
        switch (kind) {
        case UNIFORM:
            random_dir(&seed, p);
            break;
        case HEMISPHERE:
            do random_dir(&seed, p);
            while (p[2] <= 0.3);
            break;
        case GREAT_CIRCLE:
        case HALF_CIRCLE:
            if (kind == HALF_CIRCLE) t /= 3;
            p[0] = cos(t), p[1] = sin(t), p[2] = 0;
            break;
        case TILTED_CIRCLE:
            for (int k = 0; k < 3; k++) p[k] = cos(t) * e1[k] + sin(t) * e2[k];
            normalize3(p);
            break;
        case SMALL_CAP: {
            double r = 0.02 * sqrt(urand(&seed));
            for (int k = 0; k < 3; k++)
                p[k] = cos(r) * axis[k] + sin(r) * (cos(t) * e1[k] + sin(t) * e2[k]);
            normalize3(p);
        } break;
        }
    }
    return s;
}

static iir_stri *build(const set *s)
{
    iir_stri *st = iir_stri_create();
    assert_non_null(st);
    assert_ok(iir_stri_build(st, s->xyz, s->ids, s->n));
    assert_int_equal(iir_stri_count(st), s->n);
    return st;
}

/* The handle's sites (ids ascending, stored positions): owned, free with set_free. */
static set sites_of(const iir_stri *st)
{
    size_t n;
    assert_ok(iir_stri_ids(st, NULL, 0, &n));
    set s = set_alloc(n);
    assert_ok(iir_stri_ids(st, s.ids, n, &n));
    for (size_t i = 0; i < n; i++) assert_ok(iir_stri_position(st, s.ids[i], &s.xyz[3 * i]));
    return s;
}

/* Index of the site nearest to p by brute force, and its distance. */
static size_t brute_nearest(const set *s, const double *p, double *d)
{
    size_t best = 0;
    double bd = -2;
    for (size_t i = 0; i < s->n; i++) {
        double c = dot3(p, &s->xyz[3 * i]);
        if (c > bd) bd = c, best = i;
    }
    *d = ang(p, &s->xyz[3 * best]);
    return best;
}

static double brute_min_angle(const set *s, const double *p)
{
    double best = INFINITY;
    for (size_t i = 0; i < s->n; i++) best = fmin(best, ang(p, &s->xyz[3 * i]));
    return best;
}

/* ---- brute-force checks, one per query ------------------------------------------------------ */

enum { PROBES = 100000 };

/* Areas: positive, tile the sphere, and match the share of random probes nearest to each site. */
static void check_areas(const iir_stri *st, const set *s, uint64_t seed)
{
    size_t n;
    double *areas = calloc(s->n + 1, sizeof(double)), *hits = calloc(s->n + 1, sizeof(double));
    uint32_t *ids = calloc(s->n + 1, sizeof(uint32_t));
    assert_ok(iir_stri_cell_areas(st, ids, areas, s->n, &n));
    assert_int_equal(n, s->n);
    double sum = 0;
    for (size_t i = 0; i < n; i++) {
        assert_int_equal(ids[i], s->ids[i]);
        assert_true(areas[i] > 0);
        double one;
        assert_ok(iir_stri_cell_area(st, ids[i], &one));
        assert_true(one == areas[i]);
        sum += areas[i];
    }
    assert_near(sum, 4 * PI, 1e-9);
    for (int k = 0; k < PROBES; k++) {
        double p[3], d;
        random_dir(&seed, p);
        hits[brute_nearest(s, p, &d)] += 1;
    }
    for (size_t i = 0; i < n; i++) {
        double frac = areas[i] / (4 * PI);
        double sigma = sqrt(frac * (1 - frac) / PROBES) * 4 * PI;
        assert_near(hits[i] / PROBES * 4 * PI, areas[i], 6 * sigma + 4 * PI * 1e-4);
    }
    free(areas);
    free(hits);
    free(ids);
}

/* The largest empty cap: a unit centre, its angle the true distance to the nearest site (so no
 * site is inside), and no probe (uniform, plus one around each site's antipode) is farther from
 * every site. */
static void check_cap(const iir_stri *st, const set *s, uint64_t seed)
{
    double c[3], a;
    assert_ok(iir_stri_largest_empty_cap(st, c, &a));
    assert_near(dot3(c, c), 1, 1e-14);
    assert_near(a, brute_min_angle(s, c), 1e-14);
    for (size_t i = 0; i < s->n; i++) assert_true(ang(c, &s->xyz[3 * i]) >= a - 1e-12);
    double worst = 0;
    for (int k = 0; k < PROBES; k++) {
        double p[3], d;
        random_dir(&seed, p);
        if (k < (int)s->n && k < 1000) /* near the antipode of a site */
            for (int j = 0; j < 3; j++) p[j] = -s->xyz[3 * k + j] + 1e-3 * p[j];
        normalize3(p);
        brute_nearest(s, p, &d);
        worst = fmax(worst, d);
    }
    if (!(worst <= a + 1e-12)) fail_msg("a probe has an empty cap of %.17g > %.17g", worst, a);
}

/* Brute-force distance from site i to its nearest site other than i and j. */
static double second_nearest(const set *s, size_t i, size_t j)
{
    double best = INFINITY;
    for (size_t k = 0; k < s->n; k++)
        if (k != i && k != j) best = fmin(best, ang(&s->xyz[3 * i], &s->xyz[3 * k]));
    return best;
}

/* The closest pair by brute force with the header's tie rule, split by the denser rule. */
static void brute_shortest(const set *s, uint32_t *denser, uint32_t *other, double *len)
{
    size_t bi = 0, bj = 0;
    double best = INFINITY;
    for (size_t i = 0; i < s->n; i++)
        for (size_t j = 0; j < s->n; j++) {
            if (s->ids[i] <= s->ids[j]) continue; /* i is the younger endpoint */
            double d = ang(&s->xyz[3 * i], &s->xyz[3 * j]);
            int wins =
                d < best || (d == best && (s->ids[i] > s->ids[bi] ||
                                           (s->ids[i] == s->ids[bi] && s->ids[j] > s->ids[bj])));
            if (wins) best = d, bi = i, bj = j;
        }
    int young_denser = second_nearest(s, bi, bj) <= second_nearest(s, bj, bi);
    *denser = young_denser ? s->ids[bi] : s->ids[bj];
    *other = young_denser ? s->ids[bj] : s->ids[bi];
    *len = best;
}

static void check_shortest(const iir_stri *st, const set *s)
{
    uint32_t d, o, bd, bo;
    double len, blen;
    assert_ok(iir_stri_shortest_edge(st, &d, &o, &len));
    brute_shortest(s, &bd, &bo, &blen);
    assert_true(len == blen);
    assert_int_equal(d, bd);
    assert_int_equal(o, bo);
}

/* Delaunay edges: sorted valid pairs; 3n - 6 of them when the hull is a solid; every site's
 * nearest neighbour is one (the nearest-neighbour graph is a subgraph of Delaunay). */
static void check_edges(const iir_stri *st, const set *s, int solid)
{
    size_t m;
    assert_ok(iir_stri_edges(st, NULL, 0, &m));
    uint32_t *pairs = calloc(2 * m + 2, sizeof(uint32_t));
    assert_ok(iir_stri_edges(st, pairs, m, &m));
    if (solid) assert_int_equal(m, 3 * s->n - 6);
    for (size_t k = 0; k < m; k++) {
        assert_true(pairs[2 * k] < pairs[2 * k + 1]);
        if (k > 0)
            assert_true(pairs[2 * k - 2] < pairs[2 * k] ||
                        (pairs[2 * k - 2] == pairs[2 * k] && pairs[2 * k - 1] < pairs[2 * k + 1]));
    }
    for (size_t i = 0; i < s->n && s->n >= 2; i++) {
        size_t nn = i;
        double best = INFINITY;
        for (size_t j = 0; j < s->n; j++)
            if (j != i && ang(&s->xyz[3 * i], &s->xyz[3 * j]) < best)
                best = ang(&s->xyz[3 * i], &s->xyz[3 * j]), nn = j;
        uint32_t a = s->ids[i] < s->ids[nn] ? s->ids[i] : s->ids[nn];
        uint32_t b = s->ids[i] < s->ids[nn] ? s->ids[nn] : s->ids[i];
        int found = 0;
        for (size_t k = 0; k < m && !found; k++) found = pairs[2 * k] == a && pairs[2 * k + 1] == b;
        assert_true(found);
    }
    free(pairs);
}

/* Polygons: unit vertices nearest (up to rounding) to their own site, counter-clockwise around
 * it, and their fan area equal to the cell area. */
static void check_polygons(const iir_stri *st, const set *s)
{
    for (size_t i = 0; i < s->n; i++) {
        size_t m;
        assert_ok(iir_stri_cell_polygon(st, s->ids[i], NULL, 0, &m));
        if (s->n == 1) {
            assert_int_equal(m, 0);
            continue;
        }
        assert_true(m >= 3 || (s->n >= 3 && m >= 2));
        double *xyz = calloc(3 * m + 3, sizeof(double)), area, fan = 0;
        assert_ok(iir_stri_cell_polygon(st, s->ids[i], xyz, m, &m));
        const double *site = &s->xyz[3 * i];
        for (size_t k = 0; k < m; k++) {
            const double *a = &xyz[3 * k], *b = &xyz[3 * ((k + 1) % m)];
            assert_near(dot3(a, a), 1, 1e-14);
            assert_near(ang(a, site), brute_min_angle(s, a), 1e-9);
            double t = tri_area(site, a, b);
            /* rounding may scatter the vertices of nearly flat sets by ~1e-12 */
            if (!(t >= -1e-10))
                fail_msg("n=%zu site %zu: polygon turns clockwise (%.3g) at vertex %zu of %zu",
                         s->n, i, t, k, m);
            fan += t;
        }
        assert_ok(iir_stri_cell_area(st, s->ids[i], &area));
        assert_near(fan, area, 1e-9);
        free(xyz);
    }
}

/* Everything about one handle against brute force over its stored sites. */
static void check_all(const iir_stri *st, int solid, uint64_t seed)
{
    set s = sites_of(st);
    check_areas(st, &s, seed);
    check_cap(st, &s, seed + 1);
    if (s.n >= 2) check_shortest(st, &s);
    check_edges(st, &s, solid);
    check_polygons(st, &s);
    set_free(&s);
}

/* ---- tests ---------------------------------------------------------------------------------- */

static void test_create_and_bad_args(void **state)
{
    (void)state;
    iir_stri_destroy(NULL);
    assert_int_equal(iir_stri_count(NULL), 0);
    iir_stri *st = iir_stri_create();
    assert_non_null(st);
    double p[3] = {0, 0, 1}, c[3], a;
    uint32_t id;
    size_t n;
    assert_int_equal(iir_stri_build(NULL, p, &id, 1), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_stri_build(st, NULL, &id, 1), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_stri_insert(NULL, p, 1), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_stri_insert(st, NULL, 1), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_stri_remove(NULL, 1), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_stri_position(st, 1, NULL), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_stri_ids(st, NULL, 0, NULL), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_stri_shortest_edge(NULL, NULL, NULL, NULL), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_stri_largest_empty_cap(st, NULL, &a), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_stri_largest_empty_cap(st, c, NULL), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_stri_cell_area(st, 1, NULL), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_stri_edges(st, NULL, 0, NULL), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_stri_cell_polygon(st, 1, NULL, 0, NULL), IIR_TRI_BAD_ARG);
    /* not unit length, NaN, inf */
    const double bad[][3] = {{0, 0, 1.1}, {0, 0, 1 + 2e-6}, {0, 0, 1 - 2e-6}, {0, 0, 0},
                             {NAN, 0, 1}, {0, INFINITY, 0}, {0.5, 0.5, 0},    {-INFINITY, 0, 0}};
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        assert_int_equal(iir_stri_insert(st, bad[k], 7), IIR_TRI_BAD_ARG);
        uint32_t ids[2] = {1, 2};
        double two[6] = {1, 0, 0, bad[k][0], bad[k][1], bad[k][2]};
        assert_int_equal(iir_stri_build(st, two, ids, 2), IIR_TRI_BAD_ARG);
    }
    assert_int_equal(iir_stri_count(st), 0);
    /* within the tolerance: accepted and stored normalised */
    double q[3] = {0, 0.6 * (1 + 5e-7), 0.8 * (1 + 5e-7)}, got[3];
    assert_ok(iir_stri_insert(st, q, 9));
    assert_ok(iir_stri_position(st, 9, got));
    assert_near(got[1], 0.6, 1e-15);
    assert_near(got[2], 0.8, 1e-15);
    assert_near(dot3(got, got), 1, 1e-15);
    /* a bad build keeps the previous set; a repeated id is refused */
    uint32_t ids[2] = {4, 4};
    double two[6] = {1, 0, 0, 0, 1, 0};
    assert_int_equal(iir_stri_build(st, two, ids, 2), IIR_TRI_DUPLICATE_ID);
    assert_int_equal(iir_stri_count(st), 1);
    assert_int_equal(iir_stri_insert(st, two, 9), IIR_TRI_DUPLICATE_ID);
    assert_ok(iir_stri_ids(st, NULL, 0, &n));
    assert_int_equal(n, 1);
    assert_string_equal(iir_tri_status_name(IIR_TRI_DUPLICATE_POINT), "duplicate_point");
    iir_stri_destroy(st);
}

static void test_empty_set(void **state)
{
    (void)state;
    iir_stri *st = iir_stri_create();
    double c[3], a, area;
    uint32_t d, o, ids[1], pairs[2];
    size_t n = 99;
    assert_int_equal(iir_stri_shortest_edge(st, &d, &o, &a), IIR_TRI_TOO_FEW);
    assert_int_equal(iir_stri_largest_empty_cap(st, c, &a), IIR_TRI_TOO_FEW);
    assert_ok(iir_stri_ids(st, ids, 1, &n));
    assert_int_equal(n, 0);
    assert_ok(iir_stri_edges(st, pairs, 1, &n));
    assert_int_equal(n, 0);
    assert_ok(iir_stri_cell_areas(st, ids, &area, 1, &n));
    assert_int_equal(n, 0);
    assert_ok(iir_stri_build(st, NULL, NULL, 0));
    assert_int_equal(iir_stri_count(st), 0);
    iir_stri_destroy(st);
}

static void test_one_site(void **state)
{
    (void)state;
    iir_stri *st = iir_stri_create();
    double p[3] = {0.48, -0.6, 0.64}, c[3], a, area;
    uint32_t d;
    assert_ok(iir_stri_insert(st, p, 5));
    assert_ok(iir_stri_cell_area(st, 5, &area));
    assert_true(area == 4 * PI);
    assert_ok(iir_stri_largest_empty_cap(st, c, &a));
    for (int k = 0; k < 3; k++) assert_true(c[k] == -p[k]);
    assert_true(a == PI);
    assert_int_equal(iir_stri_shortest_edge(st, &d, NULL, NULL), IIR_TRI_TOO_FEW);
    check_all(st, 0, 11);
    iir_stri_destroy(st);
}

/* Two sites: hemispheres, the cap at the antipode of their midpoint. */
static void test_two_sites(void **state)
{
    (void)state;
    iir_stri *st = iir_stri_create();
    double xyz[6] = {0, 0, 1, sin(0.3), 0, cos(0.3)}, c[3], a, area;
    uint32_t ids[2] = {8, 3}, d, o;
    assert_ok(iir_stri_build(st, xyz, ids, 2));
    for (int k = 0; k < 2; k++) {
        assert_ok(iir_stri_cell_area(st, ids[k], &area));
        assert_true(area == 2 * PI);
    }
    assert_ok(iir_stri_largest_empty_cap(st, c, &a));
    assert_near(a, PI - 0.15, 1e-15);
    assert_near(c[0], -sin(0.15), 1e-15);
    assert_near(c[2], -cos(0.15), 1e-15);
    assert_ok(iir_stri_shortest_edge(st, &d, &o, &a));
    assert_int_equal(d, 8); /* no third site: the younger */
    assert_int_equal(o, 3);
    assert_near(a, 0.3, 1e-15);
    check_all(st, 0, 12);
    /* antipodal: every bisector point is pi/2 away */
    double anti[6] = {0.6, 0, 0.8, -0.6, 0, -0.8};
    assert_ok(iir_stri_build(st, anti, ids, 2));
    assert_ok(iir_stri_largest_empty_cap(st, c, &a));
    assert_near(a, PI / 2, 1e-15);
    check_all(st, 0, 13);
    iir_stri_destroy(st);
}

/* Three sites on a great circle, two 120 degrees apart and one between them: the largest empty cap
 * is not a Voronoi vertex (the poles, pi/2) but the antipode of the outer pair's midpoint. */
static void test_cap_inside_an_edge(void **state)
{
    (void)state;
    iir_stri *st = iir_stri_create();
    double s3 = sin(PI / 3), c3 = cos(PI / 3);
    double xyz[12] = {s3, 0, c3, -s3, 0, c3, 0, 0, 1, 0, 0, 0}, c[3], a;
    uint32_t ids[4] = {1, 2, 3, 4};
    assert_ok(iir_stri_build(st, xyz, ids, 3));
    assert_ok(iir_stri_largest_empty_cap(st, c, &a));
    assert_near(a, 2 * PI / 3, 1e-15);
    assert_near(c[2], -1, 1e-15);
    check_all(st, 0, 21);
    /* the same in dimension 2: a fourth site off the circle */
    xyz[9] = 0, xyz[10] = sin(0.1), xyz[11] = cos(0.1);
    assert_ok(iir_stri_build(st, xyz, ids, 4));
    assert_ok(iir_stri_largest_empty_cap(st, c, &a));
    assert_near(a, 2 * PI / 3, 1e-15);
    assert_near(c[2], -1, 1e-15);
    check_all(st, 1, 22);
    iir_stri_destroy(st);
}

static void run_kind(enum kind kind, const size_t *sizes, size_t nsizes, int solid_from)
{
    for (size_t k = 0; k < nsizes; k++)
        for (uint64_t seed = 1; seed <= (sizes[k] <= 10 ? 4u : 1u); seed++) {
            set s = make_set(kind, sizes[k], seed * 1000 + sizes[k]);
            iir_stri *st = build(&s);
            check_all(st, solid_from > 0 && (int)sizes[k] >= solid_from, seed);
            iir_stri_destroy(st);
            set_free(&s);
        }
}

static void test_random_sets(void **state)
{
    (void)state;
    const size_t sizes[] = {1, 2, 3, 4, 5, 10, 100, 1000};
    run_kind(UNIFORM, sizes, 8, 4);
}

static void test_hemisphere_sets(void **state)
{
    (void)state;
    const size_t sizes[] = {1, 2, 3, 4, 5, 10, 100, 1000};
    run_kind(HEMISPHERE, sizes, 8, 4);
}

static void test_small_cap_sets(void **state)
{
    (void)state;
    const size_t sizes[] = {3, 4, 5, 10, 100};
    run_kind(SMALL_CAP, sizes, 5, 4);
}

/* All sites on one great circle: dimension 1 (exactly coplanar), on the whole circle or a third of
 * it, and the same on a tilted circle (coplanar only up to rounding: dimension 2, nearly flat). */
static void test_great_circle_sets(void **state)
{
    (void)state;
    const size_t sizes[] = {3, 4, 5, 10, 100, 1000};
    run_kind(GREAT_CIRCLE, sizes, 6, 0);
    run_kind(HALF_CIRCLE, sizes, 6, 0);
    run_kind(TILTED_CIRCLE, sizes, 6, 0);
}

/* Sites on one small circle (z = 0.5, exactly coplanar after normalising): lunes too. */
static void test_small_circle(void **state)
{
    (void)state;
    set s = set_alloc(7);
    for (size_t i = 0; i < s.n; i++) {
        double t = 0.9 * (double)i * i;
        s.xyz[3 * i] = 0.75 * cos(t), s.xyz[3 * i + 1] = 0.75 * sin(t), s.xyz[3 * i + 2] = 0.5;
        normalize3(&s.xyz[3 * i]);
    }
    iir_stri *st = build(&s);
    check_all(st, 0, 31);
    iir_stri_destroy(st);
    set_free(&s);
}

/* Repeated and too-close positions: build keeps the smallest id, insert refuses. */
static void test_duplicate_points(void **state)
{
    (void)state;
    iir_stri *st = iir_stri_create();
    double d = 5e-8; /* below IIR_STRI_MIN_DIST */
    double xyz[15] = {1, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0};
    xyz[13] = d, xyz[12] = sqrt(1 - d * d);
    uint32_t ids[5] = {40, 10, 30, 20, 5}, dropped[2] = {40, 30};
    assert_int_equal(iir_stri_build(st, xyz, ids, 5), IIR_TRI_DUPLICATE_POINT);
    assert_int_equal(iir_stri_count(st), 3);
    double p[3];
    for (int k = 0; k < 2; k++)
        assert_int_equal(iir_stri_position(st, dropped[k], p), IIR_TRI_UNKNOWN_ID);
    assert_ok(iir_stri_position(st, 5, p));
    assert_near(p[1], d, 1e-22);
    check_all(st, 0, 41);
    /* insert: exact and too close are refused, a little further is accepted */
    double same[3] = {0, 1, 0}, close[3] = {0, sqrt(1 - 1e-14), 1e-7}, far[3] = {0, 0, 0};
    far[1] = sqrt(1 - 9e-14), far[2] = 3e-7;
    assert_int_equal(iir_stri_insert(st, same, 77), IIR_TRI_DUPLICATE_POINT);
    assert_int_equal(iir_stri_insert(st, close, 77), IIR_TRI_DUPLICATE_POINT);
    assert_int_equal(iir_stri_count(st), 3);
    assert_ok(iir_stri_insert(st, far, 77));
    assert_int_equal(iir_stri_count(st), 4);
    /* a chain a-b-c with a, c apart: b (the middle one, youngest) goes, a and c stay */
    double chain[9] = {0, 0, 1, 0, 0, 0, 0, 0, 0};
    chain[4] = 1e-7, chain[5] = sqrt(1 - 1e-14), chain[7] = 2e-7, chain[8] = sqrt(1 - 4e-14);
    uint32_t cids[3] = {1, 3, 2};
    assert_int_equal(iir_stri_build(st, chain, cids, 3), IIR_TRI_DUPLICATE_POINT);
    assert_int_equal(iir_stri_count(st), 2);
    assert_int_equal(iir_stri_position(st, 3, p), IIR_TRI_UNKNOWN_ID);
    iir_stri_destroy(st);
}

static void test_unknown_id(void **state)
{
    (void)state;
    set s = make_set(UNIFORM, 20, 5);
    iir_stri *st = build(&s);
    double p[3], a;
    size_t n;
    assert_int_equal(iir_stri_remove(st, 12345), IIR_TRI_UNKNOWN_ID);
    assert_int_equal(iir_stri_position(st, 12345, p), IIR_TRI_UNKNOWN_ID);
    assert_int_equal(iir_stri_cell_area(st, 12345, &a), IIR_TRI_UNKNOWN_ID);
    assert_int_equal(iir_stri_cell_polygon(st, 12345, NULL, 0, &n), IIR_TRI_UNKNOWN_ID);
    assert_int_equal(iir_stri_count(st), 20);
    iir_stri_destroy(st);
    set_free(&s);
}

static void test_buffer_capacity(void **state)
{
    (void)state;
    set s = make_set(UNIFORM, 10, 6);
    iir_stri *st = build(&s);
    uint32_t ids[64], pairs[128];
    double areas[64], xyz[192];
    size_t n;
    assert_ok(iir_stri_ids(st, NULL, 0, &n));
    assert_int_equal(n, 10);
    ids[0] = 7;
    assert_int_equal(iir_stri_ids(st, ids, 9, &n), IIR_TRI_CAPACITY);
    assert_int_equal(n, 10);
    assert_int_equal(ids[0], 7);
    assert_ok(iir_stri_ids(st, ids, 10, &n));
    assert_int_equal(iir_stri_cell_areas(st, ids, NULL, 10, &n), IIR_TRI_BAD_ARG);
    areas[0] = -1;
    assert_int_equal(iir_stri_cell_areas(st, ids, areas, 9, &n), IIR_TRI_CAPACITY);
    assert_true(areas[0] == -1);
    assert_ok(iir_stri_cell_areas(st, NULL, NULL, 0, &n));
    assert_int_equal(n, 10);
    assert_ok(iir_stri_edges(st, NULL, 0, &n));
    assert_int_equal(n, 24);
    pairs[0] = 7;
    assert_int_equal(iir_stri_edges(st, pairs, 23, &n), IIR_TRI_CAPACITY);
    assert_int_equal(pairs[0], 7);
    assert_ok(iir_stri_edges(st, pairs, 64, &n));
    assert_int_equal(n, 24);
    size_t m;
    assert_ok(iir_stri_cell_polygon(st, s.ids[0], NULL, 0, &m));
    assert_true(m >= 3);
    xyz[0] = 7;
    assert_int_equal(iir_stri_cell_polygon(st, s.ids[0], xyz, m - 1, &n), IIR_TRI_CAPACITY);
    assert_int_equal(n, m);
    assert_true(xyz[0] == 7);
    assert_ok(iir_stri_cell_polygon(st, s.ids[0], xyz, m, &n));
    iir_stri_destroy(st);
    set_free(&s);
}

/* Two handles hold the same set: same ids, same areas, same queries. */
static void check_same(const iir_stri *a, const iir_stri *b)
{
    set sa = sites_of(a), sb = sites_of(b);
    assert_int_equal(sa.n, sb.n);
    for (size_t i = 0; i < sa.n; i++) {
        assert_int_equal(sa.ids[i], sb.ids[i]);
        double x, y;
        assert_ok(iir_stri_cell_area(a, sa.ids[i], &x));
        assert_ok(iir_stri_cell_area(b, sb.ids[i], &y));
        assert_near(x, y, 1e-12);
    }
    double ca[3], cb[3], ra, rb;
    if (sa.n >= 1) {
        assert_ok(iir_stri_largest_empty_cap(a, ca, &ra));
        assert_ok(iir_stri_largest_empty_cap(b, cb, &rb));
        assert_near(ra, rb, 1e-12);
    }
    if (sa.n >= 2) {
        uint32_t da, oa, db, ob;
        assert_ok(iir_stri_shortest_edge(a, &da, &oa, &ra));
        assert_ok(iir_stri_shortest_edge(b, &db, &ob, &rb));
        assert_int_equal(da, db);
        assert_int_equal(oa, ob);
        assert_true(ra == rb);
    }
    set_free(&sa);
    set_free(&sb);
}

static iir_stri *fresh_copy(const iir_stri *st)
{
    set s = sites_of(st);
    iir_stri *f = build(&s);
    set_free(&s);
    return f;
}

/* The incremental step's loop (remove the denser endpoint, insert at the largest empty cap) and
 * random edits, each checked against a fresh build of the same set. */
static void test_edits_match_fresh_build(void **state)
{
    (void)state;
    const enum kind kinds[] = {UNIFORM, HEMISPHERE};
    for (int kk = 0; kk < 2; kk++) {
        set s = make_set(kinds[kk], 300, 77 + kk);
        iir_stri *st = build(&s);
        uint32_t next_id = 1000000;
        uint64_t seed = 99;
        for (int round = 0; round < 60; round++) {
            uint32_t d;
            double c[3], a, p[3];
            assert_ok(iir_stri_shortest_edge(st, &d, NULL, NULL));
            assert_ok(iir_stri_remove(st, d));
            assert_ok(iir_stri_largest_empty_cap(st, c, &a));
            assert_ok(iir_stri_insert(st, c, next_id++));
            random_dir(&seed, p);
            if (kinds[kk] == HEMISPHERE && p[2] < 0.3) p[2] = -p[2];
            iir_tri_status ist = iir_stri_insert(st, p, next_id++);
            assert_true(ist == IIR_TRI_OK || ist == IIR_TRI_DUPLICATE_POINT);
            if (round % 10 == 0) {
                iir_stri *f = fresh_copy(st);
                check_same(st, f);
                iir_stri_destroy(f);
            }
        }
        check_all(st, kinds[kk] == UNIFORM, 5);
        /* a rebuild of the same set keeps every summary and answers the same */
        iir_stri *f = fresh_copy(st);
        set cur = sites_of(st);
        assert_ok(iir_stri_build(st, cur.xyz, cur.ids, cur.n));
        check_same(st, f);
        set_free(&cur);
        iir_stri_destroy(f);
        iir_stri_destroy(st);
        set_free(&s);
    }
}

/* Edits that change the dimension (one circle <-> solid, down to one site) match fresh builds. */
static void test_dimension_changes(void **state)
{
    (void)state;
    set s = make_set(GREAT_CIRCLE, 6, 3);
    iir_stri *st = build(&s);
    double off[3] = {0, 0.6, 0.8}, off2[3] = {0.6, 0, -0.8};
    assert_ok(iir_stri_insert(st, off, 500));
    iir_stri *f = fresh_copy(st);
    check_same(st, f);
    iir_stri_destroy(f);
    check_all(st, 1, 51);
    assert_ok(iir_stri_insert(st, off2, 501));
    assert_ok(iir_stri_remove(st, 500));
    assert_ok(iir_stri_remove(st, 501));
    f = fresh_copy(st);
    check_same(st, f);
    iir_stri_destroy(f);
    check_all(st, 0, 52);
    for (size_t i = 0; i < s.n; i++) {
        assert_ok(iir_stri_remove(st, s.ids[i]));
        f = fresh_copy(st);
        check_same(st, f);
        iir_stri_destroy(f);
        if (i + 1 < s.n) check_all(st, 0, 53 + i);
    }
    assert_int_equal(iir_stri_count(st), 0);
    /* and back up from nothing */
    for (size_t i = 0; i < s.n; i++) {
        assert_ok(iir_stri_insert(st, &s.xyz[3 * i], s.ids[i]));
        check_all(st, 0, 60 + i);
    }
    iir_stri_destroy(st);
    set_free(&s);
}

/* Ties: mirror images (z -> -z) give bit-identical distances. */
static void test_ties(void **state)
{
    (void)state;
    iir_stri *st = iir_stri_create();
    /* a and b = mirror(a) are the closest pair; c and d = mirror(c) their equally near others */
    double a[3] = {1, 0.2, 0.01}, c[3] = {1, -0.2, 0.05};
    normalize3(a);
    normalize3(c);
    double xyz[12] = {a[0], a[1], a[2], a[0], a[1], -a[2], c[0], c[1], c[2], c[0], c[1], -c[2]};
    uint32_t ids[4] = {10, 20, 30, 40}, d, o;
    double len;
    assert_ok(iir_stri_build(st, xyz, ids, 4));
    assert_ok(iir_stri_shortest_edge(st, &d, &o, &len));
    assert_int_equal(d, 20); /* tie: the younger */
    assert_int_equal(o, 10);
    uint32_t swapped[4] = {20, 10, 30, 40};
    assert_ok(iir_stri_build(st, xyz, swapped, 4));
    assert_ok(iir_stri_shortest_edge(st, &d, &o, &len));
    assert_int_equal(d, 20);
    assert_int_equal(o, 10);
    /* two equally short edges: a's mirror pair, and its copy with x and y swapped (bit-identical
     * lengths); the one with the larger younger id wins, and its endpoints tie again */
    double f[3] = {0.8, 0.3, 0.5};
    normalize3(f);
    double sw[18] = {a[0], a[1], a[2],  a[0], a[1], -a[2], a[1], a[0], a[2],
                     a[1], a[0], -a[2], f[0], f[1], f[2],  f[0], f[1], -f[2]};
    uint32_t ids6[6] = {1, 2, 3, 7, 5, 6};
    assert_ok(iir_stri_build(st, sw, ids6, 6));
    assert_ok(iir_stri_shortest_edge(st, &d, &o, &len));
    assert_int_equal(d, 7);
    assert_int_equal(o, 3);
    set s = sites_of(st);
    check_shortest(st, &s);
    set_free(&s);
    iir_stri_destroy(st);
}

/* The octahedron's eight Voronoi vertices tie: the first cell by id, then the smallest face. */
static void test_tie_rule_octahedron(void **state)
{
    (void)state;
    const double xyz[18] = {1, 0, 0, 0, 1, 0, 0, 0, 1, -1, 0, 0, 0, -1, 0, 0, 0, -1};
    const uint32_t ids[2][6] = {{1, 2, 3, 4, 5, 6}, {4, 5, 3, 1, 2, 6}};
    const double want[2][3] = {{1, 1, 1}, {-1, -1, 1}};
    iir_stri *st = iir_stri_create();
    for (int k = 0; k < 2; k++) {
        double c[3], a;
        assert_ok(iir_stri_build(st, xyz, ids[k], 6));
        assert_ok(iir_stri_largest_empty_cap(st, c, &a));
        for (int j = 0; j < 3; j++) assert_near(c[j], want[k][j] / sqrt(3), 1e-15);
        assert_near(a, acos(1 / sqrt(3)), 1e-15);
        check_all(st, 1, 70 + k);
    }
    iir_stri_destroy(st);
}

/* The input order changes nothing, bit for bit: areas, the cap, the shortest edge. */
static void test_permutation_invariance(void **state)
{
    (void)state;
    const enum kind kinds[] = {UNIFORM, HEMISPHERE, GREAT_CIRCLE};
    for (int kk = 0; kk < 3; kk++) {
        set s = make_set(kinds[kk], 200, 80 + kk), t = set_alloc(200);
        uint64_t seed = 81;
        size_t *perm = malloc(200 * sizeof(size_t));
        for (size_t i = 0; i < 200; i++) perm[i] = i;
        for (size_t i = 199; i > 0; i--) {
            size_t j = next_u64(&seed) % (i + 1), tmp = perm[i];
            perm[i] = perm[j], perm[j] = tmp;
        }
        for (size_t i = 0; i < 200; i++) {
            memcpy(&t.xyz[3 * i], &s.xyz[3 * perm[i]], 3 * sizeof(double));
            t.ids[i] = s.ids[perm[i]];
        }
        iir_stri *a = build(&s), *b = build(&t);
        double ca[3], cb[3], ra, rb, aa, ab;
        assert_ok(iir_stri_largest_empty_cap(a, ca, &ra));
        assert_ok(iir_stri_largest_empty_cap(b, cb, &rb));
        assert_memory_equal(ca, cb, sizeof ca);
        assert_true(ra == rb);
        for (size_t i = 0; i < 200; i++) {
            assert_ok(iir_stri_cell_area(a, s.ids[i], &aa));
            assert_ok(iir_stri_cell_area(b, s.ids[i], &ab));
            assert_true(aa == ab);
        }
        check_same(a, b);
        iir_stri_destroy(a);
        iir_stri_destroy(b);
        free(perm);
        set_free(&s);
        set_free(&t);
    }
}

/* ---- timings -------------------------------------------------------------------------------- */

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* One frame of the core's use, as in DESIGN.md section 5: build, 50 x (shortest edge, remove,
 * largest empty cap, insert), all areas. Prints milliseconds; asserts only that it works. */
static void test_timings(void **state)
{
    (void)state;
    const size_t sizes[] = {256, 1024, 4096};
    for (int k = 0; k < 3; k++) {
        set s = make_set(UNIFORM, sizes[k], 5 + k);
        iir_stri *st = iir_stri_create();
        double t0 = now();
        assert_ok(iir_stri_build(st, s.xyz, s.ids, s.n));
        double t1 = now(), t_short = 0, t_rm = 0, t_cap = 0, t_ins = 0;
        uint32_t next_id = 1u << 30;
        for (int r = 0; r < 50; r++) {
            uint32_t d;
            double c[3], a, ta = now();
            assert_ok(iir_stri_shortest_edge(st, &d, NULL, NULL));
            double tb = now();
            assert_ok(iir_stri_remove(st, d));
            double tc = now();
            assert_ok(iir_stri_largest_empty_cap(st, c, &a));
            double td = now();
            assert_ok(iir_stri_insert(st, c, next_id++));
            double te = now();
            t_short += tb - ta, t_rm += tc - tb, t_cap += td - tc, t_ins += te - td;
        }
        uint32_t *ids = malloc(s.n * sizeof(uint32_t));
        double *areas = malloc(s.n * sizeof(double));
        size_t n;
        double t2 = now();
        assert_ok(iir_stri_cell_areas(st, ids, areas, s.n, &n));
        double t3 = now();
        assert_ok(iir_stri_build(st, s.xyz, s.ids, s.n)); /* rebuild: 100 sites changed */
        double t4 = now();
        assert_ok(iir_stri_build(st, s.xyz, s.ids, s.n)); /* rebuild: nothing changed */
        double t5 = now();
        printf("stri n=%zu: build %.3f ms, per edit: shortest_edge %.1f us, remove %.1f us, "
               "largest_empty_cap %.1f us, insert %.1f us; cell_areas %.1f us; rebuild %.3f ms, "
               "unchanged rebuild %.3f ms\n",
               s.n, 1e3 * (t1 - t0), 1e6 * t_short / 50, 1e6 * t_rm / 50, 1e6 * t_cap / 50,
               1e6 * t_ins / 50, 1e6 * (t3 - t2), 1e3 * (t4 - t3), 1e3 * (t5 - t4));
        free(ids);
        free(areas);
        iir_stri_destroy(st);
        set_free(&s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_create_and_bad_args),
        cmocka_unit_test(test_empty_set),
        cmocka_unit_test(test_one_site),
        cmocka_unit_test(test_two_sites),
        cmocka_unit_test(test_cap_inside_an_edge),
        cmocka_unit_test(test_random_sets),
        cmocka_unit_test(test_hemisphere_sets),
        cmocka_unit_test(test_small_cap_sets),
        cmocka_unit_test(test_great_circle_sets),
        cmocka_unit_test(test_small_circle),
        cmocka_unit_test(test_duplicate_points),
        cmocka_unit_test(test_unknown_id),
        cmocka_unit_test(test_buffer_capacity),
        cmocka_unit_test(test_edits_match_fresh_build),
        cmocka_unit_test(test_dimension_changes),
        cmocka_unit_test(test_ties),
        cmocka_unit_test(test_tie_rule_octahedron),
        cmocka_unit_test(test_permutation_invariance),
        cmocka_unit_test(test_timings),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

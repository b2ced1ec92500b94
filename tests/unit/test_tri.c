/* test_tri.c -- libiirtri through its C header: every answer checked against brute force (closest
 * pair, second-nearest neighbours, a dense grid for cell areas and the largest empty circle), order
 * independence, edits against rebuilds (the handle's per-site summaries, kept across edits, against
 * a fresh handle that computes them all), and each documented degenerate case. Not the VPL step. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "iir/tri.h"

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

/* A small deterministic generator (splitmix64), local so the test depends only on tri.h. */
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

/* Ids that are distinct but neither sequential nor sorted like the points. */
static uint32_t id_of(size_t i)
{
    return (uint32_t)(i * 2654435761u + 17u);
}

static double dist2(const double *p, const double *q)
{
    double dx = p[0] - q[0], dy = p[1] - q[1];
    return dx * dx + dy * dy;
}

/* A point set with its ids (owned: free with set_free). */
typedef struct set {
    double *xy;
    uint32_t *ids;
    size_t n;
    double R;
} set;

static set set_alloc(size_t n, double R)
{
    set s = {calloc(2 * n + 2, sizeof(double)), calloc(n + 1, sizeof(uint32_t)), n, R};
    assert_non_null(s.xy);
    assert_non_null(s.ids);
    for (size_t i = 0; i < n; i++) s.ids[i] = id_of(i);
    return s;
}

static void set_free(set *s)
{
    free(s->xy);
    free(s->ids);
}

enum kind { UNIFORM, CLUSTERED, WITH_CIRCLE };

/* n points in the disk of radius R: uniform; in three tight clusters; or uniform with every third
 * point exactly on the circle. */
static set make_set(enum kind kind, size_t n, double R, uint64_t seed)
{
    set s = set_alloc(n, R);
    double cx[3], cy[3];
    for (int c = 0; c < 3; c++) {
        double r = 0.7 * R * sqrt(urand(&seed)), a = 2 * PI * urand(&seed);
        cx[c] = r * cos(a), cy[c] = r * sin(a);
    }
    for (size_t i = 0; i < n; i++) {
        double *p = &s.xy[2 * i];
        if (kind == WITH_CIRCLE && i % 3 == 0) {
            double a = 2 * PI * urand(&seed);
            p[0] = R * cos(a), p[1] = R * sin(a);
        } else if (kind == CLUSTERED) {
            int c = (int)(i % 3);
            do {
                p[0] = cx[c] + 0.05 * R * gauss(&seed), p[1] = cy[c] + 0.05 * R * gauss(&seed);
            } while (p[0] * p[0] + p[1] * p[1] > R * R);
        } else {
            double r = R * sqrt(urand(&seed)), a = 2 * PI * urand(&seed);
            p[0] = r * cos(a), p[1] = r * sin(a);
        }
    }
    return s;
}

static iir_tri *build(const set *s)
{
    iir_tri *tri = iir_tri_create(s->R);
    assert_non_null(tri);
    assert_ok(iir_tri_build(tri, s->xy, s->ids, s->n));
    assert_int_equal(iir_tri_count(tri), s->n);
    return tri;
}

/* Index of the site nearest to p by brute force, and its squared distance. */
static size_t brute_nearest(const set *s, const double *p, double *d2)
{
    size_t best = 0;
    *d2 = INFINITY;
    for (size_t i = 0; i < s->n; i++) {
        double d = dist2(p, &s->xy[2 * i]);
        if (d < *d2) *d2 = d, best = i;
    }
    return best;
}

/* Polygon of a cell (caller frees), its vertex count in *n. */
static double *cell_polygon(const iir_tri *tri, uint32_t id, size_t *n)
{
    assert_ok(iir_tri_cell_polygon(tri, id, NULL, 0, n));
    double *xy = malloc(2 * *n * sizeof(double) + 1);
    assert_non_null(xy);
    assert_ok(iir_tri_cell_polygon(tri, id, xy, *n, n));
    return xy;
}

static double shoelace(const double *xy, size_t n)
{
    double a = 0;
    for (size_t k = 0; k < n; k++) {
        const double *p = &xy[2 * k], *q = &xy[2 * ((k + 1) % n)];
        a += p[0] * q[1] - p[1] * q[0];
    }
    return 0.5 * a;
}

static double perimeter(const double *xy, size_t n)
{
    double l = 0;
    for (size_t k = 0; k < n; k++) l += sqrt(dist2(&xy[2 * k], &xy[2 * ((k + 1) % n)]));
    return l;
}

/* ---- brute-force checks, one per query ------------------------------------------------------ */

/* Per-site cell areas by counting grid points (spacing h) by nearest site, and the largest
 * nearest-site distance over the grid points in the disk plus samples on the circle. */
typedef struct grid_answer {
    double *area;
    double h, lec;
} grid_answer;

static grid_answer grid_search(const set *s, int res)
{
    grid_answer g = {calloc(s->n + 1, sizeof(double)), 2 * s->R / res, 0};
    assert_non_null(g.area);
    for (int i = 0; i < res; i++)
        for (int j = 0; j < res; j++) {
            double p[2] = {-s->R + (i + 0.5) * g.h, -s->R + (j + 0.5) * g.h}, d2;
            if (p[0] * p[0] + p[1] * p[1] > s->R * s->R) continue;
            g.area[brute_nearest(s, p, &d2)] += g.h * g.h;
            g.lec = fmax(g.lec, sqrt(d2));
        }
    for (int k = 0; k < 8 * res; k++) {
        double a = 2 * PI * k / (8 * res), p[2] = {s->R * cos(a), s->R * sin(a)}, d2;
        brute_nearest(s, p, &d2);
        g.lec = fmax(g.lec, sqrt(d2));
    }
    return g;
}

/* Areas sum to pi R^2, each area matches the grid, each polygon is convex, counter-clockwise, close
 * to the exact area, and its vertices are nearest to its own site. */
static void check_cells(const iir_tri *tri, const set *s, const grid_answer *g)
{
    double sum = 0;
    for (size_t i = 0; i < s->n; i++) {
        double area, d2;
        assert_ok(iir_tri_cell_area(tri, s->ids[i], &area));
        sum += area;
        size_t m;
        double *poly = cell_polygon(tri, s->ids[i], &m);
        assert_true(m >= 3);
        assert_near(area, g->area[i], perimeter(poly, m) * g->h + 1e-12);
        /* chords cut at most the circular segments of 2 pi / IIR_TRI_ARC_SEGMENTS each */
        double chord = 2 * PI / IIR_TRI_ARC_SEGMENTS;
        double lost = 0.5 * s->R * s->R * (chord - sin(chord)) * IIR_TRI_ARC_SEGMENTS;
        double shoe = shoelace(poly, m);
        assert_true(shoe <= area + 1e-12 && shoe >= area - lost - 1e-12);
        for (size_t k = 0; k < m; k++) {
            const double *a = &poly[2 * k], *b = &poly[2 * ((k + 1) % m)],
                         *c = &poly[2 * ((k + 2) % m)];
            double turn = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]);
            assert_true(turn >= -1e-12 * s->R * s->R);
            brute_nearest(s, a, &d2);
            assert_near(sqrt(dist2(a, &s->xy[2 * i])), sqrt(d2), 1e-9 * s->R);
        }
        free(poly);
    }
    assert_near(sum, PI * s->R * s->R, 1e-9 * PI * s->R * s->R);
}

/* The largest empty circle beats every grid point, is no better than the grid allows, and its
 * radius is the true distance from its centre (in the disk) to the nearest site. */
static void check_lec(const iir_tri *tri, const set *s, const grid_answer *g)
{
    double c[2], r, d2;
    assert_ok(iir_tri_largest_empty_circle(tri, c, &r));
    assert_true(c[0] * c[0] + c[1] * c[1] <= s->R * s->R * (1 + 1e-12));
    brute_nearest(s, c, &d2);
    assert_near(r, sqrt(d2), 1e-12 * s->R);
    assert_true(r >= g->lec - 1e-12 * s->R);
    assert_true(r <= g->lec + 1.5 * g->h);
}

/* Brute-force squared distance from site i to its nearest site other than i and j. */
static double second_nearest2(const set *s, size_t i, size_t j)
{
    double best = INFINITY;
    for (size_t k = 0; k < s->n; k++)
        if (k != i && k != j) best = fmin(best, dist2(&s->xy[2 * i], &s->xy[2 * k]));
    return best;
}

/* The closest pair by brute force, with the header's tie rule (larger larger-id, then larger
 * smaller-id), split into denser and other endpoint by the header's rule. */
static void brute_shortest(const set *s, uint32_t *denser, uint32_t *other, double *len)
{
    size_t bi = 0, bj = 0;
    double best = INFINITY;
    for (size_t i = 0; i < s->n; i++)
        for (size_t j = 0; j < s->n; j++) {
            if (s->ids[i] <= s->ids[j]) continue; /* i is the younger endpoint */
            double d = dist2(&s->xy[2 * i], &s->xy[2 * j]);
            int wins =
                d < best || (d == best && (s->ids[i] > s->ids[bi] ||
                                           (s->ids[i] == s->ids[bi] && s->ids[j] > s->ids[bj])));
            if (wins) best = d, bi = i, bj = j;
        }
    double di = second_nearest2(s, bi, bj), dj = second_nearest2(s, bj, bi);
    size_t d = di <= dj ? bi : bj;
    *denser = s->ids[d];
    *other = s->ids[d == bi ? bj : bi];
    *len = sqrt(best);
}

static void check_shortest(const iir_tri *tri, const set *s)
{
    uint32_t denser, other, bd, bo;
    double len, blen;
    if (s->n < 2) {
        assert_int_equal(iir_tri_shortest_edge(tri, &denser, &other, &len), IIR_TRI_TOO_FEW);
        return;
    }
    assert_ok(iir_tri_shortest_edge(tri, &denser, &other, &len));
    brute_shortest(s, &bd, &bo, &blen);
    assert_int_equal(denser, bd);
    assert_int_equal(other, bo);
    assert_near(len, blen, 1e-15 * s->R);
}

/* Edges are sorted id pairs of known sites, at most 3n, and include the closest pair. */
static void check_edges(const iir_tri *tri, const set *s)
{
    size_t n;
    assert_ok(iir_tri_edges(tri, NULL, 0, &n));
    assert_true(n <= 3 * s->n);
    uint32_t *pairs = malloc(2 * n * sizeof(uint32_t) + 1);
    assert_ok(iir_tri_edges(tri, pairs, n, &n));
    double xy[2];
    for (size_t k = 0; k < n; k++) {
        assert_true(pairs[2 * k] < pairs[2 * k + 1]);
        if (k)
            assert_true(pairs[2 * k - 2] < pairs[2 * k] ||
                        (pairs[2 * k - 2] == pairs[2 * k] && pairs[2 * k - 1] < pairs[2 * k + 1]));
        assert_ok(iir_tri_position(tri, pairs[2 * k], xy));
        assert_ok(iir_tri_position(tri, pairs[2 * k + 1], xy));
    }
    if (s->n >= 2) {
        uint32_t a, b;
        double len;
        assert_ok(iir_tri_shortest_edge(tri, &a, &b, &len));
        uint32_t lo = a < b ? a : b, hi = a < b ? b : a;
        int found = 0;
        for (size_t k = 0; k < n; k++) found |= pairs[2 * k] == lo && pairs[2 * k + 1] == hi;
        assert_true(found);
    }
    free(pairs);
}

static void check_all(const set *s, int res)
{
    iir_tri *tri = build(s);
    grid_answer g = grid_search(s, res);
    check_cells(tri, s, &g);
    check_lec(tri, s, &g);
    check_shortest(tri, s);
    check_edges(tri, s);
    free(g.area);
    iir_tri_destroy(tri);
}

/* Everything a query answers, per id, for comparing two handles. */
typedef struct answers {
    size_t n;
    uint32_t ids[512];
    double areas[512];
    uint32_t denser, other;
    double len, centre[2], radius;
    size_t n_edges;
    uint32_t edges[2 * 3 * 512];
} answers;

static void collect(const iir_tri *tri, answers *a)
{
    memset(a, 0, sizeof *a);
    assert_ok(iir_tri_cell_areas(tri, a->ids, a->areas, 512, &a->n));
    if (a->n >= 2) assert_ok(iir_tri_shortest_edge(tri, &a->denser, &a->other, &a->len));
    if (a->n >= 1) assert_ok(iir_tri_largest_empty_circle(tri, a->centre, &a->radius));
    assert_ok(iir_tri_edges(tri, a->edges, 3 * 512, &a->n_edges));
}

/* Same answers, bit for bit (random sets have a unique Delaunay triangulation). */
static void assert_same(const answers *a, const answers *b)
{
    assert_int_equal(a->n, b->n);
    assert_memory_equal(a->ids, b->ids, a->n * sizeof(uint32_t));
    for (size_t i = 0; i < a->n; i++) assert_near(a->areas[i], b->areas[i], 0);
    assert_int_equal(a->denser, b->denser);
    assert_int_equal(a->other, b->other);
    assert_near(a->len, b->len, 0);
    assert_near(a->centre[0], b->centre[0], 0);
    assert_near(a->centre[1], b->centre[1], 0);
    assert_near(a->radius, b->radius, 0);
    assert_int_equal(a->n_edges, b->n_edges);
    assert_memory_equal(a->edges, b->edges, 2 * a->n_edges * sizeof(uint32_t));
}

static void shuffle(set *s, uint64_t seed)
{
    for (size_t i = s->n; i > 1; i--) {
        size_t j = (size_t)(next_u64(&seed) % i);
        double x = s->xy[2 * (i - 1)], y = s->xy[2 * (i - 1) + 1];
        uint32_t id = s->ids[i - 1];
        s->xy[2 * (i - 1)] = s->xy[2 * j], s->xy[2 * (i - 1) + 1] = s->xy[2 * j + 1];
        s->ids[i - 1] = s->ids[j];
        s->xy[2 * j] = x, s->xy[2 * j + 1] = y, s->ids[j] = id;
    }
}

/* ---- lifetime and arguments ----------------------------------------------------------------- */

static void test_create_and_bad_args(void **state)
{
    (void)state;
    assert_null(iir_tri_create(0));
    assert_null(iir_tri_create(-1));
    assert_null(iir_tri_create(NAN));
    assert_null(iir_tri_create(INFINITY));
    iir_tri_destroy(NULL);
    assert_int_equal(iir_tri_count(NULL), 0);
    assert_true(iir_tri_radius(NULL) == 0);
    assert_true(strlen(iir_tri_cgal_version()) > 0);
    for (int a = IIR_TRI_OK; a <= IIR_TRI_INTERNAL; a++) {
        assert_non_null(iir_tri_status_name((iir_tri_status)a));
        for (int b = IIR_TRI_OK; b < a; b++)
            assert_string_not_equal(iir_tri_status_name((iir_tri_status)a),
                                    iir_tri_status_name((iir_tri_status)b));
    }

    double xy[2] = {0, 0}, c[2], r;
    uint32_t id = 1;
    size_t n;
    assert_int_equal(iir_tri_build(NULL, xy, &id, 1), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_tri_insert(NULL, 0, 0, 1), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_tri_remove(NULL, 1), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_tri_largest_empty_circle(NULL, c, &r), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_tri_shortest_edge(NULL, NULL, NULL, NULL), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_tri_edges(NULL, NULL, 0, &n), IIR_TRI_BAD_ARG);

    iir_tri *tri = iir_tri_create(0.5);
    assert_true(iir_tri_radius(tri) == 0.5);
    assert_int_equal(iir_tri_build(tri, NULL, &id, 1), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_tri_build(tri, xy, NULL, 1), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_tri_insert(tri, NAN, 0, 1), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_tri_insert(tri, 0, INFINITY, 1), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_tri_cell_areas(tri, &id, NULL, 1, &n), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_tri_largest_empty_circle(tri, NULL, &r), IIR_TRI_BAD_ARG);
    assert_int_equal(iir_tri_count(tri), 0);
    iir_tri_destroy(tri);
}

/* ---- degenerate sets, each as the header documents ------------------------------------------ */

static void test_empty_set(void **state)
{
    (void)state;
    iir_tri *tri = iir_tri_create(1);
    uint32_t a, b;
    double len, c[2] = {7, 7}, r = 7, area;
    size_t n = 99;
    assert_ok(iir_tri_build(tri, NULL, NULL, 0));
    assert_int_equal(iir_tri_shortest_edge(tri, &a, &b, &len), IIR_TRI_TOO_FEW);
    assert_int_equal(iir_tri_largest_empty_circle(tri, c, &r), IIR_TRI_TOO_FEW);
    assert_true(c[0] == 7 && c[1] == 7 && r == 7);
    assert_int_equal(iir_tri_nearest(tri, 0, 0, &a, &len), IIR_TRI_TOO_FEW);
    assert_ok(iir_tri_cell_areas(tri, &a, &area, 1, &n));
    assert_int_equal(n, 0);
    assert_ok(iir_tri_edges(tri, NULL, 0, &n));
    assert_int_equal(n, 0);
    assert_ok(iir_tri_ids(tri, NULL, 0, &n));
    assert_int_equal(n, 0);
    assert_int_equal(iir_tri_remove(tri, 3), IIR_TRI_UNKNOWN_ID);
    assert_int_equal(iir_tri_cell_area(tri, 3, &area), IIR_TRI_UNKNOWN_ID);
    assert_int_equal(iir_tri_cell_polygon(tri, 3, NULL, 0, &n), IIR_TRI_UNKNOWN_ID);
    iir_tri_destroy(tri);
}

static void test_one_site(void **state)
{
    (void)state;
    const double R = 0.5;
    iir_tri *tri = iir_tri_create(R);
    double area, c[2], r, len;
    uint32_t a, b;
    size_t n;

    /* at the centre: the cell is the whole disk; the empty circle sits on the circle at (R, 0) */
    assert_ok(iir_tri_insert(tri, 0, 0, 42));
    assert_ok(iir_tri_cell_area(tri, 42, &area));
    assert_near(area, PI * R * R, 1e-15);
    assert_ok(iir_tri_largest_empty_circle(tri, c, &r));
    assert_near(c[0], R, 1e-15);
    assert_near(c[1], 0, 1e-15);
    assert_near(r, R, 1e-15);
    assert_int_equal(iir_tri_shortest_edge(tri, &a, &b, &len), IIR_TRI_TOO_FEW);
    assert_ok(iir_tri_edges(tri, NULL, 0, &n));
    assert_int_equal(n, 0);
    double *poly = cell_polygon(tri, 42, &n);
    assert_int_equal(n, IIR_TRI_ARC_SEGMENTS);
    for (size_t k = 0; k < n; k++) assert_near(hypot(poly[2 * k], poly[2 * k + 1]), R, 1e-15);
    assert_true(shoelace(poly, n) > 0);
    free(poly);

    /* off centre: the empty circle is at the opposite point of the circle */
    assert_ok(iir_tri_remove(tri, 42));
    assert_ok(iir_tri_insert(tri, 0.3 * R, 0.2 * R, 43));
    assert_ok(iir_tri_cell_area(tri, 43, &area));
    assert_near(area, PI * R * R, 1e-15);
    assert_ok(iir_tri_largest_empty_circle(tri, c, &r));
    double s = hypot(0.3, 0.2);
    assert_near(c[0], -R * 0.3 / s, 1e-15);
    assert_near(c[1], -R * 0.2 / s, 1e-15);
    assert_near(r, R + s * R, 1e-15);
    iir_tri_destroy(tri);
}

static void test_two_sites(void **state)
{
    (void)state;
    set s = set_alloc(2, 1);
    s.xy[0] = -0.5, s.xy[2] = 0.5;
    s.ids[0] = 9, s.ids[1] = 4;
    iir_tri *tri = build(&s);
    double area, c[2], r, len;
    uint32_t a, b;
    for (int i = 0; i < 2; i++) {
        assert_ok(iir_tri_cell_area(tri, s.ids[i], &area));
        assert_near(area, PI / 2, 1e-14);
    }
    /* the empty circle is where the bisector meets the circle, (0, +-1) */
    assert_ok(iir_tri_largest_empty_circle(tri, c, &r));
    assert_near(fabs(c[0]), 0, 1e-15);
    assert_near(fabs(c[1]), 1, 1e-15);
    assert_near(r, sqrt(1.25), 1e-15);
    /* no third site for either end: the tie goes to the larger id */
    assert_ok(iir_tri_shortest_edge(tri, &a, &b, &len));
    assert_int_equal(a, 9);
    assert_int_equal(b, 4);
    assert_near(len, 1, 0);
    check_all(&s, 300);
    iir_tri_destroy(tri);
    set_free(&s);
}

/* Area of the strip |x| <= w of the unit disk. */
static double strip_area(double w)
{
    return 2 * (w * sqrt(1 - w * w) + asin(w));
}

static void test_collinear_sites(void **state)
{
    (void)state;
    set s = set_alloc(3, 1);
    s.xy[0] = -0.5, s.xy[2] = 0, s.xy[4] = 0.5;
    s.ids[0] = 10, s.ids[1] = 11, s.ids[2] = 12;
    iir_tri *tri = build(&s);
    double area, c[2], r, len;
    uint32_t a, b, pairs[4];
    size_t n;
    assert_ok(iir_tri_cell_area(tri, 11, &area));
    assert_near(area, strip_area(0.25), 1e-14);
    assert_ok(iir_tri_cell_area(tri, 12, &area));
    assert_near(area, (PI - strip_area(0.25)) / 2, 1e-14);
    assert_ok(iir_tri_edges(tri, pairs, 2, &n));
    assert_int_equal(n, 2);
    assert_true(pairs[0] == 10 && pairs[1] == 11 && pairs[2] == 11 && pairs[3] == 12);
    /* equal edges: (11,12) has the larger younger id; 11's other neighbour (10) is nearer than
     * 12's (10), so 11 is the denser end */
    assert_ok(iir_tri_shortest_edge(tri, &a, &b, &len));
    assert_int_equal(a, 11);
    assert_int_equal(b, 12);
    assert_near(len, 0.5, 0);
    assert_ok(iir_tri_largest_empty_circle(tri, c, &r));
    assert_near(r, 1, 1e-14);
    check_all(&s, 300);
    iir_tri_destroy(tri);
    set_free(&s);

    /* an oblique line of five sites, ends on the circle */
    s = set_alloc(5, 0.7);
    for (size_t i = 0; i < 5; i++) {
        double t = -1 + 0.5 * (double)i;
        s.xy[2 * i] = 0.7 * t * cos(0.3), s.xy[2 * i + 1] = 0.7 * t * sin(0.3);
    }
    check_all(&s, 300);
    set_free(&s);
}

static void test_duplicate_points(void **state)
{
    (void)state;
    set s = set_alloc(5, 1);
    double pts[10] = {0.1, 0.1, -0.3, 0.2, 0.1, 0.1, 0.5, -0.5, 0.1, 0.1};
    uint32_t ids[5] = {30, 40, 20, 50, 25};
    memcpy(s.xy, pts, sizeof pts);
    memcpy(s.ids, ids, sizeof ids);
    iir_tri *tri = iir_tri_create(1);
    double xy[2], area, sum = 0;

    /* build keeps the smallest id at a repeated position and says so */
    assert_int_equal(iir_tri_build(tri, s.xy, s.ids, 5), IIR_TRI_DUPLICATE_POINT);
    assert_int_equal(iir_tri_count(tri), 3);
    assert_ok(iir_tri_position(tri, 20, xy));
    assert_true(xy[0] == 0.1 && xy[1] == 0.1);
    assert_int_equal(iir_tri_position(tri, 30, xy), IIR_TRI_UNKNOWN_ID);
    assert_int_equal(iir_tri_position(tri, 25, xy), IIR_TRI_UNKNOWN_ID);
    uint32_t kept[3] = {20, 40, 50};
    for (int i = 0; i < 3; i++) {
        assert_ok(iir_tri_cell_area(tri, kept[i], &area));
        sum += area;
    }
    assert_near(sum, PI, 1e-12);

    /* insert of a taken position or a taken id changes nothing */
    assert_int_equal(iir_tri_insert(tri, -0.3, 0.2, 99), IIR_TRI_DUPLICATE_POINT);
    assert_int_equal(iir_tri_insert(tri, 0.7, 0.0, 40), IIR_TRI_DUPLICATE_ID);
    assert_int_equal(iir_tri_count(tri), 3);
    assert_int_equal(iir_tri_position(tri, 99, xy), IIR_TRI_UNKNOWN_ID);
    assert_ok(iir_tri_position(tri, 40, xy));
    assert_true(xy[0] == -0.3 && xy[1] == 0.2);

    /* a build with a repeated id is refused and keeps the previous set */
    s.ids[1] = 50;
    assert_int_equal(iir_tri_build(tri, s.xy, s.ids, 5), IIR_TRI_DUPLICATE_ID);
    assert_int_equal(iir_tri_count(tri), 3);
    assert_ok(iir_tri_position(tri, 40, xy));
    iir_tri_destroy(tri);
    set_free(&s);
}

static void test_outside_points(void **state)
{
    (void)state;
    const double R = 0.5;
    iir_tri *tri = iir_tri_create(R);
    double xy[2];
    assert_int_equal(iir_tri_insert(tri, R * 1.001, 0, 1), IIR_TRI_OUTSIDE);
    assert_int_equal(iir_tri_insert(tri, 0.4, 0.4, 1), IIR_TRI_OUTSIDE);
    /* rounding error on the circle is accepted and stored as given */
    assert_ok(iir_tri_insert(tri, R * (1 + 1e-12), 0, 1));
    assert_ok(iir_tri_position(tri, 1, xy));
    assert_true(xy[0] == R * (1 + 1e-12));
    /* a build with one point outside is refused and keeps the previous set */
    double pts[4] = {0, 0, 0, 0.6};
    uint32_t ids[2] = {5, 6};
    assert_int_equal(iir_tri_build(tri, pts, ids, 2), IIR_TRI_OUTSIDE);
    assert_int_equal(iir_tri_count(tri), 1);
    assert_ok(iir_tri_position(tri, 1, xy));
    iir_tri_destroy(tri);
}

static void test_cocircular_sites(void **state)
{
    (void)state;
    /* every site on the circle: the empty circle is the centre (a Voronoi vertex of degree 12) */
    set s = set_alloc(12, 1);
    for (size_t i = 0; i < 12; i++)
        s.xy[2 * i] = cos(2 * PI * (double)i / 12), s.xy[2 * i + 1] = sin(2 * PI * (double)i / 12);
    iir_tri *tri = build(&s);
    double c[2], r, area;
    assert_ok(iir_tri_largest_empty_circle(tri, c, &r));
    assert_near(c[0], 0, 1e-12);
    assert_near(c[1], 0, 1e-12);
    assert_near(r, 1, 1e-12);
    for (size_t i = 0; i < 12; i++) {
        assert_ok(iir_tri_cell_area(tri, s.ids[i], &area));
        assert_near(area, PI / 12, 1e-12);
    }
    check_all(&s, 300);
    iir_tri_destroy(tri);
    set_free(&s);
}

static void test_unknown_id(void **state)
{
    (void)state;
    set s = make_set(UNIFORM, 20, 1, 7);
    iir_tri *tri = build(&s);
    double area, xy[2];
    size_t n;
    assert_int_equal(iir_tri_remove(tri, 12345), IIR_TRI_UNKNOWN_ID);
    assert_int_equal(iir_tri_cell_area(tri, 12345, &area), IIR_TRI_UNKNOWN_ID);
    assert_int_equal(iir_tri_cell_polygon(tri, 12345, NULL, 0, &n), IIR_TRI_UNKNOWN_ID);
    assert_int_equal(iir_tri_position(tri, 12345, xy), IIR_TRI_UNKNOWN_ID);
    assert_ok(iir_tri_remove(tri, s.ids[3]));
    assert_int_equal(iir_tri_remove(tri, s.ids[3]), IIR_TRI_UNKNOWN_ID);
    assert_int_equal(iir_tri_count(tri), 19);
    iir_tri_destroy(tri);
    set_free(&s);
}

static void test_buffer_capacity(void **state)
{
    (void)state;
    set s = make_set(UNIFORM, 10, 1, 11);
    iir_tri *tri = build(&s);
    uint32_t ids[10], pairs[64];
    double areas[10], xy[256];
    size_t n = 0;
    memset(ids, 0xab, sizeof ids);
    assert_int_equal(iir_tri_ids(tri, ids, 9, &n), IIR_TRI_CAPACITY);
    assert_int_equal(n, 10);
    assert_int_equal(ids[0], 0xabababab);
    assert_ok(iir_tri_ids(tri, ids, 10, &n));
    for (size_t i = 1; i < n; i++) assert_true(ids[i - 1] < ids[i]);
    assert_int_equal(iir_tri_cell_areas(tri, ids, areas, 3, &n), IIR_TRI_CAPACITY);
    assert_int_equal(n, 10);
    assert_ok(iir_tri_edges(tri, NULL, 0, &n));
    size_t ne = n;
    assert_int_equal(iir_tri_edges(tri, pairs, ne - 1, &n), IIR_TRI_CAPACITY);
    assert_int_equal(n, ne);
    assert_ok(iir_tri_edges(tri, pairs, ne, &n));
    assert_ok(iir_tri_cell_polygon(tri, s.ids[0], NULL, 0, &n));
    size_t nv = n;
    assert_int_equal(iir_tri_cell_polygon(tri, s.ids[0], xy, nv - 1, &n), IIR_TRI_CAPACITY);
    assert_int_equal(n, nv);
    iir_tri_destroy(tri);
    set_free(&s);
}

/* ---- random sets against brute force -------------------------------------------------------- */

static void test_random_sets_brute_force(void **state)
{
    (void)state;
    const size_t sizes[] = {1, 2, 3, 4, 7, 15, 40, 100, 200};
    uint64_t seed = 1000;
    for (int kind = UNIFORM; kind <= WITH_CIRCLE; kind++)
        for (size_t k = 0; k < sizeof sizes / sizeof *sizes; k++) {
            double R = (k % 2) ? 1.0 : 0.5; /* 0.5 = sin 30 degrees */
            set s = make_set((enum kind)kind, sizes[k], R, seed++);
            check_all(&s, sizes[k] > 50 ? 500 : 300);
            set_free(&s);
        }
}

/* ---- order independence and edits ----------------------------------------------------------- */

static void test_permutation_invariance(void **state)
{
    (void)state;
    static answers ref, got;
    for (int kind = UNIFORM; kind <= WITH_CIRCLE; kind++) {
        set s = make_set((enum kind)kind, 150, 1, 77 + (uint64_t)kind);
        iir_tri *tri = build(&s);
        collect(tri, &ref);
        iir_tri_destroy(tri);
        for (uint64_t p = 0; p < 5; p++) {
            shuffle(&s, 500 + p);
            tri = build(&s);
            collect(tri, &got);
            assert_same(&ref, &got);
            iir_tri_destroy(tri);
        }
        set_free(&s);
    }
}

static void test_edits_match_rebuild(void **state)
{
    (void)state;
    static answers edited, fresh;
    set s = make_set(WITH_CIRCLE, 120, 1, 4242);
    iir_tri *tri = build(&s);
    /* remove the first 40 of a shuffled copy, compare with a build of the other 80 */
    set t = set_alloc(120, 1);
    memcpy(t.xy, s.xy, 240 * sizeof(double));
    memcpy(t.ids, s.ids, 120 * sizeof(uint32_t));
    shuffle(&t, 99);
    for (size_t i = 0; i < 40; i++) assert_ok(iir_tri_remove(tri, t.ids[i]));
    set rest = {t.xy + 80, t.ids + 40, 80, 1};
    iir_tri *ref = build(&rest);
    collect(tri, &edited);
    collect(ref, &fresh);
    assert_same(&edited, &fresh);
    iir_tri_destroy(ref);
    /* insert them again in reverse, compare with a build of all */
    for (size_t i = 40; i-- > 0;)
        assert_ok(iir_tri_insert(tri, t.xy[2 * i], t.xy[2 * i + 1], t.ids[i]));
    ref = build(&s);
    collect(tri, &edited);
    collect(ref, &fresh);
    assert_same(&edited, &fresh);
    iir_tri_destroy(ref);
    iir_tri_destroy(tri);
    set_free(&t);
    set_free(&s);
}

/* A fresh handle over the same sites (ids and positions) as tri: nothing carried over from tri's
 * edits, every per-site summary computed from scratch by the build. */
static iir_tri *fresh_copy(const iir_tri *tri)
{
    size_t n;
    assert_ok(iir_tri_ids(tri, NULL, 0, &n));
    uint32_t *ids = malloc(n * sizeof *ids + 1);
    double *xy = malloc(2 * n * sizeof *xy + 1);
    assert_non_null(ids);
    assert_non_null(xy);
    assert_ok(iir_tri_ids(tri, ids, n, &n));
    for (size_t i = 0; i < n; i++) assert_ok(iir_tri_position(tri, ids[i], &xy[2 * i]));
    iir_tri *fresh = iir_tri_create(iir_tri_radius(tri));
    assert_non_null(fresh);
    assert_ok(iir_tri_build(fresh, xy, ids, n));
    free(ids);
    free(xy);
    return fresh;
}

/* Every answer of the edited handle equals, bit for bit, the fresh handle's (with polygons when
 * `polygons`). Exact only where the Delaunay triangulation is unique (no four cocircular sites). */
static void assert_same_as_fresh(const iir_tri *tri, int polygons)
{
    static answers got, want;
    iir_tri *fresh = fresh_copy(tri);
    collect(tri, &got);
    collect(fresh, &want);
    assert_same(&got, &want);
    assert_memory_equal(got.areas, want.areas, got.n * sizeof(double));
    assert_memory_equal(got.centre, want.centre, sizeof got.centre);
    assert_memory_equal(&got.radius, &want.radius, sizeof got.radius);
    for (size_t i = 0; i < got.n; i++) {
        double area;
        assert_ok(iir_tri_cell_area(tri, got.ids[i], &area));
        assert_memory_equal(&area, &got.areas[i], sizeof area);
        if (!polygons) continue;
        size_t m, mf;
        double *poly = cell_polygon(tri, got.ids[i], &m);
        double *pf = cell_polygon(fresh, got.ids[i], &mf);
        assert_int_equal(m, mf);
        assert_memory_equal(poly, pf, 2 * m * sizeof(double));
        free(poly);
        free(pf);
    }
    iir_tri_destroy(fresh);
}

/* Rebuilds tri from its own sites, most of them as they are (a build keeps their summaries), some
 * dropped, some moved a little, one given a new id. */
static void rebuild_changed(iir_tri *tri, uint64_t *seed, uint32_t new_id)
{
    uint32_t ids[512];
    double xy[2 * 512];
    size_t n, m = 0;
    assert_ok(iir_tri_ids(tri, ids, 512, &n));
    for (size_t i = 0; i < n; i++) {
        uint64_t u = next_u64(seed) % 20;
        if (u == 0) continue;
        assert_ok(iir_tri_position(tri, ids[i], &xy[2 * m]));
        if (u == 1) xy[2 * m] *= 0.999, xy[2 * m + 1] *= 0.999;
        ids[m++] = ids[i];
    }
    ids[m / 2] = new_id;
    assert_ok(iir_tri_build(tri, xy, ids, m));
}

/* 500 random edits of the kinds the VPL step makes (insert at the largest empty circle, insert
 * anywhere, remove the denser end of the shortest edge, remove any site, now and then a rebuild of
 * the same sites with a few changed), each followed by every query, against a fresh handle: the
 * summaries an edit keeps are the ones it did not change. */
static void test_edits_match_fresh_build(void **state)
{
    (void)state;
    for (int kind = UNIFORM; kind <= WITH_CIRCLE; kind += WITH_CIRCLE - UNIFORM) {
        set s = make_set((enum kind)kind, 200, 1, 31337 + (uint64_t)kind);
        uint64_t seed = 0x5eed + (uint64_t)kind; /* not make_set's stream: no repeated points */
        iir_tri *tri = build(&s);
        uint32_t next_id = 1u << 30, ids[512];
        for (int edit = 0; edit < 500; edit++) {
            size_t n = iir_tri_count(tri);
            int op = (int)(next_u64(&seed) % 4);
            if (n < 150) op = op % 2;
            if (n > 250) op = 2 + op % 2;
            if (op == 0) {
                double c[2], r;
                assert_ok(iir_tri_largest_empty_circle(tri, c, &r));
                assert_ok(iir_tri_insert(tri, c[0], c[1], next_id++));
            } else if (op == 1) {
                double r = sqrt(urand(&seed)), a = 2 * PI * urand(&seed);
                assert_ok(iir_tri_insert(tri, r * cos(a), r * sin(a), next_id++));
            } else if (op == 2) {
                uint32_t denser;
                assert_ok(iir_tri_shortest_edge(tri, &denser, NULL, NULL));
                assert_ok(iir_tri_remove(tri, denser));
            } else {
                assert_ok(iir_tri_ids(tri, ids, 512, &n));
                assert_ok(iir_tri_remove(tri, ids[next_u64(&seed) % n]));
            }
            if (edit % 50 == 49) rebuild_changed(tri, &seed, next_id++);
            assert_same_as_fresh(tri, edit % 25 == 0);
        }
        iir_tri_destroy(tri);
        set_free(&s);
    }
}

/* Edits across dimensions: sites on a line (dimension 1, exactly collinear), one site off it
 * (dimension 2) and back, then down to none; after each edit every answer equals a fresh build's.
 */
static void test_dimension_changes_match_fresh_build(void **state)
{
    (void)state;
    const double t[7] = {0.25, -0.5, 0.75, 0, -0.625, 0.5, -0.25};
    iir_tri *tri = iir_tri_create(1);
    for (uint32_t i = 0; i < 7; i++) {
        assert_ok(iir_tri_insert(tri, t[i], 0.5 * t[i] - 0.125, 10 + (i * 3) % 7));
        assert_same_as_fresh(tri, 1);
    }
    for (int round = 0; round < 2; round++) {
        assert_ok(iir_tri_insert(tri, round ? 0.1 : -0.3, round ? -0.6 : 0.5, 99));
        assert_same_as_fresh(tri, 1);
        assert_ok(iir_tri_remove(tri, 99));
        assert_same_as_fresh(tri, 1);
    }
    const uint32_t order[7] = {13, 10, 16, 11, 15, 12, 14};
    for (int i = 0; i < 7; i++) {
        assert_ok(iir_tri_remove(tri, order[i]));
        assert_same_as_fresh(tri, 1);
    }
    assert_int_equal(iir_tri_count(tri), 0);
    iir_tri_destroy(tri);
}

/* The incremental step's loop on a large set: delete the denser end of the shortest edge, insert at
 * the largest empty circle. A sanity run, no timing asserted. */
static void test_large_churn(void **state)
{
    (void)state;
    set s = make_set(UNIFORM, 2000, 1, 2024);
    iir_tri *tri = build(&s);
    uint32_t next_id = 1u << 31;
    for (int cycle = 0; cycle < 100; cycle++) {
        uint32_t denser, other;
        double len, c[2], r;
        assert_ok(iir_tri_shortest_edge(tri, &denser, &other, &len));
        assert_ok(iir_tri_remove(tri, denser));
        assert_ok(iir_tri_largest_empty_circle(tri, c, &r));
        assert_true(r > 0);
        assert_ok(iir_tri_insert(tri, c[0], c[1], next_id++));
    }
    assert_int_equal(iir_tri_count(tri), 2000);
    size_t n;
    double *areas = malloc(2000 * sizeof(double));
    uint32_t *ids = malloc(2000 * sizeof(uint32_t));
    assert_ok(iir_tri_cell_areas(tri, ids, areas, 2000, &n));
    double sum = 0;
    for (size_t i = 0; i < n; i++) sum += areas[i];
    assert_near(sum, PI, 1e-9 * PI);
    free(areas);
    free(ids);
    iir_tri_destroy(tri);
    set_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_create_and_bad_args),
        cmocka_unit_test(test_empty_set),
        cmocka_unit_test(test_one_site),
        cmocka_unit_test(test_two_sites),
        cmocka_unit_test(test_collinear_sites),
        cmocka_unit_test(test_duplicate_points),
        cmocka_unit_test(test_outside_points),
        cmocka_unit_test(test_cocircular_sites),
        cmocka_unit_test(test_unknown_id),
        cmocka_unit_test(test_buffer_capacity),
        cmocka_unit_test(test_random_sets_brute_force),
        cmocka_unit_test(test_permutation_invariance),
        cmocka_unit_test(test_edits_match_rebuild),
        cmocka_unit_test(test_edits_match_fresh_build),
        cmocka_unit_test(test_dimension_changes_match_fresh_build),
        cmocka_unit_test(test_large_churn),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

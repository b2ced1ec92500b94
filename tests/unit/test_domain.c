/* test_domain.c -- iir_method_domain, the light's disk domain for drawing: sites are the VPLs (by
 * id, flags from the frame's stats), edges index sites, the clipped cells tile the unit disk and
 * hold their sites, and the removed points are the frame's invalidated and deleted VPLs, on the
 * built-in Cornell box with a moving spot (including a jump that regenerates the set); and a point
 * light's sphere drawn by the equal-area map. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "testutil.h"

#include "iir/method.h"
#include "iir/scene.h"
#include "iir/tri.h"

typedef iir_test_cornell fixture;
enum { W = 32, H = 24 };

/* Frame t of a path: small steps sideways, a still stretch (frames 6-8), a jump at frame 9. */
static iir_light light_at(const iir_light *base, int t)
{
    iir_light l = *base;
    float dx = t < 6 ? 0.04f * (float)t : t < 9 ? 0.2f : -0.6f;
    l.position = iir_add(base->position, iir_v3(dx, 0.f, 0.f));
    if (t >= 9) l.direction = iir_normalize(iir_v3(0.2f, 1.f, 0.1f)); /* now facing the ceiling */
    return l;
}

/* Shoelace area of cell k (counter-clockwise: positive). */
static double cell_area(const iir_domain *d, uint32_t k)
{
    double a = 0.0;
    uint32_t s = d->cell_start[k], e = d->cell_start[k + 1];
    for (uint32_t i = s; i < e; i++) {
        const float *p = d->cell_points[i], *q = d->cell_points[i + 1 < e ? i + 1 : s];
        a += (double)p[0] * q[1] - (double)q[0] * p[1];
    }
    return 0.5 * a;
}

/* Whether (x, y) lies inside the convex counter-clockwise cell k (with a little slack). */
static bool in_cell(const iir_domain *d, uint32_t k, float x, float y)
{
    uint32_t s = d->cell_start[k], e = d->cell_start[k + 1];
    for (uint32_t i = s; i < e; i++) {
        const float *p = d->cell_points[i], *q = d->cell_points[i + 1 < e ? i + 1 : s];
        double cross =
            ((double)q[0] - p[0]) * ((double)y - p[1]) - ((double)q[1] - p[1]) * ((double)x - p[0]);
        if (cross < -1e-6) return false;
    }
    return e > s;
}

/* Checks one frame's domain against the method's VPLs and stats. */
static void check_frame(iir_method *m, const iir_frame_stats *fs, const iir_domain *d, float R)
{
    uint32_t n = 0;
    const iir_vpl *v = iir_method_vpls(m, &n);
    assert_int_equal(d->num_sites, n);
    assert_int_equal(d->num_cells, n);
    uint32_t fresh = 0;
    double area = 0.0;
    for (uint32_t k = 0; k < n; k++) {
        const iir_domain_site *s = &d->sites[k];
        assert_int_equal(s->id, v[k].id);
        assert_int_equal((s->flags & IIR_SITE_NULL) != 0, v[k].null_sample);
        fresh += (s->flags & IIR_SITE_NEW) != 0;
        assert_float_equal(s->x, v[k].disk.x / R, 1e-5);
        assert_float_equal(s->y, v[k].disk.y / R, 1e-5);
        assert_true(s->x * s->x + s->y * s->y < 1.f);
        double a = cell_area(d, k);
        assert_true(a > 0.0);
        area += a;
        /* a site in the sliver between an arc and its chord (|s| > cos(pi / segments)) may be
         * outside the drawn polygon */
        float r = sqrtf(s->x * s->x + s->y * s->y);
        if (r < cosf((float)M_PI / IIR_TRI_ARC_SEGMENTS) && !in_cell(d, k, s->x, s->y))
            fail_msg("site %u (%g, %g) |s| = %g outside its cell of %u points", k, s->x, s->y,
                     (double)r, d->cell_start[k + 1] - d->cell_start[k]);
    }
    assert_int_equal(fresh, fs->vpl.inserted);
    /* 64 chords per turn (tri.h) lose 1 - sin(2 pi / 64) 64 / (2 pi) = 0.16% of the disk */
    assert_true(fabs(area - M_PI) < 0.005 * M_PI);
    assert_true(d->num_edges >= n - 1 && d->num_edges <= 3 * n);
    for (uint32_t e = 0; e < d->num_edges; e++) {
        assert_true(d->edges[e][0] < d->edges[e][1]);
        assert_true(d->edges[e][1] < n);
    }
    assert_int_equal(d->num_removed, fs->vpl.invalidated + fs->vpl.deleted);
}

/* While the light is still, every removed point is where a site of the previous frame was, and no
 * site of this frame is there. */
static void check_removed_still(const iir_domain *d, const iir_domain_site *prev, uint32_t nprev)
{
    for (uint32_t r = 0; r < d->num_removed; r++) {
        bool was = false, is = false;
        for (uint32_t k = 0; k < nprev; k++)
            was |= fabsf(prev[k].x - d->removed[r][0]) < 1e-6f &&
                   fabsf(prev[k].y - d->removed[r][1]) < 1e-6f;
        for (uint32_t k = 0; k < d->num_sites; k++)
            is |= d->sites[k].x == d->removed[r][0] && d->sites[k].y == d->removed[r][1];
        assert_true(was);
        assert_false(is);
    }
}

static void test_domain_follows_frames(void **state)
{
    fixture *f = *state;
    iir_params p = iir_params_default();
    iir_test_set(&p, "vpls", 128);
    iir_method *m = iir_test_method(f, "iir", &p);
    iir_image *img = iir_image_create(W, H);
    iir_frame_stats fs;
    iir_domain d;
    assert_false(iir_method_domain(m, &d)); /* nothing rendered */
    assert_int_equal(d.num_sites, 0);
    iir_domain_site *prev = malloc(sizeof(iir_domain_site) * 512);
    uint32_t nprev = 0, removed_total = 0, regenerations = 0;
    for (int t = 0; t < 11; t++) {
        iir_light l = light_at(&f->scene->lights[0], t);
        iir_view v = {&l, 1, f->scene->camera};
        iir_test_render(m, &v, img, &fs);
        assert_true(iir_method_domain(m, &d));
        check_frame(m, &fs, &d, iir_spot_radius(&l));
        if (t == 7 || t == 8) check_removed_still(&d, prev, nprev);
        if (t == 0) assert_int_equal(fs.vpl.inserted, d.num_sites); /* all new */
        removed_total += d.num_removed;
        regenerations += fs.vpl.regenerated;
        memcpy(prev, d.sites, sizeof(iir_domain_site) * d.num_sites);
        nprev = d.num_sites;
        iir_domain again;
        assert_true(iir_method_domain(m, &again)); /* cached: the same buffers */
        assert_ptr_equal(again.sites, d.sites);
    }
    print_message("%u removed over the path, %u regeneration(s)\n", removed_total, regenerations);
    assert_true(regenerations >= 1); /* the jump exercised the discard path */
    free(prev);
    iir_method_destroy(m);
    iir_image_destroy(img);
}

/* A point light's sphere, drawn by the equal-area map: every site and cell point lies in the unit
 * disk, no drawn edge crosses the disk (the map tears only at the rim), the drawn cells cover the
 * disk's area pi up to the few torn cells at the rim (the map keeps areas: a quarter of each cell's
 * solid angle), and a site near the centre lies in its own cell. With a spot beside it, the drawn
 * domain is the spot's disk (the light a user moves). */
static void test_sphere_domain_equal_area(void **state)
{
    fixture *f = *state;
    iir_params p = iir_params_default();
    iir_test_set(&p, "vpls", 256);
    iir_method *m = iir_test_method(f, "iir", &p);
    iir_image *img = iir_image_create(W, H);
    iir_frame_stats fs;
    iir_light bulb = {.type = IIR_LIGHT_POINT,
                      .name = "bulb",
                      .position = iir_v3(0.1f, 1.3f, 0.2f),
                      .intensity = iir_v3s(1.f)};
    iir_view v = {&bulb, 1, f->scene->camera};
    for (int t = 0; t < 3; t++) iir_test_render(m, &v, img, &fs);
    iir_domain d;
    assert_true(iir_method_domain(m, &d));
    assert_string_equal(d.map, "sphere (equal-area)");
    assert_int_equal(d.num_sites, fs.vpl.count);
    for (uint32_t k = 0; k < d.num_sites; k++)
        assert_true(d.sites[k].x * d.sites[k].x + d.sites[k].y * d.sites[k].y <= 1.f + 1e-5f);
    for (uint32_t e = 0; e < d.num_edges; e++) {
        const iir_domain_site *a = &d.sites[d.edges[e][0]], *b = &d.sites[d.edges[e][1]];
        assert_true(iir_sqr(a->x - b->x) + iir_sqr(a->y - b->y) <= 1.f);
    }
    assert_true(d.num_edges > 2 * d.num_sites); /* ~3n - 6, minus the torn ones */
    double area = 0.0;
    uint32_t drawn = 0, centred = 0;
    for (uint32_t k = 0; k < d.num_cells; k++) {
        if (d.cell_start[k + 1] == d.cell_start[k]) continue; /* torn at the rim */
        drawn++;
        area += fabs(cell_area(&d, k));
        float x = d.sites[k].x, y = d.sites[k].y;
        if (x * x + y * y < 0.25f && cell_area(&d, k) > 0.0)
            centred++, assert_true(in_cell(&d, k, x, y));
    }
    print_message("sphere: %u sites, %u cells drawn, their area %.4f of pi, %u near the centre\n",
                  d.num_sites, drawn, area / M_PI, centred);
    assert_true(drawn >= d.num_sites * 9 / 10);
    assert_true(area > 0.85 * M_PI && area < 1.02 * M_PI);
    assert_true(centred > 20);

    iir_light two[2] = {f->scene->lights[0], bulb};
    v = (iir_view){two, 2, f->scene->camera};
    iir_test_render(m, &v, img, &fs);
    assert_true(iir_method_domain(m, &d));
    assert_string_equal(d.map, "disk");
    iir_method_destroy(m);
    iir_image_destroy(img);
}

static void test_other_methods_have_none(void **state)
{
    fixture *f = *state;
    iir_params p = iir_params_default();
    const char *names[] = {"pt", "ir"};
    iir_image *img = iir_image_create(8, 8);
    for (int k = 0; k < 2; k++) {
        iir_method *m = iir_test_method(f, names[k], &p);
        iir_view v = {f->scene->lights, f->scene->num_lights, f->scene->camera};
        iir_frame_stats fs;
        iir_test_render(m, &v, img, &fs);
        iir_domain d;
        memset(&d, 0xff, sizeof d);
        assert_false(iir_method_domain(m, &d));
        assert_int_equal(d.num_sites, 0);
        assert_null(d.sites);
        iir_method_destroy(m);
    }
    iir_image_destroy(img);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_domain_follows_frames),
        cmocka_unit_test(test_sphere_domain_equal_area),
        cmocka_unit_test(test_other_methods_have_none),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

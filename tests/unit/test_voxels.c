/* test_voxels.c -- the coarse voxel grid and its 3DDA (voxels.h) against geometry worked out by
 * hand and against Embree: a plane inside one layer of cells marks exactly that layer; a segment
 * through an occupied cell is blocked and one beside it is not; a segment lying on the face
 * between an occupied and a free cell is blocked whichever side of the face floor() picks; and on
 * the Cornell box the grid agrees with Embree's occlusion on at least 95% of random segments. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>

#include <cmocka.h>

#include "testutil.h"

#include "iir/rng.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "iir/voxels.h"

enum { RES = 16 };

/* Two tiny triangles at the corners of [-2, 2]^3 fix the bounds; `extra` adds more OBJ lines. */
static void load_box(const char *extra, iir_scene **scene, iir_rt **rt)
{
    const char *dir = iir_test_tmpdir("voxels");
    char obj[4096];
    snprintf(obj, sizeof obj,
             "v -2 -2 -2\nv -1.99 -2 -2\nv -2 -1.99 -2\n"
             "v 2 2 2\nv 1.99 2 2\nv 2 1.99 2\n"
             "f 1 2 3\nf 4 5 6\n%s",
             extra);
    iir_test_write_file(dir, "box.obj", obj);
    iir_error err = {0};
    if (iir_test_load_obj(dir, "box", scene, rt, &err) != IIR_OK) fail_msg("%s", err.msg);
}

static iir_voxels *voxelize(const iir_scene *s, int res)
{
    iir_voxels *v = NULL;
    iir_error err = {0};
    if (iir_voxels_build(s, res, NULL, &v, &err) != IIR_OK) fail_msg("%s", err.msg);
    return v;
}

/* The world coordinate of cell boundary k along axis y (or any: the grid is cubic). */
static float boundary(const iir_voxels *v, int k, int axis)
{
    iir_vec3 o = iir_voxels_origin(v);
    float base = axis == 0 ? o.x : axis == 1 ? o.y : o.z;
    return base + (float)k * iir_voxels_cell_size(v);
}

static void test_plane_marks_one_layer(void **state)
{
    (void)state;
    iir_scene *s;
    iir_rt *rt;
    load_box("", &s, &rt);
    iir_voxels *v0 = voxelize(s, RES);
    /* a floor across the whole box, in the middle of layer 5 */
    float y = 0.5f * (boundary(v0, 5, 1) + boundary(v0, 6, 1));
    char extra[512];
    snprintf(extra, sizeof extra,
             "v -2 %.9g -2\nv 2 %.9g -2\nv 2 %.9g 2\nv -2 %.9g 2\nf 7 8 9\nf 7 9 10\n", (double)y,
             (double)y, (double)y, (double)y);
    iir_scene_destroy(s);
    iir_rt_destroy(rt);
    load_box(extra, &s, &rt);
    iir_voxels *v = voxelize(s, RES);
    int n[3];
    iir_voxels_dims(v, n);
    assert_int_equal(n[0], RES);
    assert_int_equal(n[1], RES);
    for (int x = 0; x < n[0]; x++)
        for (int z = 0; z < n[2]; z++) {
            assert_true(iir_voxels_cell(v, x, 5, z));
            assert_false(iir_voxels_cell(v, x, 4, z) && x > 0 && z > 0 && x < n[0] - 1);
        }
    /* the layer, plus the corner triangles' cells */
    assert_int_equal(iir_voxels_count(v), (uint64_t)(n[0] * n[2]) + 2);
    /* through the floor: blocked; above it, parallel: free */
    assert_true(
        iir_voxels_occluded(v, iir_v3(0.1f, 1.5f, 0.2f), iir_v3(0.3f, -1.5f, -0.1f), 0.f, 0.f));
    float above = boundary(v, 7, 1) + 0.3f * iir_voxels_cell_size(v);
    assert_false(
        iir_voxels_occluded(v, iir_v3(-1.5f, above, -1.5f), iir_v3(1.5f, above, 1.2f), 0.f, 0.f));
    /* skip: a segment from the floor up is free once the floor's cell is skipped */
    float h = iir_voxels_cell_size(v);
    assert_true(iir_voxels_occluded(v, iir_v3(0.f, y, 0.f), iir_v3(0.f, y + 1.f, 0.f), 0.f, 0.f));
    assert_false(iir_voxels_occluded(v, iir_v3(0.f, y, 0.f), iir_v3(0.f, y + 1.f, 0.f), h, 0.f));
    iir_voxels_destroy(v0);
    iir_voxels_destroy(v);
    iir_rt_destroy(rt);
    iir_scene_destroy(s);
}

/* One small triangle inside cell (8, 8, 8) only; segments along the faces of that cell. */
static void test_segment_on_a_cell_face(void **state)
{
    (void)state;
    iir_scene *s;
    iir_rt *rt;
    load_box("", &s, &rt);
    iir_voxels *v0 = voxelize(s, RES);
    float lo = boundary(v0, 8, 0), h = iir_voxels_cell_size(v0);
    float a = lo + 0.3f * h, b = lo + 0.7f * h, m = lo + 0.5f * h;
    char extra[512];
    snprintf(extra, sizeof extra, "v %.9g %.9g %.9g\nv %.9g %.9g %.9g\nv %.9g %.9g %.9g\nf 7 8 9\n",
             (double)a, (double)m, (double)a, (double)b, (double)m, (double)a, (double)m, (double)m,
             (double)b);
    iir_scene_destroy(s);
    iir_rt_destroy(rt);
    load_box(extra, &s, &rt);
    iir_voxels *v = voxelize(s, RES);
    assert_true(iir_voxels_cell(v, 8, 8, 8));
    assert_false(iir_voxels_cell(v, 8, 9, 8));
    assert_false(iir_voxels_cell(v, 8, 7, 8));
    float top = lo + h, bottom = lo; /* the cell's faces y = top and y = bottom */
    /* along x on the top face (floor() picks the free cell above: the cell below counts too) */
    assert_true(iir_voxels_occluded(v, iir_v3(-1.9f, top, m), iir_v3(1.9f, top, m), 0.f, 0.f));
    /* along x on the bottom face (floor() picks the occupied cell itself) */
    assert_true(
        iir_voxels_occluded(v, iir_v3(-1.9f, bottom, m), iir_v3(1.9f, bottom, m), 0.f, 0.f));
    /* one cell higher or lower along the same line: free */
    assert_false(
        iir_voxels_occluded(v, iir_v3(-1.9f, top + h, m), iir_v3(1.9f, top + h, m), 0.f, 0.f));
    assert_false(iir_voxels_occluded(v, iir_v3(-1.9f, bottom - h, m), iir_v3(1.9f, bottom - h, m),
                                     0.f, 0.f));
    /* along an edge of the cell (on two faces): blocked */
    assert_true(
        iir_voxels_occluded(v, iir_v3(-1.9f, top, lo + h), iir_v3(1.9f, top, lo + h), 0.f, 0.f));
    /* a diagonal through the cell's centre, and one that passes beside it */
    assert_true(
        iir_voxels_occluded(v, iir_v3(m - 1, m - 1, m - 1), iir_v3(m + 1, m + 1, m + 1), 0.f, 0.f));
    assert_false(iir_voxels_occluded(v, iir_v3(m - 1, m + 2 * h, m - 1),
                                     iir_v3(m + 1, m + 2 * h, m + 1), 0.f, 0.f));
    iir_voxels_destroy(v0);
    iir_voxels_destroy(v);
    iir_rt_destroy(rt);
    iir_scene_destroy(s);
}

static iir_vec3 uniform_in(const iir_scene *s, iir_rng *rng)
{
    iir_vec3 e = iir_sub(s->bounds_max, s->bounds_min);
    return iir_add(s->bounds_min, iir_v3(e.x * iir_rng_uniform(rng), e.y * iir_rng_uniform(rng),
                                         e.z * iir_rng_uniform(rng)));
}

/* A point on a random triangle (chosen by index, not area), and the triangle's normal. */
static iir_vec3 on_surface(const iir_scene *s, iir_rng *rng, iir_vec3 *n)
{
    uint32_t t = (uint32_t)(iir_rng_uniform(rng) * (float)s->num_triangles) % s->num_triangles;
    const uint32_t *i = &s->indices[3 * t];
    float u = iir_rng_uniform(rng), w = iir_rng_uniform(rng);
    if (u + w > 1.f) u = 1.f - u, w = 1.f - w;
    iir_vec3 p0 = s->positions[i[0]], p1 = s->positions[i[1]], p2 = s->positions[i[2]];
    *n = iir_normalize(iir_cross(iir_sub(p1, p0), iir_sub(p2, p0)));
    return iir_add(p0, iir_add(iir_scale(iir_sub(p1, p0), u), iir_scale(iir_sub(p2, p0), w)));
}

/* Share of n random segments on which the grid and Embree agree: from a point in the volume, or
 * (surfaces) from a point on a surface moved off it by `offset` towards the other end -- as a
 * shadow ray leaves its receiver -- to a point in the volume. */
static double agreement(const iir_test_cornell *f, const iir_voxels *v, bool surfaces, float offset,
                        int n)
{
    iir_rng rng = iir_rng_make(7, surfaces);
    int agree = 0;
    for (int i = 0; i < n; i++) {
        iir_vec3 a = uniform_in(f->scene, &rng), b = uniform_in(f->scene, &rng), nrm;
        if (surfaces) {
            a = on_surface(f->scene, &rng, &nrm);
            if (iir_dot(nrm, iir_sub(b, a)) < 0.f) nrm = iir_neg(nrm);
            a = iir_madd(a, nrm, offset);
        }
        iir_vec3 d = iir_sub(b, a);
        float len = iir_length(d);
        iir_ray ray = iir_make_ray(a, iir_scale(d, 1.f / len), 0.f, len);
        bool exact = iir_rt_occluded(f->rt, &ray, NULL, IIR_RAYS_BENCH);
        agree += exact == iir_voxels_occluded(v, a, b, 0.f, 0.f);
    }
    return (double)agree / n;
}

/* Random segments through the box's volume, and from points on its surfaces, moved a cell's
 * diagonal off them (out of the cells their own surface marks), to points in its volume (as shadow
 * rays from a receiver to a light sample). The grid errs within a cell of surfaces, so agreement
 * grows with the resolution. */
static void test_cornell_agrees_with_embree(void **state)
{
    const iir_test_cornell *f = *state;
    double volume[3], surface = 0;
    for (int i = 0, res = 32; i < 3; i++, res *= 2) {
        iir_voxels *v = voxelize(f->scene, res);
        volume[i] = agreement(f, v, false, 0.f, 20000);
        if (res == 128)
            surface = agreement(f, v, true, sqrtf(3.f) * iir_voxels_cell_size(v), 20000);
        print_message("cornell, %d cells: %llu marked; agreement with Embree %.2f%% (random "
                      "segments)\n",
                      res, (unsigned long long)iir_voxels_count(v), 100 * volume[i]);
        iir_voxels_destroy(v);
    }
    print_message("cornell, 128 cells: %.2f%% (surface to volume)\n", 100 * surface);
    assert_true(volume[2] >= 0.95);
    assert_true(volume[0] < volume[1] && volume[1] < volume[2]);
    assert_true(surface >= 0.95);
}

static void test_bad_resolution(void **state)
{
    const iir_test_cornell *f = *state;
    iir_voxels *v = (iir_voxels *)1;
    iir_error err = {0};
    assert_int_equal(iir_voxels_build(f->scene, 0, NULL, &v, &err), IIR_ERR_INVALID);
    assert_null(v);
    assert_int_equal(iir_voxels_build(f->scene, 5000, NULL, &v, &err), IIR_ERR_INVALID);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_plane_marks_one_layer),
        cmocka_unit_test(test_segment_on_a_cell_face),
        cmocka_unit_test(test_cornell_agrees_with_embree),
        cmocka_unit_test(test_bad_resolution),
    };
    return cmocka_run_group_tests(tests, iir_test_cornell_setup, iir_test_cornell_teardown);
}

/* testutil.h -- helpers shared by the unit tests: a scratch directory and small file writers.
 * Nothing here decides a test's outcome. */
#ifndef IIR_TESTUTIL_H
#define IIR_TESTUTIL_H

#include <stddef.h>
#include <stdio.h>

#include "iir/method.h"
#include "iir/render.h"
#include "iir/rt.h"
#include "iir/scene.h"
#include "iir/vecmath.h"

/* The end of a glTF's JSON (its buffers, views and accessors, closing the top object): a quad
 * [-1, 1] x {0} x [-1, 1] facing +y as accessor 0 (POSITION) and 1 (indices), for glTF test files
 * written as string literals. */
#define IIR_TEST_GLTF_QUAD_DATA                                                                    \
    " \"buffers\": [{\"byteLength\": 60, \"uri\": \"data:application/octet-stream;base64,"         \
    "AACAvwAAAAAAAIC/AACAPwAAAAAAAIC/AACAPwAAAAAAAIA/AACAvwAAAAAAAIA/AAACAAEAAAADAAIA\"}],\n"      \
    " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 48},\n"                 \
    "   {\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": 12}],\n"                               \
    " \"accessors\": [\n"                                                                          \
    "   {\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\",\n"          \
    "    \"min\": [-1, 0, -1], \"max\": [1, 0, 1]},\n"                                             \
    "   {\"bufferView\": 1, \"componentType\": 5123, \"count\": 6, \"type\": \"SCALAR\"}]}\n"

/* A fresh directory for this test executable (under $IIR_TEST_TMP or /tmp); returns its path. */
const char *iir_test_tmpdir(const char *test_name);

/* Writes text to dir/name, returns the full path in a static buffer (overwritten by the next call).
 */
const char *iir_test_write_file(const char *dir, const char *name, const char *text);

/* The glTF 2.0 specification's appendix-B BRDF (a mix of a dielectric and a metal BRDF) of a grey
 * material, in double, written out independently of bsdf.c; n = +y, wo and wi unit. */
double iir_test_gltf_brdf(double base, double metallic, double roughness, const double wo[3],
                          const double wi[3]);

/* Writes dir/name.mtl holding mtl_text and opens dir/name.obj for writing, its mtllib line written:
 * the caller writes the quads (iir_test_write_quad) and closes it. Fails the test on error. */
FILE *iir_test_open_obj(const char *dir, const char *name, const char *mtl_text);

/* Writes an OBJ quad centred at c spanned by +-a, +-b (normal cross(a, b)) with material mtl. */
void iir_test_write_quad(FILE *f, const char *mtl, iir_vec3 c, iir_vec3 a, iir_vec3 b);

/* Appends to OBJ file f a disc lamp in material mtl: the regular n-gon with corners
 * c + cos(2 pi k / n) a + sin(2 pi k / n) b, as a fan of n triangles about c, facing a x b. */
void iir_test_write_disc(FILE *f, const char *mtl, iir_vec3 c, iir_vec3 a, iir_vec3 b, int n);

/* The same n-gon as an area light's shape: corners at radius 1/2, angles 2 pi k / n, as a fan of
 * n triangles about the centre (n <= IIR_AREA_MAX_TRIANGLES). Its fraction of the rectangle is
 * n sin(2 pi / n) / 8. */
void iir_test_disc_shape(iir_area_shape *s, int n);

/* Loads dir/name.obj (with its sidecar, if any) and builds its ray tracer; on error both stay NULL
 * and err says why. */
iir_status iir_test_load_obj(const char *dir, const char *name, iir_scene **scene, iir_rt **rt,
                             iir_error *err);

/* cmocka group fixture: *state becomes an iir_test_cornell with the built-in box and its rays. */
typedef struct iir_test_cornell {
    iir_scene *scene;
    iir_rt *rt;
} iir_test_cornell;
int iir_test_cornell_setup(void **state);
int iir_test_cornell_teardown(void **state);

/* dir/name.obj (with its sidecar) and its rays as a pair like the fixture's; fails the running
 * cmocka test when it does not load. iir_test_unload frees both. */
iir_test_cornell iir_test_load(const char *dir, const char *name);
void iir_test_unload(iir_test_cornell *l);

/* Writes dir/corner.obj (and corner.mtl holding mtl_text): an open corner, nothing occluding --
 * the floor y = 0 over [-2, 2]^2, the back wall z = -2 and the left wall x = -2, 4 high -- of the
 * materials named floor, back and left. */
void iir_test_corner_obj(const char *dir, const char *mtl_text, const char *floor, const char *back,
                         const char *left);

/* An open corner (iir_test_corner_obj) whose floor is brass
 * (a metal of roughness 0.4; the walls grey and red, diffuse), lit by a spot aimed at the floor so
 * that its reflection lights the walls. */
iir_test_cornell iir_test_brass_corner(void);

/* Creates method `name` over the fixture's scene; fails the running cmocka test with the method's
 * error when it cannot. */
/* Sets parameter `name` of p (any method's), failing the test when it is refused. */
void iir_test_set(iir_params *p, const char *name, double v);
/* The value of `name` in p, else its (first declaring method's) default. */
double iir_test_get(const iir_params *p, const char *name);

iir_method *iir_test_method(const iir_test_cornell *f, const char *name, const iir_params *p);
/* iir_method_render that fails the running cmocka test with the method's error. */
void iir_test_render(iir_method *m, const iir_view *v, iir_image *img, iir_frame_stats *fs);

/* Whether pixel (x, y)'s 3x3 neighbourhood sees one plane: away from edges, where pt's pixel
 * jitter and the G-buffer's pixel centres legitimately differ (the methods-against-pt tests). */
bool iir_test_smooth_pixel(const iir_gbuffer *gb, int x, int y);

#endif

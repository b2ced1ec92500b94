/* scene_cornell.c -- the Cornell box built into the binary, as data tables (geometry and colours of
 * McGuire's CornellBox-Original, CC BY 3.0, see scenes/cornell_box/); not file loading. */
#include "scene_build.h"

#include <stdlib.h>

enum {
    FLOOR,
    CEILING,
    BACK_WALL,
    RIGHT_WALL,
    LEFT_WALL,
    SHORT_BOX,
    TALL_BOX,
    LIGHT,
    NUM_MATERIALS
};

/* Order and values of CornellBox-Original.mtl (Kd); the order is that of first use in the OBJ, so
 * loading scenes/cornell_box gives the same list. The ceiling panel keeps its white Kd but emits
 * nothing: the spot light below replaces it. */
static const struct {
    const char *name;
    float kd[3];
} materials[NUM_MATERIALS] = {
    [FLOOR] = {"floor", {0.725f, 0.71f, 0.68f}},
    [CEILING] = {"ceiling", {0.725f, 0.71f, 0.68f}},
    [BACK_WALL] = {"backWall", {0.725f, 0.71f, 0.68f}},
    [RIGHT_WALL] = {"rightWall", {0.14f, 0.45f, 0.091f}},
    [LEFT_WALL] = {"leftWall", {0.63f, 0.065f, 0.05f}},
    [SHORT_BOX] = {"shortBox", {0.725f, 0.71f, 0.68f}},
    [TALL_BOX] = {"tallBox", {0.725f, 0.71f, 0.68f}},
    [LIGHT] = {"light", {0.78f, 0.78f, 0.78f}},
};

/* The OBJ's quads in file order, vertices in its winding order (y up, open side towards +z).
 * Each splits into triangles (0, 1, 2) and (0, 2, 3). The OBJ's "bottom" faces of both boxes
 * index the vertices of another side face (short box: right face, tall box: front face), so they
 * duplicate that face; they are left out here, and the loader drops them from the OBJ as duplicate
 * triangles, so the built-in box and the shipped scenes/cornell_box are the same geometry. */
#define NUM_QUADS 16
/* clang-format off */
static const struct {
    int material;
    float v[4][3];
} quads[NUM_QUADS] = {
    {FLOOR, {{-1.01f, 0.00f, 0.99f}, {1.00f, 0.00f, 0.99f}, {1.00f, 0.00f, -1.04f}, {-0.99f, 0.00f, -1.04f}}},
    {CEILING, {{-1.02f, 1.99f, 0.99f}, {-1.02f, 1.99f, -1.04f}, {1.00f, 1.99f, -1.04f}, {1.00f, 1.99f, 0.99f}}},
    {BACK_WALL, {{-0.99f, 0.00f, -1.04f}, {1.00f, 0.00f, -1.04f}, {1.00f, 1.99f, -1.04f}, {-1.02f, 1.99f, -1.04f}}},
    {RIGHT_WALL, {{1.00f, 0.00f, -1.04f}, {1.00f, 0.00f, 0.99f}, {1.00f, 1.99f, 0.99f}, {1.00f, 1.99f, -1.04f}}},
    {LEFT_WALL, {{-1.01f, 0.00f, 0.99f}, {-0.99f, 0.00f, -1.04f}, {-1.02f, 1.99f, -1.04f}, {-1.02f, 1.99f, 0.99f}}},
    /* short box: top, left, front, right, back */
    {SHORT_BOX, {{0.53f, 0.60f, 0.75f}, {0.70f, 0.60f, 0.17f}, {0.13f, 0.60f, 0.00f}, {-0.05f, 0.60f, 0.57f}}},
    {SHORT_BOX, {{-0.05f, 0.00f, 0.57f}, {-0.05f, 0.60f, 0.57f}, {0.13f, 0.60f, 0.00f}, {0.13f, 0.00f, 0.00f}}},
    {SHORT_BOX, {{0.53f, 0.00f, 0.75f}, {0.53f, 0.60f, 0.75f}, {-0.05f, 0.60f, 0.57f}, {-0.05f, 0.00f, 0.57f}}},
    {SHORT_BOX, {{0.70f, 0.00f, 0.17f}, {0.70f, 0.60f, 0.17f}, {0.53f, 0.60f, 0.75f}, {0.53f, 0.00f, 0.75f}}},
    {SHORT_BOX, {{0.13f, 0.00f, 0.00f}, {0.13f, 0.60f, 0.00f}, {0.70f, 0.60f, 0.17f}, {0.70f, 0.00f, 0.17f}}},
    /* tall box: top, left, back, right, front */
    {TALL_BOX, {{-0.53f, 1.20f, 0.09f}, {0.04f, 1.20f, -0.09f}, {-0.14f, 1.20f, -0.67f}, {-0.71f, 1.20f, -0.49f}}},
    {TALL_BOX, {{-0.53f, 0.00f, 0.09f}, {-0.53f, 1.20f, 0.09f}, {-0.71f, 1.20f, -0.49f}, {-0.71f, 0.00f, -0.49f}}},
    {TALL_BOX, {{-0.71f, 0.00f, -0.49f}, {-0.71f, 1.20f, -0.49f}, {-0.14f, 1.20f, -0.67f}, {-0.14f, 0.00f, -0.67f}}},
    {TALL_BOX, {{-0.14f, 0.00f, -0.67f}, {-0.14f, 1.20f, -0.67f}, {0.04f, 1.20f, -0.09f}, {0.04f, 0.00f, -0.09f}}},
    {TALL_BOX, {{0.04f, 0.00f, -0.09f}, {0.04f, 1.20f, -0.09f}, {-0.53f, 1.20f, 0.09f}, {-0.53f, 0.00f, 0.09f}}},
    /* the ceiling panel (the original area light), 0.47 x 0.38, facing down */
    {LIGHT, {{-0.24f, 1.98f, 0.16f}, {-0.24f, 1.98f, -0.22f}, {0.23f, 1.98f, -0.22f}, {0.23f, 1.98f, 0.16f}}},
};
/* clang-format on */

/* The panel's emission (MTL Ke) and size, used only to give the spot the same flux. */
static const float PANEL_KE[3] = {17.f, 12.f, 4.f};
#define PANEL_AREA (0.47f * 0.38f)
#define SPOT_CONE_DEGREES 60.f

/* A Lambertian panel of radiance Ke and area A emits Phi = pi Ke A; a spot of half-angle alpha
 * with the cosine lobe emits Phi = pi I0 sin^2(alpha). Equal flux: I0 = Ke A / sin^2(alpha). */
static iir_light cornell_spot(void)
{
    float k = PANEL_AREA / iir_sqr(sinf(iir_radians(SPOT_CONE_DEGREES)));
    iir_light spot = {
        .type = IIR_LIGHT_SPOT,
        .name = "spot",
        .position = iir_v3(0.f, 1.9f, 0.f),
        .direction = iir_v3(0.f, -1.f, 0.f),
        .up = iir_v3(0.f, 0.f, -1.f), /* disk u axis towards the back wall */
        .cone_angle = iir_radians(SPOT_CONE_DEGREES),
        .smooth = 0.f,
        .intensity = iir_v3(PANEL_KE[0] * k, PANEL_KE[1] * k, PANEL_KE[2] * k),
    };
    return spot;
}

static iir_camera cornell_camera(void)
{
    iir_camera cam = {iir_v3(0.f, 1.f, 3.9f), iir_v3(0.f, 1.f, 0.f), iir_v3(0.f, 1.f, 0.f), 39.3f};
    return cam;
}

static iir_status add_materials(iir_scene_builder *b)
{
    for (int i = 0; i < NUM_MATERIALS; i++) {
        iir_material m = {.albedo =
                              iir_v3(materials[i].kd[0], materials[i].kd[1], materials[i].kd[2])};
        iir_scene_strcpy(m.name, sizeof m.name, materials[i].name);
        iir_status st = iir_builder_add_material(b, &m, NULL, NULL);
        if (st != IIR_OK) return st;
    }
    return IIR_OK;
}

static iir_status add_quads(iir_scene_builder *b)
{
    for (int q = 0; q < NUM_QUADS; q++) {
        uint32_t first = b->num_vertices;
        for (int k = 0; k < 4; k++) {
            const float *v = quads[q].v[k];
            iir_status st = iir_builder_add_vertex(b, iir_v3(v[0], v[1], v[2]), NULL, NULL);
            if (st != IIR_OK) return st;
        }
        uint32_t m = (uint32_t)quads[q].material;
        iir_status st = iir_builder_add_triangle(b, first, first + 1, first + 2, m, NULL);
        if (st == IIR_OK) st = iir_builder_add_triangle(b, first, first + 2, first + 3, m, NULL);
        if (st != IIR_OK) return st;
    }
    return IIR_OK;
}

iir_scene *iir_scene_create_cornell_box(void)
{
    iir_scene_builder b;
    iir_builder_init(&b, "cornell_box", "the built-in Cornell box");
    iir_light spot = cornell_spot();
    iir_camera cam = cornell_camera();
    iir_scene *scene = NULL;
    iir_status st = add_materials(&b);
    if (st == IIR_OK) st = add_quads(&b);
    if (st == IIR_OK) st = iir_builder_add_light(&b, &spot, NULL);
    if (st == IIR_OK) {
        iir_builder_set_camera(&b, &cam);
        iir_builder_set_camera_origin(&b, IIR_CAMERA_BUILTIN, 1.f);
        st = iir_builder_finish(&b, &scene, NULL);
    }
    iir_builder_free(&b);
    if (scene) scene->source[0] = '\0';
    return st == IIR_OK ? scene : NULL;
}

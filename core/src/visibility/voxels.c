/* voxels.c -- the scene's coarse voxel grid (voxels.h): building it with a separating-axis
 * triangle-box test per candidate cell, and 3DDA traversal of segments through it. One bit per
 * cell. */
#include "iir/voxels.h"
#include "surface.h"

#include <math.h>
#include <stdlib.h>

#include "iir/scene.h"

struct iir_voxels {
    int n[3];       /* cells along x, y, z */
    float h;        /* a cell's side */
    iir_vec3 o;     /* the grid's lower corner */
    uint64_t *bits; /* cell (x, y, z) is bit (z n1 + y) n0 + x */
    uint64_t count;
};

static inline uint64_t cell_index(const iir_voxels *v, int x, int y, int z)
{
    return ((uint64_t)z * (uint64_t)v->n[1] + (uint64_t)y) * (uint64_t)v->n[0] + (uint64_t)x;
}

static inline float axis(iir_vec3 p, int k)
{
    return k == 0 ? p.x : k == 1 ? p.y : p.z;
}

/* ---- building ---- */

/* Whether axis a separates the triangle (vertices relative to the box's centre) from the box of
 * half-side r0: their projections on a do not overlap. */
static bool separates(iir_vec3 a, iir_vec3 p0, iir_vec3 p1, iir_vec3 p2, float r0)
{
    float q0 = iir_dot(a, p0), q1 = iir_dot(a, p1), q2 = iir_dot(a, p2);
    float lo = fminf(q0, fminf(q1, q2)), hi = fmaxf(q0, fmaxf(q1, q2));
    float r = r0 * (fabsf(a.x) + fabsf(a.y) + fabsf(a.z));
    return lo > r || hi < -r;
}

/* Akenine-Moeller's triangle-box overlap by separating axes: the box's three face normals, the
 * triangle's normal, and the nine cross products of the box's axes with the triangle's edges. */
static bool triangle_meets_box(iir_vec3 c, float r0, const iir_vec3 t[3])
{
    iir_vec3 p0 = iir_sub(t[0], c), p1 = iir_sub(t[1], c), p2 = iir_sub(t[2], c);
    const iir_vec3 e[3] = {iir_sub(p1, p0), iir_sub(p2, p1), iir_sub(p0, p2)};
    const iir_vec3 box[3] = {iir_v3(1, 0, 0), iir_v3(0, 1, 0), iir_v3(0, 0, 1)};
    for (int k = 0; k < 3; k++)
        if (separates(box[k], p0, p1, p2, r0)) return false;
    if (separates(iir_cross(e[0], e[1]), p0, p1, p2, r0)) return false;
    for (int i = 0; i < 3; i++)
        for (int k = 0; k < 3; k++)
            if (separates(iir_cross(box[k], e[i]), p0, p1, p2, r0)) return false;
    return true;
}

static int cell_of(const iir_voxels *v, float p, int k)
{
    int c = (int)floorf((p - axis(v->o, k)) / v->h);
    return c < 0 ? 0 : c >= v->n[k] ? v->n[k] - 1 : c;
}

/* Marks every cell triangle t touches (cells of its bounds that it meets); false once stop says
 * stop (polled per slice of its bounds: at most res^2 cells). */
static bool mark_triangle(iir_voxels *v, const iir_vec3 t[3], const iir_stop *stop)
{
    int lo[3], hi[3];
    for (int k = 0; k < 3; k++) {
        float a = axis(t[0], k), b = axis(t[1], k), c = axis(t[2], k);
        lo[k] = cell_of(v, fminf(a, fminf(b, c)), k);
        hi[k] = cell_of(v, fmaxf(a, fmaxf(b, c)), k);
    }
    const float r0 = 0.5f * v->h * (1.f + 1e-4f); /* a hair larger: conservative */
    const bool big =
        (int64_t)(hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1) > 4096;
    for (int z = lo[2]; z <= hi[2]; z++) {
        if (big && iir_stop_now(stop)) return false;
        for (int y = lo[1]; y <= hi[1]; y++)
            for (int x = lo[0]; x <= hi[0]; x++) {
                iir_vec3 c = iir_add(
                    v->o,
                    iir_scale(iir_v3((float)x + 0.5f, (float)y + 0.5f, (float)z + 0.5f), v->h));
                if (!triangle_meets_box(c, r0, t)) continue;
                uint64_t i = cell_index(v, x, y, z);
                __atomic_fetch_or(&v->bits[i >> 6], 1ull << (i & 63), __ATOMIC_RELAXED);
            }
    }
    return true;
}

/* A sample of a cut-out triangle: its cell and whether the material covers it there. */
typedef struct cell_sample {
    uint64_t cell;
    bool covered;
} cell_sample;

static int cmp_cell(const void *a, const void *b)
{
    uint64_t x = ((const cell_sample *)a)->cell, y = ((const cell_sample *)b)->cell;
    return x < y ? -1 : x > y;
}

/* A triangle with an alpha cut-out: a cell is solid where at least half of the triangle's part in
 * it is covered, judged from a barycentric grid of points a quarter cell apart (false on no
 * memory: then marked whole, conservatively). */
static bool mark_cutout(iir_voxels *v, const iir_scene *s, uint32_t prim, const iir_vec3 t[3])
{
    float edge = fmaxf(iir_length(iir_sub(t[1], t[0])),
                       fmaxf(iir_length(iir_sub(t[2], t[1])), iir_length(iir_sub(t[0], t[2]))));
    int m = (int)ceilf(4.f * edge / v->h);
    m = m < 1 ? 1 : m > 2048 ? 2048 : m;
    cell_sample *smp = malloc(sizeof *smp * (size_t)m * (size_t)(m + 1) / 2);
    if (!smp) return false;
    size_t n = 0;
    for (int i = 0; i < m; i++)
        for (int j = 0; i + j < m; j++) {
            float b1 = ((float)i + 1.f / 3.f) / (float)m, b2 = ((float)j + 1.f / 3.f) / (float)m;
            iir_vec3 p = iir_add(iir_scale(t[0], 1.f - b1 - b2),
                                 iir_add(iir_scale(t[1], b1), iir_scale(t[2], b2)));
            smp[n].cell = cell_index(v, cell_of(v, p.x, 0), cell_of(v, p.y, 1), cell_of(v, p.z, 2));
            smp[n++].covered = iir_surface_covers(s, prim, b1, b2);
        }
    qsort(smp, n, sizeof *smp, cmp_cell);
    for (size_t a = 0, b; a < n; a = b) {
        size_t covered = 0;
        for (b = a; b < n && smp[b].cell == smp[a].cell; b++) covered += smp[b].covered;
        uint64_t i = smp[a].cell;
        if (2 * covered >= b - a)
            __atomic_fetch_or(&v->bits[i >> 6], 1ull << (i & 63), __ATOMIC_RELAXED);
    }
    free(smp);
    return true;
}

/* Cells of side h covering the extent, res along its longest side. */
static void grid_dims(iir_vec3 extent, int res, int n[3], float *h)
{
    float longest = fmaxf(extent.x, fmaxf(extent.y, extent.z));
    *h = longest > 0.f ? longest / (float)res : 1.f;
    for (int k = 0; k < 3; k++) {
        int c = (int)ceilf(axis(extent, k) / *h);
        n[k] = c < 1 ? 1 : c > res ? res : c;
    }
}

uint64_t iir_voxels_memory(iir_vec3 extent, int res)
{
    int n[3];
    float h;
    grid_dims(extent, res, n, &h);
    uint64_t cells = (uint64_t)n[0] * (uint64_t)n[1] * (uint64_t)n[2];
    return (cells + 63) / 64 * 8 + sizeof(iir_voxels);
}

iir_status iir_voxels_build(const iir_scene *scene, int res, const iir_stop *stop, iir_voxels **out,
                            iir_error *err)
{
    *out = NULL;
    if (res < 1 || res > 1024)
        return iir_fail(err, IIR_ERR_INVALID, "voxel grid resolution %d is outside [1, 1024]", res);
    iir_voxels *v = calloc(1, sizeof *v);
    if (!v) return iir_fail(err, IIR_ERR_NOMEM, "out of memory for the voxel grid");
    iir_vec3 extent = iir_sub(scene->bounds_max, scene->bounds_min);
    float pad = 1e-4f * iir_length(extent) + 1e-6f; /* surfaces on the bounds lie inside */
    extent = iir_add(extent, iir_v3s(2.f * pad));
    v->o = iir_sub(scene->bounds_min, iir_v3s(pad));
    grid_dims(extent, res, v->n, &v->h);
    uint64_t cells = (uint64_t)v->n[0] * (uint64_t)v->n[1] * (uint64_t)v->n[2];
    v->bits = calloc((cells + 63) / 64, sizeof *v->bits);
    if (!v->bits) {
        free(v);
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for a voxel grid of %llu cells",
                        (unsigned long long)cells);
    }
    const long num = (long)scene->num_triangles;
    bool stopped = false;
#pragma omp parallel for schedule(dynamic, 64)
    for (long i = 0; i < num; i++) {
        bool quit;
#pragma omp atomic read
        quit = stopped;
        if (quit || (i % 256 == 0 && iir_stop_now(stop))) quit = true;
        const uint32_t *idx = &scene->indices[3 * i];
        const iir_vec3 t[3] = {scene->positions[idx[0]], scene->positions[idx[1]],
                               scene->positions[idx[2]]};
        bool cutout = !quit && scene->materials &&
                      iir_material_has_cutout(&scene->material_list[scene->materials[i]]);
        if (cutout && mark_cutout(v, scene, (uint32_t)i, t)) continue;
        if (quit || !mark_triangle(v, t, stop)) {
#pragma omp atomic write
            stopped = true;
        }
    }
    if (stopped) {
        iir_voxels_destroy(v);
        return iir_fail(err, IIR_ERR_INTERRUPTED, "voxel grid stopped");
    }
    for (uint64_t w = 0; w < (cells + 63) / 64; w++)
        v->count += (uint64_t)__builtin_popcountll(v->bits[w]);
    *out = v;
    return IIR_OK;
}

void iir_voxels_destroy(iir_voxels *v)
{
    if (!v) return;
    free(v->bits);
    free(v);
}

void iir_voxels_dims(const iir_voxels *v, int dims[3])
{
    for (int k = 0; k < 3; k++) dims[k] = v->n[k];
}

float iir_voxels_cell_size(const iir_voxels *v)
{
    return v->h;
}

iir_vec3 iir_voxels_origin(const iir_voxels *v)
{
    return v->o;
}

uint64_t iir_voxels_count(const iir_voxels *v)
{
    return v->count;
}

bool iir_voxels_cell(const iir_voxels *v, int x, int y, int z)
{
    if (x < 0 || y < 0 || z < 0 || x >= v->n[0] || y >= v->n[1] || z >= v->n[2]) return false;
    uint64_t i = cell_index(v, x, y, z);
    return (v->bits[i >> 6] >> (i & 63)) & 1u;
}

/* ---- 3DDA ---- */

/* The segment's parameter range [*t0, *t1] inside the grid's box (slabs); false if none. */
static bool clip_to_grid(const iir_voxels *v, iir_vec3 a, iir_vec3 d, float *t0, float *t1)
{
    for (int k = 0; k < 3; k++) {
        float lo = axis(v->o, k), hi = lo + (float)v->n[k] * v->h;
        float p = axis(a, k), q = axis(d, k);
        if (q == 0.f) {
            if (p < lo || p > hi) return false;
            continue;
        }
        float ta = (lo - p) / q, tb = (hi - p) / q;
        *t0 = fmaxf(*t0, fminf(ta, tb));
        *t1 = fminf(*t1, fmaxf(ta, tb));
    }
    return *t0 <= *t1;
}

/* Whether the cell, or -- along axes the segment runs parallel to, exactly on a cell boundary --
 * its neighbour below on that boundary, is marked: a segment along a face touches both cells. */
static bool marked_here(const iir_voxels *v, const int c[3], const int twin[3])
{
    for (int dz = 0; dz <= twin[2]; dz++)
        for (int dy = 0; dy <= twin[1]; dy++)
            for (int dx = 0; dx <= twin[0]; dx++)
                if (iir_voxels_cell(v, c[0] - dx, c[1] - dy, c[2] - dz)) return true;
    return false;
}

bool iir_voxels_marked_at(const iir_voxels *v, iir_vec3 p)
{
    iir_vec3 g = iir_scale(iir_sub(p, v->o), 1.f / v->h);
    return iir_voxels_cell(v, (int)floorf(g.x), (int)floorf(g.y), (int)floorf(g.z));
}

bool iir_voxels_occluded(const iir_voxels *v, iir_vec3 a, iir_vec3 b, float skip_a, float skip_b)
{
    iir_vec3 d = iir_sub(b, a);
    float len = iir_length(d);
    if (!(len > skip_a + skip_b)) return false;
    float t0 = skip_a / len, t1 = 1.f - skip_b / len;
    if (!clip_to_grid(v, a, d, &t0, &t1)) return false;
    int c[3], step[3], twin[3];
    float t_max[3], t_delta[3];
    for (int k = 0; k < 3; k++) {
        float p = axis(a, k) + t0 * axis(d, k), q = axis(d, k);
        float g = (p - axis(v->o, k)) / v->h; /* in cells */
        c[k] = (int)floorf(g);
        c[k] = c[k] < 0 ? 0 : c[k] >= v->n[k] ? v->n[k] - 1 : c[k];
        twin[k] = q == 0.f && g == floorf(g) && g > 0.f;
        step[k] = q > 0.f ? 1 : q < 0.f ? -1 : 0;
        float next = axis(v->o, k) + (float)(c[k] + (q > 0.f)) * v->h;
        t_max[k] = q != 0.f ? (next - axis(a, k)) / q : INFINITY;
        t_delta[k] = q != 0.f ? v->h / fabsf(q) : INFINITY;
    }
    for (;;) {
        if (marked_here(v, c, twin)) return true;
        int k = t_max[0] < t_max[1] ? (t_max[0] < t_max[2] ? 0 : 2) : (t_max[1] < t_max[2] ? 1 : 2);
        if (t_max[k] > t1) return false;
        c[k] += step[k];
        if (c[k] < 0 || c[k] >= v->n[k]) return false;
        t_max[k] += t_delta[k];
    }
}

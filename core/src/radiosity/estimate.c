/* estimate.c -- what a radiosity solution will hold on a given scene, from the scene's real counts
 * before anything large is allocated (radiosity.h, "the size"): the patches exactly (every triangle
 * is one patch at least), and the form factors' non-zeros from a few sampled hemicube rows. Also
 * the bytes a built solution holds, by the same formula, so the two can be compared. Not meshing
 * or form factors themselves (mesh.c, hemicube.c). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "iir/rng.h"
#include "radiosity.h"

/* Rows sampled, and the hemicube cells traced per row at most (a row with more cells is
 * subsampled and its distinct patches estimated, below): 64 x 4096 rays, tens of milliseconds. */
enum { EST_ROWS = 64, EST_CELLS = 4096 };

/* ---- the formula ---- */

/* Bytes of a solution with n patches, v display vertices, nnz form factors, T source triangles,
 * C hemicube cells and `threads` OpenMP threads: what it keeps (mesh, F, per-patch arrays) plus the
 * largest transient of its life (computing F: the rows before they are gathered, each thread's
 * row scratch; then progressive's transpose or Gauss's dense matrix, which come after F's
 * transient is freed). */
static uint64_t solution_bytes(uint64_t n, uint64_t v, uint64_t nnz, uint64_t T, uint64_t C,
                               rad_solver solver, int threads)
{
    uint64_t mesh = n * 68 + v * 12 + T * 8; /* 4 vec3, area, tri, 3 corners; vpos; tri maps */
    uint64_t ff = (n + 1) * 8 + nnz * 8;
    uint64_t arrays = n * 60 + v * 16; /* Ed, E, B, Bd, H; vH, vw */
    uint64_t compute = nnz * 8 + (uint64_t)threads * n * 8 + C * 16 + n * 20;
    uint64_t solve = solver == RAD_PROGRESSIVE ? nnz * 8 + (n + 1) * 16 + n * 12
                     : solver == RAD_GAUSS     ? n * n * 8 + n * 8
                                               : 0;
    return mesh + ff + arrays + (compute > solve ? compute : solve);
}

uint64_t rad_solution_bytes(const rad_solution *s, int threads)
{
    uint64_t C = rad_hemicube_cells(s->o.hemicube_res, NULL, NULL);
    return solution_bytes(s->mesh.num_patches, s->mesh.num_vertices, s->ff.nnz,
                          s->scene->num_triangles, C, s->o.solver, threads);
}

/* ---- sampled rows ---- */

typedef struct est_index {
    rad_mesh m;    /* tri_first and tri_n only: enough for rad_patch_of */
    uint64_t n, v; /* patches; grid points before welding (an upper bound of the vertices) */
} est_index;

/* The patch counts of the mesh rad_mesh_build would make; false when out of memory. */
static bool index_build(est_index *ix, const iir_scene *s, float target_area)
{
    memset(ix, 0, sizeof *ix);
    size_t T = (size_t)s->num_triangles + 1;
    ix->m.tri_first = malloc(T * sizeof *ix->m.tri_first);
    ix->m.tri_n = malloc(T * sizeof *ix->m.tri_n);
    if (!ix->m.tri_first || !ix->m.tri_n) return false;
    for (uint32_t t = 0; t < s->num_triangles; t++) {
        uint32_t nt = rad_patches_along(s->areas[t], target_area);
        ix->m.tri_n[t] = nt;
        ix->m.tri_first[t] = (uint32_t)(ix->n < UINT32_MAX ? ix->n : UINT32_MAX);
        ix->n += (uint64_t)nt * nt;
        ix->v += (uint64_t)(nt + 1) * (nt + 2) / 2;
    }
    return true;
}

static void index_free(est_index *ix)
{
    free(ix->m.tri_first), free(ix->m.tri_n);
}

/* The source triangle of patch p (binary search over tri_first). */
static uint32_t triangle_of(const est_index *ix, uint32_t T, uint64_t p)
{
    uint32_t lo = 0, hi = T - 1;
    while (lo < hi) {
        uint32_t mid = lo + (hi - lo + 1) / 2;
        if (ix->m.tri_first[mid] <= p)
            lo = mid;
        else
            hi = mid - 1;
    }
    return lo;
}

/* Patch p's centre (its sub-triangle's centroid) and normal. */
static void patch_frame(const est_index *ix, const iir_scene *s, uint64_t p, iir_vec3 *c,
                        iir_vec3 *nrm)
{
    uint32_t t = triangle_of(ix, s->num_triangles, p), n = ix->m.tri_n[t];
    int gi[3], gj[3];
    rad_subtri_grid(n, (uint32_t)(p - ix->m.tri_first[t]), gi, gj);
    const iir_vec3 *P = s->positions;
    const uint32_t *idx = &s->indices[3 * t];
    float u = (float)(gi[0] + gi[1] + gi[2]) / (3.f * (float)n);
    float w = (float)(gj[0] + gj[1] + gj[2]) / (3.f * (float)n);
    *c = iir_add(iir_scale(P[idx[0]], 1.f - u - w),
                 iir_add(iir_scale(P[idx[1]], u), iir_scale(P[idx[2]], w)));
    *nrm = s->normals[t];
}

/* The distinct patches a whole row of C cells would hit, from the distinct, once-hit (f1) and
 * twice-hit (f2) patches of `traced` of them: exact when every cell was traced; else Chao's
 * estimator d + f1^2 / (2 f2) (f1 (f1 - 1) / 2 without doubletons), at most C. */
static double row_distinct(uint32_t d, uint32_t f1, uint32_t f2, uint32_t traced, uint32_t C)
{
    if (traced >= C) return d;
    double more = f2 > 0 ? (double)f1 * f1 / (2.0 * f2) : (double)f1 * (f1 > 0 ? f1 - 1 : 0) / 2.0;
    return fmin((double)C, d + more);
}

/* The mean row length of F over EST_ROWS patches spread evenly over the mesh. */
static double mean_row(const est_index *ix, const iir_scene *s, const iir_rt *rt, int res)
{
    uint32_t C = rad_hemicube_cells(res, NULL, NULL);
    iir_vec3 *dir = malloc(C * sizeof *dir);
    uint32_t *hits = calloc(ix->n ? ix->n : 1, sizeof *hits), *touched = malloc(EST_CELLS * 4);
    double sum = 0;
    int rows = 0;
    if (dir && hits && touched) {
        rad_hemicube_cells(res, NULL, dir);
        for (int r = 0; r < EST_ROWS; r++, rows++) {
            iir_vec3 c, nrm;
            patch_frame(ix, s, (uint64_t)((r + 0.5) * (double)ix->n / EST_ROWS), &c, &nrm);
            uint32_t count = rad_ff_sample_row(&ix->m, s, rt, dir, C, EST_CELLS, c, nrm,
                                               iir_hash3(0x52ad, (uint64_t)r, 0), hits, touched);
            uint32_t f1 = 0, f2 = 0;
            for (uint32_t k = 0; k < count; k++) {
                f1 += hits[touched[k]] == 1, f2 += hits[touched[k]] == 2;
                hits[touched[k]] = 0;
            }
            sum += row_distinct(count, f1, f2, C < EST_CELLS ? C : EST_CELLS, C);
        }
    }
    free(dir), free(hits), free(touched);
    return rows ? sum / rows : (double)C;
}

uint64_t rad_solution_estimate(const rad_params *o, const iir_scene *scene, const iir_rt *rt,
                               int threads)
{
    est_index ix;
    uint64_t C = rad_hemicube_cells(o->hemicube_res, NULL, NULL), bytes = UINT64_MAX;
    if (index_build(&ix, scene, rad_target_area(scene, o->patch_area))) {
        double row = ix.n > 0 ? mean_row(&ix, scene, rt, o->hemicube_res) : 0.0;
        uint64_t nnz = (uint64_t)(row * (double)ix.n);
        bytes = solution_bytes(ix.n, ix.v, nnz, scene->num_triangles, C, o->solver, threads);
    }
    index_free(&ix);
    return bytes;
}

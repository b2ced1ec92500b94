/* radiosity.h -- the patch radiosity solver's parts (internal; the method is methods/radiosity.c):
 * the mesh of patches (mesh.c), hemicube form factors (hemicube.c), their on-disk cache
 * (ffcache.c) and the solvers (solve.c). Not the display: the method interpolates and shades.
 *
 * Units: B, E (W/m^2, radiosity and emitted exitance), H (irradiance, W/m^2), per RGB channel.
 * The radiosity equation, per patch i:  B_i = E_i + rho_i sum_j F_ij B_j. */
#ifndef IIR_RADIOSITY_H
#define IIR_RADIOSITY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "iir/rt.h"
#include "iir/scene.h"
#include "iir/status.h"
#include "iir/vecmath.h"

/* ---- the mesh (mesh.c) ----
 * Source triangle t is split regularly into n_t^2 sub-triangles (n_t = ceil(sqrt(A_t / a)), a the
 * target patch area), patches tri_first[t] .. tri_first[t] + n_t^2 - 1. A point of t with
 * Embree's barycentrics (u, v) (p = (1-u-v) p0 + u p1 + v p2) lies in patch rad_patch_of(). Grid
 * vertices are shared inside a triangle and welded across triangles where positions agree (to
 * 1e-5 of the scene's diagonal) and normals agree (cosine > 0.99): creases stay sharp. */
typedef struct rad_mesh {
    uint32_t num_patches;
    iir_vec3 *centre, *normal, *rho, *emit; /* emit: E = pi Le of the patch's material */
    float *area;
    uint32_t *tri;         /* source triangle of each patch */
    uint32_t (*vert)[3];   /* each patch's corners, into vpos */
    uint32_t num_vertices; /* welded display vertices */
    iir_vec3 *vpos;
    uint32_t *tri_first; /* per source triangle: its first patch */
    uint32_t *tri_n;     /* per source triangle: n_t */
} rad_mesh;

/* Meshes scene to patches of at most target_area (world units^2). IIR_ERR_NOMEM, or
 * IIR_ERR_UNSUPPORTED when it would exceed max_patches (the message names the count). */
iir_status rad_mesh_build(rad_mesh *m, const iir_scene *scene, float target_area,
                          uint32_t max_patches, iir_error *err);
void rad_mesh_free(rad_mesh *m);
/* The patch of source triangle t holding barycentrics (u, v). */
uint32_t rad_patch_of(const rad_mesh *m, uint32_t t, float u, float v);
/* The corners of patch k of source triangle t (k < n_t^2) as barycentric grid points (i, j), in
 * the order the patch's vert holds them. */
void rad_subtri_grid(uint32_t n, uint32_t k, int gi[3], int gj[3]);

/* ---- form factors (hemicube.c) ---- */
typedef struct rad_ff {
    uint32_t n; /* rows = patches */
    uint64_t nnz;
    uint64_t *row; /* n + 1 offsets into col, val */
    uint32_t *col; /* ascending within a row */
    float *val;    /* F_ij */
} rad_ff;

/* Progress: done of total patches; called from one thread at most every 10 %. */
typedef void (*rad_progress_fn)(void *ctx, uint32_t done, uint32_t total);

/* F_ij for every patch by the hemicube of res x res cells on top (sides res x res / 2), each cell
 * one ray from the patch centre through its centre (8-wide packets; OpenMP over patches); the
 * delta form factors are normalised to sum to 1 over the hemicube. Hits on a patch's back face
 * count for nothing. IIR_ERR_NOMEM. */
iir_status rad_ff_compute(rad_ff *ff, const rad_mesh *m, const iir_scene *scene, const iir_rt *rt,
                          int res, rad_progress_fn progress, void *ctx, iir_error *err);
void rad_ff_free(rad_ff *ff);
/* The delta form factor of every cell, in ray order (top face rows, then the four sides); writes
 * the cells' hemicube directions (frame-local, z along the normal) to dir when not NULL. Returns
 * the number of cells, 3 res^2 (res even). */
uint32_t rad_hemicube_cells(int res, float *dF, iir_vec3 *dir);

/* ---- the cache (ffcache.c) ----
 * One file per key, `<dir>/<key as 16 hex digits>.ff`: a 64-byte header (magic "IIRRADFF",
 * format version, key, n, nnz, FNV-1a 64 of the payload), then row[n + 1] (u64), col[nnz] (u32),
 * val[nnz] (f32), little-endian as the machine writes them. Written to a temporary file and
 * renamed, so a reader sees a whole file or none. */

/* The key: FNV-1a 64 over the triangles' positions (in index order), the meshing's target area,
 * the hemicube resolution and the format version. */
uint64_t rad_ff_key(const iir_scene *scene, float target_area, int res);
/* The cache directory: $IIR_CACHE_DIR, else $XDG_CACHE_HOME/iir/radiosity, else
 * $HOME/.cache/iir/radiosity; "" (caching off) when IIR_CACHE_DIR is set empty or no home is
 * known. Writes at most size bytes. */
void rad_cache_dir(char *out, size_t size);
/* Loads the file of `key` from dir into ff (which must be empty): true on success; false when
 * there is none or it is corrupt (bad header, size, offsets, column or checksum -- *why says which,
 * may be NULL), leaving ff empty. */
bool rad_ff_load(rad_ff *ff, const char *dir, uint64_t key, uint32_t n, const char **why);
/* Saves ff under key into dir (creating it): false with a message in err when it cannot. */
bool rad_ff_save(const rad_ff *ff, const char *dir, uint64_t key, iir_error *err);

/* ---- solvers (solve.c) ---- */
typedef enum rad_solver { RAD_GAUSS, RAD_GAUSS_SEIDEL, RAD_PROGRESSIVE } rad_solver;

/* Gauss elimination with partial pivoting on the dense (I - rho F) B = E, per channel, in double.
 * IIR_ERR_NOMEM (n^2 doubles), IIR_ERR_INVALID for a singular system. */
iir_status rad_solve_gauss(const rad_ff *ff, const iir_vec3 *rho, const iir_vec3 *E, iir_vec3 *B,
                           iir_error *err);
/* Gauss-Seidel sweeps from B = E (warm: from B as given, e.g. the last frame's solution) until
 * the largest change of a sweep is below tol times the largest B (or max_iter sweeps); the sweeps
 * done. */
int rad_solve_gauss_seidel(const rad_ff *ff, const iir_vec3 *rho, const iir_vec3 *E, iir_vec3 *B,
                           int max_iter, float tol, bool warm);

/* Progressive refinement (Cohen et al. 1988): state between batches of shots. */
typedef struct rad_progressive {
    iir_vec3 *dB;     /* unshot radiosity */
    rad_ff Ft;        /* F transposed: row i holds F_ji of every j that sees i (built once) */
    float rho_avg[3]; /* area-weighted mean reflectance, for the ambient term */
    double area_total;
    double emitted; /* sum E_i A_i (luminance), the scale of the tolerance */
    uint64_t shots;
} rad_progressive;
/* Starts over with B = unshot = E; keeps (or first builds) the transpose of ff. False when out of
 * memory. */
bool rad_progressive_init(rad_progressive *p, const rad_mesh *m, const rad_ff *ff,
                          const iir_vec3 *E, iir_vec3 *B);
void rad_progressive_free(rad_progressive *p);
/* Shoots up to `shots` times the patch i with the most unshot power: dB_j += rho_j F_ji dB_i for
 * every j (F_ji read from the transpose, not F_ij A_i / A_j: the hemicube's F is not exactly
 * reciprocal, and with F_ji shooting is Southwell relaxation of the very system gauss and
 * gauss_seidel solve, so all three agree). True once the unshot power (luminance) is below tol
 * times the emitted power. */
bool rad_progressive_shoot(rad_progressive *p, const rad_mesh *m, iir_vec3 *B, int shots,
                           float tol);
/* The ambient term (Cohen et al. 1988): rho_avg-weighted unshot radiosity, added as rho_i * it. */
iir_vec3 rad_progressive_ambient(const rad_progressive *p, const rad_mesh *m);

#endif

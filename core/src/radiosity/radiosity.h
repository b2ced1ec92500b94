/* radiosity.h -- the patch radiosity solver's parts (internal; the methods are methods/radiosity.c
 * and methods/hybrid.c): the mesh of patches (mesh.c), hemicube form factors (hemicube.c), their
 * on-disk cache (ffcache.c), the solvers (solve.c) and the solution a method keeps and looks up
 * (solution.c). Not the pixels: the methods shade.
 *
 * Units: B, E (W/m^2, radiosity and emitted exitance), H (irradiance, W/m^2), per RGB channel.
 * The radiosity equation, per patch i:  B_i = E_i + rho_i sum_j F_ij B_j. */
#ifndef IIR_RADIOSITY_H
#define IIR_RADIOSITY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

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

/* The patches along each edge of a triangle of this area: n, for n^2 patches (at least 1). */
uint32_t rad_patches_along(float area, float target_area);
/* Meshes scene to patches of at most target_area (world units^2). IIR_ERR_NOMEM, or
 * IIR_ERR_UNSUPPORTED when it would exceed max_patches (the message names the count, or says that
 * the scene has more triangles than that); a failed build leaves m empty. */
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
 * count for nothing. stop (may be NULL) is polled every few thousand rays: IIR_ERR_INTERRUPTED
 * with ff empty. IIR_ERR_NOMEM. */
iir_status rad_ff_compute(rad_ff *ff, const rad_mesh *m, const iir_scene *scene, const iir_rt *rt,
                          int res, const iir_stop *stop, rad_progress_fn progress, void *ctx,
                          iir_error *err);
void rad_ff_free(rad_ff *ff);
/* Traces the cells of one hemicube row from centre (facing normal) for an estimate: all `cells`
 * directions dir (rad_hemicube_cells' order) when there are at most max_cells, else max_cells of
 * them drawn uniformly (with repetition, from seed). hits[j] counts the cells that reached patch
 * j (the caller zeroes it after); touched gets the distinct patches. Returns how many. */
uint32_t rad_ff_sample_row(const rad_mesh *m, const iir_scene *scene, const iir_rt *rt,
                           const iir_vec3 *dir, uint32_t cells, uint32_t max_cells, iir_vec3 centre,
                           iir_vec3 normal, uint64_t seed, uint32_t *hits, uint32_t *touched);
/* The delta form factor of every cell, in ray order (top face rows, then the four sides); writes
 * the cells' hemicube directions (frame-local, z along the normal) to dir when not NULL. Returns
 * the number of cells, 3 res^2 (res even). */
uint32_t rad_hemicube_cells(int res, float *dF, iir_vec3 *dir);

/* ---- the cache (ffcache.c) ----
 * One file per key, `<dir>/<key as 16 hex digits>.ff`: a 64-byte header (magic "IIRRADFF",
 * format version, key, n, nnz, FNV-1a 64 of the payload), then row[n + 1] (u64), col[nnz] (u32),
 * val[nnz] (f32), little-endian as the machine writes them. Written to a temporary file of the
 * directory made by mkstemp (`.<key>.ff.XXXXXX`: created exclusively, so nothing placed there,
 * a symlink included, is ever written through) and renamed, so a reader sees a whole file or
 * none. Files are opened without following links or blocking and only regular files are read.
 *
 * The folder is bounded: after each save the least recently used *.ff files (oldest
 * modification time; a load touches it) are deleted until the folder's *.ff files take at most
 * max_bytes, never the file just written. The configuration comes from the caller (rad_cache);
 * rad_cache_config() reads the process's: $IIR_CACHE_DIR and $IIR_CACHE_MAX. */

/* The key: FNV-1a 64 over the triangles' positions (in index order), the meshing's target area,
 * the hemicube resolution and the format version. */
uint64_t rad_ff_key(const iir_scene *scene, float target_area, int res);
/* The cache directory: $IIR_CACHE_DIR, else $XDG_CACHE_HOME/iir/radiosity, else
 * $HOME/.cache/iir/radiosity; "" (caching off) when IIR_CACHE_DIR is set empty or no home is
 * known. Writes at most size bytes. */
void rad_cache_dir(char *out, size_t size);

#define RAD_CACHE_MAX_DEFAULT (512ull << 20) /* bytes of *.ff files a folder keeps */

/* Where the cache lives and how large it may grow (its *.ff files' bytes). */
typedef struct rad_cache {
    char dir[1024]; /* "" = caching off */
    uint64_t max_bytes;
} rad_cache;
/* The process's cache: rad_cache_dir(), and $IIR_CACHE_MAX (bytes, or with K, M, G, T; what
 * `iird ... --cache-max` sets) else RAD_CACHE_MAX_DEFAULT (also for an unreadable value). */
void rad_cache_config(rad_cache *c);
/* Parses a size as $IIR_CACHE_MAX holds it: false (out unchanged) unless a positive number of
 * bytes with an optional K, M, G or T. */
bool rad_cache_parse_size(const char *text, uint64_t *out);

/* What a folder holds: its regular <16 hex>.ff files, and what a trim removed. */
typedef struct rad_cache_usage {
    uint64_t bytes, files;
    uint64_t evicted, evicted_bytes; /* by the trim that filled this in */
} rad_cache_usage;
/* Counts dir's cache files into u (zeroed first); false when dir cannot be read (u zero). */
bool rad_cache_scan(const char *dir, rad_cache_usage *u);
/* Deletes the least recently used cache files of c->dir until the rest take at most
 * c->max_bytes, never the file of `keep`; u (may be NULL) gets what is left and what went.
 * Also removes temporaries of writers that died (older than an hour). False when the folder
 * cannot be read. */
bool rad_cache_trim(const rad_cache *c, uint64_t keep, rad_cache_usage *u);

/* Loads the file of `key` from dir into ff (which must be empty): true on success, and the file's
 * modification time becomes now (its recency); false when there is none or it is unusable (not a
 * regular file; bad header, size, offsets, column or checksum -- *why says which, may be NULL),
 * leaving ff empty. Never blocks on a FIFO or follows a symlink. */
bool rad_ff_load(rad_ff *ff, const char *dir, uint64_t key, uint32_t n, const char **why);
/* The reader behind rad_ff_load: f holds size bytes of a cache file. NULL on success, else why
 * (ff then empty). Allocates no more than size allows. */
const char *rad_ff_read(rad_ff *ff, FILE *f, uint64_t size, uint64_t key, uint32_t n);
/* Saves ff under key into c->dir (creating it), then trims the folder to c->max_bytes (u, may be
 * NULL, as rad_cache_trim's): false with a message in err when it cannot write. */
bool rad_ff_store(const rad_ff *ff, const rad_cache *c, uint64_t key, rad_cache_usage *u,
                  iir_error *err);
/* rad_ff_store into dir with the process's cap (rad_cache_config's max_bytes). */
bool rad_ff_save(const rad_ff *ff, const char *dir, uint64_t key, iir_error *err);

/* ---- solvers (solve.c) ---- */
typedef enum rad_solver { RAD_GAUSS, RAD_GAUSS_SEIDEL, RAD_PROGRESSIVE } rad_solver;

/* Gauss elimination with partial pivoting on the dense (I - rho F) B = E, per channel, in double.
 * IIR_ERR_NOMEM (n^2 doubles), IIR_ERR_INVALID for a singular system, IIR_ERR_INTERRUPTED once
 * stop (may be NULL; polled per pivot) says stop. */
iir_status rad_solve_gauss(const rad_ff *ff, const iir_vec3 *rho, const iir_vec3 *E, iir_vec3 *B,
                           const iir_stop *stop, iir_error *err);
/* Gauss-Seidel sweeps from B = E (warm: from B as given, e.g. the last frame's solution) until
 * the largest change of a sweep is below tol times the largest B (or max_iter sweeps); the sweeps
 * done, or -1 once stop (may be NULL; polled every few hundred rows) says stop (B then holds a
 * partial sweep: a start as good as any for the next solve). */
int rad_solve_gauss_seidel(const rad_ff *ff, const iir_vec3 *rho, const iir_vec3 *E, iir_vec3 *B,
                           int max_iter, float tol, bool warm, const iir_stop *stop);

/* Progressive refinement (Cohen et al. 1988): state between batches of shots. */
typedef struct rad_progressive {
    iir_vec3 *dB;     /* unshot radiosity */
    rad_ff Ft;        /* F transposed: row i holds F_ji of every j that sees i (built once) */
    float rho_avg[3]; /* area-weighted mean reflectance, for the ambient term */
    double area_total;
    double emitted; /* sum E_i A_i (luminance), the scale of the tolerance */
    uint64_t shots;
} rad_progressive;
/* Starts over with B = unshot = E; keeps (or first builds, polling stop) the transpose of ff.
 * IIR_ERR_NOMEM, or IIR_ERR_INTERRUPTED (no transpose kept) once stop says stop. */
iir_status rad_progressive_init(rad_progressive *p, const rad_mesh *m, const rad_ff *ff,
                                const iir_vec3 *E, iir_vec3 *B, const iir_stop *stop);
void rad_progressive_free(rad_progressive *p);
/* Shoots up to `shots` times the patch i with the most unshot power: dB_j += rho_j F_ji dB_i for
 * every j (F_ji read from the transpose, not F_ij A_i / A_j: the hemicube's F is not exactly
 * reciprocal, and with F_ji shooting is Southwell relaxation of the very system gauss and
 * gauss_seidel solve, so all three agree). True once the unshot power (luminance) is below tol
 * times the emitted power. stop (may be NULL) is polled per shot: *stopped says it ended the batch
 * (every shot before it is whole). */
bool rad_progressive_shoot(rad_progressive *p, const rad_mesh *m, iir_vec3 *B, int shots, float tol,
                           const iir_stop *stop, bool *stopped);
/* The ambient term (Cohen et al. 1988): rho_avg-weighted unshot radiosity, added as rho_i * it. */
iir_vec3 rad_progressive_ambient(const rad_progressive *p, const rad_mesh *m);

/* ---- the parameters (table rad_param_table, methods/radiosity.c; radiosity and hybrid) ---- */
typedef enum rad_direct { RAD_DIRECT_PATCHES, RAD_DIRECT_PIXELS } rad_direct;

typedef struct rad_params {
    float patch_area; /* target patch area as a fraction of the bounding box's surface */
    int hemicube_res;
    rad_solver solver;
    int iterations;
    float tolerance;
    int shoot_batch;
    int light_samples;
    rad_direct direct;
} rad_params;
struct iir_param_table;
extern const struct iir_param_table rad_param_table;

enum { RAD_GAUSS_MAX = 3000, RAD_MAX_PATCHES = 200000, RAD_MAX_LIGHTS = 64 };

/* ---- the solution (solution.c) ----
 * The mesh, its form factors (from the cache or the hemicube) and B for the lights of the last
 * update. Per patch i:  B_i = E_i + rho_i sum_j F_ij B_j,  E_i = pi Le_i + rho_i Ed_i, Ed_i the
 * irradiance from the lights (the mean over light_samples points of the patch, one shadow ray
 * each). A moving light changes only Ed: an update re-shoots it and re-solves with the cached F.
 *
 * Lookup. rad_solution_gather() makes a per-vertex irradiance H (area-weighted over the patches
 * around a vertex), of which rad_solution_H() returns the Gouraud interpolation over a point's
 * patch; diffuse light leaving x is rho_x H(x) / pi. H_i is either everything a patch receives,
 * Ed_i + sum_j F_ij B_j, or (without direct) sum_j F_ij (B_j - pi Le_j), the light of one bounce
 * or more, for a caller that computes direct light and emission per pixel. While progressive
 * refinement has unshot power, B is shown with its ambient term. */
typedef struct rad_solution {
    const iir_scene *scene;
    const iir_rt *rt;
    rad_params o;
    uint64_t seed; /* the light samples' */
    rad_mesh mesh;
    rad_ff ff;
    iir_vec3 *Ed, *E, *B, *Bd, *H, *vH; /* per patch (Bd: B as displayed); vH per vertex */
    float *vw;                          /* per vertex: the area around it */
    rad_progressive prog;
    bool converged;    /* progressive: unshot power below tolerance; the others: solved */
    iir_light *lights; /* the lights of the last solve */
    uint32_t num_lights;
    bool solved;
    bool warm;     /* B holds a Gauss-Seidel solution to start the next solve from */
    iir_stop stop; /* polled by every step that takes time: form factors, shooting, solving */
} rad_solution;

/* Meshes the scene, refuses gauss above RAD_GAUSS_MAX patches, and loads (or computes, with
 * progress on stderr, and saves) the form factors. stop (may be NULL) is kept as the solution's
 * hook (rad_solution_set_stop changes it): IIR_ERR_INTERRUPTED once it says stop. On failure s is
 * freed. */
iir_status rad_solution_init(rad_solution *s, const iir_scene *scene, const iir_rt *rt,
                             const rad_params *o, uint64_t seed, const iir_stop *stop,
                             iir_error *err);
/* The hook the solution's updates, refinements and gathers poll (fn NULL: never stop). */
void rad_solution_set_stop(rad_solution *s, iir_stop_fn fn, void *ctx);
void rad_solution_free(rad_solution *s);
/* Takes live parameters (the next update re-solves); false (keeping the old ones) when they ask
 * gauss of too many patches. */
bool rad_solution_set_params(rad_solution *s, const rad_params *o, uint64_t seed);
/* Re-shoots direct light and re-solves (progressive: restarts and shoots one batch) when the
 * lights differ from the last update's; *ms = the time it took (0 when nothing changed).
 * IIR_ERR_INTERRUPTED when stopped: the next update solves again. */
iir_status rad_solution_update(rad_solution *s, const iir_light *lights, uint32_t num_lights,
                               iir_raystats *rays, double *ms, iir_error *err);
/* Progressive: shoots another batch (*shot true when it did; a stopped batch keeps its whole
 * shots and fails with IIR_ERR_INTERRUPTED); other solvers have nothing to do. */
iir_status rad_solution_refine(rad_solution *s, bool *shot, iir_error *err);
/* H per vertex from the current B, with or without the patches' direct light (see above);
 * IIR_ERR_INTERRUPTED (H unusable until the next gather) when stopped. */
iir_status rad_solution_gather(rad_solution *s, bool with_direct, iir_error *err);
/* H at Embree barycentrics (u, v) of scene triangle t, Gouraud over its patch's corners. */
iir_vec3 rad_solution_H(const rad_solution *s, uint32_t t, float u, float v);
/* Bytes a solution holds with o: form factors, patches, the solver's scratch -- from the
 * parameters alone (no scene): a quick first check. */
uint64_t rad_solution_memory(const rad_params *o);

/* ---- the size (estimate.c) ---- */
/* The target patch area: patch_area times the scene's bounding box's surface. */
float rad_target_area(const iir_scene *scene, float patch_area);
/* Bytes a solution with o will hold on this scene at its largest (threads: the OpenMP threads that
 * compute F), before anything large is built: the patch counts exactly, F's non-zeros from a few
 * hemicube rows traced (a few thousand rays each, subsampled and extrapolated on large hemicubes).
 * UINT64_MAX when out of memory. */
uint64_t rad_solution_estimate(const rad_params *o, const iir_scene *scene, const iir_rt *rt,
                               int threads);
/* What a built solution holds by the same formula, from its real counts. */
uint64_t rad_solution_bytes(const rad_solution *s, int threads);

#endif

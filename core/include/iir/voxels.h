/* voxels.h -- a coarse voxelization of the scene for cheap, approximate visibility (the
 * hierarchical image-space method's area-light shadows, Nichols, Shopf & Wyman): a grid of cubic
 * cells over the scene's bounds, a cell marked when a triangle touches it (a conservative
 * triangle-box overlap test), and segments tested against it by 3DDA traversal (Amanatides & Woo
 * 1987). Built once per scene; read-only afterwards, so any number of threads may query it. Not
 * exact visibility (rt.h): a segment is blocked by any marked cell it crosses, so thin gaps close
 * and surfaces grow by up to a cell. */
#ifndef IIR_VOXELS_H
#define IIR_VOXELS_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/status.h"
#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

struct iir_scene;

typedef struct iir_voxels iir_voxels;

/* Voxelizes the scene into cubic cells, `res` along the longest side of its bounds (res in
 * [1, 1024]; the other sides get as many as cover them). IIR_ERR_INVALID for res out of range,
 * IIR_ERR_NOMEM, IIR_ERR_INTERRUPTED (nothing kept) once stop (may be NULL) says stop. */
iir_status iir_voxels_build(const struct iir_scene *scene, int res, const iir_stop *stop,
                            iir_voxels **out, iir_error *err);
void iir_voxels_destroy(iir_voxels *v);

/* The grid: cells along x, y, z, the cell's side and the grid's lower corner. */
void iir_voxels_dims(const iir_voxels *v, int dims[3]);
float iir_voxels_cell_size(const iir_voxels *v);
iir_vec3 iir_voxels_origin(const iir_voxels *v);

/* Whether cell (x, y, z) is marked; false outside the grid. */
bool iir_voxels_cell(const iir_voxels *v, int x, int y, int z);
/* Marked cells. */
uint64_t iir_voxels_count(const iir_voxels *v);

/* Whether the segment from a to b crosses a marked cell, leaving out the first skip_a and the last
 * skip_b of its length (world units: the cells of the surfaces a segment joins are marked, so a
 * shadow test starts a cell's diagonal off its receiver, along the normal, and skips as much at a
 * light that lies on a surface). Parts outside the grid are free. */
bool iir_voxels_occluded(const iir_voxels *v, iir_vec3 a, iir_vec3 b, float skip_a, float skip_b);

/* Whether the cell holding world point p is marked (false outside the grid). */
bool iir_voxels_marked_at(const iir_voxels *v, iir_vec3 p);

/* Bytes the grid of `res` takes for a scene whose bounds have this extent (the memory estimate). */
uint64_t iir_voxels_memory(iir_vec3 extent, int res);

#ifdef __cplusplus
}
#endif
#endif

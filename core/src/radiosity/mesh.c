/* mesh.c -- meshing a scene into radiosity patches: each triangle split regularly into n^2
 * sub-triangles, grid vertices shared inside a triangle and welded across triangles that meet in
 * a plane (radiosity.h). Not form factors, not the display. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "radiosity.h"
#include "surface.h"

/* ---- the regular grid of one triangle ----
 * Grid point (i, j), i + j <= n, has barycentrics (u, v) = (i / n, j / n). Row j holds the "up"
 * sub-triangles (i, j) (i + 1, j) (i, j + 1) for i < n - j and the "down" ones
 * (i + 1, j) (i + 1, j + 1) (i, j + 1) for i < n - j - 1: up i is 2 i, down i is 2 i + 1, after
 * the 2 n j - j^2 sub-triangles of the rows below. */

static uint32_t row_start(uint32_t n, uint32_t j)
{
    return 2 * n * j - j * j;
}

void rad_subtri_grid(uint32_t n, uint32_t k, int gi[3], int gj[3])
{
    uint32_t j = 0;
    while (j + 1 < n && row_start(n, j + 1) <= k) j++;
    uint32_t r = k - row_start(n, j), i = r / 2;
    int I = (int)i, J = (int)j;
    if (r % 2 == 0) {
        gi[0] = I, gj[0] = J, gi[1] = I + 1, gj[1] = J, gi[2] = I, gj[2] = J + 1;
    } else {
        gi[0] = I + 1, gj[0] = J, gi[1] = I + 1, gj[1] = J + 1, gi[2] = I, gj[2] = J + 1;
    }
}

uint32_t rad_patch_of(const rad_mesh *m, uint32_t t, float u, float v)
{
    const int n = (int)m->tri_n[t];
    float a = u * (float)n, b = v * (float)n;
    int i = (int)floorf(a), j = (int)floorf(b);
    j = j < 0 ? 0 : j > n - 1 ? n - 1 : j;
    i = i < 0 ? 0 : i > n - 1 - j ? n - 1 - j : i;
    bool down = (a - (float)i) + (b - (float)j) > 1.f && i + j <= n - 2;
    return m->tri_first[t] + row_start((uint32_t)n, (uint32_t)j) + 2u * (uint32_t)i + down;
}

/* The grid point's index among the triangle's (n + 1)(n + 2) / 2. */
static uint32_t grid_index(uint32_t n, int i, int j)
{
    uint32_t J = (uint32_t)j;
    return J * (n + 1) - J * (J - 1) / 2 + (uint32_t)i;
}

static iir_vec3 grid_point(const iir_vec3 p[3], uint32_t n, int i, int j)
{
    float u = (float)i / (float)n, v = (float)j / (float)n;
    return iir_add(p[0],
                   iir_add(iir_scale(iir_sub(p[1], p[0]), u), iir_scale(iir_sub(p[2], p[0]), v)));
}

/* ---- welding ---- */

typedef struct weld_key {
    int64_t q[3];
    uint32_t raw;
} weld_key;

static int cmp_key(const void *a, const void *b)
{
    const weld_key *x = a, *y = b;
    for (int c = 0; c < 3; c++)
        if (x->q[c] != y->q[c]) return x->q[c] < y->q[c] ? -1 : 1;
    return x->raw < y->raw ? -1 : x->raw > y->raw;
}

/* Maps raw grid vertices (positions pos, normals nrm) to welded ones: writes remap and the welded
 * positions into m->vpos. False when out of memory. */
static bool weld(rad_mesh *m, const iir_vec3 *pos, const iir_vec3 *nrm, uint32_t raw, float cell,
                 uint32_t *remap)
{
    weld_key *k = malloc((size_t)raw * sizeof *k);
    m->vpos = malloc((size_t)raw * sizeof *m->vpos);
    if (!k || !m->vpos) return free(k), false;
    for (uint32_t r = 0; r < raw; r++) {
        k[r].q[0] = llroundf(pos[r].x / cell), k[r].q[1] = llroundf(pos[r].y / cell);
        k[r].q[2] = llroundf(pos[r].z / cell), k[r].raw = r;
    }
    qsort(k, raw, sizeof *k, cmp_key);
    uint32_t nv = 0;
    for (uint32_t g = 0; g < raw;) {
        uint32_t e = g;
        while (e < raw && !memcmp(k[e].q, k[g].q, sizeof k[g].q)) e++;
        for (uint32_t a = g; a < e; a++) { /* one welded vertex per normal in the group */
            uint32_t ra = k[a].raw, b = g;
            while (b < a && iir_dot(nrm[k[b].raw], nrm[ra]) <= 0.99f) b++;
            if (b < a) {
                remap[ra] = remap[k[b].raw];
            } else {
                remap[ra] = nv;
                m->vpos[nv++] = pos[ra];
            }
        }
        g = e;
    }
    m->num_vertices = nv;
    free(k);
    return true;
}

/* ---- the mesh ---- */

static bool alloc_patches(rad_mesh *m, uint32_t n)
{
    m->num_patches = n;
    m->centre = malloc(n * sizeof *m->centre), m->normal = malloc(n * sizeof *m->normal);
    m->rho = malloc(n * sizeof *m->rho), m->emit = malloc(n * sizeof *m->emit);
    m->area = malloc(n * sizeof *m->area), m->tri = malloc(n * sizeof *m->tri);
    m->vert = malloc(n * sizeof *m->vert);
    return m->centre && m->normal && m->rho && m->emit && m->area && m->tri && m->vert;
}

typedef iir_vec3 (*surface_value_fn)(const iir_scene *s, uint32_t prim, float u, float v);

/* The mean of a surface value (the diffuse albedo, the emission) over a patch, the sub-triangle of
 * grid corners gi, gj of triangle t's n-grid: at 10 points spread over it, or at its centre when
 * the value has no texture to vary by (textured false). */
static iir_vec3 patch_mean(const iir_scene *s, uint32_t t, uint32_t n, const int *gi, const int *gj,
                           bool textured, surface_value_fn value)
{
    if (!s->texcoords || !textured) return value(s, t, 1.f / 3.f, 1.f / 3.f);
    enum { K = 4 };
    iir_vec3 sum = iir_v3s(0.f);
    int count = 0;
    for (int a = 0; a < K; a++)
        for (int b = 0; a + b < K; b++) {
            /* barycentrics within the patch, then on the triangle's grid */
            float wa = ((float)a + 1.f / 3.f) / (float)K, wb = ((float)b + 1.f / 3.f) / (float)K;
            float wc = 1.f - wa - wb;
            float i = wa * (float)gi[0] + wb * (float)gi[1] + wc * (float)gi[2];
            float j = wa * (float)gj[0] + wb * (float)gj[1] + wc * (float)gj[2];
            sum = iir_add(sum, value(s, t, i / (float)n, j / (float)n));
            count++;
        }
    return iir_scale(sum, 1.f / (float)count);
}

/* Fills triangle t's patches and its raw grid vertices (from base), with their normals. */
static void mesh_triangle(rad_mesh *m, const iir_scene *s, uint32_t t, uint32_t base, iir_vec3 *pos,
                          iir_vec3 *nrm)
{
    const uint32_t n = m->tri_n[t], first = m->tri_first[t];
    const iir_vec3 p[3] = {s->positions[s->indices[3 * t]], s->positions[s->indices[3 * t + 1]],
                           s->positions[s->indices[3 * t + 2]]};
    const iir_material *mat = &s->material_list[s->materials[t]];
    for (uint32_t j = 0; j <= n; j++)
        for (uint32_t i = 0; i + j <= n; i++) {
            uint32_t g = base + grid_index(n, (int)i, (int)j);
            pos[g] = grid_point(p, n, (int)i, (int)j);
            nrm[g] = s->normals[t];
        }
    for (uint32_t k = 0; k < n * n; k++) {
        int gi[3], gj[3];
        rad_subtri_grid(n, k, gi, gj);
        iir_vec3 c = iir_v3s(0.f);
        for (int a = 0; a < 3; a++) {
            m->vert[first + k][a] = base + grid_index(n, gi[a], gj[a]);
            c = iir_add(c, grid_point(p, n, gi[a], gj[a]));
        }
        m->centre[first + k] = iir_scale(c, 1.f / 3.f);
        m->normal[first + k] = s->normals[t];
        m->area[first + k] = s->areas[t] / (float)(n * n);
        m->rho[first + k] =
            patch_mean(s, t, n, gi, gj, mat->base_tex.texture != 0, iir_surface_albedo_at);
        m->emit[first + k] = iir_scale(
            patch_mean(s, t, n, gi, gj, mat->emission_tex.texture != 0, iir_surface_emission_at),
            (float)M_PI);
        m->tri[first + k] = t;
    }
}

/* Frees what the mesh holds and passes st on: a failed build leaves m empty. */
static iir_status mesh_fail(rad_mesh *m, iir_status st)
{
    rad_mesh_free(m);
    return st;
}

uint32_t rad_patches_along(float area, float target_area)
{
    double r = sqrt((double)area / (double)target_area);
    return r < 1.0 ? 1u : r > 4096.0 ? 4096u : (uint32_t)ceil(r);
}

iir_status rad_mesh_build(rad_mesh *m, const iir_scene *s, float target_area, uint32_t max_patches,
                          iir_error *err)
{
    memset(m, 0, sizeof *m);
    m->tri_first = malloc(((size_t)s->num_triangles + 1) * sizeof *m->tri_first);
    m->tri_n = malloc(((size_t)s->num_triangles + 1) * sizeof *m->tri_n);
    if (!m->tri_first || !m->tri_n)
        return mesh_fail(m, iir_fail(err, IIR_ERR_NOMEM, "radiosity: out of memory"));
    uint64_t patches = 0, raw = 0;
    for (uint32_t t = 0; t < s->num_triangles; t++) {
        uint32_t n = rad_patches_along(s->areas[t], target_area);
        m->tri_n[t] = n;
        m->tri_first[t] = (uint32_t)(patches < UINT32_MAX ? patches : UINT32_MAX);
        patches += (uint64_t)n * n;
        raw += (uint64_t)(n + 1) * (n + 2) / 2;
    }
    if (s->num_triangles > max_patches) /* every triangle is a patch at least */
        return mesh_fail(m, iir_fail(err, IIR_ERR_UNSUPPORTED,
                                     "radiosity: the scene has %u triangles, each at least one "
                                     "patch; radiosity takes at most %u patches (triangles are "
                                     "not clustered into patches)",
                                     s->num_triangles, max_patches));
    if (patches > max_patches)
        return mesh_fail(m, iir_fail(err, IIR_ERR_UNSUPPORTED,
                                     "radiosity: patch_area gives %llu patches, more than %u; "
                                     "raise patch_area",
                                     (unsigned long long)patches, max_patches));
    iir_vec3 *pos = malloc(raw * sizeof *pos), *nrm = malloc(raw * sizeof *nrm);
    uint32_t *remap = malloc(raw * sizeof *remap);
    bool ok = pos && nrm && remap && alloc_patches(m, (uint32_t)patches);
    uint32_t base = 0;
    for (uint32_t t = 0; ok && t < s->num_triangles; t++) {
        mesh_triangle(m, s, t, base, pos, nrm);
        base += (m->tri_n[t] + 1) * (m->tri_n[t] + 2) / 2;
    }
    iir_vec3 e = iir_sub(s->bounds_max, s->bounds_min);
    float cell = fmaxf(1e-5f * iir_length(e), 1e-12f);
    ok = ok && weld(m, pos, nrm, (uint32_t)raw, cell, remap);
    for (uint32_t k = 0; ok && k < m->num_patches; k++)
        for (int a = 0; a < 3; a++) m->vert[k][a] = remap[m->vert[k][a]];
    free(pos), free(nrm), free(remap);
    if (!ok)
        return mesh_fail(m, iir_fail(err, IIR_ERR_NOMEM,
                                     "radiosity: out of memory meshing %llu patches",
                                     (unsigned long long)patches));
    return IIR_OK;
}

void rad_mesh_free(rad_mesh *m)
{
    free(m->centre), free(m->normal), free(m->rho), free(m->emit), free(m->area), free(m->tri);
    free(m->vert), free(m->vpos), free(m->tri_first), free(m->tri_n);
    memset(m, 0, sizeof *m);
}

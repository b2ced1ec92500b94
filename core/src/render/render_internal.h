/* render_internal.h -- the VPL renderer's private state and the phase functions that
 * render_gbuffer.c, render_direct.c, render_indirect.c and render_filter.c implement; internal
 * to libiircore. Not the public contract (render.h). */
#ifndef IIR_RENDER_INTERNAL_H
#define IIR_RENDER_INTERNAL_H

#include <string.h>

#include "iir/bsdf.h"
#include "iir/isa.h"
#include "iir/multires.h"
#include "iir/render.h"
#include "iir/scene.h"
#include "light_tree.h"

/* Tiles of the G-buffer, direct and filter phases. The indirect phase works in bands across the
 * frame instead, so that a subset has more pixels per band to share each VPL's map texels, and its
 * pieces of the VPLs' columns (gv_columns.h), read 16 side by side, are runs through memory long
 * enough for the prefetchers: 16 KB each at 1024x768 with 4x4 interleave, against 4 KB with the
 * 128-pixel square tiles before (the phase ~13% faster; 64-pixel tiles were ~20% slower again). */
enum { IIR_RENDER_TILE = 16, IIR_INDIRECT_BAND = 64, IIR_MAX_INTERLEAVE = 8, IIR_MAX_SUBSETS = 64 };
enum { IIR_MAX_AREA_SAMPLES = 4096 }; /* iir_indirect_params.area_samples */

/* The filter's horizontal pass at one pixel: weighted sum of the accepted taps and their weight. */
typedef struct iir_filter_row {
    iir_vec3 sum;
    float w;
} iir_filter_row;

/* A VPL as the pixel loop wants it: everything precomputed, flux already scaled for its subset. */
typedef struct iir_shade_vpl {
    iir_vec3 p, r, u, n; /* position and frame (n = normal) */
    iir_vec3 org;        /* p lifted by eps along n: the end of exact visibility rays */
    iir_vec3 power;      /* Phi_i / pi * N / |subset| */
    const iir_smap *smap;
    int generation; /* iir_vpl.generation: its light has generation + 1 bounces */
    bool glossy;    /* its lobe: toward w it sends f(wi, w) pi / albedo times a diffuse VPL's */
    iir_vec3 wi;    /* glossy: unit, toward where its light came from */
    iir_vec3 inv_albedo_pi; /* glossy: pi / albedo */
    iir_bsdf bsdf;          /* glossy: the lobe about n */
    float radius;           /* a virtual spherical light's (0: a point) */
} iir_shade_vpl;

struct iir_renderer {
    const iir_scene *scene;
    const iir_rt *rt;
    float eps;                 /* iir_rt_epsilon */
    float diag2;               /* squared bounding-box diagonal D^2 */
    iir_lightset *area_lights; /* the scene's emissive triangles; NULL when it has none */
    iir_lightset *comp_lights; /* this frame's lights and emissive triangles for the clamp
                                  compensation; NULL when it is off */

    iir_gbuffer gb;
    int specular_depth;   /* iir_renderer_follow_specular: 0 = gather at the first hit */
    bool gb_valid;        /* gb matches gb_camera, the frame size and specular_depth */
    iir_camera gb_camera; /* the camera gb was rendered with */
    iir_vec2 gb_shift;    /* gb's rays went through (x + 0.5, y + 0.5) + gb_shift, and
                             render_direct.c shoots them again at the area lights (not in the BVH):
                             (0, 0) for frames; a jittered pass (pass_gbuffer) sets it and
                             gb_camera */
    uint64_t gb_serial;   /* G-buffers rendered so far: multires keeps its hierarchy per one */
    iir_multires *mr;     /* shading = multires: the hierarchy (created on first use) */
    light_tree dtree;     /* shading = multires: the delta lights' direct light (render_direct.c) */
    const uint8_t *level; /* this frame's per-pixel multires level (multires.h; 0 = shaded at full
                             resolution), or NULL when every pixel is (shading = full) */
    iir_vec3 *raw;        /* per pixel: demodulated indirect (without rho / pi), unfiltered */
    iir_filter_row *rows; /* per pixel: the filter's horizontal pass */
    uint8_t *near_fine;   /* per filter tile (IIR_RENDER_TILE), multires: a level-0 pixel lies
                             within the filter's reach (render_filter.c) */
    uint64_t near_fine_gen; /* the multires generation near_fine was computed for; 0 = none */
    int near_fine_h;        /* and the filter's half-width */
    uint64_t bg_serial;     /* the G-buffer whose background pixels in raw are 0; 0 = none */
    uint32_t *fmask;       /* per pixel: which of the filter's taps are similar (render_filter.c) */
    uint64_t fmask_serial; /* the G-buffer (gb_serial) fmask was computed for; 0 = none */
    int fmask_h;           /* and the filter's half-width */

    /* Per frame: the VPLs in use, sorted by subset; subset k is vpl[start[k] .. start[k+1]). */
    iir_shade_vpl *vpl;
    uint32_t vpl_cap;
    uint32_t num_subsets; /* n^2 */
    uint32_t start[IIR_MAX_SUBSETS + 1];

    struct iir_gv_columns *gv;    /* the kept VPLs' columns of G V (gv_columns.h), full shading */
    struct iir_gv_columns *gv_mr; /* and over the multires hierarchy's items; NULL until used */

    iir_isa isa;      /* the shading kernels' instruction set (iir_renderer_set_isa) */
    iir_stop_fn stop; /* refinement passes poll it; NULL = never */
    void *stop_ctx;
};

/* ---- tiles: size x size pixels, row-major ---- */

typedef struct iir_tile {
    int x0, y0, x1, y1; /* [x0, x1) x [y0, y1) */
} iir_tile;

static inline int iir_tile_count(int width, int height, int size)
{
    return ((width + size - 1) / size) * ((height + size - 1) / size);
}

static inline iir_tile iir_tile_at(int width, int height, int size, int t)
{
    int tiles_x = (width + size - 1) / size;
    iir_tile tl;
    tl.x0 = (t % tiles_x) * size;
    tl.y0 = (t / tiles_x) * size;
    tl.x1 = tl.x0 + size < width ? tl.x0 + size : width;
    tl.y1 = tl.y0 + size < height ? tl.y0 + size : height;
    return tl;
}

/* The indirect phase's tiles: bands of IIR_INDIRECT_BAND rows across the frame, top to bottom. */
static inline int iir_indirect_tile_count(int width, int height)
{
    return width > 0 ? (height + IIR_INDIRECT_BAND - 1) / IIR_INDIRECT_BAND : 0;
}

static inline iir_tile iir_indirect_tile_at(int width, int height, int t)
{
    iir_tile tl = {0, t * IIR_INDIRECT_BAND, width, (t + 1) * IIR_INDIRECT_BAND};
    tl.y1 = tl.y1 < height ? tl.y1 : height;
    return tl;
}

/* ---- phases ---- */

/* What the shading phases of a frame or a pass work on, besides the renderer's G-buffer and VPL
 * subsets. */
typedef struct iir_shade_job {
    const iir_light *lights;
    uint32_t num_lights;
    const iir_indirect_params *p;
    uint32_t shift; /* added to every pixel's VPL subset (mod n^2) */
    uint64_t seed;  /* of the direct light's samples (and the compensation's) */
    iir_image *out;
} iir_shade_job;

/* Whether G-buffer pixel i reflects the VPLs' light by its full BSDF under `mode`
 * (render_indirect.c); other pixels reflect it as Lambertian of their albedo. */
static inline bool iir_gb_glossy(const iir_gbuffer *gb, size_t i, iir_receiver_bsdf mode)
{
    iir_vec3 m = gb->mr[i];
    if (mode == IIR_RECEIVER_DIFFUSE || m.y < 0.f) return false;
    return mode == IIR_RECEIVER_ALL || iir_bsdf_params_glossy(m.x, m.y);
}

/* The reflectance r->raw is demodulated by at G-buffer pixel i (its radiance is demod / pi * raw):
 * the diffuse albedo; for a pixel that reflects by its full BSDF (iir_gb_glossy)
 * iir_bsdf_reflectance, so that a metal's highlights keep its colour and texture through the
 * filter. */
static inline iir_vec3 iir_gb_demod(const iir_gbuffer *gb, size_t i, iir_receiver_bsdf mode)
{
    if (!iir_gb_glossy(gb, i, mode)) return gb->albedo[i];
    iir_vec3 m = gb->mr[i];
    return iir_bsdf_reflectance(gb->albedo[i], gb->base[i], m.x, m.z);
}

/* Pixel i's metallic-roughness BSDF (about its shading normal, which faces the viewer). */
static inline iir_bsdf iir_gb_bsdf(const iir_gbuffer *gb, size_t i)
{
    iir_vec3 m = gb->mr[i];
    return iir_bsdf_make_f0(gb->normal[i], gb->base[i], m.x, m.y, m.z);
}

/* pi / a per channel: what a glossy lobe's f is divided by to compare with a Lambertian one of
 * reflectance a (a kept off zero: iir_bsdf_reflectance). */
static inline iir_vec3 iir_pi_over(iir_vec3 a)
{
    return iir_v3(IIR_PI / a.x, IIR_PI / a.y, IIR_PI / a.z);
}

/* The receiver mode of this frame's gather: p's in full shading. Multires shades the glossy pixels
 * at full resolution (its hierarchy marks them) and its coarse texels as diffuse, so there `all`
 * is `glossy`: a rough dielectric may lie on a coarse texel. */
static inline iir_receiver_bsdf iir_render_receivers(const iir_renderer *r,
                                                     const iir_indirect_params *p)
{
    if (r->level && p->receiver_bsdf == IIR_RECEIVER_ALL) return IIR_RECEIVER_GLOSSY;
    return p->receiver_bsdf;
}

/* render_gbuffer.c. Resize keeps the contents only when the size is unchanged; on failure the
 * G-buffer is freed (width 0) and IIR_ERR_NOMEM returned. Render shoots pixel (x, y)'s camera ray
 * through (x + jitter.x, y + jitter.y); (0.5, 0.5) is the pixel centre of interactive frames. */
iir_status iir_gbuffer_resize(iir_gbuffer *gb, int width, int height, iir_error *err);
void iir_gbuffer_free(iir_gbuffer *gb);
/* Render polls stop per tile: false once it says stop (the G-buffer is then incomplete). */
bool iir_gbuffer_render(iir_gbuffer *gb, const iir_scene *scene, const iir_rt *rt,
                        const iir_camera_frame *cf, iir_vec2 jitter, int specular_depth,
                        const iir_stop *stop, iir_raystats *st);

/* A frame's side (iir_render_side) and how its run went: run once by iir_side_go, its vpls after
 * the direct light. `failed` is written atomically (the direct light's threads poll it to give up
 * their bands). */
typedef struct iir_side_run {
    const iir_render_side *side;
    iir_status status;
    bool failed;
    double ms; /* its run's wall time */
    iir_error err;
} iir_side_run;
void iir_side_go(iir_side_run *sr);
bool iir_side_failed(const iir_side_run *sr);

/* render_direct.c: out = emission + direct light (every pixel written). Each tile first polls
 * r->stop (when set) and is skipped once it said stop; returns true when that happened (out is then
 * incomplete). With a side (may be NULL), one thread runs it first while the others shade, and the
 * bands left once it failed are skipped (out is then incomplete; not counted as stopped); it runs
 * whatever happens. */
bool iir_render_direct(iir_renderer *r, const iir_shade_job *job, iir_side_run *side,
                       iir_raystats *st);

/* render_indirect.c: builds the per-subset VPL lists (checking the VPLs), a subset's flux scaled
 * by N / |subset| (frames) or by n^2 (refinement passes: exact_mean), then fills r->raw, pixel
 * (x, y) evaluating subset ((y mod n) n + (x mod n) + shift) mod n^2. */
iir_status iir_render_subsets(iir_renderer *r, const iir_vpl *vpls, uint32_t num_vpls,
                              const iir_indirect_params *p, bool exact_mean, iir_error *err);
/* With `stoppable`, each tile first polls r->stop and is skipped once it said stop; returns true
 * when tiles were skipped (r->raw is then incomplete). Adds the pixel-VPL pairs shaded to *evals,
 * and those of them whose G V a kept VPL's column held (gv_columns.h) to *reused. */
bool iir_render_indirect(iir_renderer *r, const iir_indirect_params *p, uint32_t shift,
                         bool stoppable, iir_raystats *st, uint64_t *evals, uint64_t *reused);
/* Multires (r->mr built for this frame's G-buffer): the VPL sum as multires.h's client -- level-0
 * pixels into r->raw as iir_render_indirect shades them (pixel (x, y) evaluating subset
 * (y mod n) n + (x mod n)), coarse texels by their level's lattice into r->mr (multires.h), whose
 * upsampled values the filter phase reads. Same stop rule and counts as iir_render_indirect. */
bool iir_render_indirect_coarse(iir_renderer *r, const iir_indirect_params *p, bool stoppable,
                                iir_raystats *st, uint64_t *evals, uint64_t *reused);

/* render_indirect.c, one point: the light of subset k's VPLs of generation <= max_generation at x
 * (normal n), as a pixel of that subset gets it (flux scaled, G clamped, the frame's visibility);
 * demodulated like r->raw. */
iir_vec3 iir_render_vpl_light_at(const iir_renderer *r, const iir_indirect_params *p, uint32_t k,
                                 iir_vec3 x, iir_vec3 n, int max_generation, iir_raystats *st);

/* render_compensate.c: adds to r->raw (full shading) what the clamp of the geometry term removed,
 * at the rate job->p->clamp_comp asks for. Same stop rule as iir_render_indirect (always
 * stoppable). */
bool iir_render_compensate(iir_renderer *r, const iir_shade_job *job, iir_raystats *st);

/* The filter's tap masks (render_filter.c): bit IIR_FILTER_MAX_H + d of a pixel's word says
 * whether the tap d pixels along its row is similar to it, bit IIR_FILTER_COLUMN + IIR_FILTER_MAX_H
 * + d the tap d pixels along its column. */
enum { IIR_FILTER_MAX_H = IIR_MAX_INTERLEAVE / 2, IIR_FILTER_COLUMN = 16 };

/* render_direct_avx2.c: direct light's lean 8x4 pixels at (x0, y0) -- a frame of points, spots and
 * suns alone (evals, prepared) without specular chains -- into out, the same sums as
 * render_direct.c's general block (the same image). */
typedef struct iir_direct_lean {
    const iir_gbuffer *gb;
    const iir_rt *rt;
    const iir_light_eval *evals;
    uint32_t num_lights;
    float eps; /* the renderer's: shadow rays' offset */
} iir_direct_lean;
void iir_direct_lean_block_avx2(const iir_direct_lean *c, int x0, int y0, iir_image *out,
                                iir_raystats *st);

/* render_filter_avx2.c: the filter's passes 8 pixels a step, the same sums as the
 * scalar passes in the same order (the same image). The row pass of row y lives in slot y mod
 * ring of planes: ring = height keeps every row, ring >= 2 h + 1 only those a column pass reads. */
typedef struct iir_filter_lanes {
    int width, height, n, h;
    float end_weight;     /* of the taps at +-h */
    const uint32_t *mask; /* per pixel: the taps' similarity */
    const int *live;      /* n x n: 1 for the subsets with VPLs */
    const iir_vec3 *raw;  /* the demodulated indirect light */
    float *planes;        /* 4 planes of width x ring: the row pass's sums (x, y, z) and weights */
    int ring;             /* rows a plane holds */
    const uint8_t *level; /* multires's per pixel (NULL: full shading): a coarse pixel (level > 0)
                             is a tap of every subset */
} iir_filter_lanes;
/* Whether one of n (<= 8) levels is 0: a level-0 pixel. */
static inline bool iir_filter_any_fine(const uint8_t *level, int n)
{
    if (n == 8) { /* a zero byte among 8 */
        uint64_t v;
        memcpy(&v, level, sizeof v);
        return ((v - 0x0101010101010101ull) & ~v & 0x8080808080808080ull) != 0;
    }
    for (int k = 0; k < n; k++)
        if (!level[k]) return true;
    return false;
}

/* The filter's compose at one pixel: L += k / pi * E (k: its demodulation, albedo for a
 * Lambertian pixel). The AVX2 compose makes the same products in the same order. */
static inline void iir_compose_add(iir_vec3 *L, iir_vec3 k, iir_vec3 E)
{
    *L = iir_add(*L, iir_mul(iir_scale(k, IIR_INV_PI), E));
}
/* The row pass of row y into its slot of planes (multires: only groups of 8 a column pass reads).
 */
void iir_filter_rows_avx2(const iir_filter_lanes *f, int y);
/* The column pass of row y's pixels [x0, x1) (rows y - h .. y + h passed, in their slots): E[x -
 * x0], the filtered light (0 where no tap counted). */
void iir_filter_columns_avx2(const iir_filter_lanes *f, int y, int x0, int x1, iir_vec3 *E);
/* Row y composed: out += albedo / pi * E (E: the column pass) at its pixels with geometry -- for
 * frames without metallic-roughness pixels or specular chains (render_filter.c's compose, the same
 * sums). */
void iir_filter_compose_avx2(const iir_filter_lanes *f, const iir_gbuffer *gb, int y,
                             iir_image *out);
/* The same over pixels [x0, x1) of row y with their E given (E[x - x0]). */
void iir_compose_span_avx2(const iir_gbuffer *gb, int y, int x0, int x1, const iir_vec3 *E,
                           iir_image *out);

/* render_filter.c: out += demod / pi * (filtered or raw) r->raw (iir_gb_demod: the glossy pixels',
 * which multires shades at full resolution); with r->level set only its level-0 pixels
 * are filtered (the others take their upsampled value, iir_multires_upsample_span, and count as
 * taps of every subset). */
void iir_render_filter(iir_renderer *r, const iir_indirect_params *p, iir_image *out);

#endif

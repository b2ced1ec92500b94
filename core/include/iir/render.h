/* render.h -- the VPL renderer shared by the instant radiosity methods (ir, iir): a camera
 * G-buffer, direct light from punctual and emissive lights, indirect light from a VPL set with
 * shadow-map or exact-ray visibility, interleaved sampling and its geometry-aware filter. Not how
 * VPLs are chosen (incremental.h, methods/) nor how their shadow maps are rendered (shadowmap.h).
 *
 * One frame, in order (each phase timed in iir_render_timing):
 *  1. G-buffer: one camera ray per pixel centre (no jitter), 8-wide packets over 4x2 pixel blocks,
 *     OpenMP over 16x16 tiles. Kept while the camera and the frame size do not change.
 *  2. Direct: emission seen directly, plus for every punctual light one shadow ray per pixel
 *     (spot cone and cosine lobe by iir_light_intensity), plus, for every area light and
 *     the emissive triangles, area_samples stratified samples per pixel (render_direct.c).
 *  3. Indirect: vpl.h's formula, with the geometry term clamped,
 *         L(x) = (rho_x / pi) sum_i (Phi_i / pi) min(G_i, clamp / D^2) V_i(x),
 *         G_i = max(0, n_i . w) max(0, -n_x . w) / d^2,
 *     D the scene's bounding-box diagonal, over the VPLs that are neither null samples nor of
 *     zero flux (N of them). Interleaved sampling, n = interleave: VPL i belongs to subset
 *     iir_vpl_subset_of(v, n^2), by key or id and never by array position, so a VPL keeps its
 * subset while the set around it changes; pixel (x, y) evaluates only subset (y mod n) n + (x mod
 * n), its flux scaled by N / |subset|. Each subset is thus a sub-sample of the VPLs carrying their
 * whole flux: an unbiased estimate of the same light when the VPLs are samples of the light's
 * paths, even for unbalanced subsets. (Scaling by n^2 instead would keep the mean over every n x n
 *     block exactly, but light unbalanced subsets unevenly.) For balanced subsets both agree. A
 *     subset with no VPL contributes nothing, and the filter does not count its pixels.
 *     A VPL kept from frame to frame under a still camera (iir's) keeps its min(G_i, ...) V_i
 *     at its subset's pixels in a column (render/gv_columns.h: AVX2, shadow maps; multires: at
 *     the hierarchy's samples), written in its first frame (its second while the set is new, none
 *     for a set made anew every frame); from then on the sum takes them from there and multiplies
 *     by this frame's flux -- the same floats in the same order, so the same frame to the bit.
 *  4. Filter (interleave > 1, filter on): a geometry-aware box over the neighbourhood that holds
 *     every subset with equal weight: offsets -h..h on each axis, h = floor(n / 2), weight 1 per
 *     axis except 1/2 at +-h when n is even (the two ends are the same subset and share one
 *     weight), so the window is centred. A neighbour counts if it is not background, its normal's
 *     cosine with the centre's is at least filter_normal and its camera depth is within
 *     filter_depth (relative) of the centre's. It runs separably, rows then columns (a tap counts
 *     if similar to the centre of its row pass, which is similar to the pixel), on the demodulated
 *     indirect light (without rho_x / pi), which is then multiplied by the pixel's own albedo, so
 *     colour and texture edges stay sharp.
 *  With shading = multires (multires.h) phase 3 evaluates the VPL sum on coarse levels of the
 *  G-buffer where it has no depth or normal discontinuity (texel (i, j) of every level evaluates
 *  subset (j mod n) n + (i mod n), and a per-level filter with phase 4's window gathers them), and
 *  upsamples; only pixels whose 2x2 block holds a discontinuity are shaded as above, and phase 4
 *  filters only them (the upsampled pixels count as taps carrying every subset). The
 *  discontinuity hierarchy is kept with the G-buffer.
 *
 * Threads: a renderer is used by one thread at a time; inside a frame every phase is an OpenMP
 * loop over tiles (16x16; 64x64 for the indirect phase) with per-thread ray counters summed once.
 * The scene, the rt and the VPLs (with their maps) are read-only during a frame. Memory: the
 * renderer owns the G-buffer and all scratch; it reallocates only when the frame size changes or
 * the VPL count exceeds every earlier frame's, so a steady sequence of frames allocates nothing. */
#ifndef IIR_RENDER_H
#define IIR_RENDER_H

#include <stdbool.h>
#include <stdint.h>

#include "iir/camera.h"
#include "iir/image.h"
#include "iir/isa.h"
#include "iir/light.h"
#include "iir/params.h"
#include "iir/rt.h"
#include "iir/rng.h"
#include "iir/status.h"
#include "iir/vecmath.h"
#include "iir/vpl.h"

#ifdef __cplusplus
extern "C" {
#endif

struct iir_scene;

/* Per pixel, row-major, top row first, width * height entries per array. */
typedef struct iir_gbuffer {
    int width, height;
    iir_vec3 *position; /* the hit point (from barycentrics); undefined for background */
    iir_vec3 *normal;   /* unit shading normal (vertex normals, normal map), facing the camera */
    iir_vec3 *albedo;   /* rho (the diffuse albedo, textured); 0 for background */
    iir_vec3 *base;     /* metal_rough: the base colour; else rho */
    iir_vec3 *mr;       /* metal_rough: (metallic, roughness, dielectric f0); (0, -1, 0) for a
                           Lambertian pixel */
    iir_vec3 *emission; /* Le seen directly (one-sided emitters); 0 for background */
    float *depth;       /* distance along the camera ray (a specular chain's: its length from the
                           camera to the surface); INFINITY = background */
    uint32_t *prim;     /* triangle index; IIR_NO_HIT = background */
    /* With specular chains (iir_renderer_follow_specular) a camera ray that meets a mirror, glass
       or a near-mirror metal is followed to the first rough surface, which the fields above
       describe (emission is seen through the chain): */
    iir_vec3 *through; /* what the chain passes on to the camera (1 for a direct hit) */
    float *camera_t;   /* distance along the camera ray to its first hit; INFINITY: none */
    iir_vec3 *wo;      /* unit, from the surface toward the viewer (the chain's last ray back) */
    bool any_chain;    /* some pixel's through is not 1: shading reads through only then */
    bool any_pbr;      /* some pixel is metallic-roughness (mr.y >= 0): its BSDF may be read */
    bool any_emission; /* some pixel's emission is not 0: direct light reads emission only then */
} iir_gbuffer;

typedef enum iir_visibility {
    IIR_VIS_SHADOWMAP, /* the VPLs' shadow maps (iir_smaps_build them first) */
    IIR_VIS_RAYS,      /* one exact occlusion ray per pixel-VPL pair (IIR_RAYS_VISIBILITY) */
    IIR_VIS_ISM        /* imperfect shadow maps (ism.h), which the method builds into the VPLs'
                          maps: the renderer reads them as IIR_VIS_SHADOWMAP's */
} iir_visibility;

typedef enum iir_shading {
    IIR_SHADING_FULL,    /* every pixel evaluates its interleaved subset (the default) */
    IIR_SHADING_MULTIRES /* multires.h: coarse levels where the G-buffer is smooth, pixels at
                            discontinuities as full does; the interleave pattern and its filter
                            apply per level */
} iir_shading;

/* Which pixels reflect the VPLs' light by their full BSDF toward the camera (render_indirect.c;
 * multires shades glossy pixels at full resolution, its coarse texels diffuse: `all` is `glossy`
 * there). */
typedef enum iir_receiver_bsdf {
    IIR_RECEIVER_GLOSSY, /* glossy pixels (iir_bsdf_params_glossy: metals, smoother dielectrics) */
    IIR_RECEIVER_ALL,    /* every metallic-roughness pixel (rough dielectrics' (1 - F) too) */
    IIR_RECEIVER_DIFFUSE /* none: the diffuse albedo c_diff / pi at every pixel */
} iir_receiver_bsdf;

/* What a VPL is (render_indirect.c): a point, or a virtual spherical light (Hasan, Krivanek,
 * Walter, Bala 2009) of radius the distance to its IIR_VSL_NEIGHBOURS-th nearest VPL, whose light
 * falls off as 1 / (d^2 + r^2) at every receiver and which a glossy receiver's BSDF integrates
 * over the cone the sphere subtends: no spike where a VPL meets a corner or a sharp lobe. The
 * integral is estimated per pixel and VPL from IIR_VSL_SAMPLES directions, uniform in the cone
 * and, where the lobe is much narrower than the cone, partly drawn by the BSDF (half, or 3/4),
 * combined by multiple importance sampling (balance heuristic); unbiased, but one pixel's estimate
 * is still noisy where the cone cuts a lobe about its size (roughness 0.3 and below). */
typedef enum iir_vpl_kind { IIR_VPL_POINT, IIR_VPL_SPHERE } iir_vpl_kind;
#define IIR_VSL_NEIGHBOURS 4
#define IIR_VSL_SAMPLES 8

/* What the geometry term's clamp removed, given back (Kollig & Keller 2004; render_compensate.c).
 */
typedef enum iir_clamp_comp {
    IIR_CLAMP_COMP_OFF,        /* the clamped estimate: darker near contacts and corners */
    IIR_CLAMP_COMP_FULL,       /* one cosine ray per pixel estimates the residual */
    IIR_CLAMP_COMP_INTERLEAVED /* rays from one diagonal of the n x n lattice (n times fewer),
                                  weighted n, gathered by the filter */
} iir_clamp_comp;

/* Where shading multires evaluates the direct light of points, spots and suns on diffuse surfaces:
 * at every pixel, or on the light tree (render/light_tree.h; render_direct.c). */
typedef enum iir_mr_direct { IIR_MR_DIRECT_FULL, IIR_MR_DIRECT_TREE } iir_mr_direct;

/* The multires hierarchy's knobs (multires.h), as the multires parameter table (mr_levels,
 * mr_depth, mr_normal, mr_window, mr_direct, light_split) binds them wherever a method keeps them.
 */
typedef struct iir_mr_params {
    int mr_levels;   /* coarsest level (texels of 2^mr_levels pixels), [1, 6] */
    float mr_depth;  /* discontinuity where a neighbour lies off a pixel's tangent plane by more
                        than mr_depth times its camera depth, [0, inf) */
    float mr_normal; /* discontinuity where neighbours' normals' cosine is below, [-1, 1] */
    int mr_window;   /* pixels a level's interleave filter spans at most (level l of an n x n
                        lattice interleaves min(n, mr_window / 2^l); 1 there = every VPL at every
                        texel), [1, 1024] */
    iir_mr_direct mr_direct; /* the point, spot and sun lights' direct light */
    float light_split; /* the direct light's quadtree (render/light_tree.h): a block splits where
                          its light is off its corners' interpolation by more than this fraction
                          of the brightest, [0, 1] */
} iir_mr_params;

/* The geometry-aware filter's similarity (render_filter.c; multires's per-level filter): normals'
 * cosine at least IIR_FILTER_MIN_COS, camera depths within IIR_FILTER_MAX_REL_DEPTH of the
 * centre's. */
#define IIR_FILTER_MIN_COS 0.9f
#define IIR_FILTER_MAX_REL_DEPTH 0.05f

/* The VPL shading's settings: the one struct the VPL parameter tables (render_params.c) bind
 * wherever a method keeps them, and what the renderer is asked for. */
typedef struct iir_indirect_params {
    iir_visibility visibility; /* ism: the method built ISMs into the maps (read as shadowmap) */
    int sm_res;                /* the method's shadow maps: sm_res^2 texels per paraboloid */
    float sm_bias;  /* shadow maps: constant bias as a fraction of the VPL-receiver distance,
                       added to the slope term (shadowmap.h). [0, 1] */
    int interleave; /* n: n x n VPL subsets; 1 = every VPL at every pixel, no filter. [1, 8] */
    float clamp;    /* G <= clamp / D^2, D the scene's bounding-box diagonal; 0 = no clamp.
                       [0, inf) */
    iir_clamp_comp clamp_comp; /* compensation of the clamp (shading full only) */
    iir_shading shading;       /* full or multires (refinement passes are always full) */
    iir_mr_params mr;          /* shading multires: the hierarchy */
    int area_samples;          /* direct light: stratified samples per pixel of every area light
                                  and of the emissive triangles (render_direct.c). [1, 4096] */
    iir_receiver_bsdf receiver_bsdf; /* VPL light through the receiving pixel's full BSDF */
    iir_vpl_kind vpl_kind;           /* points or spheres to glossy receivers */
    int bounces;     /* the light bounces the VPLs stand for (the methods' `bounces`, >= 2):
                        compensation adds no light of more bounces. 0 counts as 2 */
    bool unfiltered; /* leave the raw interleaved estimate (tests, debugging); false: the
                        geometry-aware filter when interleave > 1 */
} iir_indirect_params;

/* The VPL parameter tables' defaults (render_params.c), bounces 2, filtered. */
iir_indirect_params iir_indirect_params_default(void);

/* ---- the VPL shading's parameter tables (render_params.c), each bound at its offset ---- */
/* visibility and sm_res of an iir_indirect_params (ism always uses ISMs: it does not list them) */
extern const iir_param_table iir_vis_table;
/* sm_bias, interleave, area_samples, receiver_bsdf, vpl_kind of an iir_indirect_params */
extern const iir_param_table iir_vpl_table;
/* `shading` (full or multires), one iir_shading, wherever a method keeps it (.shading of an
 * iir_indirect_params for ir, iir and ism). */
extern const iir_param_table iir_shading_table;
/* The geometry term's clamp, one float (the VPL methods list it at their float's offset). */
extern const iir_param_table iir_clamp_table;
/* `clamp_compensation`, bound to a whole iir_indirect_params after its shading (ir, iir, ism). */
extern const iir_param_table iir_clamp_comp_table;
/* multires's hierarchy, one iir_mr_params, for every method that shades on it. */
extern const iir_param_table iir_multires_table;

/* Bytes of the VPL renderer (G-buffer, scratch, refinement buffers) for a frame, and of n VPLs
 * with their shadow maps under these settings: the VPL methods' memory estimates share them. */
uint64_t iir_vpl_memory(const iir_indirect_params *o, uint32_t n, int width, int height);
/* Bytes of the columns a renderer keeps for n VPLs kept from frame to frame (shadow maps: a float
 * per VPL and pixel of its subset, or multires sample it is evaluated at), at most the renderer's
 * budget for them (256 MB), and of the pixels' copy they keep with them (full shading: 28 bytes a
 * pixel): what a method whose VPLs outlive a frame (iir) adds to iir_vpl_memory. */
uint64_t iir_gv_memory(const iir_indirect_params *o, uint32_t n, int width, int height);

/* The interleaving subset of VPL `id` among n2 subsets: Fibonacci hashing of the id, so
 * consecutive ids spread evenly over the subsets while a subset's ids follow no power-of-two
 * stride (an id mod n2 rule would give each subset a band of a Hammersley-ordered set's disk). */
static inline uint32_t iir_vpl_subset(uint32_t id, uint32_t n2)
{
    return iir_key_subset(iir_id_key(id), n2);
}

/* VPL v's interleaving subset among n2: by its key, where it has one (iir spreads keys over
 * neighbours in the light's domain, so that each subset is a stratified sample of a kept set),
 * else by its id. */
static inline uint32_t iir_vpl_subset_of(const iir_vpl *v, uint32_t n2)
{
    return iir_key_subset(v->key ? v->key : iir_id_key(v->id), n2);
}

/* IIR_ERR_INVALID naming the field and its range. */
iir_status iir_indirect_params_validate(const iir_indirect_params *p, iir_error *err);

/* A frame's phases in milliseconds of wall time. With a side (iir_render_side), direct_ms is the
 * time the direct phase took beyond the side's run (side_ms), and no phase holds the side's vpls,
 * so that the caller's own timing of the side plus these still add up to the frame. */
typedef struct iir_render_timing {
    double gbuffer_ms, direct_ms, indirect_ms, filter_ms, side_ms;
    bool gbuffer_cached; /* the G-buffer of the previous frame was reused */
    uint64_t vpl_evals;  /* pixel-VPL pairs shaded (multires: texel-VPL pairs and pixel-VPL
                            pairs of the full-resolution pixels) */
    uint64_t vpl_reused; /* of those, the pairs whose geometry and visibility a kept VPL's column
                            held from an earlier frame (full shading with shadow maps, AVX2) */
} iir_render_timing;

typedef struct iir_renderer iir_renderer;

/* A renderer over a scene and its ray tracer (both must outlive it). Allocates nothing per pixel
 * yet; returns NULL on allocation failure. */
iir_renderer *iir_renderer_create(const struct iir_scene *scene, const iir_rt *rt);
void iir_renderer_destroy(iir_renderer *r);

/* The instruction set of the renderer's shading kernels (isa.h): iir_isa_default() at creation;
 * set to isa when this build and CPU support it. Returns the set now in use. Any set gives the
 * scalar one's image up to float rounding. */
iir_isa iir_renderer_set_isa(iir_renderer *r, iir_isa isa);

/* Bytes a renderer holds for frames of width x height: its G-buffer and its per-pixel scratch (the
 * raw indirect light, the filter's rows, the tiles' flags). The methods' memory estimates start
 * from it. */
uint64_t iir_renderer_memory(int width, int height);

/* Camera rays that meet a mirror, glass (its stronger branch) or a metal smoother than
 * IIR_MIRROR_ROUGHNESS are followed through up to `depth` such surfaces to the first rough one,
 * where direct and VPL light are gathered and passed back through the chain (0, the default: a
 * specular surface is gathered where it is, and is black). */
void iir_renderer_follow_specular(iir_renderer *r, int depth);
/* The chains of the VPL methods (ir, iir, ism): as many links as whitted's default depth. */
#define IIR_VPL_SPECULAR_DEPTH 8

/* The G-buffer of the last frame (width 0 before the first). Valid until the next frame or
 * destroy; owned by the renderer. */
const iir_gbuffer *iir_renderer_gbuffer(const iir_renderer *r);

/* Work a frame's caller does beside its direct light, where the VPLs come from. One thread runs
 * run(ctx) while the others shade the direct light, then joins them, so that its serial parts (a
 * VPL step's triangulation) leave no core idle; its own parallel loops run on its one thread, so
 * it should be the serial kind of work. After the direct light, vpls(ctx, ...) runs on the
 * calling thread (its loops on every thread: a VPL step's shadow maps) and gives the VPLs the
 * indirect light uses. Both run after the G-buffer, on the caller's objects alone (never the
 * renderer's), once each (vpls only when run succeeded); a status other than IIR_OK ends the frame
 * with it (and err). */
typedef struct iir_render_side {
    iir_status (*run)(void *ctx, iir_error *err);
    iir_status (*vpls)(void *ctx, const iir_vpl **vpls, uint32_t *num_vpls, iir_error *err);
    void *ctx;
} iir_render_side;

/* What a frame or a pass shades: the camera, the lights (delta and area lights; emissive triangles
 * come from the scene), the VPLs (NULL when num_vpls is 0) and the seed of the frame's random
 * numbers (the emissive-triangle samples of direct light). All read-only during the call. A frame
 * with a side (may be NULL; passes have none) takes its VPLs from it instead of vpls/num_vpls. */
typedef struct iir_render_input {
    const iir_camera *camera;
    const iir_light *lights;
    uint32_t num_lights;
    const iir_vpl *vpls;
    uint32_t num_vpls;
    uint64_t seed;
    const iir_render_side *side;
} iir_render_input;

/* The seed of a live frame's direct-light samples (emissive triangles, area lights): the same
 * every frame, so their noise stays put on static emitters and moves with a moving area light (its
 * samples are in light-local coordinates) instead of flickering from frame to frame; refinement
 * passes vary it (refine.c). */
static inline uint64_t iir_frame_direct_seed(uint64_t seed)
{
    return iir_hash3(seed, 0, 2);
}

/* Renders one frame of `in` into out (its size is the frame size): emission + direct light +
 * indirect light from the VPLs (see the top of this header). The frame depends only on its inputs
 * and the seed, not on the thread count. Rays are added to *st (may be NULL); *t (may be NULL) is
 * overwritten.
 * Errors (out is then unspecified, the renderer stays usable): IIR_ERR_INVALID for an invalid
 * camera, light or params, a VPL with a non-finite or negative field, or -- with shadow-map
 * visibility -- a non-null VPL whose map is not rendered; IIR_ERR_NOMEM when growing scratch fails.
 */
iir_status iir_renderer_frame(iir_renderer *r, const iir_render_input *in,
                              const iir_indirect_params *p, iir_image *out, iir_render_timing *t,
                              iir_raystats *st, iir_error *err);

/* ---- one pass of progressive refinement (refine.h averages them) ----
 *
 * A pass differs from a frame in three ways:
 *  - Pixel (x, y)'s camera ray goes through (x + jitter.x, y + jitter.y). Unless that is the
 *    centre (0.5, 0.5), the pass renders its own G-buffer and the renderer forgets its cached
 *    pixel-centre one, so the next frame renders it again (frames stay exactly as without passes).
 *  - Visibility is always exact occlusion rays; there is no filter.
 *  - Pixel (x, y) evaluates subset ((y mod n) n + (x mod n) + shift) mod n^2 with the subset's flux
 *    scaled by n^2 (not N / |subset|). The n^2 passes with shift 0 .. n^2 - 1 thus give every
 *    pixel every subset once, and their mean is exactly the all-VPL sum (at pixel centres:
 *    iir_renderer_frame with interleave 1 and exact rays), whatever the subsets' sizes.
 * Direct light is a frame's: with emissive triangles pass a new seed per pass for new samples. */
typedef struct iir_pass_params {
    int interleave;   /* n, [1, 8] */
    uint32_t shift;   /* [0, n^2) */
    iir_vec2 jitter;  /* in [0, 1]^2; (0.5, 0.5) = the pixel centre */
    float clamp;      /* as iir_indirect_params.clamp */
    bool clamp_comp;  /* compensation at every pixel (any rate of a frame: passes average it) */
    int bounces;      /* as iir_indirect_params.bounces */
    int area_samples; /* as iir_indirect_params.area_samples; 0 = its default */
} iir_pass_params;

/* The hook (status.h) that lets a frame or a pass end early: polled between phases and before each
 * direct and indirect tile; once it returns true the call skips its remaining work and fails with
 * IIR_ERR_INTERRUPTED (out unspecified). fn NULL = never stop. */
void iir_renderer_set_stop(iir_renderer *r, iir_stop_fn fn, void *ctx);

/* Renders one pass into out (every pixel written), as iir_renderer_frame does a frame; the same
 * errors, plus IIR_ERR_INVALID for a shift or jitter out of range, and IIR_ERR_INTERRUPTED when
 * the stop hook asked (out is then unspecified). */
iir_status iir_renderer_pass(iir_renderer *r, const iir_render_input *in, const iir_pass_params *p,
                             iir_image *out, iir_render_timing *t, iir_raystats *st,
                             iir_error *err);

#ifdef __cplusplus
}
#endif
#endif

/* bsdf.h -- glTF 2.0's metallic-roughness BRDF (specification, appendix B) as a small interface:
 * evaluate f, its sampling pdf, sample a direction, the diffuse reflectance for methods that only
 * know diffuse surfaces. Reflection only; not how a method gets a surface's parameters (textures,
 * the scene's materials), nor mirrors and glass of iir_material_kind (specular.h).
 *
 * The model, as appendix B's "implementation" writes it, with v = wo, l = wi, h = (v + l)/|v + l|:
 *   f0    = mix(0.04, base_color, metallic)       c_diff = mix(base_color, 0, metallic)
 *   alpha = roughness^2                            (roughness and metallic clamped to [0, 1])
 *   F     = f0 + (1 - f0) (1 - |v.h|)^5            Schlick
 *   D     = alpha^2 / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2)      GGX / Trowbridge-Reitz
 *   V     = G2 / (4 |n.l| |n.v|), the height-correlated Smith visibility,
 *         = 0.5 / (n.l sqrt((n.v)^2 (1 - alpha^2) + alpha^2)
 *                  + n.v sqrt((n.l)^2 (1 - alpha^2) + alpha^2))
 *   f     = (1 - F) c_diff / pi  +  F D V          (no cosine: the caller multiplies by |n.wi|)
 *
 * The specular lobe is single-scattering GGX: it loses energy as roughness grows (a white metal of
 * roughness 1 reflects 1 - ln 2 = 0.31 of the light arriving head-on, 0.45 at 60 degrees; 0.92 at
 * roughness 0.5 head-on). The mix through F(v.h) is not energy conserving for dielectrics seen at
 * grazing angles: the specular lobe takes F(n.wo) of the light while the diffuse lobe, weighted by
 * 1 - F(v.h) with h between wo and each wi, keeps most of its own. A white dielectric of roughness
 * 0.05 reflects 1.00 head-on, 1.03 at 60 degrees and 1.59 at 85 (1.04 averaged over
 * cosine-weighted incidence, what a closed white furnace sees); at roughness 1, 0.97 to 0.99. That
 * is appendix B's model, kept as written (tests/unit/test_bsdf.c prints the figures).
 *
 * Near-zero roughness is a mirror: below IIR_BSDF_DELTA_ALPHA the specular lobe is a delta, the
 * perfect reflection of wo weighted by F(n.wo). iir_bsdf_f and iir_bsdf_pdf leave the delta lobe
 * out (they are 0 for it); only iir_bsdf_sample_f returns it, flagged IIR_BSDF_SPECULAR.
 *
 * Directions are world-space unit vectors pointing away from the surface (wo towards the viewer,
 * wi towards the light). Two-sided by the caller: the BSDF's normal is the shading normal already
 * turned to wo's side; with wo.n <= 0 or wi.n <= 0, f and pdf are 0 and sampling fails. Geometric
 * against shading normal is the integrator's business. All functions are pure, allocate nothing
 * and may be called from any thread. */
#ifndef IIR_BSDF_H
#define IIR_BSDF_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>

#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Lobe flags: what iir_bsdf_flags says a BSDF has and iir_bsdf_sample.flags says was sampled. */
enum { IIR_BSDF_DIFFUSE = 1, IIR_BSDF_GLOSSY = 2, IIR_BSDF_SPECULAR = 4 /* delta */ };

/* Below this alpha (roughness < ~0.032) the specular lobe is a delta (a mirror). */
#define IIR_BSDF_DELTA_ALPHA 1e-3f

typedef struct iir_bsdf {
    iir_frame frame;     /* shading frame; frame.f = shading normal (unit) */
    iir_vec3 base_color; /* linear, clamped to [0, 1] */
    float metallic;      /* clamped to [0, 1] */
    float alpha;         /* roughness^2, roughness clamped to [0, 1] */
    /* derived at make time, so evaluation does no extra work: */
    iir_vec3 f0;     /* Fresnel reflectance at normal incidence: mix(0.04, base_color, metallic) */
    iir_vec3 c_diff; /* diffuse colour: base_color (1 - metallic) */
    bool lambert;    /* a Lambertian surface of albedo c_diff alone (iir_bsdf_make_lambert) */
    /* no p_spec: the lobe choice depends on wo (iir_bsdf_spec_probability) */
} iir_bsdf;

/* The BSDF at a point with unit shading normal n (turned to wo's side by the caller); the tangents
 * come from iir_frame_from_normal (the model is isotropic, any frame will do). Roughness and
 * metallic are clamped to [0, 1], base_color's components likewise. Asserts (in the test build)
 * that n is unit and the parameters are not NaN. */
iir_bsdf iir_bsdf_make(iir_vec3 n, iir_vec3 base_color, float metallic, float roughness);
/* The same with a dielectric's reflectance at normal incidence other than glTF's 0.04 (an MTL's
 * specular colour, as Blender reads it: 0.08 mean(Ks)); f0 = mix(dielectric_f0, base, metallic). */
iir_bsdf iir_bsdf_make_f0(iir_vec3 n, iir_vec3 base_color, float metallic, float roughness,
                          float dielectric_f0);

/* A Lambertian BSDF, f = albedo / pi, sampled by the cosine (an OBJ's or sidecar's diffuse
 * material: no specular lobe at all). */
iir_bsdf iir_bsdf_make_lambert(iir_vec3 n, iir_vec3 albedo);

/* ---- 8 metallic-roughness BSDFs at once (bsdf_lanes_avx2.c): the direct-light kernel ---- */

/* 8 lanes' BSDFs as iir_bsdf_make_f0 makes them (clamped), structure of arrays, with each lane's
 * shading normal n and unit wo; no tangent frame: the model is isotropic, so the lanes evaluate it
 * from dot products with n. A lane left zeroed is black. */
typedef struct iir_bsdf_lanes {
    _Alignas(32) float nx[8], ny[8], nz[8], wox[8], woy[8], woz[8];
    float f0x[8], f0y[8], f0z[8], cx[8], cy[8], cz[8], alpha[8];
} iir_bsdf_lanes;

/* Lane k: unit shading normal n (on wo's side), unit wo, and iir_bsdf_make_f0's parameters. */
void iir_bsdf_lanes_set(iir_bsdf_lanes *L, int k, iir_vec3 n, iir_vec3 wo, iir_vec3 base_color,
                        float metallic, float roughness, float dielectric_f0);

/* f(wo, wi) of the 8 lanes for unit wi (w*[k]; 0 where no light arrives), with AVX2 and FMA:
 * only where iir_isa_supported(IIR_ISA_AVX2). iir_bsdf_f's value up to float rounding (test_bsdf:
 * lane by lane against it); 0 where wo or wi is below the surface. */
void iir_bsdf_f8_avx2(const iir_bsdf_lanes *L, const float *wx, const float *wy, const float *wz,
                      float *fx, float *fy, float *fz);

/* Whether a metallic-roughness surface counts as glossy: every metal, and a dielectric smoother
 * than IIR_GLOSSY_ROUGHNESS (rougher ones reflect nearly as a Lambertian surface of albedo c_diff
 * does). The scene's notes name the glossy materials; the VPL methods' gather evaluates the full
 * BSDF at glossy pixels only. */
#define IIR_GLOSSY_ROUGHNESS 0.6f
/* Roughness below which a metallic-roughness surface is followed as a mirror of reflectance
 * Schlick's F (its f0) where a method traces specular paths (whitted's tree, the VPL methods'
 * G-buffer chains): a chrome ball of roughness 0.05 shows the room, not a highlight on black. */
#define IIR_MIRROR_ROUGHNESS 0.1f

/* Schlick: F = f0 + (1 - f0) (1 - cos)^5, cos clamped to [0, 1]. */
static inline iir_vec3 iir_fresnel_schlick(iir_vec3 f0, float cos_theta)
{
    float m = 1.f - iir_clampf(cos_theta, 0.f, 1.f);
    float m5 = iir_sqr(iir_sqr(m)) * m;
    return iir_madd(f0, iir_sub(iir_v3s(1.f), f0), m5);
}

/* A metallic-roughness surface's diffuse albedo c_diff plus its Fresnel reflectance at normal
 * incidence (mix(dielectric_f0, base, metallic)), each channel at least 0.02: what the VPL methods
 * weigh a glossy VPL's flux by and demodulate a glossy pixel's light by (its BSDF divides it back
 * out), so that a metal carries its colour and a black one stays finite. */
static inline iir_vec3 iir_bsdf_reflectance(iir_vec3 c_diff, iir_vec3 base, float metallic,
                                            float dielectric_f0)
{
    iir_vec3 f0 = iir_add(iir_v3s(dielectric_f0 * (1.f - metallic)), iir_scale(base, metallic));
    iir_vec3 r = iir_add(c_diff, f0);
    return iir_v3(fmaxf(r.x, 0.02f), fmaxf(r.y, 0.02f), fmaxf(r.z, 0.02f));
}
static inline bool iir_bsdf_params_glossy(float metallic, float roughness)
{
    return metallic > 0.f || roughness < IIR_GLOSSY_ROUGHNESS;
}

/* The lobes b has: IIR_BSDF_DIFFUSE if c_diff is not black; IIR_BSDF_GLOSSY if alpha >=
 * IIR_BSDF_DELTA_ALPHA, else IIR_BSDF_SPECULAR. Every BSDF has one of the last two (Schlick's F is
 * not 0 at grazing angles even for black metal). */
unsigned iir_bsdf_flags(const iir_bsdf *b);

/* f(wo, wi), RGB, without the cosine; the delta lobe excluded (a delta BSDF returns its diffuse
 * part only). Symmetric in wo and wi. 0 when either direction is at or below the horizon. */
static inline iir_vec3 iir_bsdf_f(const iir_bsdf *b, iir_vec3 wo, iir_vec3 wi);

/* The solid-angle density with which iir_bsdf_sample_f(b, wo, ...) returns a non-delta wi: the
 * one-sample mixture p_spec pdf_spec + (1 - p_spec) pdf_diff, with p_spec as
 * iir_bsdf_spec_probability says, pdf_spec the visible-normal GGX pdf D_wo(wh) / (4 |wo.wh|) (0
 * for a delta BSDF) and pdf_diff = cos(theta_i) / pi. 0 when either direction is at or below the
 * horizon. Integrates over the upper hemisphere to the probability that sampling succeeds (the
 * GGX samples that reflect below the horizon fail and are not counted). Not symmetric. */
static inline float iir_bsdf_pdf(const iir_bsdf *b, iir_vec3 wo, iir_vec3 wi);

/* One sampled direction. For a non-delta sample (flags DIFFUSE or GLOSSY), f and pdf are the FULL
 * BSDF's iir_bsdf_f and iir_bsdf_pdf at wi (both lobes: what MIS with light sampling needs), and
 * f |cos(theta_i)| / pdf is the throughput. For a delta sample (flags SPECULAR), pbrt's convention:
 * pdf = p_spec, the probability that the delta lobe was chosen (a discrete probability, not a
 * density), and f = F(n.wo) / |cos(theta_i)|, so f |cos(theta_i)| / pdf = F(n.wo) / p_spec; the
 * diffuse lobe adds nothing to a delta direction. */
typedef struct iir_bsdf_sample {
    iir_vec3 wi;    /* world space, unit, above the horizon */
    iir_vec3 f;     /* see above; finite, non-negative */
    float pdf;      /* > 0 */
    unsigned flags; /* the lobe sampled: one of IIR_BSDF_DIFFUSE, _GLOSSY, _SPECULAR */
} iir_bsdf_sample;

/* Samples wi for wo: uc in [0, 1) picks the lobe (specular when uc < p_spec), u in [0, 1)^2 the
 * direction (GGX visible normals, Heitz 2018, reflected about; a cosine-weighted hemisphere for
 * the diffuse lobe; the mirror direction for a delta lobe). Returns false, *out unset, when wo is
 * at or below the horizon, or the chosen lobe's direction is (a visible normal can reflect wo
 * below it): a failed sample carries no light. */
bool iir_bsdf_sample_f(const iir_bsdf *b, iir_vec3 wo, float uc, iir_vec2 u, iir_bsdf_sample *out);

/* The probability that iir_bsdf_sample_f picks the specular lobe for wo: the lobes' estimated
 * albedos normalised, with Fs = luminance of F(f0, n.wo) for the specular lobe and
 * luminance(c_diff) (1 - Fs) for the diffuse one; 1 when both are 0 (black metal seen head-on),
 * 0 when wo is at or below the horizon. */
float iir_bsdf_spec_probability(const iir_bsdf *b, iir_vec3 wo);

/* The reflectance a diffuse-only method (VPLs, radiosity) gives this surface: c_diff =
 * base_color (1 - metallic). The (1 - F) factor is left out on purpose: such a method drops the
 * specular lobe, and c_diff alone is close to what a dielectric reflects with both lobes (a white
 * one reflects 0.96 diffusely and 0.04 specularly head-on, 1.00 together). Metals have no diffuse
 * part and are black to such a method. */
iir_vec3 iir_bsdf_albedo(const iir_bsdf *b);

/* Writes a one-line description of b for logs ("bsdf{base=(..) metallic=.. alpha=.. ...}") into
 * buf of size n (always terminated when n > 0, truncated to fit). */
void iir_bsdf_describe(const iir_bsdf *b, char *buf, size_t n);

/* ---- inline: a Lambertian BSDF's f and pdf without a call or a change of frame (the diffuse
 * scenes' hot path); the rest in bsdf.c ---- */

iir_vec3 iir_bsdf_f_general(const iir_bsdf *b, iir_vec3 wo, iir_vec3 wi);
float iir_bsdf_pdf_general(const iir_bsdf *b, iir_vec3 wo, iir_vec3 wi);

static inline bool iir_bsdf_lambert_sides(const iir_bsdf *b, iir_vec3 wo, iir_vec3 wi)
{
    return iir_dot(wo, b->frame.f) > 0.f && iir_dot(wi, b->frame.f) > 0.f;
}

static inline iir_vec3 iir_bsdf_f(const iir_bsdf *b, iir_vec3 wo, iir_vec3 wi)
{
    if (!b->lambert) return iir_bsdf_f_general(b, wo, wi);
    return iir_bsdf_lambert_sides(b, wo, wi) ? iir_scale(b->c_diff, IIR_INV_PI) : iir_v3s(0.f);
}

static inline float iir_bsdf_pdf(const iir_bsdf *b, iir_vec3 wo, iir_vec3 wi)
{
    if (!b->lambert) return iir_bsdf_pdf_general(b, wo, wi);
    float c = iir_dot(wi, b->frame.f);
    return iir_bsdf_lambert_sides(b, wo, wi) ? c * IIR_INV_PI : 0.f;
}

#ifdef __cplusplus
}
#endif
#endif

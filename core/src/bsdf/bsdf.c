/* bsdf.c -- glTF's metallic-roughness BRDF: the lobes' mix through Schlick's F, evaluation, the
 * one-sample mixture pdf and sampling (iir/bsdf.h); not the microfacet distribution (ggx.h) nor
 * where a surface's parameters come from. Works in the shading frame's local coordinates (normal
 * +z); the public functions convert at the boundary. */
#include <assert.h>
#include <stdio.h>

#include "iir/bsdf.h"
#include "bsdf/ggx.h"
#include "sampling.h"
#include "specular.h"

static bool is_delta(const iir_bsdf *b)
{
    return b->alpha < IIR_BSDF_DELTA_ALPHA;
}

static iir_vec3 mix3(iir_vec3 a, iir_vec3 b, float t)
{
    return iir_add(iir_scale(a, 1.f - t), iir_scale(b, t));
}

static iir_vec3 clamp01(iir_vec3 c)
{
    return iir_v3(iir_clampf(c.x, 0.f, 1.f), iir_clampf(c.y, 0.f, 1.f), iir_clampf(c.z, 0.f, 1.f));
}

/* ======================= local frame: normal +z, both directions above ======================= */

/* f = (1 - F) c_diff / pi + F D V; the delta lobe left out. */
static iir_vec3 f_local(const iir_bsdf *b, iir_vec3 wo, iir_vec3 wi)
{
    if (wo.z <= 0.f || wi.z <= 0.f) return iir_v3s(0.f);
    if (b->lambert) return iir_scale(b->c_diff, IIR_INV_PI);
    iir_vec3 wh = iir_normalize(iir_add(wo, wi));
    /* |v.h| as the mean of wo.wh and wi.wh (equal, but this way f is symmetric in float too) */
    iir_vec3 F = iir_fresnel_schlick(b->f0, 0.5f * fabsf(iir_dot(wo, wh) + iir_dot(wi, wh)));
    /* f_diffuse = (1 - F) c_diff / pi */
    iir_vec3 f = iir_scale(iir_mul(iir_sub(iir_v3s(1.f), F), b->c_diff), IIR_INV_PI);
    if (is_delta(b)) return f;
    /* f_specular = F D V */
    float D = iir_ggx_D(wh, b->alpha), V = iir_ggx_V(wo, wi, b->alpha);
    return iir_madd(f, F, D * V);
}

/* p_spec = Fs / (Fs + Fd): the lobes' albedos estimated as Fs = lum(F(n.wo)) for the specular
 * lobe, Fd = lum(c_diff) (1 - Fs) for the diffuse one; the specular lobe when both are 0. */
static float spec_probability_local(const iir_bsdf *b, iir_vec3 wo)
{
    if (wo.z <= 0.f || b->lambert) return 0.f;
    float Fs = iir_luminance(iir_fresnel_schlick(b->f0, wo.z));
    float Fd = iir_luminance(b->c_diff) * (1.f - Fs);
    return Fs + Fd > 0.f ? Fs / (Fs + Fd) : 1.f;
}

/* pdf_spec = D_wo(wh) / (4 |wo.wh|), the visible normal reflected about. */
static float spec_pdf_local(const iir_bsdf *b, iir_vec3 wo, iir_vec3 wi)
{
    if (is_delta(b)) return 0.f;
    iir_vec3 wh = iir_normalize(iir_add(wo, wi));
    float wo_wh = iir_dot(wo, wh);
    if (wo_wh <= 0.f) return 0.f;
    return iir_ggx_visible_pdf(wo, wh, b->alpha) / (4.f * wo_wh);
}

/* The one-sample mixture: p_spec pdf_spec + (1 - p_spec) pdf_diff. */
static float pdf_local(const iir_bsdf *b, iir_vec3 wo, iir_vec3 wi)
{
    if (wo.z <= 0.f || wi.z <= 0.f) return 0.f;
    float p_spec = spec_probability_local(b, wo);
    float pdf_diff = iir_cosine_hemisphere_pdf(wi.z);
    return p_spec * spec_pdf_local(b, wo, wi) + (1.f - p_spec) * pdf_diff;
}

/* The mirror sample of the delta lobe (pbrt's convention, iir/bsdf.h). */
static bool sample_delta_local(const iir_bsdf *b, iir_vec3 wo, float p_spec, iir_bsdf_sample *s)
{
    s->wi = iir_reflect(iir_neg(wo), iir_v3(0.f, 0.f, 1.f));
    if (s->wi.z <= 0.f) return false;
    s->f = iir_scale(iir_fresnel_schlick(b->f0, wo.z), 1.f / s->wi.z);
    s->pdf = p_spec;
    s->flags = IIR_BSDF_SPECULAR;
    return true;
}

/* A sample in local coordinates: the lobe by uc, its direction by u, then the full f and pdf. */
static bool sample_local(const iir_bsdf *b, iir_vec3 wo, float uc, iir_vec2 u, iir_bsdf_sample *s)
{
    if (wo.z <= 0.f) return false;
    float p_spec = spec_probability_local(b, wo);
    if (uc < p_spec && is_delta(b)) return sample_delta_local(b, wo, p_spec, s);
    if (uc < p_spec) {
        iir_vec3 wh = iir_ggx_sample_visible(wo, b->alpha, u);
        s->wi = iir_reflect(iir_neg(wo), wh);
        s->flags = IIR_BSDF_GLOSSY;
    } else {
        s->wi = iir_sample_cosine_hemisphere(u);
        s->flags = IIR_BSDF_DIFFUSE;
    }
    if (s->wi.z <= 0.f) return false;
    s->f = f_local(b, wo, s->wi);
    s->pdf = pdf_local(b, wo, s->wi);
    return s->pdf > 0.f;
}

/* ================================ the interface (world space) ================================ */

iir_bsdf iir_bsdf_make(iir_vec3 n, iir_vec3 base_color, float metallic, float roughness)
{
    return iir_bsdf_make_f0(n, base_color, metallic, roughness, 0.04f);
}

/* make_f0's parameters, clamped, and what it derives from them. */
static void set_params(iir_bsdf *b, iir_vec3 base_color, float metallic, float roughness,
                       float dielectric_f0)
{
    b->base_color = clamp01(base_color);
    b->metallic = iir_clampf(metallic, 0.f, 1.f);
    b->alpha = iir_sqr(iir_clampf(roughness, 0.f, 1.f));
    b->f0 = mix3(iir_v3s(iir_clampf(dielectric_f0, 0.f, 1.f)), b->base_color, b->metallic);
    b->c_diff = mix3(b->base_color, iir_v3s(0.f), b->metallic);
    b->lambert = false;
}

iir_bsdf iir_bsdf_make_f0(iir_vec3 n, iir_vec3 base_color, float metallic, float roughness,
                          float dielectric_f0)
{
    assert(fabsf(iir_length(n) - 1.f) < 1e-3f);
    assert(!isnan(base_color.x + base_color.y + base_color.z + metallic + roughness));
    iir_bsdf b;
    b.frame = iir_frame_from_normal(n);
    set_params(&b, base_color, metallic, roughness, dielectric_f0);
    return b;
}

void iir_bsdf_lanes_set(iir_bsdf_lanes *L, int k, iir_vec3 n, iir_vec3 wo, iir_vec3 base_color,
                        float metallic, float roughness, float dielectric_f0)
{
    iir_bsdf b;
    set_params(&b, base_color, metallic, roughness, dielectric_f0);
    L->nx[k] = n.x, L->ny[k] = n.y, L->nz[k] = n.z;
    L->wox[k] = wo.x, L->woy[k] = wo.y, L->woz[k] = wo.z;
    L->f0x[k] = b.f0.x, L->f0y[k] = b.f0.y, L->f0z[k] = b.f0.z;
    L->cx[k] = b.c_diff.x, L->cy[k] = b.c_diff.y, L->cz[k] = b.c_diff.z;
    L->alpha[k] = b.alpha;
}

iir_bsdf iir_bsdf_make_lambert(iir_vec3 n, iir_vec3 albedo)
{
    assert(fabsf(iir_length(n) - 1.f) < 1e-3f);
    assert(!isnan(albedo.x + albedo.y + albedo.z));
    iir_bsdf b;
    b.frame = iir_frame_from_normal(n);
    b.base_color = clamp01(albedo);
    b.metallic = 0.f;
    b.alpha = 1.f;
    b.f0 = iir_v3s(0.f);
    b.c_diff = b.base_color;
    b.lambert = true;
    return b;
}

unsigned iir_bsdf_flags(const iir_bsdf *b)
{
    if (b->lambert) return IIR_BSDF_DIFFUSE;
    unsigned flags = is_delta(b) ? IIR_BSDF_SPECULAR : IIR_BSDF_GLOSSY;
    return iir_is_black(b->c_diff) ? flags : flags | IIR_BSDF_DIFFUSE;
}

iir_vec3 iir_bsdf_f_general(const iir_bsdf *b, iir_vec3 wo, iir_vec3 wi)
{
    return f_local(b, iir_frame_to_local(&b->frame, wo), iir_frame_to_local(&b->frame, wi));
}

float iir_bsdf_pdf_general(const iir_bsdf *b, iir_vec3 wo, iir_vec3 wi)
{
    return pdf_local(b, iir_frame_to_local(&b->frame, wo), iir_frame_to_local(&b->frame, wi));
}

/* Lambert: a cosine-weighted direction about the normal, f = c_diff / pi, pdf = cos / pi. */
static bool sample_lambert(const iir_bsdf *b, iir_vec3 wo, iir_vec2 u, iir_bsdf_sample *out)
{
    if (iir_dot(wo, b->frame.f) <= 0.f) return false;
    iir_vec3 wl = iir_sample_cosine_hemisphere(u);
    if (wl.z <= 0.f) return false;
    out->wi = iir_frame_to_world(&b->frame, wl);
    out->f = iir_scale(b->c_diff, IIR_INV_PI);
    out->pdf = iir_cosine_hemisphere_pdf(wl.z);
    out->flags = IIR_BSDF_DIFFUSE;
    return true;
}

bool iir_bsdf_sample_f(const iir_bsdf *b, iir_vec3 wo, float uc, iir_vec2 u, iir_bsdf_sample *out)
{
    if (b->lambert) return sample_lambert(b, wo, u, out);
    iir_bsdf_sample s;
    if (!sample_local(b, iir_frame_to_local(&b->frame, wo), uc, u, &s)) return false;
    assert(iir_is_finite3(s.f) && s.f.x >= 0.f && s.f.y >= 0.f && s.f.z >= 0.f);
    assert(isfinite(s.pdf) && s.pdf > 0.f);
    s.wi = iir_frame_to_world(&b->frame, s.wi);
    *out = s;
    return true;
}

float iir_bsdf_spec_probability(const iir_bsdf *b, iir_vec3 wo)
{
    return spec_probability_local(b, iir_frame_to_local(&b->frame, wo));
}

iir_vec3 iir_bsdf_albedo(const iir_bsdf *b)
{
    return b->c_diff;
}

void iir_bsdf_describe(const iir_bsdf *b, char *buf, size_t n)
{
    if (n == 0) return;
    snprintf(buf, n,
             "bsdf{n=(%.3f %.3f %.3f) base=(%.3f %.3f %.3f) metallic=%.3f alpha=%.4g%s "
             "f0=(%.3f %.3f %.3f) c_diff=(%.3f %.3f %.3f)}",
             (double)b->frame.f.x, (double)b->frame.f.y, (double)b->frame.f.z,
             (double)b->base_color.x, (double)b->base_color.y, (double)b->base_color.z,
             (double)b->metallic, (double)b->alpha, is_delta(b) ? " delta" : "", (double)b->f0.x,
             (double)b->f0.y, (double)b->f0.z, (double)b->c_diff.x, (double)b->c_diff.y,
             (double)b->c_diff.z);
}

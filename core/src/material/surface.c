/* surface.c -- a material evaluated at a hit: barycentric interpolation of the vertex attributes,
 * texture lookups (base colour, metallic-roughness, emission, normal map) and the shading frame,
 * the BSDF made from them, and alpha coverage for cut-outs. The one place that reads
 * iir_material's fields for rendering; not loading (scene_*.c), not the BSDF's optics (bsdf.c), not
 * texture filtering (texture.c). */
#include "surface.h"

#include <math.h>

#include "specular.h"

/* ======================== interpolation ======================== */

typedef struct tri_verts {
    uint32_t i[3];
    float w[3]; /* barycentric weights of the three vertices */
} tri_verts;

static tri_verts tri_at(const iir_scene *s, const iir_hit *hit)
{
    const uint32_t *idx = &s->indices[3 * (size_t)hit->prim];
    tri_verts t = {{idx[0], idx[1], idx[2]}, {1.f - hit->u - hit->v, hit->u, hit->v}};
    return t;
}

static inline iir_vec3 lerp3(const iir_vec3 *a, const tri_verts *t)
{
    return iir_add(iir_add(iir_scale(a[t->i[0]], t->w[0]), iir_scale(a[t->i[1]], t->w[1])),
                   iir_scale(a[t->i[2]], t->w[2]));
}

static inline iir_vec2 lerp2(const iir_vec2 *a, const tri_verts *t)
{
    iir_vec2 r = {0.f, 0.f};
    for (int k = 0; k < 3; k++) {
        r.x += a[t->i[k]].x * t->w[k];
        r.y += a[t->i[k]].y * t->w[k];
    }
    return r;
}

/* ======================== textures ======================== */

static bool has_tex(const iir_texref *r)
{
    return r->texture != 0;
}

/* The texel value of r at uv over a footprint of `width` uv units (0: finest level). */
static iir_rgba tex_at(const iir_scene *s, const iir_texref *r, iir_vec2 uv, float width)
{
    const iir_texture *t = s->textures[r->texture - 1];
    iir_vec2 st = iir_tex_transform_apply(&r->transform, uv);
    width = iir_tex_transform_width(&r->transform, width);
    return width > 0.f ? iir_texture_sample(t, &r->sampler, st, width)
                       : iir_texture_bilinear(t, &r->sampler, st, 0);
}

static iir_vec3 rgb(iir_rgba c)
{
    return iir_v3(c.r, c.g, c.b);
}

/* World units to uv units at triangle prim: sqrt(uv area / world area). */
static float uv_per_world(const iir_scene *s, const tri_verts *t, uint32_t prim)
{
    const iir_vec2 *uv = s->texcoords;
    iir_vec2 a = uv[t->i[0]], b = uv[t->i[1]], c = uv[t->i[2]];
    float uv_area = 0.5f * fabsf((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y));
    return s->areas[prim] > 0.f ? sqrtf(uv_area / s->areas[prim]) : 0.f;
}

/* ======================== shading frame ======================== */

/* The tangent at the hit: the file's (interpolated), else dp/du of the triangle's texture
 * coordinates; w the handedness. False when neither exists (no uv gradient). */
static bool tangent_at(const iir_scene *s, const tri_verts *t, iir_vec3 *T, float *w)
{
    if (s->tangents) {
        iir_vec3 acc = iir_v3s(0.f);
        float hw = 0.f;
        for (int k = 0; k < 3; k++) {
            const float *tk = &s->tangents[4 * (size_t)t->i[k]];
            acc = iir_madd(acc, iir_v3(tk[0], tk[1], tk[2]), t->w[k]);
            hw += tk[3] * t->w[k];
        }
        if (iir_length_sq(acc) > 0.f) {
            *T = acc;
            *w = hw < 0.f ? -1.f : 1.f;
            return true;
        }
    }
    iir_vec3 p0 = s->positions[t->i[0]];
    iir_vec3 dp1 = iir_sub(s->positions[t->i[1]], p0), dp2 = iir_sub(s->positions[t->i[2]], p0);
    iir_vec2 uv0 = s->texcoords[t->i[0]], uv1 = s->texcoords[t->i[1]], uv2 = s->texcoords[t->i[2]];
    float du1 = uv1.x - uv0.x, dv1 = uv1.y - uv0.y, du2 = uv2.x - uv0.x, dv2 = uv2.y - uv0.y;
    float det = du1 * dv2 - du2 * dv1;
    if (fabsf(det) < 1e-20f) return false;
    /* dp/du and dp/dv; glTF's bitangent points up the image, towards -v */
    iir_vec3 dpdu = iir_scale(iir_sub(iir_scale(dp1, dv2), iir_scale(dp2, dv1)), 1.f / det);
    iir_vec3 dpdv = iir_scale(iir_sub(iir_scale(dp2, du1), iir_scale(dp1, du2)), 1.f / det);
    *T = dpdu;
    *w = iir_dot(iir_cross(iir_normalize(iir_cross(dp1, dp2)), dpdu), iir_neg(dpdv)) < 0.f ? -1.f
                                                                                           : 1.f;
    return true;
}

/* N perturbed by the normal map (tangent space, +x along T, +y along B = w N x T, +z along N). */
static iir_vec3 apply_normal_map(const iir_scene *s, const iir_material *m, const tri_verts *t,
                                 iir_vec3 N, iir_vec2 uv, float width)
{
    iir_vec3 T;
    float w;
    if (!tangent_at(s, t, &T, &w)) return N;
    T = iir_sub(T, iir_scale(N, iir_dot(N, T))); /* Gram-Schmidt against the shading normal */
    if (iir_length_sq(T) < 1e-20f) return N;
    T = iir_normalize(T);
    iir_vec3 B = iir_scale(iir_cross(N, T), w);
    iir_vec3 c = rgb(tex_at(s, &m->normal_tex, uv, width));
    float x = (2.f * c.x - 1.f) * m->normal_scale, y = (2.f * c.y - 1.f) * m->normal_scale;
    float z = 2.f * c.z - 1.f;
    iir_vec3 n = iir_add(iir_add(iir_scale(T, x), iir_scale(B, y)), iir_scale(N, z));
    return iir_length_sq(n) > 0.f ? iir_normalize(n) : N;
}

/* The shading normal turned to wo's side and kept at least ~1 degree above wo's horizon, so a
 * normal map never shows the back of a surface. */
static iir_vec3 face_wo(iir_vec3 sn, iir_vec3 ns, iir_vec3 wo)
{
    if (iir_dot(sn, ns) < 0.f) sn = iir_neg(sn);
    float c = iir_dot(sn, wo);
    const float min_cos = 0.02f;
    if (c >= min_cos) return sn;
    /* bend towards wo: sn + a wo with (sn + a wo).wo = min_cos |sn + a wo|, approximately */
    iir_vec3 bent = iir_normalize(iir_madd(sn, wo, min_cos - c));
    return iir_dot(bent, wo) > 0.f ? bent : ns;
}

/* ======================== the material at a point ======================== */

static void eval_material(const iir_scene *s, iir_surface *sf, float width)
{
    const iir_material *m = sf->mat;
    sf->base = m->albedo;
    sf->metallic = m->kind == IIR_MATERIAL_METAL_ROUGH ? m->metallic : 0.f;
    sf->roughness = m->kind == IIR_MATERIAL_METAL_ROUGH ? m->roughness : 1.f;
    sf->specular_f0 = m->specular_f0;
    sf->Le = m->emission;
    sf->specular = m->specular;
    sf->ior = m->ior;
    if (!s->texcoords) return;
    if (has_tex(&m->base_tex))
        sf->base = iir_mul(sf->base, rgb(tex_at(s, &m->base_tex, sf->uv, width)));
    if (has_tex(&m->mr_tex) && m->kind == IIR_MATERIAL_METAL_ROUGH) {
        iir_rgba c = tex_at(s, &m->mr_tex, sf->uv, width);
        sf->roughness *= c.g;
        sf->metallic *= c.b;
    }
    if (has_tex(&m->emission_tex))
        sf->Le = iir_mul(sf->Le, rgb(tex_at(s, &m->emission_tex, sf->uv, width)));
}

static inline iir_surface surface_at(const iir_scene *s, const iir_hit *hit, iir_vec3 wo,
                                     float width)
{
    tri_verts t = tri_at(s, hit);
    iir_surface sf;
    sf.p = lerp3(s->positions, &t);
    sf.n = s->normals[hit->prim];
    sf.ns = iir_dot(sf.n, wo) < 0.f ? iir_neg(sf.n) : sf.n;
    sf.mat = &s->material_list[s->materials[hit->prim]];
    sf.kind = sf.mat->kind;
    sf.specular_depth = sf.kind == IIR_MATERIAL_GLASS ? 2 : sf.kind == IIR_MATERIAL_MIRROR;
    sf.uv = s->texcoords ? lerp2(s->texcoords, &t) : iir_v2(0.f, 0.f);
    float uv_width = width > 0.f && s->texcoords ? width * uv_per_world(s, &t, hit->prim) /
                                                       fmaxf(fabsf(iir_dot(sf.n, wo)), 0.05f)
                                                 : 0.f;
    eval_material(s, &sf, uv_width);
    sf.albedo = iir_surface_is_rough(&sf) ? iir_scale(sf.base, 1.f - sf.metallic) : iir_v3s(0.f);
    iir_vec3 N = sf.n;
    if (s->vertex_normals) {
        iir_vec3 vn = lerp3(s->vertex_normals, &t);
        if (iir_length_sq(vn) > 1e-12f) N = iir_normalize(vn);
        if (iir_dot(N, sf.n) < 0.f) N = iir_neg(N); /* winding side, as n */
    }
    if (s->texcoords && has_tex(&sf.mat->normal_tex))
        N = apply_normal_map(s, sf.mat, &t, N, sf.uv, uv_width);
    sf.sn = (N.x == sf.n.x && N.y == sf.n.y && N.z == sf.n.z) ? sf.ns : face_wo(N, sf.ns, wo);
    return sf;
}

iir_surface iir_surface_at(const iir_scene *s, const iir_hit *hit, iir_vec3 wo)
{
    return surface_at(s, hit, wo, 0.f);
}

iir_surface iir_surface_at_cone(const iir_scene *s, const iir_hit *hit, iir_vec3 wo, float width)
{
    return surface_at(s, hit, wo, width);
}

static iir_surface front_at(const iir_scene *s, uint32_t prim, float u, float v)
{
    iir_hit hit = {0.f, prim, u, v};
    return surface_at(s, &hit, s->normals[prim], 0.f);
}

iir_vec3 iir_surface_albedo_at(const iir_scene *s, uint32_t prim, float u, float v)
{
    return front_at(s, prim, u, v).albedo;
}

iir_vec3 iir_surface_emission_at(const iir_scene *s, uint32_t prim, float u, float v)
{
    const iir_material *m = &s->material_list[s->materials[prim]];
    if (!m->emission_tex.texture || !s->texcoords) return m->emission;
    iir_hit hit = {0.f, prim, u, v};
    tri_verts t = tri_at(s, &hit);
    return iir_mul(m->emission, rgb(tex_at(s, &m->emission_tex, lerp2(s->texcoords, &t), 0.f)));
}

/* ======================== the BSDF ======================== */

iir_bsdf iir_surface_bsdf(const iir_surface *sf)
{
    switch (sf->kind) {
    case IIR_MATERIAL_METAL_ROUGH:
        return iir_bsdf_make_f0(sf->sn, sf->base, sf->metallic, sf->roughness, sf->specular_f0);
    case IIR_MATERIAL_DIFFUSE:
        return iir_bsdf_make_lambert(sf->sn, sf->albedo);
    case IIR_MATERIAL_MIRROR:
    case IIR_MATERIAL_GLASS:
        break;
    }
    return iir_bsdf_make_lambert(sf->sn, iir_v3s(0.f));
}

/* ======================== coverage ======================== */

bool iir_scene_has_blend(const iir_scene *s)
{
    for (uint32_t i = 0; i < s->num_materials; i++)
        if (s->material_list[i].alpha_mode == IIR_ALPHA_BLEND) return true;
    return false;
}

bool iir_scene_has_cutouts(const iir_scene *s)
{
    for (uint32_t i = 0; i < s->num_materials; i++)
        if (iir_material_has_cutout(&s->material_list[i])) return true;
    return false;
}

float iir_surface_alpha(const iir_scene *s, uint32_t prim, float u, float v)
{
    const iir_material *m = &s->material_list[s->materials[prim]];
    float alpha = m->opacity;
    if (s->texcoords && has_tex(&m->base_tex)) {
        iir_hit hit = {0.f, prim, u, v};
        tri_verts t = tri_at(s, &hit);
        alpha *= tex_at(s, &m->base_tex, lerp2(s->texcoords, &t), 0.f).a;
    }
    return alpha;
}

bool iir_surface_blends(const iir_scene *s, uint32_t prim)
{
    return s->material_list[s->materials[prim]].alpha_mode == IIR_ALPHA_BLEND;
}

bool iir_surface_covers(const iir_scene *s, uint32_t prim, float u, float v)
{
    const iir_material *m = &s->material_list[s->materials[prim]];
    if (!iir_material_has_cutout(m)) return true;
    float cutoff = m->alpha_mode == IIR_ALPHA_MASK ? m->alpha_cutoff : 0.5f;
    return iir_surface_alpha(s, prim, u, v) >= cutoff;
}

bool iir_surface_mirror_reflection(const iir_surface *sf, iir_vec3 V, iir_vec3 *wi, iir_vec3 *F)
{
    if (sf->kind != IIR_MATERIAL_METAL_ROUGH || !(sf->roughness < IIR_MIRROR_ROUGHNESS))
        return false;
    *F = iir_fresnel_schlick(iir_surface_bsdf(sf).f0, fabsf(iir_dot(V, sf->sn)));
    *wi = iir_reflect(V, sf->sn);
    return iir_dot(*wi, sf->ns) > 0.f;
}

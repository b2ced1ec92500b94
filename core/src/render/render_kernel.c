/* render_kernel.c -- the scalar shadow-map kernel of the VPL sum (render_batch.h), the reference
 * the vector kernels are tested against, and the choice of kernel by instruction set. */
#include "render_batch.h"

#include <assert.h>

static void apply_one(const iir_kernel_args *a, const iir_shade_vpl *v, iir_pixel_batch *b)
{
    iir_smap_probe probe = iir_smap_probe_make(v->smap, a->rel_bias, a->eps);
    for (int j = 0; j < b->m; j++) {
        iir_vec3 x = iir_v3(b->px[j], b->py[j], b->pz[j]), n = iir_v3(b->nx[j], b->ny[j], b->nz[j]);
        iir_vpl_geometry g = iir_vpl_geometry_at(v, x, n, a->g_max);
        if (!g.lit) continue;
        float V = iir_smap_probe_visibility(&probe, iir_dot(g.w, v->r), iir_dot(g.w, v->u), g.ci,
                                            sqrtf(g.d2), g.cx);
        if (v->glossy || iir_batch_is_glossy(b, j)) {
            iir_batch_add_lit(b, j, v, g.G * V, a->g_max);
            continue;
        }
        b->Ex[j] += v->power.x * (g.G * V);
        b->Ey[j] += v->power.y * (g.G * V);
        b->Ez[j] += v->power.z * (g.G * V);
    }
}

void iir_apply_smap_scalar(const iir_kernel_args *a, const iir_shade_vpl *v, const iir_gv_ref *gv,
                           uint32_t count, iir_pixel_batch *b)
{
    assert(!gv && "the scalar kernel takes no columns");
    (void)gv;
    for (uint32_t i = 0; i < count; i++) apply_one(a, &v[i], b);
}

void iir_batch_glossy_lanes(const iir_kernel_args *a, const iir_shade_vpl *v, iir_pixel_batch *b,
                            int j, float *g, int lanes)
{
    for (int l = 0; l < lanes; l++)
        if (v->glossy || iir_batch_is_glossy(b, j + l))
            iir_batch_add_lit(b, j + l, v, g[l], a->g_max), g[l] = 0.f;
}

iir_smap_kernel iir_smap_kernel_for(iir_isa isa)
{
    switch (isa) {
#if defined(__x86_64__)
    case IIR_ISA_AVX2:
        return iir_apply_smap_avx2;
    case IIR_ISA_SSE2:
        return iir_apply_smap_sse2;
#endif
    default:
        return iir_apply_smap_scalar;
    }
}

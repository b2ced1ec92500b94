/* solve.c -- the radiosity equation's solvers, B_i = E_i + rho_i sum_j F_ij B_j per RGB channel:
 * Gauss elimination (dense, small systems), Gauss-Seidel sweeps, and progressive refinement
 * (shooting, Cohen et al. 1988) with its ambient term. Not E (the method shoots direct light). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "radiosity.h"

static float comp(iir_vec3 v, int c)
{
    return c == 0 ? v.x : c == 1 ? v.y : v.z;
}
static void set_comp(iir_vec3 *v, int c, float x)
{
    if (c == 0)
        v->x = x;
    else if (c == 1)
        v->y = x;
    else
        v->z = x;
}

/* ---- Gauss elimination ---- */

/* Solves the dense n x n system a x = b in place (partial pivoting): IIR_ERR_INVALID when
 * singular, IIR_ERR_INTERRUPTED once stop says stop (polled per pivot: n^2 operations). */
static iir_status gauss_dense(double *a, double *b, uint32_t n, const iir_stop *stop)
{
    for (uint32_t k = 0; k < n; k++) {
        if (iir_stop_now(stop)) return IIR_ERR_INTERRUPTED;
        uint32_t p = k;
        for (uint32_t i = k + 1; i < n; i++)
            if (fabs(a[(size_t)i * n + k]) > fabs(a[(size_t)p * n + k])) p = i;
        if (fabs(a[(size_t)p * n + k]) < 1e-12) return IIR_ERR_INVALID;
        if (p != k) {
            for (uint32_t j = 0; j < n; j++) {
                double t = a[(size_t)k * n + j];
                a[(size_t)k * n + j] = a[(size_t)p * n + j], a[(size_t)p * n + j] = t;
            }
            double t = b[k];
            b[k] = b[p], b[p] = t;
        }
        for (uint32_t i = k + 1; i < n; i++) {
            if ((i - k) % 512 == 0 && iir_stop_now(stop)) return IIR_ERR_INTERRUPTED;
            double f = a[(size_t)i * n + k] / a[(size_t)k * n + k];
            if (f == 0.0) continue;
            for (uint32_t j = k; j < n; j++) a[(size_t)i * n + j] -= f * a[(size_t)k * n + j];
            b[i] -= f * b[k];
        }
    }
    for (uint32_t i = n; i-- > 0;) {
        double s = b[i];
        for (uint32_t j = i + 1; j < n; j++) s -= a[(size_t)i * n + j] * b[j];
        b[i] = s / a[(size_t)i * n + i];
    }
    return IIR_OK;
}

iir_status rad_solve_gauss(const rad_ff *ff, const iir_vec3 *rho, const iir_vec3 *E, iir_vec3 *B,
                           const iir_stop *stop, iir_error *err)
{
    const uint32_t n = ff->n;
    double *a = malloc((size_t)n * n * sizeof *a), *b = malloc((n ? n : 1) * sizeof *b);
    if (!a || !b) {
        free(a), free(b);
        return iir_fail(err, IIR_ERR_NOMEM, "radiosity: out of memory for Gauss (%u patches)", n);
    }
    for (int c = 0; c < 3; c++) {
        /* (I - rho F) B = E */
        iir_status st = IIR_OK;
        for (uint32_t i = 0; st == IIR_OK && i < n; i++) {
            if (i % 256 == 0 && iir_stop_now(stop)) st = IIR_ERR_INTERRUPTED;
            memset(a + (size_t)i * n, 0, n * sizeof *a);
            a[(size_t)i * n + i] = 1.0;
            for (uint64_t k = ff->row[i]; k < ff->row[i + 1]; k++)
                a[(size_t)i * n + ff->col[k]] -= (double)comp(rho[i], c) * ff->val[k];
            b[i] = comp(E[i], c);
        }
        if (st == IIR_OK) st = gauss_dense(a, b, n, stop);
        if (st != IIR_OK) {
            free(a), free(b);
            return st == IIR_ERR_INTERRUPTED
                       ? iir_fail(err, st, "radiosity: solve stopped")
                       : iir_fail(err, st, "radiosity: singular system (rho = 1?)");
        }
        for (uint32_t i = 0; i < n; i++) set_comp(&B[i], c, (float)b[i]);
    }
    free(a), free(b);
    return IIR_OK;
}

/* ---- Gauss-Seidel ---- */

/* sum_j F_ij B_j */
static iir_vec3 gather(const rad_ff *ff, uint32_t i, const iir_vec3 *B)
{
    iir_vec3 s = iir_v3s(0.f);
    for (uint64_t k = ff->row[i]; k < ff->row[i + 1]; k++)
        s = iir_madd(s, B[ff->col[k]], ff->val[k]);
    return s;
}

/* Rows of a sweep between two looks at the stop hook. */
enum { STOP_ROWS = 256 };

int rad_solve_gauss_seidel(const rad_ff *ff, const iir_vec3 *rho, const iir_vec3 *E, iir_vec3 *B,
                           int max_iter, float tol, bool warm, const iir_stop *stop)
{
    const uint32_t n = ff->n;
    if (!warm) memcpy(B, E, n * sizeof *B);
    int it = 0;
    while (it < max_iter) {
        float change = 0.f, big = 0.f;
        for (uint32_t i = 0; i < n; i++) {
            if (i % STOP_ROWS == 0 && iir_stop_now(stop)) return -1;
            iir_vec3 b = iir_add(E[i], iir_mul(rho[i], gather(ff, i, B)));
            change = fmaxf(change, iir_max_comp(iir_sub(b, B[i])));
            change = fmaxf(change, iir_max_comp(iir_sub(B[i], b)));
            big = fmaxf(big, iir_max_comp(b));
            B[i] = b;
        }
        it++;
        if (change <= tol * big) break;
    }
    return it;
}

/* ---- progressive refinement ---- */

/* t = the transpose of f (columns ascend within t's rows): IIR_ERR_NOMEM, or IIR_ERR_INTERRUPTED
 * (t empty) once stop says stop. */
static iir_status transpose(rad_ff *t, const rad_ff *f, const iir_stop *stop)
{
    t->n = f->n, t->nnz = f->nnz;
    t->row = calloc((size_t)f->n + 1, sizeof *t->row);
    t->col = malloc((f->nnz ? f->nnz : 1) * sizeof *t->col);
    t->val = malloc((f->nnz ? f->nnz : 1) * sizeof *t->val);
    uint64_t *fill = calloc((size_t)f->n + 1, sizeof *fill);
    bool ok = t->row && t->col && t->val && fill;
    for (uint64_t k = 0; ok && k < f->nnz; k++) t->row[f->col[k] + 1]++;
    for (uint32_t j = 0; ok && j < f->n; j++) t->row[j + 1] += t->row[j], fill[j] = t->row[j];
    bool stopped = false;
    for (uint32_t i = 0; ok && !stopped && i < f->n; i++) {
        stopped = i % STOP_ROWS == 0 && iir_stop_now(stop);
        for (uint64_t k = f->row[i]; !stopped && k < f->row[i + 1]; k++) {
            uint64_t q = fill[f->col[k]]++;
            t->col[q] = i, t->val[q] = f->val[k];
        }
    }
    free(fill);
    if (!ok || stopped) rad_ff_free(t);
    return !ok ? IIR_ERR_NOMEM : stopped ? IIR_ERR_INTERRUPTED : IIR_OK;
}

iir_status rad_progressive_init(rad_progressive *p, const rad_mesh *m, const rad_ff *ff,
                                const iir_vec3 *E, iir_vec3 *B, const iir_stop *stop)
{
    const uint32_t n = m->num_patches;
    rad_ff Ft = p->Ft;
    free(p->dB);
    memset(p, 0, sizeof *p);
    p->Ft = Ft;
    iir_status st = p->Ft.row ? IIR_OK : transpose(&p->Ft, ff, stop);
    if (st != IIR_OK) return st;
    p->dB = malloc((n ? n : 1) * sizeof *p->dB);
    if (!p->dB) return IIR_ERR_NOMEM;
    memcpy(p->dB, E, n * sizeof *E);
    memcpy(B, E, n * sizeof *E);
    double rho_a[3] = {0, 0, 0};
    for (uint32_t i = 0; i < n; i++) {
        p->area_total += m->area[i];
        p->emitted += (double)iir_luminance(E[i]) * m->area[i];
        for (int c = 0; c < 3; c++) rho_a[c] += (double)comp(m->rho[i], c) * m->area[i];
    }
    for (int c = 0; c < 3; c++)
        p->rho_avg[c] = p->area_total > 0 ? (float)(rho_a[c] / p->area_total) : 0.f;
    return IIR_OK;
}

void rad_progressive_free(rad_progressive *p)
{
    free(p->dB);
    rad_ff_free(&p->Ft);
    memset(p, 0, sizeof *p);
}

/* The patch with the most unshot power dB_i A_i (luminance); its power in *power. */
static uint32_t brightest(const rad_progressive *p, const rad_mesh *m, double *power)
{
    uint32_t best = 0;
    double big = -1.0, total = 0.0;
    for (uint32_t i = 0; i < m->num_patches; i++) {
        double w = (double)iir_luminance(p->dB[i]) * m->area[i];
        total += w;
        if (w > big) big = w, best = i;
    }
    *power = total;
    return best;
}

bool rad_progressive_shoot(rad_progressive *p, const rad_mesh *m, iir_vec3 *B, int shots, float tol,
                           const iir_stop *stop, bool *stopped)
{
    double unshot = 0.0;
    *stopped = false;
    for (int s = 0; s < shots; s++) {
        if (iir_stop_now(stop)) {
            *stopped = true;
            return false;
        }
        uint32_t i = brightest(p, m, &unshot);
        if (unshot <= (double)tol * p->emitted || m->num_patches == 0) return true;
        const iir_vec3 dBi = p->dB[i];
        p->dB[i] = iir_v3s(0.f);
        for (uint64_t k = p->Ft.row[i]; k < p->Ft.row[i + 1]; k++) {
            uint32_t j = p->Ft.col[k];
            iir_vec3 dRad = iir_scale(iir_mul(m->rho[j], dBi), p->Ft.val[k]); /* rho_j F_ji dB_i */
            p->dB[j] = iir_add(p->dB[j], dRad);
            B[j] = iir_add(B[j], dRad);
        }
        p->shots++;
    }
    brightest(p, m, &unshot);
    return unshot <= (double)tol * p->emitted;
}

iir_vec3 rad_progressive_ambient(const rad_progressive *p, const rad_mesh *m)
{
    /* ambient = R sum_j dB_j A_j / A_total, R = 1 / (1 - rho_avg) (the interreflection factor) */
    double s[3] = {0, 0, 0};
    for (uint32_t j = 0; j < m->num_patches; j++)
        for (int c = 0; c < 3; c++) s[c] += (double)comp(p->dB[j], c) * m->area[j];
    iir_vec3 a;
    for (int c = 0; c < 3; c++) {
        double R = 1.0 / fmax(1e-3, 1.0 - (double)p->rho_avg[c]);
        set_comp(&a, c, p->area_total > 0 ? (float)(R * s[c] / p->area_total) : 0.f);
    }
    return a;
}

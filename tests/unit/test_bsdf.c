/* test_bsdf.c -- glTF's metallic-roughness BRDF (iir/bsdf.h): reciprocity; the directional albedo
 * by importance sampling against a quadrature, and its bound; the white furnace of the GGX lobe
 * (single-scattering loss); sampling against the pdf (chi-square); the pdf's integral against the
 * fraction of samples that succeed, and sample_f's f and pdf against iir_bsdf_f and iir_bsdf_pdf;
 * the delta (mirror) lobe; f against appendix B's formulas re-derived here. Prints the figures it
 * measures (for the release note).
 *
 * The quadratures work on the sphere in coordinates (s, phi') about an axis r (the mirror
 * direction of wo): theta' = pi s^3, so cells shrink towards r, where the narrow lobes of small
 * roughness sit (a lobe of roughness 0.1 is about 0.02 rad wide). The chi-square test bins the
 * samples in the same coordinates: bins uniform in (cos theta, phi) would put such a lobe in one
 * cell. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>

#include "iir/bsdf.h"
#include "iir/isa.h"
#include "iir/rng.h"
#include "sampling.h"

#define PI_D 3.14159265358979323846

/* A normal off the axes, so the frame code is exercised. */
static iir_vec3 test_normal(void)
{
    return iir_normalize(iir_v3(0.3f, -0.4f, 0.866f));
}

/* The world direction at polar angle theta (radians) and azimuth phi in b's shading frame. */
static iir_vec3 dir_at(const iir_bsdf *b, double theta, double phi)
{
    iir_vec3 l =
        iir_v3((float)(sin(theta) * cos(phi)), (float)(sin(theta) * sin(phi)), (float)cos(theta));
    return iir_frame_to_world(&b->frame, l);
}

static double dot_d(iir_vec3 a, iir_vec3 b)
{
    return (double)a.x * b.x + (double)a.y * b.y + (double)a.z * b.z;
}

static double rel_diff(double a, double b)
{
    double m = fmax(fabs(a), fabs(b));
    return m > 0.0 ? fabs(a - b) / m : 0.0;
}

static double rel_diff3(iir_vec3 a, iir_vec3 b)
{
    return fmax(rel_diff(a.x, b.x), fmax(rel_diff(a.y, b.y), rel_diff(a.z, b.z)));
}

/* ===================== quadrature on the sphere about an axis ===================== */

/* The direction at (s, phi') about the frame's f, theta' = pi s^3; *jac = d(omega) / (ds dphi'). */
static iir_vec3 about_axis(const iir_frame *ax, double s, double phi, double *jac)
{
    double theta = PI_D * s * s * s;
    *jac = sin(theta) * 3.0 * PI_D * s * s;
    iir_vec3 l =
        iir_v3((float)(sin(theta) * cos(phi)), (float)(sin(theta) * sin(phi)), (float)cos(theta));
    return iir_frame_to_world(ax, l);
}

/* The cell coordinates (s, phi') of unit w about the frame's f. */
static void axis_coords(const iir_frame *ax, iir_vec3 w, double *s, double *phi)
{
    iir_vec3 l = iir_frame_to_local(ax, w);
    double theta = atan2(hypot(l.x, l.y), l.z);
    *s = cbrt(theta / PI_D);
    *phi = atan2(l.y, l.x);
    if (*phi < 0.0) *phi += 2.0 * PI_D;
}

typedef double (*sphere_fn)(iir_vec3 w, const void *ctx);

/* The sphere about an axis (ax.f), for integrands that vanish below the horizon of the normal n
 * (ax.f above it). */
typedef struct sphere {
    iir_frame ax;
    iir_vec3 n;
} sphere;

/* Where the arc at azimuth phi' about the axis meets the horizon, as s: along it w.n =
 * A sin(theta') + B cos(theta') with A = cos(phi') ax.r.n + sin(phi') ax.u.n and B = ax.f.n > 0,
 * which is 0 at theta' = pi - atan2(B, A). */
static double horizon_s(const sphere *sp, double phi)
{
    double A = cos(phi) * dot_d(sp->ax.r, sp->n) + sin(phi) * dot_d(sp->ax.u, sp->n);
    double B = dot_d(sp->ax.f, sp->n);
    assert_true(B > 0.0);
    return cbrt((PI_D - atan2(B, A)) / PI_D);
}

/* The integral of g over the part [s0, s1] x [phi0, phi1] of the sphere about the axis, by the
 * midpoint rule on nphi azimuths and ns points along each, the arcs cut at the horizon (so the
 * integrand's jump there costs no accuracy). */
static double integrate_cell(const sphere *sp, sphere_fn g, const void *ctx, double s0, double s1,
                             double phi0, double phi1, int ns, int nphi)
{
    double dphi = (phi1 - phi0) / nphi, sum = 0.0;
    for (int j = 0; j < nphi; j++) {
        double phi = phi0 + (j + 0.5) * dphi, s_top = fmin(s1, horizon_s(sp, phi));
        if (s_top <= s0) continue;
        double ds = (s_top - s0) / ns, arc = 0.0;
        for (int i = 0; i < ns; i++) {
            double jac;
            iir_vec3 w = about_axis(&sp->ax, s0 + (i + 0.5) * ds, phi, &jac);
            arc += g(w, ctx) * jac;
        }
        sum += arc * ds;
    }
    return sum * dphi;
}

/* The integral of g over the upper hemisphere of n, about axis r, at two resolutions: *q on
 * 2ns x 2nphi points and *err = |*q - the same on ns x nphi|, a bound on the error of the coarser,
 * so (at least) on the finer. */
static void integrate_hemisphere(iir_vec3 n, iir_vec3 r, sphere_fn g, const void *ctx, int ns,
                                 int nphi, double *q, double *err)
{
    sphere sp = {iir_frame_from_normal(r), n};
    double coarse = integrate_cell(&sp, g, ctx, 0.0, 1.0, 0.0, 2.0 * PI_D, ns, nphi);
    *q = integrate_cell(&sp, g, ctx, 0.0, 1.0, 0.0, 2.0 * PI_D, 2 * ns, 2 * nphi);
    *err = fabs(*q - coarse);
}

/* The mirror direction of wo about b's normal: the axis of the quadratures. */
static iir_vec3 mirror_of(const iir_bsdf *b, iir_vec3 wo)
{
    iir_vec3 n = b->frame.f;
    return iir_normalize(iir_sub(iir_scale(n, 2.f * iir_dot(wo, n)), wo));
}

typedef struct at_wo {
    const iir_bsdf *b;
    iir_vec3 wo;
} at_wo;

/* f(wo, w).x cos(theta): the albedo's integrand (red; a white base makes the channels equal). */
static double f_cos(iir_vec3 w, const void *ctx)
{
    const at_wo *a = ctx;
    double cos_i = iir_dot(w, a->b->frame.f);
    return cos_i > 0.0 ? iir_bsdf_f(a->b, a->wo, w).x * cos_i : 0.0;
}

static double pdf_at(iir_vec3 w, const void *ctx)
{
    const at_wo *a = ctx;
    return iir_bsdf_pdf(a->b, a->wo, w);
}

/* ===================== the directional albedo by importance sampling ===================== */

typedef struct estimate {
    double mean, sigma; /* sigma: the standard error of the mean */
} estimate;

/* E(wo) = int f cos d(omega_i) (red channel) from n samples of iir_bsdf_sample_f; a failed sample
 * counts 0. */
static estimate albedo_mc(const iir_bsdf *b, iir_vec3 wo, int n, uint64_t seed)
{
    iir_rng rng = iir_rng_make(seed, 1);
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < n; i++) {
        iir_bsdf_sample s;
        float uc = iir_rng_uniform(&rng);
        if (!iir_bsdf_sample_f(b, wo, uc, iir_rng_uniform2(&rng), &s)) continue;
        double x = s.f.x * fabs(iir_dot(s.wi, b->frame.f)) / s.pdf;
        sum += x;
        sum2 += x * x;
    }
    estimate e;
    e.mean = sum / n;
    double var = fmax(0.0, sum2 / n - e.mean * e.mean);
    e.sigma = sqrt(var / (n - 1));
    return e;
}

/* ============================== 1. reciprocity ============================== */

static void test_reciprocity(void **state)
{
    (void)state;
    const float roughness[] = {0.05f, 0.3f, 0.7f, 1.f}, metallic[] = {0.f, 0.5f, 1.f};
    iir_rng rng = iir_rng_make(11, 0);
    double worst = 0.0;
    for (int r = 0; r < 4; r++) {
        for (int m = 0; m < 3; m++) {
            iir_bsdf b =
                iir_bsdf_make(test_normal(), iir_v3(0.9f, 0.5f, 0.1f), metallic[m], roughness[r]);
            for (int i = 0; i < 20000; i++) {
                double t0 = acos(iir_rng_uniform(&rng)), t1 = acos(iir_rng_uniform(&rng));
                iir_vec3 wo = dir_at(&b, t0, 2.0 * PI_D * iir_rng_uniform(&rng));
                iir_vec3 wi = dir_at(&b, t1, 2.0 * PI_D * iir_rng_uniform(&rng));
                iir_vec3 f = iir_bsdf_f(&b, wo, wi), f_rev = iir_bsdf_f(&b, wi, wo);
                double d = rel_diff3(f, f_rev);
                worst = fmax(worst, d);
                if (d > 1e-5) {
                    printf("f(wo, wi) = (%g %g %g), f(wi, wo) = (%g %g %g), roughness %g\n",
                           (double)f.x, (double)f.y, (double)f.z, (double)f_rev.x, (double)f_rev.y,
                           (double)f_rev.z, (double)roughness[r]);
                    fail();
                }
            }
        }
    }
    printf("reciprocity: max relative |f(wo,wi) - f(wi,wo)| = %.2e over 240000 pairs\n", worst);
}

/* ============================== 2. energy ============================== */

/* The directional albedo of a white base for a grid of roughness, metallic and theta_o: the
 * importance-sampled estimate and the quadrature agree within their errors everywhere, and neither
 * is significantly above 1 where appendix B's model keeps E <= 1: metals (single-scattering GGX) at
 * every angle, every material up to theta_o = 30 degrees. Beyond, a dielectric's diffuse lobe is
 * weighted by 1 - F(v.h), h between wo and each wi, not by one minus the specular lobe's albedo: at
 * grazing view the specular lobe takes F(n.wo) of the light while the diffuse lobe keeps most of
 * its own, so E exceeds 1 (the model's own figure, printed with the cosine-weighted mean 2 int E mu
 * dmu that a closed white furnace sees). */
static void test_energy(void **state)
{
    (void)state;
    const float roughness[] = {0.05f, 0.1f, 0.3f, 0.6f, 1.f}, metallic[] = {0.f, 0.5f, 1.f};
    const float theta_o[] = {0.f, 30.f, 60.f, 85.f};
    enum { N = 100000 };
    double max_bounded = 0.0, max_all = 0.0, worst_agree = 0.0;
    printf("directional albedo E(theta_o), base 1: importance sampling (+- 1 sigma) | quadrature "
           "(+- error)\n");
    for (int m = 0; m < 3; m++) {
        for (int r = 0; r < 5; r++) {
            iir_bsdf b = iir_bsdf_make(test_normal(), iir_v3s(1.f), metallic[m], roughness[r]);
            printf("  metallic %.1f roughness %.2f:", (double)metallic[m], (double)roughness[r]);
            for (int t = 0; t < 4; t++) {
                at_wo a = {&b, dir_at(&b, iir_radians(theta_o[t]), 0.7)};
                estimate e = albedo_mc(&b, a.wo, N, 100 + 20 * m + 4 * r + t);
                double q, q_err;
                integrate_hemisphere(b.frame.f, mirror_of(&b, a.wo), f_cos, &a, 256, 128, &q,
                                     &q_err);
                printf(" %4.1f: %.4f+-%.4f|%.4f+-%.4f", (double)theta_o[t], e.mean, e.sigma, q,
                       q_err);
                double slack = 4.0 * e.sigma + q_err + 1e-4;
                worst_agree = fmax(worst_agree, fabs(e.mean - q) / slack);
                assert_true(fabs(e.mean - q) <= slack);
                max_all = fmax(max_all, e.mean);
                if (metallic[m] == 1.f || theta_o[t] <= 30.f) {
                    max_bounded = fmax(max_bounded, e.mean);
                    /* not significantly above 1 (a smooth metal is 1 - 1e-5: mean + 4 sigma
                     * would exceed it); 1e-5 for f's single precision */
                    assert_true(e.mean - 4.0 * e.sigma <= 1.0 + 1e-5);
                    assert_true(q - q_err <= 1.0 + 1e-5);
                }
            }
            printf("\n");
        }
    }
    printf("energy: max E = %.4f where bounded (metals; theta_o <= 30), %.4f over the grid; "
           "|IS - quadrature| <= %.2f of (4 sigma + quadrature error)\n",
           max_bounded, max_all, worst_agree);
    /* a dielectric's cosine-weighted mean albedo 2 int E(mu) mu dmu, midpoint over mu */
    for (int r = 0; r < 5; r++) {
        iir_bsdf b = iir_bsdf_make(test_normal(), iir_v3s(1.f), 0.f, roughness[r]);
        enum { NMU = 16 };
        double mean = 0.0;
        for (int k = 0; k < NMU; k++) {
            double mu = (k + 0.5) / NMU;
            at_wo a = {&b, dir_at(&b, acos(mu), 0.7)};
            double q, q_err;
            integrate_hemisphere(b.frame.f, mirror_of(&b, a.wo), f_cos, &a, 96, 48, &q, &q_err);
            mean += 2.0 * q * mu / NMU;
        }
        printf("  metallic 0 roughness %.2f: cosine-weighted mean albedo %.4f\n",
               (double)roughness[r], mean);
    }
}

/* ============================== 3. white furnace ============================== */

/* Metallic 1, base 1 (F = 1): the GGX lobe alone; its loss 1 - E(mu) by quadrature and by
 * sampling agree, is positive and grows with roughness; at roughness 0.04 it is below 1% at normal
 * incidence; at roughness 1 head-on it is ln 2 (E = 1 - ln 2 in closed form). */
static void test_white_furnace(void **state)
{
    (void)state;
    const float roughness[] = {0.04f, 0.25f, 0.5f, 0.75f, 1.f};
    const double mu[] = {1.0, 0.5, 0.1};
    double prev[3] = {-1.0, -1.0, -1.0};
    printf("white furnace (metallic 1, base 1): loss 1 - E(mu), quadrature | sampling\n");
    for (int r = 0; r < 5; r++) {
        iir_bsdf b = iir_bsdf_make(test_normal(), iir_v3s(1.f), 1.f, roughness[r]);
        printf("  roughness %.2f:", (double)roughness[r]);
        for (int k = 0; k < 3; k++) {
            at_wo a = {&b, dir_at(&b, acos(mu[k]), 1.9)};
            double q, q_err;
            integrate_hemisphere(b.frame.f, mirror_of(&b, a.wo), f_cos, &a, 256, 128, &q, &q_err);
            estimate e = albedo_mc(&b, a.wo, 100000, 300 + 3 * r + k);
            double loss = 1.0 - q;
            printf("  mu %.1f: %.4f+-%.4f | %.4f+-%.4f", mu[k], loss, q_err, 1.0 - e.mean, e.sigma);
            assert_true(fabs(e.mean - q) <= 4.0 * e.sigma + q_err + 1e-4);
            if (r == 0 && k == 0) assert_true(loss + q_err < 0.01);
            /* alpha = 1, head-on: D = 1/pi, V = 1 / (2 (1 + cos_i)), so E = 1 - ln 2 */
            if (r == 4 && k == 0) assert_true(fabs(q - (1.0 - log(2.0))) < 1e-3);
            if (r > 0) {
                assert_true(loss - q_err > 0.0);
                assert_true(loss - q_err > prev[k]);
            }
            prev[k] = loss + q_err;
        }
        printf("\n");
    }
}

/* ======================= 4 and 5. sampling against the pdf ======================= */

enum { NS = 20, NPHI = 40, SUB = 12, NCASES = 32, NSAMPLES = 200000 };

typedef struct sampling_result {
    float theta_o, roughness, metallic;
    double p_value;                  /* chi-square */
    double pdf_integral;             /* int pdf over the hemisphere (the cells' quadrature) */
    double ok_fraction;              /* sample_f calls that succeeded */
    double max_f_diff, max_pdf_diff; /* relative, sample_f against iir_bsdf_f / iir_bsdf_pdf */
} sampling_result;

/* Q(a, x), the regularised upper incomplete gamma function (Numerical Recipes' series and
 * continued fraction): the chi-square p-value is Q(dof / 2, chi2 / 2). */
static double gamma_q(double a, double x)
{
    if (x <= 0.0) return 1.0;
    double lg = lgamma(a);
    if (x < a + 1.0) {
        double ap = a, sum = 1.0 / a, del = sum;
        for (int n = 0; n < 1000 && fabs(del) > fabs(sum) * 1e-15; n++) {
            ap += 1.0;
            del *= x / ap;
            sum += del;
        }
        return 1.0 - sum * exp(-x + a * log(x) - lg);
    }
    double b = x + 1.0 - a, c = 1e300, d = 1.0 / b, h = d;
    for (int i = 1; i < 1000; i++) {
        double an = -i * (i - a);
        b += 2.0;
        d = an * d + b;
        if (fabs(d) < 1e-300) d = 1e-300;
        c = b + an / c;
        if (fabs(c) < 1e-300) c = 1e-300;
        d = 1.0 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1.0) < 1e-15) break;
    }
    return exp(-x + a * log(x) - lg) * h;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The chi-square p-value of observed counts against expected ones (pbrt-v3's chi2test): cells are
 * taken in increasing expected count; those expecting fewer than 5 are pooled into one; a cell
 * expecting 0 that got more than 1e-5 n samples makes the p-value 0. */
static double chi2_p_value(const double *observed, const double *expected, int cells, int n)
{
    double *pairs = malloc(sizeof(double) * 2 * cells);
    for (int i = 0; i < cells; i++) {
        pairs[2 * i] = expected[i];
        pairs[2 * i + 1] = observed[i];
    }
    qsort(pairs, cells, 2 * sizeof(double), cmp_double);
    double chi2 = 0.0, pooled_obs = 0.0, pooled_exp = 0.0;
    int dof = 0, pooled = 0;
    bool impossible = false;
    for (int i = 0; i < cells; i++) {
        double e = pairs[2 * i], o = pairs[2 * i + 1];
        if (e == 0.0) {
            impossible |= o > 1e-5 * n;
        } else if (e < 5.0 || (pooled_exp > 0.0 && pooled_exp < 5.0)) {
            pooled_obs += o;
            pooled_exp += e;
            pooled++;
        } else {
            chi2 += (o - e) * (o - e) / e;
            dof++;
        }
    }
    free(pairs);
    if (pooled > 0) {
        chi2 += (pooled_obs - pooled_exp) * (pooled_obs - pooled_exp) / pooled_exp;
        dof++;
    }
    dof--;
    if (impossible || dof < 1) return impossible ? 0.0 : 1.0;
    return gamma_q(0.5 * dof, 0.5 * chi2);
}

/* One case: NSAMPLES samples binned about the mirror direction, the expected counts from the pdf
 * integrated over each cell, and every sample's f and pdf against the evaluation functions. */
static sampling_result run_sampling_case(float theta_o, float roughness, float metallic,
                                         uint64_t seed)
{
    sampling_result res = {theta_o, roughness, metallic, 0, 0, 0, 0, 0};
    iir_bsdf b = iir_bsdf_make(test_normal(), iir_v3(0.9f, 0.6f, 0.3f), metallic, roughness);
    at_wo a = {&b, dir_at(&b, iir_radians(theta_o), 2.3)};
    sphere sp = {iir_frame_from_normal(mirror_of(&b, a.wo)), b.frame.f};
    static double observed[NS * NPHI], expected[NS * NPHI];
    memset(observed, 0, sizeof observed);
    /* the samples */
    iir_rng rng = iir_rng_make(seed, 2);
    int ok = 0;
    for (int i = 0; i < NSAMPLES; i++) {
        iir_bsdf_sample s;
        float uc = iir_rng_uniform(&rng);
        if (!iir_bsdf_sample_f(&b, a.wo, uc, iir_rng_uniform2(&rng), &s)) continue;
        ok++;
        res.max_f_diff = fmax(res.max_f_diff, rel_diff3(s.f, iir_bsdf_f(&b, a.wo, s.wi)));
        res.max_pdf_diff = fmax(res.max_pdf_diff, rel_diff(s.pdf, iir_bsdf_pdf(&b, a.wo, s.wi)));
        double sc, phi;
        axis_coords(&sp.ax, s.wi, &sc, &phi);
        int is = (int)fmin(NS - 1, sc * NS), ip = (int)fmin(NPHI - 1, phi / (2.0 * PI_D) * NPHI);
        observed[is * NPHI + ip] += 1.0;
    }
    res.ok_fraction = (double)ok / NSAMPLES;
    /* the expected counts */
    for (int is = 0; is < NS; is++) {
        for (int ip = 0; ip < NPHI; ip++) {
            double p =
                integrate_cell(&sp, pdf_at, &a, (double)is / NS, (double)(is + 1) / NS,
                               2.0 * PI_D * ip / NPHI, 2.0 * PI_D * (ip + 1) / NPHI, SUB, SUB);
            expected[is * NPHI + ip] = p * NSAMPLES;
            res.pdf_integral += p;
        }
    }
    res.p_value = chi2_p_value(observed, expected, NS * NPHI, NSAMPLES);
    return res;
}

/* The grid theta_o x roughness x metallic, run once for tests 4 and 5. */
static const sampling_result *sampling_results(void)
{
    static sampling_result results[NCASES];
    static bool done = false;
    if (done) return results;
    const float theta_o[] = {0.f, 30.f, 60.f, 85.f}, roughness[] = {0.1f, 0.3f, 0.6f, 1.f};
    int k = 0;
    for (int t = 0; t < 4; t++)
        for (int r = 0; r < 4; r++)
            for (int m = 0; m < 2; m++, k++)
                results[k] = run_sampling_case(theta_o[t], roughness[r], (float)m, 500 + k);
    done = true;
    return results;
}

static void test_sampling_matches_pdf(void **state)
{
    (void)state;
    const sampling_result *res = sampling_results();
    double alpha = 0.01 / NCASES, min_p = 1.0;
    printf("chi-square (%d x %d cells about the mirror direction, %d samples), p-values:\n", NS,
           NPHI, NSAMPLES);
    for (int k = 0; k < NCASES; k++) {
        printf("  theta_o %2.0f roughness %.1f metallic %.0f: p = %.4f\n", (double)res[k].theta_o,
               (double)res[k].roughness, (double)res[k].metallic, res[k].p_value);
        min_p = fmin(min_p, res[k].p_value);
    }
    printf("chi-square: min p-value %.4f over %d cases (rejected below %.2e)\n", min_p, NCASES,
           alpha);
    for (int k = 0; k < NCASES; k++) assert_true(res[k].p_value >= alpha);
}

static void test_pdf_integrates_to_success_fraction(void **state)
{
    (void)state;
    const sampling_result *res = sampling_results();
    double worst = 0.0, worst_f = 0.0, worst_pdf = 0.0;
    for (int k = 0; k < NCASES; k++) {
        double d = fabs(res[k].pdf_integral / res[k].ok_fraction - 1.0);
        printf("  theta_o %2.0f roughness %.1f metallic %.0f: int pdf = %.4f, succeeded %.4f\n",
               (double)res[k].theta_o, (double)res[k].roughness, (double)res[k].metallic,
               res[k].pdf_integral, res[k].ok_fraction);
        worst = fmax(worst, d);
        worst_f = fmax(worst_f, res[k].max_f_diff);
        worst_pdf = fmax(worst_pdf, res[k].max_pdf_diff);
        assert_true(d < 0.01);
        assert_true(res[k].max_f_diff < 1e-3 && res[k].max_pdf_diff < 1e-3);
    }
    printf("pdf: max |int pdf / success fraction - 1| = %.2e; sample_f against iir_bsdf_f, "
           "iir_bsdf_pdf at its wi: max relative difference %.2e, %.2e\n",
           worst, worst_f, worst_pdf);
}

/* ============================== 6. the delta lobe ============================== */

static iir_vec3 schlick(iir_vec3 f0, double cos_theta)
{
    float m5 = (float)pow(1.0 - cos_theta, 5.0);
    return iir_v3(f0.x + (1.f - f0.x) * m5, f0.y + (1.f - f0.y) * m5, f0.z + (1.f - f0.z) * m5);
}

/* Roughness 0.01 (alpha 1e-4) is a mirror: the SPECULAR flag, the mirror direction, f cos / pdf =
 * F(n.wo) / p_lobe with p_lobe the frequency with which uc picks it; f and pdf leave it out. */
static void test_delta_lobe(void **state)
{
    (void)state;
    iir_vec3 base = iir_v3(0.9f, 0.6f, 0.3f);
    const float metallic[] = {1.f, 0.5f}, theta_o[] = {0.f, 30.f, 60.f, 85.f};
    iir_bsdf edge = iir_bsdf_make(test_normal(), base, 1.f, 0.0316f); /* alpha 0.000999 */
    assert_int_equal(iir_bsdf_flags(&edge), IIR_BSDF_SPECULAR);
    edge = iir_bsdf_make(test_normal(), base, 1.f, 0.0317f); /* alpha 0.001005 */
    assert_int_equal(iir_bsdf_flags(&edge), IIR_BSDF_GLOSSY);
    iir_bsdf rough = iir_bsdf_make(test_normal(), base, 0.f, 0.04f);
    assert_int_equal(iir_bsdf_flags(&rough), IIR_BSDF_GLOSSY | IIR_BSDF_DIFFUSE);
    for (int m = 0; m < 2; m++) {
        iir_bsdf b = iir_bsdf_make(test_normal(), base, metallic[m], 0.01f);
        unsigned want =
            metallic[m] == 1.f ? IIR_BSDF_SPECULAR : IIR_BSDF_SPECULAR | IIR_BSDF_DIFFUSE;
        assert_int_equal(iir_bsdf_flags(&b), want);
        iir_vec3 f0 =
            iir_v3(0.04f + (base.x - 0.04f) * metallic[m], 0.04f + (base.y - 0.04f) * metallic[m],
                   0.04f + (base.z - 0.04f) * metallic[m]);
        for (int t = 0; t < 4; t++) {
            double theta = iir_radians(theta_o[t]);
            iir_vec3 wo = dir_at(&b, theta, 0.4), mirror = dir_at(&b, theta, 0.4 + PI_D);
            iir_vec3 F = schlick(f0, cos(theta));
            enum { NU = 4000 };
            int delta = 0;
            float p_lobe = 0.f;
            for (int i = 0; i < NU; i++) {
                iir_bsdf_sample s;
                assert_true(iir_bsdf_sample_f(&b, wo, (i + 0.5f) / NU, iir_v2(0.3f, 0.6f), &s));
                if (s.flags != IIR_BSDF_SPECULAR) continue;
                delta++;
                p_lobe = s.pdf;
                assert_true(iir_length(iir_sub(s.wi, mirror)) < 1e-5f);
                /* f cos = F, so f cos / pdf = F / p_lobe */
                iir_vec3 f_cos_i = iir_scale(s.f, iir_dot(s.wi, b.frame.f));
                assert_true(rel_diff3(f_cos_i, F) < 1e-5);
            }
            printf("delta: metallic %.1f theta_o %2.0f: p_lobe %.4f (uc picks it %.4f), "
                   "f cos = (%.4f %.4f %.4f) = F\n",
                   (double)metallic[m], (double)theta_o[t], (double)p_lobe, (double)delta / NU,
                   (double)F.x, (double)F.y, (double)F.z);
            assert_true(delta > 0);
            assert_true(fabs((double)delta / NU - p_lobe) <= 1.0 / NU);
            assert_true(fabsf(p_lobe - iir_bsdf_spec_probability(&b, wo)) < 1e-6f);
            if (metallic[m] == 1.f) assert_true(delta == NU); /* no diffuse lobe */
            /* evaluation leaves the delta out: only the diffuse lobe remains */
            float cos_m = iir_dot(mirror, b.frame.f);
            float pdf_want = (1.f - p_lobe) * cos_m * IIR_INV_PI;
            assert_true(fabsf(iir_bsdf_pdf(&b, wo, mirror) - pdf_want) <= 1e-5f * (1.f + pdf_want));
            if (metallic[m] == 1.f) assert_true(iir_is_black(iir_bsdf_f(&b, wo, mirror)));
        }
    }
}

/* ==================== 7. f against the formulas, re-derived ==================== */

/* Appendix B in double, from the world-space vectors: (1 - F) c_diff / pi + F D V, channel c. */
static double gltf_f(iir_vec3 n, iir_vec3 v, iir_vec3 l, double base, double metallic,
                     double roughness)
{
    double alpha = roughness * roughness, a2 = alpha * alpha;
    double hx = v.x + l.x, hy = v.y + l.y, hz = v.z + l.z, hl = sqrt(hx * hx + hy * hy + hz * hz);
    iir_vec3 h = iir_v3((float)(hx / hl), (float)(hy / hl), (float)(hz / hl));
    double NdotL = dot_d(n, l), NdotV = dot_d(n, v), NdotH = dot_d(n, h), VdotH = dot_d(v, h);
    double f0 = 0.04 + (base - 0.04) * metallic, c_diff = base * (1.0 - metallic);
    double F = f0 + (1.0 - f0) * pow(1.0 - fabs(VdotH), 5.0);
    double D = a2 / (PI_D * pow(NdotH * NdotH * (a2 - 1.0) + 1.0, 2.0));
    double V = 0.5 / (NdotL * sqrt(NdotV * NdotV * (1.0 - a2) + a2) +
                      NdotV * sqrt(NdotL * NdotL * (1.0 - a2) + a2));
    return (1.0 - F) * c_diff / PI_D + F * D * V;
}

static void test_f_against_formulas(void **state)
{
    (void)state;
    iir_vec3 base = iir_v3(0.8f, 0.4f, 0.2f);
    struct {
        float metallic, roughness;
        double theta_o, phi_o, theta_i, phi_i;
    } cases[] = {
        {0.f, 1.f, 0.0, 0.0, 0.0, 0.0}, /* wo = wi = n */
        {0.f, 0.5f, 0.7, 0.2, 1.2, 2.9}, {0.3f, 0.2f, 0.5, 1.0, 0.55, 4.1},
        {1.f, 0.7f, 1.3, 0.0, 0.3, 3.0}, {0.6f, 0.1f, 0.9, 2.0, 0.85, 5.1},
    };
    double worst = 0.0;
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        iir_bsdf b = iir_bsdf_make(test_normal(), base, cases[k].metallic, cases[k].roughness);
        iir_vec3 wo = dir_at(&b, cases[k].theta_o, cases[k].phi_o);
        iir_vec3 wi = dir_at(&b, cases[k].theta_i, cases[k].phi_i);
        iir_vec3 f = iir_bsdf_f(&b, wo, wi), n = b.frame.f;
        iir_vec3 want =
            iir_v3((float)gltf_f(n, wo, wi, base.x, cases[k].metallic, cases[k].roughness),
                   (float)gltf_f(n, wo, wi, base.y, cases[k].metallic, cases[k].roughness),
                   (float)gltf_f(n, wo, wi, base.z, cases[k].metallic, cases[k].roughness));
        printf("f: metallic %.1f roughness %.1f: (%.6f %.6f %.6f), formulas (%.6f %.6f %.6f)\n",
               (double)cases[k].metallic, (double)cases[k].roughness, (double)f.x, (double)f.y,
               (double)f.z, (double)want.x, (double)want.y, (double)want.z);
        worst = fmax(worst, rel_diff3(f, want));
        assert_true(rel_diff3(f, want) < 1e-4);
    }
    /* wo = wi = n, metallic 0, roughness 1: F = 0.04, D = 1/pi, V = 1/4 */
    iir_bsdf b = iir_bsdf_make(test_normal(), base, 0.f, 1.f);
    iir_vec3 f = iir_bsdf_f(&b, b.frame.f, b.frame.f);
    double want_x = 0.96 * base.x / PI_D + 0.04 / PI_D * 0.25;
    assert_true(rel_diff(f.x, want_x) < 1e-5);
    printf("f: max relative difference from the formulas %.2e\n", worst);
}

/* ====================== 8 lanes at once ====================== */

/* iir_bsdf_f8_avx2 against iir_bsdf_f, lane by lane, for random BSDFs (mirrors, rough metals and
 * dielectrics, Lambertian-like roughness 1) and directions on both sides of the surface: within
 * 2e-5 of the larger value (they differ in rounding: cosines as dot products with n against
 * coordinates in the tangent frame, FMA), and 0 exactly where wo or wi is below the surface.
 * A wrong term (Schlick's power, D's alpha^2, V's roots) is off by far more. */
static void test_lanes_match_scalar(void **state)
{
    (void)state;
    if (!iir_isa_supported(IIR_ISA_AVX2)) {
        printf("no AVX2 here: the 8-lane BSDF is not run\n");
        return;
    }
    iir_rng rng = iir_rng_make(31, 7);
    double worst = 0.0;
    for (int round = 0; round < 2000; round++) {
        iir_bsdf_lanes L;
        memset(&L, 0, sizeof L);
        iir_bsdf b[8];
        _Alignas(32) float wx[8], wy[8], wz[8], fx[8], fy[8], fz[8];
        iir_vec3 wo[8], wi[8];
        for (int k = 0; k < 8; k++) {
            iir_vec3 n = iir_sample_uniform_sphere(iir_rng_uniform2(&rng));
            iir_vec3 base =
                iir_v3(iir_rng_uniform(&rng), iir_rng_uniform(&rng), iir_rng_uniform(&rng));
            float metallic = iir_rng_uniform(&rng), rough = k == 0 ? 0.01f : iir_rng_uniform(&rng);
            float f0 = 0.08f * iir_rng_uniform(&rng);
            b[k] = iir_bsdf_make_f0(n, base, metallic, rough, f0);
            wo[k] = iir_sample_uniform_sphere(iir_rng_uniform2(&rng));
            wi[k] = iir_sample_uniform_sphere(iir_rng_uniform2(&rng));
            if (iir_dot(wo[k], n) < 0.f && k % 2) wo[k] = iir_neg(wo[k]); /* mostly above */
            if (iir_dot(wi[k], n) < 0.f && k % 3) wi[k] = iir_neg(wi[k]);
            iir_bsdf_lanes_set(&L, k, n, wo[k], base, metallic, rough, f0);
            wx[k] = wi[k].x, wy[k] = wi[k].y, wz[k] = wi[k].z;
        }
        iir_bsdf_f8_avx2(&L, wx, wy, wz, fx, fy, fz);
        for (int k = 0; k < 8; k++) {
            iir_vec3 want = iir_bsdf_f(&b[k], wo[k], wi[k]), got = iir_v3(fx[k], fy[k], fz[k]);
            if (iir_is_black(want)) {
                assert_true(iir_is_black(got));
                continue;
            }
            double scale = fmax(fmax(want.x, want.y), want.z);
            double d = fmax(fmax(fabs(got.x - want.x), fabs(got.y - want.y)), fabs(got.z - want.z));
            worst = fmax(worst, d / scale);
            if (!(d <= 2e-5 * scale))
                fail_msg("lane %d: (%g %g %g) against iir_bsdf_f's (%g %g %g)", k, (double)got.x,
                         (double)got.y, (double)got.z, (double)want.x, (double)want.y,
                         (double)want.z);
        }
    }
    printf("8 lanes against iir_bsdf_f: largest difference %.2e of the value\n", worst);
}

/* ====================== the two-sided convention and the rest ====================== */

static void test_horizon_and_albedo(void **state)
{
    (void)state;
    iir_bsdf b = iir_bsdf_make(test_normal(), iir_v3(0.9f, 0.6f, 0.3f), 0.25f, 0.5f);
    iir_vec3 up = dir_at(&b, 0.5, 1.0), down = dir_at(&b, 2.0, 3.0);
    assert_true(iir_is_black(iir_bsdf_f(&b, down, up)));
    assert_true(iir_is_black(iir_bsdf_f(&b, up, down)));
    assert_true(iir_bsdf_pdf(&b, down, up) == 0.f && iir_bsdf_pdf(&b, up, down) == 0.f);
    assert_true(iir_bsdf_spec_probability(&b, down) == 0.f);
    iir_rng rng = iir_rng_make(3, 3);
    for (int i = 0; i < 1000; i++) {
        iir_bsdf_sample s;
        float uc = iir_rng_uniform(&rng);
        assert_false(iir_bsdf_sample_f(&b, down, uc, iir_rng_uniform2(&rng), &s));
        if (iir_bsdf_sample_f(&b, up, uc, iir_rng_uniform2(&rng), &s))
            assert_true(iir_dot(s.wi, b.frame.f) > 0.f);
    }
    iir_vec3 albedo = iir_bsdf_albedo(&b);
    assert_true(rel_diff3(albedo, iir_v3(0.675f, 0.45f, 0.225f)) < 1e-6);
    /* clamping and black metal: the lobe choice falls back to the specular lobe */
    iir_bsdf black = iir_bsdf_make(test_normal(), iir_v3(-1.f, 0.f, 2.f), 3.f, 7.f);
    assert_true(black.metallic == 1.f && black.alpha == 1.f && black.base_color.z == 1.f);
    iir_bsdf coal = iir_bsdf_make(test_normal(), iir_v3s(0.f), 1.f, 0.5f);
    assert_true(iir_bsdf_spec_probability(&coal, coal.frame.f) == 1.f);
    char text[256];
    iir_bsdf_describe(&b, text, sizeof text);
    printf("%s\n", text);
    assert_non_null(strstr(text, "metallic=0.250"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_reciprocity),
        cmocka_unit_test(test_energy),
        cmocka_unit_test(test_white_furnace),
        cmocka_unit_test(test_sampling_matches_pdf),
        cmocka_unit_test(test_pdf_integrates_to_success_fraction),
        cmocka_unit_test(test_delta_lobe),
        cmocka_unit_test(test_f_against_formulas),
        cmocka_unit_test(test_horizon_and_albedo),
        cmocka_unit_test(test_lanes_match_scalar),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

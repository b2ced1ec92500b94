/* metrics.c -- RMSE, relative MSE, SSIM and flicker; not where references come from. */

/* Sums are accumulated in double. SSIM follows Wang et al. 2004 on the Rec. 709 luminance: an
 * 11x11 Gaussian window (sigma 1.5) applied as two 1-D passes; near the border the window is cut
 * to the image and renormalised (the 2-D weights are a product, so renormalising each pass is
 * exactly renormalising the 2-D window). Rows run in parallel, but each row's sum is kept apart
 * and the rows are added in order, so the result does not depend on the thread count. SSIM also
 * returns NAN when its working memory (seven floats per pixel) cannot be allocated. */
#include "iir/metrics.h"

#include <math.h>
#include <stdlib.h>

#define SSIM_RADIUS 5
#define SSIM_TAPS (2 * SSIM_RADIUS + 1)
#define SSIM_SIGMA 1.5
#define SSIM_C1 (0.01 * 0.01) /* (K1 L)^2 with L = 1 */
#define SSIM_C2 (0.03 * 0.03) /* (K2 L)^2 */

static int same_size(const iir_image *a, const iir_image *b)
{
    return a && b && a->width == b->width && a->height == b->height;
}

static size_t pixel_count(const iir_image *img)
{
    return (size_t)img->width * (size_t)img->height;
}

/* ---- per-channel errors --------------------------------------------------------------------- */

double iir_metric_rmse(const iir_image *a, const iir_image *ref)
{
    if (!same_size(a, ref)) return NAN;
    double sum = 0.0;
    for (size_t i = 0, n = pixel_count(a); i < n; i++) {
        iir_vec3 d = iir_sub(a->pixels[i], ref->pixels[i]);
        sum += (double)d.x * d.x + (double)d.y * d.y + (double)d.z * d.z;
    }
    return sqrt(sum / (3.0 * (double)pixel_count(a)));
}

static double relative_sq(float a, float ref)
{
    double d = (double)a - ref;
    return d * d / ((double)ref * ref + 0.01);
}

double iir_metric_relmse(const iir_image *a, const iir_image *ref)
{
    if (!same_size(a, ref)) return NAN;
    double sum = 0.0;
    for (size_t i = 0, n = pixel_count(a); i < n; i++) {
        iir_vec3 p = a->pixels[i], r = ref->pixels[i];
        sum += relative_sq(p.x, r.x) + relative_sq(p.y, r.y) + relative_sq(p.z, r.z);
    }
    return sum / (3.0 * (double)pixel_count(a));
}

double iir_metric_flicker(const iir_image *a_t, const iir_image *a_prev, const iir_image *ref_t,
                          const iir_image *ref_prev)
{
    if (!same_size(a_t, a_prev) || !same_size(a_t, ref_t) || !same_size(a_t, ref_prev)) return NAN;
    double sum = 0.0;
    for (size_t i = 0, n = pixel_count(a_t); i < n; i++) {
        iir_vec3 da = iir_sub(a_t->pixels[i], a_prev->pixels[i]);
        iir_vec3 dr = iir_sub(ref_t->pixels[i], ref_prev->pixels[i]);
        double x = (double)da.x - dr.x, y = (double)da.y - dr.y, z = (double)da.z - dr.z;
        sum += x * x + y * y + z * z;
    }
    return sqrt(sum / (3.0 * (double)pixel_count(a_t)));
}

/* ---- SSIM ----------------------------------------------------------------------------------- */

/* The five windowed moments SSIM needs, one plane each: E[a], E[b], E[a^2], E[b^2], E[ab]. */
enum { M_A, M_B, M_AA, M_BB, M_AB, M_COUNT };

typedef struct ssim_work {
    int w, h;
    double g[SSIM_TAPS]; /* normalised 1-D Gaussian */
    float *ya, *yb;      /* luminance of a and ref */
    float *m[M_COUNT];   /* moments after the horizontal pass */
    double *row_sum;     /* SSIM summed over each row */
} ssim_work;

static void gaussian_taps(double g[SSIM_TAPS])
{
    double total = 0.0;
    for (int k = 0; k < SSIM_TAPS; k++) {
        double t = k - SSIM_RADIUS;
        g[k] = exp(-t * t / (2.0 * SSIM_SIGMA * SSIM_SIGMA));
        total += g[k];
    }
    for (int k = 0; k < SSIM_TAPS; k++) g[k] /= total;
}

static void luminance_plane(const iir_image *img, float *y)
{
    for (size_t i = 0, n = pixel_count(img); i < n; i++) y[i] = iir_luminance(img->pixels[i]);
}

/* Horizontal pass: the five moments of row y, each a renormalised Gaussian sum over x. */
static void moments_row(ssim_work *s, int y)
{
    const float *a = s->ya + (size_t)y * s->w, *b = s->yb + (size_t)y * s->w;
    for (int x = 0; x < s->w; x++) {
        double sum[M_COUNT] = {0}, norm = 0.0;
        for (int k = 0; k < SSIM_TAPS; k++) {
            int xx = x + k - SSIM_RADIUS;
            if (xx < 0 || xx >= s->w) continue;
            double wk = s->g[k], av = a[xx], bv = b[xx];
            sum[M_A] += wk * av;
            sum[M_B] += wk * bv;
            sum[M_AA] += wk * av * av;
            sum[M_BB] += wk * bv * bv;
            sum[M_AB] += wk * av * bv;
            norm += wk;
        }
        for (int m = 0; m < M_COUNT; m++) s->m[m][(size_t)y * s->w + x] = (float)(sum[m] / norm);
    }
}

/* SSIM from the windowed moments (Wang et al. 2004, eq. 13). */
static double ssim_from_moments(const double e[M_COUNT])
{
    double mu_a = e[M_A], mu_b = e[M_B];
    double var_a = e[M_AA] - mu_a * mu_a, var_b = e[M_BB] - mu_b * mu_b;
    double cov = e[M_AB] - mu_a * mu_b;
    return (2.0 * mu_a * mu_b + SSIM_C1) * (2.0 * cov + SSIM_C2) /
           ((mu_a * mu_a + mu_b * mu_b + SSIM_C1) * (var_a + var_b + SSIM_C2));
}

/* Vertical pass for row y, then SSIM at each pixel of the row, summed. */
static double ssim_row(const ssim_work *s, int y)
{
    double row = 0.0;
    for (int x = 0; x < s->w; x++) {
        double e[M_COUNT] = {0}, norm = 0.0;
        for (int k = 0; k < SSIM_TAPS; k++) {
            int yy = y + k - SSIM_RADIUS;
            if (yy < 0 || yy >= s->h) continue;
            size_t i = (size_t)yy * s->w + x;
            for (int m = 0; m < M_COUNT; m++) e[m] += s->g[k] * s->m[m][i];
            norm += s->g[k];
        }
        for (int m = 0; m < M_COUNT; m++) e[m] /= norm;
        row += ssim_from_moments(e);
    }
    return row;
}

static int ssim_work_init(ssim_work *s, int w, int h)
{
    size_t n = (size_t)w * (size_t)h;
    s->w = w;
    s->h = h;
    gaussian_taps(s->g);
    s->ya = malloc((2 + M_COUNT) * n * sizeof(float));
    s->row_sum = malloc((size_t)h * sizeof(double));
    if (!s->ya || !s->row_sum) return 0;
    s->yb = s->ya + n;
    for (int m = 0; m < M_COUNT; m++) s->m[m] = s->ya + (2 + (size_t)m) * n;
    return 1;
}

static void ssim_work_free(ssim_work *s)
{
    free(s->ya);
    free(s->row_sum);
}

double iir_metric_ssim(const iir_image *a, const iir_image *ref)
{
    if (!same_size(a, ref)) return NAN;
    ssim_work s;
    if (!ssim_work_init(&s, a->width, a->height)) {
        ssim_work_free(&s);
        return NAN;
    }
    luminance_plane(a, s.ya);
    luminance_plane(ref, s.yb);
#pragma omp parallel for schedule(static)
    for (int y = 0; y < s.h; y++) moments_row(&s, y);
#pragma omp parallel for schedule(static)
    for (int y = 0; y < s.h; y++) s.row_sum[y] = ssim_row(&s, y);
    double total = 0.0;
    for (int y = 0; y < s.h; y++) total += s.row_sum[y];
    ssim_work_free(&s);
    return total / (double)pixel_count(a);
}

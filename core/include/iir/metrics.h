/* metrics.h -- image error against a reference: RMSE, relative MSE, SSIM on luminance, and the
 * temporal flicker measure of DESIGN section 10. Pure functions of their inputs.
 * Every function returns NAN when the images differ in size. */
#ifndef IIR_METRICS_H
#define IIR_METRICS_H

#include "iir/image.h"

#ifdef __cplusplus
extern "C" {
#endif

/* sqrt(mean over pixels and channels of (a - ref)^2). */
double iir_metric_rmse(const iir_image *a, const iir_image *ref);

/* mean over pixels and channels of (a - ref)^2 / (ref^2 + 0.01). */
double iir_metric_relmse(const iir_image *a, const iir_image *ref);

/* Mean SSIM of the luminances (Wang et al. 2004: 11x11 Gaussian window, sigma 1.5, K1 0.01,
 * K2 0.03, dynamic range L = 1, so pass images tone-mapped to about [0, 1]). 1 for identical
 * images. */
double iir_metric_ssim(const iir_image *a, const iir_image *ref);

/* Flicker beyond the reference's own change: RMS over pixels and channels of
 * (a_t - a_prev) - (ref_t - ref_prev). */
double iir_metric_flicker(const iir_image *a_t, const iir_image *a_prev, const iir_image *ref_t,
                          const iir_image *ref_prev);

#ifdef __cplusplus
}
#endif
#endif

/* camera.h -- the pinhole camera: its description (as scenes and the protocol give it) and the
 * precomputed frame that turns pixel coordinates into ray directions. Not the G-buffer. */
#ifndef IIR_CAMERA_H
#define IIR_CAMERA_H

#include "iir/status.h"
#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct iir_camera {
    iir_vec3 position;
    iir_vec3 target;
    iir_vec3 up;
    float fov_y; /* vertical field of view, degrees, in (0, 180) */
} iir_camera;

/* Precomputed for one image size; cheap to make, so make one per frame. */
typedef struct iir_camera_frame {
    iir_vec3 origin;
    iir_frame basis; /* r = image right, u = image up, f = view direction */
    float tan_half_y, aspect;
    int width, height;
} iir_camera_frame;

/* IIR_ERR_INVALID with a reason for NaN/Inf fields, position == target, up parallel to the view
 * direction, or fov outside (0, 180). */
iir_status iir_camera_validate(const iir_camera *cam, iir_error *err);

iir_camera_frame iir_camera_setup(const iir_camera *cam, int width, int height);

/* Unit direction through image point (px, py) in pixel units: x grows right, y grows down, pixel
 * (i, j) covers [i, i+1) x [j, j+1), so its centre is (i + 0.5, j + 0.5). */
static inline iir_vec3 iir_camera_dir(const iir_camera_frame *cf, float px, float py)
{
    float sx = (2.f * px / (float)cf->width - 1.f) * cf->tan_half_y * cf->aspect;
    float sy = (1.f - 2.f * py / (float)cf->height) * cf->tan_half_y;
    iir_vec3 d =
        iir_add(iir_add(iir_scale(cf->basis.r, sx), iir_scale(cf->basis.u, sy)), cf->basis.f);
    return iir_normalize(d);
}

#ifdef __cplusplus
}
#endif
#endif

/* camera.c -- the pinhole camera: validating its description and precomputing the frame that
 * turns pixels into ray directions; not the G-buffer, not where a scene's camera comes from. */
#include "iir/camera.h"

#include <assert.h>

/* Relative tolerance under which two camera vectors count as equal or parallel. */
#define CAMERA_EPS 1e-6f

iir_status iir_camera_validate(const iir_camera *cam, iir_error *err)
{
    if (!iir_is_finite3(cam->position))
        return iir_fail(err, IIR_ERR_INVALID, "camera position is not finite");
    if (!iir_is_finite3(cam->target))
        return iir_fail(err, IIR_ERR_INVALID, "camera target is not finite");
    if (!iir_is_finite3(cam->up)) return iir_fail(err, IIR_ERR_INVALID, "camera up is not finite");
    if (!(cam->fov_y > 0.f && cam->fov_y < 180.f))
        return iir_fail(err, IIR_ERR_INVALID, "camera fov_y %g degrees is outside (0, 180)",
                        (double)cam->fov_y);
    iir_vec3 view = iir_sub(cam->target, cam->position);
    float scale = fmaxf(1.f, fmaxf(iir_length(cam->position), iir_length(cam->target)));
    if (iir_length(view) <= CAMERA_EPS * scale)
        return iir_fail(err, IIR_ERR_INVALID, "camera target equals its position (%g, %g, %g)",
                        (double)cam->position.x, (double)cam->position.y, (double)cam->position.z);
    if (iir_length(cam->up) == 0.f) return iir_fail(err, IIR_ERR_INVALID, "camera up is zero");
    iir_vec3 side = iir_cross(iir_normalize(view), iir_normalize(cam->up));
    if (iir_length(side) <= CAMERA_EPS)
        return iir_fail(err, IIR_ERR_INVALID,
                        "camera up (%g, %g, %g) is parallel to the view "
                        "direction",
                        (double)cam->up.x, (double)cam->up.y, (double)cam->up.z);
    return IIR_OK;
}

/* Right-handed: f looks at the target, r = f x up is image right, u = r x f is image up. */
iir_camera_frame iir_camera_setup(const iir_camera *cam, int width, int height)
{
    assert(width > 0 && height > 0 && "iir_camera_setup: image size must be positive");
    iir_camera_frame cf;
    cf.origin = cam->position;
    cf.basis.f = iir_normalize(iir_sub(cam->target, cam->position));
    cf.basis.r = iir_normalize(iir_cross(cf.basis.f, cam->up));
    cf.basis.u = iir_cross(cf.basis.r, cf.basis.f);
    cf.tan_half_y = tanf(iir_radians(0.5f * cam->fov_y));
    cf.aspect = (float)width / (float)height;
    cf.width = width;
    cf.height = height;
    return cf;
}

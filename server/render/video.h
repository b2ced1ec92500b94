/* video.h -- H.264 video through the ffmpeg program: raw sRGB8 frames written into a pipe to
 * `ffmpeg -f rawvideo -pix_fmt rgb24 ... -c:v libx264 -pix_fmt yuv420p OUT.mp4`. Not the frames'
 * files or tone mapping (image.h).
 *
 * ffmpeg runs in its own process group, so a Ctrl-C on the terminal reaches only iird, which
 * then closes the pipe and lets ffmpeg finish a valid file with the frames sent so far. While a
 * video is open SIGPIPE is ignored: ffmpeg exiting early is an error returned by
 * iird_video_frame, not a silent death. Single-threaded. */
#ifndef IIRD_VIDEO_H
#define IIRD_VIDEO_H

#include "iir/image.h"
#include "iir/status.h"

typedef struct iird_video iird_video;

/* Checks before any rendering that a video can be made: path ends in .mp4, width and height are
 * even (IIR_ERR_INVALID naming --video or --size; 4:2:0 chroma needs even sizes), and an ffmpeg
 * program is on PATH (IIR_ERR_UNSUPPORTED). Not its folder: the caller makes that
 * (iird_prepare_parent), and iird_video_open checks it exists. */
iir_status iird_video_check(const char *path, int width, int height, iir_error *err);

/* Starts ffmpeg writing path (overwriting it) from width x height frames at fps. IIR_ERR_IO when
 * path's folder does not exist. On error *out stays NULL and no process is left running. */
iir_status iird_video_open(const char *path, int width, int height, double fps, iird_video **out,
                           iir_error *err);

/* Tone-maps img (iir_image_to_srgb8 at exposure; its size must be the video's) and sends it.
 * IIR_ERR_IO when ffmpeg has stopped reading. Does not allocate. */
iir_status iird_video_frame(iird_video *v, const iir_image *img, float exposure, iir_error *err);

/* Frames sent so far. */
int iird_video_frames(const iird_video *v);

/* Closes the pipe, waits for ffmpeg and frees v (NULL is ignored and OK). IIR_ERR_IO naming
 * ffmpeg's exit status or signal when it failed; its own messages are on stderr above ours. */
iir_status iird_video_close(iird_video *v, iir_error *err);

#endif

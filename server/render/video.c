/* video.c -- the ffmpeg pipe that turns frames into an H.264 MP4 (see video.h). */
#define _GNU_SOURCE /* pipe2 */
#include "video.h"

#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

struct iird_video {
    pid_t pid;
    int fd; /* write end of ffmpeg's stdin */
    int width, height, frames;
    uint8_t *rgb; /* one frame of sRGB8, width * height * 3 */
    struct sigaction old_pipe;
    char path[4096];
};

/* ---- checks ---- */

/* True when an executable `prog` is in one of PATH's folders (as posix_spawnp searches them). */
static bool on_path(const char *prog)
{
    const char *path = getenv("PATH");
    if (!path) path = "/bin:/usr/bin";
    char dir[4096], file[4352];
    for (const char *p = path; *p;) {
        size_t n = strcspn(p, ":");
        snprintf(dir, sizeof dir, "%.*s", (int)n, n ? p : ".");
        snprintf(file, sizeof file, "%s/%s", dir, prog);
        if (access(file, X_OK) == 0) return true;
        p += n + (p[n] == ':');
    }
    return false;
}

static bool dir_of_exists(const char *path)
{
    const char *slash = strrchr(path, '/');
    char dir[4096];
    snprintf(dir, sizeof dir, "%.*s", slash ? (int)(slash - path) : 1, slash ? path : ".");
    if (slash == path) snprintf(dir, sizeof dir, "/");
    struct stat sb;
    return stat(dir, &sb) == 0 && S_ISDIR(sb.st_mode);
}

iir_status iird_video_check(const char *path, int width, int height, iir_error *err)
{
    size_t n = strlen(path);
    if (n < 5 || strcasecmp(path + n - 4, ".mp4") != 0)
        return iir_fail(err, IIR_ERR_INVALID, "--video %s: the name must end in .mp4", path);
    if (width % 2 || height % 2)
        return iir_fail(err, IIR_ERR_INVALID,
                        "--size %dx%d: --video needs an even width and height (H.264 with 4:2:0 "
                        "chroma)",
                        width, height);
    if (!on_path("ffmpeg"))
        return iir_fail(err, IIR_ERR_UNSUPPORTED,
                        "--video needs the ffmpeg program, and there is none on PATH (install it: "
                        "make deps, or apt-get install ffmpeg)");
    return IIR_OK;
}

/* ---- the pipe ---- */

static iir_status spawn_ffmpeg(iird_video *v, double fps, int in_fd, iir_error *err)
{
    char size[64], rate[64], out[4352];
    snprintf(size, sizeof size, "%dx%d", v->width, v->height);
    snprintf(rate, sizeof rate, "%.17g", fps);
    snprintf(out, sizeof out, "%s%s", v->path[0] == '-' ? "./" : "", v->path);
    char *argv[] = {"ffmpeg",   "-hide_banner", "-loglevel", "error", "-nostats", "-y",
                    "-f",       "rawvideo",     "-pix_fmt",  "rgb24", "-s",       size,
                    "-r",       rate,           "-i",        "-",     "-c:v",     "libx264",
                    "-pix_fmt", "yuv420p",      out,         NULL};
    posix_spawn_file_actions_t fa;
    posix_spawnattr_t attr;
    sigset_t def, none;
    sigemptyset(&none);
    sigemptyset(&def);
    sigaddset(&def, SIGPIPE);
    sigaddset(&def, SIGINT);
    sigaddset(&def, SIGTERM);
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, in_fd, STDIN_FILENO);
    posix_spawnattr_init(&attr);
    /* Own process group: a terminal's Ctrl-C goes to iird only (see video.h). */
    posix_spawnattr_setpgroup(&attr, 0);
    posix_spawnattr_setsigdefault(&attr, &def);
    posix_spawnattr_setsigmask(&attr, &none);
    posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGDEF |
                                        POSIX_SPAWN_SETSIGMASK);
    int rc = posix_spawnp(&v->pid, "ffmpeg", &fa, &attr, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    posix_spawnattr_destroy(&attr);
    if (rc != 0)
        return iir_fail(err, IIR_ERR_UNSUPPORTED, "--video: cannot start ffmpeg: %s", strerror(rc));
    return IIR_OK;
}

iir_status iird_video_open(const char *path, int width, int height, double fps, iird_video **out,
                           iir_error *err)
{
    *out = NULL;
    if (!dir_of_exists(path))
        return iir_fail(err, IIR_ERR_IO, "--video %s: its directory does not exist", path);
    iird_video *v = calloc(1, sizeof *v);
    uint8_t *rgb = malloc((size_t)width * (size_t)height * 3);
    int fds[2] = {-1, -1};
    if (!v || !rgb) {
        free(v), free(rgb);
        return iir_fail(err, IIR_ERR_NOMEM, "out of memory for the video");
    }
    if (pipe2(fds, O_CLOEXEC) != 0) {
        free(v), free(rgb);
        return iir_fail(err, IIR_ERR_INTERNAL, "--video: pipe: %s", strerror(errno));
    }
    *v = (iird_video){.fd = fds[1], .width = width, .height = height, .rgb = rgb};
    snprintf(v->path, sizeof v->path, "%s", path);
    iir_status st = spawn_ffmpeg(v, fps, fds[0], err);
    close(fds[0]);
    if (st != IIR_OK) {
        close(fds[1]);
        free(rgb), free(v);
        return st;
    }
    struct sigaction ign;
    memset(&ign, 0, sizeof ign);
    ign.sa_handler = SIG_IGN;
    sigaction(SIGPIPE, &ign, &v->old_pipe);
    *out = v;
    return IIR_OK;
}

iir_status iird_video_frame(iird_video *v, const iir_image *img, float exposure, iir_error *err)
{
    if (img->width != v->width || img->height != v->height)
        return iir_fail(err, IIR_ERR_INVALID, "--video: a %dx%d frame for a %dx%d video",
                        img->width, img->height, v->width, v->height);
    iir_image_to_srgb8(img, exposure, v->rgb);
    size_t left = (size_t)v->width * (size_t)v->height * 3;
    const uint8_t *p = v->rgb;
    while (left > 0) {
        ssize_t n = write(v->fd, p, left);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            return iir_fail(err, IIR_ERR_IO,
                            "--video %s: ffmpeg stopped reading frames after %d (%s); its "
                            "messages are above",
                            v->path, v->frames, strerror(errno));
        p += n;
        left -= (size_t)n;
    }
    v->frames++;
    return IIR_OK;
}

int iird_video_frames(const iird_video *v)
{
    return v ? v->frames : 0;
}

iir_status iird_video_close(iird_video *v, iir_error *err)
{
    if (!v) return IIR_OK;
    close(v->fd);
    int status = 0;
    pid_t r;
    while ((r = waitpid(v->pid, &status, 0)) < 0 && errno == EINTR) {
    }
    sigaction(SIGPIPE, &v->old_pipe, NULL);
    iir_status st = IIR_OK;
    if (r < 0)
        st = iir_fail(err, IIR_ERR_INTERNAL, "--video: waiting for ffmpeg: %s", strerror(errno));
    else if (WIFEXITED(status) && WEXITSTATUS(status) != 0)
        st = iir_fail(err, IIR_ERR_IO, "--video %s: ffmpeg exited with status %d (see above)",
                      v->path, WEXITSTATUS(status));
    else if (WIFSIGNALED(status))
        st = iir_fail(err, IIR_ERR_IO, "--video %s: ffmpeg was killed by signal %d", v->path,
                      WTERMSIG(status));
    free(v->rgb);
    free(v);
    return st;
}

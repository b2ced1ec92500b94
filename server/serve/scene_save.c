/* scene_save.c -- a new scene in the scenes directory from a sidecar's text (scene_save.h): a
 * hidden temporary folder holding the file, written and synced, then renamed into place with
 * RENAME_NOREPLACE, so a concurrent save or an existing scene is never replaced and a failure
 * leaves nothing behind. Not the sidecar's content (protocol/sidecar.c). */
#define _GNU_SOURCE /* renameat2, RENAME_NOREPLACE */
#include "scene_save.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

static bool exists_error(const char *dir, const char *name, iird_proto_error *err)
{
    return iird_proto_fail(err, IIRD_E_BAD_FIELD, "save.name",
                           "a scene named '%s' exists in %s; pick another name", name, dir);
}

/* internal, naming what failed on which path and the system's reason (errno). */
static bool os_error(const char *what, const char *path, iird_proto_error *err)
{
    return iird_proto_fail(err, IIRD_E_INTERNAL, NULL, "cannot save the scene: %s %s: %s", what,
                           path, strerror(errno));
}

/* Writes text into the new file path and syncs it. */
static bool write_file(const char *path, const char *text, iird_proto_error *err)
{
    int fd = open(path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
    if (fd < 0) return os_error("cannot create", path, err);
    size_t len = strlen(text), done = 0;
    bool ok = true;
    while (ok && done < len) {
        ssize_t n = write(fd, text + done, len - done);
        if (n < 0 && errno == EINTR) continue;
        if (n == 0) errno = EIO;
        ok = n > 0 ? (done += (size_t)n, true) : os_error("cannot write", path, err);
    }
    if (ok && fsync(fd) != 0) ok = os_error("cannot sync", path, err);
    if (close(fd) != 0 && ok) ok = os_error("cannot close", path, err);
    return ok;
}

/* The folder tmp becomes final unless final exists. On a filesystem without RENAME_NOREPLACE,
 * final is made (mkdir fails when it exists) and the file (leaf) moved into it. */
static bool place(const char *tmp, const char *final, const char *leaf, const char *dir,
                  const char *name, iird_proto_error *err)
{
    if (renameat2(AT_FDCWD, tmp, AT_FDCWD, final, RENAME_NOREPLACE) == 0) return true;
    if (errno == EEXIST || errno == ENOTEMPTY) return exists_error(dir, name, err);
    if (errno != EINVAL && errno != ENOSYS) return os_error("cannot rename", tmp, err);
    char from[PATH_MAX + 200], to[PATH_MAX + 200];
    snprintf(from, sizeof from, "%s/%s", tmp, leaf);
    snprintf(to, sizeof to, "%s/%s", final, leaf);
    if (mkdir(final, 0777) != 0)
        return errno == EEXIST ? exists_error(dir, name, err)
                               : os_error("cannot create", final, err);
    if (rename(from, to) == 0) return true;
    bool failed = os_error("cannot rename", from, err);
    rmdir(final);
    return failed;
}

bool iird_scene_save(const char *dir, const char *name, const char *text, iird_proto_error *err)
{
    char final[PATH_MAX], tmp[PATH_MAX], file[PATH_MAX + 200], leaf[160];
    struct stat sb;
    struct timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    snprintf(leaf, sizeof leaf, "%s.scene.json", name);
    if (snprintf(final, sizeof final, "%s/%s", dir, name) >= (int)sizeof final ||
        snprintf(tmp, sizeof tmp, "%s/.%s.part-%ld-%ld", dir, name, (long)getpid(),
                 (long)now.tv_nsec) >= (int)sizeof tmp)
        return iird_proto_fail(err, IIRD_E_INTERNAL, NULL,
                               "cannot save the scene: the scenes directory's path is too long");
    if (lstat(final, &sb) == 0) return exists_error(dir, name, err);
    if (errno != ENOENT) return os_error("cannot look at", final, err);
    if (mkdir(tmp, 0777) != 0) return os_error("cannot create", tmp, err);
    snprintf(file, sizeof file, "%s/%s", tmp, leaf);
    bool ok = write_file(file, text, err) && place(tmp, final, leaf, dir, name, err);
    /* after a rename of the folder both are gone already; otherwise nothing is left */
    unlink(file);
    rmdir(tmp);
    return ok;
}

/* scene_save.c -- a new scene in the scenes directory from a sidecar's text (scene_save.h): a
 * hidden temporary folder holding the file, written and synced, then renamed into place with
 * RENAME_NOREPLACE, so a concurrent save or an existing scene is never replaced and a failure
 * leaves nothing behind; and what may be saved: the base a new scene names (flattened so the
 * loader's chain limit is never reached), a token bucket per client address and the total of
 * saved scenes. Not the sidecar's content (protocol/sidecar.c). */
#define _GNU_SOURCE /* renameat2, RENAME_NOREPLACE */
#include "scene_save.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>

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

/* ======================== saved scenes' sidecars ======================== */

enum { SIDECAR_MAX_BYTES = 1 << 20 };

/* What a folder scene's sidecar says of its base. */
typedef struct sidecar_info {
    bool has_base; /* names a base (a bare name) */
    bool pure;     /* base, camera and lights alone: what save writes */
    char base[130];
    struct timespec mtime;
} sidecar_info;

static bool bare_name(const char *s)
{
    return s[0] && s[0] != '.' && !strchr(s, '/') && !strchr(s, '\\') && !strstr(s, "..") &&
           strlen(s) < 130;
}

/* The JSON text of dir/name/name.scene.json (a regular file, not reached through a final link,
 * at most SIDECAR_MAX_BYTES); NULL when there is none. *mtime gets its time. */
static char *read_sidecar_text(const char *dir, const char *name, struct timespec *mtime)
{
    char path[PATH_MAX + 300];
    struct stat sb;
    if (!bare_name(name) ||
        snprintf(path, sizeof path, "%s/%s/%s.scene.json", dir, name, name) >= (int)sizeof path)
        return NULL;
    int fd = open(path, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) return NULL;
    char *text = NULL;
    if (fstat(fd, &sb) == 0 && S_ISREG(sb.st_mode) && sb.st_size <= SIDECAR_MAX_BYTES &&
        (text = malloc((size_t)sb.st_size + 1))) {
        ssize_t got = read(fd, text, (size_t)sb.st_size);
        text[got > 0 ? got : 0] = '\0';
        *mtime = sb.st_mtim;
    }
    close(fd);
    return text;
}

/* Reads the sidecar of folder scene `name` in dir; false when it has none (or no JSON object). */
static bool read_sidecar(const char *dir, const char *name, sidecar_info *in)
{
    memset(in, 0, sizeof *in);
    char *text = read_sidecar_text(dir, name, &in->mtime);
    cJSON *root = text ? cJSON_Parse(text) : NULL;
    free(text);
    if (!cJSON_IsObject(root)) return cJSON_Delete(root), false;
    const cJSON *base = cJSON_GetObjectItemCaseSensitive(root, "base");
    in->has_base = cJSON_IsString(base) && bare_name(base->valuestring);
    if (in->has_base) snprintf(in->base, sizeof in->base, "%s", base->valuestring);
    in->pure = in->has_base;
    for (const cJSON *e = root->child; e && in->pure; e = e->next)
        in->pure = !strcmp(e->string, "base") || !strcmp(e->string, "camera") ||
                   !strcmp(e->string, "lights");
    cJSON_Delete(root);
    return true;
}

/* Sidecars with a base the loader follows when loading a scene based on `at` (one for the new
 * scene's own link, then one per sidecar down the chain), stopping past IIRD_SAVE_MAX_CHAIN. */
static int chain_links(const char *dir, const char *at)
{
    char name[130];
    sidecar_info in;
    int links = 0;
    snprintf(name, sizeof name, "%s", at);
    while (strcmp(name, "builtin") != 0 && links <= IIRD_SAVE_MAX_CHAIN) {
        links++;
        if (!read_sidecar(dir, name, &in) || !in.has_base) break;
        snprintf(name, sizeof name, "%s", in.base);
    }
    return links;
}

bool iird_save_base(const char *dir, const char *scene, char *base, size_t n, iird_proto_error *err)
{
    char cur[130];
    sidecar_info in;
    snprintf(cur, sizeof cur, "%s", scene);
    for (int hops = 0; hops < 64 && strcmp(cur, "builtin") != 0; hops++) {
        if (!read_sidecar(dir, cur, &in) || !in.pure) break;
        snprintf(cur, sizeof cur, "%s", in.base); /* its camera and lights are replaced anyway */
    }
    if (chain_links(dir, cur) > IIRD_SAVE_MAX_CHAIN)
        return iird_proto_fail(err, IIRD_E_UNSUPPORTED, "save.name",
                               "scene %s is based on a chain of more than %d scenes, so a scene "
                               "saved from it could not be loaded; send save without a name to "
                               "get the sidecar",
                               scene, IIRD_SAVE_MAX_CHAIN - 1);
    snprintf(base, n, "%s", cur);
    return true;
}

/* ======================== the limits ======================== */

enum { BUCKETS = 256 }; /* client addresses tracked; the least recently seen makes room */

typedef struct bucket {
    char addr[64];
    double tokens, at_ms; /* at_ms 0: free */
} bucket;

typedef struct saved_scene {
    char *name;
    struct timespec mtime;
} saved_scene;

struct iird_saves {
    int max_saved, per_minute;
    saved_scene *saved; /* oldest first */
    size_t n, cap;
    bucket buckets[BUCKETS];
};

static bool add_saved(iird_saves *s, const char *name, struct timespec mtime)
{
    if (s->n == s->cap) {
        size_t cap = s->cap ? 2 * s->cap : 32;
        saved_scene *grown = realloc(s->saved, cap * sizeof *grown);
        if (!grown) return false;
        s->saved = grown, s->cap = cap;
    }
    char *copy = strdup(name);
    if (!copy) return false;
    s->saved[s->n++] = (saved_scene){copy, mtime};
    return true;
}

static int older_first(const void *pa, const void *pb)
{
    const saved_scene *a = pa, *b = pb;
    if (a->mtime.tv_sec != b->mtime.tv_sec) return a->mtime.tv_sec < b->mtime.tv_sec ? -1 : 1;
    if (a->mtime.tv_nsec != b->mtime.tv_nsec) return a->mtime.tv_nsec < b->mtime.tv_nsec ? -1 : 1;
    return strcmp(a->name, b->name);
}

/* The folders of dir whose sidecars name a base, oldest first. */
static bool scan_saved(iird_saves *s, const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return true; /* no scenes folder: nothing saved yet */
    bool ok = true;
    sidecar_info in;
    for (struct dirent *de; ok && (de = readdir(d));)
        if (de->d_name[0] != '.' && read_sidecar(dir, de->d_name, &in) && in.has_base)
            ok = add_saved(s, de->d_name, in.mtime);
    closedir(d);
    if (s->n) qsort(s->saved, s->n, sizeof *s->saved, older_first);
    return ok;
}

iird_saves *iird_saves_create(const char *dir, int max_saved, int per_minute)
{
    iird_saves *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->max_saved = max_saved, s->per_minute = per_minute;
    if (!scan_saved(s, dir)) {
        iird_saves_destroy(s);
        return NULL;
    }
    return s;
}

void iird_saves_destroy(iird_saves *s)
{
    if (!s) return;
    for (size_t i = 0; i < s->n; i++) free(s->saved[i].name);
    free(s->saved);
    free(s);
}

/* addr's bucket, or the least recently used one made addr's with a full bucket. */
static bucket *bucket_of(iird_saves *s, const char *addr, double now_ms)
{
    bucket *lru = &s->buckets[0];
    for (int i = 0; i < BUCKETS; i++) {
        bucket *b = &s->buckets[i];
        if (b->at_ms > 0 && !strcmp(b->addr, addr)) return b;
        if (b->at_ms < lru->at_ms) lru = b;
    }
    snprintf(lru->addr, sizeof lru->addr, "%s", addr);
    lru->tokens = s->per_minute, lru->at_ms = now_ms;
    return lru;
}

bool iird_saves_admit(iird_saves *s, const char *addr, double now_ms, iird_proto_error *err)
{
    if (s->n >= (size_t)s->max_saved)
        return iird_proto_fail(err, IIRD_E_UNSUPPORTED, "save.name",
                               "this server holds its maximum of %d saved scenes "
                               "(--max-saved-scenes); send save without a name to get the sidecar",
                               s->max_saved);
    bucket *b = bucket_of(s, addr, now_ms);
    double rate = s->per_minute / 60000.0; /* tokens per ms */
    b->tokens += (now_ms - b->at_ms) * rate;
    if (b->tokens > s->per_minute) b->tokens = s->per_minute;
    b->at_ms = now_ms > 0 ? now_ms : 1;
    if (b->tokens < 1.0)
        return iird_proto_fail(err, IIRD_E_RATE_LIMITED, "save.name",
                               "too many saves from this address: at most %d a minute "
                               "(--save-rate); the next in %.0f s",
                               s->per_minute, ceil((1.0 - b->tokens) / rate / 1000.0));
    b->tokens -= 1.0;
    return true;
}

void iird_saves_added(iird_saves *s, const char *name)
{
    struct timespec now;
    clock_gettime(CLOCK_REALTIME, &now);
    add_saved(s, name, now); /* out of memory: the count is low by one, the files are right */
}

size_t iird_saves_count(const iird_saves *s)
{
    return s ? s->n : 0;
}

/* ---- what welcome lists ---- */

typedef struct ranked {
    const char *name;
    size_t order; /* 0 = oldest */
} ranked;

static int by_name(const void *pa, const void *pb)
{
    return strcmp(((const ranked *)pa)->name, ((const ranked *)pb)->name);
}

const char **iird_saves_listed(const iird_saves *s, const char *const *names, size_t max,
                               size_t *more)
{
    size_t total = 0, n = s ? s->n : 0, out = 0;
    while (names[total]) total++;
    const char **list = malloc((total + 1) * sizeof *list);
    ranked *r = malloc((n ? n : 1) * sizeof *r);
    *more = 0;
    if (!list || !r) return free(list), free(r), NULL;
    for (size_t i = 0; i < n; i++) r[i] = (ranked){s->saved[i].name, i};
    qsort(r, n, sizeof *r, by_name);
    for (size_t i = 0; i < total; i++) {
        ranked *hit = n ? bsearch(&(ranked){names[i], 0}, r, n, sizeof *r, by_name) : NULL;
        if (hit && hit->order + max < n)
            ++*more;
        else
            list[out++] = names[i];
    }
    list[out] = NULL;
    free(r);
    return list;
}

/* ffcache.c -- the form factors' on-disk cache: its key, its directory and size cap, a file
 * format that a reader checks completely (header, sizes, offsets, columns, checksum) before
 * trusting it, files written through exclusive temporaries and read without following links or
 * blocking, and least-recently-used eviction (radiosity.h describes the format). Not how form
 * factors are computed. Holds no state: every call gets its folder and cap from the caller. */
#define _GNU_SOURCE /* O_NOFOLLOW, O_DIRECTORY, futimens, fstatat */
#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "iir/hash.h"
#include "surface.h"
#include "iir/ffcache.h"
#include "radiosity.h"

enum { FF_VERSION = 1 };
static const char FF_MAGIC[8] = {'I', 'I', 'R', 'R', 'A', 'D', 'F', 'F'};
enum { TMP_STALE_SECONDS = 3600 }; /* a temporary this old belongs to a writer that died */

typedef struct ff_header {
    char magic[8];
    uint64_t version, key, n, nnz, checksum;
    uint64_t reserved[2];
} ff_header; /* 64 bytes */

/* ---- hashing ---- */

/* What the form factors see through: each cut-out triangle's material (alpha mode, cutoff,
 * opacity, texture) and texture coordinates, and the textures' texels. A scene without cut-outs
 * keeps the key it had before cut-outs existed. */
static uint64_t cutout_key(uint64_t h, const iir_scene *s)
{
    for (uint32_t t = 0; t < s->num_triangles; t++) {
        const iir_material *m = &s->material_list[s->materials[t]];
        if (!iir_material_has_cutout(m)) continue;
        h = IIR_HASH(h, t);
        h = iir_material_hash(h, m);
        for (int k = 0; s->texcoords && k < 3; k++)
            h = IIR_HASH(h, s->texcoords[s->indices[3 * t + k]]);
    }
    for (uint32_t i = 0; i < s->num_textures; i++) h = iir_texture_hash(h, s->textures[i]);
    return h;
}

uint64_t rad_ff_key(const iir_scene *s, float target_area, int res)
{
    uint64_t h = IIR_HASH_BASIS, version = FF_VERSION;
    h = iir_hash_bytes(h, &version, sizeof version);
    h = iir_hash_bytes(h, &target_area, sizeof target_area);
    h = iir_hash_bytes(h, &res, sizeof res);
    h = iir_hash_bytes(h, &s->num_triangles, sizeof s->num_triangles);
    for (uint32_t k = 0; k < 3 * s->num_triangles; k++)
        h = iir_hash_bytes(h, &s->positions[s->indices[k]], sizeof(iir_vec3));
    return iir_scene_has_cutouts(s) ? cutout_key(h, s) : h;
}

static uint64_t payload_checksum(const rad_ff *ff)
{
    uint64_t h = iir_hash_bytes(IIR_HASH_BASIS, ff->row, ((size_t)ff->n + 1) * sizeof *ff->row);
    h = iir_hash_bytes(h, ff->col, ff->nnz * sizeof *ff->col);
    return iir_hash_bytes(h, ff->val, ff->nnz * sizeof *ff->val);
}

/* ---- the configuration ---- */

void rad_cache_dir(char *out, size_t size)
{
    const char *env = getenv("IIR_CACHE_DIR"), *xdg = getenv("XDG_CACHE_HOME");
    const char *home = getenv("HOME");
    if (env)
        snprintf(out, size, "%s", env);
    else if (xdg && *xdg)
        snprintf(out, size, "%s/iir/radiosity", xdg);
    else if (home && *home)
        snprintf(out, size, "%s/.cache/iir/radiosity", home);
    else
        snprintf(out, size, "%s", "");
}

bool rad_cache_parse_size(const char *text, uint64_t *out)
{
    char *end = NULL;
    errno = 0;
    double v = text ? strtod(text, &end) : 0.0;
    if (!text || end == text || errno || !isfinite(v) || v <= 0) return false;
    static const char units[] = "KMGT";
    const char *u = *end ? strchr(units, *end) : NULL;
    if (u) v *= (double)(1ull << (10 * (u - units + 1))), end++;
    if (*end || v < 1.0 || v >= 1.8e19) return false;
    *out = (uint64_t)v;
    return true;
}

void rad_cache_config(rad_cache *c)
{
    rad_cache_dir(c->dir, sizeof c->dir);
    c->max_bytes = RAD_CACHE_MAX_DEFAULT;
    rad_cache_parse_size(getenv(IIR_FFCACHE_MAX_ENV), &c->max_bytes);
}

/* mkdir -p; false when a component cannot be made. */
static bool make_dirs(const char *dir)
{
    char buf[1024];
    if (snprintf(buf, sizeof buf, "%s", dir) >= (int)sizeof buf) return false;
    for (char *p = buf + 1; *p; p++)
        if (*p == '/') {
            *p = 0;
            if (mkdir(buf, 0755) != 0 && errno != EEXIST) return false;
            *p = '/';
        }
    return mkdir(buf, 0755) == 0 || errno == EEXIST;
}

static void file_name(char *out, size_t size, const char *dir, uint64_t key, const char *ext)
{
    snprintf(out, size, "%s/%016llx.%s", dir, (unsigned long long)key, ext);
}

/* ---- the folder's files: counting and eviction ---- */

static bool hex16(const char *s)
{
    for (int i = 0; i < 16; i++)
        if (!isxdigit((unsigned char)s[i])) return false;
    return true;
}

/* A cache file's name: 16 hex digits and ".ff". */
static bool is_cache_name(const char *name)
{
    return hex16(name) && strcmp(name + 16, ".ff") == 0;
}

/* A temporary of rad_ff_store: ".<16 hex>.ff.XXXXXX". */
static bool is_temp_name(const char *name)
{
    return name[0] == '.' && hex16(name + 1) && strncmp(name + 17, ".ff.", 4) == 0 &&
           strlen(name + 21) == 6;
}

typedef struct cache_file {
    char name[24];
    uint64_t bytes;
    struct timespec mtime;
} cache_file;

static int older_first(const void *pa, const void *pb)
{
    const cache_file *a = pa, *b = pb;
    if (a->mtime.tv_sec != b->mtime.tv_sec) return a->mtime.tv_sec < b->mtime.tv_sec ? -1 : 1;
    if (a->mtime.tv_nsec != b->mtime.tv_nsec) return a->mtime.tv_nsec < b->mtime.tv_nsec ? -1 : 1;
    return strcmp(a->name, b->name);
}

/* Removes a dead writer's temporary (dirfd's entry `name`, not followed). */
static void remove_stale_temp(int dfd, const char *name, const struct stat *sb)
{
    if (S_ISREG(sb->st_mode) && time(NULL) - sb->st_mtim.tv_sec > TMP_STALE_SECONDS)
        unlinkat(dfd, name, 0);
}

/* Appends one file to the growing list *files (count *n, room *cap); false when out of memory. */
static bool add_file(cache_file **files, size_t *n, size_t *cap, const char *name,
                     const struct stat *sb)
{
    if (*n == *cap) {
        size_t grown = *cap ? 2 * *cap : 64;
        cache_file *f = realloc(*files, grown * sizeof *f);
        if (!f) return false;
        *files = f, *cap = grown;
    }
    cache_file *f = &(*files)[(*n)++];
    memcpy(f->name, name, 20); /* a cache name: 19 characters and its NUL */
    f->bytes = (uint64_t)sb->st_size, f->mtime = sb->st_mtim;
    return true;
}

/* The regular cache files of the open folder dfd (symlinks and the rest are not the cache's);
 * with clean, dead writers' temporaries are removed on the way. NULL with *n 0 when none. */
static cache_file *list_files(int dfd, bool clean, size_t *n)
{
    cache_file *files = NULL;
    size_t cap = 0;
    *n = 0;
    DIR *d = fdopendir(dup(dfd));
    if (!d) return NULL;
    for (struct dirent *de; (de = readdir(d));) {
        struct stat sb;
        bool cache = is_cache_name(de->d_name), temp = clean && is_temp_name(de->d_name);
        if ((!cache && !temp) || fstatat(dfd, de->d_name, &sb, AT_SYMLINK_NOFOLLOW) != 0) continue;
        if (temp)
            remove_stale_temp(dfd, de->d_name, &sb);
        else if (S_ISREG(sb.st_mode) && !add_file(&files, n, &cap, de->d_name, &sb))
            break;
    }
    closedir(d);
    return files;
}

static void sum_files(const cache_file *files, size_t n, rad_cache_usage *u)
{
    for (size_t i = 0; i < n; i++) u->bytes += files[i].bytes, u->files++;
}

bool rad_cache_scan(const char *dir, rad_cache_usage *u)
{
    memset(u, 0, sizeof *u);
    int dfd = *dir ? open(dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC) : -1;
    if (dfd < 0) return false;
    size_t n;
    cache_file *files = list_files(dfd, false, &n);
    sum_files(files, n, u);
    free(files);
    close(dfd);
    return true;
}

/* Deletes the oldest of files (sorted, oldest first) until u->bytes <= max, skipping `keep`. */
static void evict(int dfd, const cache_file *files, size_t n, const char *keep, uint64_t max,
                  rad_cache_usage *u)
{
    for (size_t i = 0; i < n && u->bytes > max; i++) {
        if (!strcmp(files[i].name, keep) || unlinkat(dfd, files[i].name, 0) != 0) continue;
        u->bytes -= files[i].bytes, u->files--;
        u->evicted++, u->evicted_bytes += files[i].bytes;
    }
}

bool rad_cache_trim(const rad_cache *c, uint64_t keep, rad_cache_usage *u)
{
    rad_cache_usage local;
    if (!u) u = &local;
    memset(u, 0, sizeof *u);
    int dfd = c->dir[0] ? open(c->dir, O_RDONLY | O_DIRECTORY | O_CLOEXEC) : -1;
    if (dfd < 0) return false;
    size_t n;
    cache_file *files = list_files(dfd, true, &n);
    sum_files(files, n, u);
    char keep_name[24];
    snprintf(keep_name, sizeof keep_name, "%016llx.ff", (unsigned long long)keep);
    if (u->bytes > c->max_bytes) {
        qsort(files, n, sizeof *files, older_first);
        evict(dfd, files, n, keep_name, c->max_bytes, u);
    }
    free(files);
    close(dfd);
    return true;
}

/* ---- loading ---- */

/* Whether the loaded arrays are consistent: offsets ascend to nnz, columns ascend below n. */
static const char *check_rows(const rad_ff *ff)
{
    if (ff->row[0] != 0 || ff->row[ff->n] != ff->nnz) return "bad row offsets";
    for (uint32_t i = 0; i < ff->n; i++) {
        if (ff->row[i + 1] < ff->row[i]) return "bad row offsets";
        for (uint64_t k = ff->row[i]; k < ff->row[i + 1]; k++)
            if (ff->col[k] >= ff->n || (k > ff->row[i] && ff->col[k] <= ff->col[k - 1]))
                return "bad column";
    }
    return NULL;
}

static bool read_arrays(FILE *f, rad_ff *ff)
{
    ff->row = malloc(((size_t)ff->n + 1) * sizeof *ff->row);
    ff->col = malloc((ff->nnz ? ff->nnz : 1) * sizeof *ff->col);
    ff->val = malloc((ff->nnz ? ff->nnz : 1) * sizeof *ff->val);
    return ff->row && ff->col && ff->val &&
           fread(ff->row, sizeof *ff->row, (size_t)ff->n + 1, f) == (size_t)ff->n + 1 &&
           fread(ff->col, sizeof *ff->col, ff->nnz, f) == ff->nnz &&
           fread(ff->val, sizeof *ff->val, ff->nnz, f) == ff->nnz;
}

/* The header's sizes against the file's: the payload must fill it exactly. Bounds n and nnz by
 * size before any product can overflow. */
static const char *check_size(const ff_header *h, uint64_t size)
{
    if (size < sizeof *h) return "short header";
    uint64_t payload = size - sizeof *h;
    if (h->n + 1 > payload / 8) return "wrong file size";
    uint64_t rest = payload - (h->n + 1) * 8;
    if (h->nnz > rest / 8 || h->nnz * 8 != rest) return "wrong file size";
    return NULL;
}

static const char *read_file(rad_ff *ff, FILE *f, uint64_t size, uint64_t key, uint32_t n)
{
    ff_header h;
    if (fread(&h, sizeof h, 1, f) != 1) return "short header";
    if (memcmp(h.magic, FF_MAGIC, sizeof FF_MAGIC) || h.version != FF_VERSION) return "bad magic";
    if (h.key != key || h.n != n) return "key or patch count differs";
    if (h.nnz > (uint64_t)n * n) return "bad size";
    const char *bad = check_size(&h, size);
    if (bad) return bad;
    ff->n = n, ff->nnz = h.nnz;
    if (!read_arrays(f, ff)) return "short read or out of memory";
    if (payload_checksum(ff) != h.checksum) return "checksum mismatch";
    return check_rows(ff);
}

const char *rad_ff_read(rad_ff *ff, FILE *f, uint64_t size, uint64_t key, uint32_t n)
{
    memset(ff, 0, sizeof *ff);
    const char *bad = read_file(ff, f, size, key, n);
    if (bad) rad_ff_free(ff);
    return bad;
}

/* Opens path for reading: never follows a symlink, never waits on a FIFO or device, and refuses
 * anything but a regular file. -1 with *why otherwise. */
static int open_regular(const char *path, struct stat *sb, const char **why)
{
    int fd = open(path, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        *why = errno == ENOENT ? "no file" : errno == ELOOP ? "a symlink" : "cannot open";
        return -1;
    }
    if (fstat(fd, sb) != 0 || !S_ISREG(sb->st_mode)) {
        close(fd);
        *why = "not a regular file";
        return -1;
    }
    return fd;
}

bool rad_ff_load(rad_ff *ff, const char *dir, uint64_t key, uint32_t n, const char **why)
{
    char path[1200];
    const char *bad = "no file";
    struct stat sb;
    memset(ff, 0, sizeof *ff);
    file_name(path, sizeof path, dir, key, "ff");
    int fd = *dir ? open_regular(path, &sb, &bad) : -1;
    FILE *f = fd >= 0 ? fdopen(fd, "rb") : NULL;
    if (fd >= 0 && !f) close(fd), bad = "cannot open";
    if (f) bad = rad_ff_read(ff, f, (uint64_t)sb.st_size, key, n);
    if (f && !bad) futimens(fileno(f), NULL); /* recency for the eviction; read-only: no matter */
    if (f) fclose(f);
    if (why) *why = bad;
    return !bad;
}

/* ---- saving ---- */

static bool write_all(FILE *f, const rad_ff *ff, uint64_t key)
{
    ff_header h = {.version = FF_VERSION, .key = key, .n = ff->n, .nnz = ff->nnz};
    memcpy(h.magic, FF_MAGIC, sizeof FF_MAGIC);
    h.checksum = payload_checksum(ff);
    return fwrite(&h, sizeof h, 1, f) == 1 &&
           fwrite(ff->row, sizeof *ff->row, (size_t)ff->n + 1, f) == (size_t)ff->n + 1 &&
           fwrite(ff->col, sizeof *ff->col, ff->nnz, f) == ff->nnz &&
           fwrite(ff->val, sizeof *ff->val, ff->nnz, f) == ff->nnz;
}

/* Writes ff into a new temporary of dir (mkstemp: O_CREAT | O_EXCL, so nothing that is already
 * there -- a symlink included -- is opened), its name in tmp. False (nothing left) on failure. */
static bool write_temp(const rad_ff *ff, const char *dir, uint64_t key, char *tmp, size_t size)
{
    snprintf(tmp, size, "%s/.%016llx.ff.XXXXXX", dir, (unsigned long long)key);
    int fd = mkstemp(tmp);
    if (fd < 0) return false;
    FILE *f = fchmod(fd, 0644) == 0 ? fdopen(fd, "wb") : NULL;
    if (!f) {
        close(fd), unlink(tmp);
        return false;
    }
    bool ok = write_all(f, ff, key);
    ok = (fclose(f) == 0) && ok;
    if (!ok) unlink(tmp);
    return ok;
}

bool rad_ff_store(const rad_ff *ff, const rad_cache *c, uint64_t key, rad_cache_usage *u,
                  iir_error *err)
{
    char path[1200], tmp[1300];
    if (u) memset(u, 0, sizeof *u);
    if (!c->dir[0]) return iir_fail(err, IIR_ERR_IO, "caching is off"), false;
    if (!make_dirs(c->dir))
        return iir_fail(err, IIR_ERR_IO, "cannot create %s: %s", c->dir, strerror(errno)), false;
    file_name(path, sizeof path, c->dir, key, "ff");
    if (!write_temp(ff, c->dir, key, tmp, sizeof tmp))
        return iir_fail(err, IIR_ERR_IO, "cannot write in %s: %s", c->dir, strerror(errno)), false;
    if (rename(tmp, path) != 0) { /* replaces whatever had the name, a symlink itself included */
        int e = errno;
        unlink(tmp);
        return iir_fail(err, IIR_ERR_IO, "cannot write %s: %s", path, strerror(e)), false;
    }
    rad_cache_trim(c, key, u);
    return true;
}

bool rad_ff_save(const rad_ff *ff, const char *dir, uint64_t key, iir_error *err)
{
    rad_cache c;
    rad_cache_config(&c);
    snprintf(c.dir, sizeof c.dir, "%s", dir);
    return rad_ff_store(ff, &c, key, NULL, err);
}

/* ---- iir/ffcache.h ---- */

void iir_ffcache_config(char *dir, size_t n, uint64_t *max_bytes)
{
    rad_cache c;
    rad_cache_config(&c);
    snprintf(dir, n, "%s", c.dir);
    *max_bytes = c.max_bytes;
}

bool iir_ffcache_usage(const char *dir, uint64_t *bytes, uint64_t *files)
{
    rad_cache_usage u;
    bool ok = rad_cache_scan(dir, &u);
    *bytes = u.bytes, *files = u.files;
    return ok;
}

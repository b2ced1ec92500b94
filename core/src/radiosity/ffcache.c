/* ffcache.c -- the form factors' on-disk cache: its key, its directory, and a file format that a
 * reader checks completely (header, sizes, offsets, columns, checksum) before trusting it
 * (radiosity.h describes the format). Not how form factors are computed. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "radiosity.h"

enum { FF_VERSION = 1 };
static const char FF_MAGIC[8] = {'I', 'I', 'R', 'R', 'A', 'D', 'F', 'F'};

typedef struct ff_header {
    char magic[8];
    uint64_t version, key, n, nnz, checksum;
    uint64_t reserved[2];
} ff_header; /* 64 bytes */

/* ---- hashing ---- */

static uint64_t fnv(uint64_t h, const void *data, size_t len)
{
    const unsigned char *p = data;
    for (size_t i = 0; i < len; i++) h = (h ^ p[i]) * 1099511628211ull;
    return h;
}
static const uint64_t FNV_BASIS = 14695981039346656037ull;

uint64_t rad_ff_key(const iir_scene *s, float target_area, int res)
{
    uint64_t h = FNV_BASIS, version = FF_VERSION;
    h = fnv(h, &version, sizeof version);
    h = fnv(h, &target_area, sizeof target_area);
    h = fnv(h, &res, sizeof res);
    h = fnv(h, &s->num_triangles, sizeof s->num_triangles);
    for (uint32_t k = 0; k < 3 * s->num_triangles; k++)
        h = fnv(h, &s->positions[s->indices[k]], sizeof(iir_vec3));
    return h;
}

static uint64_t payload_checksum(const rad_ff *ff)
{
    uint64_t h = fnv(FNV_BASIS, ff->row, ((size_t)ff->n + 1) * sizeof *ff->row);
    h = fnv(h, ff->col, ff->nnz * sizeof *ff->col);
    return fnv(h, ff->val, ff->nnz * sizeof *ff->val);
}

/* ---- the directory ---- */

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

static const char *load_file(FILE *f, rad_ff *ff, uint64_t key, uint32_t n)
{
    ff_header h;
    if (fread(&h, sizeof h, 1, f) != 1) return "short header";
    if (memcmp(h.magic, FF_MAGIC, sizeof FF_MAGIC) || h.version != FF_VERSION) return "bad magic";
    if (h.key != key || h.n != n) return "key or patch count differs";
    if (h.nnz > (uint64_t)n * n) return "bad size";
    if (fseek(f, 0, SEEK_END) != 0) return "cannot seek";
    long len = ftell(f);
    uint64_t want = sizeof h + (h.n + 1) * 8 + h.nnz * 8;
    if (len < 0 || (uint64_t)len != want) return "wrong file size";
    if (fseek(f, (long)sizeof h, SEEK_SET) != 0) return "cannot seek";
    ff->n = n, ff->nnz = h.nnz;
    if (!read_arrays(f, ff)) return "short read or out of memory";
    if (payload_checksum(ff) != h.checksum) return "checksum mismatch";
    return check_rows(ff);
}

bool rad_ff_load(rad_ff *ff, const char *dir, uint64_t key, uint32_t n, const char **why)
{
    char path[1200];
    memset(ff, 0, sizeof *ff);
    file_name(path, sizeof path, dir, key, "ff");
    FILE *f = *dir ? fopen(path, "rb") : NULL;
    const char *bad = f ? load_file(f, ff, key, n) : "no file";
    if (f) fclose(f);
    if (why) *why = bad;
    if (bad) rad_ff_free(ff);
    return !bad;
}

/* ---- saving ---- */

bool rad_ff_save(const rad_ff *ff, const char *dir, uint64_t key, iir_error *err)
{
    char path[1200], tmp[1300];
    if (!*dir) return iir_fail(err, IIR_ERR_IO, "caching is off"), false;
    if (!make_dirs(dir))
        return iir_fail(err, IIR_ERR_IO, "cannot create %s: %s", dir, strerror(errno)), false;
    file_name(path, sizeof path, dir, key, "ff");
    snprintf(tmp, sizeof tmp, "%s.%ld.tmp", path, (long)getpid());
    FILE *f = fopen(tmp, "wb");
    if (!f) return iir_fail(err, IIR_ERR_IO, "cannot write %s: %s", tmp, strerror(errno)), false;
    ff_header h = {.version = FF_VERSION, .key = key, .n = ff->n, .nnz = ff->nnz};
    memcpy(h.magic, FF_MAGIC, sizeof FF_MAGIC);
    h.checksum = payload_checksum(ff);
    bool ok = fwrite(&h, sizeof h, 1, f) == 1 &&
              fwrite(ff->row, sizeof *ff->row, (size_t)ff->n + 1, f) == (size_t)ff->n + 1 &&
              fwrite(ff->col, sizeof *ff->col, ff->nnz, f) == ff->nnz &&
              fwrite(ff->val, sizeof *ff->val, ff->nnz, f) == ff->nnz;
    ok = (fclose(f) == 0) && ok;
    if (!ok || rename(tmp, path) != 0) {
        remove(tmp);
        return iir_fail(err, IIR_ERR_IO, "cannot write %s", path), false;
    }
    return true;
}

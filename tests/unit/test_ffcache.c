/* test_ffcache.c -- the form-factor cache's folder (issue 25, finding 5): a symlink planted at a
 * writer's temporary name or at a cache file's name is never written through or read; a FIFO in
 * the cache is refused at once; the folder stays under its cap by evicting the least recently used
 * files (never the one just written); the reader refuses sizes whose products overflow. Small
 * hand-made form factors, no scene. Each test has its own folder under this test's directory. */
#define _GNU_SOURCE /* fmemopen, utimensat */
#include <dirent.h>
#include <fcntl.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <cmocka.h>

#include "testutil.h"

#include "radiosity/radiosity.h"

static const char *tmp;

/* A valid ff of n patches, each seeing the next one with F = 0.5. */
static rad_ff small_ff(uint32_t n)
{
    rad_ff ff = {.n = n, .nnz = n};
    ff.row = malloc((n + 1) * sizeof *ff.row);
    ff.col = malloc(n * sizeof *ff.col);
    ff.val = malloc(n * sizeof *ff.val);
    for (uint32_t i = 0; i <= n; i++) ff.row[i] = i;
    for (uint32_t i = 0; i < n; i++) ff.col[i] = (i + 1) % n, ff.val[i] = 0.5f;
    return ff;
}

/* A fresh folder tmp/name; its path in a static buffer. */
static const char *fresh_dir(const char *name)
{
    static char dir[1024];
    snprintf(dir, sizeof dir, "%s/%s", tmp, name);
    mkdir(dir, 0755);
    return dir;
}

static void path_of(char *out, size_t n, const char *dir, uint64_t key)
{
    snprintf(out, n, "%s/%016llx.ff", dir, (unsigned long long)key);
}

static char *read_text(const char *path)
{
    static char buf[256];
    FILE *f = fopen(path, "r");
    assert_non_null(f);
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    buf[n] = 0;
    fclose(f);
    return buf;
}

/* Regular *.ff files in dir and their bytes (counted here, not by the code under test). */
static int count_ff(const char *dir, long long *bytes)
{
    DIR *d = opendir(dir);
    assert_non_null(d);
    int n = 0;
    *bytes = 0;
    for (struct dirent *de; (de = readdir(d));) {
        size_t len = strlen(de->d_name);
        char p[1200];
        struct stat sb;
        snprintf(p, sizeof p, "%s/%s", dir, de->d_name);
        if (len > 3 && !strcmp(de->d_name + len - 3, ".ff") && lstat(p, &sb) == 0 &&
            S_ISREG(sb.st_mode))
            n++, *bytes += sb.st_size;
    }
    closedir(d);
    return n;
}

/* Sets a file's modification time to `age` seconds ago. */
static void age_file(const char *path, int age)
{
    struct timespec t[2];
    clock_gettime(CLOCK_REALTIME, &t[0]);
    t[0].tv_sec -= age, t[1] = t[0];
    assert_int_equal(utimensat(AT_FDCWD, path, t, AT_SYMLINK_NOFOLLOW), 0);
}

/* A symlink at the old predictable temporary name (KEY.ff.PID.tmp) and one at the cache file's
 * name: the save writes neither target, and leaves a regular file as the cache file. */
static void test_save_through_symlinks(void **state)
{
    (void)state;
    const char *dir = fresh_dir("symlink_save");
    char outside[1200], link[1300], path[1200];
    snprintf(outside, sizeof outside, "%s/outside.txt", tmp);
    iir_test_write_file(tmp, "outside.txt", "precious\n");
    const uint64_t key = 0x1234;
    path_of(path, sizeof path, dir, key);
    snprintf(link, sizeof link, "%s.%ld.tmp", path, (long)getpid());
    assert_int_equal(symlink(outside, link), 0);
    rad_ff ff = small_ff(8);
    iir_error err = {0};
    assert_true(rad_ff_save(&ff, dir, key, &err));
    assert_string_equal(read_text(outside), "precious\n");
    struct stat sb;
    assert_int_equal(lstat(path, &sb), 0);
    assert_true(S_ISREG(sb.st_mode));
    /* now the cache file's own name is a link to the outside file */
    unlink(path);
    assert_int_equal(symlink(outside, path), 0);
    assert_true(rad_ff_save(&ff, dir, key, &err));
    assert_string_equal(read_text(outside), "precious\n");
    assert_int_equal(lstat(path, &sb), 0);
    assert_true(S_ISREG(sb.st_mode));
    rad_ff_free(&ff);
}

/* A valid cache file reached through a symlink is not read (the link could name anything). */
static void test_load_refuses_symlink(void **state)
{
    (void)state;
    char real[1024];
    snprintf(real, sizeof real, "%s", fresh_dir("symlink_real"));
    const char *dir = fresh_dir("symlink_load");
    rad_ff ff = small_ff(8), back;
    iir_error err = {0};
    char target[1200], path[1200];
    assert_true(rad_ff_save(&ff, real, 7, &err));
    assert_true(rad_ff_load(&back, real, 7, 8, NULL));
    rad_ff_free(&back);
    path_of(target, sizeof target, real, 7);
    path_of(path, sizeof path, dir, 7);
    assert_int_equal(symlink(target, path), 0);
    const char *why = NULL;
    assert_false(rad_ff_load(&back, dir, 7, 8, &why));
    assert_non_null(why);
    assert_null(back.row);
    rad_ff_free(&ff);
}

/* A FIFO under a cache file's name: refused at once (the old reader blocked for good; the alarm
 * turns that into a failure). */
static void test_load_refuses_fifo(void **state)
{
    (void)state;
    const char *dir = fresh_dir("fifo");
    char path[1200];
    path_of(path, sizeof path, dir, 9);
    assert_int_equal(mkfifo(path, 0644), 0);
    rad_ff back;
    const char *why = NULL;
    alarm(5);
    assert_false(rad_ff_load(&back, dir, 9, 8, &why));
    alarm(0);
    assert_string_equal(why, "not a regular file");
}

/* Seven saves under a cap of 4 files' bytes ($IIR_CACHE_MAX, as --cache-max sets it): the folder
 * stays at 4 files; the three evicted are the least recently used -- not the oldest written (key
 * 1), which a load touched before the later saves; a cap below one file keeps the file just
 * written. */
static void test_cap_evicts_least_recent(void **state)
{
    (void)state;
    const char *dir = fresh_dir("cap");
    rad_ff ff = small_ff(64), back;
    const long long file_bytes = 64 + 65 * 8 + 64 * 8;
    char cap[32], path[1200];
    snprintf(cap, sizeof cap, "%lld", 4 * file_bytes);
    setenv("IIR_CACHE_MAX", cap, 1);
    iir_error err = {0};
    for (uint64_t k = 1; k <= 4; k++) {
        assert_true(rad_ff_save(&ff, dir, k, &err));
        path_of(path, sizeof path, dir, k);
        age_file(path, 500 - 100 * (int)k); /* 1 oldest ... 4 newest, all in the past */
    }
    assert_true(rad_ff_load(&back, dir, 1, 64, NULL)); /* key 1 becomes the most recent */
    rad_ff_free(&back);
    for (uint64_t k = 5; k <= 7; k++) assert_true(rad_ff_save(&ff, dir, k, &err));
    long long bytes;
    assert_int_equal(count_ff(dir, &bytes), 4);
    assert_true(bytes <= 4 * file_bytes);
    for (uint64_t k = 1; k <= 7; k++) {
        path_of(path, sizeof path, dir, k);
        assert_int_equal(access(path, F_OK) == 0, k == 1 || k >= 5);
    }
    setenv("IIR_CACHE_MAX", "100", 1); /* below one file */
    assert_true(rad_ff_save(&ff, dir, 99, &err));
    assert_int_equal(count_ff(dir, &bytes), 1);
    assert_true(rad_ff_load(&back, dir, 99, 64, NULL));
    rad_ff_free(&back);
    unsetenv("IIR_CACHE_MAX");
    rad_ff_free(&ff);
}

/* The explicit API: rad_ff_store reports what the trim left and removed; scan agrees; other
 * files of the folder (not <16 hex>.ff) are never counted or removed. */
static void test_store_usage(void **state)
{
    (void)state;
    const char *dir = fresh_dir("usage");
    rad_cache c = {.max_bytes = 2500};
    snprintf(c.dir, sizeof c.dir, "%s", dir);
    iir_test_write_file(dir, "notes.ff", "not a cache file\n");
    rad_ff ff = small_ff(40); /* 64 + 41 * 8 + 40 * 8 = 712 bytes */
    rad_cache_usage u;
    iir_error err = {0};
    for (uint64_t k = 1; k <= 3; k++) {
        assert_true(rad_ff_store(&ff, &c, k, &u, &err));
        assert_int_equal(u.evicted, 0);
    }
    assert_int_equal(u.files, 3);
    assert_int_equal(u.bytes, 3 * 712);
    assert_true(rad_ff_store(&ff, &c, 4, &u, &err));
    assert_int_equal(u.files, 3);
    assert_int_equal(u.evicted, 1);
    assert_int_equal(u.evicted_bytes, 712);
    rad_cache_usage s;
    assert_true(rad_cache_scan(dir, &s));
    assert_int_equal(s.files, 3);
    assert_int_equal(s.bytes, 3 * 712);
    long long bytes;
    assert_int_equal(count_ff(dir, &bytes), 4); /* notes.ff stays */
    uint64_t v = 0;
    assert_true(rad_cache_parse_size("512M", &v));
    assert_int_equal(v, 512ull << 20);
    assert_false(rad_cache_parse_size("12Q", &v));
    assert_false(rad_cache_parse_size("-1", &v));
    rad_ff_free(&ff);
}

/* Headers whose n and nnz would overflow the size check's products, or that ask for more than
 * the file holds, are refused before anything is allocated. */
static void test_reader_sizes(void **state)
{
    (void)state;
    unsigned char buf[64 + 64] = {0};
    const uint64_t n = 0xffffffffull,
                   nnz = (1ull << 61) - (1ull << 32) + 8; /* 8 nnz wrap to 64 B */
    memcpy(buf, "IIRRADFF", 8);
    uint64_t fields[5] = {1, 0x77, n, nnz, 0};
    memcpy(buf + 8, fields, sizeof fields);
    FILE *f = fmemopen(buf, sizeof buf, "rb");
    rad_ff ff;
    const char *why = rad_ff_read(&ff, f, sizeof buf, 0x77, (uint32_t)n);
    fclose(f);
    assert_non_null(why);
    assert_string_equal(why, "wrong file size");
    assert_null(ff.row);
}

int main(void)
{
    tmp = iir_test_tmpdir("ffcache");
    unsetenv("IIR_CACHE_MAX");
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_save_through_symlinks),
        cmocka_unit_test(test_load_refuses_symlink),
        cmocka_unit_test(test_load_refuses_fifo),
        cmocka_unit_test(test_cap_evicts_least_recent),
        cmocka_unit_test(test_store_usage),
        cmocka_unit_test(test_reader_sizes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

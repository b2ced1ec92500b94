/* fuzz_files.c -- what the fuzz targets share: the scratch directory and file writing of the
 * file-based ones, and the verbose notes; not a target. One directory per process, so parallel
 * fuzzers and tests never see each other's files. */
#include <dirent.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fuzz.h"

static char temp_dir[512];

static void remove_temp_dir(void)
{
    DIR *d = opendir(temp_dir);
    if (!d) return;
    struct dirent *de;
    char path[1024];
    while ((de = readdir(d)) != NULL) {
        if (strcmp(de->d_name, ".") == 0 || strcmp(de->d_name, "..") == 0) continue;
        snprintf(path, sizeof path, "%s/%s", temp_dir, de->d_name);
        unlink(path);
    }
    closedir(d);
    rmdir(temp_dir);
}

const char *fuzz_temp_dir(void)
{
    if (temp_dir[0]) return temp_dir;
    const char *base = getenv("IIR_TEST_TMP");
    if (!base || !*base) base = getenv("TMPDIR");
    if (!base || !*base) base = "/tmp";
    snprintf(temp_dir, sizeof temp_dir, "%s/iir-fuzz-XXXXXX", base);
    if (!mkdtemp(temp_dir)) {
        perror(temp_dir);
        temp_dir[0] = '\0';
        return NULL;
    }
    atexit(remove_temp_dir);
    return temp_dir;
}

int fuzz_write_file(const char *dir, const char *name, const uint8_t *data, size_t size)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f) return -1;
    size_t put = size ? fwrite(data, 1, size, f) : 0;
    int failed = put != size;
    failed |= fclose(f) != 0;
    return failed ? -1 : 0;
}

void fuzz_note(const char *fmt, ...)
{
    static int verbose = -1;
    if (verbose < 0) verbose = getenv("IIR_FUZZ_VERBOSE") != NULL;
    if (!verbose) return;
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

/* replay_main.c -- runs a libFuzzer target without libFuzzer: calls LLVMFuzzerTestOneInput once
 * on each regular file of the directories (or files) named on the command line, so that `make
 * test` replays every corpus entry through every target with the normal (gcc, sanitizer) build.
 * Exits 1 when an argument cannot be read or names no input at all; a target's crash ends it. */
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "fuzz.h"

/* Reads the whole file into a malloc'd buffer (not NUL-terminated, like libFuzzer's input). */
static int run_file(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) {
        perror(path);
        return 1;
    }
    size_t cap = 4096, n = 0;
    uint8_t *buf = malloc(cap);
    size_t got;
    while (buf && (got = fread(buf + n, 1, cap - n, f)) > 0) {
        n += got;
        if (n == cap) {
            uint8_t *bigger = realloc(buf, cap * 2);
            if (!bigger) free(buf);
            buf = bigger;
            cap *= 2;
        }
    }
    int failed = !buf || ferror(f);
    fclose(f);
    if (failed) {
        fprintf(stderr, "%s: cannot read\n", path);
        free(buf);
        return 1;
    }
    /* an exact-size copy, so that ASan sees reads past the input's end */
    uint8_t *input = malloc(n ? n : 1);
    if (!input) {
        free(buf);
        return 1;
    }
    memcpy(input, buf, n);
    free(buf);
    LLVMFuzzerTestOneInput(input, n);
    free(input);
    return 0;
}

static int name_cmp(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

/* Runs every regular file directly in dir, in name order; counts them into *runs. */
static int run_dir(const char *dir, int *runs)
{
    DIR *d = opendir(dir);
    if (!d) {
        perror(dir);
        return 1;
    }
    char **names = NULL;
    size_t count = 0;
    int failed = 0;
    struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        if (de->d_name[0] == '.') continue;
        char **more = realloc(names, (count + 1) * sizeof *names);
        if (!more) {
            failed = 1;
            break;
        }
        names = more;
        size_t len = strlen(dir) + strlen(de->d_name) + 2;
        names[count] = malloc(len);
        if (!names[count]) {
            failed = 1;
            break;
        }
        snprintf(names[count++], len, "%s/%s", dir, de->d_name);
    }
    closedir(d);
    if (count) qsort(names, count, sizeof *names, name_cmp);
    for (size_t i = 0; i < count; i++) {
        struct stat st;
        if (!failed && stat(names[i], &st) == 0 && S_ISREG(st.st_mode)) {
            failed = run_file(names[i]);
            (*runs)++;
        }
        free(names[i]);
    }
    free(names);
    return failed;
}

int main(int argc, char **argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: %s DIR_OR_FILE...\n", argv[0]);
        return 2;
    }
    int runs = 0;
    for (int i = 1; i < argc; i++) {
        struct stat st;
        if (stat(argv[i], &st) != 0) {
            perror(argv[i]);
            return 1;
        }
        int failed = S_ISDIR(st.st_mode) ? run_dir(argv[i], &runs) : run_file(argv[i]);
        if (!S_ISDIR(st.st_mode)) runs++;
        if (failed) return 1;
    }
    printf("%s: replayed %d input%s\n", argv[0], runs, runs == 1 ? "" : "s");
    return runs > 0 ? 0 : 1;
}

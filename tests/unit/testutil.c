/* testutil.c -- scratch directories and file writers for the unit tests. */
#include "testutil.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

const char *iir_test_tmpdir(const char *test_name)
{
    static char path[1024];
    const char *base = getenv("IIR_TEST_TMP");
    if (!base || !*base) base = "/tmp/iir-test";
    mkdir(base, 0755);
    snprintf(path, sizeof path, "%s/%s-%d", base, test_name, (int)getpid());
    mkdir(path, 0755);
    return path;
}

const char *iir_test_write_file(const char *dir, const char *name, const char *text)
{
    static char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f) return NULL;
    fwrite(text, 1, strlen(text), f);
    fclose(f);
    return path;
}

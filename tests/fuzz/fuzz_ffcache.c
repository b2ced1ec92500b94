/* fuzz_ffcache.c -- libFuzzer target for the form-factor cache's file reader
 * (core/src/radiosity/ffcache.c, rad_ff_read): the bytes are a cache file whose key and patch
 * count are taken from its own header, so inputs get past the header to the sizes, offsets,
 * columns and checksum. The reader must refuse with a reason and leave nothing allocated, or
 * return form factors whose arrays fill the file exactly and whose rows are consistent. */
#define _GNU_SOURCE /* fmemopen */
#include <string.h>

#include "fuzz.h"
#include "radiosity/radiosity.h"

static uint64_t u64_at(const uint8_t *data, size_t size, size_t at)
{
    uint64_t v = 0;
    if (size >= at + 8) memcpy(&v, data + at, 8);
    return v;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size == 0) return 0; /* fmemopen needs a buffer */
    FILE *f = fmemopen((void *)data, size, "rb");
    if (!f) return 0;
    uint64_t key = u64_at(data, size, 16), n = u64_at(data, size, 24);
    rad_ff ff;
    const char *why = rad_ff_read(&ff, f, size, key, (uint32_t)n);
    fclose(f);
    if (why) {
        FUZZ_CHECK(ff.row == NULL && ff.col == NULL && ff.val == NULL && why[0]);
        fuzz_note("refused: %s", why);
        return 0;
    }
    FUZZ_CHECK(ff.n == (uint32_t)n && 64 + ((uint64_t)ff.n + 1) * 8 + ff.nnz * 8 == size);
    FUZZ_CHECK(ff.row[0] == 0 && ff.row[ff.n] == ff.nnz);
    for (uint32_t i = 0; i < ff.n; i++)
        for (uint64_t k = ff.row[i]; k < ff.row[i + 1]; k++) FUZZ_CHECK(ff.col[k] < ff.n);
    fuzz_note("loaded %u patches, %llu non-zeros", ff.n, (unsigned long long)ff.nnz);
    rad_ff_free(&ff);
    return 0;
}

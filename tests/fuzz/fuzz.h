/* fuzz.h -- what the libFuzzer targets under tests/fuzz/ share: the entry point each defines and
 * the check that turns a broken promise of the code under test into a crash the fuzzer records.
 * Not the targets themselves (fuzz_*.c) and not the corpus replay driver (replay_main.c). */
#ifndef IIR_FUZZ_H
#define IIR_FUZZ_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

/* Each fuzz_*.c defines this; libFuzzer (clang, `make fuzz`) or replay_main.c (any compiler,
 * `make test`) calls it once per input. Returns 0. */
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

/* Aborts with file and line when cond is false: the fuzzer saves the input as a crash. */
#define FUZZ_CHECK(cond)                                                                           \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            fprintf(stderr, "%s:%d: fuzz check failed: %s\n", __FILE__, __LINE__, #cond);          \
            abort();                                                                               \
        }                                                                                          \
    } while (0)

/* A directory of this process's own for targets that need files (the mesh loader), made on first
 * use under $IIR_TEST_TMP, else $TMPDIR, else /tmp, and removed with its files at exit. NULL when
 * it cannot be made. */
const char *fuzz_temp_dir(void);

/* Prints what became of an input (printf-style, one line) when IIR_FUZZ_VERBOSE is set, to see
 * which seeds get past which checks; silent otherwise. */
void fuzz_note(const char *fmt, ...) __attribute__((format(printf, 1, 2)));

/* Writes size bytes to dir/name; returns 0 on success. */
int fuzz_write_file(const char *dir, const char *name, const uint8_t *data, size_t size);

#endif

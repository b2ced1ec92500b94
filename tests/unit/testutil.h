/* testutil.h -- helpers shared by the unit tests: a scratch directory and small file writers.
 * Nothing here decides a test's outcome. */
#ifndef IIR_TESTUTIL_H
#define IIR_TESTUTIL_H

#include <stddef.h>

/* A fresh directory for this test executable (under $IIR_TEST_TMP or /tmp); returns its path. */
const char *iir_test_tmpdir(const char *test_name);

/* Writes text to dir/name, returns the full path in a static buffer (overwritten by the next call).
 */
const char *iir_test_write_file(const char *dir, const char *name, const char *text);

#endif

/* status.h -- how iir reports expected failures: a status code plus a message a user can act on.
 *
 * Every fallible public function returns an iir_status and, when given a non-NULL iir_error*,
 * fills it with a sentence that names the thing that failed (file, field, value) and why.
 * Broken invariants are asserts, never status codes. */
#ifndef IIR_STATUS_H
#define IIR_STATUS_H

#include <stdbool.h>

#ifdef __cplusplus
extern "C" {
#endif

typedef enum iir_status {
    IIR_OK = 0,
    IIR_ERR_IO,          /* a file is missing, unreadable or unwritable */
    IIR_ERR_FORMAT,      /* a file or message is malformed */
    IIR_ERR_INVALID,     /* a value is out of range, NaN, or makes no sense */
    IIR_ERR_UNSUPPORTED, /* a valid request this build cannot honour */
    IIR_ERR_NOMEM,       /* allocation failed */
    IIR_ERR_INTERRUPTED, /* the user asked us to stop */
    IIR_ERR_INTERNAL     /* a library we call failed in a way we did not expect */
} iir_status;

typedef struct iir_error {
    iir_status status;
    char msg[512];
} iir_error;

/* Records `status` and a printf-style message into err (if err is not NULL) and returns status,
 * so callers can write `return iir_fail(err, IIR_ERR_IO, "cannot open %s", path);`. */
iir_status iir_fail(iir_error *err, iir_status status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* Short stable name of a status ("io", "format", ...), for logs and protocol error codes. */
const char *iir_status_name(iir_status status);

/* Process exit code for a status: 0 ok, 2 invalid input/format, 3 io, 4 unsupported, 130
 * interrupted, 1 otherwise. Documented in docs/cli.md. */
int iir_status_exit_code(iir_status status);

/* A hook that lets long work end early (a live session's new input, a closing session, shutdown):
 * polled from any of the worker's threads, so it must be thread-safe (e.g. an atomic load); once it
 * returns true the work skips what remains and fails with IIR_ERR_INTERRUPTED. */
typedef bool (*iir_stop_fn)(void *ctx);

/* A stop hook with its context, handed to work that has no method state to keep it in (a method's
 * creation, a radiosity solve); fn NULL = never stop. */
typedef struct iir_stop {
    iir_stop_fn fn;
    void *ctx;
} iir_stop;

/* Whether the work under way should end now (s may be NULL). */
static inline bool iir_stop_now(const iir_stop *s)
{
    return s && s->fn && s->fn(s->ctx);
}

#ifdef __cplusplus
}
#endif
#endif

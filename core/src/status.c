/* status.c -- formatting of iir_error; nothing else. */
#include "iir/status.h"

#include <stdarg.h>
#include <stdio.h>

iir_status iir_fail(iir_error *err, iir_status status, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
        err->status = status;
    }
    return status;
}

const char *iir_status_name(iir_status status)
{
    switch (status) {
    case IIR_OK:
        return "ok";
    case IIR_ERR_IO:
        return "io";
    case IIR_ERR_FORMAT:
        return "format";
    case IIR_ERR_INVALID:
        return "invalid";
    case IIR_ERR_UNSUPPORTED:
        return "unsupported";
    case IIR_ERR_NOMEM:
        return "nomem";
    case IIR_ERR_INTERRUPTED:
        return "interrupted";
    case IIR_ERR_INTERNAL:
        return "internal";
    }
    return "unknown";
}

int iir_status_exit_code(iir_status status)
{
    switch (status) {
    case IIR_OK:
        return 0;
    case IIR_ERR_FORMAT:
    case IIR_ERR_INVALID:
        return 2;
    case IIR_ERR_IO:
        return 3;
    case IIR_ERR_UNSUPPORTED:
        return 4;
    case IIR_ERR_INTERRUPTED:
        return 130;
    default:
        return 1;
    }
}

/* protocol_fields.c -- the protocol's errors and the readers of single JSON values (integers,
 * numbers, vectors, strings, enums) that check type and range and name the field's path in the
 * error; UTF-8 checks. Not which fields a message has (protocol_parse.c). */
#include "protocol_internal.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

/* ======================== errors ======================== */

const char *iird_err_name(iird_err code)
{
    static const char *const names[IIRD_E_COUNT] = {
        "bad_json",     "too_large",   "bad_type",  "unknown_type", "unknown_field",
        "out_of_range", "bad_field",   "not_ready", "unauthorized", "unsupported",
        "rate_limited", "scene_error", "busy",      "internal",     "idle_timeout"};
    return (unsigned)code < IIRD_E_COUNT ? names[code] : "internal";
}

bool iird_proto_fail(iird_proto_error *e, iird_err code, const char *field, const char *fmt, ...)
{
    if (!e) return false;
    e->code = code;
    snprintf(e->field, sizeof e->field, "%s", field ? field : "");
    iird_utf8_trim(e->field);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(e->message, sizeof e->message, fmt, ap);
    va_end(ap);
    iird_utf8_trim(e->message);
    return false;
}

/* ======================== UTF-8 ======================== */

/* Length of the well-formed sequence at s (n bytes available), 0 if there is none. */
static size_t utf8_seq(const unsigned char *s, size_t n)
{
    unsigned c = s[0];
    if (c >= 0x01 && c < 0x80) return 1;
    size_t len = c >= 0xC2 && c <= 0xDF   ? 2
                 : c >= 0xE0 && c <= 0xEF ? 3
                 : c >= 0xF0 && c <= 0xF4 ? 4
                                          : 0;
    if (len == 0 || len > n) return 0;
    for (size_t i = 1; i < len; i++)
        if ((s[i] & 0xC0) != 0x80) return 0;
    /* overlong 3- and 4-byte forms, surrogates, past U+10FFFF */
    if (c == 0xE0 && s[1] < 0xA0) return 0;
    if (c == 0xED && s[1] >= 0xA0) return 0;
    if (c == 0xF0 && s[1] < 0x90) return 0;
    if (c == 0xF4 && s[1] >= 0x90) return 0;
    return len;
}

bool iird_utf8_valid(const char *s, size_t len)
{
    const unsigned char *u = (const unsigned char *)s;
    for (size_t i = 0; i < len;) {
        size_t n = utf8_seq(u + i, len - i);
        if (n == 0) return false;
        i += n;
    }
    return true;
}

void iird_utf8_trim(char *s)
{
    size_t len = strlen(s), i = 0;
    while (i < len) {
        size_t n = utf8_seq((const unsigned char *)s + i, len - i);
        if (n == 0) break;
        i += n;
    }
    s[i] = '\0';
}

/* ======================== paths and JSON types ======================== */

void iird_path(char out[IIRD_PATH_BYTES], const char *prefix, const char *name)
{
    snprintf(out, IIRD_PATH_BYTES, "%s%s%s", prefix, *prefix ? "." : "", name);
    iird_utf8_trim(out);
}

const char *iird_json_kind(const cJSON *v)
{
    return iir_json_kind(v);
}

/* ======================== values (json_read.h) ======================== */

/* The protocol's code for a reader's fault. */
static iird_err code_of(iir_json_fault f)
{
    switch (f) {
    case IIR_JSON_BAD_TYPE:
    case IIR_JSON_MISSING:
        return IIRD_E_BAD_TYPE;
    case IIR_JSON_UNKNOWN_FIELD:
        return IIRD_E_UNKNOWN_FIELD;
    default:
        return IIRD_E_OUT_OF_RANGE;
    }
}

static void to_proto(void *ctx, iir_json_fault f, const char *path, const char *msg)
{
    iird_proto_fail(ctx, code_of(f), path, "%s", msg);
}

/* A reader reporting into c's protocol error, and the field's path. */
static iir_json_reader reader(const iird_pctx *c, const char *name, char path[IIRD_PATH_BYTES])
{
    iird_path(path, c->prefix, name);
    iir_json_reader r = {to_proto, c->err};
    return r;
}

bool iird_get_number(const iird_pctx *c, const cJSON *v, const char *name, iird_range r,
                     double *out)
{
    char path[IIRD_PATH_BYTES];
    iir_json_reader rd = reader(c, name, path);
    return iir_json_number(&rd, v, path, r, out);
}

bool iird_get_int(const iird_pctx *c, const cJSON *v, const char *name, double lo, double hi,
                  int64_t *out)
{
    char path[IIRD_PATH_BYTES];
    iir_json_reader rd = reader(c, name, path);
    return iir_json_int(&rd, v, path, lo, hi, out);
}

bool iird_get_int32(const iird_pctx *c, const cJSON *v, const char *name, int lo, int hi, int *out)
{
    int64_t w = 0;
    if (!iird_get_int(c, v, name, lo, hi, &w)) return false;
    *out = (int)w;
    return true;
}

bool iird_get_bool(const iird_pctx *c, const cJSON *v, const char *name, bool *out)
{
    char path[IIRD_PATH_BYTES];
    iir_json_reader rd = reader(c, name, path);
    return iir_json_bool(&rd, v, path, out);
}

bool iird_get_vec3(const iird_pctx *c, const cJSON *v, const char *name, double lo, double hi,
                   iir_vec3 *out)
{
    char path[IIRD_PATH_BYTES];
    iir_json_reader rd = reader(c, name, path);
    return iir_json_vec3(&rd, v, path, lo, hi, out);
}

/* ======================== strings ======================== */

/* out_of_range naming path when the string held a \u0000 (IIRD_NUL_MARK) escape. */
static bool no_nul(const iird_pctx *c, const char *path, const cJSON *v)
{
    if (!strchr(v->valuestring, IIRD_NUL_MARK)) return true;
    return iird_proto_fail(c->err, IIRD_E_OUT_OF_RANGE, path,
                           "%s must not hold a NUL character (\\u0000)", path);
}

bool iird_get_string(const iird_pctx *c, const cJSON *v, const char *name, size_t max_bytes,
                     char *out)
{
    char path[IIRD_PATH_BYTES];
    iir_json_reader rd = reader(c, name, path);
    if (cJSON_IsString(v) && v->valuestring && !no_nul(c, path, v)) return false;
    return iir_json_string(&rd, v, path, 0, max_bytes, out);
}

bool iird_get_enum(const iird_pctx *c, const cJSON *v, const char *name, const char *const *allowed,
                   int *index)
{
    char path[IIRD_PATH_BYTES];
    iir_json_reader rd = reader(c, name, path);
    if (cJSON_IsString(v) && v->valuestring && !no_nul(c, path, v)) return false;
    return iir_json_enum(&rd, v, path, allowed, index);
}

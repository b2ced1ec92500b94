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
    if (!v) return "nothing";
    if (cJSON_IsNumber(v)) return "a number";
    if (cJSON_IsString(v)) return "a string";
    if (cJSON_IsBool(v)) return "a boolean";
    if (cJSON_IsNull(v)) return "null";
    if (cJSON_IsArray(v)) return "an array";
    if (cJSON_IsObject(v)) return "an object";
    return "an unknown JSON value";
}

/* ======================== numbers ======================== */

static bool number_value(const iird_pctx *c, const char *path, const cJSON *v, const char *what,
                         double *out)
{
    if (!cJSON_IsNumber(v))
        return iird_proto_fail(c->err, IIRD_E_BAD_TYPE, path, "%s must be %s, got %s", path, what,
                               iird_json_kind(v));
    if (!isfinite(v->valuedouble))
        return iird_proto_fail(c->err, IIRD_E_OUT_OF_RANGE, path,
                               "%s must be a finite number (got one that overflows a double)",
                               path);
    *out = v->valuedouble;
    return true;
}

bool iird_get_number(const iird_pctx *c, const cJSON *v, const char *name, iird_range r,
                     double *out)
{
    char path[IIRD_PATH_BYTES];
    iird_path(path, c->prefix, name);
    if (!number_value(c, path, v, "a number", out)) return false;
    bool ok = (r.open_lo ? *out > r.lo : *out >= r.lo) && (r.open_hi ? *out < r.hi : *out <= r.hi);
    if (!ok)
        return iird_proto_fail(c->err, IIRD_E_OUT_OF_RANGE, path,
                               "%s must be in %c%.15g, %.15g%c%s%s, got %.15g", path,
                               r.open_lo ? '(' : '[', r.lo, r.hi, r.open_hi ? ')' : ']',
                               r.unit ? " " : "", r.unit ? r.unit : "", *out);
    return true;
}

bool iird_get_int(const iird_pctx *c, const cJSON *v, const char *name, double lo, double hi,
                  int64_t *out)
{
    char path[IIRD_PATH_BYTES];
    double d = 0.0;
    iird_path(path, c->prefix, name);
    if (!number_value(c, path, v, "an integer", &d)) return false;
    if (d != floor(d))
        return iird_proto_fail(c->err, IIRD_E_BAD_TYPE, path, "%s must be an integer, got %.15g",
                               path, d);
    if (d < lo || d > hi)
        return iird_proto_fail(c->err, IIRD_E_OUT_OF_RANGE, path,
                               "%s must be in [%.17g, %.17g], got %.17g", path, lo, hi, d);
    *out = (int64_t)d;
    return true;
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
    iird_path(path, c->prefix, name);
    if (!cJSON_IsBool(v))
        return iird_proto_fail(c->err, IIRD_E_BAD_TYPE, path, "%s must be true or false, got %s",
                               path, iird_json_kind(v));
    *out = cJSON_IsTrue(v);
    return true;
}

bool iird_get_vec3(const iird_pctx *c, const cJSON *v, const char *name, double lo, double hi,
                   iir_vec3 *out)
{
    char path[IIRD_PATH_BYTES], ep[IIRD_PATH_BYTES];
    iird_path(path, c->prefix, name);
    int n = cJSON_IsArray(v) ? cJSON_GetArraySize(v) : -1;
    if (n != 3) {
        if (n < 0)
            return iird_proto_fail(c->err, IIRD_E_BAD_TYPE, path,
                                   "%s must be an array of 3 numbers, got %s", path,
                                   iird_json_kind(v));
        return iird_proto_fail(c->err, IIRD_E_BAD_TYPE, path,
                               "%s must be an array of 3 numbers, got %d elements", path, n);
    }
    double e[3];
    int i = 0;
    for (const cJSON *x = v->child; x; x = x->next, i++) {
        if (snprintf(ep, sizeof ep, "%s[%d]", path, i) >= (int)sizeof ep) /* cut short */
            iird_utf8_trim(ep);
        if (!number_value(c, ep, x, "a number", &e[i])) return false;
        if (e[i] < lo || e[i] > hi)
            return iird_proto_fail(c->err, IIRD_E_OUT_OF_RANGE, ep,
                                   "%s must be in [%.15g, %.15g], got %.15g", ep, lo, hi, e[i]);
    }
    *out = iir_v3((float)e[0], (float)e[1], (float)e[2]);
    return true;
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
    iird_path(path, c->prefix, name);
    if (!cJSON_IsString(v) || !v->valuestring)
        return iird_proto_fail(c->err, IIRD_E_BAD_TYPE, path, "%s must be a string, got %s", path,
                               iird_json_kind(v));
    if (!no_nul(c, path, v)) return false;
    size_t len = strlen(v->valuestring);
    if (len > max_bytes)
        return iird_proto_fail(c->err, IIRD_E_OUT_OF_RANGE, path,
                               "%s must be at most %zu bytes long, got %zu", path, max_bytes, len);
    memcpy(out, v->valuestring, len + 1);
    return true;
}

bool iird_get_enum(const iird_pctx *c, const cJSON *v, const char *name, const char *const *allowed,
                   int *index)
{
    char path[IIRD_PATH_BYTES], got[40], list[160] = "";
    iird_path(path, c->prefix, name);
    if (!cJSON_IsString(v) || !v->valuestring)
        return iird_proto_fail(c->err, IIRD_E_BAD_TYPE, path, "%s must be a string, got %s", path,
                               iird_json_kind(v));
    if (!no_nul(c, path, v)) return false;
    for (int i = 0; allowed[i]; i++) {
        if (strcmp(v->valuestring, allowed[i]) == 0) {
            *index = i;
            return true;
        }
        size_t used = strlen(list);
        snprintf(list + used, sizeof list - used, "%s\"%s\"", i ? ", " : "", allowed[i]);
    }
    snprintf(got, sizeof got, "%s", v->valuestring);
    iird_utf8_trim(got);
    return iird_proto_fail(c->err, IIRD_E_OUT_OF_RANGE, path, "%s must be one of %s, got \"%s\"",
                           path, list, got);
}

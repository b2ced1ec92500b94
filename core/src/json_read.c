/* json_read.c -- the readers of single JSON values and of an object's member names that the scene
 * sidecar, the animation scripts and the protocol share (json_read.h): type, range and names
 * checked, faults reported with the field's path and what it got. Not what fields a file or a
 * message has (their parsers). */
#include "iir/json_read.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

static bool fault(const iir_json_reader *r, iir_json_fault f, const char *path, const char *fmt,
                  ...) __attribute__((format(printf, 4, 5)));

static bool fault(const iir_json_reader *r, iir_json_fault f, const char *path, const char *fmt,
                  ...)
{
    char msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    r->fail(r->ctx, f, path, msg);
    return false;
}

/* ---- a file's errors ---- */

static void file_fail(void *ctx, iir_json_fault f, const char *path, const char *msg)
{
    iir_json_file *jf = ctx;
    (void)path;
    jf->status = iir_fail(jf->err, f == IIR_JSON_OUT_OF_RANGE ? IIR_ERR_INVALID : IIR_ERR_FORMAT,
                          "%s: %s", jf->source, msg);
}

void iir_json_file_init(iir_json_file *f, const char *source, iir_error *err)
{
    *f = (iir_json_file){{file_fail, f}, source, err, IIR_OK};
}

iir_status iir_json_file_status(const iir_json_file *f, bool ok)
{
    return ok ? IIR_OK : f->status;
}

/* ---- paths ---- */

void iir_json_path(char out[IIR_JSON_PATH], const char *prefix, const char *name)
{
    if (snprintf(out, IIR_JSON_PATH, "%s%s%s", prefix, *prefix ? "." : "", name) >= IIR_JSON_PATH)
        out[IIR_JSON_PATH - 1] = '\0';
}

void iir_json_index(char out[IIR_JSON_PATH], const char *prefix, int i)
{
    if (snprintf(out, IIR_JSON_PATH, "%s[%d]", prefix, i) >= IIR_JSON_PATH)
        out[IIR_JSON_PATH - 1] = '\0';
}

const char *iir_json_kind(const cJSON *v)
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

/* ---- numbers ---- */

/* A finite number of JSON type number; what: "a number" or "an integer". */
static bool number_value(const iir_json_reader *r, const cJSON *v, const char *path,
                         const char *what, double *out)
{
    if (!cJSON_IsNumber(v))
        return fault(r, IIR_JSON_BAD_TYPE, path, "%s must be %s, got %s", path, what,
                     iir_json_kind(v));
    if (!isfinite(v->valuedouble))
        return fault(r, IIR_JSON_OUT_OF_RANGE, path,
                     "%s must be a finite number (got one that overflows a double)", path);
    *out = v->valuedouble;
    return true;
}

static bool in_range(double x, iir_json_range g)
{
    return (g.open_lo ? x > g.lo : x >= g.lo) && (g.open_hi ? x < g.hi : x <= g.hi);
}

bool iir_json_number(const iir_json_reader *r, const cJSON *v, const char *path,
                     iir_json_range range, double *out)
{
    double x = 0.0;
    if (!number_value(r, v, path, "a number", &x)) return false;
    if (!in_range(x, range))
        return fault(r, IIR_JSON_OUT_OF_RANGE, path,
                     "%s must be in %c%.15g, %.15g%c%s%s, got %.15g", path,
                     range.open_lo ? '(' : '[', range.lo, range.hi, range.open_hi ? ')' : ']',
                     range.unit ? " " : "", range.unit ? range.unit : "", x);
    *out = x;
    return true;
}

bool iir_json_int(const iir_json_reader *r, const cJSON *v, const char *path, double lo, double hi,
                  int64_t *out)
{
    double d = 0.0;
    if (!number_value(r, v, path, "an integer", &d)) return false;
    if (d != floor(d))
        return fault(r, IIR_JSON_BAD_TYPE, path, "%s must be an integer, got %.15g", path, d);
    if (d < lo || d > hi)
        return fault(r, IIR_JSON_OUT_OF_RANGE, path, "%s must be in [%.17g, %.17g], got %.17g",
                     path, lo, hi, d);
    *out = (int64_t)d;
    return true;
}

bool iir_json_bool(const iir_json_reader *r, const cJSON *v, const char *path, bool *out)
{
    if (!cJSON_IsBool(v))
        return fault(r, IIR_JSON_BAD_TYPE, path, "%s must be true or false, got %s", path,
                     iir_json_kind(v));
    *out = cJSON_IsTrue(v);
    return true;
}

bool iir_json_numbers(const iir_json_reader *r, const cJSON *v, const char *path, int n, double lo,
                      double hi, double *out)
{
    int got = cJSON_IsArray(v) ? cJSON_GetArraySize(v) : -1;
    if (got < 0)
        return fault(r, IIR_JSON_BAD_TYPE, path, "%s must be an array of %d numbers, got %s", path,
                     n, iir_json_kind(v));
    if (got != n)
        return fault(r, IIR_JSON_BAD_TYPE, path, "%s must be an array of %d numbers, got %d %s",
                     path, n, got, got == 1 ? "element" : "elements");
    iir_json_range range = {lo, hi, false, false, NULL};
    int i = 0;
    for (const cJSON *x = v->child; x; x = x->next, i++) {
        char ep[IIR_JSON_PATH];
        iir_json_index(ep, path, i);
        if (!iir_json_number(r, x, ep, range, &out[i])) return false;
    }
    return true;
}

bool iir_json_vec3(const iir_json_reader *r, const cJSON *v, const char *path, double lo, double hi,
                   iir_vec3 *out)
{
    double e[3];
    if (!iir_json_numbers(r, v, path, 3, lo, hi, e)) return false;
    *out = iir_v3((float)e[0], (float)e[1], (float)e[2]);
    return true;
}

/* ---- strings and names ---- */

/* Drops an incomplete UTF-8 sequence that a cut left at the end of s. */
static void cut_utf8(char *s)
{
    size_t len = strlen(s), p = len;
    while (p > 0 && len - p < 4 && ((unsigned char)s[p - 1] & 0xC0) == 0x80) p--;
    if (p == 0) return;
    unsigned char lead = (unsigned char)s[p - 1];
    size_t need = lead >= 0xF0 ? 4 : lead >= 0xE0 ? 3 : lead >= 0xC0 ? 2 : 1;
    if (p - 1 + need > len) s[p - 1] = '\0';
}

bool iir_json_string(const iir_json_reader *r, const cJSON *v, const char *path, size_t min_bytes,
                     size_t max_bytes, char *out)
{
    if (!cJSON_IsString(v) || !v->valuestring)
        return fault(r, IIR_JSON_BAD_TYPE, path, "%s must be a string, got %s", path,
                     iir_json_kind(v));
    size_t len = strlen(v->valuestring);
    if (len < min_bytes) return fault(r, IIR_JSON_OUT_OF_RANGE, path, "%s must not be empty", path);
    if (len > max_bytes)
        return fault(r, IIR_JSON_OUT_OF_RANGE, path, "%s must be at most %zu bytes long, got %zu",
                     path, max_bytes, len);
    memcpy(out, v->valuestring, len + 1);
    return true;
}

bool iir_json_enum(const iir_json_reader *r, const cJSON *v, const char *path,
                   const char *const *allowed, int *index)
{
    char got[40], list[160] = "";
    if (!cJSON_IsString(v) || !v->valuestring)
        return fault(r, IIR_JSON_BAD_TYPE, path, "%s must be a string, got %s", path,
                     iir_json_kind(v));
    for (int i = 0; allowed[i]; i++) {
        if (strcmp(v->valuestring, allowed[i]) == 0) {
            *index = i;
            return true;
        }
        size_t used = strlen(list);
        snprintf(list + used, sizeof list - used, "%s\"%s\"", i ? ", " : "", allowed[i]);
    }
    snprintf(got, sizeof got, "%s", v->valuestring);
    cut_utf8(got);
    return fault(r, IIR_JSON_OUT_OF_RANGE, path, "%s must be one of %s, got \"%s\"", path, list,
                 got);
}

static bool named(const char *name, const char *const *allowed)
{
    for (; *allowed; allowed++)
        if (strcmp(name, *allowed) == 0) return true;
    return false;
}

bool iir_json_fields(const iir_json_reader *r, const cJSON *obj, const char *path,
                     const char *const *allowed)
{
    if (!cJSON_IsObject(obj))
        return fault(r, IIR_JSON_BAD_TYPE, path, "%s must be an object, got %s",
                     *path ? path : "the top level", iir_json_kind(obj));
    for (const cJSON *it = obj->child; it; it = it->next) {
        char field[IIR_JSON_PATH];
        iir_json_path(field, path, it->string);
        if (!named(it->string, allowed)) {
            char list[256] = "";
            for (const char *const *a = allowed; *a; a++)
                snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s",
                         a == allowed ? "" : ", ", *a);
            return fault(r, IIR_JSON_UNKNOWN_FIELD, field, "%s: unknown field (known: %s)", field,
                         list);
        }
        for (const cJSON *prev = obj->child; prev != it; prev = prev->next)
            if (strcmp(prev->string, it->string) == 0)
                return fault(r, IIR_JSON_UNKNOWN_FIELD, field, "%s: field given twice", field);
    }
    return true;
}

const cJSON *iir_json_member(const iir_json_reader *r, const cJSON *obj, const char *path,
                             const char *name, bool required, const char *what)
{
    const cJSON *m = cJSON_GetObjectItemCaseSensitive(obj, name);
    if (m || !required) return m;
    char field[IIR_JSON_PATH];
    iir_json_path(field, path, name);
    fault(r, IIR_JSON_MISSING, field, "%s is required%s", field, what ? what : "");
    return NULL;
}

/* params.c -- parameter sets, one value against its row (check, parse, format), and binding a
 * table's values into an options struct. Not which tables exist (method.c, the methods). */
#include "iir/params.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ======================== sets ======================== */

iir_params iir_params_default(void)
{
    iir_params p;
    memset(&p, 0, sizeof p);
    return p;
}

static int find_index(const iir_params *p, const char *name)
{
    for (uint32_t i = 0; i < p->count; i++)
        if (strcmp(p->v[i].name, name) == 0) return (int)i;
    return -1;
}

iir_status iir_params_set(iir_params *p, const iir_param *row, double value, iir_error *err)
{
    iir_status st = iir_param_check(row, value, false, err);
    if (st != IIR_OK) return st;
    int i = find_index(p, row->name);
    if (i < 0 && p->count == IIR_PARAMS_MAX)
        return iir_fail(err, IIR_ERR_INVALID, "%s: more than %d parameters set", row->name,
                        IIR_PARAMS_MAX);
    if (i < 0) i = (int)p->count++;
    p->v[i].name = row->name;
    p->v[i].value = value;
    return IIR_OK;
}

bool iir_params_get(const iir_params *p, const char *name, double *value)
{
    int i = find_index(p, name);
    if (i >= 0 && value) *value = p->v[i].value;
    return i >= 0;
}

bool iir_params_has(const iir_params *p, const char *name)
{
    return find_index(p, name) >= 0;
}

bool iir_params_merge(iir_params *p, const iir_params *from)
{
    iir_params out = *p;
    for (uint32_t k = 0; k < from->count; k++) {
        int i = find_index(&out, from->v[k].name);
        if (i < 0 && out.count == IIR_PARAMS_MAX) return false;
        if (i < 0) i = (int)out.count++;
        out.v[i] = from->v[k];
    }
    *p = out;
    return true;
}

bool iir_params_equal(const iir_params *a, const iir_params *b)
{
    if (a->count != b->count) return false;
    for (uint32_t k = 0; k < a->count; k++) {
        double v;
        if (!iir_params_get(b, a->v[k].name, &v) || v != a->v[k].value) return false;
    }
    return true;
}

/* ======================== one value ======================== */

const char *iir_param_type_name(iir_param_type t)
{
    static const char *const names[] = {"int", "u64", "float", "bool", "enum"};
    return (unsigned)t < sizeof names / sizeof names[0] ? names[t] : "?";
}

double iir_param_max(const iir_param *row, bool live)
{
    return live && row->live_hi > 0.0 ? row->live_hi : row->hi;
}

static iir_status choice_error(const iir_param *row, const char *got, iir_error *err)
{
    char list[256] = "";
    for (int i = 0; row->choices[i]; i++) {
        size_t used = strlen(list);
        snprintf(list + used, sizeof list - used, "%s%s", i ? ", " : "", row->choices[i]);
    }
    return iir_fail(err, IIR_ERR_INVALID, "%s must be one of %s, got '%s'", row->name, list, got);
}

iir_status iir_param_check(const iir_param *row, double v, bool live, iir_error *err)
{
    double hi = iir_param_max(row, live);
    const char *unit = row->unit && row->unit[0] ? " " : "";
    if (!isfinite(v))
        return iir_fail(err, IIR_ERR_INVALID, "%s must be a finite number", row->name);
    if (row->type != IIR_PARAM_FLOAT && v != floor(v))
        return iir_fail(err, IIR_ERR_INVALID, "%s must be %s, got %.17g", row->name,
                        row->type == IIR_PARAM_BOOL ? "true or false" : "an integer", v);
    if (row->type == IIR_PARAM_ENUM && !(v >= row->lo && v <= hi)) {
        char got[32];
        snprintf(got, sizeof got, "%.17g", v);
        return choice_error(row, got, err);
    }
    if (!(v >= row->lo && v <= hi))
        return iir_fail(err, IIR_ERR_INVALID, "%s must be in [%.17g, %.17g]%s%s, got %.17g",
                        row->name, row->lo, hi, unit, row->unit ? row->unit : "", v);
    return IIR_OK;
}

static bool parse_bool(const char *text, double *v)
{
    static const char *const yes[] = {"true", "1", "on", "yes"}, *const no[] = {"false", "0", "off",
                                                                                "no"};
    for (int i = 0; i < 4; i++) {
        if (!strcmp(text, yes[i])) return *v = 1.0, true;
        if (!strcmp(text, no[i])) return *v = 0.0, true;
    }
    return false;
}

iir_status iir_param_parse(const iir_param *row, const char *text, double *v, iir_error *err)
{
    if (row->type == IIR_PARAM_ENUM) {
        for (int i = 0; row->choices[i]; i++)
            if (!strcmp(row->choices[i], text)) return *v = i, IIR_OK;
        return choice_error(row, text, err);
    }
    if (row->type == IIR_PARAM_BOOL) {
        if (parse_bool(text, v)) return IIR_OK;
        return iir_fail(err, IIR_ERR_INVALID, "%s must be true or false, got '%s'", row->name,
                        text);
    }
    char *end = NULL;
    errno = 0;
    double d = strtod(text, &end);
    if (end == text || *end || errno == ERANGE || !isfinite(d))
        return iir_fail(err, IIR_ERR_INVALID, "%s must be %s, got '%s'", row->name,
                        row->type == IIR_PARAM_FLOAT ? "a finite number" : "an integer", text);
    iir_status st = iir_param_check(row, d, false, err);
    if (st == IIR_OK) *v = d;
    return st;
}

void iir_param_format(const iir_param *row, double v, char *buf, size_t n)
{
    switch (row->type) {
    case IIR_PARAM_ENUM: {
        int i = (int)v, k = 0;
        while (row->choices[k] && k < i) k++;
        snprintf(buf, n, "%s", row->choices[k] ? row->choices[k] : "?");
        break;
    }
    case IIR_PARAM_BOOL:
        snprintf(buf, n, "%s", v != 0.0 ? "true" : "false");
        break;
    case IIR_PARAM_FLOAT: /* the shortest text that reads back as the same float */
        for (int prec = 6; prec <= 9; prec++) {
            snprintf(buf, n, "%.*g", prec, v);
            if (strtof(buf, NULL) == (float)v) break;
        }
        break;
    default:
        snprintf(buf, n, "%.0f", v);
    }
}

void iir_param_reword(iir_error *err, const iir_param *row, const char *spelling)
{
    size_t len = strlen(row->name);
    if (strncmp(err->msg, row->name, len) != 0) return;
    char rest[sizeof err->msg];
    snprintf(rest, sizeof rest, "%s", err->msg + len);
    snprintf(err->msg, sizeof err->msg, "%s%s", spelling, rest);
}

void iir_param_option_name(const iir_param *row, char *buf, size_t n)
{
    snprintf(buf, n, "%s", row->name);
    for (char *c = buf; *c; c++)
        if (*c == '_') *c = '-';
}

/* ======================== tables ======================== */

const iir_param *iir_param_table_find(const iir_param_table *t, const char *name)
{
    for (int i = 0; i < t->count; i++)
        if (!strcmp(t->rows[i].name, name)) return &t->rows[i];
    return NULL;
}

static void write_field(const iir_param *row, void *opts, double v)
{
    char *f = (char *)opts + row->offset;
    switch (row->type) {
    case IIR_PARAM_INT:
    case IIR_PARAM_ENUM:
        *(int *)f = (int)v;
        break;
    case IIR_PARAM_U64:
        *(uint64_t *)f = (uint64_t)v;
        break;
    case IIR_PARAM_FLOAT:
        *(float *)f = (float)v;
        break;
    case IIR_PARAM_BOOL:
        *(bool *)f = v != 0.0;
        break;
    }
}

double iir_param_read(const iir_param *row, const void *opts)
{
    const char *f = (const char *)opts + row->offset;
    switch (row->type) {
    case IIR_PARAM_INT:
    case IIR_PARAM_ENUM:
        return *(const int *)f;
    case IIR_PARAM_U64:
        return (double)*(const uint64_t *)f;
    case IIR_PARAM_FLOAT:
        return *(const float *)f;
    case IIR_PARAM_BOOL:
        return *(const bool *)f ? 1.0 : 0.0;
    }
    return 0.0;
}

void iir_params_defaults(const iir_param_table *t, void *opts)
{
    for (int i = 0; i < t->count; i++) write_field(&t->rows[i], opts, t->rows[i].def);
}

iir_status iir_params_bind(const iir_param_table *t, const iir_params *p, const iir_params *given,
                           void *opts, const iir_param **bad, iir_error *err)
{
    const iir_param *unused;
    if (!bad) bad = &unused;
    *bad = NULL;
    for (int i = 0; i < t->count; i++) {
        const iir_param *row = &t->rows[i];
        double v = row->def;
        iir_params_get(p, row->name, &v);
        iir_status st = iir_param_check(row, v, false, err);
        if (st != IIR_OK) return *bad = row, st;
        write_field(row, opts, v);
    }
    return t->check ? t->check(opts, given ? given : p, bad, err) : IIR_OK;
}

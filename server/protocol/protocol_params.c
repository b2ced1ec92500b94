/* protocol_params.c -- parameters on the wire: the session's own frame and stream settings as a
 * parameter table (iird_stream_table), reading one params field by its row, and parameter tables
 * and values as JSON (welcome, state, render.json). The method parameters themselves are the
 * methods' tables (method.h); nothing here names one. */
#include "protocol_internal.h"

#include <stddef.h>
#include <stdio.h>
#include <string.h>

/* width and height are further bound by the server's limits (protocol_apply.c). */
static const iir_param STREAM_ROWS[] = {
    {"width", IIR_PARAM_INT, offsetof(iird_settings, width), 512, 16, 16384, 0, NULL, "pixels",
     "frame width", IIR_PARAM_RESTART},
    {"height", IIR_PARAM_INT, offsetof(iird_settings, height), 384, 16, 16384, 0, NULL, "pixels",
     "frame height", IIR_PARAM_RESTART},
    {"quality", IIR_PARAM_INT, offsetof(iird_settings, quality), 80, 1, 100, 0, NULL, "",
     "JPEG quality of streamed frames", IIR_PARAM_LIVE},
    {"exposure", IIR_PARAM_FLOAT, offsetof(iird_settings, exposure), 0, -20, 20, 0, NULL, "stops",
     "exposure of streamed frames", IIR_PARAM_LIVE},
    {"refine", IIR_PARAM_BOOL, offsetof(iird_settings, refine), 1, 0, 1, 0, NULL, "",
     "refine the frame progressively while nothing moves", IIR_PARAM_LIVE},
    {"domain", IIR_PARAM_BOOL, offsetof(iird_settings, domain), 1, 0, 1, 0, NULL, "",
     "send the light's VPL domain with frames", IIR_PARAM_LIVE},
};
const iir_param_table iird_stream_table = {"frame and stream", STREAM_ROWS,
                                           sizeof STREAM_ROWS / sizeof STREAM_ROWS[0], NULL};

const iir_param *iird_params_row(const char *name)
{
    const iir_param *row = iir_param_table_find(&iird_stream_table, name);
    return row ? row : iir_method_any_param(name);
}

bool iird_get_param(const iird_pctx *c, const cJSON *v, const iir_param *row, double *out)
{
    bool b = false;
    int k = 0;
    int64_t i = 0;
    iird_range r = {row->lo, iir_param_max(row, true), false, false,
                    row->unit[0] ? row->unit : NULL};
    switch (row->type) {
    case IIR_PARAM_BOOL:
        if (!iird_get_bool(c, v, row->name, &b)) return false;
        *out = b ? 1.0 : 0.0;
        return true;
    case IIR_PARAM_ENUM:
        if (!iird_get_enum(c, v, row->name, row->choices, &k)) return false;
        *out = k;
        return true;
    case IIR_PARAM_FLOAT:
        return iird_get_number(c, v, row->name, r, out);
    default:
        if (!iird_get_int(c, v, row->name, r.lo, r.hi, &i)) return false;
        *out = (double)i;
        return true;
    }
}

/* ======================== JSON ======================== */

static bool add(cJSON *o, const char *name, cJSON *item)
{
    if (item && cJSON_AddItemToObject(o, name, item)) return true;
    cJSON_Delete(item);
    return false;
}

cJSON *iird_json_param_value(const iir_param *row, double v)
{
    if (row->type == IIR_PARAM_BOOL) return cJSON_CreateBool(v != 0.0);
    if (row->type == IIR_PARAM_ENUM) {
        char name[64];
        iir_param_format(row, v, name, sizeof name);
        return cJSON_CreateString(name);
    }
    if (row->type == IIR_PARAM_U64 && v > 2147483647.0) { /* all digits, as cJSON would not */
        char digits[32];
        snprintf(digits, sizeof digits, "%.0f", v);
        return cJSON_CreateRaw(digits);
    }
    return cJSON_CreateNumber(row->type == IIR_PARAM_FLOAT ? iird_compact_float((float)v) : v);
}

static cJSON *row_json(const iir_param *row)
{
    cJSON *o = cJSON_CreateObject(), *choices = NULL;
    bool ok = o && add(o, "name", cJSON_CreateString(row->name)) &&
              add(o, "type", cJSON_CreateString(iir_param_type_name(row->type))) &&
              add(o, "default", iird_json_param_value(row, row->def));
    if (ok && row->type != IIR_PARAM_BOOL && row->type != IIR_PARAM_ENUM) /* exact digits */
        ok = add(o, "min", iird_json_param_value(row, row->lo)) &&
             add(o, "max", iird_json_param_value(row, row->hi)) &&
             add(o, "live_max", iird_json_param_value(row, iir_param_max(row, true)));
    if (ok && row->type == IIR_PARAM_ENUM) {
        ok = add(o, "choices", (choices = cJSON_CreateArray()));
        for (int i = 0; ok && row->choices[i]; i++)
            ok = cJSON_AddItemToArray(choices, cJSON_CreateString(row->choices[i]));
    }
    ok = ok && add(o, "unit", cJSON_CreateString(row->unit)) &&
         add(o, "help", cJSON_CreateString(row->help)) &&
         add(o, "effect", cJSON_CreateString(row->effect == IIR_PARAM_LIVE ? "live" : "restart"));
    if (!ok) cJSON_Delete(o);
    return ok ? o : NULL;
}

cJSON *iird_json_param_table(const iir_param_table *t)
{
    cJSON *a = cJSON_CreateArray();
    for (int i = 0; a && i < t->count; i++) {
        cJSON *row = row_json(&t->rows[i]);
        if (!row || !cJSON_AddItemToArray(a, row)) {
            cJSON_Delete(row);
            cJSON_Delete(a);
            return NULL;
        }
    }
    return a;
}

cJSON *iird_json_method_params(const char *method, const iir_params *p)
{
    const iir_param_table *const *tables = iir_method_tables(method);
    cJSON *o = cJSON_CreateObject();
    for (int t = 0; o && tables && tables[t]; t++)
        for (int i = 0; i < tables[t]->count; i++) {
            const iir_param *row = &tables[t]->rows[i];
            if (!add(o, row->name, iird_json_param_value(row, iir_method_param_value(row, p)))) {
                cJSON_Delete(o);
                return NULL;
            }
        }
    return o;
}

/* params.h -- parameter tables and parameter sets. Each method (and each part shared by several,
 * like the VPL shading) declares its parameters once, as a table of rows: name, type, default,
 * range, unit, one-line help, where the value lives in the method's own options struct, and what
 * changing it costs. Everything else -- the command line, the live protocol, render.json, the
 * docs -- is derived from the tables, so adding a parameter is one row plus its use.
 *
 * A parameter set (iir_params) is what a user asked for: values by name, any method's. A method
 * binds the set into its options struct with its own tables (iir_params_bind); names it does not
 * declare are not its business. Not which methods exist or which tables they have (method.h). */
#ifndef IIR_PARAMS_H
#define IIR_PARAMS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "iir/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum iir_param_type {
    IIR_PARAM_INT,   /* C int */
    IIR_PARAM_U64,   /* C uint64_t (seeds); exact up to hi <= 2^53 */
    IIR_PARAM_FLOAT, /* C float */
    IIR_PARAM_BOOL,  /* C bool */
    IIR_PARAM_ENUM   /* a C enum (int-sized) whose values are the indices of `choices` */
} iir_param_type;

struct iir_params;

/* What a change of the parameter costs a method that is running (iir_method_set_params). */
typedef enum iir_param_effect {
    IIR_PARAM_LIVE,   /* nothing: the next frame uses it, VPLs, shadow maps and G-buffer are kept */
    IIR_PARAM_RESTART /* a new VPL set (and its shadow maps): the method starts over */
} iir_param_effect;

/* One parameter. Values travel as doubles: exact for every int, float, bool, enum index and for
 * U64 values up to 2^53. */
typedef struct iir_param {
    const char *name; /* snake_case: the protocol's field; the CLI option is --name with '-' */
    iir_param_type type;
    size_t offset;      /* of the C field in the table's options struct */
    double def, lo, hi; /* default and inclusive range (ENUM: indices) */
    double live_hi;     /* the most a live session may ask for (a frame stays interactive); 0 = hi.
                           There is one default, `def`, for commands and live sessions alike. */
    const char *const *choices; /* ENUM: the names, NULL-terminated */
    const char *unit;           /* "" or a unit for messages and help: "pixels", "VPLs" */
    const char *help;           /* one line */
    iir_param_effect effect;
} iir_param;

/* The rows of one method or shared part, with an optional check across them. */
typedef struct iir_param_table {
    const char *title; /* "iir: incremental step", "VPL shading", ... for help and docs */
    const iir_param *rows;
    int count;
    /* Optional: checks across rows on the bound options struct (e.g. kmin <= kmax <= vpls).
     * Returns IIR_ERR_INVALID with a message that starts with the parameter's name and sets *bad
     * to its row; `given` says which names the user gave (to blame the one they changed). */
    iir_status (*check)(const void *opts, const struct iir_params *given, const iir_param **bad,
                        iir_error *err);
} iir_param_table;

/* ---- parameter sets ---- */

enum { IIR_PARAMS_MAX = 48 };

/* Values by name; names point at table rows' static strings, so a set is a plain value (copy it,
 * compare it with iir_params_equal). Zero-initialised = empty = every parameter at its default. */
typedef struct iir_params {
    uint32_t count;
    struct iir_param_value {
        const char *name;
        double value;
    } v[IIR_PARAMS_MAX];
} iir_params;

/* An empty set: every method binds its defaults. */
iir_params iir_params_default(void);

/* Sets row's value (replacing an earlier one). The value must suit the row (see
 * iir_param_check); IIR_ERR_INVALID otherwise, or when the set is full; the set is then unchanged.
 */
iir_status iir_params_set(iir_params *p, const iir_param *row, double value, iir_error *err);
/* true and *value when the set holds `name`. */
bool iir_params_get(const iir_params *p, const char *name, double *value);
bool iir_params_has(const iir_params *p, const char *name);
/* Copies every value of `from` into p (later wins). false when p would overflow (p unchanged). */
bool iir_params_merge(iir_params *p, const iir_params *from);
/* Same names with the same values, in any order. */
bool iir_params_equal(const iir_params *a, const iir_params *b);

/* ---- one value against its row ---- */

/* IIR_ERR_INVALID unless v is finite, in [lo, hi] (live_hi instead of hi when live), and an
 * integer for INT, U64, BOOL and ENUM. The message starts with row->name, e.g. "vpls must be in
 * [1, 16384], got 0", so that a caller can swap the name for its own spelling (iir_param_reword).
 */
iir_status iir_param_check(const iir_param *row, double v, bool live, iir_error *err);

/* Parses text as row's type: integers, numbers, "true"/"false"/"1"/"0"/"on"/"off", or one of the
 * choices; then iir_param_check. The same message convention. */
iir_status iir_param_parse(const iir_param *row, const char *text, double *v, iir_error *err);

/* Writes v as text the way iir_param_parse reads it ("voronoi", "0.005", "true", "256"). */
void iir_param_format(const iir_param *row, double v, char *buf, size_t n);

/* The row's largest value for a live session (live) or a command (not live). */
double iir_param_max(const iir_param *row, bool live);

/* Rewrites err->msg's leading row name as `spelling` ("--sm-res", "params.sm_res"). */
void iir_param_reword(iir_error *err, const iir_param *row, const char *spelling);

/* The CLI option of a row without "--": name with '_' -> '-' ("sm-res"). */
void iir_param_option_name(const iir_param *row, char *buf, size_t n);

/* "int", "u64", "float", "bool", "enum". */
const char *iir_param_type_name(iir_param_type t);

/* ---- tables ---- */

/* The row named `name`, or NULL. */
const iir_param *iir_param_table_find(const iir_param_table *t, const char *name);

/* Writes every row's default into opts (the table's options struct). */
void iir_params_defaults(const iir_param_table *t, void *opts);

/* Writes defaults, then every value of p that the table declares, into opts, checking each value
 * and then the table's check. `given` (may be NULL = p) is passed to the check. On error opts is
 * unspecified and *bad (may be NULL) is the row to blame. */
iir_status iir_params_bind(const iir_param_table *t, const iir_params *p, const iir_params *given,
                           void *opts, const iir_param **bad, iir_error *err);

/* The row's value in a bound options struct, as a double. */
double iir_param_read(const iir_param *row, const void *opts);

#ifdef __cplusplus
}
#endif
#endif

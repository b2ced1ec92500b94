/* protocol_internal.h -- helpers shared by the protocol's files (protocol_parse.c,
 * protocol_apply.c, protocol_json.c, recording.c): UTF-8 checks, compact numbers for JSON, the
 * params fields' names. Not part of the protocol's interface (protocol.h). */
#ifndef IIRD_PROTOCOL_INTERNAL_H
#define IIRD_PROTOCOL_INTERNAL_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <cjson/cJSON.h>

#include "iir/json_read.h"
#include "protocol.h"

/* Largest coordinate magnitude a client may send (docs/protocol.md, Conventions). */
#define IIRD_MAX_COORD 1e6

/* True when s[0..len) is well-formed UTF-8 (no overlong forms, surrogates or code points past
 * U+10FFFF) without NUL bytes. */
bool iird_utf8_valid(const char *s, size_t len);

/* Cuts a trailing incomplete UTF-8 sequence off s (left by truncating it to a buffer). */
void iird_utf8_trim(char *s);

/* What a \u0000 escape in a client's JSON string becomes before cJSON parses it
 * (iird_parse_message): cJSON would decode it to a NUL that silently ends the C string
 * ("cornell_box\u0000/../x" would read as "cornell_box"). 0xFF is never part of well-formed UTF-8
 * (the message is checked first) nor of what cJSON decodes, so the string readers refuse any
 * string holding it, naming the field. */
#define IIRD_NUL_MARK '\xFF'

/* The double nearest to the shortest decimal that reads back as f, so that cJSON prints 0.1f as
 * 0.1 rather than 0.10000000149011612. Non-finite values are returned unchanged. */
double iird_compact_float(float f);

/* Adds a number member / array element. u64: exact digits even past 2^53 (cJSON would round). */
bool iird_json_add_num(cJSON *obj, const char *name, double v);
bool iird_json_add_float(cJSON *obj, const char *name, float v);
bool iird_json_add_u64(cJSON *obj, const char *name, uint64_t v);
bool iird_json_add_vec3(cJSON *obj, const char *name, iir_vec3 v);
/* An area light's shape as "shape": [[[x, y], [x, y], [x, y]], ...] (light-local corners, each
 * float written to read back the same); false on out-of-memory. */
bool iird_json_add_shape(cJSON *obj, const iir_area_shape *shape);

/* ---- readers of one JSON value (protocol_fields.c over json_read.h's) ----
 * Each checks the value's JSON type and range and returns true, or returns false with *c->err
 * filled: bad_type (wrong JSON type, vector length, a fraction for an integer), out_of_range
 * (outside the range, not finite, a string too long or not among the allowed ones), with the
 * field's path "<prefix>.<name>" ("light.position[1]" for a vector element). */

enum { IIRD_PATH_BYTES = sizeof(((iird_proto_error *)0)->field) };

typedef struct iird_pctx {
    const char *prefix; /* the message type: "light", "params", ... */
    iird_proto_error *err;
} iird_pctx;

typedef iir_json_range iird_range; /* json_read.h: [lo, hi], open ends, a unit */

void iird_path(char out[IIRD_PATH_BYTES], const char *prefix, const char *name);
const char *iird_json_kind(const cJSON *v); /* "a string", "an array", ... */

bool iird_get_number(const iird_pctx *c, const cJSON *v, const char *name, iird_range r,
                     double *out);
bool iird_get_int(const iird_pctx *c, const cJSON *v, const char *name, double lo, double hi,
                  int64_t *out);
bool iird_get_int32(const iird_pctx *c, const cJSON *v, const char *name, int lo, int hi, int *out);
bool iird_get_bool(const iird_pctx *c, const cJSON *v, const char *name, bool *out);
/* Exactly 3 finite numbers, each in [lo, hi]. */
bool iird_get_vec3(const iird_pctx *c, const cJSON *v, const char *name, double lo, double hi,
                   iir_vec3 *out);
/* At most max_bytes bytes; out holds max_bytes + 1. */
bool iird_get_string(const iird_pctx *c, const cJSON *v, const char *name, size_t max_bytes,
                     char *out);
/* One of allowed (NULL-terminated); *index is its position. */
bool iird_get_enum(const iird_pctx *c, const cJSON *v, const char *name, const char *const *allowed,
                   int *index);

/* ---- shared tables ---- */

/* Reads a params field's JSON value as its row says (type, range up to the live maximum, enum
 * names), naming "params.<name>" in errors. */
bool iird_get_param(const iird_pctx *c, const cJSON *v, const iir_param *row, double *out);

/* A parameter's value as JSON: enum names, booleans, numbers (every digit of a large u64). NULL
 * only on out-of-memory. */
cJSON *iird_json_param_value(const iir_param *row, double v);

/* The row of a params field: the stream table's, else any method's; NULL for an unknown name. */
const iir_param *iird_params_row(const char *name);

/* Prints obj unformatted and deletes it; NULL when obj is NULL or printing fails. */
char *iird_json_finish(cJSON *obj);

#endif

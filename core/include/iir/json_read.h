/* json_read.h -- reading the JSON that people write (scene sidecars, animation scripts, protocol
 * messages): each reader checks one value's JSON type and range, or an object's member names, and
 * on a fault reports the field's path ("lights[0].position[1]") and a message that names it and
 * says what it must be and what it got. The caller's sink turns that into its own error: an
 * iir_error naming the file (scene_sidecar.c, anim_parse.c) or a protocol error code
 * (protocol_fields.c). One set of readers, so a field means the same thing and fails with the same
 * words wherever it is read. */
#ifndef IIR_JSON_READ_H
#define IIR_JSON_READ_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include <cjson/cJSON.h>

#include "iir/status.h"
#include "iir/vecmath.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum iir_json_fault {
    IIR_JSON_BAD_TYPE,      /* the wrong JSON type, vector length, a fraction for an integer */
    IIR_JSON_OUT_OF_RANGE,  /* outside the range, not finite, too long, not one of the names */
    IIR_JSON_UNKNOWN_FIELD, /* a member the object may not have, or one given twice */
    IIR_JSON_MISSING        /* a required member is absent */
} iir_json_fault;

/* Where faults go: fail(ctx, fault, path, message); message names the path itself. */
typedef struct iir_json_reader {
    void (*fail)(void *ctx, iir_json_fault fault, const char *path, const char *msg);
    void *ctx;
} iir_json_reader;

/* A file's reader (the scene sidecar's, the animation scripts'): a fault becomes the iir_error
 * "SOURCE: message", IIR_ERR_INVALID for a value out of range, else IIR_ERR_FORMAT; status keeps
 * it. Initialise with iir_json_file_init (r points back at it: do not copy it afterwards). */
typedef struct iir_json_file {
    iir_json_reader r;
    const char *source;
    iir_error *err;
    iir_status status;
} iir_json_file;
void iir_json_file_init(iir_json_file *f, const char *source, iir_error *err);
/* IIR_OK when ok, else the status of the fault f's reader reported. */
iir_status iir_json_file_status(const iir_json_file *f, bool ok);

/* A number's range: [lo, hi], either end open; unit (NULL or "degrees") follows it in messages. */
typedef struct iir_json_range {
    double lo, hi;
    bool open_lo, open_hi;
    const char *unit;
} iir_json_range;

enum { IIR_JSON_PATH = 192 }; /* bytes of a field's path (longer ones are cut short) */

/* out = "prefix.name", or name when prefix is "" (a path longer than the buffer is cut short). */
void iir_json_path(char out[IIR_JSON_PATH], const char *prefix, const char *name);
/* out = "prefix[i]". */
void iir_json_index(char out[IIR_JSON_PATH], const char *prefix, int i);
/* "a number", "a string", "an array", ... ("nothing" for NULL): what a message says it got. */
const char *iir_json_kind(const cJSON *v);

/* Each returns true and sets *out, or reports the fault through r and returns false. */

/* A finite number within range (a double that overflowed on parsing is out of range). */
bool iir_json_number(const iir_json_reader *r, const cJSON *v, const char *path,
                     iir_json_range range, double *out);
/* An integer within [lo, hi]. */
bool iir_json_int(const iir_json_reader *r, const cJSON *v, const char *path, double lo, double hi,
                  int64_t *out);
bool iir_json_bool(const iir_json_reader *r, const cJSON *v, const char *path, bool *out);
/* Exactly n (<= 4) numbers, each finite and within [lo, hi], into out[0 .. n). */
bool iir_json_numbers(const iir_json_reader *r, const cJSON *v, const char *path, int n, double lo,
                      double hi, double *out);
/* [x, y, z], each within [lo, hi]. */
bool iir_json_vec3(const iir_json_reader *r, const cJSON *v, const char *path, double lo, double hi,
                   iir_vec3 *out);
/* A string of min_bytes to max_bytes bytes, copied to out (max_bytes + 1 bytes). */
bool iir_json_string(const iir_json_reader *r, const cJSON *v, const char *path, size_t min_bytes,
                     size_t max_bytes, char *out);
/* One of allowed (NULL-terminated): *index is its position. */
bool iir_json_enum(const iir_json_reader *r, const cJSON *v, const char *path,
                   const char *const *allowed, int *index);
/* obj is an object whose members are all named in allowed (NULL-terminated), none twice. */
bool iir_json_fields(const iir_json_reader *r, const cJSON *obj, const char *path,
                     const char *const *allowed);
/* The member name of obj; absent: reports IIR_JSON_MISSING ("<path> is required<what>") when
 * required, else returns NULL quietly. */
const cJSON *iir_json_member(const iir_json_reader *r, const cJSON *obj, const char *path,
                             const char *name, bool required, const char *what);

#ifdef __cplusplus
}
#endif

#endif

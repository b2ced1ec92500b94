/* budget.h -- the daemon's memory budget: each session reserves what its settings will make it
 * allocate (iird_session_estimate: frame buffers plus its method's own estimate from its parameter
 * tables, iir_method_memory) before anything is allocated, within a per-session and a daemon-wide
 * limit (--max-session-memory, --max-memory). A `params` message that would pass either is refused
 * with both figures; the session keeps its state.
 *
 * Threads: `reserved` is an atomic that every session's service-thread messages and the sessions'
 * destruction change; the limits are set before the server starts and only read afterwards. */
#ifndef IIRD_BUDGET_H
#define IIRD_BUDGET_H

#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

#include "protocol/protocol.h"

typedef struct iird_budget {
    uint64_t session_max; /* bytes one session may reserve */
    uint64_t total_max;   /* bytes all sessions together may reserve */
    _Atomic uint64_t reserved;
} iird_budget;

/* Half of the machine's physical memory (the default of --max-memory); 8 GiB if unknown. */
uint64_t iird_budget_default_total(void);

/* Moves a session's reservation from *held to `want` bytes: true when want fits the session limit
 * and, with every other session's reservation, the daemon's; then *held = want. Otherwise false
 * with *err (out_of_range for the session limit, busy for the daemon's) naming both figures, and
 * nothing changed. b NULL: no budget, always true. */
bool iird_budget_reserve(iird_budget *b, uint64_t *held, uint64_t want, iird_proto_error *err);

/* Reserves a loaded scene's bytes (its geometry and decoded textures: iir_scene_bytes) under the
 * daemon's limit alone, shared by every session on it: true, *held = want, when it fits with every
 * other reservation; else false with why (size n) naming both figures. b NULL: always true. */
bool iird_budget_reserve_scene(iird_budget *b, uint64_t *held, uint64_t want, char *why, size_t n);

/* Gives *held back (a session that ended); *held becomes 0. */
void iird_budget_release(iird_budget *b, uint64_t *held);

/* Parses "1073741824", "512M", "2G", "1.5G" (binary units K, M, G, T) into bytes. */
bool iird_parse_bytes(const char *text, uint64_t *out);

#endif

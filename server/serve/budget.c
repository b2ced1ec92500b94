/* budget.c -- the daemon's memory budget (budget.h): reservations under two limits, and sizes as
 * people write them. */
#include "budget.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

static double mib(uint64_t bytes)
{
    return (double)bytes / (1024.0 * 1024.0);
}

uint64_t iird_budget_default_total(void)
{
    long pages = sysconf(_SC_PHYS_PAGES), size = sysconf(_SC_PAGESIZE);
    if (pages <= 0 || size <= 0) return 8ull << 30;
    return (uint64_t)pages * (uint64_t)size / 2;
}

bool iird_budget_reserve(iird_budget *b, uint64_t *held, uint64_t want, iird_proto_error *err)
{
    if (!b) return *held = want, true;
    if (want > b->session_max)
        return iird_proto_fail(err, IIRD_E_OUT_OF_RANGE, "params",
                               "params: this session would need about %.0f MiB, over its memory "
                               "budget of %.0f MiB (--max-session-memory); fewer VPLs, smaller "
                               "shadow maps or a smaller frame fit",
                               mib(want), mib(b->session_max));
    uint64_t now = atomic_load(&b->reserved);
    for (;;) {
        uint64_t next = now - *held + want;
        if (want > *held && next > b->total_max)
            return iird_proto_fail(err, IIRD_E_BUSY, "params",
                                   "params: the daemon's sessions would need about %.0f MiB "
                                   "together, over its memory budget of %.0f MiB (--max-memory); "
                                   "try again when other sessions have left, or ask for less",
                                   mib(next), mib(b->total_max));
        if (atomic_compare_exchange_weak(&b->reserved, &now, next)) break;
    }
    *held = want;
    return true;
}

bool iird_budget_reserve_scene(iird_budget *b, uint64_t *held, uint64_t want, char *why, size_t n)
{
    if (!b) return *held = want, true;
    uint64_t now = atomic_load(&b->reserved);
    for (;;) {
        uint64_t next = now - *held + want;
        if (want > *held && next > b->total_max) {
            snprintf(why, n,
                     "its geometry and textures (%.0f MiB) with the sessions' reservations would "
                     "pass the daemon's memory budget of %.0f MiB (--max-memory)",
                     mib(want), mib(b->total_max));
            return false;
        }
        if (atomic_compare_exchange_weak(&b->reserved, &now, next)) break;
    }
    *held = want;
    return true;
}

void iird_budget_release(iird_budget *b, uint64_t *held)
{
    if (b) atomic_fetch_sub(&b->reserved, *held);
    *held = 0;
}

bool iird_parse_bytes(const char *text, uint64_t *out)
{
    char *end = NULL;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || errno || !isfinite(v) || v <= 0) return false;
    double unit = 1.0;
    switch (*end) {
    case 'K':
        unit = 1024.0;
        end++;
        break;
    case 'M':
        unit = 1024.0 * 1024.0;
        end++;
        break;
    case 'G':
        unit = 1024.0 * 1024.0 * 1024.0;
        end++;
        break;
    case 'T':
        unit = 1024.0 * 1024.0 * 1024.0 * 1024.0;
        end++;
        break;
    default:
        break;
    }
    if (*end == 'i') end++;
    if (*end == 'B') end++;
    if (*end || v * unit >= 1.8e19) return false;
    *out = (uint64_t)(v * unit);
    return true;
}

/* timer.h -- monotonic wall-clock time in milliseconds (iir_now_ms), for phase timings in core and
 * the daemon's clocks. Inline; no state. */
#ifndef IIR_TIMER_H
#define IIR_TIMER_H

#include <time.h>

static inline double iir_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

#endif

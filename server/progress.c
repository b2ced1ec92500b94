/* progress.c -- the progress bar with ETA drawn on stderr when it is a terminal; silent otherwise
 * so logs and pipes stay clean. The ETA comes from the measured time per unit of this bar's work
 * from its first finished unit on (so set-up and a cold first frame do not skew it), plus what the
 * caller expects after it (a bench's later phases). */
#include <stdio.h>
#include <unistd.h>

#include "cli.h"
#include "iir/timer.h"

enum { BAR_WIDTH = 32 };

void iird_progress_start(iird_progress *p, const char *label, double total)
{
    p->enabled = isatty(STDERR_FILENO) != 0;
    p->label = label;
    p->total = total > 0 ? total : 1;
    p->start_ms = iir_now_ms();
    p->last_draw_ms = 0;
    p->mark_ms = p->mark_done = -1;
    p->after_s = -1;
    p->after_label = NULL;
    iird_progress_update(p, 0);
}

void iird_progress_set_after(iird_progress *p, const char *label, double seconds)
{
    p->after_label = label;
    p->after_s = seconds;
}

double iird_progress_rate(const iird_progress *p, double done, double now_ms)
{
    if (p->mark_done >= 0 && done > p->mark_done)
        return (now_ms - p->mark_ms) / 1e3 / (done - p->mark_done);
    return done > 0 ? (now_ms - p->start_ms) / 1e3 / done : -1;
}

static void format_seconds(double s, char *buf, size_t n)
{
    if (s < 0 || s > 1e7)
        snprintf(buf, n, "--:--");
    else if (s >= 3600)
        snprintf(buf, n, "%d:%02d:%02d", (int)s / 3600, (int)s / 60 % 60, (int)s % 60);
    else
        snprintf(buf, n, "%02d:%02d", (int)s / 60, (int)s % 60);
}

/* "eta MM:SS" of this bar, and ", LABEL MM:SS" with what comes after it. */
static void eta_text(const iird_progress *p, double done, double now, char *buf, size_t n)
{
    double rate = iird_progress_rate(p, done, now);
    double left = rate >= 0 ? rate * (p->total - done) : -1;
    char eta[32], all[32];
    format_seconds(left, eta, sizeof eta);
    if (p->after_s < 0 || !p->after_label) {
        snprintf(buf, n, "eta %s", eta);
        return;
    }
    format_seconds(left >= 0 ? left + p->after_s : -1, all, sizeof all);
    snprintf(buf, n, "eta %s, %s %s", eta, p->after_label, all);
}

void iird_progress_update(iird_progress *p, double done)
{
    double now = iir_now_ms();
    if (done > 0 && p->mark_done < 0) p->mark_ms = now, p->mark_done = done;
    if (!p->enabled) return;
    if (done < p->total && now - p->last_draw_ms < 100) return;
    p->last_draw_ms = now;
    double frac = done / p->total;
    if (frac > 1) frac = 1;
    int fill = (int)(frac * BAR_WIDTH);
    char bar[BAR_WIDTH + 1];
    for (int i = 0; i < BAR_WIDTH; i++) bar[i] = i < fill ? '#' : '.';
    bar[BAR_WIDTH] = 0;
    char eta[96], el[32];
    eta_text(p, done, now, eta, sizeof eta);
    format_seconds((now - p->start_ms) / 1e3, el, sizeof el);
    fprintf(stderr, "\r%s [%s] %3d%%  elapsed %s  %s ", p->label, bar, (int)(frac * 100), el, eta);
    fflush(stderr);
}

void iird_progress_finish(iird_progress *p)
{
    if (!p->enabled) return;
    iird_progress_update(p, p->total);
    fputc('\n', stderr);
}

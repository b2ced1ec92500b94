/* progress.c -- the progress bar with ETA drawn on stderr when it is a terminal; silent otherwise
 * so logs and pipes stay clean. */
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
    iird_progress_update(p, 0);
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

void iird_progress_update(iird_progress *p, double done)
{
    if (!p->enabled) return;
    double now = iir_now_ms();
    if (done < p->total && now - p->last_draw_ms < 100) return;
    p->last_draw_ms = now;
    double frac = done / p->total;
    if (frac > 1) frac = 1;
    int fill = (int)(frac * BAR_WIDTH);
    char bar[BAR_WIDTH + 1];
    for (int i = 0; i < BAR_WIDTH; i++) bar[i] = i < fill ? '#' : '.';
    bar[BAR_WIDTH] = 0;
    double elapsed = (now - p->start_ms) / 1e3;
    char eta[32], el[32];
    format_seconds(frac > 0 ? elapsed * (1 - frac) / frac : -1, eta, sizeof eta);
    format_seconds(elapsed, el, sizeof el);
    fprintf(stderr, "\r%s [%s] %3d%%  elapsed %s  eta %s ", p->label, bar, (int)(frac * 100), el,
            eta);
    fflush(stderr);
}

void iird_progress_finish(iird_progress *p)
{
    if (!p->enabled) return;
    iird_progress_update(p, p->total);
    fputc('\n', stderr);
}

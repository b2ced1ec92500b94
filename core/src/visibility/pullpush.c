/* pullpush.c -- pull-push hole filling of a 2D map (pullpush.h): the pyramid of means of defined
 * texels, built only up to its first complete level, and the bilinear push back down. Not what
 * the map holds (ism.c splats depths into it). Allocates nothing: the coarser levels live in the
 * caller's scratch. */
#include "iir/pullpush.h"

#include <math.h>
#include <stdbool.h>

/* One level of the pyramid: w x h texels at t. */
typedef struct level {
    float *t;
    int w, h;
} level;

static int half_up(int n)
{
    return (n + 1) / 2;
}

size_t iir_pullpush_scratch_floats(int w, int h)
{
    size_t total = 0;
    while (w > 1 || h > 1) {
        w = half_up(w), h = half_up(h);
        total += (size_t)w * (size_t)h;
    }
    return total;
}

static bool complete(const level *l)
{
    for (size_t k = 0; k < (size_t)l->w * (size_t)l->h; k++)
        if (!isfinite(l->t[k])) return false;
    return true;
}

/* Pull: coarse (i, j) = mean of the defined children of fine; a hole when none is defined. */
static void pull(const level *fine, level *coarse)
{
    for (int j = 0; j < coarse->h; j++)
        for (int i = 0; i < coarse->w; i++) {
            float sum = 0.f;
            int defined = 0;
            for (int b = 0; b < 2; b++)
                for (int a = 0; a < 2; a++) {
                    int x = 2 * i + a, y = 2 * j + b;
                    if (x >= fine->w || y >= fine->h) continue;
                    float z = fine->t[(size_t)y * (size_t)fine->w + (size_t)x];
                    if (isfinite(z)) sum += z, defined++;
                }
            coarse->t[(size_t)j * (size_t)coarse->w + (size_t)i] =
                defined ? sum / (float)defined : INFINITY;
        }
}

/* The two coarse taps of fine texel i and the weight of the first (the second gets 1 - w0):
 * its centre lies at i / 2 - 1/4 in coarse texel coordinates; taps clamped to [0, n - 1]. */
static void taps(int i, int n, int *c0, int *c1, float *w0)
{
    int lo = i % 2 == 0 ? i / 2 - 1 : (i - 1) / 2;
    *w0 = i % 2 == 0 ? 0.25f : 0.75f;
    *c0 = lo < 0 ? 0 : lo;
    *c1 = lo + 1 < n ? lo + 1 : n - 1;
}

/* Push: every hole of fine takes coarse (complete) bilinearly at its centre. */
static void push(level *fine, const level *coarse)
{
    for (int j = 0; j < fine->h; j++) {
        int y0, y1;
        float wy;
        taps(j, coarse->h, &y0, &y1, &wy);
        const float *r0 = coarse->t + (size_t)y0 * (size_t)coarse->w;
        const float *r1 = coarse->t + (size_t)y1 * (size_t)coarse->w;
        for (int i = 0; i < fine->w; i++) {
            float *z = &fine->t[(size_t)j * (size_t)fine->w + (size_t)i];
            if (isfinite(*z)) continue;
            int x0, x1;
            float wx;
            taps(i, coarse->w, &x0, &x1, &wx);
            float top = wx * r0[x0] + (1.f - wx) * r0[x1];
            float bottom = wx * r1[x0] + (1.f - wx) * r1[x1];
            *z = wy * top + (1.f - wy) * bottom;
        }
    }
}

int iir_pullpush(float *map, int w, int h, float *scratch)
{
    enum { MAX_LEVELS = 34 }; /* ceil halving of an int reaches 1 in at most 32 steps */
    level lv[MAX_LEVELS];
    lv[0] = (level){map, w, h};
    int top = 0;
    float *next = scratch;
    while (!complete(&lv[top]) && (lv[top].w > 1 || lv[top].h > 1)) {
        level *c = &lv[top + 1];
        *c = (level){next, half_up(lv[top].w), half_up(lv[top].h)};
        next += (size_t)c->w * (size_t)c->h;
        pull(&lv[top], c);
        top++;
    }
    if (!complete(&lv[top])) return top; /* 1 x 1 and a hole: nothing was defined */
    for (int l = top - 1; l >= 0; l--) push(&lv[l], &lv[l + 1]);
    return top;
}

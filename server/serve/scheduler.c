/* scheduler.c -- gang scheduling of the sessions' renders with fair shares (scheduler.h): slots,
 * the waiting sessions, virtual time. One mutex guards it all; yield's fast path reads two atomics
 * and the clock, so a lone session pays nothing per tile. */
#include "scheduler.h"

#include <stdlib.h>

#include "iir/timer.h"

struct iird_sched {
    pthread_mutex_t lock;
    int slots;
    int threads; /* a session's team when it renders alone */
    double slice_ms;
    int running;
    atomic_int waiting;     /* read without the lock by yield's fast path */
    iird_sched_entity head; /* sentinel of the registered entities' ring */
    double floor_ms;        /* the least virtual time of the busy sessions, as it last was */
    uint64_t next_ticket;
    uint64_t handovers;
    double wait_ms;
};

iird_sched *iird_sched_create(int slots, int threads, double slice_ms)
{
    iird_sched *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    pthread_mutex_init(&s->lock, NULL);
    s->slots = slots < 1 ? 1 : slots;
    s->threads = threads < 1 ? 1 : threads;
    s->slice_ms = slice_ms;
    s->head.prev = s->head.next = &s->head;
    return s;
}

void iird_sched_destroy(iird_sched *s)
{
    if (!s) return;
    pthread_mutex_destroy(&s->lock);
    free(s);
}

void iird_sched_add(iird_sched *s, iird_sched_entity *e)
{
    *e = (iird_sched_entity){0};
    pthread_cond_init(&e->go, NULL);
    pthread_mutex_lock(&s->lock);
    e->prev = s->head.prev;
    e->next = &s->head;
    e->prev->next = e;
    s->head.prev = e;
    pthread_mutex_unlock(&s->lock);
}

void iird_sched_remove(iird_sched *s, iird_sched_entity *e)
{
    iird_sched_leave(s, e);
    pthread_mutex_lock(&s->lock);
    e->prev->next = e->next;
    e->next->prev = e->prev;
    pthread_mutex_unlock(&s->lock);
    pthread_cond_destroy(&e->go);
}

/* ---- with the lock held ---- */

static bool active(const iird_sched_entity *e)
{
    return e->waiting || atomic_load(&e->running);
}

/* Raises the floor to the least virtual time of the sessions rendering or waiting (it never
 * goes down: a session alone moves it along with its own). */
static void raise_floor(iird_sched *s)
{
    bool any = false;
    double least = 0;
    for (const iird_sched_entity *o = s->head.next; o != &s->head; o = o->next)
        if (active(o) && (!any || o->vtime_ms < least)) least = o->vtime_ms, any = true;
    if (any && least > s->floor_ms) s->floor_ms = least;
}

static void stop_running(iird_sched *s, iird_sched_entity *e, double now)
{
    double ran = now - atomic_load(&e->slice_start_ms);
    e->vtime_ms += ran;
    e->used_ms += ran;
    raise_floor(s);
    atomic_store(&e->running, false);
    s->running--;
}

static void start_waiting(iird_sched *s, iird_sched_entity *e, double now)
{
    e->waiting = true;
    e->ticket = s->next_ticket++;
    atomic_store(&e->slice_start_ms, now); /* while waiting: when the wait began */
    atomic_fetch_add(&s->waiting, 1);
}

static void stop_waiting(iird_sched *s, iird_sched_entity *e)
{
    e->waiting = false;
    atomic_fetch_sub(&s->waiting, 1);
}

/* Whether a foreground session other than e renders or waits. */
static bool foreground_busy(const iird_sched *s, const iird_sched_entity *e)
{
    for (const iird_sched_entity *o = s->head.next; o != &s->head; o = o->next)
        if (o != e && !o->background && active(o)) return true;
    return false;
}

/* Whether waiting o goes before best: foreground before background, then the least virtual time,
 * then the earliest arrival. */
static bool before(const iird_sched_entity *o, const iird_sched_entity *best)
{
    if (!best || o->background != best->background) return !best || !o->background;
    return o->vtime_ms < best->vtime_ms ||
           (o->vtime_ms == best->vtime_ms && o->ticket < best->ticket);
}

/* Fills free slots with the waiting sessions that go first (before()); background ones only while
 * no foreground session renders or waits. */
static void grant(iird_sched *s, double now)
{
    while (s->running < s->slots) {
        iird_sched_entity *best = NULL;
        for (iird_sched_entity *o = s->head.next; o != &s->head; o = o->next)
            if (o->waiting && before(o, best)) best = o;
        if (!best || (best->background && foreground_busy(s, best))) return;
        stop_waiting(s, best);
        s->wait_ms += now - atomic_load(&best->slice_start_ms);
        atomic_store(&best->slice_start_ms, now);
        atomic_store(&best->preempt, false);
        atomic_store(&best->running, true);
        s->running++;
        pthread_cond_broadcast(&best->go);
    }
}

/* A session that comes back from sleep behind a running one takes its slot at the running one's
 * next tile rather than after its slice (wake-up preemption, as CFS does): an interactive frame
 * waits a tile, not a slice. */
static void preempt_for(iird_sched *s, const iird_sched_entity *e, double now)
{
    iird_sched_entity *victim = NULL;
    double most = 0;
    for (iird_sched_entity *o = s->head.next; o != &s->head; o = o->next) {
        if (!atomic_load(&o->running)) continue;
        if (!e->background && o->background) { /* foreground first: every background yields */
            atomic_store(&o->preempt, true);
            continue;
        }
        double v = o->vtime_ms + (now - atomic_load(&o->slice_start_ms));
        if (!victim || v > most) victim = o, most = v;
    }
    if (victim && s->running >= s->slots && e->vtime_ms + IIRD_SCHED_WAKEUP_MS < most)
        atomic_store(&victim->preempt, true);
}

/* Waits until e holds a slot or is cancelled; a cancelled wait leaves the queue. */
static void wait_turn(iird_sched *s, iird_sched_entity *e)
{
    while (e->waiting && !e->cancelled) pthread_cond_wait(&e->go, &s->lock);
    if (e->waiting) stop_waiting(s, e);
}

/* ---- the interface ---- */

/* e's team: every thread when it is the only busy session, else its part of them. Background
 * sessions do not count for a foreground one: the waiting ones get no slot beside it and the
 * running ones hand theirs over at their next tile. */
static int team(const iird_sched *s, const iird_sched_entity *e)
{
    for (const iird_sched_entity *o = s->head.next; o != &s->head; o = o->next)
        if (o != e && active(o) && (e->background || !o->background))
            return s->threads / s->slots > 1 ? s->threads / s->slots : 1;
    return s->threads;
}

static int enter(iird_sched *s, iird_sched_entity *e, bool background)
{
    pthread_mutex_lock(&s->lock);
    if (!e->cancelled && !active(e)) {
        e->background = background;
        double now = iir_now_ms();
        /* new, or back from sleep: at most one slice behind the least-served */
        if (e->vtime_ms < s->floor_ms - s->slice_ms) e->vtime_ms = s->floor_ms - s->slice_ms;
        start_waiting(s, e, now);
        grant(s, now);
        if (e->waiting) preempt_for(s, e, now);
        wait_turn(s, e);
    }
    int n = team(s, e);
    pthread_mutex_unlock(&s->lock);
    return n;
}

int iird_sched_enter(iird_sched *s, iird_sched_entity *e)
{
    return enter(s, e, false);
}

int iird_sched_enter_background(iird_sched *s, iird_sched_entity *e)
{
    return enter(s, e, true);
}

void iird_sched_promote(iird_sched *s, iird_sched_entity *e)
{
    pthread_mutex_lock(&s->lock);
    if (e->background) {
        double now = iir_now_ms();
        e->background = false;
        if (e->waiting) {
            grant(s, now);
            if (e->waiting) preempt_for(s, e, now);
        }
    }
    pthread_mutex_unlock(&s->lock);
}

void iird_sched_leave(iird_sched *s, iird_sched_entity *e)
{
    pthread_mutex_lock(&s->lock);
    double now = iir_now_ms();
    if (atomic_load(&e->running)) stop_running(s, e, now);
    if (e->waiting) stop_waiting(s, e);
    grant(s, now);
    pthread_mutex_unlock(&s->lock);
}

void iird_sched_yield(iird_sched *s, iird_sched_entity *e)
{
    if (atomic_load_explicit(&s->waiting, memory_order_relaxed) == 0) return;
    double now = iir_now_ms();
    if (atomic_load_explicit(&e->running, memory_order_relaxed) &&
        now - atomic_load_explicit(&e->slice_start_ms, memory_order_relaxed) < s->slice_ms &&
        !atomic_load_explicit(&e->preempt, memory_order_relaxed))
        return;
    pthread_mutex_lock(&s->lock);
    now = iir_now_ms();
    bool over = now - atomic_load(&e->slice_start_ms) >= s->slice_ms || atomic_load(&e->preempt);
    if (atomic_load(&e->running) && over && atomic_load(&s->waiting) > 0) {
        stop_running(s, e, now);
        start_waiting(s, e, now);
        grant(s, now); /* e again when it is still the least-served */
        if (!atomic_load(&e->running)) s->handovers++;
    }
    wait_turn(s, e); /* also for e's other threads, which find it waiting */
    pthread_mutex_unlock(&s->lock);
}

void iird_sched_cancel(iird_sched *s, iird_sched_entity *e)
{
    pthread_mutex_lock(&s->lock);
    e->cancelled = true;
    pthread_cond_broadcast(&e->go);
    pthread_mutex_unlock(&s->lock);
}

iird_sched_stats iird_sched_get_stats(iird_sched *s)
{
    pthread_mutex_lock(&s->lock);
    iird_sched_stats st = {s->slots, s->running, atomic_load(&s->waiting), s->handovers,
                           s->wait_ms};
    pthread_mutex_unlock(&s->lock);
    return st;
}

double iird_sched_used_ms(iird_sched *s, const iird_sched_entity *e)
{
    pthread_mutex_lock(&s->lock);
    double ms = e->used_ms;
    if (atomic_load(&e->running)) ms += iir_now_ms() - atomic_load(&e->slice_start_ms);
    pthread_mutex_unlock(&s->lock);
    return ms;
}

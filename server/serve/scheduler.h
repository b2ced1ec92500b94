/* scheduler.h -- a fair share of the cores between the sessions' renders (issue 15, finding 11).
 *
 * Each session's render uses every core (OpenMP over tiles). When several sessions render at
 * once, the OS interleaves their thread teams and every barrier of a frame waits for a teammate
 * that is not running: a light session beside seven heavy ones fell to a fifth of its solo frame
 * rate. The scheduler gang-schedules instead: at most `slots` sessions render at a time; at the
 * method's stop hook (per tile) a session that has had its time slice while others wait hands the
 * cores over, and the waiting session that has rendered least (its virtual time, as in Linux's
 * CFS) goes next. A session that slept (an interactive one between frames) comes back at most one
 * slice behind the least-served, so its frame starts within a slice and a tile, and over time
 * every busy session gets the same share of render time.
 *
 * A session owns one iird_sched_entity; its worker brackets each render or refinement pass with
 * enter/leave, and the method's threads call iird_sched_yield from the stop hook. Every call is
 * thread-safe; enter, leave and cancel come from the session's worker or service thread. */
#ifndef IIRD_SCHEDULER_H
#define IIRD_SCHEDULER_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include <stdint.h>

/* How long a session keeps the cores while others wait: short enough that an interactive frame
 * waits a few of them at most, long enough that handing over (waking one thread team, its caches
 * cold) costs under a percent. */
#define IIRD_SCHED_SLICE_MS 10.0
/* A waking session preempts a running one that has used this much more render time. */
#define IIRD_SCHED_WAKEUP_MS 1.0

typedef struct iird_sched iird_sched;

/* One session's place in the scheduler; fields are the scheduler's (guarded by its lock, but
 * slice_start and running, read lock-free by yield's fast path). */
typedef struct iird_sched_entity {
    struct iird_sched_entity *prev, *next; /* every registered entity */
    pthread_cond_t go;                     /* signalled when it is granted a slot or cancelled */
    double vtime_ms;                       /* render time it has used, as the scheduler counts */
    double used_ms;                        /* render time it has used (slots held) */
    _Atomic double slice_start_ms;         /* when its current slice began */
    atomic_bool running;                   /* it holds a slot */
    atomic_bool preempt;                   /* a session behind it woke up: hand over now */
    bool waiting;                          /* it waits for a slot */
    bool background;                       /* its work under way is background (refinement):
                                              it gets a slot only when no foreground session
                                              renders or waits, and yields to one at once */
    bool cancelled;                        /* its session is stopping: never wait again */
    uint64_t ticket;                       /* arrival order among equal virtual times */
} iird_sched_entity;

typedef struct iird_sched_stats {
    int slots, running, waiting;
    uint64_t handovers; /* slots handed from a session whose slice ended (or that was preempted)
                           to another */
    double wait_ms;     /* time sessions spent waiting for a slot */
} iird_sched_stats;

/* slots: sessions rendering at once (>= 1); threads: a session's OpenMP team when it renders
 * alone (the cores); slice_ms: how long a session keeps its slot while others wait. NULL when out
 * of memory. */
iird_sched *iird_sched_create(int slots, int threads, double slice_ms);
void iird_sched_destroy(iird_sched *s);

void iird_sched_add(iird_sched *s, iird_sched_entity *e);
/* e must not be inside enter/leave. */
void iird_sched_remove(iird_sched *s, iird_sched_entity *e);

/* Blocks until e holds a slot (or is cancelled); returns the OpenMP team e's render should use:
 * every thread when no other session is busy, else threads / slots (at least 1). */
int iird_sched_enter(iird_sched *s, iird_sched_entity *e);
/* The same for background work (progressive refinement of a frame already shown): e waits while
 * any foreground session (a frame answering input, a method's creation) renders or waits, and a
 * foreground session that arrives takes e's slot at e's next tile. Among themselves background
 * sessions share as foreground ones do. */
int iird_sched_enter_background(iird_sched *s, iird_sched_entity *e);
/* e's session has new input: its background work under way (or waiting) becomes foreground, so
 * that it reaches its stop hook and the frame answering the input soon. Any thread. */
void iird_sched_promote(iird_sched *s, iird_sched_entity *e);
/* Gives e's slot back; harmless when e holds none. */
void iird_sched_leave(iird_sched *s, iird_sched_entity *e);
/* From any of e's render threads, per tile: when e's slice is over and another session waits,
 * hands the slot on and blocks until e holds one again (or is cancelled). Lock-free while no
 * session waits. */
void iird_sched_yield(iird_sched *s, iird_sched_entity *e);
/* e's session is stopping: its waits return at once, now and later. */
void iird_sched_cancel(iird_sched *s, iird_sched_entity *e);

iird_sched_stats iird_sched_get_stats(iird_sched *s);
/* Render time e has used so far, in ms (its slots held, the current one too). */
double iird_sched_used_ms(iird_sched *s, const iird_sched_entity *e);

#endif

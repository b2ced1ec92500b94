/* test_scheduler.c -- the daemon's render scheduler (server/serve/scheduler.c): one slot is held by
 * one session at a time, busy sessions get equal render time, a session waking from sleep preempts
 * a running one at its next yield, a cancelled wait returns, the OpenMP team a session gets, and
 * background work (refinement) goes after every frame. */
#include <pthread.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stddef.h>
#include <time.h>
#include <cmocka.h>

#include "iir/timer.h"
#include "scheduler.h"

static void sleep_ms(double ms)
{
    struct timespec ts = {(time_t)(ms / 1e3), (long)((ms - 1e3 * (double)(long)(ms / 1e3)) * 1e6)};
    nanosleep(&ts, NULL);
}

static void test_alone_gets_every_thread_and_never_waits(void **state)
{
    (void)state;
    iird_sched *s = iird_sched_create(1, 8, 10.0);
    iird_sched_entity a;
    iird_sched_add(s, &a);
    assert_int_equal(iird_sched_enter(s, &a), 8);
    sleep_ms(15); /* past the slice: nobody waits, so yield returns at once */
    double t0 = iir_now_ms();
    iird_sched_yield(s, &a);
    assert_true(iir_now_ms() - t0 < 5.0);
    assert_true(atomic_load(&a.running));
    iird_sched_leave(s, &a);
    assert_false(atomic_load(&a.running));
    assert_true(iird_sched_used_ms(s, &a) >= 15.0);
    iird_sched_remove(s, &a);
    iird_sched_destroy(s);
}

/* ---- two busy sessions on one slot ---- */

/* This thread's CPU time, ms. The busy sessions' work is counted in it, as a render's tiles are
 * work: a thread the OS leaves waiting for a core (ctest -j beside other tests on two cores) has
 * done less, not ended its frame early; the wait stays in the scheduler's render time. */
static double thread_cpu_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec * 1e3 + (double)ts.tv_nsec * 1e-6;
}

/* Work a busy session does before both stop (~400 ms of the slot for the two on an idle machine).
 */
#define BUSY_WORK_MS 200.0

typedef struct busy {
    iird_sched *s;
    iird_sched_entity e;
    pthread_barrier_t *start; /* both sessions busy from the same moment */
    atomic_bool *done;        /* one has done BUSY_WORK_MS: both stop at their next step */
    atomic_int *inside;       /* sessions between a granted enter/yield and the next yield/leave */
    int max_inside;
    double work_ms; /* CPU time it spun */
} busy;

/* Frames of 12 ms of work (longer than the slice), yielding after every 0.1 ms of it as a render
 * does after each tile, until either session has done BUSY_WORK_MS. */
static void *busy_main(void *arg)
{
    busy *b = arg;
    pthread_barrier_wait(b->start);
    double t0 = thread_cpu_ms();
    while (!atomic_load(b->done)) {
        iird_sched_enter(b->s, &b->e);
        double end = thread_cpu_ms() + 12.0;
        while (thread_cpu_ms() < end && !atomic_load(b->done)) {
            int n = atomic_fetch_add(b->inside, 1) + 1;
            if (n > b->max_inside) b->max_inside = n;
            double step = thread_cpu_ms() + 0.1;
            while (thread_cpu_ms() < step) {
            }
            atomic_fetch_sub(b->inside, 1);
            if (thread_cpu_ms() - t0 >= BUSY_WORK_MS) atomic_store(b->done, true);
            iird_sched_yield(b->s, &b->e);
        }
        iird_sched_leave(b->s, &b->e);
    }
    b->work_ms = thread_cpu_ms() - t0;
    return NULL;
}

/* Equal shares of the scheduler's render time (iird_sched_used_ms: what it divides, the time a
 * session holds a slot), not of the threads' CPU time: how much of a core a slot holder gets is
 * the OS's (beside busy threads the two differed up to 3x while their render time was equal). */
static void test_busy_sessions_share_one_slot_equally(void **state)
{
    (void)state;
    iird_sched *s = iird_sched_create(1, 2, 5.0);
    atomic_int inside = 0;
    atomic_bool done = false;
    pthread_barrier_t start;
    pthread_barrier_init(&start, NULL, 2);
    busy b[2] = {{.s = s, .start = &start, .done = &done, .inside = &inside},
                 {.s = s, .start = &start, .done = &done, .inside = &inside}};
    pthread_t t[2];
    for (int i = 0; i < 2; i++) iird_sched_add(s, &b[i].e);
    for (int i = 0; i < 2; i++) pthread_create(&t[i], NULL, busy_main, &b[i]);
    for (int i = 0; i < 2; i++) pthread_join(t[i], NULL);
    pthread_barrier_destroy(&start);
    double u0 = iird_sched_used_ms(s, &b[0].e), u1 = iird_sched_used_ms(s, &b[1].e);
    print_message("render time used: %.1f and %.1f ms (CPU time spun: %.1f and %.1f ms); "
                  "handovers %llu\n",
                  u0, u1, b[0].work_ms, b[1].work_ms,
                  (unsigned long long)iird_sched_get_stats(s).handovers);
    assert_int_equal(b[0].max_inside, 1);
    assert_int_equal(b[1].max_inside, 1);
    assert_true(u0 > 0.0 && u1 > 0.0);
    assert_true(u0 < 1.5 * u1 && u1 < 1.5 * u0);
    assert_true(iird_sched_get_stats(s).handovers > 0);
    for (int i = 0; i < 2; i++) iird_sched_remove(s, &b[i].e);
    iird_sched_destroy(s);
}

/* ---- a waiting session ---- */

typedef struct waiter {
    iird_sched *s;
    iird_sched_entity *e;
    atomic_bool entered;
} waiter;

/* Enters (blocking until granted or cancelled), then leaves at once. */
static void *enter_main(void *arg)
{
    waiter *w = arg;
    iird_sched_enter(w->s, w->e);
    atomic_store(&w->entered, true);
    iird_sched_leave(w->s, w->e);
    return NULL;
}

static void wait_until_waiting(iird_sched *s, int n)
{
    for (int i = 0; i < 5000 && iird_sched_get_stats(s).waiting < n; i++) sleep_ms(1);
    assert_int_equal(iird_sched_get_stats(s).waiting, n);
}

static void test_a_cancelled_wait_returns_without_a_slot(void **state)
{
    (void)state;
    iird_sched *s = iird_sched_create(1, 2, 10.0);
    iird_sched_entity a, b;
    iird_sched_add(s, &a);
    iird_sched_add(s, &b);
    iird_sched_enter(s, &a); /* a holds the only slot and never yields */
    waiter w = {.s = s, .e = &b};
    pthread_t t;
    pthread_create(&t, NULL, enter_main, &w);
    wait_until_waiting(s, 1);
    assert_false(atomic_load(&w.entered));
    iird_sched_cancel(s, &b);
    pthread_join(t, NULL);
    assert_true(atomic_load(&w.entered));
    assert_false(atomic_load(&b.running));
    assert_true(atomic_load(&a.running));
    assert_int_equal(iird_sched_get_stats(s).waiting, 0);
    iird_sched_enter(s, &b); /* cancelled for good: no more waiting */
    assert_false(atomic_load(&b.running));
    iird_sched_leave(s, &a);
    iird_sched_remove(s, &a);
    iird_sched_remove(s, &b);
    iird_sched_destroy(s);
}

static void test_a_waking_session_preempts_at_the_next_yield(void **state)
{
    (void)state;
    iird_sched *s = iird_sched_create(1, 4, 1000.0); /* a slice far longer than the test */
    iird_sched_entity a, b;
    iird_sched_add(s, &a);
    iird_sched_add(s, &b);
    assert_int_equal(iird_sched_enter(s, &a), 4);
    sleep_ms(20); /* a has rendered 20 ms; b has rendered nothing */
    waiter w = {.s = s, .e = &b};
    pthread_t t;
    pthread_create(&t, NULL, enter_main, &w);
    wait_until_waiting(s, 1);
    assert_true(atomic_load(&a.preempt));
    iird_sched_yield(s, &a); /* hands over, and blocks until b leaves */
    assert_true(atomic_load(&w.entered));
    assert_true(atomic_load(&a.running));
    assert_false(atomic_load(&a.preempt));
    pthread_join(t, NULL);
    assert_int_equal(iird_sched_get_stats(s).handovers, 1);
    iird_sched_leave(s, &a);
    iird_sched_remove(s, &a);
    iird_sched_remove(s, &b);
    iird_sched_destroy(s);
}

static void test_teams_split_the_threads_between_slots(void **state)
{
    (void)state;
    iird_sched *s = iird_sched_create(2, 4, 10.0);
    iird_sched_entity a, b;
    iird_sched_add(s, &a);
    iird_sched_add(s, &b);
    assert_int_equal(iird_sched_enter(s, &a), 4); /* alone: every thread */
    assert_int_equal(iird_sched_enter(s, &b), 2); /* beside a, in the second slot: half */
    assert_true(atomic_load(&a.running) && atomic_load(&b.running));
    iird_sched_leave(s, &a);
    iird_sched_leave(s, &b);
    assert_int_equal(iird_sched_enter(s, &b), 4); /* alone again */
    iird_sched_leave(s, &b);
    iird_sched_remove(s, &a);
    iird_sched_remove(s, &b);
    iird_sched_destroy(s);
}

/* Enters as background work and keeps the slot (the test leaves for it). */
static void *background_main(void *arg)
{
    waiter *w = arg;
    iird_sched_enter_background(w->s, w->e);
    atomic_store(&w->entered, true);
    return NULL;
}

/* A frame that arrives takes a background pass's only slot at its next yield, and the pass waits
 * until no frame renders. */
static void test_a_frame_preempts_background_work(void **state)
{
    (void)state;
    iird_sched *s = iird_sched_create(1, 4, 1000.0); /* a slice far longer than the test */
    iird_sched_entity a, b;
    iird_sched_add(s, &a);
    iird_sched_add(s, &b);
    assert_int_equal(iird_sched_enter_background(s, &a), 4);
    waiter w = {.s = s, .e = &b};
    pthread_t t;
    pthread_create(&t, NULL, enter_main, &w); /* b has rendered no less than a: preempts anyway */
    wait_until_waiting(s, 1);
    assert_true(atomic_load(&a.preempt));
    iird_sched_yield(s, &a); /* hands over, and blocks until b leaves */
    pthread_join(t, NULL);
    assert_true(atomic_load(&w.entered) && atomic_load(&a.running));
    iird_sched_leave(s, &a);
    iird_sched_remove(s, &a);
    iird_sched_remove(s, &b);
    iird_sched_destroy(s);
}

/* Background work gets no free slot while a frame renders, and a frame beside background work gets
 * every thread; new input promotes a waiting pass to a frame. */
static void test_background_waits_for_frames(void **state)
{
    (void)state;
    iird_sched *s = iird_sched_create(2, 4, 1000.0);
    iird_sched_entity a, b;
    iird_sched_add(s, &a);
    iird_sched_add(s, &b);
    assert_int_equal(iird_sched_enter(s, &b), 4);
    waiter w = {.s = s, .e = &a};
    pthread_t t;
    pthread_create(&t, NULL, background_main, &w);
    wait_until_waiting(s, 1);
    sleep_ms(20); /* a free slot, but b renders: a waits */
    assert_false(atomic_load(&w.entered));
    iird_sched_leave(s, &b);
    pthread_join(t, NULL); /* no frame left: a's turn */
    assert_true(atomic_load(&w.entered) && atomic_load(&a.running));
    assert_int_equal(iird_sched_enter(s, &b), 4); /* beside background work: every thread */
    iird_sched_leave(s, &b);
    iird_sched_leave(s, &a);
    assert_int_equal(iird_sched_enter(s, &b), 4);
    atomic_store(&w.entered, false);
    pthread_create(&t, NULL, background_main, &w);
    wait_until_waiting(s, 1);
    iird_sched_promote(s, &a); /* new input: a is a frame now, and takes the free slot */
    pthread_join(t, NULL);
    assert_true(atomic_load(&w.entered) && atomic_load(&a.running));
    iird_sched_leave(s, &a);
    iird_sched_leave(s, &b);
    iird_sched_remove(s, &a);
    iird_sched_remove(s, &b);
    iird_sched_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_alone_gets_every_thread_and_never_waits),
        cmocka_unit_test(test_busy_sessions_share_one_slot_equally),
        cmocka_unit_test(test_a_cancelled_wait_returns_without_a_slot),
        cmocka_unit_test(test_a_waking_session_preempts_at_the_next_yield),
        cmocka_unit_test(test_teams_split_the_threads_between_slots),
        cmocka_unit_test(test_a_frame_preempts_background_work),
        cmocka_unit_test(test_background_waits_for_frames),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}

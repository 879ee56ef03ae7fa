/* pool.h — the compute pool: a few worker threads that run every job's work off the loop
 * thread (session jobs and mesh loads), and the one channel back from them.
 *
 * Same contract as uv_queue_work (work on a worker, `after` on the loop thread in completion
 * order, the loop never waits for work), with a cheaper hand-off for interactive requests:
 *   - one completion channel: a running task may also post progress messages
 *     (df_pool_post), delivered on the loop thread in the same order as completions, so a
 *     task's progress always arrives before its completion (handle moves' iterates);
 *   - the pool's handle keeps the loop alive only while tasks are in flight;
 *   - completions are signalled through one eventfd watched by a uv_poll handle, written only
 *     when the loop has not been told yet (uv_async makes the woken loop spin until the sender
 *     has left uv_async_send, which on a loaded machine means waiting for it to be rescheduled);
 *   - sleeping workers are woken last-idle-first (each has its own condition variable), so one
 *     stroke after another runs on the same cache-warm thread;
 *   - optionally (spin_ns > 0) a worker that just finished a SHORT task (< DF_POOL_SHORT_TASK_NS)
 *     polls the queue for up to spin_ns (<= DF_POOL_MAX_SPIN_NS) before sleeping, yielding the
 *     CPU between polls, so that back-to-back strokes skip the futex wake-up. It helps only with
 *     idle cores (on the shared 2-core test machine: ~1 us of a 50 us round trip), hence
 *     deformd's default 0 (config `spin_us`). A worker that ran a long task sleeps at once.
 *   - long lane: tasks marked `heavy` (handle moves: may run for hours) occupy at most threads - 1 workers (1 with a single thread), so that short tasks
 *     (brush strokes, reads) always find a worker while long solves run; heavy tasks beyond
 *     that wait in their own FIFO, in submission order. A heavy task may yield: its work sets
 *     `requeue` and returns, and it goes back to the tail of the long lane instead of completing
 *     (its `after` runs only once it really finished), so long tasks take turns (and with a
 *     single thread, short tasks get it between turns).
 *     df_pool_heavy_waiting tells a running heavy task that others wait for the lane.
 * The loop itself never busy-polls for results: measured, it took the core the worker needed
 * (the scheduler wakes the worker on the loop's CPU) and made round trips slower, not faster. */
#ifndef DF_SERVER_POOL_H
#define DF_SERVER_POOL_H

#include <stdint.h>
#include <uv.h>

#include "core/common/df_error.h"

#define DF_POOL_MAX_THREADS 64
#define DF_POOL_SHORT_TASK_NS 200000ull /* tasks below this are "interactive" (may spin after) */
#define DF_POOL_MAX_SPIN_NS 1000000ull  /* upper bound of spin_ns                             */

typedef struct df_task df_task;
typedef void (*df_task_fn)(df_task *t);

/* A unit of work, embedded by the caller (which owns its memory until `after` ran). */
struct df_task {
    df_task_fn work;   /* worker thread; required */
    df_task_fn after;  /* loop thread, once work returned; required */
    uint64_t work_ns;  /* measured work time in ns, set before `after` runs */
    int heavy;         /* 1: long-lane task (see above); set by the caller before submit */
    int requeue;       /* set by a heavy task's work to yield (see above); the pool clears it */
    int post;          /* pool-internal: a progress message (df_pool_post), not a task */
    df_task *next;     /* pool-internal */
};

typedef struct df_pool df_pool;

/* Starts `threads` (1..DF_POOL_MAX_THREADS) workers delivering completions on `loop` (call on
 * the loop thread); spin_ns (0..DF_POOL_MAX_SPIN_NS, ns) is how long a worker polls for new work
 * after a short task, 0 = never. *out receives the pool. Errors: DF_EINVAL (threads or spin_ns
 * out of range), DF_ENOMEM, DF_EIO (eventfd, handle or thread creation failed; nothing is left
 * running, *out untouched). */
int df_pool_start(uv_loop_t *loop, int threads, uint64_t spin_ns, df_pool **out, df_error *err);

/* Queues `t` (loop thread; t->work and t->after set). Never waits for running work. */
void df_pool_submit(df_pool *p, df_task *t);

/* Posts progress message `msg` from a running task's work (worker thread): msg->after runs on
 * the loop thread, after everything posted or completed before it and before the posting
 * task's own `after`. msg->work is not used; the poster owns msg until its `after` ran. */
void df_pool_post(df_pool *p, df_task *msg);

/* Tasks that wait because heavy tasks occupy workers (any thread): heavy tasks queued beyond
 * the long lane's room, plus the queued short tasks when the pool has a single thread (its
 * lane is then that thread). A running heavy task yields (requeue) when this is > 0. */
int df_pool_heavy_waiting(const df_pool *p);

/* Tasks submitted and whose `after` has not run yet. */
int df_pool_inflight(const df_pool *p);

/* Stops the workers (they finish the task they run; queued tasks are NOT run: call this when
 * nothing is in flight), joins them and closes the pool's handles (loop thread). The memory
 * stays valid until df_pool_free, to be called once the loop has run the close callbacks. */
void df_pool_close(df_pool *p);

/* Frees a closed pool (NULL-safe). */
void df_pool_free(df_pool *p);

/* Counters (loop thread): tasks completed, tasks a spinning worker picked up without a
 * wake-up, eventfd wake-ups of the loop (several completions may share one); the long lane's
 * size and the heavy tasks that had to wait for the lane. */
typedef struct df_pool_counters {
    uint64_t tasks, spin_hits, wakeups;
    int heavy_max;
    uint64_t heavy_waits;
} df_pool_counters;
void df_pool_counters_get(const df_pool *p, df_pool_counters *out);

#endif

/* pool.c — compute pool: condition-variable workers, optional bounded spin, eventfd completions
 * (see pool.h).
 *
 * Lost wake-ups. Completions: a worker appends to the done list and then sets `signaled`
 * (exchange); only the worker that flips it 0 -> 1 writes the eventfd. The loop clears
 * `signaled` before taking the list, so an append after the take finds it 0 and writes again.
 * Queue: a spinner leaving its spin decrements nspinning under the queue lock and re-checks the
 * queue under it, so a submit that counted it as spinning (and did not signal) is still seen.
 * Sleeping workers form a LIFO stack, each with its own condition variable: a submit wakes the
 * worker that went idle last, so one stroke after another keeps landing on the same (cache-warm)
 * thread instead of rotating through the pool.
 * Long lane: heavy tasks wait in their own FIFO and at most `heavy_max` (threads - 1, at least 1)
 * of them run at once; a worker takes a short task first, a heavy one only while the lane has
 * room, so with two or more threads one worker is always left for short tasks. */
#include "server/exec/pool.h"

#include <errno.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/eventfd.h>
#include <unistd.h>

#define DF_POOL_PAUSES_PER_YIELD 16 /* pause instructions between two sched_yield in a spin */

typedef struct worker {
    struct df_pool *p;
    pthread_t th;
    pthread_cond_t cond;     /* this worker's wake-up                                   */
    int woken;               /* set (under lock) by the submit that picked this worker  */
    struct worker *next_idle;
} worker;

struct df_pool {
    uv_loop_t *loop;
    int efd;                 /* eventfd: workers -> loop, "the done list is not empty"   */
    uv_poll_t poll;          /* watches efd                                             */
    int handle_open;         /* poll handle initialized and not closed yet              */
    int closing;             /* df_pool_close ran                                       */
    int free_on_close;       /* start failed: free the struct in the close callback     */
    uint64_t spin_ns;
    worker w[DF_POOL_MAX_THREADS];
    int nthreads;
    int nworkers;            /* threads asked for (set before any worker starts) */
    /* queue, under lock */
    pthread_mutex_t lock;
    df_task *qhead, *qtail;  /* short tasks */
    df_task *hhead, *htail;  /* heavy tasks (long lane) */
    int nhq, nheavy, heavy_max; /* heavy tasks queued / running (at most heavy_max) */
    worker *idle;            /* sleeping workers, most recently idle first (LIFO: the woken
                              * thread is the one whose caches are warm)                 */
    int nq, nspinning, stopping;
    atomic_int qhint;        /* nq, read by spinners without the lock */
    atomic_int hwait;        /* tasks a running heavy task keeps waiting (df_pool_heavy_waiting) */
    atomic_int stop;
    /* completions, under dlock */
    pthread_mutex_t dlock;
    df_task *dhead, *dtail;
    atomic_int signaled;     /* the eventfd was written and the loop has not drained yet */
    atomic_uint_fast64_t spin_hits;
    /* loop thread only */
    int inflight;
    uint64_t tasks, wakeups;
    uint64_t heavy_waits;    /* heavy tasks queued while the lane was full (written in submit) */
};

/* 1 when a worker may take a task now (under lock). */
static int runnable(const df_pool *p)
{
    return p->qhead || (p->hhead && p->nheavy < p->heavy_max);
}

/* Tasks a worker may take now, for the spinners' hint and the wake-up decision (under lock). */
static int nrunnable(const df_pool *p)
{
    int room = p->heavy_max - p->nheavy;
    return p->nq + (p->nhq < room ? p->nhq : room);
}

/* Refreshes the lock-free hints after a queue or lane change (under lock). */
static void update_hints(df_pool *p)
{
    int room = p->heavy_max - p->nheavy;
    int wait = p->nhq > room ? p->nhq - room : 0;
    if (p->heavy_max >= p->nworkers) wait += p->nq; /* one thread: short tasks wait for it too */
    atomic_store_explicit(&p->qhint, nrunnable(p), memory_order_release);
    atomic_store_explicit(&p->hwait, wait, memory_order_relaxed);
}

int df_pool_heavy_waiting(const df_pool *p)
{
    return atomic_load_explicit(&((df_pool *)p)->hwait, memory_order_relaxed);
}

/* One spin step: a few pause instructions, then give the core to any runnable thread. */
static inline void relax(void)
{
#if defined(__x86_64__) || defined(__i386__)
    for (int i = 0; i < DF_POOL_PAUSES_PER_YIELD; i++) __builtin_ia32_pause();
#endif
    sched_yield();
}

static void complete(df_pool *p, df_task *t)
{
    t->next = NULL;
    pthread_mutex_lock(&p->dlock);
    if (p->dtail) p->dtail->next = t;
    else p->dhead = t;
    p->dtail = t;
    pthread_mutex_unlock(&p->dlock);
    if (atomic_exchange(&p->signaled, 1) == 0) {
        uint64_t one = 1;
        while (write(p->efd, &one, sizeof one) < 0 && errno == EINTR) {
        }
    }
}

static void *worker_main(void *arg)
{
    worker *me = arg;
    df_pool *p = me->p;
    uint64_t spin_until = 0;
    pthread_mutex_lock(&p->lock);
    for (;;) {
        int spun = 0;
        while (!runnable(p) && !p->stopping) {
            if (spin_until && uv_hrtime() < spin_until) {
                p->nspinning++;
                pthread_mutex_unlock(&p->lock);
                while (!atomic_load_explicit(&p->qhint, memory_order_acquire) &&
                       !atomic_load_explicit(&p->stop, memory_order_relaxed) &&
                       uv_hrtime() < spin_until)
                    relax();
                pthread_mutex_lock(&p->lock);
                p->nspinning--;
                spun = 1;
                continue;
            }
            spun = 0;
            me->woken = 0;
            me->next_idle = p->idle;
            p->idle = me;
            while (!me->woken && !p->stopping) pthread_cond_wait(&me->cond, &p->lock);
        }
        if (p->stopping) break;
        df_task *t;
        if (p->qhead) { /* short tasks first */
            t = p->qhead;
            p->qhead = t->next;
            if (!p->qhead) p->qtail = NULL;
            p->nq--;
        } else {
            t = p->hhead;
            p->hhead = t->next;
            if (!p->hhead) p->htail = NULL;
            p->nhq--;
            p->nheavy++;
        }
        update_hints(p);
        pthread_mutex_unlock(&p->lock);
        if (spun) atomic_fetch_add_explicit(&p->spin_hits, 1, memory_order_relaxed);
        uint64_t t0 = uv_hrtime();
        t->work(t);
        uint64_t t1 = uv_hrtime();
        t->work_ns = t1 - t0;
        spin_until = p->spin_ns && t->work_ns < DF_POOL_SHORT_TASK_NS ? t1 + p->spin_ns : 0;
        int heavy = t->heavy;
        if (heavy && t->requeue) { /* yields: back to the tail of the long lane */
            t->requeue = 0;
            t->next = NULL;
            pthread_mutex_lock(&p->lock);
            p->nheavy--;
            if (p->htail) p->htail->next = t;
            else p->hhead = t;
            p->htail = t;
            p->nhq++;
            update_hints(p);
            continue;
        }
        complete(p, t); /* t may be freed by the loop from here on */
        pthread_mutex_lock(&p->lock);
        if (heavy) {
            p->nheavy--;
            update_hints(p);
        }
    }
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

/* Runs `after` of every completed task in completion order (loop thread). */
static void drain(df_pool *p)
{
    atomic_store(&p->signaled, 0);
    pthread_mutex_lock(&p->dlock);
    df_task *t = p->dhead;
    p->dhead = p->dtail = NULL;
    pthread_mutex_unlock(&p->dlock);
    while (t) {
        df_task *next = t->next;
        if (!t->post) { /* a completion (posts are progress messages of a running task) */
            p->inflight--;
            p->tasks++;
            if (p->inflight == 0 && p->handle_open && !p->closing)
                uv_unref((uv_handle_t *)&p->poll); /* idle: the pool keeps no loop alive */
        }
        t->after(t);
        t = next;
    }
}

static void on_poll(uv_poll_t *h, int status, int events)
{
    (void)status;
    (void)events;
    df_pool *p = h->data;
    uint64_t v;
    while (read(p->efd, &v, sizeof v) < 0 && errno == EINTR) {
    }
    p->wakeups++;
    drain(p);
}

void df_pool_post(df_pool *p, df_task *msg)
{
    msg->post = 1;
    complete(p, msg);
}

void df_pool_submit(df_pool *p, df_task *t)
{
    if (p->inflight++ == 0 && p->handle_open && !p->closing) uv_ref((uv_handle_t *)&p->poll);
    t->post = 0;
    t->next = NULL;
    t->work_ns = 0;
    pthread_mutex_lock(&p->lock);
    if (t->heavy) {
        if (p->htail) p->htail->next = t;
        else p->hhead = t;
        p->htail = t;
        p->nhq++;
        if (p->nheavy + p->nhq > p->heavy_max) p->heavy_waits++; /* the lane is full: t waits */
    } else {
        if (p->qtail) p->qtail->next = t;
        else p->qhead = t;
        p->qtail = t;
        p->nq++;
    }
    int n = nrunnable(p);
    update_hints(p);
    if (p->idle && n > p->nspinning) { /* wake the most recently idle worker */
        worker *w = p->idle;
        p->idle = w->next_idle;
        w->woken = 1;
        pthread_cond_signal(&w->cond);
    }
    pthread_mutex_unlock(&p->lock);
}

int df_pool_inflight(const df_pool *p) { return p->inflight; }

void df_pool_counters_get(const df_pool *p, df_pool_counters *out)
{
    out->tasks = p->tasks;
    out->spin_hits = atomic_load_explicit(&p->spin_hits, memory_order_relaxed);
    out->wakeups = p->wakeups;
    out->heavy_max = p->heavy_max;
    out->heavy_waits = p->heavy_waits;
}

static void stop_threads(df_pool *p)
{
    pthread_mutex_lock(&p->lock);
    p->stopping = 1;
    atomic_store(&p->stop, 1);
    for (int i = 0; i < p->nthreads; i++) pthread_cond_signal(&p->w[i].cond);
    pthread_mutex_unlock(&p->lock);
    for (int i = 0; i < p->nthreads; i++) {
        pthread_join(p->w[i].th, NULL);
        pthread_cond_destroy(&p->w[i].cond);
    }
    p->nthreads = 0;
}

static void on_closed(uv_handle_t *h)
{
    df_pool *p = h->data;
    p->handle_open = 0;
    if (p->free_on_close) df_pool_free(p);
}

static void close_handle(df_pool *p)
{
    if (p->closing) return;
    p->closing = 1;
    if (!p->handle_open) {
        if (p->free_on_close) df_pool_free(p);
        return;
    }
    uv_poll_stop(&p->poll);
    uv_close((uv_handle_t *)&p->poll, on_closed);
}

int df_pool_start(uv_loop_t *loop, int threads, uint64_t spin_ns, df_pool **out, df_error *err)
{
    if (threads < 1 || threads > DF_POOL_MAX_THREADS)
        return df_error_set(err, DF_EINVAL, "pool: %d threads not in 1..%d", threads,
                            DF_POOL_MAX_THREADS);
    if (spin_ns > DF_POOL_MAX_SPIN_NS)
        return df_error_set(err, DF_EINVAL, "pool: spin of %llu ns over the %llu ns bound",
                            (unsigned long long)spin_ns, (unsigned long long)DF_POOL_MAX_SPIN_NS);
    df_pool *p = calloc(1, sizeof *p);
    if (!p) return df_error_set(err, DF_ENOMEM, "pool: out of memory");
    p->loop = loop;
    p->spin_ns = spin_ns;
    p->heavy_max = threads > 1 ? threads - 1 : 1;
    p->nworkers = threads;
    p->efd = -1;
    pthread_mutex_init(&p->lock, NULL);
    pthread_mutex_init(&p->dlock, NULL);
    atomic_init(&p->qhint, 0);
    atomic_init(&p->hwait, 0);
    atomic_init(&p->stop, 0);
    atomic_init(&p->signaled, 0);
    atomic_init(&p->spin_hits, 0);
    p->efd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    int rc = p->efd < 0 ? -errno : uv_poll_init(loop, &p->poll, p->efd);
    if (rc == 0) {
        p->poll.data = p;
        p->handle_open = 1;
        rc = uv_poll_start(&p->poll, UV_READABLE, on_poll);
        if (rc == 0) uv_unref((uv_handle_t *)&p->poll); /* referenced while tasks are in flight */
    }
    if (rc != 0) {
        const char *what = p->efd < 0 ? strerror(-rc) : uv_strerror(rc);
        df_error_set(err, DF_EIO, "pool: cannot watch an eventfd: %s", what);
        p->free_on_close = 1;
        close_handle(p);
        return DF_EIO;
    }
    for (int i = 0; i < threads; i++) {
        worker *w = &p->w[i];
        w->p = p;
        pthread_cond_init(&w->cond, NULL);
        int e = pthread_create(&w->th, NULL, worker_main, w);
        if (e != 0) {
            pthread_cond_destroy(&w->cond);
            stop_threads(p);
            p->free_on_close = 1;
            close_handle(p);
            return df_error_set(err, DF_EIO, "pool: cannot start worker %d: %s", i, strerror(e));
        }
        p->nthreads++;
    }
    *out = p;
    return DF_OK;
}

void df_pool_close(df_pool *p)
{
    if (!p) return;
    stop_threads(p);
    close_handle(p);
}

void df_pool_free(df_pool *p)
{
    if (!p) return;
    if (p->efd >= 0) close(p->efd);
    pthread_mutex_destroy(&p->lock);
    pthread_mutex_destroy(&p->dlock);
    free(p);
}

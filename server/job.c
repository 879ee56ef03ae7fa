/* job.c — per-session FIFO of jobs on the libuv pool (see job.h). */
#include "server/job.h"

#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "proto/messages.h"
#include "server/conn.h"
#include "server/log.h"
#include "server/reply.h"

df_job *df_job_new(df_server *srv, df_session *s, df_conn *c, uint16_t type, uint64_t req_id,
                   df_job_fn work, df_job_fn done)
{
    df_job *j = calloc(1, sizeof *j);
    if (!j) return NULL;
    j->srv = srv;
    j->s = s;
    j->c = c;
    if (c) {
        df_conn_ref(c);
        j->conn_id = c->id;
    }
    j->type = type;
    j->req_id = req_id;
    j->work = work;
    j->done = done;
    atomic_init(&j->cancel, 0);
    return j;
}

df_job *df_job_for_request(df_conn *c, const df_frame_header *h, df_session *s, size_t body_size,
                           df_job_fn work, df_job_fn done, df_job_fn cleanup)
{
    void *body = calloc(1, body_size);
    df_job *j = body ? df_job_new(c->srv, s, c, h->type, h->request_id, work, done) : NULL;
    if (!j) {
        free(body);
        df_error e;
        df_error_set(&e, DF_ENOMEM, "out of memory");
        df_reply_fail(c, h->type, h->request_id, &e);
        return NULL;
    }
    j->body = body;
    j->cleanup = cleanup;
    return j;
}

static void job_free(df_job *j)
{
    if (j->cleanup) j->cleanup(j);
    if (j->c) df_conn_unref(j->c);
    free(j);
}

void df_job_broadcast(df_job *j, const df_frames *f)
{
    for (size_t i = 0; i < f->n; i++) df_session_broadcast(j->s, f->v[i]);
    if (f->n) j->srv->stats.versions++;
}

void df_job_ack(df_job *j)
{
    df_msg_ack a = {.session_id = j->s->id, .version = atomic_load(&j->s->version)};
    if (j->c) df_reply_ack(j->c, j->type, j->req_id, &a, 1);
}

static void pump(df_session *s);

int df_job_move_running(const df_session *s)
{
    return s->running && s->running->preemptible && !s->jhead;
}

/* Ends the running move early (loop thread): a request has to wait for it. */
static void preempt(df_session *s)
{
    df_job *r = s->running;
    if (!r || !r->preemptible || atomic_load(&r->cancel)) return;
    atomic_store(&r->cancel, 1);
    s->srv->stats.moves_preempted++;
}

/* Answers `j` beside the running move (see job.h, "Moves"); loop thread. */
static void run_beside(df_job *j)
{
    df_session *s = j->s;
    df_server *srv = j->srv;
    pthread_mutex_lock(&s->pub_lock);
    df_server_drain_mail(srv); /* subscribers have every version the move published so far */
    if (j->beside == DF_JOB_BESIDE_REFUSE)
        j->rc = df_error_set(&j->err, DF_ESTATE, "%s: a handle move is running on session %llu",
                             df_msg_type_name(j->type), (unsigned long long)s->id);
    else if (j->work)
        j->work(j);
    j->done(j);
    pthread_mutex_unlock(&s->pub_lock);
    job_free(j);
    srv->stats.jobs_completed++;
    srv->stats.jobs_beside_move++;
}

/* Runs `done`, frees the job and clears the session's running slot (loop thread). */
static void finish(df_job *j)
{
    df_server *srv = j->srv;
    df_session *s = j->s;
    j->done(j);
    job_free(j);
    srv->stats.jobs_completed++;
    if (s) {
        s->running = NULL;
        df_session_seen_sync(s); /* stats reads these copies while the next job runs */
    }
}

static void work_cb(uv_work_t *w)
{
    df_job *j = w->data;
    j->work(j);
}

/* The job's work has run (or was cancelled: status UV_ECANCELED); loop thread. */
static void completed(df_job *j, int status)
{
    df_server *srv = j->srv;
    df_session *s = j->s;
    srv->jobs_running--;
    /* Progress frames the worker posted must go out before the job's final frames. */
    df_server_drain_mail(srv);
    if (status == UV_ECANCELED) {
        j->canceled = 1;
        j->rc = df_error_set(&j->err, DF_ESTATE, "server shutting down");
    }
    finish(j);
    if (s) pump(s);
}

static void after_cb(uv_work_t *w, int status) { completed(w->data, status); }

static void task_work(df_task *t)
{
    df_job *j = (df_job *)((char *)t - offsetof(df_job, task));
    j->work(j);
}

static void task_after(df_task *t)
{
    completed((df_job *)((char *)t - offsetof(df_job, task)), 0);
}

/* 1 when the head job `j` may run its work on the loop thread (see job.h, "Inline jobs"). */
static int runs_inline(df_job *j)
{
    uint64_t budget_ns = (uint64_t)j->srv->cfg.inline_us * 1000u;
    if (!j->inline_cost || budget_ns == 0 || j->srv->stopping) return 0;
    uint64_t ns = j->inline_cost(j);
    if (ns == 0 || ns > budget_ns) return 0;
    if (j->srv->inline_spent_ns + ns > DF_JOB_INLINE_ITER_FACTOR * budget_ns) {
        j->srv->stats.jobs_inline_deferred++; /* this iteration's inline budget is spent */
        return 0;
    }
    return 1;
}

/* Starts queued jobs until one is running on the pool or the FIFO is empty; frees a closed
 * session once it is idle. */
static void pump(df_session *s)
{
    while (!s->running && s->jhead) {
        df_job *j = s->jhead;
        s->jhead = j->next;
        if (!s->jhead) s->jtail = NULL;
        j->next = NULL;
        s->running = j;
        if (j->preemptible && s->jhead) preempt(s); /* requests already wait behind it */
        if (j->work && runs_inline(j)) { /* cheaper than two thread hand-offs */
            uint64_t t0 = uv_hrtime();
            j->work(j);
            j->srv->inline_spent_ns += uv_hrtime() - t0;
            j->srv->stats.jobs_inline++;
            finish(j);
            continue;
        }
        if (j->work && j->srv->pool) { /* the server's low-latency pool */
            j->srv->jobs_running++;
            j->task.work = task_work;
            j->task.after = task_after;
            j->task.heavy = j->heavy;
            df_pool_submit(j->srv->pool, &j->task);
            return;
        }
        if (j->work) { /* bare servers (unit tests): the libuv pool */
            j->w.data = j;
            j->srv->jobs_running++;
            int rc = uv_queue_work(j->srv->loop, &j->w, work_cb, after_cb);
            if (rc == 0) return;
            j->srv->jobs_running--;
            j->rc = df_error_set(&j->err, DF_EINTERNAL, "uv_queue_work: %s", uv_strerror(rc));
        }
        finish(j);
    }
    if (s->closed && !s->running && !s->jhead) df_session_destroy(s);
}

void df_job_pump(df_session *s) { pump(s); }

void df_job_submit(df_job *j)
{
    j->srv->stats.jobs_submitted++;
    df_session *s = j->s;
    if (!s) {
        j->w.data = j;
        j->srv->jobs_running++;
        int rc = j->work ? uv_queue_work(j->srv->loop, &j->w, work_cb, after_cb) : -1;
        if (rc != 0) {
            j->srv->jobs_running--;
            if (j->work)
                j->rc = df_error_set(&j->err, DF_EINTERNAL, "uv_queue_work: %s", uv_strerror(rc));
            finish(j);
        }
        return;
    }
    if (j->beside != DF_JOB_BESIDE_NONE && df_job_move_running(s)) {
        run_beside(j);
        return;
    }
    if (j->c) preempt(s); /* a requester must not wait for a move: it ends at its next iteration */
    if (s->jtail) s->jtail->next = j;
    else s->jhead = j;
    s->jtail = j;
    if (!s->running) pump(s);
}

int df_job_drop_queued(df_session *s, int (*pred)(const df_job *j, void *arg), void *arg,
                       const char *why)
{
    int n = 0;
    df_job **pp = &s->jhead, *last = NULL;
    while (*pp) {
        df_job *j = *pp;
        if (pred(j, arg)) {
            *pp = j->next;
            j->next = NULL;
            j->rc = df_error_set(&j->err, DF_ESTATE, "%s", why);
            j->work = NULL;
            j->done(j);
            job_free(j);
            s->srv->stats.jobs_completed++;
            n++;
        } else {
            last = j;
            pp = &j->next;
        }
    }
    s->jtail = last;
    return n;
}

int df_job_pred_all(const df_job *j, void *arg)
{
    (void)j;
    (void)arg;
    return 1;
}

int df_job_failed(df_job *j)
{
    if (j->rc == DF_OK) return 0;
    if (j->c) df_reply_fail(j->c, j->type, j->req_id, &j->err);
    return 1;
}

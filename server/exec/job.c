/* job.c — per-session FIFO of jobs on the libuv pool (see job.h). */
#include "server/exec/job.h"

#include <stddef.h>
#include <stdlib.h>
#include <string.h>

#include "proto/messages.h"
#include "server/session/access.h"
#include "server/net/conn.h"
#include "server/log.h"
#include "server/net/reply.h"
#include "server/session/commit.h"

df_job *df_job_new(df_server *srv, df_session *s, df_conn *c, uint16_t type, uint64_t req_id,
                   df_job_fn work, df_job_fn done)
{
    df_job *j = calloc(1, sizeof *j);
    if (!j) return NULL;
    j->srv = srv;
    j->s = s;
    j->req.srv = srv;
    j->req.c = c;
    if (c) {
        df_conn_ref(c);
        j->conn_id = c->id;
    }
    j->req.type = type;
    j->req.id = req_id;
    j->work = work;
    j->done = done;
    atomic_init(&j->cancel, 0);
    df_change_init(&j->change, &j->req, &j->err);
    return j;
}

/* Frees the body of a job made by df_job_request (what it owns first). */
static void kind_cleanup(df_job *j)
{
    if (j->kind->release && j->body) j->kind->release(j->srv, j->body);
    free(j->body);
}

int df_job_decode_ref(const df_req *r, const uint8_t *p, void *body, uint64_t *session_id,
                      df_error *err)
{
    (void)body;
    df_msg_session_ref m;
    int rc = df_msg_session_ref_decode(p, r->len, &m, err);
    if (rc == DF_OK) *session_id = m.session_id;
    return rc;
}

int df_job_is_change(uint16_t type)
{
    switch (type) {
    case DF_MSG_BRUSH_BEGIN: case DF_MSG_BRUSH_UPDATE: case DF_MSG_BRUSH_END:
    case DF_MSG_BRUSH_CANCEL: case DF_MSG_SET_BRUSH_PARAM: case DF_MSG_HANDLES_SET:
    case DF_MSG_HANDLES_MOVE: case DF_MSG_RESET_REST: case DF_MSG_UNDO: case DF_MSG_REDO:
    case DF_MSG_SUBSCRIBE:
        return 1;
    default:
        return 0;
    }
}

int df_job_request(df_req *r, const uint8_t *p, const df_job_kind *kind, df_error *err)
{
    void *body = kind->body_size ? calloc(1, kind->body_size) : NULL;
    if (kind->body_size && !body) return df_error_set(err, DF_ENOMEM, "out of memory");
    uint64_t sid = 0;
    int rc = kind->decode(r, p, body, &sid, err);
    df_session *s = NULL;
    if (rc == DF_OK && !(s = df_session_find(r->srv, sid)) && r->srv->session_route)
        rc = r->srv->session_route(r->srv, sid, &s, err); /* redirect or take over */
    else if (rc == DF_OK && !s)
        rc = df_error_set(err, DF_ENOTFOUND, "%s: no session %llu", df_msg_type_name(r->type),
                          (unsigned long long)sid);
    if (rc == DF_OK) rc = df_access_check(r, s, err); /* per-session rights (access.h) */
    df_job *j = rc == DF_OK ? df_job_new(r->srv, s, r->c, r->type, r->id, kind->work, kind->done)
                            : NULL;
    if (!j) {
        if (kind->release && body) kind->release(r->srv, body);
        free(body);
        return rc != DF_OK ? rc : df_error_set(err, DF_ENOMEM, "out of memory");
    }
    j->req.flags = r->flags;
    j->req.len = r->len;
    j->req.origin_id = r->origin_id;
    if (r->origin_id) j->conn_id = r->origin_id; /* a device's request: its stroke key */
    if (r->c && df_job_is_change(r->type)) r->srv->last_change_session = s->id;
    r->answered = 1; /* the job answers it now (j->req) */
    j->kind = kind;
    j->body = body;
    j->cleanup = kind_cleanup;
    j->inline_cost = kind->inline_cost;
    j->beside = kind->beside;
    j->heavy = kind->heavy;
    j->preemptible = kind->preemptible;
    if (kind->queued) kind->queued(j);
    df_job_submit(j);
    return DF_OK;
}

static void job_free(df_job *j)
{
    if (j->cleanup) j->cleanup(j);
    df_change_clear(j->srv, &j->change);
    if (j->req.c) df_conn_unref(j->req.c);
    free(j);
}

void df_job_commit(df_job *j)
{
    j->change.rc = j->rc;
    df_session_commit(j->s, &j->change);
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
    /* The move's iterates are committed on this thread as they arrive (commit.h): the session
     * holds exactly the last version its subscribers have been sent. */
    if (j->beside == DF_JOB_BESIDE_REFUSE)
        j->rc = df_error_set(&j->err, DF_ESTATE, "%s: a handle move is running on session %llu",
                             df_msg_type_name(j->req.type), (unsigned long long)s->id);
    else if (j->work)
        j->work(j);
    j->done(j);
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

static void task_work(df_task *t)
{
    df_job *j = (df_job *)((char *)t - offsetof(df_job, task));
    j->work(j);
}

/* The job's work has run: its completion came through the pool's channel, after everything it
 * posted (loop thread). */
static void task_after(df_task *t)
{
    df_job *j = (df_job *)((char *)t - offsetof(df_job, task));
    df_session *s = j->s;
    j->srv->jobs_running--;
    finish(j);
    if (s) pump(s);
}

/* Hands j's work to the compute pool (every job's work that does not run inline). 0, or -1
 * with j->rc set when the server has no pool (then `done` must still run). */
static int start_on_pool(df_job *j)
{
    if (!j->srv->pool) {
        j->rc = df_error_set(&j->err, DF_EINTERNAL, "%s: the server has no compute pool",
                             df_msg_type_name(j->req.type));
        return -1;
    }
    j->srv->jobs_running++;
    j->task.work = task_work;
    j->task.after = task_after;
    j->task.heavy = j->heavy;
    df_pool_submit(j->srv->pool, &j->task);
    return 0;
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
        if (j->work && (j->rc = df_stream_scratch(s, &j->err)) != DF_OK) { /* lent to the work */
            finish(j);
            continue;
        }
        if (j->work && runs_inline(j)) { /* cheaper than two thread hand-offs */
            uint64_t t0 = uv_hrtime();
            j->work(j);
            j->srv->inline_spent_ns += uv_hrtime() - t0;
            j->srv->stats.jobs_inline++;
            finish(j);
            continue;
        }
        if (j->work && start_on_pool(j) == 0) return;
        finish(j);
    }
    if (s->closed && !s->running && !s->jhead) df_session_destroy(s);
}

void df_job_pump(df_session *s) { pump(s); }

void df_job_submit(df_job *j)
{
    j->srv->stats.jobs_submitted++;
    df_session *s = j->s;
    if (!s) { /* a mesh load: long work, so the long lane (a worker stays free for strokes) */
        j->heavy = 1;
        if (!j->work || start_on_pool(j) != 0) finish(j);
        return;
    }
    if (j->beside != DF_JOB_BESIDE_NONE && df_job_move_running(s)) {
        run_beside(j);
        return;
    }
    if (j->req.c) preempt(s); /* a requester must not wait for a move: it ends at its next iteration */
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
    df_req_fail(&j->req, &j->err);
    return 1;
}

/* Ends (commits) a departed client's stroke. */
/* Ends the stroke of a disconnected client as BRUSH_END would: one undo step, committed through
 * df_session_commit so the store journals it (durable like any step; nobody is answered). */
static void end_stroke(df_session *s, uint64_t conn_id)
{
    df_error err = {0};
    df_change c;
    df_change_init(&c, NULL, &err);
    c.hist = DF_HIST_COMMIT;
    c.drop_stroke = 1; /* with no request the commit leaves the dropping to us (below) */
    if (df_session_commit(s, &c) != DF_OK)
        df_log(DF_LOG_WARN, "session %llu: could not record a stroke for undo: %s",
               (unsigned long long)s->id, err.msg);
    df_change_clear(s->srv, &c);
    df_session_drop_stroke(s, conn_id);
    if (s->srv->hid_ops && s->srv->hid_ops->strokes_changed) /* force feedback stops */
        s->srv->hid_ops->strokes_changed(s->srv, s);
}

static void drop_stroke_done(df_job *j)
{
    if (j->rc == DF_OK && df_session_stroke(j->s, j->conn_id)) end_stroke(j->s, j->conn_id);
}

/* A queued move of connection *arg. */
static int pred_conn_move(const df_job *j, void *arg)
{
    return j->preemptible && j->conn_id == *(const uint64_t *)arg;
}

void df_job_forget_conn(df_server *srv, df_conn *c)
{
    for (df_session *s = srv->sessions; s; s = s->next) {
        df_session_unsubscribe(s, c);
        df_job *r = s->running;
        if (r && r->preemptible && r->conn_id == c->id && !atomic_load(&r->cancel)) {
            atomic_store(&r->cancel, 1); /* nobody waits for it any more */
            srv->stats.moves_orphaned++;
        }
        uint64_t id = c->id;
        df_job_drop_queued(s, pred_conn_move, &id, "requester disconnected");
        if (!df_session_stroke(s, c->id)) continue;
        if (!s->running) {
            end_stroke(s, c->id);
            continue;
        }
        /* A worker may be reading the stroke: drop it in FIFO order instead. */
        df_job *j = df_job_new(srv, s, NULL, 0, 0, NULL, drop_stroke_done);
        if (j) {
            j->conn_id = c->id;
            df_job_submit(j);
        }
    }
}

/* job.h — requests as jobs: per-session FIFO, compute on the server's pool.
 *
 * A job has an optional `work` (runs on a worker thread: reads its session, which no other
 * job touches meanwhile, and fills the job's own data and change record j->change; it writes no
 * session field, see commit.h) and a `done` (runs on the loop thread afterwards: commits the
 * change with df_job_commit, or answers a read). Jobs of one session run strictly one after
 * another in submission order; jobs of
 * different sessions run in parallel on the server's compute pool (srv->pool, see pool.h: low
 * hand-off latency for interactive strokes; its completion channel is the one way back). A job
 * without `work` runs `done` directly on the loop thread when it reaches the head of its FIFO.
 * Jobs without a session (mesh loads) go straight to the pool's long lane.
 *
 * Inline jobs. Handing a job to a worker and its completion back costs two thread wake-ups:
 * on the 2-core test machine ~20-25 us of latency and ~30 us of CPU, three times the work of a
 * 1k-vertex brush update (bench_net). A job with an `inline_cost` therefore runs `work` on the
 * loop thread when it reaches the head of its FIFO and inline_cost predicts at most the server's
 * inline_us (config; 0 = never). The prediction is a measurement (the same stroke's previous
 * update), so the loop is held for at most about that long; solves, factorizations, mesh loads,
 * pinned strokes and anything not measured yet always go to the pool, so a slow job on one
 * session still never stalls another session. A client pipelining many cheap updates cannot
 * hold the loop either: inline work is capped at DF_JOB_INLINE_ITER_FACTOR x inline_us per loop
 * iteration (srv->inline_spent_ns, reset by the server's check handle); past that, jobs go to
 * the pool until the next iteration.
 *
 * Moves never lock a session out (a handle move may run for hours). A `preemptible` job (a
 * HANDLES_MOVE) ends at its next iteration (j->cancel, status superseded, its last published
 * iterate stays and is one undo step) as soon as a request with a requester has to queue behind
 * it. Requests that need not wait are answered beside it when they arrive and nothing else is
 * queued (`beside`): DF_JOB_BESIDE_READ jobs (get-mesh, snapshot, handles-get, subscribe,
 * unsubscribe, stream-shm) run their work and done on the loop thread at once against the last
 * committed version (the move's iterates are committed on the loop thread as they arrive, so
 * they see exactly the versions subscribers have been sent); DF_JOB_BESIDE_REFUSE jobs (undo, redo) fail
 * with ESTATE at once. A move whose requester disconnects ends too (df_job_forget_conn). */
#ifndef DF_SERVER_JOB_H
#define DF_SERVER_JOB_H

#include <stdatomic.h>
#include <stdint.h>
#include <uv.h>

#include "core/common/df_error.h"
#include "proto/frame.h"
#include "server/session/commit.h"
#include "server/exec/pool.h"
#include "server/net/req.h"
#include "server/net/sbuf.h"
#include "server/server.h"
#include "server/session/session.h"
#include "server/session/stream.h"

#define DF_JOB_INLINE_ITER_FACTOR 4 /* inline work per loop iteration <= this x inline_us */

/* What a job does when it arrives while a preemptible move runs on its session (see above). */
enum { DF_JOB_BESIDE_NONE = 0, DF_JOB_BESIDE_READ = 1, DF_JOB_BESIDE_REFUSE = 2 };

typedef struct df_job df_job;
typedef void (*df_job_fn)(df_job *j);
/* Predicted work time in ns of a job at the head of its FIFO (the loop thread owns the session's
 * state then); 0 = unknown or must not run inline. */
typedef uint64_t (*df_job_cost_fn)(const df_job *j);

struct df_job {
    df_server *srv;
    df_session *s;            /* NULL for session-less jobs */
    df_req req;               /* the request (req.c: a reference is held), or req.c NULL */
    uint64_t conn_id;
    df_job_fn work;           /* worker thread, may be NULL */
    df_job_fn done;           /* loop thread, required */
    df_job_fn cleanup;        /* frees `body`, may be NULL */
    df_job_cost_fn inline_cost; /* may be NULL: never inline (see "Inline jobs" above) */
    void *body;               /* request data owned by the job */
    const struct df_job_kind *kind; /* df_job_for_request's kind, or NULL */
    int rc;                   /* result of work (DF_OK or DF_E*) */
    df_error err;
    atomic_int cancel;        /* set by the loop thread to supersede a running move */
    int heavy;                /* long work (handle moves): the pool's long lane */
    int preemptible;          /* a move: cancelled when a request must queue behind it */
    int beside;               /* DF_JOB_BESIDE_*: behaviour while a move runs (see above) */
    df_task task;             /* its work on srv->pool */
    uint64_t version;         /* version after the job (for the ack) */
    df_change change;         /* what the work computed, committed by df_job_commit (commit.h) */
    struct df_job *next;
};

/* A new job for request (type, req_id) of connection `c` (may be NULL) on session `s` (may be
 * NULL). Takes a reference on c. NULL when out of memory. */
df_job *df_job_new(df_server *srv, df_session *s, df_conn *c, uint16_t type, uint64_t req_id,
                   df_job_fn work, df_job_fn done);

/* What a kind of session request is (dispatch.c routes a request type to its kind): how its
 * payload is decoded, the job's private body, its functions and how it queues. */
typedef struct df_job_kind {
    size_t body_size;         /* zeroed body in j->body (0: none) */
    /* Decodes payload `p` (r->len bytes) into `body` and names the session (*session_id);
     * DF_OK or the decode/check error. Loop thread. Required. */
    int (*decode)(const df_req *r, const uint8_t *p, void *body, uint64_t *session_id,
                  df_error *err);
    /* Frees what a body owns (not the body itself); also after a failed decode. May be NULL. */
    void (*release)(df_server *srv, void *body);
    /* Called with the new job before it is queued (a move supersedes older ones). May be NULL. */
    void (*queued)(df_job *j);
    df_job_fn work;           /* NULL: done only, on the loop thread */
    df_job_fn done;           /* required */
    df_job_cost_fn inline_cost;
    int beside;               /* DF_JOB_BESIDE_* */
    int heavy, preemptible;   /* handle moves */
} df_job_kind;

/* The one path of every session request: decodes request `r` with kind->decode, looks its
 * session up and queues a job of `kind` for it, which takes the request over (r is marked
 * answered; j->req answers it, holding a connection reference). DF_OK, or the decode error,
 * DF_ENOTFOUND (no such live session) or DF_ENOMEM with err set and nothing queued or answered
 * (the dispatcher answers). Loop thread. */
int df_job_request(df_req *r, const uint8_t *p, const df_job_kind *kind, df_error *err);

/* 1 when a client's request of `type` makes its session the most recently active one
 * (srv->last_change_session, which unbound HID devices follow): the change requests (brush,
 * handles, reset-rest, undo/redo) and subscribe. (BRUSH_STATE_SET, answered without a job,
 * sets it in its handler.) */
int df_job_is_change(uint16_t type);

/* Decoder of the requests whose body is a session_ref (no job body). */
int df_job_decode_ref(const df_req *r, const uint8_t *p, void *body, uint64_t *session_id,
                      df_error *err);

/* Queues the job (FIFO of j->s, or the pool when s is NULL). The job is freed after `done`. */
void df_job_submit(df_job *j);

/* Starts the session's next queued job when none is running; frees the session when it is
 * closed and idle (loop thread). */
void df_job_pump(df_session *s);

/* The `done` of jobs whose work fills j->change: commits it (df_session_commit with the job's
 * rc and error), which answers the request. */
void df_job_commit(df_job *j);

/* Removes queued (not started) jobs of session `s` for which pred(j, arg) is 1, running their
 * `done` with rc = DF_ESTATE and the given message first. Returns how many. */
int df_job_drop_queued(df_session *s, int (*pred)(const df_job *j, void *arg), void *arg,
                       const char *why);

/* When j->rc is an error: answers the requester (if any) with j->err and returns 1; else 0.
 * A `done` that does not commit starts with `if (df_job_failed(j)) return;`. */
int df_job_failed(df_job *j);

/* 1 when the session's running job is a move that a request arriving now could be answered
 * beside (nothing queued behind it): see "Moves" above (loop thread). */
int df_job_move_running(const df_session *s);

/* Called when a connection closes: unsubscribes it everywhere, drops its open strokes in
 * idle sessions (strokes of busy sessions are dropped by their next job), ends its running move
 * (its last published iterate stays, as with supersession) and drops its queued moves. */
void df_job_forget_conn(df_server *srv, df_conn *c);

/* Predicate matching every job (for df_job_drop_queued at shutdown). */
int df_job_pred_all(const df_job *j, void *arg);

#endif

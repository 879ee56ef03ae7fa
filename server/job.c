/* job.c — per-session FIFO of jobs on the libuv pool (see job.h). */
#include "server/job.h"

#include <stdlib.h>
#include <string.h>

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

static void job_free(df_job *j)
{
    if (j->cleanup) j->cleanup(j);
    for (size_t i = 0; i < j->nframes; i++) df_sbuf_unref(j->frames[i]);
    free(j->frames);
    if (j->c) df_conn_unref(j->c);
    free(j);
}

int df_job_add_frame(df_job *j, df_sbuf *frame)
{
    if (j->nframes == j->capframes) {
        size_t nc = j->capframes ? 2 * j->capframes : 4;
        df_sbuf **n = realloc(j->frames, nc * sizeof *n);
        if (!n) {
            df_sbuf_unref(frame);
            return DF_ENOMEM;
        }
        j->frames = n;
        j->capframes = nc;
    }
    j->frames[j->nframes++] = frame;
    return DF_OK;
}

void df_job_publish(df_job *j)
{
    for (size_t i = 0; i < j->nframes; i++) {
        if (j->s) df_session_broadcast(j->s, j->frames[i]);
        df_sbuf_unref(j->frames[i]);
    }
    j->nframes = 0;
}

static void pump(df_session *s);

/* Runs `done`, frees the job and clears the session's running slot (loop thread). */
static void finish(df_job *j)
{
    df_server *srv = j->srv;
    df_session *s = j->s;
    j->done(j);
    job_free(j);
    srv->stats.jobs_completed++;
    if (s) s->running = NULL;
}

#include <stdio.h>
uint64_t df_tr_sub, df_tr_ws, df_tr_we, df_tr_aft, df_tr_done;
static double tr_acc[5][4096]; static int tr_n;
void df_tr_flush(uint64_t t);
void df_tr_flush(uint64_t t)
{
    if (!df_tr_sub || tr_n >= 4096) return;
    tr_acc[0][tr_n] = (double)(df_tr_ws - df_tr_sub) / 1e3;
    tr_acc[1][tr_n] = (double)(df_tr_we - df_tr_ws) / 1e3;
    tr_acc[2][tr_n] = (double)(df_tr_aft - df_tr_we) / 1e3;
    tr_acc[3][tr_n] = (double)(df_tr_done - df_tr_aft) / 1e3;
    tr_acc[4][tr_n] = (double)(t - df_tr_done) / 1e3;
    tr_n++;
    df_tr_sub = 0;
    if (tr_n == 1000) {
        for (int k = 0; k < 5; k++) {
            double *a = tr_acc[k];
            for (int x = 1; x < tr_n; x++) for (int y = x; y > 0 && a[y-1] > a[y]; y--) { double q = a[y]; a[y] = a[y-1]; a[y-1] = q; }
            fprintf(stderr, "TRACE stage %d p50 %.2f us p90 %.2f\n", k, a[tr_n/2], a[tr_n*9/10]);
        }
        tr_n = 0;
    }
}
static void work_cb(uv_work_t *w)
{
    df_job *j = w->data;
    df_tr_ws = uv_hrtime();
    j->work(j);
    df_tr_we = uv_hrtime();
}

static void after_cb(uv_work_t *w, int status)
{
    df_job *j = w->data;
    df_server *srv = j->srv;
    df_session *s = j->s;
    df_tr_aft = uv_hrtime();
    srv->jobs_running--;
    /* Progress frames the worker posted must go out before the job's final frames. */
    df_server_drain_mail(srv);
    if (status == UV_ECANCELED) {
        j->canceled = 1;
        j->rc = df_error_set(&j->err, DF_ESTATE, "server shutting down");
    }
    finish(j);
    df_tr_done = uv_hrtime();
    if (s) pump(s);
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
        if (j->work) {
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
    if (j->work) df_tr_sub = uv_hrtime();
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
